#pragma once

// `clogscope run` (and `clogscope measure --manifest`): a whole experiment from one manifest.

#include <atomic>

#include "pipeline/manifest_run.h"

namespace clogscope::apps {

// Parses argv (argv[0] is the subcommand name) into the options below and calls the typed
// function; returns the process exit code (main.cc dispatches to it).
int RunRun(int argc, char** argv);

// pipeline::RunManifest with `cancel` and the progress printed on stderr as steps finish.
pipeline::ManifestRunReport RunExperimentCommand(pipeline::ManifestRunOptions options,
                                                 std::atomic<bool>* cancel);

// The command-line side shared by `run` and `measure --manifest`: Ctrl-C handling, the printed
// table, the exit status.
int RunExperimentCli(const pipeline::ManifestRunOptions& options);

}  // namespace clogscope::apps
