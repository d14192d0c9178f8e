#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace clogscope::vision {

// One image file of a folder, with what tells one file under a name from another (not a clock to
// order by: a camera's clock may be anywhere).
struct ImageFileEntry {
  std::string path;  // the folder's path joined with the name
  std::string name;  // the file name
  uintmax_t inode = 0, size = 0;
  int64_t mtime_ns = 0;
};

// The regular image files (by extension, IsImagePath) of folder `dir` after links, sorted by name.
// A looping or dangling link, or a file that vanished between listing and looking, is skipped.
// False when the folder cannot be listed (*files then holds what was listed before the error).
bool ListImageFiles(const std::string& dir, std::vector<ImageFileEntry>* files);

}  // namespace clogscope::vision
