#include "vision/scene/strand_measure.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "common/angle.h"
#include "common/robust.h"
#include "vision/scene/calipers.h"
#include "vision/scene/scene.h"
#include "vision/scene/self_check.h"

namespace clogscope::vision {
namespace {
constexpr size_t kMaxFallbacks = 2;             // runner-up pairs measured after the chosen one
constexpr double kMinFallbackScoreRatio = 0.5;  // of the chosen pair's score
// A second guess must be clearly strand-like: weak short pairs are what clutter makes.
constexpr double kMinFallbackScoreFactor = 3.0;    // times the scene's minimum score
constexpr double kStraightPartMarginCalipers = 6;  // tracking a filament: calipers beside its part
// A colour channel's edges this much blurrier than luma's: half-resolution chroma mixed in.
constexpr double kChromaBlurRatio = 1.15;

// Statuses of one channel's measurement that another channel of the same pair may not share:
// its noise, its blur, its sampling. Not those by which the calipers refuse the pair
// (RejectsPair): luma must not bring back a pair judged not to be the strand.
bool LumaMayMeasure(FrameStatus s) {
  return s == FrameStatus::kValid || s == FrameStatus::kImprecise;
}

// The parts of a width's doubt about the edge model and the scene (all of WidthDoubt's but the
// calipers' spread, a channel's own noise), each named for a user.
struct NamedDoubtPart {
  const char* what;
  double WidthDoubt::*part;
};
constexpr NamedDoubtPart kModelDoubtParts[] = {
    {"shading too weak to decide", &WidthDoubt::shading_px},
    {"the lit cylinders against the per-edge fits", &WidthDoubt::cylinder_px},
    {"the tip's place along a changing width", &WidthDoubt::tip_px},
    {"residual structure the calipers share", &WidthDoubt::structure_px},
    {"a background sloping to the edge", &WidthDoubt::two_slope_px},
    {"calipers missing from a changing width", &WidthDoubt::missing_px},
    {"the object's level differing at its two edges", &WidthDoubt::inner_level_px},
    {"one edge blurred more than the other", &WidthDoubt::edge_blur_px},
    {"one edge drifting off the strand's axis", &WidthDoubt::one_edge_px}};

// Each model part of `from`'s doubt where larger than *to's.
void TakeLargerModelDoubt(const WidthDoubt& from, WidthDoubt* to) {
  for (const NamedDoubtPart& p : kModelDoubtParts)
    to->*p.part = std::max(to->*p.part, from.*p.part);
}

// Statuses that say the pair was not the strand, rather than that the frame is poor.
bool RejectsPair(FrameStatus s) {
  return s == FrameStatus::kNoStrand || s == FrameStatus::kOccluded ||
         s == FrameStatus::kTouchesBorder || s == FrameStatus::kBandOutsideFrame;
}
}  // namespace

std::vector<cv::Mat> SearchChannels(const cv::Mat& frame, const cv::Rect& roi) {
  if (frame.depth() != CV_8U && frame.depth() != CV_16U) {
    throw std::invalid_argument("frame: unsupported pixel depth (need 8- or 16-bit integer)");
  }
  const cv::Mat view = frame(roi);
  if (frame.channels() == 1) return {view};
  if (frame.channels() != 3 && frame.channels() != 4) {
    throw std::invalid_argument(
        fmt::format("frame: unsupported channel count {} (need 1, 3 or 4)", frame.channels()));
  }
  std::vector<cv::Mat> out(1);
  cv::cvtColor(view, out[0], frame.channels() == 3 ? cv::COLOR_BGR2GRAY : cv::COLOR_BGRA2GRAY);
  std::vector<cv::Mat> planes;
  cv::split(view, planes);
  for (int c = 0; c < 3; ++c) out.push_back(planes[c]);
  return out;
}

cv::Mat SearchChannel(const cv::Mat& frame, const cv::Rect& roi, int index) {
  if (frame.channels() == 1) return frame(roi);
  cv::Mat out;
  if (index == 0) {  // luma alone: no need to split the other three
    cv::cvtColor(frame(roi), out, frame.channels() == 3 ? cv::COLOR_BGR2GRAY : cv::COLOR_BGRA2GRAY);
    return out;
  }
  cv::extractChannel(frame(roi), out, index - 1);
  return out;
}

cv::Rect ResolveRoi(const cv::Mat& frame, const StrandMeasureOptions& opt) {
  std::string why;
  if (!opt.Validate(&why)) throw std::invalid_argument("measure options: " + why);
  if (frame.empty()) throw std::invalid_argument("frame: empty image");
  const cv::Rect roi = opt.roi.empty() ? cv::Rect(0, 0, frame.cols, frame.rows) : opt.roi;
  if ((roi & cv::Rect(0, 0, frame.cols, frame.rows)) != roi) {
    throw std::invalid_argument(fmt::format("--roi {},{},{},{} lies outside the {}x{} frame", roi.x,
                                            roi.y, roi.width, roi.height, frame.cols, frame.rows));
  }
  return roi;
}

DataLevels LevelsOf(double data_max, LumaRange range) {
  if (range == LumaRange::kFull) return {data_max, 0, data_max};
  // 16 and 235 of 255; deeper video luma comes from the decoder scaled to 16 bits, whatever
  // DataMax makes of a frame whose brightest pixel is below half of that.
  const double per_level = data_max > 255 ? 256 : 1;
  return {data_max, std::min(kLimitedBlack8 * per_level, data_max),
          std::min(kLimitedWhite8 * per_level, data_max)};
}

SceneOptions SceneOptionsFor(const StrandMeasureOptions& opt, double data_max) {
  SceneOptions so;
  so.target = opt.target;
  so.polarity = opt.polarity;
  so.max_tilt_deg = opt.max_tilt_deg;
  so.min_length_px = opt.min_length_px;
  so.min_contrast = MinContrastLevel(opt, data_max);
  return so;
}

BandPx DefaultBand(MeasureTarget target, double scale_um_per_px) {
  if (!(scale_um_per_px > 0 && std::isfinite(scale_um_per_px)))
    throw std::invalid_argument(fmt::format("pixel scale {}: must be positive", scale_um_per_px));
  if (target == MeasureTarget::kFilament) return {0.0, kWholeStretchPx};
  return {50.0 / scale_um_per_px, 150.0 / scale_um_per_px};
}

bool StrandMeasureOptions::Validate(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (roi.x < 0 || roi.y < 0 || roi.width < 0 || roi.height < 0)
    return fail("roi must have non-negative x, y, width and height");
  if (!roi.empty() && (roi.width < 16 || roi.height < 16))
    return fail("roi must be at least 16x16 px");
  if (!(band_start_px >= 0)) return fail("band start must not be negative");
  if (!(band_height_px >= 4)) return fail("band height must be at least 4 px");
  if (!(caliper_spacing_px >= 1 && caliper_spacing_px <= band_height_px))
    return fail("caliper spacing must be between 1 px and the band height");
  if (!(min_contrast_fraction > 0 && min_contrast_fraction < 1))
    return fail("min contrast fraction must be in (0, 1)");
  if (!(max_blur_px > 0)) return fail("max blur must be positive");
  if (!(max_tilt_deg > 0 && max_tilt_deg < 80)) return fail("max tilt must be in (0, 80) degrees");
  if (!(min_caliper_fraction > 0 && min_caliper_fraction <= 1))
    return fail("min caliper fraction must be in (0, 1]");
  if (!(min_length_px >= 8)) return fail("min length must be at least 8 px");
  if (!(max_saturated_fraction >= 0 && max_saturated_fraction <= 1))
    return fail("max saturated fraction must be in [0, 1]");
  if (!(max_sigma_px > 0)) return fail("max sigma must be positive");
  if (!(max_sigma_fraction >= 0)) return fail("max sigma fraction must not be negative");
  return true;
}

StrandMeasurement MeasureStrand(const cv::Mat& frame, const StrandMeasureOptions& opt) {
  return FindAndMeasure(frame, opt, nullptr);
}

StrandMeasurement FindAndMeasure(const cv::Mat& frame, const StrandMeasureOptions& opt,
                                 SceneResult* scene_out) {
  const cv::Rect roi = ResolveRoi(frame, opt);
  const std::vector<cv::Mat> channels = SearchChannels(frame, roi);
  const double data_max = DataMax(frame(roi));
  const SceneOptions scene_options = SceneOptionsFor(opt, data_max);
  SceneResult scene = FindScene(channels, scene_options);
  const cv::Mat& channel = channels[scene.channel];  // measured in, until luma takes over
  StrandMeasurement m =
      MeasureInScene(channel, data_max, scene.status, scene.detail, scene.geometry, roi, opt);
  // The calipers see more than the pair search: when they reject the chosen pair (its width
  // bends like a disc's, most of it is hidden, it runs off the frame), the next pair that held up
  // gets its turn, as long as it scored near the chosen one.
  if (scene.chosen >= 0 && RejectsPair(m.status)) {
    PairCandidate& first = scene.candidates[scene.chosen];
    first.Judge(PairVerdict::kMeasuredRefused,
                fmt::format("measured {}: {}", FrameStatusName(m.status), m.detail));
    for (size_t k = 0; k < scene.runners_up.size() && k < kMaxFallbacks; ++k) {
      const auto& [index, g] = scene.runners_up[k];
      PairCandidate& next = scene.candidates[index];
      if (next.score < std::max(kMinFallbackScoreRatio * first.score,
                                kMinFallbackScoreFactor * scene_options.min_score))
        break;
      // The pairs the first one outranked were weighed against it, not against each other: the
      // first other pair that hangs from the face where this one does not, or rivals it.
      PairContest contest = PairContest::kNotRivals;
      const PairCandidate* rival = nullptr;
      for (size_t j = 0; j < scene.runners_up.size() && !rival; ++j) {
        if (j == k) continue;
        const auto& [other, other_g] = scene.runners_up[j];
        const PairContest c =
            ContestPairs(next, g, scene.candidates[other], other_g, scene_options);
        if (c == PairContest::kSecondAtFace || Ambiguous(c)) {
          contest = c;
          rival = &scene.candidates[other];
        }
      }
      if (contest == PairContest::kSecondAtFace) {
        next.Judge(PairVerdict::kNotAtFace);
        continue;
      }
      if (Ambiguous(contest)) {
        next.Judge(PairVerdict::kAsLikely, "as likely as another pair");
        m.status = FrameStatus::kAmbiguous;
        m.detail = AmbiguityDetail(contest, next, *rival);
        break;
      }
      if (std::string why = ChoiceDoubtDetail(scene, index, g, scene_options); !why.empty()) {
        next.Judge(PairVerdict::kAsLikely,
                   "a stripe, a gap or another object's as much as the strand");
        m.status = FrameStatus::kAmbiguous;
        m.detail = std::move(why);
        break;
      }
      StrandMeasurement alt =
          MeasureInScene(channel, data_max, FrameStatus::kValid, "", g, roi, opt);
      if (!alt.valid()) {
        next.Judge(PairVerdict::kMeasuredRefused,
                   fmt::format("measured {}: {}", FrameStatusName(alt.status), alt.detail));
        continue;
      }
      next.Judge(PairVerdict::kChosen);
      scene.chosen = index;
      scene.geometry = g;
      m = std::move(alt);
      break;
    }
  }
  // A colour frame's width is luma's wherever luma measures it. Compressed colour (JPEG, MJPEG,
  // H.264: 4:2:0) keeps luma at full resolution and coarsely quantised chroma at half, which every
  // single colour channel mixes in (red came out 0.3 px narrow where luma and green held, at 2
  // to 3σ); a Bayer camera's luma is mostly green, sampled twice as densely as red or blue. The
  // channel that found the strand is measured only where luma cannot be: an orange strand on a
  // blue ground shows no luma edge. Where luma's width is too doubtful to be valid and the
  // channel's edges are blurrier than luma's by kChromaBlurRatio (half-resolution chroma mixed
  // in), what luma doubts of the scene (its background's slope, the edge model) holds for the
  // channel too: each such part is the larger of the two (a Bayer strand on a textured ground
  // through JPEG: red 0.34 px narrow at σ 0.09, its edges 1.25 times as blurred as luma's, whose
  // background slopes by the edges by 0.15 px). (A colour strand on a coloured ground, as sharp
  // in red as in luma, is shaded otherwise in luma: red is the better measure there.) Where
  // neither is valid, luma's width and doubt are the frame's.
  if (channels.size() > 1 && scene.channel != 0 && scene.chosen >= 0 && LumaMayMeasure(m.status)) {
    StrandMeasurement luma =
        MeasureInScene(channels[0], data_max, FrameStatus::kValid, "", scene.geometry, roi, opt);
    if (luma.valid() || (luma.gave_width() && !m.valid())) {
      scene.measured_channel = 0;
      m = std::move(luma);
    } else if (luma.gave_width() && m.blur_px > kChromaBlurRatio * luma.blur_px) {
      TakeLargerModelDoubt(luma.doubt, &m.doubt);
      CombineSigmas(&m);
      JudgePrecision(opt, &m);
      if (!m.valid()) {
        scene.measured_channel = 0;
        m = std::move(luma);
      } else {
        scene.channel_doubts_luma = true;
      }
    }
  }
  // A colour channel clipped at the strand's edges flattens their profile and biases the fit:
  // the same edges are measured in another channel that holds up unclipped. Single colour
  // channels first: luma mixes the clipped one in.
  if (m.status == FrameStatus::kSaturated && channels.size() > 1 && scene.chosen >= 0) {
    for (size_t k = 1; k <= channels.size(); ++k) {
      const size_t c = k % channels.size();  // 1, 2, 3, then 0 (luma)
      if (static_cast<int>(c) == scene.measured_channel) continue;
      StrandMeasurement alt =
          MeasureInScene(channels[c], data_max, FrameStatus::kValid, "", scene.geometry, roi, opt);
      if (!alt.valid()) continue;
      scene.measured_channel = static_cast<int>(c);
      m = std::move(alt);
      break;
    }
  }
  if (scene_out) *scene_out = std::move(scene);
  return m;
}

StrandMeasurement MeasureInScene(const cv::Mat& channel, double data_max, FrameStatus status,
                                 const std::string& detail, const StrandGeometry& g,
                                 const cv::Rect& roi, const StrandMeasureOptions& opt,
                                 CylinderMemory* memory) {
  StrandMeasurement m;
  m.status = status;
  m.detail = detail;
  if (status != FrameStatus::kValid) return m;
  m.polarity = g.polarity;
  m.tip_x_px = g.axis.ox + roi.x;
  m.tip_y_px = g.axis.oy + roi.y;
  if (opt.target == MeasureTarget::kStrand) m.tip_sigma_px = g.tip_sigma_px;
  m.angle_deg = std::atan2(g.axis.dx, g.axis.dy) * kRadToDeg;

  // The band: from the tip (strand) or the top of the stretch (filament), stopping short of where
  // the pair ends (a bed, an obstacle, the frame) by more than the edge windows reach.
  const double reach = 10.0 + 12.0 * std::abs(g.axis.dx);
  const double band_s0 = opt.band_start_px + (opt.target == MeasureTarget::kFilament ? reach : 0);
  double band_s1 = band_s0 + opt.band_height_px;
  band_s1 = std::min(band_s1, g.s_end - reach);
  const double min_band = opt.target == MeasureTarget::kStrand
                              ? std::max(3.0 * opt.caliper_spacing_px, 0.3 * opt.band_height_px)
                              : 3.0 * opt.caliper_spacing_px;
  if (band_s1 - band_s0 < min_band) {
    m.status = FrameStatus::kBandOutsideFrame;
    m.detail = fmt::format("band {:.0f}-{:.0f} px below the {} runs into {} {:.0f} px below it",
                           band_s0, band_s0 + std::min(opt.band_height_px, 1e5),
                           opt.target == MeasureTarget::kStrand ? "tip" : "top of the stretch",
                           g.end_is_object ? "an object" : "the frame or ROI edge", g.s_end);
    return m;
  }
  // Tracking a filament: only the straight part measured last, with a margin wide enough for its
  // end calipers' straightness windows and for the rough calipers beyond it, on the same caliper
  // grid as the whole stretch. (The whole stretch costs a caliper fit every few px of it.)
  double s0 = band_s0, s1 = band_s1;
  if (opt.target == MeasureTarget::kFilament && g.precise && g.straight_s1_px > g.straight_s0_px) {
    const double step = opt.caliper_spacing_px;
    const double margin = kStraightPartMarginCalipers * step;
    s0 = band_s0 + std::max(0.0, std::floor((g.straight_s0_px - margin - band_s0) / step)) * step;
    s1 =
        std::min(band_s1, band_s0 + std::ceil((g.straight_s1_px + margin - band_s0) / step) * step);
    if (s1 - s0 < min_band) s0 = band_s0, s1 = band_s1;
  }
  const GreyImage img{channel, channel.depth() == CV_16U};
  // A strand's calipers cover its whole band (its width may change along it: die swell), the
  // spacing stretched to a whole number of calipers.
  StrandMeasureOptions calipers = opt;
  if (opt.target == MeasureTarget::kStrand)
    calipers.caliper_spacing_px =
        (s1 - s0) / std::max(1.0, std::round((s1 - s0) / opt.caliper_spacing_px));
  MeasureCalipers(img, data_max, g, s0, s1, calipers, &m, memory);
  if (m.valid() && opt.target == MeasureTarget::kStrand) {
    if (g.tip_width_px > 0) m.swell_ratio = std::max(1.0, g.tip_width_px / m.width_px);
    SelfCheck check =
        CheckOutsideIsBackground(img, g.axis, m.band_start_px, m.band_end_px, m.left_u0_px,
                                 m.right_u0_px, m.edge_slope, m.blur_px);
    if (check.passed)
      check = CheckInsideIsOneObject(img, g.axis, m.band_start_px, m.band_end_px, m.left_u0_px,
                                     m.right_u0_px, m.edge_slope, m.blur_px,
                                     MinContrastLevel(opt, data_max));
    // Reads far out from both edges (up to 12 widths): not on a tracked frame, whose edges follow
    // a frame that passed it (a width that moves from the last frame's by more than max(2 px,
    // 3 %) sends the frame afresh).
    if (check.passed && !g.precise)
      check = CheckNotOnAWiderObject(
          img, g.axis, m.band_start_px, m.band_end_px, m.left_u0_px, m.right_u0_px, m.edge_slope,
          m.blur_px, MinContrastLevel(opt, data_max), g.polarity == Polarity::kDarkOnBright);
    if (check.passed)
      check = CheckNoEdgeJustOutside(img, g.axis, m.band_start_px, m.band_end_px, m.left_u0_px,
                                     m.right_u0_px, m.edge_slope, m.blur_px,
                                     MinContrastLevel(opt, data_max));
    if (!check.passed) {
      m.status = FrameStatus::kNotSilhouette;
      m.detail = check.why;
    }
  }
  JudgePrecision(opt, &m);
  return m;
}

namespace {
// Every part of a width's σ, each named for a user: the spread first, then the model's parts in
// WidthDoubt's order (kModelDoubtParts), then the codec's. The one list the σ is combined from
// and shown as.
constexpr size_t kSpreadPart = 0, kDoubtParts = 11;
static_assert(std::size(kModelDoubtParts) + 2 == kDoubtParts);
std::array<DoubtPart, kDoubtParts> AllDoubtParts(const StrandMeasurement& m) {
  std::array<DoubtPart, kDoubtParts> parts;
  parts[kSpreadPart] = {"the calipers' spread", m.doubt.spread_px};
  size_t k = kSpreadPart + 1;
  for (const NamedDoubtPart& p : kModelDoubtParts) parts[k++] = {p.what, m.doubt.*p.part};
  parts[k] = {"the codec", m.codec_sigma_px};
  return parts;
}
}  // namespace

void CombineSigmas(StrandMeasurement* m) {
  const std::array<DoubtPart, kDoubtParts> parts = AllDoubtParts(*m);
  double model_sq = 0;
  for (size_t k = 0; k < parts.size(); ++k)
    if (k != kSpreadPart) model_sq += parts[k].sigma_px * parts[k].sigma_px;
  m->model_sigma_px = std::sqrt(model_sq);
  m->width_sigma_px = std::hypot(parts[kSpreadPart].sigma_px, m->model_sigma_px);
}

std::vector<DoubtPart> DoubtParts(const StrandMeasurement& m) {
  const std::array<DoubtPart, kDoubtParts> all = AllDoubtParts(m);
  std::vector<DoubtPart> parts(all.begin(), all.end());
  std::stable_sort(parts.begin(), parts.end(),
                   [](const DoubtPart& a, const DoubtPart& b) { return a.sigma_px > b.sigma_px; });
  return parts;
}

double MaxValidSigmaPx(const StrandMeasureOptions& opt, double width_px) {
  return std::max(opt.max_sigma_px, opt.max_sigma_fraction * width_px);
}

void JudgePrecision(const StrandMeasureOptions& opt, StrandMeasurement* m) {
  const double max_sigma_px = MaxValidSigmaPx(opt, m->width_px);
  // An imprecise width judged again (the codec's part added) has its reason written anew.
  if (m->gave_width() && m->width_sigma_px > max_sigma_px) {
    m->status = FrameStatus::kImprecise;
    const DoubtPart largest = DoubtParts(*m).front();
    m->detail = fmt::format(
        "width {:.2f} ± {:.2f} px: σ above the {:.2f} px a valid width may carry (largest part: "
        "{}, {:.2f} px)",
        m->width_px, m->width_sigma_px, max_sigma_px, largest.what, largest.sigma_px);
  }
}

int FlagWidthOutliers(std::vector<StrandMeasurement>& frames, int half_window, double k,
                      double min_deviation_px) {
  const int n = static_cast<int>(frames.size());
  std::vector<bool> flag(n, false);
  std::vector<double> window;
  for (int i = 0; i < n; ++i) {
    if (!frames[i].valid()) continue;
    window.clear();
    for (int j = std::max(0, i - half_window); j <= std::min(n - 1, i + half_window); ++j) {
      if (frames[j].valid()) window.push_back(frames[j].width_px);
    }
    if (window.size() < 5) continue;
    const double med = Median(window);
    const double mad = Mad(window, med);
    const double dev = std::abs(frames[i].width_px - med);
    if (dev > k * kMadToSigma * mad && dev > min_deviation_px) flag[i] = true;
  }
  int count = 0;
  for (int i = 0; i < n; ++i) {
    if (!flag[i]) continue;
    frames[i].status = FrameStatus::kWidthOutlier;
    frames[i].detail = fmt::format("width {:.2f} px far from its neighbours", frames[i].width_px);
    ++count;
  }
  return count;
}

}  // namespace clogscope::vision
