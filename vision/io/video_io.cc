#include "vision/io/video_io.h"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <vector>

#include "common/atomic_file.h"
#include "common/library_text.h"
#include "vision/io/image_header.h"

namespace clogscope::vision {

std::string LowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext;
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

namespace {

// The decoder's complaint in a few words: "libpng: IDAT: CRC error", "OpenCV TIFF: failed".
std::string DecoderReason(const std::string& library_text) {
  std::string line = FirstLine(library_text);
  if (line.rfind("libpng error: ", 0) == 0) line = "libpng: " + line.substr(14);
  const size_t opencv = line.find("error: (");
  if (opencv != std::string::npos) {  // "imread_('…'): can't read data: OpenCV(4.6.0) …"
    const size_t close = line.find(") ", opencv);
    line = close == std::string::npos ? "decoder error" : line.substr(close + 2);
    const size_t failed = line.find("failed ");  // "OpenCV TIFF: failed (int)TIFFRead…(…)"
    if (failed != std::string::npos) line.resize(failed + 6);
  }
  return line.size() > 120 ? line.substr(0, 117) + "..." : line;
}

// Text a decoder prints for an image it decoded whole: warnings, not damage.
bool HarmlessDecoderText(const std::string& text) {
  size_t pos = 0;
  while (pos < text.size()) {
    const size_t end = std::min(text.find('\n', pos), text.size());
    const std::string line = text.substr(pos, end - pos);
    const bool harmless = line.find_first_not_of(" \t\r") == std::string::npos ||
                          line.rfind("libpng warning: ", 0) == 0 ||
                          line.find("extraneous bytes before marker") != std::string::npos;
    if (!harmless) return false;
    pos = end + 1;
  }
  return true;
}

}  // namespace

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
  // file), and a small file may claim a huge image: refuse it from its header before decoding.
  const ImageHeader header = ParseImageHeader(bytes);
  if (header.format.empty()) {
    *error = "not an image format the tool reads (PNG, JPEG, TIFF, BMP, PGM/PPM)";
    return cv::Mat();
  }
  if (header.width_px <= 0 || header.height_px <= 0) {
    *error = "cannot decode image (its " + header.format + " header gives no size)";
    return cv::Mat();
  }
  if (!(*error = FrameSizeProblem(header.width_px, header.height_px)).empty()) return cv::Mat();
  cv::Mat img;
  std::string library_text;
  {
    // libpng and libjpeg print their errors, and imread prints the exceptions it catches: keep
    // that text off the terminal and make it this frame's reason. Decoded from the file, not from
    // `bytes`: imdecode's JPEG source returns a cut-off file without a word, the file source says
    // "Premature end of JPEG file".
    LibraryTextCapture capture;
    try {
      img = cv::imread(path, cv::IMREAD_UNCHANGED);
    } catch (const cv::Exception&) {
      *error = "cannot decode image (malformed)";
      return cv::Mat();
    }
    library_text = capture.Text();
  }
  if (img.empty()) {
    const std::string reason = DecoderReason(library_text);
    *error = reason.empty() ? "cannot decode image" : "cannot decode image (" + reason + ")";
  } else if (!HarmlessDecoderText(library_text)) {
    // A decoder that complained but returned pixels filled in what it could not read (libjpeg
    // paints missing blocks grey): such a frame would be measured wrong.
    *error = "damaged image (" + DecoderReason(library_text) + ")";
    img.release();
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
