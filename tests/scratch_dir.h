#pragma once

// A folder of a test's own under the system's temporary directory. Its name is unique (mkdtemp):
// two runs of the suite at once (the Release and the sanitizer build, two checkouts, a developer's
// run beside CI's) never share one, as they did with fixed names. Removed when it goes out of
// scope.
#include <stdlib.h>

#include <filesystem>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

namespace clogscope::testutil {

class ScratchDir {
 public:
  explicit ScratchDir(const std::string& prefix) {
    std::string name = (std::filesystem::temp_directory_path() / (prefix + "_XXXXXX")).string();
    if (!::mkdtemp(name.data())) throw std::runtime_error("cannot create a folder like " + name);
    path_ = name;
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

// A fresh folder whose name starts with `prefix`, kept until the test program ends.
inline std::filesystem::path FreshDir(const std::string& prefix) {
  static std::mutex mutex;
  static std::vector<std::unique_ptr<ScratchDir>> dirs;  // removed at exit
  const std::lock_guard<std::mutex> lock(mutex);
  dirs.push_back(std::make_unique<ScratchDir>(prefix));
  return dirs.back()->path();
}

}  // namespace clogscope::testutil
