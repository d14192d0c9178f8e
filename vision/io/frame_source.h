#pragma once

// The tool's one way to read frames. Every command reads through FrameSource:
//   measure, inspect   FrameSource::Open(path): an image, a folder of images, a video.
//   run (a step)       FrameSource::OpenVideo / OpenImageFolder, seeking to the samples it needs.
//   run (feedstock)    FrameSource::OpenVideo, seeking to each pair of frames.
//   watch              OpenLiveSource (live_source.h): a camera, a stream, a video, a folder a
//                      camera writes into.
// Only vision/io opens a video (VideoDecoder, V4L2 through libv4l2) or lists a folder.

#include <chrono>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <string>

#include "vision/io/data_range.h"
#include "vision/io/encoder_note.h"

namespace clogscope::vision {

// Sampling a video: seek rather than decode forward when the next frame wanted is further ahead
// than this.
inline constexpr double kSeekAheadS = 2.0;

// What a source reads.
enum class SourceKind {
  kImages,  // an image file, or a folder's images sorted by name (read once)
  kVideo,   // a video file
  kDevice,  // a V4L2 camera: /dev/videoN (libv4l2)
  kStream,  // a URL FFmpeg reads: http://…/?action=stream (MJPEG), rtsp://, tcp://, udp://
  kFolder,  // a folder a camera writes images into: new files are taken as they appear
};
// The kind in the watch's words: "images", "file" (a video), "device", "stream", "folder".
const char* SourceKindName(SourceKind kind);

// One frame of an input, as read.
struct InputFrame {
  std::string source;  // the file the frame came from (the image, or the video, stream, device)
  int64_t index = 0;   // frame number within the input, from 0 (live: frames delivered so far)
  // Position in a video, seconds; -1 for still images read once; live devices, streams and
  // folders: seconds since the source was opened.
  double time_s = -1;
  cv::Mat image;  // empty when the frame could not be decoded; video frames are grey (luma)
  // Where image's black and white lie: limited range for most video luma (DecodedFrame).
  LumaRange luma_range = LumaRange::kFull;
  std::string error;  // why image is empty, or a warning about a damaged but decoded frame
  std::chrono::steady_clock::time_point arrival;  // live sources: when the frame was in hand
};

// What a read gave.
enum class FrameRead {
  kFrame,    // *frame holds the next frame (its image may be empty: see its error)
  kEnd,      // no more frames (a file, a folder read once)
  kDropped,  // a live source stopped delivering (stream closed, timed out, device gone): reopen
  kStopped,  // the stop flag the source was opened with was raised
};

// Decoder threads for a video whose frames are measured as they come, on a thread of their own:
// every core but that one (at least one). FFmpeg's own choice (a thread per core) competes with
// the measuring: on two cores a 720p H.264 file was measured at 1570 frames/s so, 1870 with one
// decoder thread.
int DecoderThreadsBesideMeasuring();

// How a video is read for sampling (steps and feedstock of `run`).
struct VideoReadOptions {
  int decoder_threads = 0;  // FFmpeg decoder threads, 0 = FFmpeg's choice
  // One undecodable entry for each gap in the frame numbers (damaged data, a jump in the
  // timestamps); off: only the frames decoded.
  bool gap_entries = true;
};

// Frames of a file, a folder, a video or a live source, read in order.
class FrameSource {
 public:
  // An image file, a directory of images (sorted by name) or a video file (entries for gaps,
  // DecoderThreadsBesideMeasuring()).
  // Throws std::invalid_argument naming the path when it does not exist, is an empty directory,
  // cannot be opened, or is a video without frames.
  static std::unique_ptr<FrameSource> Open(const std::string& path);
  // The video at `path` whatever its name (an empty video reads no frame). Throws
  // std::invalid_argument with the decoder's line when it cannot be opened.
  static std::unique_ptr<FrameSource> OpenVideo(const std::string& path,
                                                const VideoReadOptions& options);
  // The images of a directory, sorted by name. Throws std::invalid_argument naming the path when
  // it is not a directory, cannot be listed or holds no image.
  static std::unique_ptr<FrameSource> OpenImageFolder(const std::string& path);

  virtual ~FrameSource() = default;
  // The next frame. An undecodable frame comes back with an empty image and `error` set, and
  // reading goes on. `why` (optional) says what happened on kDropped. Live sources block until a
  // frame arrives, their read timeout passes, or their stop flag is raised.
  virtual FrameRead Read(InputFrame* frame, std::string* why = nullptr) = 0;
  // Read() for callers that read to the end: true for a frame, false otherwise.
  bool Next(InputFrame* frame) { return Read(frame) == FrameRead::kFrame; }
  // Videos: the next Read returns the first frame at or after time_s (decoding forward from the
  // preceding key frame). False when this source or its container cannot seek.
  virtual bool SeekToTime(double /*time_s*/) { return false; }
  // Image lists: the next Read returns frame `index` (past the end: none). False when this source
  // cannot.
  virtual bool SeekToFrame(int64_t /*index*/) { return false; }
  // Frames expected (from the container for videos; may be approximate), or -1 when unknown.
  virtual int expected_frames() const { return -1; }
  virtual double fps() const { return 0; }
  virtual double duration_s() const { return 0; }  // videos: from the container; 0 unknown
  // True when frame times are wall-clock (devices, streams, folders), false for a file's own.
  virtual bool live() const { return false; }
  SourceKind kind() const { return kind_; }
  const std::string& path() const { return path_; }
  // The settings x264 wrote into a video file it encoded (not found for other sources).
  const X264Settings& encoder() const { return encoder_; }

 protected:
  FrameSource(std::string path, SourceKind kind) : path_(std::move(path)), kind_(kind) {}
  std::string path_;
  SourceKind kind_;
  X264Settings encoder_;
};

}  // namespace clogscope::vision
