#pragma once

// Input paths named by an option (or a manifest), checked before anything reads them: what kind of
// object a path is, or why the file system cannot say, as the tool's own line — never
// std::filesystem's "filesystem error: status: …", and the same wording for every option.
#include <string>

namespace clogscope {

enum class PathKind {
  kMissing,      // nothing there (for an option that takes a preset name or a file: a name)
  kFile,         // a regular file, after links
  kDirectory,    // after links
  kOther,        // a FIFO, socket or device
  kUnreachable,  // the file system refused: a loop of links, no permission, a name too long, …
};

// A path written in a file whose folder is `base`: as written when empty or absolute, else from
// `base`, normalised.
std::string ResolveFrom(const std::string& base, const std::string& path);

// What `path` is. For kUnreachable, `why` (when given) says why ("too many levels of symbolic
// links"). Never throws.
PathKind InspectPath(const std::string& path, std::string* why = nullptr);

// What an input option takes.
enum class PathExpect {
  kFile,
  kDirectory,
  kFileOrDirectory,
  kPresetOrFile,  // a name that is not a path (nothing there), or a regular file
};

// True when `path` is what `expect` asks for. Else false and `why` is one line naming the option
// (or, for a positional input given as ""; the path alone) and the problem:
// "--extruder loop.yaml: too many levels of symbolic links".
bool CheckInputPath(const std::string& option, const std::string& path, PathExpect expect,
                    std::string* why);

// The same, throwing std::invalid_argument with that line.
void RequireInputPath(const std::string& option, const std::string& path, PathExpect expect);

}  // namespace clogscope
