#pragma once

// A finished step saved as OUT/steps/step_NNNN.json, so that an interrupted run or `--resume`
// keeps it. A file from an earlier run stands for a step only when it was measured the same way
// (the step's source and times, the sample count, the measurement options and the conversion)
// and holds a consistent, finite result; otherwise the step is measured again.
#include <string>

#include "pipeline/experiment.h"

namespace clogscope::pipeline {

// "step_0003.json".
std::string StepFileName(int step);

// The step file's text (one line of JSON) for a result measured with these options.
std::string StepFileText(const StepResult& result, const ExperimentOptions& options);

// Reads a step file's text back into `result` (marked resumed). Returns false, with the reason in
// `why`, when the text is not a step file, was measured another way, failed, or does not add up.
// Never throws.
bool ReadStepFile(const std::string& text, const StepSpec& spec, const ExperimentOptions& options,
                  StepResult* result, std::string* why);

}  // namespace clogscope::pipeline
