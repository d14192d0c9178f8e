#pragma once

// Libraries that print instead of returning an error (libpng's and libjpeg's default handlers,
// OpenCV's imread, which writes caught exceptions to std::cerr) write to file descriptor 2. The
// tool writes its own messages to ToolStderr() instead, a copy of stderr made at start-up, so that
// library text can be diverted around such calls, kept out of the user's terminal, and turned into
// the reason of the tool's own one-line message.
#include <cstdio>
#include <string>

namespace clogscope {

// The tool's message stream: the process's stderr as it was before any diversion (unbuffered).
std::FILE* ToolStderr();

// While alive, whatever is written to file descriptor 2 goes into a buffer, not the terminal.
// Nested and concurrent captures (decoders on several threads) share one diversion; each sees
// what was written during its lifetime, which may include another thread's library text.
class LibraryTextCapture {
 public:
  LibraryTextCapture();
  ~LibraryTextCapture();
  LibraryTextCapture(const LibraryTextCapture&) = delete;
  LibraryTextCapture& operator=(const LibraryTextCapture&) = delete;

  // The text written to fd 2 since this capture began.
  std::string Text() const;

 private:
  long start_ = 0;  // offset in the shared buffer where this capture's text begins
};

// The first line of library text, trimmed, for a message: "libpng error: IDAT: CRC error".
std::string FirstLine(const std::string& text);

}  // namespace clogscope
