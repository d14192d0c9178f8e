#include "common/path_check.h"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>

namespace clogscope {
namespace {

// strerror's text starts with a capital ("Too many levels of symbolic links"): a reason inside the
// tool's line reads lower-case, and some errors say more in the tool's words.
std::string Reason(int err) {
  switch (err) {
    case ENOTDIR:
      return "a part of the path is not a directory";
    case EACCES:
      return "permission denied";
    default: {
      std::string text = std::strerror(err);
      if (!text.empty() && text[0] >= 'A' && text[0] <= 'Z' && !(text.size() > 1 && text[1] < 'a'))
        text[0] = static_cast<char>(text[0] - 'A' + 'a');
      return text;
    }
  }
}

}  // namespace

PathKind InspectPath(const std::string& path, std::string* why) {
  if (path.empty()) return PathKind::kMissing;
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) {
    const int err = errno;
    if (err == ENOENT) return PathKind::kMissing;
    if (why) *why = Reason(err);
    return PathKind::kUnreachable;
  }
  if (S_ISREG(st.st_mode)) return PathKind::kFile;
  if (S_ISDIR(st.st_mode)) return PathKind::kDirectory;
  return PathKind::kOther;
}

bool CheckInputPath(const std::string& option, const std::string& path, PathExpect expect,
                    std::string* why) {
  std::string reason;
  const PathKind kind = InspectPath(path, &reason);
  switch (kind) {
    case PathKind::kMissing:
      if (expect == PathExpect::kPresetOrFile && !path.empty()) return true;
      reason = path.empty()                             ? "no path given"
               : expect == PathExpect::kDirectory       ? "no such directory"
               : expect == PathExpect::kFileOrDirectory ? "no such file or directory"
                                                        : "no such file";
      break;
    case PathKind::kFile:
      if (expect != PathExpect::kDirectory) return true;
      reason = "not a directory";
      break;
    case PathKind::kDirectory:
      if (expect == PathExpect::kDirectory || expect == PathExpect::kFileOrDirectory) return true;
      reason = "is a directory, not a file";
      break;
    case PathKind::kOther:
      reason = "not a regular file (a FIFO, socket or device)";
      break;
    case PathKind::kUnreachable:
      break;
  }
  *why = (option.empty() ? path : path.empty() ? option : option + " " + path) + ": " + reason;
  return false;
}

void RequireInputPath(const std::string& option, const std::string& path, PathExpect expect) {
  std::string why;
  if (!CheckInputPath(option, path, expect, &why)) throw std::invalid_argument(why);
}

std::string ResolveFrom(const std::string& base, const std::string& path) {
  if (path.empty() || std::filesystem::path(path).is_absolute()) return path;
  return (std::filesystem::path(base) / path).lexically_normal().string();
}

}  // namespace clogscope
