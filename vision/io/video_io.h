#pragma once

#include <opencv2/core.hpp>
#include <string>

namespace clogscope::vision {

enum class VideoKind { kNone, kMjpegAvi, kH264Mp4 };

// kMjpegAvi for ".avi", kH264Mp4 for ".mp4"/".m4v"/".mov"/".mkv", otherwise kNone
// (case-insensitive).
VideoKind VideoKindForPath(const std::string& path);

// The largest frame the tool measures (4096×4096): memory stays bounded by this, not by what a
// file's header claims (measuring a 4096×4096 H.264 video peaks near 330 MB).
inline constexpr long long kMaxFramePixels = 4096LL * 4096;
// Empty when w×h is measurable, else why not: "frames are 8192×8192 (67.1 Mpx), over …".
std::string FrameSizeProblem(long long width_px, long long height_px);

// The file name's extension in lower case with its dot (".png"), or empty.
std::string LowerExtension(const std::string& path);

// True for the file extensions `measure` reads as images.
bool IsImagePath(const std::string& path);
// Reads an image file as stored (8- or 16-bit, grey or colour). An empty image and the reason in
// `error` when it cannot be decoded, is too large, or holds another pixel type; OpenCV's own
// errors never escape.
cv::Mat ReadImage(const std::string& path, std::string* error);

// True for the file extensions `measure` reads as video.
bool IsVideoPath(const std::string& path);

// Encodes by extension (PNG, TIFF, …) and writes under a temporary name, then renames.
void WriteImageAtomically(const std::string& path, const cv::Mat& image);

}  // namespace clogscope::vision
