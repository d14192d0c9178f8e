#include "calib/solver_log.h"

#include <glog/logging.h>

namespace clogscope::calib {

void SetSolverLogging(bool verbose) {
  // glog severities: 0 INFO, 1 WARNING, 2 ERROR, 3 FATAL.
  FLAGS_minloglevel = verbose ? 0 : 3;
  FLAGS_stderrthreshold = verbose ? 0 : 3;
  FLAGS_logtostderr = true;  // never log files in /tmp
}

}  // namespace clogscope::calib
