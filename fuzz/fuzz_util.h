#pragma once

// Shared by the libFuzzer targets: an input as a file (the readers take paths), and the rule that
// a parser may reject its input only with std::invalid_argument — any other exception, crash, hang
// or sanitizer report is a finding.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

namespace clogscope::fuzz {

// Writes the bytes to a per-process file with the given extension under /dev/shm (or /tmp).
inline std::string AsFile(const uint8_t* data, size_t size, const std::string& ext) {
  static const std::string dir = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
  const std::string path = dir + "/clogscope_fuzz_" + std::to_string(getpid()) + ext;
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return path;
  std::fwrite(data, 1, size, f);
  std::fclose(f);
  return path;
}

}  // namespace clogscope::fuzz
