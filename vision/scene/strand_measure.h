#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "vision/edges/caliper.h"
#include "vision/edges/grey_image.h"
#include "vision/edges/polarity.h"
#include "vision/io/data_range.h"
#include "vision/scene/frame_status.h"

namespace clogscope::vision {

// How the strand is found and measured in one frame. Lengths are in px of the frame.
struct StrandMeasureOptions {
  cv::Rect roi;  // region to search; empty = whole frame
  Polarity polarity = Polarity::kAuto;
  // The measurement band, along the strand axis below the nozzle tip. Defaults are the reference
  // 50 µm and 150 µm at the nominal 3 µm/px.
  double band_start_px = 50.0 / 3.0;
  double band_height_px = 50.0;
  double caliper_spacing_px = 4.0;      // thickness of one caliper along the axis
  double min_contrast_fraction = 0.06;  // edge step below this fraction of full scale: low contrast
  double max_blur_px = 6.0;             // fitted PSF sigma above this: out of focus
  double max_tilt_deg = 45.0;           // strand axes leaning more than this are not strands
  // kStrand: the band starts band_start_px below the nozzle tip. kFilament (also pins, needles):
  // no tip; the band starts band_start_px below the top of the visible straight stretch and runs
  // band_height_px along it (at most to its end).
  MeasureTarget target = MeasureTarget::kStrand;
  double min_length_px = 30.0;  // shortest straight stretch of both edges that counts as a strand
  // Fit a lit cylinder's shading on the object side of each edge (edge_fit.h: FitShadedStep), so
  // a front-lit strand's silhouette is found rather than the 50 % level of its sloping plateau.
  bool shading = true;
  double min_caliper_fraction = 0.5;     // fewer consistent calipers than this: occluded
  double max_saturated_fraction = 0.05;  // more clipped pixels at the edges than this: saturated
  // Where the frames' black and white lie: kLimited for limited-range video luma (16 to 235), as
  // the source says of each frame (InputFrame::luma_range); clipping is looked for there.
  LumaRange luma_range = LumaRange::kFull;
  // A valid width is good to max(0.3 px, 0.5 %) at 3σ: a width whose σ (the calipers' spread and
  // the edge model's doubt) is above max(max_sigma_px, max_sigma_fraction·width) is `imprecise`.
  double max_sigma_px = 0.1;
  double max_sigma_fraction = 0.005 / 3;

  bool Validate(std::string* why) const;
};

// A target's default band at a pixel scale: a strand's 50 µm from the tip, 150 µm long (the
// reference experiment's); a filament's whole visible stretch.
struct BandPx {
  double start_px = 0;
  double height_px = 0;
};
inline constexpr double kWholeStretchPx = 1e6;  // band height meaning "as far as the stretch goes"
inline constexpr double kNominalScaleUmPerPx = 3.0;  // the reference camera's, when none is given
BandPx DefaultBand(MeasureTarget target, double scale_um_per_px);

// The least edge step a strand's edge may have, in the data's grey levels (data_max its full
// scale).
inline double MinContrastLevel(const StrandMeasureOptions& options, double data_max) {
  return options.min_contrast_fraction * data_max;
}

// What a width's σ is made of: each part a σ of width_px, both edges together, independent of the
// others: width_sigma_px is the root of the sum of their squares and of codec_sigma_px's,
// model_sigma_px that of all but the spread (CombineSigmas). (Shading and cylinder answer one
// question, where a lit side's silhouette lies, for sides judged plain and shaded respectively:
// at most one of them is set.)
struct WidthDoubt {
  double spread_px = 0;     // the calipers' scatter about their mean (or trend), or their fits' σ
  double shading_px = 0;    // a side judged plain would lie this much further out if shaded
  double cylinder_px = 0;   // the lit cylinders' disagreement with the per-edge fits, beyond blur
  double tip_px = 0;        // the band's start along the axis, where the width changes along it
  double structure_px = 0;  // the residual structure the calipers share at each edge
  double two_slope_px = 0;  // a background sloping to a flat object: the move it makes, or its σ
  double missing_px = 0;    // calipers left out of the mean of a width changing along the band
  double inner_level_px = 0;  // a flat object's level differing at its two edges: a step by one
  double edge_blur_px = 0;    // one edge blurred more than the other: a step folded into it
  double one_edge_px = 0;     // a width changing along the band as one edge alone drifts
};

// The result for one frame. Geometry is in full-frame pixel coordinates (ROI offset added).
struct StrandMeasurement {
  FrameStatus status = FrameStatus::kNoStrand;
  std::string detail;  // human-readable reason when not valid
  bool valid() const { return status == FrameStatus::kValid; }
  bool gave_width() const { return GivesWidth(status); }

  double width_px = 0;
  // Standard error of width_px: the calipers' spread, and the model's doubt (model_sigma_px).
  double width_sigma_px = 0;
  // The part no other frame of the scene would average out: from the edge model (shading, tip,
  // structure, a sloping background: doubt) and from the codec (codec_sigma_px).
  double model_sigma_px = 0;
  double codec_sigma_px = 0;  // how far a second pass through the stream's encoder moved the width
  WidthDoubt doubt;           // the other parts of width_sigma_px
  double angle_deg = 0;       // strand axis from image vertical, + leaning to +x going down
  double contrast = 0;        // median edge step, grey levels of the frame's bit depth
  double blur_px = 0;         // median PSF sigma, pixel footprint removed
  double tip_x_px = 0;  // nozzle tip on the axis (strand); top of the measured stretch (filament)
  double tip_y_px = 0;
  // Strand: the tip's doubt along the axis where the nozzle's face or the object's own end fixed
  // it (tip.h); −1 where only the followed edges did (the band's start is then doubted by a share
  // of the width).
  double tip_sigma_px = -1;
  Polarity polarity = Polarity::kAuto;
  int calipers_used = 0;
  int calipers_total = 0;

  // Measurement frame for overlays: origin at the tip, axis direction (down the strand), and the
  // fitted edge lines u = left_u0_px + edge_slope·s (right likewise) in that frame.
  bool has_geometry = false;
  bool shading_left = false, shading_right = false;  // each side fitted with the shading model
  double axis_dx = 0, axis_dy = 1;
  double band_start_px = 0, band_end_px = 0;
  double left_u0_px = 0, right_u0_px = 0, edge_slope = 0;
  // The part of the band the width comes from: all of it, but for a filament whose edges are
  // rough (knurl marks) over part of its stretch, its longest straight part (straight_run.h).
  double straight_start_px = 0, straight_end_px = 0;
  int rough_calipers = 0;  // filament: calipers whose edges are not straight
  // Strand: the widest width between the tip and the band over width_px (die swell; 1 when the
  // strand is no wider there).
  double swell_ratio = 1;
  std::vector<Caliper> calipers;
};

// Measures the strand width in one frame (8- or 16-bit; grey, BGR or BGRA; 16-bit frames holding
// 10- or 12-bit data are judged against their data range). The strand is found by its edges (see
// scene.h); a colour frame's strand is found in the channel with the best edge pair and measured
// in luma, or in that channel where luma cannot measure it. Expected failures
// come back as a status with a reason; throws std::invalid_argument for frames of another pixel
// type or options that do not validate.
StrandMeasurement MeasureStrand(const cv::Mat& frame, const StrandMeasureOptions& options);

struct StrandGeometry;
struct SceneOptions;
struct SceneResult;
class CylinderMemory;
// MeasureStrand that also hands back the scene it found (candidates, verdicts, chosen geometry)
// when scene_out is given: for tracking and for inspect.
StrandMeasurement FindAndMeasure(const cv::Mat& frame, const StrandMeasureOptions& options,
                                 SceneResult* scene_out);

// The second half of MeasureStrand: the band and calipers on a strand already found in `channel`
// (the ROI view the scene chose). A status other than kValid is passed through with its detail.
// Tracking calls it with the geometry of the last frame, and for a filament with the memory of its
// calipers' lit cylinders (cylinder_memory.h).
StrandMeasurement MeasureInScene(const cv::Mat& channel, double data_max, FrameStatus status,
                                 const std::string& detail, const StrandGeometry& geometry,
                                 const cv::Rect& roi, const StrandMeasureOptions& options,
                                 CylinderMemory* memory = nullptr);

// The ROI views the strand is looked for in: the grey frame, or a colour frame's luma and its B, G
// and R channels (an orange strand on a blue background may show no luma edge at all); and one of
// them by index.
std::vector<cv::Mat> SearchChannels(const cv::Mat& frame, const cv::Rect& roi);
cv::Mat SearchChannel(const cv::Mat& frame, const cv::Rect& roi, int index);

// The options' ROI, or the whole frame; throws std::invalid_argument when the options do not
// validate, the frame is empty or the ROI leaves it.
cv::Rect ResolveRoi(const cv::Mat& frame, const StrandMeasureOptions& options);

// The levels of data whose largest value is data_max (DataMax) in the given range (limited-range
// data deeper than 8 bits as the video decoder gives it, scaled to 16 bits).
DataLevels LevelsOf(double data_max, LumaRange range);

// Scene-finding options from the measurement options and the data's range.
SceneOptions SceneOptionsFor(const StrandMeasureOptions& options, double data_max);

// The largest σ the options let a valid width of width_px carry; a valid width whose σ is above
// it becomes kImprecise (JudgePrecision).
double MaxValidSigmaPx(const StrandMeasureOptions& options, double width_px);
void JudgePrecision(const StrandMeasureOptions& options, StrandMeasurement* m);

// Sets m's model_sigma_px (all parts of doubt but the spread, and codec_sigma_px) and
// width_sigma_px (all of them), each the root of the sum of their squares.
void CombineSigmas(StrandMeasurement* m);

// A measurement's σ in its parts (doubt and codec_sigma_px), largest first, each named for a user.
struct DoubtPart {
  const char* what;
  double sigma_px;
};
std::vector<DoubtPart> DoubtParts(const StrandMeasurement& m);

// Marks valid frames whose width is far from the median of the valid frames within ±half_window
// frames (robust: more than k·1.4826·MAD and more than min_deviation_px away) as kWidthOutlier.
// Returns how many it marked.
inline constexpr int kWidthOutlierHalfWindow = 25;  // frames either side a width is judged by
int FlagWidthOutliers(std::vector<StrandMeasurement>& frames,
                      int half_window = kWidthOutlierHalfWindow, double k = 6.0,
                      double min_deviation_px = 1.0);

}  // namespace clogscope::vision
