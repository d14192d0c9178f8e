#pragma once

#include <memory>
#include <opencv2/core.hpp>
#include <string>

namespace clogscope::vision {

// One frame of an input, as read.
struct InputFrame {
  std::string source;  // the file the frame came from (the image, or the video)
  int index = 0;       // frame number within the input, from 0
  double time_s = -1;  // position in a video, seconds; -1 for still images
  cv::Mat image;       // empty when the frame could not be decoded; video frames are grey (luma)
  std::string error;   // why image is empty, or a warning about a damaged but decoded frame
};

// Frames of an image file, a directory of images (sorted by name) or a video file.
class FrameSource {
 public:
  // Throws std::invalid_argument naming the path when it does not exist, is an empty directory,
  // cannot be opened, or is a video without frames.
  static std::unique_ptr<FrameSource> Open(const std::string& path);
  virtual ~FrameSource() = default;
  // Reads the next frame; false at the end. An undecodable frame comes back with an empty image
  // and `error` set, and reading goes on.
  virtual bool Next(InputFrame* frame) = 0;
  // Frames expected (from the container for videos; may be approximate), or -1 when unknown.
  virtual int expected_frames() const = 0;
  virtual double fps() const { return 0; }
  const std::string& path() const { return path_; }

 protected:
  explicit FrameSource(std::string path) : path_(std::move(path)) {}
  std::string path_;
};

}  // namespace clogscope::vision
