// A step file read back under --resume (OUT/steps/step_NNNN.json): anything may be in it.
#include <string>

#include "pipeline/step_file.h"

namespace {

// The step and options the seed corpus was written for, so mutations reach the consistency checks.
clogscope::pipeline::ExperimentOptions Options() {
  clogscope::pipeline::ExperimentOptions o;
  o.samples = 3;
  o.out_dir = "/tmp/unused";
  o.conversion = clogscope::pipeline::PlainScale(3.0);
  return o;
}

clogscope::pipeline::StepSpec Spec() {
  clogscope::pipeline::StepSpec s;
  s.step = 2;
  s.temperature_c = 210;
  s.video = "/data/step2.mp4";
  return s;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const clogscope::pipeline::ExperimentOptions options = Options();
  static const clogscope::pipeline::StepSpec spec = Spec();
  const std::string text(reinterpret_cast<const char*>(data), size);
  clogscope::pipeline::StepResult result;
  std::string why;
  // Never throws: a file that is not a consistent step file is refused with a reason.
  if (clogscope::pipeline::ReadStepFile(text, spec, options, &result, &why)) {
    // What was accepted must write back (the tables are made from it).
    clogscope::pipeline::StepFileText(result, options);
  }
  return 0;
}
