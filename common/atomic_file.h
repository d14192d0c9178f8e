#pragma once

#include <cstdint>
#include <ostream>
#include <streambuf>
#include <string>

namespace clogscope {

// A text file that appears under its final name only when complete. Content goes to
// "<path>.partial"; Commit() flushes and renames it onto <path>. Destroyed without Commit(), the
// partial file is removed unless keep_partial is set (then it stays, valid up to its last line, as
// after Ctrl-C) — but never kept when destroyed by an exception or after a failed write.
// A stream buffer on a POSIX file descriptor that keeps the errno of its first failed write, so a
// full disk is reported as such (std::ofstream forgets why it failed).
class FdStreamBuf : public std::streambuf {
 public:
  FdStreamBuf() { setp(buffer_, buffer_ + sizeof(buffer_)); }
  ~FdStreamBuf() override;
  bool Open(const std::string& path);  // false with error() set
  bool Close();                        // flushes; false with error() set
  int error() const { return error_; }

 protected:
  int_type overflow(int_type ch) override;
  int sync() override;

 private:
  bool Drain();
  int fd_ = -1;
  int error_ = 0;
  char buffer_[1 << 16];
};

class AtomicTextFile {
 public:
  // Throws std::invalid_argument naming the path when the file cannot be created.
  explicit AtomicTextFile(std::string path, bool keep_partial = false);
  ~AtomicTextFile();
  AtomicTextFile(const AtomicTextFile&) = delete;
  AtomicTextFile& operator=(const AtomicTextFile&) = delete;

  std::ostream& stream() { return out_; }
  const std::string& path() const { return path_; }
  const std::string& partial_path() const { return partial_path_; }
  // Throws std::runtime_error when the data cannot be written or renamed.
  void Commit();

 private:
  std::string path_;
  std::string partial_path_;
  FdStreamBuf buf_;
  std::ostream out_{&buf_};
  bool keep_partial_ = false;
  bool committed_ = false;
  bool failed_ = false;  // a write failed: the partial file is incomplete and always removed
  int exceptions_at_start_ = 0;  // unwinding past this count means an error path: remove
};

// Writes the whole content atomically (temporary name, then rename).
void WriteFileAtomically(const std::string& path, const std::string& content);

// Reads a whole file into `content`; false with the reason in `why` when it cannot be read, is not
// a regular file (a FIFO or device would block or never end) or is over kMaxReadFileBytes.
bool TryReadFile(const std::string& path, std::string* content, std::string* why);
inline constexpr std::uintmax_t kMaxReadFileBytes = std::uintmax_t{256} << 20;

// The same, throwing std::invalid_argument "<path>: <why>".
std::string ReadFile(const std::string& path);

// True when `path` is a regular file (after links) that can be opened without blocking; else
// false with the reason ("no such file", "is a directory", "not a regular file (FIFO, device …)").
bool IsRegularFile(const std::string& path, std::string* why);

// Creates `dir` (and its parents) for outputs; throws std::invalid_argument "DIR: cannot create
// output directory" when it cannot.
void CreateOutputDirectory(const std::string& dir);

}  // namespace clogscope
