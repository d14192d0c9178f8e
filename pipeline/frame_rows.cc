#include "pipeline/frame_rows.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>
#include <filesystem>
#include <tuple>

#include "common/csv.h"
#include "common/robust.h"
#include "pipeline/statistics.h"

namespace clogscope::pipeline {

namespace fs = std::filesystem;

// "<video file name>_<frame>.png" or "<image stem>.png"; a suffix keeps names of this run unique.
std::string OverlayName(const FrameRow& r, bool from_video, std::set<std::string>* used) {
  const fs::path p(r.source);
  const std::string base =
      from_video ? fmt::format("{}_{:06d}", p.filename().string(), r.frame) : p.stem().string();
  std::string name = base + ".png";
  for (int k = 2; !used->insert(name).second; ++k) name = fmt::format("{}-{}.png", base, k);
  return name;
}

// "; width 139.570 ± 0.104 px per frame (mean ± 0.012 px, 95 %)[ = … µm]", from the valid
// frames after the steps' own outlier rejection; empty without valid frames.
std::string WidthSummary(const std::vector<FrameRow>& rows,
                         const std::optional<calib::ScaleCalibration>& conv) {
  FrameWidths frames;
  for (const FrameRow& r : rows) {
    if (!r.m.valid()) continue;
    frames.Add(r.m.width_px, r.m.width_sigma_px, r.m.model_sigma_px);
  }
  if (frames.width.empty()) return "";
  const WidthStats st = RobustWidthStats(frames);
  std::string out = fmt::format("; width {:.3f} ± {:.3f} px per frame (mean ± {:.3f} px, 95 %)",
                                st.mean, st.std, st.ci95_half_width);
  if (conv) out += fmt::format(" = {:.2f} µm", conv->ToMicrons(st.mean));
  if (st.n_rejected > 0)
    out +=
        fmt::format(", {} of {} widths left out as outliers", st.n_rejected, frames.width.size());
  if (st.frames_repeat) out += "; " + RepeatDetail(st);
  return out;
}

std::string StraightPartSummary(const std::vector<FrameRow>& rows) {
  int valid = 0, part = 0;
  std::vector<double> s0, s1;
  for (const FrameRow& r : rows) {
    if (!r.m.valid()) continue;
    ++valid;
    if (r.m.straight_start_px <= r.m.band_start_px && r.m.straight_end_px >= r.m.band_end_px)
      continue;
    ++part;
    s0.push_back(r.m.straight_start_px);
    s1.push_back(r.m.straight_end_px);
  }
  if (part == 0) return "";
  return fmt::format(
      "on {} of {} valid frames the filament's edges are rough (knurl or gear marks) along part "
      "of the stretch: the width is the straight part's, {:.0f}-{:.0f} px along it (median)",
      part, valid, Median(s0), Median(s1));
}

// The feed-speed columns of one row: mm/s, its σ (shift and scale), the reason when empty, the
// baseline, and whether the summary used it.
std::vector<std::string> SpeedFields(const vision::FeedSpeedSample& v,
                                     const FeedSpeedSummary& summary, size_t row,
                                     const calib::ScaleCalibration& conv) {
  const SpeedUse use = summary.use.at(row);
  const bool used = use == SpeedUse::kUsed;
  const std::string left_out = used ? "" : SpeedUseName(use);
  if (!v.valid) return {"", "", vision::SpeedReasonName(v.reason), "", "0", left_out};
  const double mm_per_px = conv.scale_um_per_px * 1e-3;
  const double speed = v.SpeedPxPerS() * mm_per_px;
  const double sigma = std::hypot(summary.RowSigmaPxPerS(v) * mm_per_px,
                                  speed * conv.scale_sigma_um_per_px / conv.scale_um_per_px);
  return {CsvNumber(speed, 5),
          CsvNumber(sigma, 5),
          "",
          std::to_string(v.baseline_frames),
          used ? "1" : "0",
          left_out};
}

GearAndSlip GearAndSlipOf(const FrameRow& r, const calib::ScaleCalibration& conv,
                          double radius_mm) {
  return vision::GearAndSlipOf(r.speed, r.gear, conv.scale_um_per_px * 1e-3, radius_mm);
}

// "; gear 2.00 ± 0.01 mm/s …; slip 10.0 ± 0.5 % per frame pair (mean ± …, 95 %), N of M pairs".
std::string GearSummary(const std::vector<FrameRow>& rows, const FeedSpeedSummary& speeds,
                        const calib::ScaleCalibration& conv, double radius_mm) {
  std::vector<double> gear, slip;
  for (size_t i = 0; i < rows.size(); ++i) {
    const GearAndSlip g = GearAndSlipOf(rows[i], conv, radius_mm);
    if (g.gear_mm_s) gear.push_back(*g.gear_mm_s);
    // A filament speed the feed summary leaves out (a short baseline, an outlier) leaves its
    // slip out too.
    if (g.slip_pct && speeds.use.at(i) == SpeedUse::kUsed) slip.push_back(*g.slip_pct);
  }
  std::string out;
  for (const auto& [name, unit, values] :
       {std::tuple{"gear surface speed", "mm/s", &gear}, std::tuple{"slip", "%", &slip}}) {
    if (values->empty()) {
      out += fmt::format("; {} in no frame pair", name);
      continue;
    }
    const SampleStats st = RobustStats(*values);
    out += fmt::format("; {} {:.4f} ± {:.4f} {} per frame pair (mean ± {:.4f}, 95 %), {} pairs",
                       name, st.mean, st.std, unit, st.ci95_half_width, values->size());
  }
  return out;
}

FeedSpeedSummary SummariseSpeeds(const std::vector<FrameRow>& rows) {
  std::vector<vision::FeedSpeedSample> samples;
  samples.reserve(rows.size());
  for (const FrameRow& r : rows) samples.push_back(r.speed);
  return SummariseFeedSpeeds(samples);
}

// "; feed speed 0.8001 ± 0.0102 mm/s per row (mean ± 0.0027 mm/s, 95 %), 45 of 60 pairs used (15
// with a short baseline), baselines up to 6 frames".
std::string SpeedSummary(const FeedSpeedSummary& s, const calib::ScaleCalibration& conv) {
  if (s.used == 0)
    return s.pairs ? fmt::format("; feed speed in none of {} frame pairs", s.pairs) : "";
  const double mm_per_px = conv.scale_um_per_px * 1e-3;
  std::vector<std::string> left_out;
  if (s.with_speed < s.pairs)
    left_out.push_back(fmt::format("{} without a speed", s.pairs - s.with_speed));
  if (s.short_baseline)
    left_out.push_back(fmt::format("{} with a short baseline", s.short_baseline));
  if (s.outliers)
    left_out.push_back(fmt::format("{} outlier{}", s.outliers, s.outliers == 1 ? "" : "s"));
  return fmt::format(
      "; feed speed {:.4f} ± {:.4f} mm/s per row (mean ± {:.4f} mm/s, 95 %), {} of {} pairs "
      "used{}, baselines up to {} frames",
      s.mean_px_per_s * mm_per_px, s.std_px_per_s * mm_per_px, s.ci95_px_per_s * mm_per_px, s.used,
      s.pairs, left_out.empty() ? "" : fmt::format(" ({})", fmt::join(left_out, ", ")),
      s.baseline_frames);
}

}  // namespace clogscope::pipeline
