#include "pipeline/feedstock.h"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "pipeline/experiment.h"
#include "pipeline/statistics.h"
#include "vision/io/frame_source.h"
#include "vision/motion/feed_speed.h"
#include "vision/scene/track.h"

namespace clogscope::pipeline {
namespace {

// Mean and 95 % half-width of values after robust outlier rejection.
void MeanAndCi(const std::vector<double>& v, std::optional<double>* mean,
               std::optional<double>* ci95) {
  if (v.empty()) return;
  const SampleStats st = RobustStats(v);
  *mean = st.mean;
  if (st.n_used >= 2) *ci95 = st.ci95_half_width;
}

}  // namespace

const char* FeedstockStatusName(FeedstockStatus status) {
  switch (status) {
    case FeedstockStatus::kOk:
      return "ok";
    case FeedstockStatus::kTooFewPairs:
      return "too_few_pairs";
    case FeedstockStatus::kFailed:
      return "failed";
  }
  return "?";
}

FeedstockStatus ParseFeedstockStatus(const std::string& name) {
  for (FeedstockStatus s :
       {FeedstockStatus::kOk, FeedstockStatus::kTooFewPairs, FeedstockStatus::kFailed}) {
    if (name == FeedstockStatusName(s)) return s;
  }
  throw std::invalid_argument("unknown feedstock status '" + name + "'");
}

bool FeedstockOptions::Validate(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (pairs < 1) return fail("feedstock pairs must be at least 1");
  if (strand.target != vision::MeasureTarget::kFilament)
    return fail("feedstock is measured as a filament (target filament)");
  if (!strand.Validate(why)) return false;
  if (gear) {
    if (!gear->Validate(why)) return false;
    if (!(gear_radius_mm > 0)) return fail("feedstock gear: gear_radius_mm must be positive");
    if (!conversion) return fail("feedstock gear: needs a pixel scale (its radius is in mm)");
  }
  return true;
}

FeedstockResult MeasureFeedstock(const std::string& video, double start_s, double end_s,
                                 const FeedstockOptions& o) {
  const std::optional<calib::ScaleCalibration>& conversion = o.conversion;
  FeedstockResult r;
  r.video = video;
  std::string why;
  if (!o.Validate(&why)) throw std::invalid_argument(why);
  std::unique_ptr<vision::FrameSource> dec;
  try {
    vision::VideoReadOptions vo;
    vo.decoder_threads = 1;
    vo.gap_entries = false;  // pairs of frames decoded
    dec = vision::FrameSource::OpenVideo(video, vo);
  } catch (const std::invalid_argument& e) {
    r.status = FeedstockStatus::kFailed;
    r.detail = e.what();
    return r;
  }
  const double a = start_s;
  const double b = end_s >= 0 && (dec->duration_s() <= 0 || end_s < dec->duration_s())
                       ? end_s
                       : dec->duration_s();
  if (!(b > a)) {
    r.status = FeedstockStatus::kFailed;
    r.detail = fmt::format("{}: nothing between {:g} s and {:g} s", video, a, b);
    return r;
  }
  const double slot = (b - a) / o.pairs;
  const double mm_per_px = conversion ? conversion->scale_um_per_px * 1e-3 : 0.0;
  vision::StrandTracker strand(o.strand);
  strand.SetEncoder(dec->encoder());
  FrameWidths widths;
  std::vector<double> speeds, gears, slips;
  if (a > vision::kSeekAheadS) dec->SeekToTime(a);
  vision::InputFrame f;
  f.time_s = 0;  // before the first frame: the stream's start
  for (int k = 0; k < o.pairs; ++k) {
    const double target = a + (k + 0.5) * slot;
    // Fresh speed trackers for each pair: the frame before a seek is no neighbour.
    vision::FeedSpeedTracker feed{vision::FeedSpeedOptions{}};
    std::optional<vision::GearSpeedTracker> gear;
    if (o.gear) gear.emplace(*o.gear);
    bool have_target = false;
    int in_pair = 0;
    while (in_pair < 2) {
      if (!have_target && target - f.time_s > vision::kSeekAheadS) dec->SeekToTime(target);
      have_target = true;
      if (!dec->Next(&f)) break;
      if (f.time_s < target - 1e-9 && in_pair == 0) continue;
      if (in_pair == 0 && f.time_s >= b - 1e-9) break;  // the step's part is over
      const vision::StrandMeasurement m = strand.Measure(f);
      if (in_pair == 0) {
        ++r.n_pairs;
        if (m.valid()) widths.Add(m.width_px, m.width_sigma_px, m.model_sigma_px);
      }
      const vision::FeedSpeedSample v = feed.Next(f.image, f.time_s, m);
      vision::GearSpeedSample g;
      if (gear) g = gear->Next(f.image, f.time_s);
      if (in_pair == 1 && conversion) {
        if (v.valid) speeds.push_back(v.SpeedPxPerS() * mm_per_px);
        const vision::GearAndSlip gs = vision::GearAndSlipOf(v, g, mm_per_px, o.gear_radius_mm);
        if (gs.gear_mm_s) gears.push_back(*gs.gear_mm_s);
        if (gs.slip_pct) slips.push_back(*gs.slip_pct);
      }
      ++in_pair;
    }
    if (in_pair < 2) break;  // the video or the step's part ended
  }
  r.n_diameter = static_cast<int>(widths.width.size());
  r.n_speed = static_cast<int>(speeds.size());
  r.n_gear = static_cast<int>(gears.size());
  r.n_slip = static_cast<int>(slips.size());
  if (widths.width.empty()) {
    r.status = FeedstockStatus::kFailed;
    r.detail = fmt::format("{}: no valid filament width in {} frame pairs", video, r.n_pairs);
    return r;
  }
  const WidthStats st = RobustWidthStats(widths);
  r.diameter_px = st.mean;
  r.diameter_std_px = st.std;
  if (conversion) {
    const calib::ScaleCalibration& c = *conversion;
    r.has_um = true;
    r.diameter_um = c.ToMicrons(st.mean);
    double cal_sigma_um = 0;
    r.diameter_ci95_um = MeanCi95Um(st, c, &cal_sigma_um);
  }
  MeanAndCi(speeds, &r.speed_mm_s, &r.speed_ci95_mm_s);
  MeanAndCi(gears, &r.gear_mm_s, &r.gear_ci95_mm_s);
  MeanAndCi(slips, &r.slip_pct, &r.slip_ci95_pct);
  r.status = r.n_diameter >= o.pairs ? FeedstockStatus::kOk : FeedstockStatus::kTooFewPairs;
  if (r.status != FeedstockStatus::kOk) {
    r.detail = fmt::format("{} valid filament widths of {} pairs asked ({} examined)", r.n_diameter,
                           o.pairs, r.n_pairs);
  }
  return r;
}

}  // namespace clogscope::pipeline
