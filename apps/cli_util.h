#pragma once

#include <CLI/CLI.hpp>
#include <string>

namespace clogscope::apps {

// "WxH" -> width, height (positive). Returns false on a malformed value (CLI11 callback form).
bool ParseSize(const std::string& text, int* width, int* height);

// Parses the command line into `app`'s options, then CheckNumbers. Returns false when --help was
// asked for (and printed). A usage error (unknown option, missing or unconvertible value) throws
// std::invalid_argument with CLI11's one-line reason, so it reads like every other error.
bool ParseCommandLine(CLI::App& app, int argc, char** argv);

// After parsing: every option value that reads as a number must be a finite one of normal size
// ("inf", "nan", 1e309 or 4.9e-324 reach no physical quantity). Throws std::invalid_argument
// naming the option. Each quantity's own range is checked where its options are validated.
void CheckNumbers(const CLI::App& app);

// The files of a command that reads a diameter table with an extruder (predict, drive, thermal):
// --diameters, when given, a file, and --extruder a preset or a YAML file, each checked as
// CheckInputPath does. False with its one line in *why.
bool CheckTableAndExtruderPaths(const std::string& diameters, const std::string& extruder,
                                std::string* why);

// Writes spdlog output to stderr at the given level name ("info", "warn", "debug", …).
void SetUpLogging(const std::string& level);

}  // namespace clogscope::apps
