#pragma once

// `clogscope measure`: strand width per frame from images, folders and videos
// (pipeline::MeasureInputs), or with `--manifest` the experiment of run_command.h.

namespace clogscope::apps {

// Parses argv (argv[0] is the subcommand name) into pipeline::MeasureInputsOptions and calls
// pipeline::MeasureInputs; returns the process exit code (main.cc dispatches to it).
int RunMeasure(int argc, char** argv);

}  // namespace clogscope::apps
