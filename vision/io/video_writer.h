#pragma once

#include <memory>
#include <opencv2/core.hpp>
#include <string>

#include "vision/io/video_io.h"

namespace clogscope::vision {

// Writes a video through libavformat/libavcodec (FFmpeg from Debian) under a temporary name and
// renames it on Commit(): Motion JPEG in AVI (full-range 4:2:0, about 40 kB a 720p rendered
// frame), or H.264 through libx264 at crf 23, its default (4:2:0, limited range), in MP4, MOV or
// Matroska by the extension. The settings are those of OpenCV 4.6's writer, which this replaced:
// its files come out frame for frame the same.
class VideoFileWriter {
 public:
  // Throws std::invalid_argument naming the path when the folder is missing or not writable, or
  // the encoder or file cannot be opened.
  VideoFileWriter(const std::string& path, VideoKind kind, double fps, cv::Size size);
  ~VideoFileWriter();
  VideoFileWriter(const VideoFileWriter&) = delete;
  VideoFileWriter& operator=(const VideoFileWriter&) = delete;

  // An 8-bit grey or BGR frame of the size given. Throws std::runtime_error naming the path when
  // the encoder or the disk fails.
  void Write(const cv::Mat& frame);
  // Ends the stream and renames the file to its name. Throws std::runtime_error on failure.
  void Commit();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string path_;
  std::string temp_path_;
  bool committed_ = false;
};

}  // namespace clogscope::vision
