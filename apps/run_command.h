#pragma once

// `clogscope run` (and `clogscope measure --manifest`): a whole experiment from one manifest.

#include "pipeline/manifest_run.h"

namespace clogscope::apps {

// Parses argv (argv[0] is the subcommand name) into the options below and calls the typed
// function; returns the process exit code (main.cc dispatches to it).
int RunRun(int argc, char** argv);

// pipeline::RunManifest with the command-line side shared by `run` and `measure --manifest`:
// Ctrl-C handling, the progress on stderr as steps finish, the printed table, the exit status.
int RunExperimentCli(pipeline::ManifestRunOptions options);

}  // namespace clogscope::apps
