#include "common/library_text.h"

#include <unistd.h>

namespace clogscope {

std::FILE* ToolStderr() {
  static std::FILE* const f = [] {
    const int fd = ::dup(2);
    std::FILE* out = fd >= 0 ? ::fdopen(fd, "w") : nullptr;
    if (!out) return stderr;  // no spare descriptor: share stderr
    std::setvbuf(out, nullptr, _IONBF, 0);
    return out;
  }();
  return f;
}

}  // namespace clogscope
