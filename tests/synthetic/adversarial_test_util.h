// Helpers shared by the adversarial renderer's scene tests (adversarial_test.cc,
// adversarial_choice_test.cc): render as the matrix does, measure, judge against the truth.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <vector>

#include "synthetic/adversarial.h"
#include "synthetic/adversarial_matrix.h"
#include "tests/scratch_dir.h"
#include "vision/scene/strand_measure.h"

namespace clogscope::synthetic {

// Where H.264 round trips go: a folder of this run's own (the renderer names its files after the
// scene, and another run may render the same scene at the same time).
inline const std::filesystem::path& Scratch() {
  static const testutil::ScratchDir dir("clogscope_adversarial_test");
  return dir.path();
}

// Renders the scene's first frame and measures it as the matrix does.
inline vision::StrandMeasurement RenderAndMeasure(const AdversarialScene& p, AdversarialTruth* t) {
  ClipFacts clip;
  const cv::Mat f = RenderAdversarial(p, 1, Scratch().string(), t, &clip)[0];
  return MeasureAdversarialFrame(f, p, clip);
}

// The matrix's four frames of a scene (an H.264 clip encodes its frames together), each measured
// as the matrix measures it; what the render's encoding did in `clip_out`, if given.
inline std::vector<vision::StrandMeasurement> MeasuredMatrixFrames(const AdversarialScene& p,
                                                                   AdversarialTruth* t,
                                                                   ClipFacts* clip_out = nullptr) {
  ClipFacts clip;
  std::vector<vision::StrandMeasurement> measured;
  for (const cv::Mat& frame : RenderAdversarial(p, 4, Scratch().string(), t, &clip))
    measured.push_back(MeasureAdversarialFrame(frame, p, clip));
  if (clip_out) *clip_out = clip;
  return measured;
}

// The scene's four matrix frames, each valid and within the matrix's tolerance of the truth.
inline void ExpectMatrixFramesValidAndRight(const AdversarialScene& p) {
  AdversarialTruth t;
  for (const vision::StrandMeasurement& m : MeasuredMatrixFrames(p, &t)) {
    ASSERT_TRUE(m.valid()) << m.detail << ": " << Describe(p);
    EXPECT_LE(std::abs(m.width_px - t.width_px), WrongTolerancePx(t.width_px)) << Describe(p);
  }
}

// A width within the matrix's tolerance or 3σ of the truth (never another object's).
inline void ExpectWidthRight(const vision::StrandMeasurement& m, const AdversarialTruth& t,
                             size_t frame, const AdversarialScene& p) {
  EXPECT_LE(std::abs(m.width_px - t.width_px),
            std::max(WrongTolerancePx(t.width_px), 3 * m.width_sigma_px))
      << "frame " << frame << ": " << m.width_px << " ± " << m.width_sigma_px << " px, truth "
      << t.width_px << " " << m.detail << " " << Describe(p);
}

// The scene's four matrix frames: each refused, or a width within the matrix's tolerance or 3σ
// of the truth (never another object's).
inline void ExpectMatrixFramesRefusedOrRight(const AdversarialScene& p) {
  AdversarialTruth t;
  const std::vector<vision::StrandMeasurement> measured = MeasuredMatrixFrames(p, &t);
  for (size_t i = 0; i < measured.size(); ++i)
    if (measured[i].gave_width()) ExpectWidthRight(measured[i], t, i, p);
}

// The scene's four matrix frames, each `ambiguous`.
inline void ExpectMatrixFramesAmbiguous(const AdversarialScene& p) {
  AdversarialTruth t;
  const std::vector<vision::StrandMeasurement> measured = MeasuredMatrixFrames(p, &t);
  for (size_t i = 0; i < measured.size(); ++i) {
    EXPECT_EQ(measured[i].status, vision::FrameStatus::kAmbiguous)
        << "frame " << i << ": " << measured[i].width_px << " px, truth " << t.width_px << " "
        << measured[i].detail << " " << Describe(p);
  }
}

}  // namespace clogscope::synthetic
