// Scenes from the adversarial renderer (synthetic/adversarial.h) with more than one strand-like
// object, or a strand that is more than one: the strand, or a refusal, never another object's
// width.
#include <gtest/gtest.h>

#include "tests/synthetic/adversarial_test_util.h"

namespace clogscope::synthetic {
namespace {

TEST(AdversarialTest, AHairBesideTheStrandIsNeverMeasuredAsIt) {
  // Stringers 10–50 µm beside the strand, hanging from the nozzle or from above (behind the
  // nozzle's flank), the nozzle often barely visible: the strand or a refusal, never the hair.
  int valid = 0;
  for (uint64_t seed = 1; seed <= 12; ++seed) {
    const AdversarialScene p = RandomAdversarialScene(TroubleClass::kStringer, seed);
    AdversarialTruth t;
    const vision::StrandMeasurement m = RenderAndMeasure(p, &t);
    // A width, valid or `imprecise`, is the strand's.
    if (!m.valid() && m.status != vision::FrameStatus::kImprecise) continue;
    ++valid;
    EXPECT_NEAR(m.width_px, t.width_px, std::max(0.45, 0.0075 * t.width_px)) << Describe(p);
  }
  // Seed 4's hair comes from above and ends at the nozzle's flank: the strand hangs from the
  // face. (Ambiguous before the face decided.) Its σ sits at the valid limit (±0.20 px on a
  // 117 px strand): the strand measured, valid or `imprecise`.
  const AdversarialScene p = RandomAdversarialScene(TroubleClass::kStringer, 4);
  AdversarialTruth t;
  const vision::StrandMeasurement m = RenderAndMeasure(p, &t);
  ASSERT_TRUE(m.valid() || m.status == vision::FrameStatus::kImprecise) << m.detail;
  EXPECT_NEAR(m.width_px, t.width_px, WrongTolerancePx(t.width_px));
  EXPECT_GE(valid, 8);
}

TEST(AdversarialTest, TheGapBetweenAHairClosingInAndTheStrandIsNoSwell) {
  // A bright 85 px strand and a 7.7 px hair 288 px to its left, slanting 1.2° toward it: the
  // background between them, a dark 236 px pair, closes by 10 px over its 489 px, half of that
  // in its lower half, as two straight lines do. Taken for a swell's closing (a swell holds a
  // third of it there at most), it outscored the strand, and all four frames were refused
  // (`not_silhouette`). Every frame measures the strand.
  const AdversarialScene p = RandomAdversarialScene(TroubleClass::kStringer, 4136);
  AdversarialTruth t;
  const std::vector<vision::StrandMeasurement> measured = MeasuredMatrixFrames(p, &t);
  for (size_t i = 0; i < measured.size(); ++i) {
    ASSERT_TRUE(measured[i].gave_width()) << "frame " << i << ": " << measured[i].detail;
    ExpectWidthRight(measured[i], t, i, p);
  }
}

TEST(AdversarialTest, AStrandAndAHairUnderANozzleAtTheBackgroundsLevelAreAmbiguous) {
  // An 83 px strand 19° off vertical and a 10 px hair beside it, under a nozzle 2 grey levels
  // above the background: no face shows beside either. What the columns beside them read are
  // steps onto other levels (the tilted strand's own outline) or that do not step the same way on
  // both sides, which once counted as faces: the strand "hung from the face" in two frames by
  // luck, and with fewer such readings the hair did in one. Which of the two hangs from the
  // nozzle the frames cannot say.
  ExpectMatrixFramesAmbiguous(RandomAdversarialScene(TroubleClass::kStringer, 24));
}

TEST(AdversarialTest, AFaceReadFaintlyBesideAHairDoesNotChooseIt) {
  // A 137 px strand and a 12 px hair both hanging from a nozzle 8 grey levels below the
  // background (JPEG q42, noise 4). The columns beside the hair read a face at 16-21 grey levels
  // (the least the search takes is 15.3: the background's slope taken as part of a step), on
  // both sides in one frame of four, and none beside the strand: the hair was measured in that
  // frame, 11.76 ± 0.05 px. Which of the two hangs from the nozzle the frames cannot say.
  ExpectMatrixFramesAmbiguous(RandomAdversarialScene(TroubleClass::kStringer, 5307));
}

TEST(AdversarialTest, AFaceReadOnOneSideDoesNotChooseBetweenAStrandAndAHair) {
  // A 91 px strand under a dim nozzle (33 grey levels above the background) and an 8 px hair
  // from the face's corner: in one frame of four the face showed beside the strand on one side
  // only and beside the hair on both, and the hair was measured, 7.97 ± 0.14 px.
  ExpectMatrixFramesRefusedOrRight(RandomAdversarialScene(TroubleClass::kStringer, 322));
}

TEST(AdversarialTest, AStrandWhoseFaintEdgeLostItsTipStillDoubtsAHairFromTheCorner) {
  // A 111 px strand lit from one side (its shadowed edge 6 grey levels above the background, at
  // noise 11) and a 14 px hair from the nozzle's corner, the face read beside the hair on one
  // side only. In three frames of four the strand's faint edge faded before the nozzle (its pair
  // had no tip, or scored 18-34 % of the hair's), and the hair was measured alone, valid at
  // sigma 0.04-0.08.
  ExpectMatrixFramesRefusedOrRight(RandomAdversarialScene(TroubleClass::kStringer, 709));
}

TEST(AdversarialTest, AStrandWhoseShadedEdgeSankBelowTheBackgroundStillDoubtsTheHair) {
  // The same scene with the strand dimmer (level 40 or 60, not 84): its shaded rim falls to the
  // background's level. Its pair was then mixed, scored below the minimum or shared too short a
  // stretch, and the hair was measured alone, 14.4 px at sigma 0.04-0.08, in all four frames
  // (level 40) or three (60). At 40 every frame is ambiguous; at 60 one is refused otherwise.
  // (Lit from the camera's side, as it was drawn when this was found: the lamp the matrix now
  // puts 33° off leaves the strand's far rim below the background too, and its pair was not
  // found at all in one frame of four at 40 and two at 60: the hair alone, 14.4 px at sigma
  // 0.05-0.08. docs/accuracy.md, left alone.)
  AdversarialScene p = RandomAdversarialScene(TroubleClass::kStringer, 709);
  p.light_deg = 0;
  p.strand_level = 40;
  ExpectMatrixFramesAmbiguous(p);
  p.strand_level = 60;
  ExpectMatrixFramesRefusedOrRight(p);
}

TEST(AdversarialTest, AHairBesideALitStrandIsNotMeasuredWithItAsOneObject) {
  // A 10 px hair from above the view, 30 px beside a lit 112 px strand: in one frame of four the
  // pair of the strand's left edge and the hair's right edge held up as one 152 px object at
  // sigma 0.12, the background between them 19.7 % of its inside (two objects from 20 %).
  ExpectMatrixFramesRefusedOrRight(RandomAdversarialScene(TroubleClass::kStringer, 1118));
}

TEST(AdversarialTest, AHairBesideADarkStrandIsNotMeasuredWithItAsOneObject) {
  // A 10 px hair hanging from the nozzle's face 36 px beside a dark 137 px strand on a textured
  // background: the pair of the strand's left edge and the hair's right edge held up as one
  // 184 px object in every frame (valid at sigma 0.05-0.11), the background between them 16-17
  // of its 86 samples across. Both hang from the face, so the tip cannot choose between them.
  ExpectMatrixFramesAmbiguous(RandomAdversarialScene(TroubleClass::kStringer, 1517));
}

TEST(AdversarialTest, AHairCloseBesideADarkStrandIsNotMeasuredWithItAsOneObject) {
  // A 4.6 px hair from the nozzle's face, 7 px beside a dark 33 px strand (JPEG q84, noise 10, the
  // background textured 9 grey levels deep and sloping 16 levels across the two): the pair of the
  // strand's left edge and the hair's right edge held up as one 45.1 px object, valid at sigma
  // 0.06-0.07 in three frames of four. The search's coarse scale sees the gap as under 4 samples,
  // and the hair too thin to read its level inside the edge; read across the band px by px, the
  // gap is 7 px at the background's level.
  ExpectMatrixFramesRefusedOrRight(RandomAdversarialScene(TroubleClass::kStringer, 6801));
}

TEST(AdversarialTest, AStrandBendingAboveItsStraightEdgesHasNoTipInLine) {
  // A 44 px strand bending 57 px below the nozzle: the only straight pair is its lower part, 43°
  // off vertical, whose outline curves on up to the nozzle. The tip was put where the following
  // stopped, and the band across the bend measured 31.6 ± 0.45 px.
  ExpectMatrixFramesRefusedOrRight(RandomAdversarialScene(TroubleClass::kBend, 223));
}

TEST(AdversarialTest, AStrandSplitByAStripeWhoseNarrowSideIsNoPairIsAmbiguous) {
  // A dark 65 px strand whose 15 px stripe comes out at the background's level 7 px from its
  // right edge: the outline is ruled out for the background showing inside it, the 7 px side is
  // no pair of its own, and the 43 px side stood alone, valid at sigma 0.02-0.06.
  ExpectMatrixFramesRefusedOrRight(RandomAdversarialScene(TroubleClass::kSpecularStripe, 624));
}

TEST(AdversarialTest, AStripeWithTheStrandsOutlineJustOutsideItIsNotTheStrand) {
  // A dark 66 px strand whose stripe, 14 px wide and near the background's level, lies 5 px from
  // its right edge: the stripe was measured as a bright object, 14.1 px at sigma 0.16-1.3, the
  // strand's thin dark rim and outline 5.5-6 px beyond its right edge.
  ExpectMatrixFramesRefusedOrRight(RandomAdversarialScene(TroubleClass::kSpecularStripe, 523));
}

TEST(AdversarialTest, AStripeOnALitStrandWhosePairFailedIsNotTheObject) {
  // A lit 86 px strand, the lamp 33° off: its lit side 75 grey levels on a background of 20, its
  // shaded side falling to 45, and a 9.5 px stripe 140 levels above it. The strand's own pair
  // faded along its shaded edge (too weak, or no tip in line), and the stripe stood alone: 9.3 px,
  // valid at sigma 0.09-0.10 in two frames of four (`imprecise` in the others). Read outward from
  // the stripe, both sides step on to the background's level: it lies on a wider object.
  AdversarialTruth t;
  for (const vision::StrandMeasurement& m :
       MeasuredMatrixFrames(RandomAdversarialScene(TroubleClass::kSpecularStripe, 7710), &t))
    EXPECT_EQ(m.status, vision::FrameStatus::kNotSilhouette) << m.width_px << " px " << m.detail;
}

TEST(AdversarialTest, AStripeAtADarkStrandsRimIsNotTheObject) {
  // A dark 46 px strand (50 grey levels on a background of 112) whose bright stripe, 9 px wide
  // and 45 above the background, lies at its left rim: the stripe was measured as a bright
  // object, 8.3 px at sigma 0.11-0.26 (`imprecise`), the background outside it on one side and
  // the strand, 59 levels darker, on the other. Too thin for the self-check's read of its level
  // 3 blurs inside its edges, it had not been checked at all.
  ExpectMatrixFramesRefusedOrRight(RandomAdversarialScene(TroubleClass::kSpecularStripe, 3623));
}

TEST(AdversarialTest, AStripeByADarkStrandsRimIsNotTheObjectWhereTheRimHidesInBlur) {
  // A dark 108.5 px strand (64 grey levels on a background of 107, blur 2.6 px) whose bright
  // 18 px stripe lies 3 px inside its left rim: the rim hides in the blur, and the stripe was
  // measured alone, 17.6 px at sigma 0.14-0.57 (`imprecise`) in all four frames. Outside its left
  // edge lies the background; outside its right edge the strand's body steps on to the
  // background's level 87 px out.
  AdversarialTruth t;
  for (const vision::StrandMeasurement& m :
       MeasuredMatrixFrames(RandomAdversarialScene(TroubleClass::kSpecularStripe, 8208), &t))
    EXPECT_EQ(m.status, vision::FrameStatus::kNotSilhouette) << m.width_px << " px " << m.detail;
}

TEST(AdversarialTest, AHairFromTheFaceBesideAStrandWhoseShadedEdgeFadedIsNotMeasured) {
  // A lit 153 px strand, the lamp 35° off, its shaded side near the background's level on a
  // textured ground (11 grey levels), and a 49 µm hair hanging from the nozzle 179 px beside it.
  // In one frame of four the strand's shaded edge read too weak along its pair (contrast 7
  // against 65 on its lit side) and the hair, hanging from the face, was measured alone: 18.2 px
  // at sigma 0.10.
  ExpectMatrixFramesRefusedOrRight(RandomAdversarialScene(TroubleClass::kStringer, 8104));
}

TEST(AdversarialTest, AStrandAndAHairFarBesideItPairedAcrossBothAreNotOneObject) {
  // A lit 153 px strand and a 30 µm hair 300 px from its axis, the nozzle at the background's
  // level, on a background sloping by 0.23 grey levels a px: in one frame the pair of the
  // strand's far edge and the hair's held up as one object, 381.9 px at sigma 2.2 (`imprecise`),
  // 218 px of background between them.
  ExpectMatrixFramesRefusedOrRight(RandomAdversarialScene(TroubleClass::kStringer, 3725));
}

TEST(AdversarialTest, AStrandAndAHairThinnerThanTheInsetPairedAcrossBothAreNotOneObject) {
  // A faint 178.5 px strand (185 on 227, the background sloping and textured) and a 20 µm hair
  // 230 px from its axis: the pair of the hair's outer edge and the strand's far edge held up as
  // one object in all four frames, 322.8 px at sigma 0.14-0.25. The hair lies within the read's
  // inset from the edge, so the background between them starts the read.
  ExpectMatrixFramesRefusedOrRight(RandomAdversarialScene(TroubleClass::kStringer, 3690));
}

TEST(AdversarialTest, ALensWhoseCoreCoversHalfItsWidthIsOneObject) {
  // A 113 px backlit lens (n 1.40, acceptance 0.35 rad) whose core, at the backlight's level,
  // covers 51 % of its width: its rims alike (28 px each), it is not two objects with the
  // background between them. Valid and right in all four frames.
  ExpectMatrixFramesValidAndRight(RandomAdversarialScene(TroubleClass::kBacklitLens, 9114));
}

TEST(AdversarialTest, APairInsideAStrandWhoseFaintEdgeLostItsTipIsNotTheStrand) {
  // A 162 px strand lit 37 degrees off (ambient 0.48) on a dark ground: its shaded edge is faint,
  // and a bright stripe lies inside it. In one frame of four the faint edge faded 23 px before
  // the nozzle (no tip in line), and the pair of the stripe's edge and the strand's far edge,
  // once lifted from inside it, hung from the face: 83.4 px at sigma 0.04.
  ExpectMatrixFramesRefusedOrRight(RandomAdversarialScene(TroubleClass::kSpecularStripe, 5717));
}

TEST(AdversarialTest, AStripeInsideAStrandWhoseFarEdgeShowsLowDownIsNotTheStrand) {
  // A dark 180 px strand with a bright 14 px stripe near one rim, hanging from a nozzle brighter
  // than the background: the strand's far edge, faint on texture, was detected along the lower
  // half of the view only, too short to rule the stripe out. In one frame of four the stripe was
  // measured, 14.03 px at σ 0.19; the strand's pair then held up to the same tip, and is now
  // the object or, where a pair made with the stripe held up first, the frame is ambiguous.
  ExpectMatrixFramesRefusedOrRight(RandomAdversarialScene(TroubleClass::kSpecularStripe, 4823));
}

TEST(AdversarialTest, AStripeInsideALitStrandOfItsOwnKindIsNotTheStrand) {
  // A bright 143 px strand lit from near the camera's side (ambient 0.48), its shaded rims faint
  // on a textured ground, with a bright 11.5 px stripe along its middle: in one frame of four the
  // strand's pair scored 13 % of the stripe's, too little to rule it out, and the stripe was
  // measured, 11.54 px at σ 0.18. The strand's pair held up and hangs clearly from the face.
  ExpectMatrixFramesRefusedOrRight(RandomAdversarialScene(TroubleClass::kSpecularStripe, 5802));
}

TEST(AdversarialTest, AStripeInsideAFaintStrandIsNotMeasuredForItsFace) {
  // A dark 45 px strand under noise of 10 grey levels and texture of 13, its bright stripe 13 px
  // wide: the stripe's edges stand out, the strand's hardly. Beside the stripe the nozzle's face
  // steps onto the strand's level, read as the face on both sides, and in all four frames the
  // stripe was measured, 12.3-13.6 px at σ 0.3-0.8. The strand's dark pair, no tip in line or too
  // weak to rule the stripe out, now leaves three frames ambiguous; in the fourth it was not
  // among the pairs followed (only a mixed pair around the stripe was), and the stripe is still
  // measured there, imprecise.
  const AdversarialScene p = RandomAdversarialScene(TroubleClass::kSpecularStripe, 4024);
  AdversarialTruth t;
  int ambiguous = 0, stripe = 0;
  for (const vision::StrandMeasurement& m : MeasuredMatrixFrames(p, &t)) {
    ambiguous += m.status == vision::FrameStatus::kAmbiguous;
    EXPECT_FALSE(m.valid()) << m.width_px << " ± " << m.width_sigma_px << " px, truth "
                            << t.width_px;
    stripe += m.gave_width() && std::abs(m.width_px - t.width_px) > 4 * m.width_sigma_px;
  }
  EXPECT_GE(ambiguous, 3) << Describe(p);
  EXPECT_LE(stripe, 1) << Describe(p);
}

TEST(AdversarialTest, AStripeAtTheBackgroundsLevelSplitsTheStrandIntoAmbiguity) {
  // A dark 191 px strand whose specular stripe comes out near the background's level (JPEG
  // q40) looks like two parallel strands side by side, 32 and 114 px, both under the nozzle.
  // Either part, or their union, could be the strand: `ambiguous`, whichever part scores
  // higher. (Frame 1 was the 32 px part, valid at ± 0.06 px. In frame 3 the narrow part's edge
  // segments ran on into the nozzle, its walks started off the edge and put its top 60 px up in
  // the nozzle, and the 114 px part was measured, 114.17 ± 0.04 px. Walked from the middle, the
  // narrow part's top is on the face again; and the gap between the parts, 45 px and bright, is
  // no strand either, though each part scores under 0.8 of it.)
  ExpectMatrixFramesAmbiguous(RandomAdversarialScene(TroubleClass::kSpecularStripe, 122));
}

TEST(AdversarialTest, AStripeBetweenTwoDarkHalvesIsNotTheStrand) {
  // A dark 52 px strand whose bright stripe, 10 px wide, has the background's level (matrix seed
  // 117 of the unseen set, its noise lowered): two dark bars hang from the nozzle with a bright
  // gap between them, and the silhouette around all three is ruled out for the background
  // showing inside it. The gap was measured as a bright strand, 9.8 px (valid at this noise).
  // It is as much a stripe as a strand between two gaps: `ambiguous`.
  AdversarialScene p = RandomAdversarialScene(TroubleClass::kSpecularStripe, 117);
  p.noise_sigma = 2;
  AdversarialTruth t;
  for (const vision::StrandMeasurement& m : MeasuredMatrixFrames(p, &t)) {
    EXPECT_TRUE(!m.valid() || std::abs(m.width_px - t.width_px) <= WrongTolerancePx(t.width_px))
        << m.width_px << " ± " << m.width_sigma_px << " px, truth " << t.width_px << ": "
        << Describe(p);
    EXPECT_EQ(m.status, vision::FrameStatus::kAmbiguous) << m.detail;
  }
}

TEST(AdversarialTest, NozzleAloneNeverGivesAWidth) {
  for (uint64_t seed = 1; seed <= 6; ++seed) {
    const AdversarialScene p = RandomAdversarialScene(TroubleClass::kNoStrand, seed);
    const vision::StrandMeasurement m = RenderAndMeasure(p, nullptr);
    // The README's accuracy table: "nozzle alone … 0 (all `no_strand`)".
    EXPECT_EQ(m.status, vision::FrameStatus::kNoStrand)
        << vision::FrameStatusName(m.status) << ", " << m.width_px << " px: " << Describe(p);
  }
}

}  // namespace
}  // namespace clogscope::synthetic
