#include "vision/overlay/overlay.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <string_view>
#include <utility>

#include "vision/io/data_range.h"

namespace clogscope::vision {
namespace {

constexpr int kShift = 4;  // sub-pixel drawing: coordinates in 1/16 px
const cv::Scalar kYellow(0, 220, 255), kGreen(0, 230, 0), kRed(0, 0, 255), kCyan(255, 255, 0),
    kWhite(255, 255, 255), kBlack(0, 0, 0);

cv::Point Fixed(double x, double y, double zoom = 1.0, cv::Point2d offset = {0, 0}) {
  return cv::Point(static_cast<int>(std::lround(((x - offset.x) * zoom) * (1 << kShift))),
                   static_cast<int>(std::lround(((y - offset.y) * zoom) * (1 << kShift))));
}

cv::Mat ToBgr8(const cv::Mat& frame) {
  cv::Mat eight;
  if (frame.depth() == CV_16U) {
    frame.convertTo(eight, CV_8U, 255.0 / DataMax(frame));  // 12-bit data shows as bright as 16
  } else {
    eight = frame;
  }
  cv::Mat bgr;
  if (eight.channels() == 1) {
    cv::cvtColor(eight, bgr, cv::COLOR_GRAY2BGR);
  } else if (eight.channels() == 4) {
    cv::cvtColor(eight, bgr, cv::COLOR_BGRA2BGR);
  } else {
    bgr = eight.clone();
  }
  return bgr;
}

// Draws band, edges and calipers in image coordinates mapped by (p - offset) * zoom.
void DrawGeometry(cv::Mat& img, const StrandMeasurement& m, double zoom, cv::Point2d offset) {
  const double dx = m.axis_dx, dy = m.axis_dy;
  auto at = [&](double s, double u) {
    return Fixed(m.tip_x_px + s * dx + u * dy, m.tip_y_px + s * dy - u * dx, zoom, offset);
  };
  const double s0 = m.band_start_px, s1 = m.band_end_px;
  const double margin = 6;
  const double l0 = m.left_u0_px + m.edge_slope * s0, l1 = m.left_u0_px + m.edge_slope * s1;
  const double r0 = m.right_u0_px + m.edge_slope * s0, r1 = m.right_u0_px + m.edge_slope * s1;
  std::vector<cv::Point> band = {at(s0, l0 - margin), at(s0, r0 + margin), at(s1, r1 + margin),
                                 at(s1, l1 - margin)};
  cv::polylines(img, band, true, kYellow, 1, cv::LINE_AA, kShift);
  cv::line(img, at(s0, l0), at(s1, l1), kGreen, 1, cv::LINE_AA, kShift);
  cv::line(img, at(s0, r0), at(s1, r1), kGreen, 1, cv::LINE_AA, kShift);
  const int r = static_cast<int>(std::max(2.0, 1.5 * zoom)) << kShift;
  for (const auto& c : m.calipers) {
    if (!c.fitted) continue;
    const cv::Scalar col = c.inlier ? kGreen : kRed;
    cv::circle(img, at(c.s_px, c.left_u_px), r, col, 1, cv::LINE_AA, kShift);
    cv::circle(img, at(c.s_px, c.right_u_px), r, col, 1, cv::LINE_AA, kShift);
  }
  // Tip: a short cross on the axis.
  cv::line(img, at(0, -10), at(0, 10), kCyan, 1, cv::LINE_AA, kShift);
  cv::line(img, at(-10, 0), at(10, 0), kCyan, 1, cv::LINE_AA, kShift);
}

void Text(cv::Mat& img, const std::string& s, cv::Point org, double size) {
  // Hershey fonts draw ASCII only: a "±" or "σ" in a status line came out as "??".
  const std::string ascii = OverlayText(s);
  cv::putText(img, ascii, org, cv::FONT_HERSHEY_SIMPLEX, size, kBlack, 4, cv::LINE_AA);
  cv::putText(img, ascii, org, cv::FONT_HERSHEY_SIMPLEX, size, kWhite, 1, cv::LINE_AA);
}

}  // namespace

std::string OverlayText(const std::string& utf8) {
  static const std::pair<const char*, const char*> kSpelled[] = {
      {"\u00b1", "+/-"}, {"\u03c3", "sigma"}, {"\u00b0", " deg"}, {"\u00b5", "u"},
      {"\u03bc", "u"},   {"\u2212", "-"},     {"\u00b7", "*"},    {"\u00d7", "x"},
      {"\u2013", "-"},   {"\u2014", "-"},     {"\u2192", "->"},   {"\u2026", "..."}};
  std::string out;
  out.reserve(utf8.size());
  for (size_t i = 0; i < utf8.size();) {
    const unsigned char c = static_cast<unsigned char>(utf8[i]);
    if (c < 0x80) {
      out += static_cast<char>(c);
      ++i;
      continue;
    }
    // A UTF-8 sequence's length from its lead byte (a stray continuation byte counts alone).
    const size_t n = (c & 0xe0) == 0xc0 ? 2 : (c & 0xf0) == 0xe0 ? 3 : (c & 0xf8) == 0xf0 ? 4 : 1;
    const std::string_view seq(utf8.data() + i, std::min(n, utf8.size() - i));
    const char* spelled = "?";
    for (const auto& [from, to] : kSpelled)
      if (seq == from) spelled = to;
    out += spelled;
    i += n;
  }
  return out;
}

cv::Mat DrawOverlay(const cv::Mat& frame, const StrandMeasurement& m, double scale_um_per_px,
                    double edge_bias_px) {
  cv::Mat out = ToBgr8(frame);
  const double font = std::max(0.4, out.cols / 2400.0);
  const int line_h = static_cast<int>(30 * font / 0.5);
  std::vector<std::string> lines;
  if (m.valid()) {
    std::string w = fmt::format("width {:.3f} +/- {:.3f} px", m.width_px, m.width_sigma_px);
    if (scale_um_per_px > 0) {
      w += fmt::format(" = {:.2f} um", (m.width_px - edge_bias_px) * scale_um_per_px);
    }
    lines.push_back(w);
  } else {
    lines.push_back(fmt::format("INVALID: {} {}", FrameStatusName(m.status), m.detail));
  }
  if (m.has_geometry) {
    lines.push_back(fmt::format("angle {:.2f} deg  blur {:.2f} px  contrast {:.0f}  calipers {}/{}",
                                m.angle_deg, m.blur_px, m.contrast, m.calipers_used,
                                m.calipers_total));
    DrawGeometry(out, m, 1.0, {0, 0});
    // Inset: the band magnified, in the corner away from the strand.
    const double cx = m.tip_x_px + 0.5 * (m.band_start_px + m.band_end_px) * m.axis_dx;
    const double cy = m.tip_y_px + 0.5 * (m.band_start_px + m.band_end_px) * m.axis_dy;
    const double half_w = 0.5 * (m.right_u0_px - m.left_u0_px) + 15;
    const double half_h = 0.5 * (m.band_end_px - m.band_start_px) + 15;
    cv::Rect crop(static_cast<int>(cx - half_w), static_cast<int>(cy - half_h),
                  static_cast<int>(2 * half_w), static_cast<int>(2 * half_h));
    crop &= cv::Rect(0, 0, frame.cols, frame.rows);
    const double zoom = std::min(0.45 * out.cols / std::max(crop.width, 1),
                                 0.6 * out.rows / std::max(crop.height, 1));
    if (crop.area() > 0 && zoom >= 1.5) {
      cv::Mat inset;
      cv::resize(ToBgr8(frame(crop)), inset, cv::Size(), zoom, zoom, cv::INTER_NEAREST);
      DrawGeometry(inset, m, zoom, {crop.x - 0.5 + 0.5 / zoom, crop.y - 0.5 + 0.5 / zoom});
      const int x0 = cx < out.cols / 2 ? out.cols - inset.cols - 8 : 8;
      const int y0 = out.rows - inset.rows - 8;
      if (y0 > 0 && x0 >= 0) {
        inset.copyTo(out(cv::Rect(x0, y0, inset.cols, inset.rows)));
        cv::rectangle(out, cv::Rect(x0, y0, inset.cols, inset.rows), kWhite, 1);
        Text(out, fmt::format("band x{:.1f}", zoom), {x0 + 6, y0 + line_h}, font);
      }
    }
  }
  for (size_t i = 0; i < lines.size(); ++i) {
    Text(out, lines[i], {10, static_cast<int>((i + 1) * line_h)}, font);
  }
  return out;
}

void DrawCandidates(cv::Mat& overlay, const SceneResult& scene, cv::Point roi_offset,
                    int max_candidates) {
  const cv::Scalar kOrange(0, 140, 255), kGrey(150, 150, 150);
  const cv::Point2d off(roi_offset.x, roi_offset.y);
  for (int i = std::min<int>(max_candidates, scene.candidates.size()) - 1; i >= 0; --i) {
    const PairCandidate& c = scene.candidates[i];
    const bool chosen = i == scene.chosen;
    const bool ruled_out = RulesOut(c.verdict);
    const cv::Scalar colour = chosen ? kGreen : ruled_out ? kGrey : kOrange;
    for (double u0 : {c.left_u0, c.right_u0}) {
      const cv::Point2d a(c.axis.ImageX(0, u0), c.axis.ImageY(0, u0));
      const cv::Point2d b(c.axis.ImageX(c.length_px, u0 + c.edge_slope * c.length_px),
                          c.axis.ImageY(c.length_px, u0 + c.edge_slope * c.length_px));
      cv::line(overlay, Fixed(a.x + off.x, a.y + off.y), Fixed(b.x + off.x, b.y + off.y), colour,
               chosen ? 2 : 1, cv::LINE_AA, kShift);
    }
    const cv::Point label(static_cast<int>(c.axis.ox + off.x) - 8,
                          std::max(12, static_cast<int>(c.axis.oy + off.y) - 6));
    cv::putText(overlay, fmt::format("#{}", i + 1), label, cv::FONT_HERSHEY_SIMPLEX, 0.45, kBlack,
                3, cv::LINE_AA);
    cv::putText(overlay, fmt::format("#{}", i + 1), label, cv::FONT_HERSHEY_SIMPLEX, 0.45, colour,
                1, cv::LINE_AA);
  }
}

}  // namespace clogscope::vision
