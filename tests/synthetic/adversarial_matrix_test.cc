// The adversarial matrix (issue 22) as a statistical test: 25 scenes of every trouble class × 4
// frames (1200 frames), measured and judged against the renders' truth. Labelled slow. The bounds
// hold what the measurement reached when they were written, so that a change that makes it worse
// fails; the goal (confident-wrong ≤ 0.1 %, valid ≥ 90 %) is issue 22's, and
// `clogscope_bench adversarial 25 --list` prints the figures and every wrong frame.
#include "synthetic/adversarial_matrix.h"

#include <gtest/gtest.h>

namespace clogscope::synthetic {
namespace {

TEST(AdversarialMatrixTest, FewConfidentlyWrongWidthsAndNoneWithoutAStrand) {
  MatrixOptions o;
  o.scenes_per_class = 25;
  const MatrixResult r = RunAdversarialMatrix(o);
  ASSERT_GE(r.all.frames, 1000);
  std::string wrong;
  for (const auto& f : r.frames)
    if (f.wrong)
      wrong += "\n  " + f.scene + ": " + std::to_string(f.width_px) + " px, truth " +
               std::to_string(f.truth_px);
  SCOPED_TRACE(MatrixTable(r) + "confidently wrong:" + wrong);
  // No width where there is no strand, ever.
  EXPECT_EQ(r.classes[static_cast<int>(TroubleClass::kNoStrand)].valid, 0);
  // Confidently wrong: 0 of 1200 frames when this was written (1 allowed). 4 before the lit
  // cylinder took each side's background as its own line and carried the residual structure its
  // calipers share near the silhouettes as doubt: the four frames of one lit strand in a Bayer
  // frame through H.264 (seed 1), whose luma comes out 0.37-0.42 px narrow, are now imprecise.
  // (Over the four matrices, seeds 1 and 101 with the noise × 1 and × 0.3, that change with the
  // two below took the wrong frames from 20 to 10, 9 of them lit strands through H.264 whose
  // edges sit at one phase of the codec's block grid in every row and frame.) 3 before the tip
  // was read on the object's own end (a swell whose tip the nozzle's face put 2 px low); 7 before
  // lit cylinders that disagree with the per-edge fits carried that as doubt, 32 before the σ
  // carried the edge model's doubt and imprecise widths were refused, 120 before the object
  // model's first round. The renders are the same from run to run (H.264 on one thread).
  EXPECT_LE(r.all.wrong, 1);
  EXPECT_LE(r.all.wrong_beyond_sigma, 1);
  // What that costs: valid widths on 619 of the 1000 measurable strand frames (2026-12-03: 620
  // before a side too noisy to call shaded took its lit cylinders' outward shift as doubt too;
  // 632 on 2026-12-01; 631 before a swell's edges were followed from where they lie; 2026-11-30:
  // 661 before the slopes read along the band past each edge's window were doubted, and luma's
  // doubt about the scene was carried by a blurrier colour channel; over seeds 1, 101 and twelve
  // unseen sets the widths whose doubt that changed had 3.3 % of their errors beyond 3σ before
  // and 1.5 % after. 664 when this floor was written, 672 before a face read beside one object on
  // one side only stopped deciding between it and a rival: two scenes of a hair from the face's
  // corner are ambiguous; 660 before an edge whose background slopes toward a flat object was put
  // where the band's two-slope step says; 674 before a width from x264 carried the codec's doubt,
  // 654 while its second pass coded a lone key frame, 677 before the change above; the saturated
  // and nozzle-alone classes are refused by design).
  const int measurable = r.all.frames -
                         r.classes[static_cast<int>(TroubleClass::kSaturated)].frames -
                         r.classes[static_cast<int>(TroubleClass::kNoStrand)].frames;
  EXPECT_GE(r.all.valid, 0.61 * measurable);
  // The classes the first round fixed stay fixed: the lens at its silhouette, clipping refused,
  // the tip of a swelling strand at the nozzle (1 % wrong measured; 10 % in the first round, 57 %
  // before).
  for (TroubleClass c : {TroubleClass::kSaturated, TroubleClass::kBacklitLens}) {
    const ClassSummary& s = r.classes[static_cast<int>(c)];
    EXPECT_LE(s.wrong, 0.02 * s.frames) << TroubleClassName(c);
  }
  const ClassSummary& swell = r.classes[static_cast<int>(TroubleClass::kDieSwell)];
  EXPECT_LE(swell.wrong, 0.02 * swell.frames);
  // A swell relaxing through the band whose tip neither the nozzle's face nor the object's own end
  // fixes, or whose top caliper found no edge, is imprecise, or no_tip where that tip's doubt
  // alone is above 1 % of the width (48 % valid measured since a swell's edges are followed from
  // where they lie, 2026-12-01; 49 % since the slopes read past each edge's window are doubted,
  // 2026-11-30: seed 7's four frames, 0.34–0.39 of the tolerance wide at σ 0.04–0.05, are
  // imprecise at σ 0.17–0.23; 53 % before: the four frames of seed 12, a 31 px strand through
  // H.264 within 0.01 px, carry a codec σ of 0.08 px since the second pass codes a steady run, and
  // are imprecise at σ 0.10-0.11; 57 % before, while a lone key frame's second pass refused 59 of
  // 60 frames of the default strand through x264's defaults; 44 % before the object's end was
  // read, 95 % before the tip's doubt counted, 10 % of them wrong).
  EXPECT_GE(swell.valid, 0.45 * swell.frames);
  const ClassSummary& lens = r.classes[static_cast<int>(TroubleClass::kBacklitLens)];
  EXPECT_GE(lens.valid, 0.8 * lens.frames);
  // The σ covers the error, and no more: (width − truth)/σ over every width given (valid or
  // imprecise) has an RMS of 1.23 (a σ twice too cautious would give ~0.6; one that left the
  // model's residual structure out, ~3 where that doubt leads).
  EXPECT_GT(r.all.error_sigmas_rms, 0.8);
  EXPECT_LT(r.all.error_sigmas_rms, 1.6);
  // Bias and spread of the valid widths that are not wrong.
  EXPECT_LT(std::abs(r.all.bias_px), 0.05);
  EXPECT_LT(r.all.sd_px, 0.11);  // 0.072 measured (0.081 before)
}

}  // namespace
}  // namespace clogscope::synthetic
