#pragma once

// `clogscope run` (and `clogscope measure --manifest`): a whole experiment from one manifest.

#include <atomic>

#include "pipeline/manifest_run.h"

namespace clogscope::apps {

// Parses argv (argv[0] is the subcommand name) into the options below and calls the typed
// function; returns the process exit code (main.cc dispatches to it).
int RunRun(int argc, char** argv);

// The options and report of a manifest run (pipeline/manifest_run.h).
using ExperimentCommandOptions = pipeline::ManifestRunOptions;
using ExperimentReport = pipeline::ManifestRunReport;

// pipeline::RunManifest with `cancel` and the progress printed on stderr as steps finish.
ExperimentReport RunExperimentCommand(ExperimentCommandOptions options, std::atomic<bool>* cancel);

// The command-line side shared by `run` and `measure --manifest`: Ctrl-C handling, the printed
// table, the exit status.
int RunExperimentCli(const ExperimentCommandOptions& options);

}  // namespace clogscope::apps
