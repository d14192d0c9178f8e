// The contest between pairs that held up, and the doubts about the chosen one (scene.h).
#include <fmt/format.h>

#include <algorithm>
#include <cassert>
#include <cmath>

#include "vision/scene/pair_relations.h"
#include "vision/scene/scene.h"

namespace clogscope::vision {

// Whether the nozzle's face shows on both sides of a pair clearly enough that its absence beside
// another object says that object does not hang from it: a reading of it steps by
// kDecisiveFaceContrast times the least contrast searched for. One just above that least contrast
// may be missed beside the next object, or be a background's slope taken for part of a step.
namespace {
constexpr double kDecisiveFaceContrast = 1.5;
}  // namespace

bool HangsFromFace(const StrandGeometry& g, const SceneOptions& o) {
  return g.tip_face_sides == 2 && g.tip_face_step >= kDecisiveFaceContrast * o.min_contrast;
}

namespace {

// Objects of the other polarity on both sides of a pair, sharing its edges, make it a stripe or a
// gap as much as a strand when each scores this share of it: its edges are theirs, so a score
// short of the ambiguity ratio says little about which is the object.
constexpr double kFlankScoreRatio = 0.5;
// An edge this many times the least contrast is an object's, not a background's texture.
constexpr double kFadedRivalContrast = 3.0;
// The face read beside a pair, on one side or faintly on both, but not decisively.
bool FaceReadInPart(const StrandGeometry& g, const SceneOptions& o) {
  return g.tip_face_sides >= 1 && !HangsFromFace(g, o);
}

}  // namespace

PairContest ContestPairs(const PairCandidate& b, const StrandGeometry& bg, const PairCandidate& c,
                         const StrandGeometry& cg, const SceneOptions& o) {
  const auto [bl, br] = Interval(b, b.axis);
  const auto [cl, cr] = Interval(c, b.axis);
  // Two strands in one view look alike; a gap between objects (a mixed pair) is another thing.
  if (!Disjoint(b, c) || c.polarity != b.polarity) return PairContest::kNotRivals;
  // Two strand-like objects: the one hanging from the nozzle's face (the nozzle on both its
  // sides) is the strand; a hair that ends at a flank, or in the open, is not. But the face read
  // on one side only does not tell a rival apart: a hair from the face's corner reads so, and so
  // does a strand whose face noise hid on one side (a 91 px strand lost so to an 8 px hair from
  // the corner, in one of four frames). The better-scoring pair read so is never outranked by
  // the face; a weaker one that could not rival it (CouldRival) is.
  const bool b_at_face = HangsFromFace(bg, o), c_at_face = HangsFromFace(cg, o);
  if (o.target == MeasureTarget::kStrand && b_at_face != c_at_face) {
    if (FaceReadInPart(bg, o) || (FaceReadInPart(cg, o) && CouldRival(b, c)))
      return PairContest::kFaceOnOneSide;
    return b_at_face ? PairContest::kFirstAtFace : PairContest::kSecondAtFace;
  }
  // Two parallel objects side by side, closer than either is wide, that the tip did not tell
  // apart: one strand whose stripe matches the background, or a strand and its neighbour.
  // Which is the strand, or whether their union is, the frame cannot say, whatever the scores.
  const double gap_px = std::max(cl - br, bl - cr);
  if (Parallel(b, c) && gap_px < std::max(br - bl, cr - cl)) return PairContest::kSideBySide;
  // Neither at the face: which object is the strand the frame does not say, if the other could
  // be one. (Scores once chose a 10 px hair over an 83 px strand whose nozzle was at the
  // background's level.)
  if (o.target == MeasureTarget::kStrand && !b_at_face && !c_at_face && CouldRival(b, c))
    return PairContest::kNeitherAtFace;
  // Both at the face: the tip does not tell them apart either, and a wider object that could be
  // the strand is not outranked by a narrower one's score (a 50 µm stringer from the face's
  // corner, 9.1 px at σ 0.17 reported where the strand beside it is 102.6 px, stringer 3966). A
  // narrower rival is a stringer beside the strand as often as not; the better-scoring wider one
  // stays chosen.
  if (o.target == MeasureTarget::kStrand && b_at_face && c_at_face && c.width_px > b.width_px &&
      CouldRival(b, c))
    return PairContest::kBothAtFace;
  return c.score >= o.ambiguity_ratio * b.score ? PairContest::kSimilarScore
                                                : PairContest::kOutscored;
}

std::string AmbiguityDetail(PairContest contest, const PairCandidate& b, const PairCandidate& c) {
  assert(Ambiguous(contest));
  return fmt::format(contest == PairContest::kSideBySide
                         ? "two strand-like objects side by side: {} and {}"
                     : contest == PairContest::kNeitherAtFace
                         ? "two strand-like objects, neither hanging clearly from the nozzle's "
                           "face: {} and {}"
                     : contest == PairContest::kFaceOnOneSide
                         ? "two strand-like objects, the nozzle's face read on one side only, or "
                           "faintly, beside one of them: {} and {}"
                     : contest == PairContest::kBothAtFace
                         ? "two strand-like objects, both hanging from the nozzle's face, the "
                           "wider scoring less: {} and {}"
                         : "two strand-like pairs of similar score: {} and {}",
                     Describe(b), Describe(c));
}

namespace {

// A dark strand's stripe at the background's level leaves two dark bars with a bright gap, and
// the silhouette around all three is ruled out for the background showing inside it: the gap's
// neighbours are of the other polarity, so ContestPairs sees no rivals, and nothing else would
// stop the gap from being measured as the strand.
std::string FlankedDetail(const SceneResult& r, int index) {
  const PairCandidate& b = r.candidates[index];
  if (b.polarity == Polarity::kMixed) return "";
  const PairCandidate* flank[2] = {nullptr, nullptr};
  const auto consider = [&](int other) {
    if (other < 0 || other == index) return;
    const PairCandidate& c = r.candidates[other];
    if (c.polarity == b.polarity || c.polarity == Polarity::kMixed ||
        c.score < kFlankScoreRatio * b.score || !Parallel(b, c))
      return;
    if (c.right == b.left) flank[0] = &c;
    if (c.left == b.right) flank[1] = &c;
  };
  consider(r.chosen);
  for (const auto& runner_up : r.runners_up) consider(runner_up.first);
  if (!flank[0] || !flank[1]) return "";
  return fmt::format(
      "{} lies between two strand-like objects of the other polarity, {} and {}: a stripe in one "
      "strand or a gap between two",
      Describe(b), Describe(*flank[0]), Describe(*flank[1]));
}

// A dark strand's stripe at the background's level whose narrow side is no pair of its own: the
// strand's outline is ruled out for the background showing inside it, and its wide side stood
// alone (42.8 px of a 64.6 px strand, valid at sigma 0.02-0.06).
std::string SplitDetail(const SceneResult& r, int index) {
  const PairCandidate& b = r.candidates[index];
  const auto [bl, br] = Interval(b, b.axis);
  for (const PairCandidate& c : r.candidates) {
    if (c.verdict != PairVerdict::kSpansObjects || c.polarity != b.polarity ||
        c.score < kFlankScoreRatio * b.score || c.width_px <= b.width_px ||
        c.width_px - b.width_px > b.width_px || !Parallel(b, c))
      continue;
    // One edge in common (the same line, if not the same segment).
    const auto [cl, cr] = Interval(c, b.axis);
    if (std::abs(cl - bl) > kSameEdgePx && std::abs(cr - br) > kSameEdgePx) continue;
    return fmt::format(
        "{} shares an edge with a wider pair whose inside shows the background, {}: one strand "
        "split by a stripe at the background's level, or a strand beside another object",
        Describe(b), Describe(c));
  }
  return "";
}

// A pair inside a wider one (or inside one inside it), which then did not hold up for want of a
// tip in line only: a strand lit from one side whose faint shaded edge faded before the nozzle (the
// edges ending 23 px apart), and inside it its bright stripe's edge paired with its far edge, which
// hangs from the face (83.4 px at sigma 0.04, where the strand is 161.8). The wider pair may be
// the strand.
std::string InsideUnheldDetail(const SceneResult& r, int index) {
  const PairCandidate& b = r.candidates[index];
  const auto wider_may_be_strand = [&](const PairCandidate& c) {
    return fmt::format(
        "{} lies inside a wider strand-like pair whose tip was not found ({}: {}): the strand "
        "may be the wider one",
        Describe(b), Describe(c), c.why);
  };
  // Each wider than the last: the chain ends.
  for (int w = b.reinstated_from; w >= 0; w = r.candidates[w].reinstated_from) {
    const PairCandidate& c = r.candidates[w];
    if (c.verdict == PairVerdict::kNoTip) return wider_may_be_strand(c);
  }
  // Or inside one that had no tip in line, though too weak or too short to rule it out first
  // (MayBeInsideOf): a dark 45 px strand under noise of 10 grey levels, its faint edges ending
  // 41 px apart, and inside it a bright stripe hanging from the face (12.8 px at σ 0.5). The face
  // read beside a pair inside another is the other's inside, not the background.
  for (const PairCandidate& c : r.candidates)
    if (c.verdict == PairVerdict::kNoTip && MayBeInsideOf(b, c)) return wider_may_be_strand(c);
  return "";
}

// A wider strand-like pair that did not hold up as the strand is out as the strand, but not as
// the reason to doubt a narrower one that does not hang clearly from the nozzle's face: a
// strand lit from one side whose shaded edge is faint reads so. Beside a 14 px hair from the
// face's corner (measured alone, valid at sigma 0.04, where the strand is 111 px), such a strand's
// pair had no tip in line (its faint edge faded before the nozzle) or scored below the minimum
// (never followed), from frame to frame; where its shaded rim sank to the background's level (a
// strand level of 40-60 on a background of 21) it paired as mixed. Such a pair counts as a rival
// whose tip is unknown (one not at the face) and, if mixed, of the narrower one's polarity. A
// narrower one is a hair crossing the view, or hanging from above it. (On ten matrices of 1100
// strand frames each, 3 valid frames became ambiguous so, on pairs of background texture. Pairs
// whose edges faded along them, kWeakEdges, do not count: there they were faint texture 150-680
// px wide, and would have cost 4 more valid frames for no wrong one.)
std::string UnheldRivalDetail(const SceneResult& r, int index, const StrandGeometry& g,
                              const SceneOptions& o) {
  if (HangsFromFace(g, o)) return "";
  const PairCandidate& b = r.candidates[index];
  const StrandGeometry unknown_tip;
  for (const PairCandidate& c : r.candidates) {
    // Judged below the minimum: only while the search still followed pairs (ChoosePair). In a
    // cluttered view it stops before the faint ones, and they do not count: counting every pair
    // below the minimum made 4 more valid frames of ten matrices ambiguous, each on a mixed pair
    // of a long edge (a hair's, a strand's) and a short one of texture.
    // And a mixed pair that held up, but as no rival for its polarity (ContestPairs): the same
    // strand once its faint edge was followed to the nozzle (seed 709 at strand level 60: the
    // hair alone, 14.5 px at σ 0.04 where the strand is 111.4). Weighed like the others, its tip
    // unknown. Not one whose edge lies on the narrower one's own edge line, paired with texture
    // beyond it (a 180 px mixed pair beside an 87 px strand: three valid frames of eight sets
    // made ambiguous).
    const bool mixed_held = c.verdict == PairVerdict::kOutscored &&
                            c.polarity == Polarity::kMixed && !OnAnEdgeLineOf(b, c);
    if ((c.verdict != PairVerdict::kNoTip && c.verdict != PairVerdict::kScoreBelow &&
         !mixed_held) ||
        c.width_px <= b.width_px)
      continue;
    PairCandidate as_strand = c;
    if (as_strand.polarity == Polarity::kMixed) as_strand.polarity = b.polarity;
    if (!Ambiguous(ContestPairs(b, g, as_strand, unknown_tip, o))) continue;
    return fmt::format(
        "{} does not hang clearly from the nozzle's face, and a wider strand-like object {} ({}, "
        "{}, an edge {:.0f} px long{}{}): which is the strand the frame does not say",
        Describe(b), mixed_held ? "held up only as a mixed pair" : "did not hold up as a pair",
        Describe(c), PolarityName(c.polarity), c.long_edge_px, mixed_held ? "" : ": ",
        mixed_held ? "" : c.why);
  }
  return "";
}
// A wider pair of the chosen one's kind, clear of it, that could be the strand and was ruled out
// only for an edge fading along it while its other edge is an object's (kFadedRivalContrast times
// the least contrast): a strand lit from one side whose shaded rim sank to the background's level
// in places. Its tip is unknown, so a narrower pair hanging from the face does not outrank it: a
// hair from the face beside such a strand was measured alone (stringer 8104, 18.2 px at σ 0.10
// where the strand is 153.4; in the other frames the strand's pair held up, the hair's did not).
// Strand-like: its common stretch at least as long as it is wide (a nozzle's flank paired with
// texture, 38 px long and 62 px wide, is not).
std::string FadedRivalDetail(const SceneResult& r, int index, const SceneOptions& o) {
  const PairCandidate& b = r.candidates[index];
  for (const PairCandidate& c : r.candidates) {
    if (c.verdict != PairVerdict::kWeakEdges || c.polarity != b.polarity ||
        c.width_px <= b.width_px || c.length_px < c.width_px || !Disjoint(b, c) ||
        !CouldRival(b, c) ||
        std::max(c.left_contrast, c.right_contrast) < kFadedRivalContrast * o.min_contrast)
      continue;
    return fmt::format(
        "a wider strand-like object ({}) was ruled out only for an edge fading along it (edge "
        "contrast {:.0f}/{:.0f}): it may be the strand rather than {}",
        Describe(c), c.left_contrast, c.right_contrast, Describe(b));
  }
  return "";
}
}  // namespace

std::string ChoiceDoubtDetail(const SceneResult& r, int index, const StrandGeometry& g,
                              const SceneOptions& o) {
  std::string why = FlankedDetail(r, index);
  if (!why.empty() || o.target != MeasureTarget::kStrand) return why;
  why = SplitDetail(r, index);
  if (why.empty()) why = InsideUnheldDetail(r, index);
  if (why.empty()) why = UnheldRivalDetail(r, index, g, o);
  if (why.empty()) why = FadedRivalDetail(r, index, o);
  return why;
}

}  // namespace clogscope::vision
