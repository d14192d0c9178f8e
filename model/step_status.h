#pragma once

// A measured step's outcome, the diameter table's `status` column: `run` (pipeline/) sets and
// writes it, --resume reads it back from the step files, and the predictor's table reader skips
// failed steps (model/io.h). It lives here, below both, so that writer and readers share one set
// of names.
#include <string>

namespace clogscope::model {

enum class StepStatus {
  kOk,            // as many valid frames as asked
  kTooFewFrames,  // fewer valid frames than asked: the mean stands, from fewer
  kFailed,        // no diameter (no valid frame, an unreadable source, an error)
};
const char* StepStatusName(StepStatus status);  // "ok", "too_few_frames", "failed"
// The status StepStatusName gives `name`; throws std::invalid_argument ("unknown status 'x'")
// for any other text.
StepStatus ParseStepStatus(const std::string& name);

}  // namespace clogscope::model
