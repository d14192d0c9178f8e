#include "watch/watch_state.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "common/robust.h"
#include "pipeline/statistics.h"

namespace clogscope::watch {
namespace {

constexpr int kMinRecentFrames = 5;
constexpr int kMinBaselineFrames = 10;

// Keeps the time a condition began to hold; forgets it when the condition fails.
void Track(std::optional<double>* since, bool holds, double time_s) {
  if (!holds)
    since->reset();
  else if (!*since)
    *since = time_s;
}

bool Held(const std::optional<double>& since, double time_s, double hold_s) {
  return since && time_s - *since >= hold_s - 1e-9;
}

}  // namespace

const char* WatchLevelName(WatchLevel level) {
  switch (level) {
    case WatchLevel::kStarting:
      return "starting";
    case WatchLevel::kOk:
      return "ok";
    case WatchLevel::kWarn:
      return "warn";
    case WatchLevel::kClog:
      return "clog";
    case WatchLevel::kNotExtruding:
      return "not_extruding";
    case WatchLevel::kNoView:
      return "no_view";
  }
  return "?";
}

bool IsAlertLevel(WatchLevel level) {
  return level == WatchLevel::kWarn || level == WatchLevel::kClog ||
         level == WatchLevel::kNotExtruding || level == WatchLevel::kNoView;
}

// WatchStatus::changes_into is indexed by the enum's value: kWatchLevels must list it in order.
static_assert([] {
  for (size_t i = 0; i < std::size(kWatchLevels); ++i)
    if (static_cast<size_t>(kWatchLevels[i]) != i) return false;
  return true;
}());

bool WatchOptions::Validate(std::string* why) const {
  if (!(window_s >= 1 && window_s <= 3600))
    *why = fmt::format("--window-s {:g}: must be in [1, 3600] s", window_s);
  else if (!(alert_window_s >= 0.2 && alert_window_s <= window_s))
    *why = fmt::format("--alert-window-s {:g}: must be in [0.2 s, --window-s]", alert_window_s);
  else if (!(baseline_s >= 1 && baseline_s <= 3600))
    *why = fmt::format("--baseline-s {:g}: must be in [1, 3600] s", baseline_s);
  else if (baseline_um && !(*baseline_um > 0 && *baseline_um < 1e5))
    *why = fmt::format("--baseline-um {:g}: must be a positive diameter", *baseline_um);
  else if (!(warn_drift_pct < 0 && warn_drift_pct > -100))
    *why = fmt::format("--warn-pct {:g}: must be a narrowing, in (−100, 0) %", warn_drift_pct);
  else if (!(clog_drift_pct > -100 && clog_drift_pct < warn_drift_pct))
    *why = fmt::format("--clog-pct {:g}: must be below --warn-pct {:g} and above −100 %",
                       clog_drift_pct, warn_drift_pct);
  else if (!(hysteresis_pct >= 0 && hysteresis_pct < -warn_drift_pct))
    *why = fmt::format("--hysteresis-pct {:g}: must be in [0, {:g}) (less than |--warn-pct|)",
                       hysteresis_pct, -warn_drift_pct);
  else if (clog_drift_pct + hysteresis_pct >= warn_drift_pct)
    *why = fmt::format(
        "--hysteresis-pct {:g}: --clog-pct + hysteresis reaches --warn-pct (a clog could not be "
        "left for a warning)",
        hysteresis_pct);
  else if (!(hold_s >= 0 && hold_s <= 600))
    *why = fmt::format("--hold-s {:g}: must be in [0, 600] s", hold_s);
  else if (!(min_valid_fraction > 0 && min_valid_fraction < 1))
    *why = fmt::format("--min-valid-fraction {:g}: must be in (0, 1)", min_valid_fraction);
  else if (!(view_hysteresis >= 0 && min_valid_fraction + view_hysteresis <= 1))
    *why = fmt::format("view hysteresis {:g}: min valid fraction + it must not exceed 1",
                       view_hysteresis);
  else if (max_window_frames < 100)
    *why = "max window frames: at least 100";
  else
    return true;
  return false;
}

std::pair<double, double> WilsonInterval(int k, int n, double z) {
  if (n <= 0) return {0.0, 1.0};
  const double p = static_cast<double>(k) / n, z2 = z * z;
  const double centre = (p + z2 / (2.0 * n)) / (1 + z2 / n);
  const double half = z * std::sqrt(p * (1 - p) / n + z2 / (4.0 * n * n)) / (1 + z2 / n);
  return {std::max(0.0, centre - half), std::min(1.0, centre + half)};
}

double EffectiveSampleSize(const std::vector<double>& v) {
  const size_t n = v.size();
  if (n < 3) return static_cast<double>(n);
  double mean = 0;
  for (double x : v) mean += x;
  mean /= n;
  std::vector<double> d(n);
  double c0 = 0;
  for (size_t i = 0; i < n; ++i) {
    d[i] = v[i] - mean;
    c0 += d[i] * d[i];
  }
  if (!(c0 > 0)) return static_cast<double>(n);
  // Integrated autocorrelation time τ = 1 + 2 Σ ρ_k, summed over Geyer's initial positive
  // sequence: pairs ρ_2m + ρ_2m+1 while they stay positive (the noise beyond is not summed).
  const auto rho = [&](size_t k) {
    double ck = 0;
    for (size_t i = 0; i + k < n; ++i) ck += d[i] * d[i + k];
    return ck / c0;
  };
  double tau = 1 + 2 * rho(1);
  for (size_t m = 1; 2 * m + 1 < n / 2; ++m) {
    const double pair = rho(2 * m) + rho(2 * m + 1);
    if (pair <= 0) break;
    tau += 2 * pair;
  }
  return std::clamp(n / std::max(tau, 1.0), 2.0, static_cast<double>(n));
}

WatchState::WatchState(const WatchOptions& options,
                       std::optional<calib::ScaleCalibration> conversion)
    : options_(options), conversion_(std::move(conversion)) {
  std::string why;
  if (!options_.Validate(&why)) throw std::invalid_argument(why);
  if (options_.baseline_um && !conversion_)
    throw std::invalid_argument("--baseline-um needs a pixel scale (--scale-um-per-px or --calib)");
  status_.has_scale = conversion_.has_value();
  if (options_.baseline_um) {
    status_.baseline_ready = true;
    status_.baseline_source = "given";
    status_.baseline_um = *options_.baseline_um;
    status_.baseline_px =
        *options_.baseline_um / conversion_->scale_um_per_px + conversion_->edge_bias_px;
  }
}

double WatchState::ToUm(double px) const {
  return conversion_ ? (px - conversion_->edge_bias_px) * conversion_->scale_um_per_px : NAN;
}

WatchState::MeanCi WatchState::RobustMean(const std::vector<double>& widths_px) {
  MeanCi out;
  if (widths_px.size() < 2) return out;
  const double med = Median(widths_px);
  // MAD floored at 0.05 px: a steady strand's widths may agree far better than a frame's noise.
  const pipeline::SampleStats st =
      pipeline::RobustStats(widths_px, 3.5, std::max(0.05, 1e-3 * std::abs(med)));
  if (st.n_used < 2) return out;
  std::vector<double> used;
  used.reserve(st.n_used);
  for (size_t i = 0; i < widths_px.size(); ++i)
    if (st.used[i]) used.push_back(widths_px[i]);
  out.ok = true;
  out.mean_px = st.mean;
  out.std_px = st.std;
  out.n_used = st.n_used;
  out.n_rejected = st.n_rejected;
  out.n_eff = EffectiveSampleSize(used);
  const int dof = std::max(1, static_cast<int>(std::floor(out.n_eff)) - 1);
  out.half_px = pipeline::StudentT975(dof) * st.std / std::sqrt(out.n_eff);
  return out;
}

void WatchState::SetSourceUp(bool up, double time_s) {
  if (up == source_up_) return;
  source_up_ = up;
  if (last_time_s_ && time_s < *last_time_s_) time_s = *last_time_s_;
  if (!up) {
    // A source is declared down after it fell silent (a read timeout): it was down from its last
    // frame on, and that silence is the outage's, not frames the nozzle failed to show.
    down_since_s_ = last_frame_s_ ? std::min(*last_frame_s_, time_s) : time_s;
  } else if (down_since_s_) {
    down_spans_s_.emplace_back(*down_since_s_, time_s);
    down_since_s_.reset();
  }
}

double WatchState::DownSecondsWithin(double from_s, double to_s) const {
  const auto overlap = [&](double a, double b) {
    return std::max(0.0, std::min(b, to_s) - std::max(a, from_s));
  };
  double down_s = down_since_s_ ? overlap(*down_since_s_, to_s) : 0.0;
  for (const auto& [a, b] : down_spans_s_) down_s += overlap(a, b);
  return down_s;
}

bool WatchState::Add(double time_s, FrameView view, double width_px) {
  if (last_time_s_ && time_s < *last_time_s_) time_s = *last_time_s_;  // a clock step back
  SetSourceUp(true, time_s);
  if (!first_time_s_) first_time_s_ = time_s;  // the first frame: the watch has started
  last_frame_s_ = time_s;
  window_.push_back({time_s, view, width_px});
  if (view == FrameView::kStrand && !status_.baseline_ready) {
    if (baseline_first_s_ < 0) baseline_first_s_ = time_s;
    baseline_widths_px_.push_back(width_px);
    const bool long_enough = time_s - baseline_first_s_ >= options_.baseline_s &&
                             static_cast<int>(baseline_widths_px_.size()) >= kMinBaselineFrames;
    if (long_enough || static_cast<int>(baseline_widths_px_.size()) >= options_.max_window_frames) {
      const MeanCi b = RobustMean(baseline_widths_px_);
      if (b.ok) {
        status_.baseline_ready = true;
        status_.baseline_source = "measured";
        status_.baseline_px = b.mean_px;
        status_.baseline_um = ToUm(b.mean_px);
        status_.baseline_ci95_um = conversion_ ? b.half_px * conversion_->scale_um_per_px : NAN;
        status_.baseline_start_s = baseline_first_s_;
        baseline_half_px_ = b.half_px;
      }
      baseline_widths_px_.clear();
      baseline_widths_px_.shrink_to_fit();
    }
  }
  return Evaluate(time_s);
}

bool WatchState::Tick(double time_s) {
  if (last_time_s_ && time_s < *last_time_s_) time_s = *last_time_s_;
  return Evaluate(time_s);
}

void WatchState::UpdateStatistics(double t) {
  WatchStatus& s = status_;
  while (!window_.empty() && (window_.front().time_s < t - options_.window_s ||
                              static_cast<int>(window_.size()) > options_.max_window_frames))
    window_.pop_front();
  while (!down_spans_s_.empty() && down_spans_s_.front().second < t - options_.window_s)
    down_spans_s_.pop_front();
  s.time_s = t;
  s.source_up = first_time_s_.has_value() && source_up_;
  s.frames = static_cast<int>(window_.size());
  s.valid_frames = s.nozzle_only_frames = 0;
  std::vector<double> widths, recent, intervals;
  for (size_t i = 0; i < window_.size(); ++i) {
    const Sample& x = window_[i];
    if (i > 0) intervals.push_back(x.time_s - window_[i - 1].time_s);
    if (x.view == FrameView::kNozzleOnly) ++s.nozzle_only_frames;
    if (x.view != FrameView::kStrand) continue;
    ++s.valid_frames;
    widths.push_back(x.width_px);
    if (x.time_s >= t - options_.alert_window_s) recent.push_back(x.width_px);
  }
  if (intervals.size() >= 2) {
    const double dt = Median(intervals);
    if (dt > 0) rate_hz_ = 1.0 / dt;
  }
  s.frame_rate_hz = rate_hz_;
  // Frames the window should hold at the rate seen, so that frames that stop coming count as
  // frames without a strand (the window is shorter at the start of the watch). While the source
  // is down nothing is expected: that time says no_view through source_up alone, and a window that
  // expected frames of it would still count them missing long after the source is back.
  const double from_s = first_time_s_ ? std::max(t - options_.window_s, *first_time_s_) : t;
  const double up_s = std::max(0.0, t - from_s - DownSecondsWithin(from_s, t));
  expected_frames_ = std::max(static_cast<double>(s.frames), rate_hz_ * up_s);
  s.valid_fraction = expected_frames_ > 0 ? s.valid_frames / expected_frames_ : 0.0;

  const MeanCi w = RobustMean(widths);
  s.has_diameter = w.ok;
  if (w.ok) {
    s.diameter_px = w.mean_px;
    s.diameter_ci95_px = w.half_px;
    s.n_used = w.n_used;
    s.n_rejected = w.n_rejected;
    s.n_effective = w.n_eff;
    if (conversion_) {
      const calib::ScaleCalibration& c = *conversion_;
      const double cal_sigma_um = std::hypot((w.mean_px - c.edge_bias_px) * c.scale_sigma_um_per_px,
                                             c.scale_um_per_px * c.edge_bias_sigma_px);
      s.diameter_um = ToUm(w.mean_px);
      s.diameter_ci95_um = std::hypot(w.half_px * c.scale_um_per_px, kZ95 * cal_sigma_um);
      s.diameter_std_um = w.std_px * c.scale_um_per_px;
    }
  }
  const double bias = conversion_ ? conversion_->edge_bias_px : 0.0;
  const auto drift = [&](const MeanCi& m, double* pct, double* ci_pct) {
    const double d0 = status_.baseline_px - bias, d = m.mean_px - bias;
    *pct = 100 * (d / d0 - 1);
    *ci_pct = 100 * (d / d0) * std::hypot(m.half_px / d, baseline_half_px_ / d0);
  };
  if (s.baseline_ready && w.ok) {
    drift(w, &s.drift_pct, &s.drift_ci95_pct);
    s.drift_um = conversion_ ? s.diameter_um - s.baseline_um : NAN;
  }
  const MeanCi r =
      static_cast<int>(recent.size()) >= kMinRecentFrames ? RobustMean(recent) : MeanCi{};
  s.has_recent = r.ok && s.baseline_ready;
  if (s.has_recent) {
    s.recent_diameter_px = r.mean_px;
    s.recent_diameter_um = ToUm(r.mean_px);
    drift(r, &s.recent_drift_pct, &s.recent_drift_ci95_pct);
  }
}

WatchLevel WatchState::Decide(double t) {
  const WatchStatus& s = status_;
  const WatchOptions& o = options_;
  // The view: the valid fraction's Wilson interval against the threshold; frames that stop coming
  // count as frames without a strand (expected_frames_), a source that is down as no view at all.
  const int expected = static_cast<int>(std::lround(expected_frames_));
  const bool view_bad = !source_up_ || expected == 0 ||
                        WilsonInterval(s.valid_frames, expected).second < o.min_valid_fraction;
  // Not extruding needs the nozzle seen in most frames without a strand, frames missing included:
  // a window of strand frames and a silence is no evidence of a nozzle that stopped.
  const int without = std::max(expected, s.frames) - s.valid_frames;
  const bool nozzle_seen =
      source_up_ && s.nozzle_only_frames > 0 && 2 * s.nozzle_only_frames >= without;
  Track(&since_no_view_, view_bad && !nozzle_seen, t);
  Track(&since_not_extruding_, view_bad && nozzle_seen, t);
  Track(&since_view_back_,
        source_up_ && s.valid_fraction >= o.min_valid_fraction + o.view_hysteresis, t);
  // The drift: the whole CI of the alert window's mean past a threshold to enter; the mean back
  // above threshold + hysteresis to leave.
  const double hi = s.recent_drift_pct + s.recent_drift_ci95_pct;
  Track(&since_clog_, s.has_recent && hi < o.clog_drift_pct, t);
  Track(&since_warn_, s.has_recent && hi < o.warn_drift_pct, t);
  Track(&since_clog_exit_,
        s.has_recent && s.recent_drift_pct >= o.clog_drift_pct + o.hysteresis_pct, t);
  Track(&since_warn_exit_,
        s.has_recent && s.recent_drift_pct >= o.warn_drift_pct + o.hysteresis_pct, t);

  if (!first_time_s_) return WatchLevel::kStarting;
  const WatchLevel now = s.level;
  const double hold = o.hold_s;
  if (Held(since_no_view_, t, hold)) return WatchLevel::kNoView;
  if (Held(since_not_extruding_, t, hold)) return WatchLevel::kNotExtruding;
  if ((now == WatchLevel::kNoView || now == WatchLevel::kNotExtruding) &&
      !Held(since_view_back_, t, hold))
    return now;
  // A view that returns goes back to the drift level it left: the alert window is still filling,
  // and judging it afresh would pass through ok on the way back to a warn or clog.
  const WatchLevel drift = drift_level_;
  if (Held(since_clog_, t, hold)) return WatchLevel::kClog;
  if (drift == WatchLevel::kClog && !Held(since_clog_exit_, t, hold)) return WatchLevel::kClog;
  if (Held(since_warn_, t, hold)) return WatchLevel::kWarn;
  if ((drift == WatchLevel::kClog || drift == WatchLevel::kWarn) &&
      !Held(since_warn_exit_, t, hold))
    return WatchLevel::kWarn;
  return WatchLevel::kOk;
}

std::string WatchState::Reason() const {
  const WatchStatus& s = status_;
  const WatchOptions& o = options_;
  const std::string recent =
      s.has_recent ? fmt::format("drift {:+.2f} % ± {:.2f} % over the last {:g} s",
                                 s.recent_drift_pct, s.recent_drift_ci95_pct, o.alert_window_s)
                   : "";
  switch (s.level) {
    case WatchLevel::kStarting:
      return "waiting for the first frame";
    case WatchLevel::kNoView:
      if (!s.source_up) return "the source is down (reconnecting)";
      return fmt::format("a strand in {:.0f} % of the last {:g} s and the nozzle not recognised",
                         100 * s.valid_fraction, o.window_s);
    case WatchLevel::kNotExtruding:
      return fmt::format("a strand in {:.0f} % of the last {:g} s while the nozzle is in view",
                         100 * s.valid_fraction, o.window_s);
    case WatchLevel::kClog:
      return fmt::format("{}: past the clog threshold {:g} %", recent, o.clog_drift_pct);
    case WatchLevel::kWarn:
      return fmt::format("{}: past the warn threshold {:g} %", recent, o.warn_drift_pct);
    case WatchLevel::kOk:
      break;
  }
  if (!s.baseline_ready) {
    return baseline_first_s_ < 0 ? std::string("waiting for a strand to take the baseline")
                                 : fmt::format("taking the baseline ({:.1f} of {:g} s)",
                                               s.time_s - baseline_first_s_, o.baseline_s);
  }
  if (!s.has_recent)
    return "too few valid frames in the last " + fmt::format("{:g} s", o.alert_window_s);
  return fmt::format("{}: within the warn threshold {:g} %", recent, o.warn_drift_pct);
}

bool WatchState::Evaluate(double t) {
  last_time_s_ = t;
  UpdateStatistics(t);
  const WatchLevel next = Decide(t);
  // The first level is not a change: nothing that was known changed (no `level` line, no alert).
  const bool changed = next != status_.level && status_.level != WatchLevel::kStarting;
  if (next != status_.level) {
    status_.previous_level = status_.level;
    status_.level = next;
    status_.level_since_s = t;
    status_.level_changes += changed;
    status_.changes_into[static_cast<size_t>(next)] += changed;
  }
  if (next == WatchLevel::kOk || next == WatchLevel::kWarn || next == WatchLevel::kClog)
    drift_level_ = next;
  status_.reason = Reason();
  return changed;
}

}  // namespace clogscope::watch
