#include "vision/io/frame_source.h"

#include <fmt/format.h>

#include <algorithm>
#include <deque>
#include <stdexcept>
#include <thread>
#include <vector>

#include "common/path_check.h"
#include "vision/io/image_folder.h"
#include "vision/io/source_name.h"
#include "vision/io/video_decoder.h"
#include "vision/io/video_io.h"

namespace clogscope::vision {
namespace {

class ImageListSource : public FrameSource {
 public:
  // first: the first file already decoded (Open() decodes a single image to check it), or empty.
  ImageListSource(std::string path, std::vector<std::string> files, cv::Mat first = cv::Mat())
      : FrameSource(std::move(path), SourceKind::kImages),
        files_(std::move(files)),
        first_(std::move(first)) {}
  FrameRead Read(InputFrame* frame, std::string* /*why*/) override {
    if (next_ >= files_.size()) return FrameRead::kEnd;
    frame->source = files_[next_];
    frame->index = static_cast<int64_t>(next_);
    frame->time_s = -1;
    frame->error.clear();
    // A decoded first image is used once, not decoded again (a 720p colour PNG costs as much
    // as measuring it).
    if (next_ == 0 && !first_.empty()) {
      frame->image = std::move(first_);
    } else {
      frame->image = ReadImage(files_[next_], &frame->error);
    }
    ++next_;
    return FrameRead::kFrame;
  }
  bool SeekToFrame(int64_t index) override {
    next_ = static_cast<size_t>(std::max<int64_t>(0, index));
    return true;
  }
  int expected_frames() const override { return static_cast<int>(files_.size()); }

 private:
  std::vector<std::string> files_;
  cv::Mat first_;
  size_t next_ = 0;
};

class VideoSource : public FrameSource {
 public:
  VideoSource(std::string path, const VideoReadOptions& options)
      : FrameSource(std::move(path), SourceKind::kVideo),
        options_(options),
        decoder_(path_, options.decoder_threads),
        shown_(RedactCredentials(path_)) {
    encoder_ = ReadX264Settings(path_);
  }
  // For Open(): a video must hold a frame.
  void RequireAFrame() {
    if (!Fill()) throw std::invalid_argument(shown_ + ": video has no frames");
  }
  FrameRead Read(InputFrame* frame, std::string* /*why*/) override {
    if (pending_.empty() && !Fill()) return FrameRead::kEnd;
    *frame = std::move(pending_.front());
    pending_.pop_front();
    return FrameRead::kFrame;
  }
  bool SeekToTime(double time_s) override {
    pending_.clear();
    seeked_ = true;  // the frame numbers jump: no gap
    return decoder_.SeekToTime(time_s);
  }
  int expected_frames() const override { return decoder_.frame_count_estimate(); }
  double fps() const override { return decoder_.fps(); }
  double duration_s() const override { return decoder_.duration_s(); }

 private:
  // Queues the next decoded frame, preceded (with gap entries) by an undecodable entry for each
  // frame number the decoder skipped (damaged data leaves a gap in the timestamps).
  bool Fill() {
    DecodedFrame d;
    if (!decoder_.Read(&d)) return false;
    if (seeked_) next_index_ = d.index;
    seeked_ = false;
    // One entry per gap, however long: a jump in the timestamps is not a million lost frames.
    if (options_.gap_entries && d.index > next_index_) {
      const int missing = d.index - next_index_;
      InputFrame bad;
      bad.source = shown_;
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
    good.source = shown_;
    good.index = d.index;
    good.time_s = d.time_s;
    good.image = std::move(d.grey);
    good.luma_range = d.luma_range;
    if (d.corrupt) good.error = d.damage.empty() ? "decoder reported damage" : d.damage;
    pending_.push_back(std::move(good));
    next_index_ = d.index + 1;
    return true;
  }

  VideoReadOptions options_;
  VideoDecoder decoder_;
  std::string shown_;  // the path as messages and frames name it
  int next_index_ = 0;
  bool seeked_ = false;
  std::deque<InputFrame> pending_;
};

// The images of a directory, sorted; throws naming it when it cannot be listed or holds none.
std::vector<std::string> ImagesOf(const std::string& dir) {
  std::vector<ImageFileEntry> entries;
  if (!ListImageFiles(dir, &entries)) throw std::invalid_argument(dir + ": cannot list directory");
  if (entries.empty()) throw std::invalid_argument(dir + ": directory holds no images");
  std::vector<std::string> files;
  for (auto& e : entries) files.push_back(std::move(e.path));
  return files;
}

std::unique_ptr<FrameSource> OneImage(const std::string& path, cv::Mat decoded) {
  return std::make_unique<ImageListSource>(path, std::vector<std::string>{path},
                                           std::move(decoded));
}

std::unique_ptr<FrameSource> VideoWithAFrame(const std::string& path) {
  VideoReadOptions options;
  options.decoder_threads = DecoderThreadsBesideMeasuring();
  auto v = std::make_unique<VideoSource>(path, options);
  v->RequireAFrame();
  return v;
}

}  // namespace

int DecoderThreadsBesideMeasuring() {
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()) - 1);
}

const char* SourceKindName(SourceKind kind) {
  switch (kind) {
    case SourceKind::kImages:
      return "images";
    case SourceKind::kVideo:
      return "file";
    case SourceKind::kDevice:
      return "device";
    case SourceKind::kStream:
      return "stream";
    case SourceKind::kFolder:
      return "folder";
  }
  return "?";
}

std::unique_ptr<FrameSource> FrameSource::Open(const std::string& path) {
  // No such file, a name too long, a loop of symbolic links, a FIFO or device (it would block or
  // never end; a camera is `watch`'s, not a file's): the one path check's line.
  RequireInputPath("", path, PathExpect::kFileOrDirectory);
  if (InspectPath(path) == PathKind::kDirectory)
    return std::make_unique<ImageListSource>(path, ImagesOf(path));
  if (IsVideoPath(path)) return VideoWithAFrame(path);
  if (IsImagePath(path)) {
    std::string error;
    cv::Mat image = ReadImage(path, &error);
    if (image.empty()) throw std::invalid_argument(path + ": " + error);
    return OneImage(path, std::move(image));
  }
  // Unknown extension: an image if it decodes as one, else a video.
  std::string error;
  if (cv::Mat image = ReadImage(path, &error); !image.empty())
    return OneImage(path, std::move(image));
  try {
    return VideoWithAFrame(path);
  } catch (const std::invalid_argument&) {
    throw std::invalid_argument(path + ": neither a readable image nor a video");
  }
}

std::unique_ptr<FrameSource> FrameSource::OpenVideo(const std::string& path,
                                                    const VideoReadOptions& options) {
  return std::make_unique<VideoSource>(path, options);
}

std::unique_ptr<FrameSource> FrameSource::OpenImageFolder(const std::string& path) {
  if (InspectPath(path) != PathKind::kDirectory)
    throw std::invalid_argument(path + ": no such directory");
  return std::make_unique<ImageListSource>(path, ImagesOf(path));
}

}  // namespace clogscope::vision
