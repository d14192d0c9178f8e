#include "apps/inspect_command.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <stdexcept>

#include "apps/cli_util.h"
#include "common/angle.h"
#include "common/path_check.h"
#include "pipeline/band.h"
#include "vision/io/frame_source.h"
#include "vision/io/video_io.h"
#include "vision/overlay/overlay.h"

namespace clogscope::apps {
namespace {

const char* kChannelNames[] = {"luma", "blue", "green", "red"};

// Frame `index` of the input, or an error naming it.
vision::InputFrame ReadFrame(const std::string& input, int index) {
  const auto source = vision::FrameSource::Open(input);
  vision::InputFrame f;
  int read = 0;
  while (source->Next(&f)) {
    ++read;
    if (f.index < index) continue;
    if (f.image.empty())
      throw std::invalid_argument(
          fmt::format("{}: frame {} unreadable: {}", input, index, f.error));
    return f;
  }
  throw std::invalid_argument(
      fmt::format("--frame {}: {} has only {} frame(s)", index, input, read));
}

// The band in px as asked for, the target's default (pipeline/band.h, no scale) for the rest. A
// band that cannot be used is left to the strand options' Validate to name.
void SetBandPx(const pipeline::BandRequest& asked, vision::StrandMeasureOptions* o) {
  const vision::BandPx band = pipeline::ResolveBandPx(asked, o->target, std::nullopt).band;
  o->band_start_px = band.start_px;
  o->band_height_px = band.height_px;
}

// The options for a target, with its default band unless one was given.
vision::StrandMeasureOptions ForTarget(vision::StrandMeasureOptions o, vision::MeasureTarget t,
                                       bool band_given) {
  o.target = t;
  if (!band_given) SetBandPx({}, &o);
  return o;
}

// The chosen pair's stretch with room around it: the ROI a user can give to keep clutter out.
cv::Rect SuggestRoi(const vision::StrandGeometry& g, const cv::Rect& roi, const cv::Size& size) {
  const double margin = std::max(40.0, 0.5 * g.width_px);
  const double s0 = g.has_tip ? -std::max(20.0, 0.3 * g.width_px) : 0.0;
  double x0 = 1e30, y0 = 1e30, x1 = -1e30, y1 = -1e30;
  for (double s : {s0, g.s_end}) {
    for (double u :
         {g.left_u0 + g.edge_slope * s - margin, g.right_u0 + g.edge_slope * s + margin}) {
      x0 = std::min(x0, g.axis.ImageX(s, u));
      x1 = std::max(x1, g.axis.ImageX(s, u));
      y0 = std::min(y0, g.axis.ImageY(s, u));
      y1 = std::max(y1, g.axis.ImageY(s, u));
    }
  }
  const cv::Rect r(static_cast<int>(std::floor(x0)) + roi.x,
                   static_cast<int>(std::floor(y0)) + roi.y, static_cast<int>(std::ceil(x1 - x0)),
                   static_cast<int>(std::ceil(y1 - y0)));
  return r & cv::Rect(cv::Point(0, 0), size);
}

}  // namespace

bool InspectCommandOptions::Validate(std::string* why) const {
  if (input.empty())
    *why = "no input given";
  else if (frame < 0)
    *why = fmt::format("--frame {}: must not be negative", frame);
  else if (out_png.empty())
    *why = "--out must name a PNG file";
  else if (vision::LowerExtension(out_png) != ".png")
    *why = "--out " + out_png + ": must end in .png (the annotated frame is a PNG)";
  else if (!CheckInputPath("", input, PathExpect::kFileOrDirectory, why))
    return false;
  else
    return strand.Validate(why);
  return false;
}

InspectReport InspectInput(const InspectCommandOptions& o) {
  std::string why;
  if (!o.Validate(&why)) throw std::invalid_argument(why);
  const vision::InputFrame f = ReadFrame(o.input, o.frame);
  const cv::Mat& img = f.image;
  vision::StrandMeasureOptions strand = o.strand;
  strand.luma_range = f.luma_range;  // a video frame's, as `measure` reads it
  InspectReport rep;
  rep.frame_rect = cv::Rect(0, 0, img.cols, img.rows);
  const cv::Rect roi = vision::ResolveRoi(img, o.strand);
  const double data_max = vision::DataMax(img(roi));
  // Without a target given: a strand below a tip, or else whatever straight stretch is in view.
  std::vector<vision::MeasureTarget> tries = {o.strand.target};
  if (!o.target_given) tries = {vision::MeasureTarget::kStrand, vision::MeasureTarget::kFilament};
  vision::StrandMeasureOptions measured_with;  // the last target's, the one reported
  for (const auto t : tries) {
    rep.target = t;
    measured_with = ForTarget(strand, t, o.band_given);
    rep.measurement = vision::FindAndMeasure(img, measured_with, &rep.scene);
    if (rep.scene.status != vision::FrameStatus::kNoTip) break;
  }
  const vision::StrandMeasurement& m = rep.measurement;

  std::string& t = rep.text;
  t += fmt::format("{} frame {}: {}x{}, {} channel(s), {}-bit data (largest value {:.0f})\n",
                   f.source, f.index, img.cols, img.rows, img.channels(),
                   static_cast<int>(std::round(std::log2(data_max + 1))), data_max);
  t += fmt::format(
      "searched {} in {}, gradient noise {:.2f} grey levels/px\n",
      roi == rep.frame_rect ? "the whole frame"
                            : fmt::format("ROI {},{},{},{}", roi.x, roi.y, roi.width, roi.height),
      img.channels() == 1
          ? "grey"
          : fmt::format(
                "{}{}", kChannelNames[rep.scene.channel],
                rep.scene.measured_channel == rep.scene.channel
                    ? ""
                    : fmt::format(" (measured in {})", kChannelNames[rep.scene.measured_channel])),
      rep.scene.gradient_noise);
  t += fmt::format("target {}{}\n", vision::MeasureTargetName(rep.target),
                   o.target_given ? ""
                                  : " (chosen: a tip is " +
                                        std::string(rep.target == vision::MeasureTarget::kStrand
                                                        ? "in view)"
                                                        : "not in view)"));
  t += "candidate edge pairs, best first (numbered as in the picture):\n";
  for (size_t i = 0; i < rep.scene.candidates.size() && i < 8; ++i) {
    const auto& c = rep.scene.candidates[i];
    t += fmt::format(
        "  #{:<2} width {:7.1f} px  length {:5.0f} px  tilt {:+5.1f}°  {:6} SNR {:4.0f}  "
        "score {:5.0f}  {}\n",
        i + 1, c.width_px, c.length_px, std::atan2(c.axis.dx, c.axis.dy) * kRadToDeg,
        vision::PolarityName(c.polarity), c.snr, c.score,
        c.verdict == vision::PairVerdict::kNotExamined ? "not examined" : c.why);
  }
  if (rep.scene.candidates.empty()) t += "  none\n";
  if (m.valid()) {
    t += fmt::format(
        "result: width {:.3f} ± {:.3f} px, angle {:+.2f}°, {} ({:.1f}, {:.1f}), band {:.0f}–{:.0f} "
        "px, "
        "{} of {} calipers, blur {:.2f} px, contrast {:.0f}, edges {} / {}\n",
        m.width_px, m.width_sigma_px, m.angle_deg,
        rep.target == vision::MeasureTarget::kStrand ? "tip" : "stretch top", m.tip_x_px,
        m.tip_y_px, m.band_start_px, m.band_end_px, m.calipers_used, m.calipers_total, m.blur_px,
        m.contrast, m.shading_left ? "shaded" : "plain", m.shading_right ? "shaded" : "plain");
    if (rep.target == vision::MeasureTarget::kStrand) {
      const vision::StrandGeometry& g = rep.scene.geometry;
      const int face = g.tip_face_sides;
      const bool decides =
          vision::HangsFromFace(g, vision::SceneOptionsFor(measured_with, data_max));
      t += fmt::format("  tip: {}{}; swell ratio {:.2f} (widest below the tip over the width)\n",
                       face == 2   ? fmt::format("on the nozzle's face, which shows on both sides "
                                                   "(stepping by up to {:.0f} grey levels: {})",
                                                 g.tip_face_step,
                                               decides ? "clear enough to tell it from "
                                                           "another object"
                                                         : "too faint to tell it from another "
                                                           "object")
                       : face == 1 ? "on the nozzle's face, which shows on one side"
                                   : "where the edges end (the nozzle's face does not show)",
                       m.tip_sigma_px >= 0
                           ? fmt::format(", ± {:.2f} px along the axis", m.tip_sigma_px)
                           : std::string(),
                       m.swell_ratio);
    }
    if (m.straight_start_px > m.band_start_px || m.straight_end_px < m.band_end_px) {
      t += fmt::format(
          "  the edges are rough (knurl or gear marks) on {} calipers: the width is the straight "
          "part's, {:.0f}–{:.0f} px\n",
          m.rough_calipers, m.straight_start_px, m.straight_end_px);
    }
    rep.suggested_roi = SuggestRoi(rep.scene.geometry, roi, img.size());
  } else {
    t += fmt::format("result: {}: {}\n", vision::FrameStatusName(m.status), m.detail);
  }
  if (m.gave_width()) {
    // The σ's parts, largest first, while they matter.
    std::string parts;
    for (const vision::DoubtPart& p : vision::DoubtParts(m)) {
      if (p.sigma_px < 0.001 || p.sigma_px < 0.1 * m.width_sigma_px) break;
      parts += fmt::format("{}{} {:.3f}", parts.empty() ? "" : ", ", p.what, p.sigma_px);
    }
    if (!parts.empty()) t += fmt::format("  σ {:.3f} px: {}\n", m.width_sigma_px, parts);
  }
  // What to give measure (and the manifest) for this camera.
  const std::string polarity = m.valid() && m.polarity != vision::Polarity::kMixed
                                   ? vision::PolarityName(m.polarity)
                                   : "auto";
  std::string cmd = fmt::format("clogscope measure {} --target {}", o.input,
                                vision::MeasureTargetName(rep.target));
  std::string yaml = fmt::format("target: {}\n", vision::MeasureTargetName(rep.target));
  if (!rep.suggested_roi.empty()) {
    const cv::Rect& r = rep.suggested_roi;
    cmd += fmt::format(" --roi {},{},{},{}", r.x, r.y, r.width, r.height);
    yaml += fmt::format("roi: {},{},{},{}\n", r.x, r.y, r.width, r.height);
  }
  if (polarity != "auto") {
    cmd += " --polarity " + polarity;
    yaml += "polarity: " + polarity + "\n";
  }
  t += "suggested command line:\n  " + cmd + " --out-frames frames.csv\n";
  t += "suggested manifest keys:\n";
  for (size_t a = 0, b; a < yaml.size(); a = b + 1) {
    b = yaml.find('\n', a);
    t += "  " + yaml.substr(a, b - a) + "\n";
  }
  if (!m.valid()) {
    t += "hint: look at the picture — is the strand among the numbered pairs? An --roi around it "
         "keeps clutter out; --target filament measures a stretch with no tip.\n";
  }

  cv::Mat overlay = vision::DrawOverlay(img, m, 0.0);
  vision::DrawCandidates(overlay, rep.scene, roi.tl());
  if (!rep.suggested_roi.empty())
    cv::rectangle(overlay, rep.suggested_roi, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  vision::WriteImageAtomically(o.out_png, overlay);
  return rep;
}

int RunInspect(int argc, char** argv) {
  CLI::App app{"Show what the tool sees in one frame and suggest the options for this camera.",
               "clogscope inspect"};
  InspectCommandOptions o;
  std::string roi, polarity = "auto", target;
  app.add_option("input", o.input, "An image, a directory of images or a video")->required();
  app.add_option("--frame", o.frame, "Which frame (from 0)")->capture_default_str();
  app.add_option("--out", o.out_png, "Annotated PNG to write")->capture_default_str();
  app.add_option("--roi", roi, "Search only inside x,y,w,h (px)");
  app.add_option("--polarity", polarity, "auto, bright or dark")->capture_default_str();
  app.add_option("--target", target, "strand or filament (default: strand if a tip is in view)");
  pipeline::BandRequest band;
  app.add_option("--band-start-px", band.start_px,
                 "Band start below the tip or the top of the stretch (default: as measure)");
  app.add_option("--band-height-px", band.height_px, "Band height (default: as measure)");
  app.footer(
      "Examples:\n"
      "  clogscope inspect step1.mp4 --out inspect.png\n"
      "  clogscope inspect feed.avi --frame 100 --target filament\n"
      "The picture numbers every candidate edge pair (green: chosen, orange: lost on score, grey:\n"
      "ruled out), with the band, calipers and tip of the measurement and the suggested ROI "
      "(white).");
  if (!ParseCommandLine(app, argc, argv)) return 0;  // --help printed
  if (!roi.empty()) o.strand.roi = pipeline::ParseRoi(roi);
  o.strand.polarity = vision::ParsePolarity(polarity);
  if (!target.empty()) {
    o.strand.target = vision::ParseMeasureTarget(target);
    o.target_given = true;
  }
  if (band.start_px || band.height_px) {
    SetBandPx(band, &o.strand);
    o.band_given = true;
  }
  const InspectReport rep = InspectInput(o);
  std::fputs(rep.text.c_str(), stdout);
  std::fflush(stdout);
  spdlog::info("wrote {}", o.out_png);
  return rep.measurement.valid() ? 0 : 1;
}

}  // namespace clogscope::apps
