#pragma once

#include <array>
#include <cmath>
#include <deque>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

#include "calib/pixel_scale.h"
#include "common/robust.h"

namespace clogscope::watch {

// What a live watch says about the nozzle.
enum class WatchLevel {
  kStarting,  // no frame yet (the source is opening or has not delivered): nothing is known
  kOk,        // the strand is seen and its diameter holds (or the baseline is still being taken)
  kWarn,      // the diameter has fallen past the warn threshold
  kClog,      // past the clog threshold
  kNotExtruding,  // the nozzle is in view but no strand leaves it
  kNoView,        // nothing recognisable (covered, moved, dark) or no frames (source down)
};
const char* WatchLevelName(WatchLevel level);
// Every level, in the order above (for the outputs that list them all).
inline constexpr WatchLevel kWatchLevels[] = {WatchLevel::kStarting,     WatchLevel::kOk,
                                              WatchLevel::kWarn,         WatchLevel::kClog,
                                              WatchLevel::kNotExtruding, WatchLevel::kNoView};
// True for the levels that ask for attention: warn, clog, not_extruding, no_view.
bool IsAlertLevel(WatchLevel level);

// What one frame showed.
enum class FrameView {
  kStrand,      // a valid width
  kNozzleOnly,  // no width, but the nozzle seen before is still in view
  kNothing,     // no width and nothing recognisable (or an unreadable frame)
};

struct WatchOptions {
  double window_s = 10;       // rolling statistics: the last window_s seconds
  double alert_window_s = 2;  // the alert levels test the mean drift of the last alert_window_s
  double baseline_s = 10;     // the baseline: the first baseline_s seconds of valid frames
  std::optional<double> baseline_um;  // or given (needs a scale); then it has no uncertainty
  double warn_drift_pct = -2;  // reference experiment: −0.8 % at the first cooling step, −2.5 % at
  double clog_drift_pct = -5;   // the second, −4.7 % at the third, −8.5 % at the fourth
  double hysteresis_pct = 0.5;  // a drift level is left when its mean is this far back above it
  double hold_s = 2;            // a level is entered (and left) when its condition held this long
  double min_valid_fraction = 0.5;  // valid frames in the window: below, not_extruding or no_view
  double view_hysteresis = 0.1;     // …which are left when the fraction is this much above it
  int max_window_frames = 20000;    // memory bound on the window (800 frames/s over 25 s)
  bool Validate(std::string* why) const;  // names the option (--warn-pct, --hold-s, …)
};

// The rolling state after the latest frame (or tick).
struct WatchStatus {
  double time_s = 0;
  WatchLevel level = WatchLevel::kStarting;
  WatchLevel previous_level = WatchLevel::kStarting;
  double level_since_s = 0;
  int level_changes = 0;  // leaving kStarting is not one (nothing changed that was known)
  // The changes into each level, indexed by its enum value (kWatchLevels' order); those into an
  // alert level (IsAlertLevel) are the alerts, a return to ok is none.
  std::array<int, std::size(kWatchLevels)> changes_into{};
  std::string reason = "waiting for the first frame";  // why the watch is at this level
  bool source_up = false;  // false until the first frame, and while the source is down

  // Frames in the window.
  int frames = 0, valid_frames = 0, nozzle_only_frames = 0;
  double valid_fraction = 0;  // of the frames expected in the window (missing frames count)
  double frame_rate_hz = 0;   // frames arriving per second (median interval)

  // Mean effective diameter over the window's valid frames after robust outlier rejection. Its
  // 95 % CI has the frame-to-frame spread (t · s/√n_eff, n_eff from the autocorrelation time)
  // and the calibration's σ in quadrature. µm fields need a scale (has_scale): NaN until known,
  // and always without a scale (null in JSON, empty in CSV, absent from the metrics).
  bool has_diameter = false;
  bool has_scale = false;
  double diameter_px = 0;
  double diameter_ci95_px = 0;  // the frame-to-frame spread's alone (the scale's σ is in µm)
  double diameter_um = NAN;
  double diameter_ci95_um = NAN;
  double diameter_std_um = NAN;  // frame-to-frame
  int n_used = 0, n_rejected = 0;
  double n_effective = 0;

  // Baseline and drift. The drift's CI has both means' spread but not the scale's σ, which
  // cancels in the ratio.
  bool baseline_ready = false;
  std::string baseline_source;  // "measured" or "given"
  double baseline_px = 0, baseline_um = NAN, baseline_ci95_um = NAN;
  double baseline_start_s = 0;
  double drift_um = NAN, drift_pct = 0, drift_ci95_pct = 0;  // window
  bool has_recent = false;
  double recent_diameter_um = NAN, recent_drift_pct = 0, recent_drift_ci95_pct = 0;  // alert window
  double recent_diameter_px = 0;
};

// Rolling statistics and alert levels of a live watch: a pure state machine fed with one sample per
// frame, in time order, and ticks while no frames arrive. It is kStarting until the first frame,
// which sets the first level without counting a change. A level is entered only when its
// condition held for hold_s: for warn and clog, the whole 95 % CI of the alert window's drift is
// past the threshold; for not_extruding and no_view, the upper bound of the valid fraction's Wilson
// interval is below min_valid_fraction (or the source is down). A drift level is left when the
// alert window's mean drift has been back above threshold + hysteresis for hold_s; a view level
// when the valid fraction has been above min + view_hysteresis for hold_s, back to the drift level
// it left (ok, warn or clog). Frames missing while the source is up count as frames without a
// view, never as nozzle-only ones; the time the source is down (from its last frame to its return)
// is no part of the frames the window expects.
class WatchState {
 public:
  // conversion: widths in px to µm ((w − b)·s with its σ); nullopt: px only (no µm fields, and a
  // given baseline is refused). Throws std::invalid_argument when the options do not validate.
  WatchState(const WatchOptions& options, std::optional<calib::ScaleCalibration> conversion);

  // One frame. Returns true when the level changed.
  bool Add(double time_s, FrameView view, double width_px = 0);
  // No frame: time passes (ages the window, lets held conditions mature). Returns true when the
  // level changed.
  bool Tick(double time_s);
  // The source is down (reconnecting) or back, at time_s. A frame (Add) says it is up.
  void SetSourceUp(bool up, double time_s);

  const WatchStatus& status() const { return status_; }
  const WatchOptions& options() const { return options_; }

 private:
  struct Sample {
    double time_s;
    FrameView view;
    double width_px;
  };
  struct MeanCi {
    bool ok = false;
    double mean_px = 0, half_px = 0, std_px = 0, n_eff = 0;
    int n_used = 0, n_rejected = 0;
  };
  static MeanCi RobustMean(const std::vector<double>& widths_px);
  bool Evaluate(double time_s);
  void UpdateStatistics(double time_s);
  WatchLevel Decide(double time_s);
  std::string Reason() const;
  double ToUm(double px) const;
  double DownSecondsWithin(double from_s, double to_s) const;

  WatchOptions options_;
  std::optional<calib::ScaleCalibration> conversion_;
  std::deque<Sample> window_;
  std::vector<double> baseline_widths_px_;
  double baseline_first_s_ = -1;
  double baseline_half_px_ = 0;  // the baseline mean's 95 % half-width (0 when given)
  bool source_up_ = true;
  std::optional<double> down_since_s_;                  // the source is down since (its last frame)
  std::deque<std::pair<double, double>> down_spans_s_;  // outages ended, within the window
  WatchLevel drift_level_ = WatchLevel::kOk;  // the last of ok, warn, clog: where a view returns
  std::optional<double> last_time_s_, last_frame_s_;
  std::optional<double> first_time_s_;  // the first frame's; none: still starting
  double rate_hz_ = 0;                  // frame rate seen (kept while frames stop coming)
  double expected_frames_ = 0;          // frames the window should hold at that rate
  // When each condition began to hold continuously (nullopt: it does not hold now).
  std::optional<double> since_no_view_, since_not_extruding_, since_clog_, since_warn_;
  std::optional<double> since_view_back_, since_clog_exit_, since_warn_exit_;
  WatchStatus status_;
};

// Wilson score interval of a proportion k/n at z (1.96 for 95 %): {lower, upper}; {0, 1} for n = 0.
std::pair<double, double> WilsonInterval(int k, int n, double z = kZ95);

// n/τ with τ the integrated autocorrelation time of the values (Sokal's automatic window), at
// least 2 and at most n: how many independent samples a correlated series is worth for its mean.
double EffectiveSampleSize(const std::vector<double>& values);

}  // namespace clogscope::watch
