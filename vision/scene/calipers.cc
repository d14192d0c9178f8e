#include "vision/scene/calipers.h"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "common/angle.h"
#include "common/robust.h"
#include "vision/edges/caliper_samples.h"
#include "vision/edges/cylinder_fit.h"
#include "vision/edges/edge_fit.h"
#include "vision/edges/residual_structure.h"
#include "vision/edges/straight_run.h"
#include "vision/scene/caliper_cylinders.h"
#include "vision/scene/caliper_edges.h"
#include "vision/scene/cylinder_memory.h"
#include "vision/scene/self_check.h"

namespace clogscope::vision {
namespace {

// A side is shaded only when its edge also moves out by more than this under the shading model.
constexpr double kMinShadingShiftPx = 0.1;
constexpr int kReferenceCalipers = 5;  // outside the band, for the occlusion check
// Edges inside the object are looked for this share of its width in from each side; the object's
// own slope is read no deeper.
constexpr double kInnerEdgeShare = 0.45;
// Tracking from templates: more of the band's calipers than this refusing theirs (the scene
// changed) and the frame is measured as the first was.
constexpr double kMaxRefusedTemplates = 0.25;
// How far the tip may lie from where it was placed along the axis: set by the nozzle's face on
// both sides of the strand, or inferred from the outline (tip.h).
constexpr double kTipSigmaWidths = 0.25;  // an unconfirmed tip's doubt, in widths
// Where such a tip's doubt alone is above this share of the width, the band's place is unknown.
// The doubt extends the band's slope in a straight line over a quarter of the width, and so
// understates a swell, whose width grows ever faster toward the face: over the matrix's 26 sets
// a third of the imprecise widths whose tip doubt was above 1 % of them lay beyond 3σ (a tip
// 70 px low: 161.1 ± 4.7 px where the band is 183.8), none of the 21 between 0.5 and 1 %.
constexpr double kMaxUnfixedTipDoubtShare = 0.01;
// A lamp off to one side whose dark strip inside the far rim (cylinder_fit.h) is deeper than this
// many blurs leaves that rim's per-edge blur no PSF's (BlurMismatchDoubtPx not taken).
constexpr double kLampAsideBlurs = 0.25;
// Curvature of the width along the band: more than 1 px of sag, bending like a disc (|w''|/2 above
// 0.25/w, i.e. a chord of a circle less than 4 widths in radius), by more than 3σ of the calipers'
// own scatter about it.
constexpr double kMaxSagPx = 1.0, kMaxBend = 0.25, kMinBendSigmas = 3.0;
// Whether a side's calipers show shading: each caliper's F statistic for the shading term is about
// χ²(1) without shading (mean 1, σ √2), so their mean over n calipers stays near 1 ± √(2/n).
// Shading is taken when the mean (each F capped, so that one odd caliper cannot decide) is 6σ
// above that, plus a margin for structured noise such as compression artefacts. The mean capped F
// statistic in its own σ units above 1:
double ShadingEvidenceSigmas(const std::vector<double>& f) {
  if (f.empty()) return 0;
  double sum = 0;
  for (double x : f) sum += std::min(x, 50.0);
  const double n = static_cast<double>(f.size());
  return (sum / n - 1.0 - 10.0 / n) / std::sqrt(2.0 / n);
}
// On a strand's band, most calipers must show it too: their median F beyond chance's 90 % point
// (2.7). A lit cylinder's shading is the same all along the band, while a colour camera's
// demosaicing artefacts change with the Bayer phase along a tilted edge and made a few calipers
// of a flat strand's edge look strongly shaded (F 30–70 on 3 of 7, the rest below 2.5). (At 4,
// chance's 95 % point, weakly lit strands lost their shading: 0.6 % fewer valid.) Not on a
// filament's stretch, parts of which gear and knurl marks spoil (on Greeff's lit filament the
// median left 5 frames of 281 measured afresh without the shading they have).
constexpr double kMinMedianShadingF = 2.7;
bool ShadingEvident(const std::vector<double>& f, bool strand) {
  return ShadingEvidenceSigmas(f) > 6.0 && (!strand || Median(f) > kMinMedianShadingF);
}
// A fit's residual sum of squares.
double Rss(const EdgeFit& fit) { return fit.rms * fit.rms * fit.samples; }

// A fit counts when it converged inside its window [u0, u1] (not within 1 px of its ends) with
// the edge's expected sign of contrast, and its σ places the edge within the window: a blur gone
// to its floor leaves a hard step whose place between two pixels nothing fixes (die swell 4697,
// an edge at σ 3.5e5 px, which made its frame's σ 2.4e4 px).
bool UsableFit(const EdgeFit& fit, double u0, double u1, int expected_sign) {
  return fit.converged && fit.edge_px > u0 + 1.0 && fit.edge_px < u1 - 1.0 &&
         fit.edge_sigma_px < u1 - u0 && fit.contrast * expected_sign > 0;
}

}  // namespace

void MeasureCalipers(const GreyImage& img, double data_max, const StrandGeometry& g, double band_s0,
                     double band_s1, const StrandMeasureOptions& opt, StrandMeasurement* m,
                     CylinderMemory* memory) {
  auto fail = [&](FrameStatus st, std::string detail) {
    m->status = st;
    m->detail = std::move(detail);
  };
  const AxisFrame& f = g.axis;
  const double min_contrast = MinContrastLevel(opt, data_max);
  const double width0 = g.width_px;
  const int n_cal = static_cast<int>((band_s1 - band_s0) / opt.caliper_spacing_px + 1e-9);
  m->band_start_px = band_s0;
  m->band_end_px = band_s0 + n_cal * opt.caliper_spacing_px;
  m->calipers_total = n_cal;

  std::vector<CaliperFit> fits(n_cal);
  // Per side (left, right): −1 undecided, 0 plain blurred step, 1 shaded step.
  int shade[2] = {opt.shading ? g.shading_left : 0, opt.shading ? g.shading_right : 0};
  std::vector<double> shade_evidence[2], shade_shift[2];
  double shading_doubt_px[2] = {0, 0};  // per side: how far out a shaded edge would lie
  double cylinder_doubt_px = 0;         // the lit cylinders' disagreement with the per-edge fits
  double cylinder_structure_px[2] = {0, 0};  // per side: what the cylinders' residuals share
  std::vector<EdgeSample> samples;
  samples.reserve(512);
  double sigma_guess = 1.5;
  double left_guess = g.left_u0, right_guess = g.right_u0, slope_guess = g.edge_slope;
  if (!g.precise) {
    // Sub-pixel starting edges at the top and bottom of the band: most frames then need one pass.
    // (Tracked edges are the last frame's fitted lines: better than two profiles, which on a rough
    // edge such as a knurled filament's would move the windows and cost a second pass.)
    const double sa = band_s0 + 0.5 * opt.caliper_spacing_px;
    const double sb = band_s0 + (n_cal - 0.5) * opt.caliper_spacing_px;
    const double half = std::min(10.0, 0.25 * width0);
    const double la =
        RefineEdgeGuess(img, f, sa, left_guess + slope_guess * sa, half, min_contrast, g.left_sign);
    const double lb =
        RefineEdgeGuess(img, f, sb, left_guess + slope_guess * sb, half, min_contrast, g.left_sign);
    const double ra = RefineEdgeGuess(img, f, sa, right_guess + slope_guess * sa, half,
                                      min_contrast, g.right_sign);
    const double rb = RefineEdgeGuess(img, f, sb, right_guess + slope_guess * sb, half,
                                      min_contrast, g.right_sign);
    if (sb > sa) slope_guess = 0.5 * ((lb - la) + (rb - ra)) / (sb - sa);
    left_guess = 0.5 * (la + lb) - slope_guess * 0.5 * (sa + sb);
    right_guess = 0.5 * (ra + rb) - slope_guess * 0.5 * (sa + sb);
  }
  const bool filament = opt.target == MeasureTarget::kFilament;
  // Edges inside the object near its silhouette (a stripe, a lens's core) must stay out of the
  // edge windows: how deep inside each side's window may reach.
  // (A filament's band is its whole stretch, its median profile blurred by gear and knurl marks:
  // not looked at.)
  // And where such an edge's stripe ends (its far side), when that is as deep.
  constexpr double kNone = std::numeric_limits<double>::infinity();
  double inner_edge_px[2] = {kNone, kNone}, inner_far_px[2] = {kNone, kNone};
  for (int side = 0; side < 2 && !filament; ++side) {
    const double mid = 0.5 * (band_s0 + band_s1);
    const double e = (side == 0 ? left_guess : right_guess) + slope_guess * mid;
    inner_edge_px[side] = InnerEdgeDistance(img, f, band_s0, band_s1, e, side == 0 ? 1 : -1,
                                            std::min(kInnerEdgeShare * width0, 40.0), min_contrast,
                                            &inner_far_px[side], std::min(0.9 * width0, 60.0));
  }
  // How far inside a side's window may reach and stop short of an edge inside the object by the
  // blur (sigma_guess as it stands).
  const auto short_of_inner_edge = [&](int side) {
    return inner_edge_px[side] - BlurredStepReachPx(sigma_guess);
  };
  // An edge inside a dark silhouette (a glossy strand's stripe) so close that a window stopping
  // short of it cannot hold the silhouette's inner flank (2 blurs and a px; such frames had no
  // caliper fit both edges): the window reaches past it onto the stripe, and the edge is fitted
  // with the stripe's step (FitStepBeforeInnerStep). Only inside a silhouette darker than its
  // background, whose edge is a plain step: a lit strand's shading by its rim is no second step.
  // Decided at the first guess of the blur, and again at each blur the passes fit, which then go
  // on with the new windows and model; once taken, for good. Windows stopping short of a lens's
  // core 11.5 px inside at a blur of 2.7 px held 1.4 blurs of the rim, and each edge came out
  // 0.09 px outward (decided at 2.7, 0.015 px). (Not, after the first guess, for a narrow stripe,
  // next: a 29 px strand's 5 px stripe at a blur of 2.5 px left no caliper with both edges. But a
  // core across the middle, whose far side lies past it, is, with the inner step alone: the
  // window stops at the middle, where the far side's blur may still reach (2 blurs from it in a
  // 32 px lens: a window short of that blur held too little of the core to fit it at all, and
  // one to the middle is within 0.05 px without noise). Windows left short of a 32 px
  // lens's core 10 px inside, at a fitted blur of 2.7 px, held one blur of the rim, and the width
  // came out 0.4 px wide in three frames of four, valid at sigma 0.06-0.08. At the first
  // guess such a core already in reach is still taken as a stripe: not looked at.)
  // A stripe so narrow that such a window would reach its far side's blur too: the window takes
  // in the whole stripe, a box of the same blur.
  bool inner_step[2] = {false, false}, inner_stripe[2] = {false, false};
  // Whether a side's window reaches an edge inside the object (a step), and its stripe's far side.
  const auto inner_reach = [&](int side, bool* step, bool* stripe) {
    *step = g.polarity == Polarity::kDarkOnBright && std::isfinite(inner_edge_px[side]) &&
            short_of_inner_edge(side) < 2.0 * sigma_guess + 1.0;
    *stripe = *step && std::isfinite(inner_far_px[side]) &&
              inner_far_px[side] - 2.5 * sigma_guess - 1.0 <
                  inner_edge_px[side] + 2.5 * sigma_guess + 2.0;
  };
  // A core across the middle: both its sides a blur or more from it, and kMinCoreBlurs wide (a
  // lens's core, 11-12.5 px in 32-35 px lenses at blurs of 2.7-2.9 px; a narrow stripe by the
  // middle, 3 px in a dark 27 px strand at a blur of 2.5 px and read 6.5 px wide, is no plateau
  // to fit: that strand's calipers found no edges so).
  constexpr double kMinCoreBlurs = 3.0;
  const auto core_across_middle = [&](int side) {
    return inner_edge_px[side] < 0.5 * width0 - sigma_guess &&
           inner_far_px[side] > 0.5 * width0 + sigma_guess &&
           inner_far_px[side] - inner_edge_px[side] >= kMinCoreBlurs * sigma_guess;
  };
  for (int side = 0; side < 2; ++side) {
    inner_reach(side, &inner_step[side], &inner_stripe[side]);
    if (inner_step[side]) shade[side] = 0;
  }
  // One side's edge window about e0: `outer` px into the background, `inner` into the object
  // but short of an edge inside it, or onto its far side (inner_step).
  struct Window {
    double u0, u1;
  };
  const auto window = [&](int side, double e0, double outer, double inner) {
    // (Past a stripe's far side it may reach beyond the middle, short of the other silhouette.)
    const double past = inner_stripe[side] ? inner_far_px[side] : inner_edge_px[side];
    const double most = inner_stripe[side] ? width0 - 2.5 * sigma_guess - 2.0 : 0.5 * width0;
    const double in = inner_step[side] ? std::min(most, past + 2.5 * sigma_guess + 2.0)
                                       : std::min(inner, std::max(3.0, short_of_inner_edge(side)));
    return side == 0 ? Window{e0 - outer, e0 + in} : Window{e0 - in, e0 + outer};
  };
  // The clip levels, on the decoded frame (where a codec put the clipped plateau): the edge fits
  // read clipped pixels as censored (edge_fit.h), and saturation is judged by them. (Background
  // spot 4400, a lamp's spot clipped at white from 3.5 px beside a dark strand's edge, through
  // H.264: with the clipped pixels taken at their value, the edge's step was cut short, its blur
  // fitted at 1.81 px and the width 0.66 px narrow at sigma 0.08-0.19, valid. Censored, its blur
  // is 1.96 px, nearer the 2.0 px rendered, and with it the clipped share of the transitions
  // passes the limit: `saturated`.)
  const double mid_s = 0.5 * (band_s0 + band_s1), reach_px = 12.0;
  const ClipLevels clip = FindClipLevels(
      img, f, band_s0, band_s1, left_guess + slope_guess * mid_s - reach_px,
      right_guess + slope_guess * mid_s + reach_px, LevelsOf(data_max, opt.luma_range));
  // A side's plain step in the window's samples about e0.
  const auto fit_plain = [&](int side, double e0) {
    const double inward = side == 0 ? 1.0 : -1.0;
    return inner_step[side]
               ? FitStepBeforeInnerStep(
                     samples, e0, sigma_guess, e0, e0 + inward * inner_edge_px[side],
                     inner_stripe[side] ? e0 + inward * inner_far_px[side] : kNone, &clip)
               : FitBlurredStep(samples, e0, sigma_guess, e0, &clip);
  };
  // Its shaded step, and the step as its side's model stands (shaded once decided so).
  const auto fit_shaded = [&](int side, double e0) {
    return FitShadedStep(samples, e0, sigma_guess, e0, side == 0 ? 1 : -1, &clip);
  };
  const auto fit_as_decided = [&](int side, double e0) {
    return shade[side] == 1 ? fit_shaded(side, e0) : fit_plain(side, e0);
  };
  int total_samples = 0, total_saturated = 0, per_edge_consistent = 0;
  bool border = false;
  // A filament's band is its whole visible stretch, parts of which a drive gear or a guide may
  // hide: a quarter of it (at least 8 calipers) will do. A strand's short band must be clean.
  double min_used = filament ? std::max(8.0, 0.5 * opt.min_caliper_fraction * n_cal)
                             : opt.min_caliper_fraction * n_cal;
  // Tracking a lit object: its calipers' cylinders from the templates the last full measurement
  // left (cylinder_memory.h), without the per-edge fits, unless more than a few refuse the frame
  // (the scene changed): then as in the first frame, which makes new templates.
  if (!filament) memory = nullptr;  // templates have one background line: a filament's
  if (memory) memory->Use(f, opt.caliper_spacing_px);
  TrackedCylinders tracked;
  bool from_memory = false;
  if (memory && !memory->empty() && g.precise && shade[0] == 1 && shade[1] == 1 &&
      g.left_sign == -g.right_sign) {
    tracked = TrackCylinders(img, f, clip, band_s0, opt.caliper_spacing_px, n_cal, memory);
    from_memory = tracked.refused <= kMaxRefusedTemplates * n_cal;
    if (from_memory) ++memory->frames_from_templates;
  }
  // Usually one pass. Another re-centres the windows on the fitted edge lines, or widens them to
  // the fitted blur; a badly blurred frame needs a few widenings before its fit sees the whole
  // edge.
  constexpr int kMaxPasses = 4;
  // A core across the middle is tried once, as the only change for a pass, and kept unless too
  // few calipers fit both edges with it for a width (its plateau may be too narrow for the window
  // that stops at the middle: a 34 px lens's 8 px core, 4 px of it in reach at a blur of 2.4 px,
  // left no caliper with both edges): what the pass before it fitted, and how.
  struct CoreTrial {
    bool tried = false, pending = false;
    std::vector<CaliperFit> fits;
    double left_guess = 0, right_guess = 0, slope_guess = 0, sigma_guess = 0;
    int shade[2] = {0, 0}, total_samples = 0, total_saturated = 0, consistent = 0;
    bool inner_step[2] = {false, false}, border = false;
  } core;
  for (int pass = 0; pass < kMaxPasses && !from_memory; ++pass) {
    double outer = std::max(6.5, 3.0 * sigma_guess + 2.5);
    // A guess from the scene (a gradient peak) lies inside a shaded silhouette by a few px: the
    // first pass looks wider so that both plateaus are in its windows.
    // The shading model needs room to see the ramp's shape, too.
    if ((pass == 0 && !g.precise) || shade[0] != 0 || shade[1] != 0) outer = std::max(outer, 10.0);
    const double inner = std::min(outer, std::max(4.0, 0.3 * width0));
    total_samples = total_saturated = 0;
    border = false;
    for (int k = 0; k < n_cal; ++k) {
      const double s0 = band_s0 + k * opt.caliper_spacing_px;
      const double s1 = s0 + opt.caliper_spacing_px;
      const double sc = 0.5 * (s0 + s1);
      CaliperFit& cf = fits[k];
      cf = CaliperFit{};
      for (int side = 0; side < 2; ++side) {
        const double e0 = (side == 0 ? left_guess : right_guess) + slope_guess * sc;
        const Window w = window(side, e0, outer, inner);  // no structured binding: captured below
        const double u0 = w.u0, u1 = w.u1;
        int window_clipped = 0;
        if (!GatherEdgeSamples(img, f, s0, s1, u0, u1, clip, &samples, &window_clipped)) {
          cf.inside_roi = false;
          break;
        }
        // Reject fits that wandered out of their window or have the wrong sign of step.
        const int expected = side == 0 ? g.left_sign : g.right_sign;
        const auto usable = [&](const EdgeFit& fit) { return UsableFit(fit, u0, u1, expected); };
        // The shading model only where the side is known (or may turn out) to be shaded: on a
        // plain edge its extra parameter costs precision for nothing.
        const int model = shade[side];
        EdgeFit plain, shaded;
        if (model != 1) plain = fit_plain(side, e0);
        if (model != 0) shaded = fit_shaded(side, e0);
        if (!usable(plain)) plain.converged = false;
        if (!usable(shaded)) shaded.converged = false;
        if (model < 0) {
          // Evidence for shading: how much the shaded model lowers the residuals below the
          // plain step's, in units of the residual variance (an F statistic with 1 and n − 6
          // degrees of freedom). An edge only the shaded model describes counts as strong
          // evidence. Shading is one-sided, while a PSF that is not a Gaussian changes the edge's
          // profile on both sides alike and the shaded model takes part of that too (a colour
          // camera's demosaiced luma on a flat strand, at low noise, looked shaded on one side,
          // 0.2–0.5 px outward): wherever the F could count (ShadingEvident's median), it is
          // taken over the better of the plain and the peaked step. That comparison is not
          // nested, so the F is floored at 0 and is an upper bound on the χ²(1) one.
          // And where the silhouette moves: shading pulls a plain fit inward, so the shaded edge
          // lies outward of it; structured noise moves it either way.
          double evidence = 0, outward = 0;
          if (shaded.converged) {  // (on 10 samples at least: FitShadedStep)
            const double rss_s = Rss(shaded);
            const double unit = std::max(1e-12, rss_s / (shaded.samples - 6));
            double rss_alt = plain.converged ? Rss(plain) : std::numeric_limits<double>::infinity();
            if (!plain.converged || (rss_alt - rss_s) / unit > kMinMedianShadingF) {
              const EdgeFit& start = plain.converged ? plain : shaded;
              const EdgeFit peaked =
                  FitPeakedStep(samples, start.edge_px, start.sigma_px, e0, &clip);
              if (usable(peaked)) rss_alt = std::min(rss_alt, Rss(peaked));
            }
            evidence = std::isinf(rss_alt) ? 1e9 : std::max(0.0, rss_alt - rss_s) / unit;
            outward =
                plain.converged ? (shaded.edge_px - plain.edge_px) * (side == 0 ? -1.0 : 1.0) : 1.0;
          }
          if (plain.converged || shaded.converged) {
            shade_evidence[side].push_back(evidence);
            shade_shift[side].push_back(outward);
          }
        }
        (side == 0 ? cf.left_shaded : cf.right_shaded) = shaded;
        const EdgeFit fit = model == 1 || (model < 0 && !plain.converged) ? shaded : plain;
        (side == 0 ? cf.left : cf.right) = fit;
        // Clipping is judged where the edge's position is read, its transition: a background
        // clipped at black by texture or noise a few blurs away moves its plateau's level by a
        // fraction of a grey level, and the edge by far less than its σ. Without an edge, the
        // whole window.
        const ClippedCount near =
            fit.converged
                ? CountClippedNear(samples, clip, fit.edge_px, ClipZoneHalfWidthPx(fit.sigma_px))
                : ClippedCount{static_cast<int>(samples.size()), window_clipped};
        cf.samples += near.samples;
        cf.saturated += near.clipped;
      }
      if (!cf.inside_roi) border = true;
      total_samples += cf.samples;
      total_saturated += cf.saturated;
    }
    // After the first pass each undecided side settles on one model for all its calipers.
    for (int side = 0; side < 2; ++side) {
      if (shade[side] >= 0) continue;
      const double shift = Median(shade_shift[side]);
      shade[side] = ShadingEvident(shade_evidence[side], !filament) && shift > kMinShadingShiftPx;
      // A side taken as plain may still be shaded, whatever the evidence says: noise hides the
      // shading of a strand lit almost flat (ambient 0.9, which pulls a plain fit 0.07 px
      // inward at blur 2.9) long before it stops mattering. The width's σ carries the shaded
      // fit's outward shift as the model's doubt. (Counted only above 2σ of evidence, 4.5 % of
      // the matrix's valid widths lay beyond 3σ; counted always, 3.6 %, for 1 % fewer valid.)
      if (shade[side] == 0) {
        shading_doubt_px[side] = std::max(0.0, shift);
        continue;
      }
      for (auto& cf : fits)
        (side == 0 ? cf.left : cf.right) = side == 0 ? cf.left_shaded : cf.right_shaded;
    }
    const EdgeLines lines = FitEdgeLines(fits, band_s0, opt.caliper_spacing_px);
    if (core.pending) {
      core.pending = false;
      if (lines.calipers < std::min<double>(core.consistent, min_used)) {
        fits = core.fits;
        left_guess = core.left_guess, right_guess = core.right_guess;
        slope_guess = core.slope_guess, sigma_guess = core.sigma_guess;
        total_samples = core.total_samples, total_saturated = core.total_saturated;
        border = core.border;
        per_edge_consistent = core.consistent;
        for (int side = 0; side < 2; ++side)
          shade[side] = core.shade[side], inner_step[side] = core.inner_step[side];
        break;
      }
    }
    per_edge_consistent = lines.calipers;
    if (lines.calipers < 2) {
      // No edge fitted: perhaps blur far wider than the window. Widen and look again.
      sigma_guess = std::max(2.5 * sigma_guess, 0.6 * outer);
      continue;
    }
    std::vector<double> sigmas;
    for (const auto& cf : fits) {
      if (!cf.left.converged || !cf.right.converged) continue;
      sigmas.push_back(cf.left.sigma_px);
      sigmas.push_back(cf.right.sigma_px);
    }
    const double new_sigma = Median(sigmas);
    const double s_mid = 0.5 * (band_s0 + band_s1);
    const bool recentre =
        std::abs(lines.left_u0 + lines.slope * s_mid - (left_guess + slope_guess * s_mid)) > 1.0 ||
        std::abs(lines.right_u0 + lines.slope * s_mid - (right_guess + slope_guess * s_mid)) > 1.0;
    const bool widen = 3.0 * new_sigma + 2.5 > 1.25 * outer;
    left_guess = lines.left_u0;
    right_guess = lines.right_u0;
    slope_guess = lines.slope;
    // A fit in a window too narrow for the edge underestimates its width: widen geometrically.
    sigma_guess = widen ? std::max(new_sigma, 0.6 * outer) : new_sigma;
    // At the blur fitted (not at a widened guess), while a pass remains to use it.
    const bool redecide = pass + 1 < kMaxPasses && !widen;
    bool step[2] = {false, false}, stripe[2] = {false, false}, core_now[2] = {false, false};
    for (int side = 0; side < 2 && redecide; ++side) {
      inner_reach(side, &step[side], &stripe[side]);
      core_now[side] = !core.tried && !recentre && !inner_step[side] && step[side] &&
                       stripe[side] && core_across_middle(side);
    }
    if (core_now[0] || core_now[1]) {
      core.tried = core.pending = true;
      core.fits = fits;
      core.left_guess = left_guess, core.right_guess = right_guess;
      core.slope_guess = slope_guess, core.sigma_guess = sigma_guess;
      core.total_samples = total_samples, core.total_saturated = total_saturated;
      core.border = border;
      core.consistent = lines.calipers;
      for (int side = 0; side < 2; ++side)
        core.shade[side] = shade[side], core.inner_step[side] = inner_step[side];
    }
    bool now_inner_step = false;
    for (int side = 0; side < 2 && redecide; ++side) {
      if (inner_step[side] || !step[side] || (stripe[side] && !core_now[side])) continue;
      inner_step[side] = now_inner_step = true;
      shade[side] = 0;
    }
    if (!(recentre || widen || now_inner_step)) break;
  }
  if (from_memory) {
    TakeTrackedCylinders(tracked, &fits);
    total_samples = tracked.samples;
    total_saturated = tracked.saturated;
    border = tracked.border;
    sigma_guess = memory->sigma_px;
  }
  if (border)
    return fail(FrameStatus::kTouchesBorder, "edge windows reach the frame or ROI border");
  // The windows from here on, at the blur and models the passes settled on.
  const double outer = std::max(6.5, 3.0 * sigma_guess + 2.5) + (shade[0] || shade[1] ? 3.5 : 0);
  const double inner = std::min(outer, std::max(4.0, 0.3 * width0));
  // A strand's edges may curve out of windows placed on straight lines near the tip (die swell):
  // from the bottom up, a caliper that found no edge looks again where the two below point.
  if (!filament) {
    for (int k = n_cal - 3; k >= 0; --k) {
      CaliperFit& cf = fits[k];
      const CaliperFit& b1 = fits[k + 1];
      const CaliperFit& b2 = fits[k + 2];
      if ((cf.left.converged && cf.right.converged) || !cf.inside_roi) continue;
      if (!(b1.left.converged && b1.right.converged && b2.left.converged && b2.right.converged))
        continue;
      const double s0 = band_s0 + k * opt.caliper_spacing_px, s1 = s0 + opt.caliper_spacing_px;
      for (int side = 0; side < 2; ++side) {
        EdgeFit& fit = side == 0 ? cf.left : cf.right;
        if (fit.converged) continue;
        const double e1 = (side == 0 ? b1.left : b1.right).edge_px;
        const double e2 = (side == 0 ? b2.left : b2.right).edge_px;
        const double e0 = 2 * e1 - e2;
        const auto [u0, u1] = window(side, e0, outer, inner);
        if (!GatherEdgeSamples(img, f, s0, s1, u0, u1, clip, &samples)) break;
        const EdgeFit again = fit_as_decided(side, e0);
        if (UsableFit(again, u0, u1, side == 0 ? g.left_sign : g.right_sign)) fit = again;
      }
    }
  }
  if (total_samples > 0 && total_saturated > opt.max_saturated_fraction * total_samples) {
    return fail(FrameStatus::kSaturated,
                fmt::format("{} of {} edge pixels clipped", total_saturated, total_samples));
  }
  // A strand's interior clipped at the object's end of the range (a dark background clipped at 0
  // is no matter): the shading model reads the lit interior, and cannot be fitted to it clipped.
  // A plain step only reads its plateau's level: clipped there by noise about a level just inside
  // the range it moves by a fraction of a grey level, but when most of the interior is clipped
  // (its median), the level itself is out of range: a lit ramp the plain step cannot tell is
  // there (a bright strand lit down to 0.4 at its rim, clipped 9 px in, came out 1.4 px narrow),
  // or a dark strand below a codec's black losing the foot of its edges.
  const double slab_px = width0 + 2 * reach_px;  // FindClipLevels' slab across the band
  const double object_share = slab_px > 0 ? std::clamp(width0 / slab_px, 0.0, 1.0) : 1.0;
  const bool shaded = shade[0] == 1 || shade[1] == 1;
  const double max_object_clipped = shaded
                                        ? opt.max_saturated_fraction
                                        : std::max(opt.max_saturated_fraction, 0.5 * object_share);
  const double object_clipped = g.polarity == Polarity::kBrightOnDark ? clip.clipped_high_fraction
                                : g.polarity == Polarity::kDarkOnBright
                                    ? clip.clipped_low_fraction
                                    : clip.clipped_low_fraction + clip.clipped_high_fraction;
  if (object_clipped > max_object_clipped) {
    return fail(FrameStatus::kSaturated,
                fmt::format("{:.0f} % of the band clipped: {}", 100 * object_clipped,
                            shaded ? "its shading cannot be fitted"
                                   : "the strand's level is out of range"));
  }
  // Each edge's own blur, before any cylinder takes one for both (BlurMismatchDoubtPx); over
  // every caliper that fitted both edges, since which are inliers is decided after the cylinders.
  // A strand's only.
  EdgeBlur own_blur[2];
  if (!filament) {
    std::vector<double> blurs_px[2];
    for (const CaliperFit& cf : fits) {
      if (!(cf.left.converged && cf.right.converged)) continue;
      blurs_px[0].push_back(PsfSigmaPx(cf.left));
      blurs_px[1].push_back(PsfSigmaPx(cf.right));
    }
    for (int side = 0; side < 2; ++side) own_blur[side] = MedianBlur(blurs_px[side]);
  }
  // A lit object on both sides (a front-lit strand or filament): one cylinder per caliper.
  // Only on an object the per-edge fits already saw as one (enough consistent calipers): a wrong
  // pair (an edge and a shading step, filament and idler) must not become one by a richer model.
  // Then on every caliper: a knurl or gear tooth that spoils one edge's window spoils the
  // cylinder's less, which uses both edges and the interior.
  if (from_memory) {
    const EdgeLines lines = FitEdgeLines(fits, band_s0, opt.caliper_spacing_px);
    if (lines.calipers >= 2) {
      left_guess = lines.left_u0;
      right_guess = lines.right_u0;
      slope_guess = lines.slope;
    }
    // The model's doubt is the scene's, as the full measurement found it.
    cylinder_doubt_px = memory->cylinder_doubt_px;
  } else if (shade[0] == 1 && shade[1] == 1 && g.left_sign == -g.right_sign &&
             per_edge_consistent >= min_used) {
    EdgeLines lines;
    lines.left_u0 = left_guess;
    lines.right_u0 = right_guess;
    lines.slope = slope_guess;
    RefitAsCylinders(img, f, clip, band_s0, opt.caliper_spacing_px, lines, sigma_guess,
                     filament ? CylinderBackground::kOneLine : CylinderBackground::kEachSide, &fits,
                     filament ? nullptr : cylinder_structure_px, memory);
    if (memory) {
      memory->left_u0_px = lines.left_u0;
      memory->right_u0_px = lines.right_u0;
      memory->slope = lines.slope;
      memory->sigma_px = sigma_guess;
    }
    lines = FitEdgeLines(fits, band_s0, opt.caliper_spacing_px);
    if (lines.calipers >= 2) {
      // Two models of the same silhouette: each within its blur of it where it holds. Beyond
      // that, one of them is wrong (a stripe the cylinder traded its blur against), and which
      // one the frame cannot tell: half the excess counts as one σ, as the shading's does.
      // With an edge found inside the object, the cylinder's smooth interior does not hold, and
      // the whole disagreement is doubt (a bright strand's brighter stripe 2 px inside its rim:
      // the cylinder put the other edge 0.85 px inside the per-edge fit's, within the blur, and the
      // width came out 1.5 px narrow at σ 0.12-0.15).
      const double sc = 0.5 * (band_s0 + band_s1);
      const double allowed_px =
          std::isfinite(inner_edge_px[0]) || std::isfinite(inner_edge_px[1]) ? 0.0 : sigma_guess;
      const auto excess = [&](double cylinder_u0, double per_edge_u0) {
        const double apart =
            std::abs((cylinder_u0 + lines.slope * sc) - (per_edge_u0 + slope_guess * sc));
        return std::max(0.0, apart - allowed_px);
      };
      cylinder_doubt_px =
          0.5 * (excess(lines.left_u0, left_guess) + excess(lines.right_u0, right_guess));
      left_guess = lines.left_u0;
      right_guess = lines.right_u0;
      slope_guess = lines.slope;
    }
    if (memory) memory->cylinder_doubt_px = cylinder_doubt_px;
  } else {
    if (memory) memory->Clear();  // not lit cylinders this time: nothing to track
    // Both sides taken as plain, while the shaded fits put one of them as far out as a shaded
    // side lies: the evidence was too weak to decide. On their rims' windows alone, the shaded
    // fits come short of the shift in noise (a 205 px strand at ambient 0.75, noise 10: 0.13-0.37
    // px of a true 0.4 px a side; the width 1.0-1.1 px narrow at σ 0.23-0.29, valid). The lit
    // cylinders, whose whole interior's curve fixes the shading, tell it better: each side's
    // doubt is the larger of the two. (Not on flat objects, whose shaded fits barely move: the
    // cylinders would double a frame's cost.)
    double outward_px[2];
    if (!filament && shade[0] == 0 && shade[1] == 0 &&
        std::max(shading_doubt_px[0], shading_doubt_px[1]) > kMinShadingShiftPx &&
        g.left_sign == -g.right_sign && per_edge_consistent >= min_used &&
        CylinderOutwardShiftsPx(img, f, clip, band_s0, opt.caliper_spacing_px,
                                0.5 * (band_s0 + band_s1), {left_guess, right_guess, slope_guess},
                                sigma_guess, fits, outward_px)) {
      for (int side = 0; side < 2; ++side)
        shading_doubt_px[side] = std::max(shading_doubt_px[side], outward_px[side]);
    }
  }

  // Per-caliper widths, robust combination.
  const double cos_d = 1.0 / std::sqrt(1.0 + slope_guess * slope_guess);
  std::vector<double> cal_widths, steps, blurs;
  m->calipers.assign(n_cal, Caliper{});
  for (int k = 0; k < n_cal; ++k) {
    Caliper& c = m->calipers[k];
    c.s_px = band_s0 + (k + 0.5) * opt.caliper_spacing_px;
    c.fitted = fits[k].left.converged && fits[k].right.converged;
    if (!c.fitted) continue;
    c.left_u_px = fits[k].left.edge_px;
    c.right_u_px = fits[k].right.edge_px;
    c.width_px = (c.right_u_px - c.left_u_px) * cos_d;
    c.width_sigma_px = (fits[k].width_sigma_px >= 0
                            ? fits[k].width_sigma_px
                            : std::hypot(fits[k].left.edge_sigma_px, fits[k].right.edge_sigma_px)) *
                       cos_d;
    cal_widths.push_back(c.width_px);
    steps.push_back(std::abs(fits[k].left.contrast));
    steps.push_back(std::abs(fits[k].right.contrast));
    blurs.push_back(PsfSigmaPx(fits[k].left));
    blurs.push_back(PsfSigmaPx(fits[k].right));
  }
  m->has_geometry = true;
  m->shading_left = shade[0] == 1;
  m->shading_right = shade[1] == 1;
  m->axis_dx = f.dx;
  m->axis_dy = f.dy;
  m->left_u0_px = left_guess;
  m->right_u0_px = right_guess;
  m->edge_slope = slope_guess;
  // Report the refined axis: the edges' slope in the measurement frame tilts the first estimate.
  m->angle_deg = (std::atan2(f.dx, f.dy) + std::atan(slope_guess)) * kRadToDeg;
  if (cal_widths.empty()) return fail(FrameStatus::kOccluded, "no caliper found both edges");
  m->contrast = Median(steps);
  m->blur_px = Median(blurs);

  // A filament's width is taken on the longest straight part of its stretch (straight_run.h).
  int run_begin = 0, run_end = n_cal;
  if (filament) {
    StraightRunOptions so;
    if (g.straight_s1_px > g.straight_s0_px) {
      so.prefer_begin =
          static_cast<int>(std::lround((g.straight_s0_px - band_s0) / opt.caliper_spacing_px));
      so.prefer_end =
          static_cast<int>(std::lround((g.straight_s1_px - band_s0) / opt.caliper_spacing_px));
    }
    const StraightRun run = FindStraightRun(m->calipers, so);
    m->rough_calipers = run.rough;
    if (run.sections > 0 || run.end - run.begin < n_cal) {
      run_begin = run.begin;
      run_end = run.end;
      cal_widths.clear();
      for (int k = run_begin; k < run_end; ++k)
        if (m->calipers[k].fitted) cal_widths.push_back(m->calipers[k].width_px);
      if (cal_widths.size() < 2) {
        const long unfitted = std::count_if(m->calipers.begin(), m->calipers.end(),
                                            [](const Caliper& c) { return !c.fitted; });
        return fail(FrameStatus::kOccluded,
                    fmt::format("no straight part of the stretch: of {} calipers {} have rough "
                                "edges (gear or knurl marks), {} lack an edge",
                                n_cal, run.rough, unfitted));
      }
      min_used = std::max(8.0, 0.5 * opt.min_caliper_fraction * (run_end - run_begin));
    }
  }
  m->straight_start_px = band_s0 + run_begin * opt.caliper_spacing_px;
  m->straight_end_px = band_s0 + run_end * opt.caliper_spacing_px;

  const double med = Median(cal_widths);
  const double mad = Mad(cal_widths, med);
  const double tol = std::max(4.0 * kMadToSigma * mad, 0.1);
  double sum = 0, sum2 = 0;
  int used = 0;
  // A strand relaxing from die swell is wider at the band's top and narrows steadily down it:
  // those calipers are the strand too, kept while each is no wider than the one above it.
  bool relaxing = !filament;
  double above = 1e30;
  for (int k = run_begin; k < run_end; ++k) {
    Caliper& c = m->calipers[k];
    if (!c.fitted) continue;
    c.inlier = std::abs(c.width_px - med) <= tol;
    if (!c.inlier && relaxing && c.width_px > med && c.width_px <= above + tol)
      c.inlier = true;
    else
      relaxing = false;
    above = c.width_px;
    if (!c.inlier) continue;
    sum += c.width_px;
    sum2 += c.width_px * c.width_px;
    ++used;
  }
  m->calipers_used = used;
  // A strand's width along the band is constant (or changes linearly: die swell); the chord of a
  // disc sags toward the ends. Periodic roughness (a filament marked by drive-gear teeth) averages
  // out of a quadratic over several periods.
  // All fitted calipers: on a disc the chord's change leaves few of them within the MAD cut.
  // A strand's width about its smooth trend along the band: a swell relaxing down the band widens
  // the calipers' spread without making their mean any less certain.
  double trend_var = -1, width_slope = 0;
  double missing_doubt_px = 0;   // a changing width's calipers that are not in the mean
  double one_edge_doubt_px = 0;  // a changing width whose band turns off the strand's axis
  if (cal_widths.size() >= 4) {
    Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
    Eigen::Vector3d atb = Eigen::Vector3d::Zero();
    const double s_mid = 0.5 * (m->straight_start_px + m->straight_end_px);
    for (int k = run_begin; k < run_end; ++k) {
      const Caliper& c = m->calipers[k];
      if (!c.fitted) continue;
      const Eigen::Vector3d row(1.0, c.s_px - s_mid, (c.s_px - s_mid) * (c.s_px - s_mid));
      ata += row * row.transpose();
      atb += row * c.width_px;
    }
    const Eigen::Vector3d coef = ata.ldlt().solve(atb);
    const Eigen::Matrix3d ata_inv = ata.inverse();
    const auto trend = [&](double s_px) {
      const double ds = s_px - s_mid;
      return coef[0] + coef[1] * ds + coef[2] * ds * ds;
    };
    // The widths' scatter about the trend: every fitted caliper's, and the mean's (the inliers').
    double ss_fitted = 0, ss_inliers = 0;
    int n_fitted = 0;
    for (int k = run_begin; k < run_end; ++k) {
      const Caliper& c = m->calipers[k];
      if (!c.fitted) continue;
      const double r = c.width_px - trend(c.s_px);
      ss_fitted += r * r;
      ++n_fitted;
      if (c.inlier) ss_inliers += r * r;
    }
    // How surely the widths bend: the quadratic term over its σ from the fitted calipers' scatter
    // (noise of 11 grey levels on a 60 px strand bent a straight strand's widths by a px over the
    // band).
    const double bend_var = n_fitted > 3 ? ss_fitted / (n_fitted - 3) * ata_inv(2, 2) : 0.0;
    const double bend_sigmas = bend_var > 0 ? std::abs(coef[2]) / std::sqrt(bend_var)
                                            : std::numeric_limits<double>::infinity();
    if (!filament && used >= 5) {
      trend_var = ss_inliers / (used - 3);
      // Only a width that clearly changes: the slope of a straight strand's noisy widths is noise.
      const double slope_sigma = std::sqrt(trend_var * ata_inv(1, 1));
      if (std::abs(coef[1]) > 3.0 * slope_sigma) width_slope = coef[1];
      // The band's width is the mean over all its rows: where the width changes along it (a swell
      // relaxing), a caliper missing from the mean (no edge found, an outlier) takes its part of
      // the change with it. The trend at the calipers used against at all of them says how much.
      if (width_slope != 0) {
        double all = 0, in = 0;
        int n_all = 0, n_in = 0;
        for (int k = run_begin; k < run_end; ++k) {
          const Caliper& c = m->calipers[k];
          const double w = trend(c.s_px);
          all += w;
          ++n_all;
          if (c.inlier) in += w, ++n_in;
        }
        if (n_in > 0) missing_doubt_px = std::abs(all / n_all - in / n_in);
        one_edge_doubt_px = OneEdgeDriftDoubtPx(m->calipers, run_begin, run_end, width_slope,
                                                m->straight_end_px - m->straight_start_px);
      }
    }
    const double half = 0.5 * (m->straight_end_px - m->straight_start_px);
    // A disc's chord w(s) ≈ 2R − s²/R bends with |w''|/2 = 1/R ≈ 2/w; a strand's slow changes
    // (or a filament's along a long stretch) bend hundreds of widths more gently.
    const double sag = std::abs(coef[2]) * half * half;
    // Only a width bulging in the middle: a swell relaxing down the band bends the other way.
    if (coef[2] < 0 && sag > kMaxSagPx && std::abs(coef[2]) > kMaxBend / med &&
        bend_sigmas > kMinBendSigmas) {
      return fail(FrameStatus::kNoStrand,
                  fmt::format("the edges curve: the width changes by {:.1f} px over the band (a "
                              "disc or bend, not a straight strand)",
                              sag));
    }
  }
  m->width_px = sum / used;
  // The calipers' spread, or what their own fits expect of it when a few calipers happen to agree.
  double expected_var = 0;
  for (const Caliper& c : m->calipers)
    if (c.inlier) expected_var += c.width_sigma_px * c.width_sigma_px;
  WidthDoubt& doubt = m->doubt;
  doubt = WidthDoubt{};
  doubt.spread_px = std::sqrt(expected_var) / used;
  if (used >= 2) {
    const double var =
        trend_var >= 0 ? trend_var : std::max(0.0, (sum2 - sum * sum / used) / (used - 1));
    doubt.spread_px = std::max(doubt.spread_px, std::sqrt(var / used));
  }
  // The model's doubt: a side judged plain would be this much wider if shaded; half of it (both
  // sides together) counts as one σ.
  doubt.shading_px = 0.5 * (shading_doubt_px[0] + shading_doubt_px[1]);
  doubt.cylinder_px = cylinder_doubt_px;
  doubt.missing_px = missing_doubt_px;
  doubt.one_edge_px = one_edge_doubt_px;
  // A flat object's two edges (plain steps, no stripe modelled beside either) see one level
  // inside it: where they do not, a step beside one edge may have moved it (caliper_edges.h).
  // (The inlier calipers with their own edge models, not refitted as one cylinder.)
  std::vector<bool> own_edges(n_cal);
  for (int k = 0; k < n_cal; ++k)
    own_edges[k] = m->calipers[k].inlier && fits[k].width_sigma_px < 0;
  if (!filament) {
    if (shade[0] == 0 && shade[1] == 0 && !inner_step[0] && !inner_step[1]) {
      doubt.inner_level_px =
          InnerLevelDoubtPx(img, f, band_s0, opt.caliper_spacing_px, fits, own_edges, m->blur_px);
    }
    // A lamp's dark strip by one rim deeper than kLampAsideBlurs: the per-edge shaded step on
    // that side, which does not model it, takes a blur that is no PSF's (0.6 px against the lit
    // rim's 1.1, a lamp 25° off a 95 px strand): no comparison. (A lamp-lit strand whose dark
    // side was taken as plain has no cylinder, and no strip: the one-shaded allowance holds.)
    std::vector<double> terminator_px;
    for (int k = 0; k < n_cal; ++k)
      if (m->calipers[k].inlier) terminator_px.push_back(fits[k].terminator_px);
    const bool lamp_aside =
        !terminator_px.empty() && Median(terminator_px) > kLampAsideBlurs * m->blur_px;
    const int shaded_sides = (shade[0] == 1) + (shade[1] == 1);
    const EdgeModels models = shaded_sides == 0   ? EdgeModels::kBothPlain
                              : shaded_sides == 2 ? EdgeModels::kBothShaded
                                                  : EdgeModels::kOneShaded;
    if (!lamp_aside) doubt.edge_blur_px = BlurMismatchDoubtPx(own_blur[0], own_blur[1], models);
  }
  {
    // The inlier calipers' own edge models; a strand's calipers refitted as cylinders, the
    // cylinders'. (A filament's cylinders carry only their disagreement with the per-edge fits:
    // their residual structure on Greeff's real filament, knurled and lit, doubled its σ to
    // 0.16 px against a frame-to-frame scatter of 0.08 px.)
    double edge_shift_px[2];
    for (int side = 0; side < 2; ++side) {
      std::vector<CaliperEdge> edges;
      for (int k = 0; k < n_cal; ++k) {
        if (!own_edges[k]) continue;
        const double s0 = band_s0 + k * opt.caliper_spacing_px;
        edges.push_back(
            {s0, s0 + opt.caliper_spacing_px, side == 0 ? fits[k].left : fits[k].right});
      }
      // About each caliper's fitted edge: the window's reach either side of it.
      const Window w = window(side, 0.0, outer, inner);
      // The object's slope is read short of an edge inside it, and of its middle.
      const double object_reach_px = std::min(kInnerEdgeShare * width0, short_of_inner_edge(side));
      const BandEdgeDoubt judged =
          JudgeBandEdge(img, f, clip, edges, -w.u0, w.u1, side == 0 ? -1 : 1, object_reach_px);
      edge_shift_px[side] = judged.shift_px;
      doubt.structure_px = std::hypot(doubt.structure_px,
                                      std::hypot(judged.structure_px, cylinder_structure_px[side]));
      doubt.two_slope_px = std::hypot(doubt.two_slope_px, judged.two_slope_px);
    }
    // An edge whose background slopes toward a flat object lies where the two-slope step puts it.
    if (edge_shift_px[0] != 0 || edge_shift_px[1] != 0) {
      m->width_px += (edge_shift_px[1] - edge_shift_px[0]) * cos_d;
      m->left_u0_px += edge_shift_px[0];
      m->right_u0_px += edge_shift_px[1];
    }
    // And where the band starts, when the width changes along it (die swell relaxing): a tip set
    // by the nozzle's face or the object's own end is good to a fraction of a px (tip.h); one
    // inferred from where the outline leaves the nozzle's may be off by a good part of the
    // strand's width.
    const double tip_sigma_px = g.tip_sigma_px >= 0 ? g.tip_sigma_px : kTipSigmaWidths * width0;
    doubt.tip_px = std::abs(width_slope) * tip_sigma_px;
  }
  CombineSigmas(m);

  // The same calipers further down the strand, outside the band: a blob covering one edge over
  // the band makes the band's edges agree with each other but not with the strand. (A filament's
  // band is its whole stretch: there is no elsewhere, and occlusion shows as calipers that
  // disagree.)
  if (opt.target == MeasureTarget::kStrand) {
    const double lo = m->band_end_px + 2 * opt.caliper_spacing_px;
    const double hi = g.s_end - 10.0 - 12.0 * std::abs(f.dx);
    std::vector<double> elsewhere;
    for (int i = 0; i < kReferenceCalipers && hi - lo > opt.caliper_spacing_px; ++i) {
      const double s0 = lo + (hi - lo - opt.caliper_spacing_px) * (i + 0.5) / kReferenceCalipers;
      const double s1 = s0 + opt.caliper_spacing_px, sc = 0.5 * (s0 + s1);
      double edge[2];
      bool ok = true;
      for (int side = 0; side < 2 && ok; ++side) {
        const double e0 = (side == 0 ? left_guess : right_guess) + slope_guess * sc;
        const auto [u0, u1] = window(side, e0, outer, inner);
        ok = GatherEdgeSamples(img, f, s0, s1, u0, u1, clip, &samples);
        if (!ok) break;
        const EdgeFit fit = fit_as_decided(side, e0);
        ok = UsableFit(fit, u0, u1, side == 0 ? g.left_sign : g.right_sign);
        edge[side] = fit.edge_px;
      }
      if (ok) elsewhere.push_back((edge[1] - edge[0]) * cos_d);
    }
    if (elsewhere.size() >= 3) {
      const double ref = Median(elsewhere);
      // Wider in the band than below it, narrowing steadily down the band toward it: die swell
      // relaxing, not an object over one edge.
      const Caliper* first = nullptr;
      const Caliper* last = nullptr;
      for (const Caliper& c : m->calipers) {
        if (!c.inlier) continue;
        if (!first) first = &c;
        last = &c;
      }
      const bool relaxes = first && last && m->width_px > ref && first->width_px > last->width_px &&
                           first->width_px - last->width_px > 0.5 * (m->width_px - ref);
      if (!relaxes && std::abs(m->width_px - ref) > std::max(3.0, 0.04 * ref)) {
        return fail(FrameStatus::kOccluded,
                    fmt::format("width in the band {:.1f} px disagrees with the strand's {:.1f} px "
                                "further down",
                                m->width_px, ref));
      }
    }
  }
  if (!filament && g.tip_sigma_px < 0 && doubt.tip_px > kMaxUnfixedTipDoubtShare * m->width_px)
    return fail(FrameStatus::kNoTip,
                fmt::format("no nozzle face or strand end fixed the tip, and the width changes "
                            "along the band: where the band lies is unknown ({:.1f} ± {:.1f} px "
                            "and more)",
                            m->width_px, doubt.tip_px));
  // Self-check (self_check.h): both silhouettes fit about as well.
  if (!filament) {
    std::vector<double> rms[2];
    for (int k = run_begin; k < run_end; ++k) {
      if (!m->calipers[k].inlier) continue;
      rms[0].push_back(fits[k].left.rms);
      rms[1].push_back(fits[k].right.rms);
    }
    const SelfCheck check = CheckEdgeResiduals(rms[0], rms[1]);
    if (!check.passed) return fail(FrameStatus::kNotSilhouette, check.why);
  }
  if (m->contrast < min_contrast)
    return fail(FrameStatus::kLowContrast,
                fmt::format("edge contrast {:.1f} below {:.1f}", m->contrast, min_contrast));
  if (m->blur_px > opt.max_blur_px)
    return fail(FrameStatus::kOutOfFocus,
                fmt::format("edge blur {:.2f} px above {:.2f} px", m->blur_px, opt.max_blur_px));
  if (used < min_used)
    return fail(FrameStatus::kOccluded, fmt::format("{} of {} calipers consistent", used, n_cal));
  m->status = FrameStatus::kValid;
  m->detail.clear();
}

}  // namespace clogscope::vision
