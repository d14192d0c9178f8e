#pragma once

#include <opencv2/core.hpp>
#include <vector>

#include "vision/scene/scene.h"

// Straight pieces of intensity edges in one channel, for scene finding (scene.cc): gradient edge
// points on sampled rows, linked into chains, cut into straight pieces, joined along common lines.
// Internal to the vision module.
namespace clogscope::vision {

constexpr int kMinPiecePoints = 4;  // edge points (sampled rows) in a straight piece

struct EdgePoint {
  float x, y;  // detection-scale px
  float g;     // |gradient|, grey per detection-scale px
  int sign;    // +1: brighter to +x
};

// A straight run of edge points: x = a + b·y in detection-scale px.
struct Piece {
  std::vector<EdgePoint> pts;
  int sign = 0;
  double a = 0, b = 0;
  double max_residual = 0;
  double y0() const { return pts.front().y; }
  double y1() const { return pts.back().y; }
  double X(double y) const { return a + b * y; }
  void Fit();  // a, b and max_residual from pts
};

// One channel at the detection scale (half resolution for frames of usual size): its gradient's
// edge points on sampled rows.
struct Detection {
  int factor = 1;    // full px per detection-scale px
  int row_step = 2;  // detection-scale px between sampled rows
  double noise = 0;  // σ of the horizontal gradient from noise, grey per detection-scale px
  std::vector<std::vector<EdgePoint>> rows;  // sorted by x
  std::vector<float> row_y;
  cv::Mat image;  // the channel at the detection scale: CV_8U for 8-bit data, else CV_32F
};

// Edge points: local maxima of |∂/∂x| above 5σ of the pixel noise (Immerkær's estimate) and the
// weakest accepted step, oriented within max_tilt_deg + 10° of upright, with sub-pixel positions.
Detection DetectEdgePoints(const cv::Mat& channel, const SceneOptions& options);

// The straight pieces of the detection's edges (at least kMinPiecePoints points each).
std::vector<Piece> StraightPieces(const Detection& d, double max_tilt_deg);

// A piece as a segment in full-resolution ROI coordinates.
EdgeSegment ToSegment(const Piece& p, const Detection& d);

}  // namespace clogscope::vision
