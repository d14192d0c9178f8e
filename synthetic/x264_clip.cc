#include "synthetic/x264_clip.h"

#include <fmt/format.h>

#include <stdexcept>

#include "common/spawn.h"
#include "vision/io/video_io.h"

namespace clogscope::synthetic {

std::string EncodeX264Clip(const std::vector<cv::Mat>& frames, const std::filesystem::path& dir,
                           const std::string& name, int fps) {
  std::filesystem::create_directories(dir);
  for (size_t i = 0; i < frames.size(); ++i)
    vision::WriteImageAtomically((dir / fmt::format("{:03d}.png", i)).string(), frames[i]);
  const std::string path = (dir / name).string();
  SpawnOptions encode;
  encode.argv = {"ffmpeg",
                 "-nostdin",
                 "-v",
                 "error",
                 "-y",
                 "-framerate",
                 std::to_string(fps),
                 "-i",
                 (dir / "%03d.png").string(),
                 "-c:v",
                 "libx264",
                 "-threads",
                 "1",
                 "-pix_fmt",
                 "yuv420p",
                 path};
  std::string why;
  const pid_t pid = Spawn(encode, &why);
  if (pid < 0 || !WaitForExit(pid, &why))
    throw std::runtime_error(path + ": x264 encode: ffmpeg " + why);
  return path;
}

}  // namespace clogscope::synthetic
