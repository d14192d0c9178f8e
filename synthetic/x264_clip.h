#pragma once

#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace clogscope::synthetic {

// Encodes frames (8-bit grey or BGR) as an H.264 clip `name` in `dir` at `fps` frames/s with the
// ffmpeg program's libx264 at its defaults, on one thread (x264 on many threads codes differently
// from run to run), through lossless PNG copies of the frames in `dir`. Returns the clip's path;
// throws std::runtime_error when ffmpeg fails.
std::string EncodeX264Clip(const std::vector<cv::Mat>& frames, const std::filesystem::path& dir,
                           const std::string& name, int fps);

}  // namespace clogscope::synthetic
