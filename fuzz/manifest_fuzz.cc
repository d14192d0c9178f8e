// Experiment manifests, YAML and CSV (the first byte chooses which).
#include <stdexcept>

#include "fuzz/fuzz_util.h"
#include "pipeline/manifest.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const std::string path =
      clogscope::fuzz::AsFile(data + 1, size - 1, data[0] & 1 ? ".csv" : ".yaml");
  try {
    clogscope::pipeline::LoadManifest(path);
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
