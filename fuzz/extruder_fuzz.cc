// Extruder parameter files.
#include <stdexcept>
#include <string>

#include "model/io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    clogscope::model::ParseExtruderYaml(text, "fuzz.yaml");
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
