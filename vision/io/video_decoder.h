#pragma once

#include <atomic>
#include <memory>
#include <opencv2/core.hpp>
#include <string>

#include "vision/io/data_range.h"

namespace clogscope::vision {

// One decoded video frame as a grey image: the luma plane straight from the decoder (8-bit, or
// 16-bit for deeper formats), so no colour conversion is spent on what the measurement drops.
struct DecodedFrame {
  cv::Mat grey;
  // kLimited when grey is limited-range luma (black 16, white 235): a YUV frame not marked full
  // range. Grey, RGB and full-range ("yuvj", JPEG) frames are kFull.
  LumaRange luma_range = LumaRange::kFull;
  int index = 0;      // frame number: from the timestamp at constant frame rate, else decode order
  double time_s = 0;  // presentation time from the stream start
  bool corrupt = false;  // the decoder reported damage in this frame's data
  // Why grey is empty (or damaged), when known: a JPEG refused before decoding (cut short, too
  // large, without a frame header) or rejected by the decoder.
  std::string damage;
  // Why the frame before this one was not decoded, when the decoder knows (it was too large).
  std::string skipped_reason;
};

// How a decoder opens and reads: for live streams, limits on how long it may wait and a flag that
// interrupts it.
struct VideoDecoderOptions {
  int threads = 0;            // decoder threads, 0 = FFmpeg's choice
  double open_timeout_s = 0;  // opening and probing the stream may take this long; 0: no limit
  double read_timeout_s = 0;  // each read may wait this long for data; 0: no limit
  const std::atomic<bool>* stop = nullptr;  // when set and true, blocking calls return at once
  bool low_latency = false;  // live: short probing, no input buffering, one decoder thread
};

// Reads video files and streams (any URL FFmpeg reads) through libavformat/libavcodec (FFmpeg
// from Debian).
class VideoDecoder {
 public:
  // Throws std::invalid_argument naming the path when it cannot be opened (or opening timed out)
  // or has no video stream. threads: decoder threads, 0 = FFmpeg's choice.
  explicit VideoDecoder(const std::string& path, int threads = 0);
  VideoDecoder(const std::string& path, const VideoDecoderOptions& options);
  ~VideoDecoder();
  VideoDecoder(const VideoDecoder&) = delete;
  VideoDecoder& operator=(const VideoDecoder&) = delete;

  // Next frame in presentation order; false at the end of the stream. A packet the decoder rejects
  // is skipped and counted in corrupt_packets(). Motion JPEG, whose frames stand alone, instead
  // returns each frame it refuses (empty grey, corrupt, the reason in damage): a JPEG cut short,
  // declaring a frame over kMaxFramePixels (refused from its header, before any decoding), or
  // with damaged data (the decoder stops at the first error rather than conceal it).
  bool Read(DecodedFrame* frame);
  // Positions the stream so that the next Read() returns the first frame at or after time_s
  // (decodes forward from the preceding key frame). Returns false when the container cannot seek.
  bool SeekToTime(double time_s);

  double fps() const { return fps_; }
  double duration_s() const { return duration_s_; }
  int frame_count_estimate() const { return frame_count_; }
  int width() const;
  int height() const;
  int corrupt_packets() const { return corrupt_packets_; }
  // After Read() returned false: the read timed out or was stopped rather than reaching the end.
  bool interrupted() const;
  const std::string& path() const { return path_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string path_;
  double fps_ = 0;
  double duration_s_ = 0;
  int frame_count_ = -1;
  int next_index_ = 0;
  double read_timeout_s_ = 0;
  int corrupt_packets_ = 0;
  std::string skipped_reason_;  // for the next frame returned
  double skip_before_s_ = -1;   // after a seek: drop frames earlier than this
};

}  // namespace clogscope::vision
