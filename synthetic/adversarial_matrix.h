#pragma once

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "synthetic/adversarial.h"
#include "vision/scene/frame_status.h"
#include "vision/scene/strand_measure.h"

namespace clogscope::synthetic {

// Renders adversarial scenes of every class and measures them with the production measurement
// (vision::MeasureStrand, default options at the scene's scale), judging each frame against the
// render's truth.
struct MatrixOptions {
  int scenes_per_class = 20;
  int frames_per_scene = 4;
  uint64_t first_seed = 1;
  // Every scene's noise times this: below 1, a bias the noise hid (its σ was too large to be
  // valid) shows as a confidently wrong width where the model's doubt does not cover it.
  double noise_scale = 1.0;
  std::string temp_dir;  // for H.264 round trips; empty: the system's temporary directory
};

// A valid width is confidently wrong when it is off by more than max(0.3 px, 0.5 %); its σ is
// honest about it when the error is within 4 σ.
inline constexpr double kWrongPx = 0.3, kWrongFraction = 0.005, kCoveredSigmas = 4.0;
inline double WrongTolerancePx(double truth_px) {
  return std::max(kWrongPx, kWrongFraction * truth_px);
}

struct FrameRecord {
  TroubleClass trouble = TroubleClass::kPlain;
  uint64_t seed = 0;
  int frame = 0;
  vision::FrameStatus status = vision::FrameStatus::kNoStrand;
  std::string detail;
  double truth_px = 0, width_px = 0, sigma_px = 0;
  double model_sigma_px = 0, codec_sigma_px = 0;  // the parts of sigma_px (strand_measure.h)
  vision::WidthDoubt doubt;                       // and model_sigma_px's
  // The Cramér–Rao bound on the width's σ (adversarial_bound.h), and whether it lets a valid width
  // be measured at all (at most the σ a valid width may carry, MaxValidSigmaPx).
  double bound_sigma_px = 0;
  bool bound_allows = false;
  bool strand = false;
  bool wrong = false;  // valid and confidently wrong (or a width where there is no strand)
  bool wrong_beyond_sigma = false;  // and off by more than 4 of its own σ too
  std::string scene;                // Describe() of the scene
};

struct ClassSummary {
  int frames = 0, valid = 0, wrong = 0;
  int allowed = 0, allowed_valid = 0;  // frames the bound allows, and of them the valid ones
  int wrong_beyond_sigma = 0;  // of the wrong ones, those whose σ does not cover the error either
  double bias_px = 0, sd_px = 0;  // of the valid frames that are not wrong
  // Whether the σ covers the error: the RMS of (width − truth)/σ over every strand frame that gave
  // a width (valid or imprecise); 1 for an honest σ of Gaussian errors, below for one too cautious.
  double error_sigmas_rms = 0;
  std::vector<int> refusals;  // count per FrameStatus
};

struct MatrixResult {
  std::vector<FrameRecord> frames;
  ClassSummary classes[kTroubleClassCount];
  ClassSummary all;
  ClassSummary strands;  // the frames with a strand: those where a width is wanted
};

MatrixResult RunAdversarialMatrix(const MatrixOptions& options);

// The options the matrix measures a scene's frames with: the defaults with the reference band
// (50 µm below the tip, 150 µm long) at the scene's scale, in the clip's luma range.
vision::StrandMeasureOptions AdversarialMeasureOptions(const AdversarialScene& scene,
                                                       const ClipFacts& clip);

// How the matrix measures a frame of a scene: with AdversarialMeasureOptions; a width from an
// x264 clip (`encoder` found) with the codec's doubt, as `measure` gives it (codec_doubt.h).
vision::StrandMeasurement MeasureAdversarialFrame(const cv::Mat& frame,
                                                  const AdversarialScene& scene,
                                                  const ClipFacts& clip = {});

// A Markdown table of the result, one row per class and one for all.
std::string MatrixTable(const MatrixResult& result);

}  // namespace clogscope::synthetic
