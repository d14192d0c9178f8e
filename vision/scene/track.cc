#include "vision/scene/track.h"

#include <cmath>
#include <stdexcept>

#include "vision/edges/straight_run.h"

namespace clogscope::vision {
namespace {
constexpr double kTipHysteresisPx = 1.5;  // tip moves smaller than this keep the band in place
// A filament's straight part shorter than this many of its fewest calipers is short: a gear mark
// or a speck split what was straight, and the part kept (FindStraightRun keeps it where it was),
// however long it stays, may lie beside the mark. The whole stretch is looked at again, in full,
// for a longer part in the second frame in a row the part is short, then ever more rarely while
// it stays short (its 4th, 8th … frame), and at least every kRegrowAtMostFrames frames. (Greeff's
// real video: a part of 10 calipers, kept 20 frames, read 137.38–137.49 px where the 17 found
// again then read 137.65, and 4 of 281 widths were left out as outliers; with the looks, none
// (3 once the looks from templates brought the frame-to-frame σ to 0.046 px: the same few frames
// then stand further out).
// Looking from the first short frame: 7 looks in 281 frames, each then measured in full at the
// cost of a few dozen tracked frames; from the second: 4, the video measured 1.26 times as fast,
// and its widths' frame-to-frame σ 0.066 px instead of 0.062. A look from the templates a look
// taken before left costs about a tenth of one in full.)
constexpr int kShortStraightPartTimes = 2;
constexpr int kRegrowAtMostFrames = 32;
constexpr int kFirstLookFrame = 2;

// True when a filament's width came from (part of) the straight part measured before, as
// FindStraightRun keeps it while it has enough straight calipers.
bool KeptStraightPart(const StrandMeasurement& m, const StrandGeometry& before, double spacing_px) {
  constexpr double kSlackPx = 0.5;
  return m.valid() && m.straight_start_px >= before.straight_s0_px - kSlackPx &&
         m.straight_end_px <= before.straight_s1_px + kSlackPx &&
         m.straight_end_px - m.straight_start_px >=
             StraightRunOptions{}.min_kept_calipers * spacing_px - kSlackPx;
}

// The calipers of a filament's straight part.
int StraightCalipers(const StrandMeasurement& m, double spacing_px) {
  return static_cast<int>(std::lround((m.straight_end_px - m.straight_start_px) / spacing_px));
}
}  // namespace

StrandTracker::StrandTracker(const StrandMeasureOptions& options) : options_(options) {
  std::string why;
  if (!options_.Validate(&why)) throw std::invalid_argument("measure options: " + why);
}

void StrandTracker::SetEncoder(const X264Settings& encoder) {
  codec_.reset();
  if (encoder.found && X264RoundTrip::Available()) codec_.emplace(encoder);
}

StrandMeasurement StrandTracker::Measure(const cv::Mat& frame) {
  StrandMeasurement m;
  if (tracking_ && Follow(frame, &m))
    ++tracked_frames_;
  else
    m = Detect(frame);
  if (codec_) codec_->Apply(frame, options_, &m);
  return m;
}

StrandMeasurement StrandTracker::Measure(const InputFrame& frame) {
  options_.luma_range = frame.luma_range;
  return Measure(frame.image);
}

StrandMeasurement StrandTracker::Detect(const cv::Mat& frame) {
  ++full_detections_;
  cylinders_.Clear();  // perhaps another scene, or another channel of it
  short_straight_frames_ = 0;
  SceneResult scene;
  StrandMeasurement m = FindAndMeasure(frame, options_, &scene);
  // (A channel that carries luma's doubt is not followed alone: Follow measures one channel.)
  if (scene.channel_doubts_luma)
    tracking_ = false;
  else if (m.valid())
    Remember(scene, m, frame.size());
  return m;
}

bool StrandTracker::Follow(const cv::Mat& frame, StrandMeasurement* out) {
  const cv::Rect roi = ResolveRoi(frame, options_);
  if (frame.size() != frame_size_) return false;
  const cv::Mat channel = SearchChannel(frame, roi, scene_.measured_channel);
  const double data_max = DataMax(frame(roi));
  StrandGeometry g = scene_.geometry;
  if (options_.target == MeasureTarget::kStrand) {
    // The tip is found again along the fitted edges (cheap walks); small moves are noise and keep
    // the band where it was.
    PairCandidate c;
    c.axis = g.axis;
    c.left_u0 = g.left_u0;
    c.right_u0 = g.right_u0;
    c.edge_slope = g.edge_slope;
    c.width_px = g.width_px;
    c.polarity = g.polarity;
    c.score = g.score;
    c.length_px = std::max(options_.min_length_px,
                           std::min(g.s_end, options_.band_start_px + options_.band_height_px));
    const GreyImage img{channel, channel.depth() == CV_16U};
    StrandGeometry now;
    PairVerdict failure;
    std::string why;
    if (!FollowPair(img, SceneOptionsFor(options_, data_max), c, g.left_sign, g.right_sign, &now,
                    &failure, &why)) {
      return false;
    }
    const double tip_shift = g.axis.S(now.axis.ox, now.axis.oy);
    // The tip's doubt and what showed there go with the tip (tip.h).
    const auto take_tip = [&] {
      g.tip_sigma_px = now.tip_sigma_px;
      g.tip_face_sides = now.tip_face_sides;
      g.tip_face_step = now.tip_face_step;
      g.tip_width_px = now.tip_width_px;
    };
    if (std::abs(tip_shift) > kTipHysteresisPx) {
      g.axis = now.axis;
      g.left_u0 = now.left_u0;
      g.right_u0 = now.right_u0;
      g.s_end = now.s_end;
      take_tip();
    } else if (std::abs(now.s_end + tip_shift - g.s_end) > kTipHysteresisPx) {
      g.s_end = now.s_end + tip_shift;
      take_tip();
    }
  }
  CylinderMemory* cylinders = options_.target == MeasureTarget::kFilament ? &cylinders_ : nullptr;
  StrandMeasurement m =
      MeasureInScene(channel, data_max, FrameStatus::kValid, "", g, roi, options_, cylinders);
  if (options_.target == MeasureTarget::kFilament && g.straight_s1_px > g.straight_s0_px &&
      !KeptStraightPart(m, g, options_.caliper_spacing_px)) {
    // A filament is measured on its last straight part only (MeasureInScene); when that part no
    // longer holds, the whole stretch is looked at for the longest straight part again.
    g.straight_s0_px = g.straight_s1_px = 0;
    m = MeasureInScene(channel, data_max, FrameStatus::kValid, "", g, roi, options_, cylinders);
    short_straight_frames_ = 0;
  } else if (options_.target == MeasureTarget::kFilament && g.straight_s1_px > g.straight_s0_px) {
    const double spacing = options_.caliper_spacing_px;
    const bool short_part = StraightCalipers(m, spacing) <
                            kShortStraightPartTimes * StraightRunOptions{}.min_kept_calipers;
    short_straight_frames_ = short_part ? short_straight_frames_ + 1 : 0;
    const int n = short_straight_frames_;
    if (short_part && n >= kFirstLookFrame &&
        ((n & (n - 1)) == 0 || n % kRegrowAtMostFrames == 0)) {
      // Perhaps straight again beyond it: the whole stretch's longest straight part, if longer.
      // Into a copy of the memory, every rest ended (a caliper beside a gear mark may have
      // straightened): each caliper from its template where it holds (a look taken before left
      // templates for the whole stretch), in full where it refuses or has none (on slabs about
      // the memory's edge lines, as when the part no longer holds, above), and the whole stretch
      // measured in full when more than a few refuse (calipers.cc). Taken, its templates replace
      // the part's; not taken, the part's templates, lines and doubt stay.
      StrandGeometry whole = g;
      whole.straight_s0_px = whole.straight_s1_px = 0;
      CylinderMemory look = cylinders_;
      look.Wake();
      StrandMeasurement w =
          MeasureInScene(channel, data_max, FrameStatus::kValid, "", whole, roi, options_, &look);
      if (w.valid() && StraightCalipers(w, spacing) > StraightCalipers(m, spacing)) {
        m = std::move(w);
        look.frames_from_templates = cylinders_.frames_from_templates;
        cylinders_ = std::move(look);
      }
    }
  }
  // A frame that does not measure like the last one is looked at afresh.
  if (!m.valid() || std::abs(m.width_px - width_px_) > std::max(2.0, 0.03 * width_px_))
    return false;
  scene_.geometry = g;
  Remember(scene_, m, frame.size());
  *out = std::move(m);
  return true;
}

void StrandTracker::Remember(const SceneResult& scene, const StrandMeasurement& m,
                             cv::Size frame_size) {
  if (&scene != &scene_) scene_ = scene;
  // The next frame starts from this one's fitted edges, in the same axis frame.
  StrandGeometry& g = scene_.geometry;
  g.left_u0 = m.left_u0_px;
  g.right_u0 = m.right_u0_px;
  g.edge_slope = m.edge_slope;
  g.width_px = m.width_px;
  g.precise = true;
  g.shading_left = m.shading_left ? 1 : 0;
  g.shading_right = m.shading_right ? 1 : 0;
  g.straight_s0_px = m.straight_start_px;
  g.straight_s1_px = m.straight_end_px;
  width_px_ = m.width_px;
  frame_size_ = frame_size;
  tracking_ = true;
}

}  // namespace clogscope::vision
