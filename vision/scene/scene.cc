#include "vision/scene/scene.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <opencv2/imgproc.hpp>

#include "common/angle.h"
#include "common/robust.h"
#include "vision/scene/edge_segments.h"
#include "vision/scene/pair_candidates.h"
#include "vision/scene/pair_relations.h"
#include "vision/scene/tip.h"

namespace clogscope::vision {
namespace {

constexpr int kMaxFollowed = 6;  // pairs followed along the full-resolution image

// For a pair of segments leaving the image at one border only, is it an object cut lengthwise by
// the ROI? (One long edge whose object side runs uniformly to the nearer side border.)
bool CutByBorder(const GreyImage& img, const std::vector<EdgeSegment>& edges, double min_length) {
  std::vector<double> levels;
  for (int y = 4; y < img.m.rows; y += 8)
    for (int x = 4; x < img.m.cols; x += 8) levels.push_back(img.At(x, y));
  const double background = Median(levels);
  for (const auto& e : edges) {
    // Cut lengthwise, the object runs along the side border; a steep edge (a nozzle flank) is not.
    if (e.length_px() < std::max(3.0 * min_length, 0.3 * img.m.rows)) continue;
    if (std::abs(e.bottom.x - e.top.x) > std::tan(15.0 * kDegToRad) * (e.bottom.y - e.top.y))
      continue;
    const cv::Point2d mid = 0.5 * (e.top + e.bottom);
    const int y = static_cast<int>(std::lround(mid.y));
    const bool to_left = mid.x < 0.5 * img.m.cols;
    const int x_from = static_cast<int>(std::lround(mid.x)) + (to_left ? -4 : 4);
    const int x_to = to_left ? 0 : img.m.cols - 1;
    if (x_from < 0 || x_from >= img.m.cols) continue;
    std::vector<double> v;
    for (int x = x_from; to_left ? x >= x_to : x <= x_to; x += to_left ? -1 : 1)
      v.push_back(img.At(x, y));
    if (v.size() < 2) continue;
    const double level = Median(v);
    const double far_side = img.At(std::clamp(x_from + (to_left ? 8 : -8), 0, img.m.cols - 1), y);
    const double step = std::abs(level - far_side);
    if (step < 1e-9 || std::abs(level - background) < 0.5 * step) continue;
    double max_dev = 0;
    for (double x : v) max_dev = std::max(max_dev, std::abs(x - level));
    if (max_dev < 0.3 * step) return true;
  }
  return false;
}

}  // namespace

void PairCandidate::Judge(PairVerdict v, std::string words) {
  verdict = v;
  if (!words.empty()) {
    why = std::move(words);
    return;
  }
  switch (v) {
    case PairVerdict::kChosen:
      why = "chosen";
      return;
    case PairVerdict::kSpansObjects:
      why = "spans separate objects: the background shows between its edges";
      return;
    case PairVerdict::kNotAtFace:
      why = "its top is not at the nozzle's face";
      return;
    default:
      why.clear();
  }
}

bool RulesOut(PairVerdict v) {
  return v == PairVerdict::kSpansObjects || v == PairVerdict::kInsideWider ||
         v == PairVerdict::kNoTip || v == PairVerdict::kNotAtFace;
}

namespace {

// The frame is ambiguous: `rival` is as likely as the chosen pair, for the reason `detail`.
void AsLikely(PairCandidate* rival, std::string detail, SceneResult* r) {
  rival->Judge(PairVerdict::kAsLikely, "as likely as the chosen pair");
  r->status = FrameStatus::kAmbiguous;
  r->detail = std::move(detail);
}

// Follows the best candidates of one channel on its full-resolution image; the first that holds
// up is chosen (or the frame is ambiguous, or nothing holds up: r.status says which, and why).
void ChoosePair(const cv::Mat& channel, const SceneOptions& o, SceneResult* result) {
  SceneResult& r = *result;
  const GreyImage img{channel, channel.depth() == CV_16U};

  // Follow the best candidates on the full-resolution image; the first that holds up is chosen.
  std::string first_reason;
  PairVerdict first_failure = PairVerdict::kNotExamined;
  int examined = 0;
  for (int i = 0; i < static_cast<int>(r.candidates.size()) && examined < kMaxFollowed; ++i) {
    PairCandidate& c = r.candidates[i];
    if (c.verdict != PairVerdict::kNotExamined) continue;
    if (c.score < o.min_score) {
      c.Judge(PairVerdict::kScoreBelow, fmt::format("score below {:.0f}", o.min_score));
      continue;
    }
    ++examined;
    StrandGeometry g;
    if (!FollowPair(img, o, c, r.edges[c.left].sign, r.edges[c.right].sign, &g, &c.verdict,
                    &c.why)) {
      if (c.verdict == PairVerdict::kWeakEdges) {
        c.left_contrast = g.left_contrast;
        c.right_contrast = g.right_contrast;
      }
      if (first_reason.empty()) {
        first_reason = c.why;
        first_failure = c.verdict;
      }
      // The pairs this one outranked as their wider silhouette compete again, best first.
      bool reinstated = false;
      for (auto& inner : r.candidates) {
        if (inner.suppressed_by != i) continue;
        inner.suppressed_by = -1;
        inner.reinstated_from = i;
        inner.Judge(PairVerdict::kNotExamined);
        reinstated = true;
      }
      if (reinstated) i = -1;
      continue;
    }
    if (r.chosen < 0) {
      r.chosen = i;
      r.geometry = g;
      c.Judge(PairVerdict::kChosen);
      continue;
    }
    // A second pair that holds up: ambiguous when it is a separate object of similar score.
    const PairCandidate& b = r.candidates[r.chosen];
    // Or the wider silhouette of the other kind the chosen one lies inside (MayBeInsideOf). Its
    // detected stretch was too short to rule the chosen one out (SuppressNested): a dark strand
    // whose far edge showed along its lower half only, and inside it a bright stripe hanging
    // from the face (14.0 px at σ 0.19 where the strand is 179.9). A comparable one hanging from
    // the same tip is the object. One too weak to be it outright, or whose tip lies elsewhere,
    // could still be the strand (a faint 45 px strand under noise of 10 grey levels around its
    // bright stripe, 12.8 px at σ 0.5): the face read beside a pair inside another is the
    // other's inside, not the background, and does not decide.
    const auto inside_the_wider = [&] {
      AsLikely(&c,
               fmt::format("{} lies inside a wider strand-like pair that also holds up, {}: the "
                           "strand may be the wider one",
                           Describe(b), Describe(c)),
               &r);
    };
    // One of its own kind, too, where it hangs clearly from the face as a strand does and lies
    // clear of both its edges: a lit strand whose faint shaded rims scored 13 % of its bright
    // stripe's, which was measured (11.5 px at σ 0.18 where the strand is 143.4). One that does
    // not hang so is as often the strand and a hair beside it, paired across both; one on its
    // edge line, the strand's edge paired with a lamp's spot beyond its other (8 right valid
    // frames of 26 sets).
    if (o.target == MeasureTarget::kStrand && SameKind(b, c) && InsideARival(b, c) &&
        !OnAnEdgeLineOf(b, c) && HangsFromFace(g, o)) {
      inside_the_wider();
      return;
    }
    if (o.target == MeasureTarget::kStrand && MayBeInsideOf(b, c)) {
      const bool same_tip =
          std::abs(r.geometry.axis.S(g.axis.ox, g.axis.oy)) <= MaxTipMismatchPx(c.width_px);
      if (!same_tip || !Encloses(o.target, c, b)) {
        inside_the_wider();
        return;
      }
      JudgeInsideWider(c, &r.candidates[r.chosen]);
      r.chosen = i;
      r.geometry = g;
      c.Judge(PairVerdict::kChosen);
      // The pairs the inner one outscored, weighed again against the strand.
      for (const auto& [k, kg] : r.runners_up) {
        const PairContest again = ContestPairs(c, g, r.candidates[k], kg, o);
        if (!Ambiguous(again)) continue;
        AsLikely(&r.candidates[k], AmbiguityDetail(again, c, r.candidates[k]), &r);
        return;
      }
      continue;
    }
    const PairContest contest = ContestPairs(b, r.geometry, c, g, o);
    if (contest == PairContest::kSecondAtFace) {
      r.candidates[r.chosen].Judge(PairVerdict::kNotAtFace);
      r.runners_up.clear();
      r.chosen = i;
      r.geometry = g;
      c.Judge(PairVerdict::kChosen);
      continue;
    }
    if (contest == PairContest::kFirstAtFace) {
      c.Judge(PairVerdict::kNotAtFace);
      continue;
    }
    if (Ambiguous(contest)) {
      AsLikely(&c, AmbiguityDetail(contest, b, c), &r);
      return;
    }
    c.Judge(PairVerdict::kOutscored,
            fmt::format("scores {:.0f} % of the chosen pair", 100 * c.score / b.score));
    r.runners_up.emplace_back(i, g);
  }
  if (r.chosen >= 0) {
    if (std::string why = ChoiceDoubtDetail(r, r.chosen, r.geometry, o); !why.empty()) {
      r.status = FrameStatus::kAmbiguous;
      r.detail = std::move(why);
      return;
    }
    r.status = FrameStatus::kValid;
    r.detail.clear();
    return;
  }
  const PairCandidate* top = nullptr;
  for (const auto& c : r.candidates)
    if (!top || c.score > top->score) top = &c;
  if (top && top->score >= o.min_score && o.target == MeasureTarget::kStrand &&
      first_failure == PairVerdict::kNoTip) {
    r.status = FrameStatus::kNoTip;
    r.detail = fmt::format("best pair ({}): {}", Describe(*top), first_reason);
    return;
  }
  if (CutByBorder(img, r.edges, o.min_length_px)) {
    r.status = FrameStatus::kTouchesBorder;
    r.detail = "a long object runs into the frame or ROI side: its other edge is outside";
    return;
  }
  r.status = FrameStatus::kNoStrand;
  if (top) {
    r.detail =
        fmt::format("best pair ({}) lost: {}", Describe(*top),
                    top->verdict == PairVerdict::kNotExamined ? "no better candidate" : top->why);
  } else {
    r.detail = fmt::format("no pair of parallel edges at least {:.0f} px long ({} straight edges)",
                           o.min_length_px, r.edges.size());
  }
}

}  // namespace

SceneResult FindScene(const std::vector<cv::Mat>& channels, const SceneOptions& o) {
  // Each channel is searched on its own. They are tried best pair first: the first channel in
  // which a pair holds up is used (a clear strand's internal lines may outscore its silhouette in
  // luma and leave two look-alike pairs, while the silhouette stands alone in blue).
  std::vector<SceneResult> found;
  std::vector<double> top_score;
  for (int ch = 0; ch < static_cast<int>(channels.size()); ++ch) {
    const Detection d = DetectEdgePoints(channels[ch], o);
    const std::vector<Piece> pieces = StraightPieces(d, o.max_tilt_deg);
    SceneResult r;
    r.channel = r.measured_channel = ch;
    r.gradient_noise = d.noise / d.factor;
    for (const Piece& p : pieces) {
      EdgeSegment s = ToSegment(p, d);
      if (s.length_px() >= o.min_length_px) r.edges.push_back(s);
    }
    r.candidates = PairSegments(d, r.edges, r.gradient_noise, channels[ch].cols, o);
    for (auto& c : r.candidates) {
      if (!InsideIsOneObject(d, c)) {
        c.Judge(PairVerdict::kSpansObjects);
      }
    }
    SuppressNested(o.target, &r.candidates);
    double top = 0;
    for (const auto& c : r.candidates)
      if (c.verdict == PairVerdict::kNotExamined) top = std::max(top, c.score);
    found.push_back(std::move(r));
    top_score.push_back(top);
  }
  std::vector<int> order(found.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return top_score[a] > top_score[b]; });
  for (int ch : order) {
    if (top_score[ch] < o.min_score && ch != order.front()) break;
    ChoosePair(channels[ch], o, &found[ch]);
    if (found[ch].status == FrameStatus::kValid) return std::move(found[ch]);
  }
  // Nothing held up anywhere: the best channel's account of why.
  return std::move(found[order.front()]);
}

}  // namespace clogscope::vision
