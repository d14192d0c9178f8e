#pragma once

#include <cassert>
#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>

namespace clogscope::vision {

// Read access to one 8- or 16-bit channel, with bilinear sampling. Internal to the vision module.
struct GreyImage {
  const cv::Mat& m;
  bool is16;
  float At(int x, int y) const {
    return is16 ? static_cast<float>(m.ptr<uint16_t>(y)[x])
                : static_cast<float>(m.ptr<uint8_t>(y)[x]);
  }
  // Bilinear, inside the image only (the caller checks with InsideForBilinear). Every edge walk
  // and profile samples through here: x, y >= 0 make truncation the floor, and the two rows are
  // read through one pointer each.
  float Bilinear(double x, double y) const {
    assert(x >= 0 && y >= 0);
    const int x0 = static_cast<int>(x);
    const int y0 = static_cast<int>(y);
    const double fx = x - x0, fy = y - y0;
    double v00, v10, v01, v11;
    if (is16) {
      const uint16_t* r0 = m.ptr<uint16_t>(y0) + x0;
      const uint16_t* r1 = m.ptr<uint16_t>(y0 + 1) + x0;
      v00 = r0[0], v10 = r0[1], v01 = r1[0], v11 = r1[1];
    } else {
      const uint8_t* r0 = m.ptr<uint8_t>(y0) + x0;
      const uint8_t* r1 = m.ptr<uint8_t>(y0 + 1) + x0;
      v00 = r0[0], v10 = r0[1], v01 = r1[0], v11 = r1[1];
    }
    return static_cast<float>((v00 * (1 - fx) + v10 * fx) * (1 - fy) +
                              (v01 * (1 - fx) + v11 * fx) * fy);
  }
  bool InsideForBilinear(double x, double y) const {
    return x >= 0 && y >= 0 && x <= m.cols - 1.001 && y <= m.rows - 1.001;
  }
};

// The data's largest value and where its black and white lie (data_range.h: LumaRange).
struct DataLevels {
  double max = 255, black = 0, white = 255;
};

// The measurement frame of a strand: origin on its axis, unit axis direction pointing down the
// strand. Across-axis coordinate u grows along n = (dy, −dx), to the right of a downward axis.
struct AxisFrame {
  double ox = 0, oy = 0;
  double dx = 0, dy = 1;
  double ImageX(double s, double u) const { return ox + s * dx + u * dy; }
  double ImageY(double s, double u) const { return oy + s * dy - u * dx; }
  double S(double x, double y) const { return (x - ox) * dx + (y - oy) * dy; }
  double U(double x, double y) const { return (x - ox) * dy - (y - oy) * dx; }
};

// N profile rows across a band s0..s1 of an axis frame, evenly spread (row r at
// s0 + (s1 − s0)(r + ½)/N), for profiles that step along u in every row: each row's point at u = 0
// is worked out once, and X and Y add the u term as ImageX and ImageY do (the same doubles).
template <int N>
struct BandRows {
  double s[N], x0[N], y0[N];
  double dx, dy;
  BandRows(const AxisFrame& f, double s0, double s1) : dx(f.dx), dy(f.dy) {
    for (int r = 0; r < N; ++r) {
      s[r] = s0 + (s1 - s0) * (r + 0.5) / N;
      x0[r] = f.ImageX(s[r], 0.0);
      y0[r] = f.ImageY(s[r], 0.0);
    }
  }
  double X(int r, double u) const { return x0[r] + u * dy; }
  double Y(int r, double u) const { return y0[r] - u * dx; }
};

// An edge's contrast across the line u at s: sign·(I(u + offset) − I(u − offset)), positive when
// the edge is there with its sign; false when either point leaves the image.
inline bool ContrastAcross(const GreyImage& img, const AxisFrame& a, double s, double u, int sign,
                           double offset_px, double* contrast) {
  const double xa = a.ImageX(s, u - offset_px), ya = a.ImageY(s, u - offset_px);
  const double xb = a.ImageX(s, u + offset_px), yb = a.ImageY(s, u + offset_px);
  if (!img.InsideForBilinear(xa, ya) || !img.InsideForBilinear(xb, yb)) return false;
  *contrast = sign * (img.Bilinear(xb, yb) - img.Bilinear(xa, ya));
  return true;
}

}  // namespace clogscope::vision
