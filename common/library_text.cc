#include "common/library_text.h"

#include <sys/mman.h>
#include <unistd.h>

#include <iostream>
#include <mutex>

namespace clogscope {
namespace {

// One diversion of fd 2 for the whole process, shared by the captures alive at a time.
struct Diversion {
  std::mutex mu;
  int depth = 0;
  int saved_fd = -1;  // fd 2 as it was before the diversion
  int sink_fd = -1;   // the buffer (a memory file); fd 2 shares its file offset
};

Diversion& TheDiversion() {
  static Diversion d;
  return d;
}

void FlushLibraryStreams() {
  std::cerr.flush();
  std::fflush(stderr);
}

long Offset(int fd) { return fd >= 0 ? static_cast<long>(::lseek(fd, 0, SEEK_CUR)) : 0; }

}  // namespace

std::FILE* ToolStderr() {
  static std::FILE* const f = [] {
    const int fd = ::dup(2);
    std::FILE* out = fd >= 0 ? ::fdopen(fd, "w") : nullptr;
    if (!out) return stderr;  // no spare descriptor: share stderr (text may then be diverted)
    std::setvbuf(out, nullptr, _IONBF, 0);
    return out;
  }();
  return f;
}

LibraryTextCapture::LibraryTextCapture() {
  ToolStderr();  // made before fd 2 is ever diverted
  Diversion& d = TheDiversion();
  std::lock_guard<std::mutex> lock(d.mu);
  if (d.depth++ == 0) {
    FlushLibraryStreams();
    const int sink = ::memfd_create("clogscope-library-text", MFD_CLOEXEC);
    const int saved = sink >= 0 ? ::dup(2) : -1;
    if (saved >= 0 && ::dup2(sink, 2) >= 0) {
      d.sink_fd = sink;
      d.saved_fd = saved;
    } else {  // cannot divert: library text stays on the terminal, nothing else changes
      if (saved >= 0) ::close(saved);
      if (sink >= 0) ::close(sink);
    }
  }
  start_ = Offset(d.sink_fd);
}

LibraryTextCapture::~LibraryTextCapture() {
  Diversion& d = TheDiversion();
  std::lock_guard<std::mutex> lock(d.mu);
  if (--d.depth == 0 && d.sink_fd >= 0) {
    FlushLibraryStreams();
    ::dup2(d.saved_fd, 2);
    ::close(d.saved_fd);
    ::close(d.sink_fd);
    d.saved_fd = d.sink_fd = -1;
  }
}

std::string LibraryTextCapture::Text() const {
  Diversion& d = TheDiversion();
  std::lock_guard<std::mutex> lock(d.mu);
  if (d.sink_fd < 0) return std::string();
  FlushLibraryStreams();
  const long end = Offset(d.sink_fd);
  std::string text(end > start_ ? static_cast<size_t>(end - start_) : 0, '\0');
  const ssize_t n = text.empty() ? 0 : ::pread(d.sink_fd, text.data(), text.size(), start_);
  text.resize(n > 0 ? static_cast<size_t>(n) : 0);
  return text;
}

std::string FirstLine(const std::string& text) {
  const size_t begin = text.find_first_not_of(" \t\r\n");
  if (begin == std::string::npos) return std::string();
  const size_t end = text.find_first_of("\r\n", begin);
  std::string line = text.substr(begin, end == std::string::npos ? std::string::npos : end - begin);
  while (!line.empty() && (line.back() == ' ' || line.back() == '\t')) line.pop_back();
  return line;
}

}  // namespace clogscope
