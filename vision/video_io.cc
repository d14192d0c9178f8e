#include "vision/video_io.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <vector>

#include "common/atomic_file.h"

namespace clogscope::vision {
namespace {
std::string LowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext;
}
}  // namespace

VideoKind VideoKindForPath(const std::string& path) {
  const std::string ext = LowerExtension(path);
  if (ext == ".avi") return VideoKind::kMjpegAvi;
  if (ext == ".mp4" || ext == ".m4v" || ext == ".mov" || ext == ".mkv") return VideoKind::kH264Mp4;
  return VideoKind::kNone;
}

bool IsImagePath(const std::string& path) {
  static const char* kExts[] = {".png", ".tif", ".tiff", ".bmp", ".jpg", ".jpeg", ".pgm", ".ppm"};
  const std::string ext = LowerExtension(path);
  return std::any_of(std::begin(kExts), std::end(kExts), [&](const char* e) { return ext == e; });
}

bool IsVideoPath(const std::string& path) {
  const std::string ext = LowerExtension(path);
  return VideoKindForPath(path) != VideoKind::kNone || ext == ".webm" || ext == ".mpg" ||
         ext == ".mpeg" || ext == ".h264" || ext == ".264";
}

VideoFileWriter::VideoFileWriter(const std::string& path, VideoKind kind, double fps, cv::Size size)
    : path_(path) {
  // The temporary name keeps the extension: FFmpeg picks the container from it.
  std::filesystem::path p(path);
  temp_path_ =
      (p.parent_path() / (p.stem().string() + ".partial" + p.extension().string())).string();
  if (!(fps > 0)) throw std::invalid_argument(path + ": frame rate must be positive");
  // The encoder cannot tell a missing folder from a codec it lacks: look first.
  const std::filesystem::path dir = p.has_parent_path() ? p.parent_path() : ".";
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec))
    throw std::invalid_argument(path + ": folder " + dir.string() + " does not exist");
  if (access(dir.c_str(), W_OK) != 0)
    throw std::invalid_argument(path + ": folder " + dir.string() + " is not writable");
  const int fourcc = kind == VideoKind::kMjpegAvi ? cv::VideoWriter::fourcc('M', 'J', 'P', 'G')
                                                  : cv::VideoWriter::fourcc('a', 'v', 'c', '1');
  // Always a colour stream: grey input is expanded in Write(), which every codec and player
  // accepts.
  writer_.open(temp_path_, cv::CAP_FFMPEG, fourcc, fps, size, true);
  if (!writer_.isOpened()) {
    throw std::invalid_argument(path + ": cannot open a video encoder for this file type");
  }
}

VideoFileWriter::~VideoFileWriter() {
  if (!committed_) {
    writer_.release();
    std::remove(temp_path_.c_str());
  }
}

void VideoFileWriter::Write(const cv::Mat& frame) {
  if (frame.channels() == 1) {
    cv::Mat bgr;
    cv::cvtColor(frame, bgr, cv::COLOR_GRAY2BGR);
    writer_.write(bgr);
  } else {
    writer_.write(frame);
  }
}

void VideoFileWriter::Commit() {
  writer_.release();
  if (std::rename(temp_path_.c_str(), path_.c_str()) != 0) {
    throw std::runtime_error(path_ + ": cannot rename from " + temp_path_);
  }
  committed_ = true;
}

cv::Mat ReadImage(const std::string& path, std::string* error) {
  cv::Mat img;
  try {
    img = cv::imread(path, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    // OpenCV asserts on headers it refuses (say, 65535×65535 pixels): say so in our words.
    *error = e.err.find("CV_IO_MAX_IMAGE_PIXELS") != std::string::npos
                 ? "image too large to decode (its header claims over 2^30 pixels)"
                 : "cannot decode image (malformed)";
    return cv::Mat();
  }
  if (img.empty()) {
    *error = "cannot decode image";
  } else if (img.depth() != CV_8U && img.depth() != CV_16U) {
    *error = "unsupported pixel type (need 8- or 16-bit integer)";
    img.release();
  }
  return img;
}

void WriteImageAtomically(const std::string& path, const cv::Mat& image) {
  std::vector<uchar> bytes;
  const std::string ext = LowerExtension(path);
  bool encoded = false;
  try {
    encoded = cv::imencode(ext.empty() ? ".png" : ext, image, bytes);
  } catch (const cv::Exception&) {
    encoded = false;
  }
  if (!encoded) throw std::invalid_argument(path + ": cannot encode image for this extension");
  WriteFileAtomically(path, std::string(bytes.begin(), bytes.end()));
}

}  // namespace clogscope::vision
