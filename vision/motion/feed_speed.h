#pragma once

// Feed speed of a filament from video frames: its surface texture (print marks, scratches, colour
// noise) travels along its axis. Both frames are sampled along the same axis (the earlier frame's
// geometry), the mean grey over the inner part of the width at every pixel step; the shift between
// the two profiles is found by normalised cross-correlation over whole pixels, then refined to a
// fraction of a pixel by Gauss–Newton on the interpolated profile. Along a video, each frame is
// compared with the one before it and, when the filament moves slowly, with an earlier one
// several px of movement back (a longer baseline).
#include <cmath>
#include <deque>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "vision/scene/strand_measure.h"

namespace clogscope::vision {

struct FeedSpeedOptions {
  double inner_fraction = 0.6;    // share of the width sampled, centred (keeps off the edges)
  double max_shift_px = 40;       // search range per frame pair
  double min_texture_ratio = 4;   // texture σ over the profile's noise σ
  double min_correlation = 0.6;   // normalised cross-correlation at the best whole-pixel shift
  double highpass_sigma_px = 25;  // slow illumination along the axis is removed at this scale
  // Profiles are smoothed at this scale before the shift (0: not at all): it takes out much of a
  // codec's block pattern and the interpolator's phase error, and some of a fine real texture
  // (1.5 px would suit blocky MJPEG better, but leaves Greeff's real video 2.6× noisier).
  double smooth_sigma_px = 1.0;
  // Along a video (FeedSpeedTracker), a frame is compared with the frame far enough back for the
  // texture to have moved baseline_shift_px (at most half the search range), at most
  // max_baseline_frames back; 0 px or 1 frame: always the frame before.
  double baseline_shift_px = 8;
  int max_baseline_frames = 16;
  bool Validate(std::string* why) const;
};

// The surface along the axis: values[i] at s = start_s_px + i (px from the measurement origin),
// each the mean over the inner width; noise is the estimated σ of one value.
struct AxisProfile {
  double start_s_px = 0;
  std::vector<double> values;
  double noise = 0;
};

// Samples `grey` (CV_8U or CV_16U, one channel) along the axis and inside the edges of `geometry`
// (a measurement with geometry, of this frame or a neighbour), from the start of its band to where
// the axis leaves the frame (the filament target's band is its whole straight stretch). Empty when
// fewer than 32 px can be sampled.
AxisProfile SampleAxisProfile(const cv::Mat& grey, const StrandMeasurement& geometry,
                              const FeedSpeedOptions& options);

enum class FeedShiftStatus { kValid, kNoTexture, kTooFast, kNoStrand };
const char* FeedShiftStatusName(
    FeedShiftStatus s);  // "valid", "no_texture", "too_fast", "no_strand"

struct AxisShift {
  FeedShiftStatus status = FeedShiftStatus::kNoStrand;
  std::string detail;
  double shift_px = 0;  // how far the surface moved down the axis (+s) from a to b
  double sigma_px = 0;  // from the residuals and the texture's gradient energy
  double correlation = 0;
  double texture_ratio = 0;
  int search_limit_px = 0;  // the shifts searched: ±this
  bool valid() const { return status == FeedShiftStatus::kValid; }
};

// A profile as EstimateAxisShift compares it: high-passed (the texture's σ taken there), then
// smoothed and cut to its inner part, 2 high-pass σ (at most a quarter of the profile) in from
// either end, where the high-pass saw its whole window. A frame's profile is prepared once however
// many frames it is compared with.
struct PreparedAxisProfile {
  double start_s_px = 0;
  size_t samples = 0;          // the profile's length before its ends were cut (0: empty)
  double noise = 0;            // the profile's
  double texture_sd_grey = 0;  // σ of the high-passed profile, grey levels
  std::vector<double> inner;
};
PreparedAxisProfile PrepareAxisProfile(const AxisProfile& p, const FeedSpeedOptions& options);

// The shift of profile b against profile a (same axis, same sampling), measured on their prepared
// inner parts. Expected failures come back as a status: no_texture (texture too weak for its
// noise), too_fast (a clear texture but no match inside the search range, or the best match on
// its limit).
AxisShift EstimateAxisShift(const PreparedAxisProfile& a, const PreparedAxisProfile& b,
                            const FeedSpeedOptions& options);
// The same for profiles not yet prepared.
AxisShift EstimateAxisShift(const AxisProfile& a, const AxisProfile& b,
                            const FeedSpeedOptions& options);

// Both frames sampled with `geometry` (normally the earlier frame's measurement), then the shift.
AxisShift EstimateFeedShift(const cv::Mat& grey_a, const cv::Mat& grey_b,
                            const StrandMeasurement& geometry, const FeedSpeedOptions& options);

// Why a frame has no speed, the filament's (FeedSpeedSample) or the gear's (GearSpeedSample).
enum class SpeedReason {
  kNone,        // it has one
  kFirstFrame,  // no frame before it
  kNoTime,      // still images have no frame times
  kBadTime,     // its time does not follow the frame before's
  kNoStrand,    // the filament: not measured in the frame before, or the frame unreadable
  kNoTexture,   // the filament: its texture too weak for its noise
  kTooFast,     // no match inside the search range
  kNoGear,      // the gear: its ROI off the frame, or nothing varies around its centre
};
// "none", "first_frame", "no_time", "bad_time", "no_strand", "no_texture", "too_fast", "no_gear".
const char* SpeedReasonName(SpeedReason reason);

// One frame's feed speed in px per second: the shift against an earlier frame over the time
// between them. The frame before decides whether there is a speed (and its reason when not); the
// speed itself comes from baseline_frames back when the tracker could look that far.
struct FeedSpeedSample {
  bool valid = false;
  SpeedReason reason = SpeedReason::kNone;  // when not valid: first_frame … too_fast
  std::string detail;
  double shift_px = 0, sigma_px = 0;
  double dt_s = 0;  // between the two frames' own timestamps
  int search_limit_px = 0;
  int baseline_frames = 0;         // how many frames back the frame compared with is (valid: ≥ 1)
  int wanted_baseline_frames = 0;  // how far back it should be for this speed (≥ baseline_frames)
  double SpeedPxPerS() const { return shift_px / dt_s; }
  double SigmaPxPerS() const { return sigma_px / dt_s; }
};

// Frame by frame along a video. Every frame is sampled once, along a reference geometry (a
// measurement) that is kept while the filament stays where it was (its centre line within 3 % of
// its width or 0.3 px, its width within 1 px), so the profiles compared always share their axis;
// when it moves, the previous frame is sampled again along the new reference and the earlier ones
// are forgotten. Each frame is compared with the one before (validity, the speed's size) and then,
// when the texture moves less than baseline_shift_px per frame, with the frame far enough back for
// that shift: a codec's artefacts that stay in place (its block grid) and the interpolator's error
// pull a fraction of a pixel per comparison, which the longer baseline divides by its frames.
// Frames of any supported type; colour is measured as grey.
class FeedSpeedTracker {
 public:
  explicit FeedSpeedTracker(const FeedSpeedOptions& options);
  // time_s: the frame's own timestamp (< 0: none, as for still images).
  FeedSpeedSample Next(const cv::Mat& frame, double time_s, const StrandMeasurement& m);

 private:
  FeedSpeedOptions options_;
  cv::Mat previous_;
  StrandMeasurement previous_m_;
  double previous_t_ = -1;
  StrandMeasurement reference_;  // has_geometry false: none yet
  struct PastFrame {
    PreparedAxisProfile profile;  // along reference_
    double time_s = 0;
  };
  std::deque<PastFrame> history_;    // the last frames along reference_, oldest first
  int baseline_frames_ = 0;          // the baseline the speed wants (0: none yet)
  double shift_per_frame_px_ = NAN;  // the last speed measured, px per frame

  // After a valid comparison with the frame before (its shift pair_shift_px): holds or renews the
  // baseline the speed wants and, where the history reaches that far back and the two agree,
  // measures `current` against that frame instead (out's shift, σ, dt and baseline).
  void CompareFurtherBack(const PreparedAxisProfile& current, double time_s, double pair_shift_px,
                          FeedSpeedSample* out);
};

}  // namespace clogscope::vision
