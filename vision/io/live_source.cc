#include "vision/io/live_source.h"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>
#include <thread>
#include <vector>

#include "common/path_check.h"
#include "vision/io/image_folder.h"
#include "vision/io/source_name.h"
#include "vision/io/v4l2_camera.h"
#include "vision/io/video_decoder.h"
#include "vision/io/video_io.h"

namespace clogscope::vision {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

bool Stopped(const std::atomic<bool>* stop) { return stop && stop->load(); }

// Files and streams, decoded by FFmpeg to grey.
class DecodedSource : public FrameSource {
 public:
  DecodedSource(const std::string& source, SourceKind kind, const LiveSourceOptions& options,
                const std::atomic<bool>* stop)
      : FrameSource(source, kind),
        options_(options),
        stop_(stop),
        opened_(Clock::now()),
        shown_(RedactCredentials(source)) {
    VideoDecoderOptions d;
    d.stop = stop;
    if (kind == SourceKind::kStream) {
      d.open_timeout_s = options.open_timeout_s;
      d.read_timeout_s = options.read_timeout_s;
      d.low_latency = true;
    }
    decoder_ = std::make_unique<VideoDecoder>(source, d);
    if (kind == SourceKind::kStream) {
      // A stream may open and then send nothing: wait for the first frame here, so that a camera
      // that never delivers is refused like one that cannot be opened.
      DecodedFrame f;
      if (!decoder_->Read(&f)) {
        if (Stopped(stop)) throw std::invalid_argument(shown_ + ": stopped while opening");
        throw std::invalid_argument(
            fmt::format("{}: opened, but no frame within {:g} s (--open-timeout-s)", shown_,
                        std::max(options.open_timeout_s, options.read_timeout_s)));
      }
      pending_ = std::move(f);
    }
  }

  bool live() const override { return kind_ == SourceKind::kStream; }

  FrameRead Read(InputFrame* out, std::string* why) override {
    if (Stopped(stop_)) return FrameRead::kStopped;
    DecodedFrame f;
    if (pending_) {
      f = std::move(*pending_);
      pending_.reset();
    } else if (!decoder_->Read(&f)) {
      if (Stopped(stop_)) return FrameRead::kStopped;
      if (kind_ == SourceKind::kVideo) return FrameRead::kEnd;
      if (why)
        *why = decoder_->interrupted() ? fmt::format("no data for {:g} s", options_.read_timeout_s)
                                       : std::string("the stream ended");
      return FrameRead::kDropped;
    }
    if (kind_ == SourceKind::kVideo && options_.realtime) {
      // Pace at the video's own timestamps from the first frame on.
      if (!first_time_s_) first_time_s_ = f.time_s;
      const double due_s = f.time_s - *first_time_s_;
      const bool waited =
          options_.wait_until
              ? options_.wait_until(due_s)
              : SleepUnlessStopped(opened_ + std::chrono::duration_cast<Clock::duration>(
                                                 std::chrono::duration<double>(due_s)),
                                   stop_);
      if (!waited || Stopped(stop_)) return FrameRead::kStopped;
    }
    if (!f.skipped_reason.empty()) {
      // The decoder lost the frame before this one (it was too large): that frame is delivered
      // first, without pixels, and this one on the next read.
      DecodedFrame lost;
      lost.index = f.index;
      lost.time_s = f.time_s;
      lost.corrupt = true;
      lost.damage = std::move(f.skipped_reason);
      f.skipped_reason.clear();
      pending_ = std::move(f);
      f = std::move(lost);
    }
    out->arrival = Clock::now();
    // A frame the decoder refused or reported damaged is delivered without pixels: what it
    // concealed would be measured as the strand.
    if (f.corrupt) f.grey.release();
    out->image = std::move(f.grey);
    out->luma_range = f.luma_range;
    out->error = !out->image.empty() ? "" : f.damage.empty() ? "undecodable frame" : f.damage;
    out->time_s = kind_ == SourceKind::kVideo ? f.time_s : SecondsSince(opened_);
    out->index = index_++;
    out->source = shown_;
    return FrameRead::kFrame;
  }

 private:
  LiveSourceOptions options_;
  const std::atomic<bool>* stop_;
  Clock::time_point opened_;
  std::string shown_;  // the source as messages and frames name it
  std::unique_ptr<VideoDecoder> decoder_;
  std::optional<DecodedFrame> pending_;
  std::optional<double> first_time_s_;
  int64_t index_ = 0;
};

// A V4L2 camera, its frames' luma (V4l2Camera).
class DeviceSource : public FrameSource {
 public:
  DeviceSource(const std::string& source, const std::atomic<bool>* stop)
      : FrameSource(source, SourceKind::kDevice), stop_(stop), opened_(Clock::now()) {
    std::error_code ec;
    if (!fs::exists(source, ec)) throw std::invalid_argument(source + ": no such device");
    camera_ = std::make_unique<V4l2Camera>(source);
    std::string why;
    const V4l2Camera::Grab g = camera_->Read(&first_, kFrameWaitS, stop_, &why);
    if (g == V4l2Camera::Grab::kStopped)
      throw std::invalid_argument(source + ": stopped while opening");
    if (g != V4l2Camera::Grab::kFrame) throw std::invalid_argument(source + ": opened, but " + why);
  }

  FrameRead Read(InputFrame* out, std::string* why) override {
    if (Stopped(stop_)) return FrameRead::kStopped;
    cv::Mat frame;
    if (!first_.empty()) {
      frame = first_;
      first_.release();
    } else {
      const V4l2Camera::Grab g = camera_->Read(&frame, kFrameWaitS, stop_, why);
      if (g == V4l2Camera::Grab::kStopped) return FrameRead::kStopped;
      if (g == V4l2Camera::Grab::kFailed) return FrameRead::kDropped;
    }
    out->arrival = Clock::now();
    out->image = frame;
    out->luma_range = camera_->luma_range();
    out->error.clear();
    out->time_s = SecondsSince(opened_);
    out->index = index_++;
    out->source = path_;
    return FrameRead::kFrame;
  }

  bool live() const override { return true; }

 private:
  // A camera that sends nothing this long has stopped (OpenCV's V4L2 capture waited as long).
  static constexpr double kFrameWaitS = 10;
  const std::atomic<bool>* stop_;
  Clock::time_point opened_;
  std::unique_ptr<V4l2Camera> camera_;
  cv::Mat first_;
  int64_t index_ = 0;
};

// A folder a camera writes images into. The images there at Open are not taken; every image that
// appears afterwards (a new name, or a name whose file was replaced or rewritten: another inode,
// size or modification time) is taken once, in order of arrival — the poll that first saw it, then
// its name — never by its modification time, which a camera whose clock is off puts anywhere. An
// image is taken once its size and time have held for one poll, so a half-written one is not read.
// What is remembered is one entry per image in the folder: names that vanish are forgotten.
class FolderSource : public FrameSource {
 public:
  FolderSource(const std::string& source, const LiveSourceOptions& options,
               const std::atomic<bool>* stop)
      : FrameSource(source, SourceKind::kFolder),
        options_(options),
        stop_(stop),
        opened_(Clock::now()) {
    std::error_code ec;
    if (!fs::is_directory(source, ec)) throw std::invalid_argument(source + ": not a directory");
    for (const ImageFileEntry& f : List()) seen_[f.name] = {f, 0, /*taken=*/true, true};
  }

  bool live() const override { return true; }

  FrameRead Read(InputFrame* out, std::string* why) override {
    while (!Stopped(stop_)) {
      std::error_code ec;
      if (!fs::is_directory(path_, ec)) {
        if (why) *why = "the folder is gone";
        return FrameRead::kDropped;
      }
      Update(List());
      // The earliest arrival not taken yet (names in order within one poll); it waits until it
      // has held still for a poll, and the later ones wait behind it.
      auto next = seen_.end();
      for (auto it = seen_.begin(); it != seen_.end(); ++it) {
        if (!it->second.taken && (next == seen_.end() || it->second.arrival < next->second.arrival))
          next = it;
      }
      if (next != seen_.end() && next->second.held) {
        next->second.taken = true;
        out->arrival = Clock::now();
        out->source = next->second.file.path;
        out->image = ReadImage(out->source, &out->error);
        out->time_s = SecondsSince(opened_);
        out->index = index_++;
        return FrameRead::kFrame;
      }
      if (!SleepUnlessStopped(
              Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                 std::chrono::duration<double>(options_.folder_poll_s)),
              stop_))
        break;
    }
    return FrameRead::kStopped;
  }

 private:
  struct Seen {
    ImageFileEntry file;  // as last listed
    int64_t arrival = 0;  // the poll that first saw this file
    bool taken = false;
    bool held = false;  // unchanged since the poll before
  };

  // The same file, unchanged: inode, size and modification time alike.
  static bool Unchanged(const ImageFileEntry& a, const ImageFileEntry& b) {
    return a.inode == b.inode && a.size == b.size && a.mtime_ns == b.mtime_ns;
  }

  // The folder's image files (a folder that cannot be listed: what was listed).
  std::vector<ImageFileEntry> List() const {
    std::vector<ImageFileEntry> files;
    ListImageFiles(path_, &files);
    return files;
  }

  void Update(std::vector<ImageFileEntry> listing) {
    ++polls_;
    std::map<std::string, Seen> updated;
    for (ImageFileEntry& f : listing) {
      const auto it = seen_.find(f.name);
      Seen& s = updated[f.name];
      if (it == seen_.end() || it->second.file.inode != f.inode ||
          (it->second.taken && !Unchanged(it->second.file, f))) {
        s = {std::move(f), polls_, false, false};  // arrived (or arrived anew)
      } else {
        s = std::move(it->second);
        if (!s.taken) s.held = Unchanged(s.file, f);
        s.file = std::move(f);
      }
    }
    seen_.swap(updated);
  }

  LiveSourceOptions options_;
  const std::atomic<bool>* stop_;
  Clock::time_point opened_;
  std::map<std::string, Seen> seen_;  // by file name
  int64_t polls_ = 0;
  int64_t index_ = 0;
};

}  // namespace

bool SleepUnlessStopped(Clock::time_point until, const std::atomic<bool>* stop) {
  while (Clock::now() < until) {
    if (Stopped(stop)) return false;
    std::this_thread::sleep_for(
        std::min<Clock::duration>(until - Clock::now(), std::chrono::milliseconds(20)));
  }
  return !Stopped(stop);
}

bool LiveSourceOptions::Validate(std::string* why) const {
  if (!(open_timeout_s > 0 && open_timeout_s <= 3600))
    *why = fmt::format("--open-timeout-s {:g}: must be in (0, 3600] s", open_timeout_s);
  else if (!(read_timeout_s > 0 && read_timeout_s <= 3600))
    *why = fmt::format("read timeout {:g} s: must be in (0, 3600] s", read_timeout_s);
  else if (!(folder_poll_s >= 0.01 && folder_poll_s <= 60))
    *why = fmt::format("folder poll {:g} s: must be in [0.01, 60] s", folder_poll_s);
  else
    return true;
  return false;
}

SourceKind LiveSourceKindOf(const std::string& source) {
  if (source.rfind("/dev/", 0) == 0) return SourceKind::kDevice;
  if (source.find("://") != std::string::npos) return SourceKind::kStream;
  std::error_code ec;
  if (fs::is_directory(source, ec)) return SourceKind::kFolder;
  return SourceKind::kVideo;
}

std::unique_ptr<FrameSource> OpenLiveSource(const std::string& source,
                                            const LiveSourceOptions& options,
                                            const std::atomic<bool>* stop) {
  std::string why;
  if (!options.Validate(&why)) throw std::invalid_argument(why);
  if (source.empty()) throw std::invalid_argument("no source given");
  switch (LiveSourceKindOf(source)) {
    case SourceKind::kDevice:
      return std::make_unique<DeviceSource>(source, stop);
    case SourceKind::kStream:
      return std::make_unique<DecodedSource>(source, SourceKind::kStream, options, stop);
    case SourceKind::kFolder:
      return std::make_unique<FolderSource>(source, options, stop);
    case SourceKind::kVideo:
    case SourceKind::kImages:
      RequireInputPath("", source, PathExpect::kFile);
      return std::make_unique<DecodedSource>(source, SourceKind::kVideo, options, stop);
  }
  throw std::invalid_argument(RedactCredentials(source) + ": unknown kind of source");
}

}  // namespace clogscope::vision
