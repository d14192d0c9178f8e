#pragma once

#include <opencv2/core.hpp>
#include <string>

#include "vision/scene/scene.h"
#include "vision/scene/strand_measure.h"

namespace clogscope::vision {

// An 8-bit BGR picture of the frame with the measurement drawn on it, for a person to check at a
// glance: the band (yellow), the fitted edges (green), each caliper's edge points (green used, red
// rejected), the tip (cyan), the width and status as text, and a magnified inset of the band.
// The width in µm is (width_px − edge_bias_px)·scale_um_per_px, as in the tables; scale_um_per_px
// <= 0 leaves it out.
cv::Mat DrawOverlay(const cv::Mat& frame, const StrandMeasurement& m, double scale_um_per_px,
                    double edge_bias_px = 0.0);

// Draws a scene's candidate edge pairs onto an overlay (BGR, full-frame coordinates; the scene's
// are the ROI's, shifted by roi_offset): each pair's two edge lines over its stretch with its
// number at the top (#1 is the best score), the chosen pair in green, the others in orange, those
// that lost by rule (nested, spanning objects, no tip) in grey.
void DrawCandidates(cv::Mat& overlay, const SceneResult& scene, cv::Point roi_offset,
                    int max_candidates = 8);

// A UTF-8 line as the overlay's (Hershey) font can draw it: ASCII only, the signs the tool's
// messages use spelled out ("±" → "+/-", "σ" → "sigma", "°" → " deg", "µ" → "u", "−" → "-"), any
// other non-ASCII character as "?".
std::string OverlayText(const std::string& utf8);

}  // namespace clogscope::vision
