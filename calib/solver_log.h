#pragma once

namespace clogscope::calib {

// Ceres reports through glog, which writes warnings to stderr on its own (several lines beside the
// tool's one-line message). Quiet by default; verbose for CLOGSCOPE_LOG=debug. Process-wide.
void SetSolverLogging(bool verbose);

}  // namespace clogscope::calib
