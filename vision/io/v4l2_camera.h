#pragma once

// A V4L2 camera (/dev/videoN) through libv4l2, which converts whatever the camera sends (YUYV,
// Motion JPEG, Bayer, …) to planar YUV 4:2:0, whose luma plane is the grey frame (internal to
// vision/io: LiveSource's device source).
#include <atomic>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "vision/io/data_range.h"

namespace clogscope::vision {

class V4l2Camera {
 public:
  // Throws std::invalid_argument naming the device when it cannot be opened, is not a V4L2
  // capture device, or cannot deliver YUV 4:2:0 (even through libv4l2's conversion).
  explicit V4l2Camera(const std::string& device);
  ~V4l2Camera();
  V4l2Camera(const V4l2Camera&) = delete;
  V4l2Camera& operator=(const V4l2Camera&) = delete;

  enum class Grab { kFrame, kStopped, kFailed };
  // The next frame's luma as 8-bit grey. Waits up to wait_s, returning early when *stop turns true
  // (kStopped); kFailed and *why when the camera fails or sends nothing in that time.
  Grab Read(cv::Mat* grey, double wait_s, const std::atomic<bool>* stop, std::string* why);
  // The luma's range: full when the driver says so, else limited (V4L2's default for YUV).
  LumaRange luma_range() const { return luma_range_; }

 private:
  int fd_ = -1;
  LumaRange luma_range_ = LumaRange::kLimited;
  int width_ = 0, height_ = 0, stride_ = 0;
  std::vector<unsigned char> buffer_;
};

}  // namespace clogscope::vision
