#include "vision/frame_source.h"

#include <algorithm>
#include <deque>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <stdexcept>
#include <vector>

#include "vision/video_io.h"

namespace clogscope::vision {
namespace {

namespace fs = std::filesystem;

cv::Mat ReadImage(const std::string& path, std::string* error) {
  cv::Mat img = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (img.empty()) {
    *error = "cannot decode image";
  } else if (img.depth() != CV_8U && img.depth() != CV_16U) {
    *error = "unsupported pixel type (need 8- or 16-bit integer)";
    img.release();
  }
  return img;
}

class ImageListSource : public FrameSource {
 public:
  ImageListSource(std::string path, std::vector<std::string> files)
      : FrameSource(std::move(path)), files_(std::move(files)) {}
  bool Next(InputFrame* frame) override {
    if (next_ >= files_.size()) return false;
    frame->source = files_[next_];
    frame->index = static_cast<int>(next_);
    frame->time_s = -1;
    frame->error.clear();
    frame->image = ReadImage(files_[next_], &frame->error);
    ++next_;
    return true;
  }
  int expected_frames() const override { return static_cast<int>(files_.size()); }

 private:
  std::vector<std::string> files_;
  size_t next_ = 0;
};

class VideoSource : public FrameSource {
 public:
  explicit VideoSource(std::string path) : FrameSource(std::move(path)) {
    if (!cap_.open(path_, cv::CAP_FFMPEG)) {
      throw std::invalid_argument(path_ + ": cannot open as video");
    }
    expected_ = static_cast<int>(cap_.get(cv::CAP_PROP_FRAME_COUNT));
    fps_ = cap_.get(cv::CAP_PROP_FPS);
    if (!Fill()) throw std::invalid_argument(path_ + ": video has no frames");
  }
  bool Next(InputFrame* frame) override {
    if (pending_.empty() && !Fill()) return false;
    *frame = std::move(pending_.front());
    pending_.pop_front();
    return true;
  }
  int expected_frames() const override { return expected_; }
  double fps() const override { return fps_; }

 private:
  // Queues the next decodable frame. A failed read before the expected end is retried; frames
  // that failed are queued as undecodable only when a later frame decodes (the container's count is
  // approximate, so failures at the very end are just the end).
  bool Fill() {
    constexpr int kMaxConsecutiveFailures = 25;
    int failures = 0;
    cv::Mat img;
    while (!(cap_.read(img) && !img.empty())) {
      ++failures;
      if (index_ + failures >= expected_ || failures >= kMaxConsecutiveFailures) return false;
    }
    for (int i = 0; i < failures; ++i) {
      InputFrame bad;
      bad.source = path_;
      bad.index = index_++;
      bad.error = "cannot decode frame";
      pending_.push_back(std::move(bad));
    }
    InputFrame good;
    good.source = path_;
    good.index = index_++;
    good.time_s = fps_ > 0 ? good.index / fps_ : cap_.get(cv::CAP_PROP_POS_MSEC) / 1000.0;
    good.image = img;
    pending_.push_back(std::move(good));
    return true;
  }

  cv::VideoCapture cap_;
  int expected_ = -1;
  double fps_ = 0;
  int index_ = 0;
  std::deque<InputFrame> pending_;
};

}  // namespace

std::unique_ptr<FrameSource> FrameSource::Open(const std::string& path) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st)) throw std::invalid_argument(path + ": no such file or directory");
  if (fs::is_directory(st)) {
    std::vector<std::string> files;
    for (const auto& entry : fs::directory_iterator(path, ec)) {
      if (entry.is_regular_file() && IsImagePath(entry.path().string()))
        files.push_back(entry.path().string());
    }
    if (ec) throw std::invalid_argument(path + ": cannot list directory");
    if (files.empty()) throw std::invalid_argument(path + ": directory holds no images");
    std::sort(files.begin(), files.end());
    return std::make_unique<ImageListSource>(path, std::move(files));
  }
  if (IsVideoPath(path)) return std::make_unique<VideoSource>(path);
  if (IsImagePath(path)) {
    std::string error;
    if (ReadImage(path, &error).empty()) throw std::invalid_argument(path + ": " + error);
    return std::make_unique<ImageListSource>(path, std::vector<std::string>{path});
  }
  // Unknown extension: an image if it decodes as one, else a video.
  std::string error;
  if (!ReadImage(path, &error).empty())
    return std::make_unique<ImageListSource>(path, std::vector<std::string>{path});
  try {
    return std::make_unique<VideoSource>(path);
  } catch (const std::invalid_argument&) {
    throw std::invalid_argument(path + ": neither a readable image nor a video");
  }
}

}  // namespace clogscope::vision
