#include "common/atomic_file.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <stdexcept>

namespace clogscope {

AtomicTextFile::AtomicTextFile(std::string path, bool keep_partial)
    : path_(std::move(path)), partial_path_(path_ + ".partial"), keep_partial_(keep_partial) {
  out_.open(partial_path_, std::ios::out | std::ios::trunc);
  if (!out_) {
    throw std::invalid_argument(path_ + ": cannot create file (" + std::strerror(errno) + ")");
  }
}

AtomicTextFile::~AtomicTextFile() {
  if (committed_) return;
  out_.close();
  if (!keep_partial_) std::remove(partial_path_.c_str());
}

void AtomicTextFile::Commit() {
  out_.flush();
  if (!out_) throw std::runtime_error(partial_path_ + ": write failed");
  out_.close();
  // rename() replaces the target atomically on POSIX file systems, so readers see the old or the
  // new file, never a half-written one.
  if (std::rename(partial_path_.c_str(), path_.c_str()) != 0) {
    throw std::runtime_error(path_ + ": cannot rename from " + partial_path_ + " (" +
                             std::strerror(errno) + ")");
  }
  committed_ = true;
}

void WriteFileAtomically(const std::string& path, const std::string& content) {
  AtomicTextFile file(path);
  file.stream() << content;
  file.Commit();
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument(path + ": cannot open (" + std::strerror(errno) + ")");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace clogscope
