#pragma once

#include <string>
#include <vector>

namespace clogscope {

// What produced an output file: the tool version, the UTC time and the command line.
struct Provenance {
  std::string version;
  std::string created_utc;  // ISO 8601, e.g. 2026-11-21T12:57:41Z
  std::string command_line;
};

// Records the command line once, from main(); later calls to CurrentProvenance() report it.
void SetCommandLine(int argc, const char* const* argv);
// The version, the current UTC time and the recorded command line (empty when none was set).
Provenance CurrentProvenance();
// The command line joined with shell-style quoting where a word needs it.
std::string JoinCommandLine(const std::vector<std::string>& words);
// Provenance as '# '-prefixed comment lines for the top of a CSV file.
std::string ProvenanceCsvComment(const Provenance& p);

}  // namespace clogscope
