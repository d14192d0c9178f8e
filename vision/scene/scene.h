#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <vector>

#include "vision/edges/grey_image.h"
#include "vision/edges/polarity.h"
#include "vision/scene/frame_status.h"

namespace clogscope::vision {

// How the strand (or filament) is looked for: a pair of long, straight, nearly parallel edges whose
// separation holds along the axis, found from the image gradient (no global threshold).
struct SceneOptions {
  MeasureTarget target = MeasureTarget::kStrand;
  Polarity polarity = Polarity::kAuto;  // forced: only pairs of that polarity count
  double max_tilt_deg = 45.0;           // axes leaning more than this from vertical are ignored
  double min_length_px = 30.0;          // shortest common stretch of the two edges
  double min_width_px = 8.0;            // narrower pairs are lines (scratches, glints), not strands
  double min_contrast = 15.0;    // edge step below this (grey levels of the data's range): too weak
  double ambiguity_ratio = 0.8;  // a disjoint runner-up scoring this much of the best: ambiguous
  double min_score = 15.0;       // below this no candidate is a strand (score units: px of edge)
};

// A straight piece of an intensity edge, ROI pixel coordinates at full resolution.
struct EdgeSegment {
  cv::Point2d top, bottom;  // ends, top.y <= bottom.y
  int sign = 0;             // +1: brighter on the +x side, −1: darker on the +x side
  double strength = 0;      // median |gradient| along it, grey levels per px
  double coverage = 0;      // fraction of the sampled rows along it that hold an edge point
  double length_px() const { return cv::norm(bottom - top); }
};

// What became of a candidate pair: chosen, or why not. Overlays colour by it and the frame's
// reason follows from it; PairCandidate::why says it in words, with its numbers.
enum class PairVerdict {
  kNotExamined,
  kChosen,
  kSpansObjects,     // the background shows between its edges
  kInsideWider,      // inside a wider pair: a stripe, a lens's core, a clear strand's lines
  kScoreBelow,       // below the minimum score
  kWeakEdges,        // its edges' contrast fades along the full-resolution image
  kNoTip,            // its edges do not end together at a nozzle tip
  kNotAtFace,        // another pair hangs from the nozzle's face; this one does not
  kAsLikely,         // a rival as likely as it: the frame is ambiguous
  kOutscored,        // held up, but scored clearly below the chosen pair
  kMeasuredRefused,  // chosen, then refused by the calipers (its measurement's status)
};
// A verdict that rules the pair out as the object, rather than ranking it below another.
bool RulesOut(PairVerdict verdict);

// One candidate: two edges as the strand's silhouette. The axis is the bisector of the pair.
struct PairCandidate {
  int left = -1, right = -1;            // indices into SceneResult::edges
  Polarity polarity = Polarity::kAuto;  // bright, dark, or kMixed (brighter on one side only)
  AxisFrame axis;                       // origin on the axis at the top of the common stretch
  double left_u0 = 0, right_u0 = 0;     // edge lines u = u0 + slope·s in `axis`
  double edge_slope = 0;
  double length_px = 0;     // common stretch (from the segments)
  double long_edge_px = 0;  // the longer of its edge lines' runs (ExtendPair's, else the seeds')
  double width_px = 0;      // perpendicular separation
  double snr = 0;           // weaker edge's gradient over the gradient noise
  // Each edge's contrast along the full-resolution image (grey levels), where it was read and
  // found too weak (kWeakEdges); else 0.
  double left_contrast = 0, right_contrast = 0;
  double score = 0;
  PairVerdict verdict = PairVerdict::kNotExamined;
  std::string why;  // the verdict in words
  // Sets the verdict and its words: `words`, or the verdict's own when it carries no numbers.
  void Judge(PairVerdict v, std::string words = {});
  int suppressed_by = -1;  // the wider pair it lies inside (index into the candidates), if any
  // The wider pair it lay inside, which then did not hold up (its suppression lifted; index into
  // the candidates), if any.
  int reinstated_from = -1;
};

// The chosen pair, followed along the full-resolution image, with where it ends.
struct StrandGeometry {
  AxisFrame axis;  // origin on the axis: at the tip (strand) or the top of the stretch (filament)
  double left_u0 = 0, right_u0 = 0, edge_slope = 0;
  double width_px = 0;  // coarse width of the pair
  int left_sign = 0, right_sign = 0;
  Polarity polarity = Polarity::kAuto;
  bool has_tip = false;
  // Strand: the widest width between the tip and the straight part (die swell), px.
  double tip_width_px = 0;
  int tip_face_sides = 0;  // strand: on how many sides the nozzle's face shows at the tip (tip.h)
  // Strand, face on both sides: its strongest reading's |step|, grey levels (tip.h).
  double tip_face_step = 0;
  double tip_sigma_px = -1;  // strand: the tip's doubt along the axis; < 0 unconfirmed (tip.h)
  bool precise = false;      // edge lines from fitted calipers (tracking), not from the gradient
  // Edge model per side: −1 decide from the calipers, 0 plain blurred step, 1 shaded (tracking
  // keeps the first frame's decision).
  int shading_left = -1, shading_right = -1;
  // Tracking a filament: the straight part of the stretch measured last (px from origin; empty
  // when none), kept while it stays straight so that the width comes from the same place.
  double straight_s0_px = 0, straight_s1_px = 0;
  // Each edge's contrast along the full-resolution image where the pair was followed (grey
  // levels; FollowPair sets them before judging them, also when they are too weak).
  double left_contrast = 0, right_contrast = 0;
  double s_end = 0;  // where the pair ends downward (bed, obstacle or border), from origin
  bool end_is_object = false;  // the pair ends at an object (bed) rather than the border
  double score = 0;
};

struct SceneResult {
  FrameStatus status = FrameStatus::kNoStrand;  // kValid when a pair was chosen
  std::string detail;                           // why not, naming the best candidate
  int channel = 0;           // which of the prepared channels the chosen pair was found in
  int measured_channel = 0;  // which one measured it (luma where it can: strand_measure.h)
  // The colour channel that measured it carries luma's doubt about the scene, which only both
  // channels measured together give: each frame is found afresh (StrandTracker).
  bool channel_doubts_luma = false;
  double gradient_noise = 0;  // grey levels per px
  std::vector<EdgeSegment> edges;
  std::vector<PairCandidate> candidates;  // best first
  int chosen = -1;
  StrandGeometry geometry;
  // The other pairs that held up when followed, best first (candidate index and geometry): the
  // measurement falls back to them when the chosen pair's calipers reject it.
  std::vector<std::pair<int, StrandGeometry>> runners_up;
};

// How a second pair that held up (c, followed as cg) stands against the first (b, bg):
// kNotRivals: not two separate objects of one polarity (a stripe inside, a gap beside);
// kFirstAtFace / kSecondAtFace: the tip decides — only that one hangs clearly from the nozzle's
// face (on both sides, stepping by 1.5 times the least contrast somewhere: HangsFromFace);
// kSideBySide: parallel and closer than either is wide (one strand with a stripe at the
// background's level, or two strands): ambiguous whatever the scores;
// kNeitherAtFace: a strand's target, neither hangs clearly from the nozzle's face, and c
// could be the strand (it scores at least half as well as b, or is wider than b and one of its
// edges longer than it is wide): the tip does not decide, and a score (contrast, length) does
// not tell a strand from a hair or another strand: ambiguous;
// kBothAtFace: a strand's target, both hang clearly from the face, and c is wider than b and
// could be the strand: the thinner one does not win on its score (a stringer from the face's
// corner beside the strand): ambiguous;
// kSimilarScore: c scores at least ambiguity_ratio of b: ambiguous; kOutscored: b wins.
// Whether the nozzle's face shows on both sides of a pair followed as `g` clearly enough to tell
// it from another strand-like object: some reading of it steps by 1.5 times the least contrast
// searched for (options.min_contrast).
bool HangsFromFace(const StrandGeometry& g, const SceneOptions& options);

enum class PairContest {
  kNotRivals,
  kFirstAtFace,
  kSecondAtFace,
  kSideBySide,
  kNeitherAtFace,
  kFaceOnOneSide,  // one clearly at the face, the other on one side or faintly: not decided so
  kBothAtFace,     // both at the face, the other wider and strand-like: not decided by score
  kSimilarScore,
  kOutscored
};
PairContest ContestPairs(const PairCandidate& b, const StrandGeometry& bg, const PairCandidate& c,
                         const StrandGeometry& cg, const SceneOptions& options);
inline bool Ambiguous(PairContest c) {
  return c == PairContest::kSideBySide || c == PairContest::kNeitherAtFace ||
         c == PairContest::kFaceOnOneSide || c == PairContest::kBothAtFace ||
         c == PairContest::kSimilarScore;
}
// The `ambiguous` detail for an ambiguous contest (Ambiguous).
std::string AmbiguityDetail(PairContest contest, const PairCandidate& b, const PairCandidate& c);
// The `ambiguous` detail when choosing candidate `index` (followed as `g`) leaves a doubt the
// contests of pairs that held up do not see; empty when none:
// - it lies between two pairs of the other polarity that held up (r.chosen and r.runners_up),
//   share its edges, are parallel to it and each score at least half as well (a stripe in one
//   strand or a gap between two objects);
// - for a strand, it shares an edge with a wider, parallel pair of its kind that was ruled out
//   only for the background showing inside it (kSpansObjects), whose other edge is nearer than
//   `index` is wide and which scores at least half as well (one strand split by a stripe at the
//   background's level, or a strand beside another object);
// - it lay inside a wider pair (SuppressNested), or inside one inside it, that then did not hold
//   up for want of a tip in line only (a strand whose faint shaded edge fades before the nozzle,
//   around its stripe);
// - for a strand not clearly at the nozzle's face, a wider pair that did not hold up (no tip
//   in line, or a score below the minimum) would be a rival by ContestPairs were its tip one not
//   at the face and, if mixed, its polarity `index`'s (a strand whose shaded edge is faint,
//   beside a hair).
std::string ChoiceDoubtDetail(const SceneResult& r, int index, const StrandGeometry& g,
                              const SceneOptions& options);

// Finds the strand in one or more single-channel 8/16-bit views of the same ROI (grey, or a
// colour frame's luma and channels): the channel whose best pair scores highest is used. Contrast
// limits come from options.min_contrast, in the data's own range.
SceneResult FindScene(const std::vector<cv::Mat>& channels, const SceneOptions& options);

// Follows a known pair (from an earlier frame) in `grey`: finds its ends again. Used by tracking;
// returns false when the pair's edges are not there, with the verdict (kWeakEdges or kNoTip) and
// why in words (out's edge contrasts are set either way).
bool FollowPair(const GreyImage& img, const SceneOptions& options, const PairCandidate& pair,
                int left_sign, int right_sign, StrandGeometry* out, PairVerdict* failure,
                std::string* why);

}  // namespace clogscope::vision
