#pragma once

#include <fstream>
#include <string>

namespace clogscope {

// A text file that appears under its final name only when complete. Content goes to
// "<path>.partial"; Commit() flushes and renames it onto <path>. Destroyed without Commit(), the
// partial file is removed unless keep_partial is set (then it stays, valid up to its last line).
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
  std::ofstream out_;
  bool keep_partial_ = false;
  bool committed_ = false;
};

// Writes the whole content atomically (temporary name, then rename).
void WriteFileAtomically(const std::string& path, const std::string& content);

// Reads a whole file; throws std::invalid_argument naming the path when it cannot be read.
std::string ReadFile(const std::string& path);

}  // namespace clogscope
