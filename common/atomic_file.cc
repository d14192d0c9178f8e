#include "common/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "common/path_check.h"

namespace clogscope {

FdStreamBuf::~FdStreamBuf() {
  if (fd_ >= 0) ::close(fd_);
}

bool FdStreamBuf::Open(const std::string& path) {
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) error_ = errno;
  return fd_ >= 0;
}

bool FdStreamBuf::Drain() {
  const char* p = pbase();
  while (p < pptr()) {
    if (error_ || fd_ < 0) break;
    const ssize_t n = ::write(fd_, p, pptr() - p);
    if (n < 0) {
      if (errno == EINTR) continue;
      error_ = errno;
      break;
    }
    p += n;
  }
  setp(buffer_, buffer_ + sizeof(buffer_));
  return error_ == 0;
}

FdStreamBuf::int_type FdStreamBuf::overflow(int_type ch) {
  if (!Drain()) return traits_type::eof();
  if (!traits_type::eq_int_type(ch, traits_type::eof())) {
    *pptr() = traits_type::to_char_type(ch);
    pbump(1);
  }
  return traits_type::not_eof(ch);
}

int FdStreamBuf::sync() { return Drain() ? 0 : -1; }

bool FdStreamBuf::Close() {
  Drain();
  if (fd_ >= 0) {
    if (::close(fd_) != 0 && !error_) error_ = errno;
    fd_ = -1;
  }
  return error_ == 0;
}

AtomicTextFile::AtomicTextFile(std::string path, bool keep_partial)
    : path_(std::move(path)),
      partial_path_(path_ + ".partial"),
      keep_partial_(keep_partial),
      exceptions_at_start_(std::uncaught_exceptions()) {
  std::error_code ec;
  if (std::filesystem::is_directory(path_, ec))
    throw std::invalid_argument(path_ + ": is a directory, not a file name");
  if (!buf_.Open(partial_path_)) {
    throw std::invalid_argument(path_ + ": cannot create file (" + std::strerror(buf_.error()) +
                                ")");
  }
}

AtomicTextFile::~AtomicTextFile() {
  if (committed_) return;
  buf_.Close();
  const bool error_path = std::uncaught_exceptions() > exceptions_at_start_;
  if (!keep_partial_ || failed_ || error_path) std::remove(partial_path_.c_str());
}

void AtomicTextFile::Commit() {
  // The first failed write's errno says why (a full disk: "No space left on device").
  out_.flush();
  if (!buf_.Close() || !out_) {
    const int err = buf_.error();
    failed_ = true;
    std::remove(partial_path_.c_str());
    throw std::runtime_error(path_ + ": write failed" +
                             (err ? std::string(" (") + std::strerror(err) + ")" : std::string()));
  }
  // rename() replaces the target atomically on POSIX file systems, so readers see the old or the
  // new file, never a half-written one.
  if (std::rename(partial_path_.c_str(), path_.c_str()) != 0) {
    const int err = errno;
    failed_ = true;
    std::remove(partial_path_.c_str());
    throw std::runtime_error(path_ + ": cannot rename from " + partial_path_ + " (" +
                             std::strerror(err) + ")");
  }
  committed_ = true;
}

void WriteFileAtomically(const std::string& path, const std::string& content) {
  AtomicTextFile file(path);
  file.stream() << content;
  file.Commit();
}

bool IsRegularFile(const std::string& path, std::string* why) {
  switch (InspectPath(path, why)) {
    case PathKind::kFile:
      return true;
    case PathKind::kMissing:
      *why = "no such file";
      break;
    case PathKind::kDirectory:
      *why = "is a directory";
      break;
    case PathKind::kOther:
      *why = "not a regular file (a FIFO, socket or device)";
      break;
    case PathKind::kUnreachable:  // why says it
      break;
  }
  return false;
}

bool TryReadFile(const std::string& path, std::string* content, std::string* why) {
  if (!IsRegularFile(path, why)) return false;
  std::error_code ec;
  if (std::filesystem::file_size(path, ec) > kMaxReadFileBytes && !ec) {
    *why = "too large (over " + std::to_string(kMaxReadFileBytes >> 20) + " MiB)";
    return false;
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    *why = std::string("cannot open (") + std::strerror(errno) + ")";
    return false;
  }
  std::ostringstream ss;
  ss << in.rdbuf();
  *content = std::move(ss).str();
  return true;
}

std::string ReadFile(const std::string& path) {
  std::string content, why;
  if (!TryReadFile(path, &content, &why)) throw std::invalid_argument(path + ": " + why);
  return content;
}

void CreateOutputDirectory(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir))
    throw std::invalid_argument(dir + ": cannot create output directory");
}

}  // namespace clogscope
