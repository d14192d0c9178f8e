#include "vision/io/video_io.h"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <vector>

#include "common/ascii.h"
#include "common/atomic_file.h"
#include "vision/io/image_codec.h"

namespace clogscope::vision {

std::string LowerExtension(const std::string& path) {
  return LowerAscii(std::filesystem::path(path).extension().string());
}

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

std::string FrameSizeProblem(long long width_px, long long height_px) {
  if (width_px * height_px <= kMaxFramePixels) return std::string();
  return fmt::format(
      "frames are {}x{} ({:.1f} Mpx), over the {:.1f} Mpx (4096x4096) measured: "
      "crop or scale it first",
      width_px, height_px, width_px * height_px / 1e6, kMaxFramePixels / 1e6);
}

cv::Mat ReadImage(const std::string& path, std::string* error) {
  // A FIFO or device would block or never end; a directory is not an image. The whole file is
  // read for its header: a TIFF's first directory may follow the pixels.
  std::string bytes;
  if (!TryReadFile(path, &bytes, error)) return cv::Mat();
  // Only the formats cameras write are decoded (each other decoder is more surface for a bad
  // file), and a huge image is refused from its header: DecodeImage says so.
  return DecodeImage(bytes, error);
}

void WriteImageAtomically(const std::string& path, const cv::Mat& image) {
  const std::string ext = LowerExtension(path);
  std::string bytes;
  try {
    bytes = EncodeImage(ext.empty() ? ".png" : ext, image);
  } catch (const std::exception& e) {
    throw std::invalid_argument(path + ": cannot encode image for this extension (" +
                                std::string(e.what()) + ")");
  }
  WriteFileAtomically(path, bytes);
}

}  // namespace clogscope::vision
