#include "vision/io/frame_source.h"

#include <fmt/format.h>

#include <algorithm>
#include <deque>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <vector>

#include "common/atomic_file.h"
#include "common/path_check.h"
#include "vision/io/video_decoder.h"
#include "vision/io/video_io.h"

namespace clogscope::vision {
namespace {

namespace fs = std::filesystem;

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
  explicit VideoSource(std::string path) : FrameSource(std::move(path)), decoder_(path_) {
    if (!Fill()) throw std::invalid_argument(path_ + ": video has no frames");
  }
  bool Next(InputFrame* frame) override {
    if (pending_.empty() && !Fill()) return false;
    *frame = std::move(pending_.front());
    pending_.pop_front();
    return true;
  }
  int expected_frames() const override { return decoder_.frame_count_estimate(); }
  double fps() const override { return decoder_.fps(); }

 private:
  // Queues the next decoded frame, preceded by an undecodable entry for each frame number the
  // decoder skipped (damaged data leaves a gap in the timestamps).
  bool Fill() {
    DecodedFrame d;
    if (!decoder_.Read(&d)) return false;
    // One entry per gap, however long: a jump in the timestamps is not a million lost frames.
    if (d.index > next_index_) {
      const int missing = d.index - next_index_;
      InputFrame bad;
      bad.source = path_;
      bad.index = next_index_;
      bad.time_s = decoder_.fps() > 0 ? next_index_ / decoder_.fps() : -1;
      bad.error = missing == 1 ? "cannot decode frame"
                               : fmt::format(
                                     "{} frames missing ({} to {}): damaged data or a jump of "
                                     "{:.6g} s in the timestamps",
                                     missing, next_index_, d.index - 1, d.time_s - bad.time_s);
      if (!d.skipped_reason.empty()) bad.error += " (" + d.skipped_reason + ")";
      pending_.push_back(std::move(bad));
    }
    InputFrame good;
    good.source = path_;
    good.index = d.index;
    good.time_s = d.time_s;
    good.image = std::move(d.grey);
    if (d.corrupt) good.error = "decoder reported damage";
    pending_.push_back(std::move(good));
    next_index_ = d.index + 1;
    return true;
  }

  VideoDecoder decoder_;
  int next_index_ = 0;
  std::deque<InputFrame> pending_;
};

}  // namespace

std::unique_ptr<FrameSource> FrameSource::Open(const std::string& path) {
  // No such file, a name too long, a loop of symbolic links: the one path check's line.
  RequireInputPath("", path, PathExpect::kFileOrDirectory);
  if (InspectPath(path) == PathKind::kDirectory) {
    std::error_code ec;
    std::vector<std::string> files;
    for (fs::directory_iterator it(path, ec), end; !ec && it != end; it.increment(ec)) {
      // An entry that cannot be followed (a link to itself, a dangling link) is not an image.
      std::error_code entry_ec;
      if (it->is_regular_file(entry_ec) && !entry_ec && IsImagePath(it->path().string()))
        files.push_back(it->path().string());
    }
    if (ec) throw std::invalid_argument(path + ": cannot list directory");
    if (files.empty()) throw std::invalid_argument(path + ": directory holds no images");
    std::sort(files.begin(), files.end());
    return std::make_unique<ImageListSource>(path, std::move(files));
  }
  // A FIFO or device would block or never end (a camera is `watch`'s, not a file's).
  std::string why;
  if (!IsRegularFile(path, &why)) throw std::invalid_argument(path + ": " + why);
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
