#pragma once

#include <string>

namespace clogscope {

// s with ASCII letters in lower case (file extensions, option words, host names); other bytes,
// UTF-8 included, as they are.
inline std::string LowerAscii(std::string s) {
  for (char& c : s)
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  return s;
}

}  // namespace clogscope
