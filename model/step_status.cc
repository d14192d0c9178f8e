#include "model/step_status.h"

#include <stdexcept>

namespace clogscope::model {

const char* StepStatusName(StepStatus status) {
  switch (status) {
    case StepStatus::kOk:
      return "ok";
    case StepStatus::kTooFewFrames:
      return "too_few_frames";
    case StepStatus::kFailed:
      return "failed";
  }
  return "?";
}

StepStatus ParseStepStatus(const std::string& name) {
  for (StepStatus s : {StepStatus::kOk, StepStatus::kTooFewFrames, StepStatus::kFailed}) {
    if (name == StepStatusName(s)) return s;
  }
  throw std::invalid_argument("unknown status '" + name + "'");
}

}  // namespace clogscope::model
