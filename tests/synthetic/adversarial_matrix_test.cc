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
  // Confidently wrong: at most 4 % of all frames, and at most 2 % whose own σ does not cover the
  // error either (2.7 % and 0.8 % measured when this was written: 32 and 10 of 1200; 10 % before
  // the object model's first round).
  EXPECT_LE(r.all.wrong, 0.04 * r.all.frames);
  EXPECT_LE(r.all.wrong_beyond_sigma, 0.02 * r.all.frames);
  // The classes the first round fixed stay fixed: the lens at its silhouette, clipping refused,
  // the tip of a swelling strand at the nozzle (10 % measured, 57 % before).
  for (TroubleClass c : {TroubleClass::kSaturated, TroubleClass::kBacklitLens}) {
    const ClassSummary& s = r.classes[static_cast<int>(c)];
    EXPECT_LE(s.wrong, 0.02 * s.frames) << TroubleClassName(c);
  }
  const ClassSummary& swell = r.classes[static_cast<int>(TroubleClass::kDieSwell)];
  EXPECT_LE(swell.wrong, 0.15 * swell.frames);
  EXPECT_GE(swell.valid, 0.9 * swell.frames);
  const ClassSummary& lens = r.classes[static_cast<int>(TroubleClass::kBacklitLens)];
  EXPECT_GE(lens.valid, 0.8 * lens.frames);
  // Bias and spread of the valid widths that are not wrong.
  EXPECT_LT(std::abs(r.all.bias_px), 0.05);
  EXPECT_LT(r.all.sd_px, 0.2);
}

}  // namespace
}  // namespace clogscope::synthetic
