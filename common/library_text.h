#pragma once

// The tool's message stream: a copy of stderr made at start-up, unbuffered, so that a message
// goes out whole and at once, whatever a library does with its own buffered stderr.
#include <cstdio>

namespace clogscope {

std::FILE* ToolStderr();

}  // namespace clogscope
