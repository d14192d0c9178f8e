#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <string>

namespace clogscope::vision {

// Where `watch` reads frames from.
enum class LiveSourceKind {
  kDevice,  // a V4L2 camera: /dev/videoN (read through OpenCV's V4L2 backend)
  kStream,  // a URL FFmpeg reads: http://…/?action=stream (MJPEG), rtsp://, tcp://, udp://
  kFile,    // a video file, read as fast as it decodes or paced at its frame rate (realtime)
  kFolder,  // a directory a camera writes images into: new files are picked up as they appear
};
const char* LiveSourceKindName(LiveSourceKind kind);

struct LiveSourceOptions {
  bool realtime = false;       // file: deliver each frame at its timestamp (replays, tests)
  double open_timeout_s = 10;  // a stream that yields no frame within this is refused
  double read_timeout_s = 5;   // a stream silent this long has dropped
  double folder_poll_s = 0.1;  // how often a folder is listed
  bool Validate(std::string* why) const;
};

struct LiveFrame {
  cv::Mat image;      // grey (8- or 16-bit) or as stored (folder images); empty when unreadable
  double time_s = 0;  // file: the video's timestamp; live sources: seconds since Open()
  int64_t index = 0;  // frames delivered since Open()
  std::string name;   // folder: the image file
  std::string error;  // why image is empty
  std::chrono::steady_clock::time_point arrival;  // when the frame was in hand (decoded)
};

enum class LiveRead {
  kFrame,    // *frame holds the next frame (its image may be empty: see error)
  kEnd,      // a file has no more frames
  kDropped,  // a live source stopped delivering (stream closed, timed out, device gone): reopen
  kStopped,  // the stop flag was raised
};

// A camera, stream, file or folder, read frame by frame. Blocking reads return within the read
// timeout (or the folder poll) and as soon as the stop flag turns true.
class LiveSource {
 public:
  // Which kind SOURCE names: /dev/… a device, "scheme://…" a stream, a directory a folder, else a
  // file.
  static LiveSourceKind KindOf(const std::string& source);
  // Opens SOURCE and waits for its first frame (streams and devices, within open_timeout_s).
  // Throws std::invalid_argument with one line naming SOURCE and why when it cannot be opened.
  static std::unique_ptr<LiveSource> Open(const std::string& source,
                                          const LiveSourceOptions& options,
                                          const std::atomic<bool>* stop);
  virtual ~LiveSource() = default;
  // The next frame; `why` says what happened on kDropped.
  virtual LiveRead Next(LiveFrame* frame, std::string* why) = 0;
  // True when frame times are wall-clock (devices, streams, folders), false for a file's own.
  virtual bool live() const { return true; }
  LiveSourceKind kind() const { return kind_; }
  const std::string& source() const { return source_; }

 protected:
  LiveSource(std::string source, LiveSourceKind kind) : source_(std::move(source)), kind_(kind) {}
  std::string source_;
  LiveSourceKind kind_;
};

// Sleeps until `until` in slices of at most 20 ms, so that a raised stop flag is seen soon.
// Returns false when stopped.
bool SleepUnlessStopped(std::chrono::steady_clock::time_point until, const std::atomic<bool>* stop);

}  // namespace clogscope::vision
