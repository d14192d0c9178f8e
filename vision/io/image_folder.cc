#include "vision/io/image_folder.h"

#include <sys/stat.h>

#include <algorithm>
#include <filesystem>

#include "vision/io/video_io.h"

namespace clogscope::vision {

bool ListImageFiles(const std::string& dir, std::vector<ImageFileEntry>* files) {
  namespace fs = std::filesystem;
  files->clear();
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string path = it->path().string();
    if (!IsImagePath(path)) continue;
    struct stat st;
    if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) continue;
    files->push_back(
        {path, it->path().filename().string(), static_cast<uintmax_t>(st.st_ino),
         static_cast<uintmax_t>(st.st_size),
         static_cast<int64_t>(st.st_mtim.tv_sec) * 1'000'000'000 + st.st_mtim.tv_nsec});
  }
  std::sort(files->begin(), files->end(),
            [](const ImageFileEntry& a, const ImageFileEntry& b) { return a.path < b.path; });
  return !ec;
}

}  // namespace clogscope::vision
