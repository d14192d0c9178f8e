#include "vision/io/v4l2_camera.h"

#include <fcntl.h>
#include <libv4l2.h>
#include <linux/videodev2.h>
#include <poll.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <stdexcept>

namespace clogscope::vision {

V4l2Camera::V4l2Camera(const std::string& device) {
  // Non-blocking, so that a read can wait in steps and see a stop.
  fd_ = v4l2_open(device.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) throw std::invalid_argument(device + ": cannot open (" + std::strerror(errno) + ")");
  auto fail = [&](const std::string& why) {
    v4l2_close(fd_);
    fd_ = -1;
    throw std::invalid_argument(device + ": " + why);
  };
  v4l2_capability cap{};
  if (v4l2_ioctl(fd_, VIDIOC_QUERYCAP, &cap) < 0) fail("not a V4L2 camera");
  const unsigned caps =
      (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
  if (!(caps & V4L2_CAP_VIDEO_CAPTURE)) fail("a V4L2 device, but not a camera (no video capture)");
  v4l2_format f{};
  f.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (v4l2_ioctl(fd_, VIDIOC_G_FMT, &f) < 0)
    fail(std::string("cannot read its format (") + std::strerror(errno) + ")");
  // The camera's own size, in planar YUV 4:2:0 (libv4l2 converts from the camera's format).
  f.fmt.pix.pixelformat = V4L2_PIX_FMT_YUV420;
  f.fmt.pix.field = V4L2_FIELD_ANY;
  if (v4l2_ioctl(fd_, VIDIOC_S_FMT, &f) < 0 || f.fmt.pix.pixelformat != V4L2_PIX_FMT_YUV420)
    fail("cannot deliver its frames as YUV 4:2:0");
  // A driver that does not say leaves the range to its colourspace's default: limited for YUV
  // but JPEG's. Taken as limited when in doubt: clipping is then looked for at 233-235 and
  // 16-18 as well as where full range looks for it (246-255, 0-9).
  if (f.fmt.pix.quantization == V4L2_QUANTIZATION_FULL_RANGE ||
      (f.fmt.pix.quantization == V4L2_QUANTIZATION_DEFAULT &&
       f.fmt.pix.colorspace == V4L2_COLORSPACE_JPEG))
    luma_range_ = LumaRange::kFull;
  width_ = static_cast<int>(f.fmt.pix.width);
  height_ = static_cast<int>(f.fmt.pix.height);
  stride_ = std::max(width_, static_cast<int>(f.fmt.pix.bytesperline));
  const size_t luma = static_cast<size_t>(stride_) * height_;
  if (width_ <= 0 || height_ <= 0) fail("reports no frame size");
  buffer_.resize(std::max<size_t>(f.fmt.pix.sizeimage, luma + luma / 2));
}

V4l2Camera::~V4l2Camera() {
  if (fd_ >= 0) v4l2_close(fd_);
}

V4l2Camera::Grab V4l2Camera::Read(cv::Mat* grey, double wait_s, const std::atomic<bool>* stop,
                                  std::string* why) {
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(wait_s));
  while (true) {
    if (stop && stop->load()) return Grab::kStopped;
    // libv4l2 emulates read() with streaming buffers; the first read starts the stream.
    const ssize_t n = v4l2_read(fd_, buffer_.data(), buffer_.size());
    if (n >= 0) {
      if (static_cast<size_t>(n) < static_cast<size_t>(stride_) * height_) {
        if (why) *why = "the camera sent a short frame (" + std::to_string(n) + " bytes)";
        return Grab::kFailed;
      }
      *grey =
          cv::Mat(height_, width_, CV_8UC1, buffer_.data(), static_cast<size_t>(stride_)).clone();
      return Grab::kFrame;
    }
    if (errno != EAGAIN && errno != EINTR) {
      if (why) *why = std::string("the camera failed (") + std::strerror(errno) + ")";
      return Grab::kFailed;
    }
    if (Clock::now() >= deadline) {
      if (why)
        *why = "the camera sent no frame for " + std::to_string(static_cast<int>(wait_s)) + " s";
      return Grab::kFailed;
    }
    // Wait for a buffer in steps short enough to see a stop.
    pollfd p{fd_, POLLIN, 0};
    if (poll(&p, 1, 100) > 0 && (p.revents & (POLLERR | POLLHUP | POLLNVAL))) {
      if (why) *why = "the camera stopped streaming";
      return Grab::kFailed;
    }
  }
}

}  // namespace clogscope::vision
