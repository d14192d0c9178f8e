#include "apps/calibrate_command.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <stdexcept>

#include "apps/cli_util.h"
#include "calib/calibration_file.h"
#include "common/plot.h"
#include "common/provenance.h"
#include "pipeline/band.h"
#include "pipeline/calibrate_targets.h"

namespace clogscope::apps {
namespace {

namespace fs = std::filesystem;

void PrintReport(const calib::ScaleCalibration& c) {
  fmt::print("calibration ({}, {} targets): scale {:.6f} ± {:.6f} µm/px ({:.4f} %)\n", c.method,
             c.targets, c.scale_um_per_px, c.scale_sigma_um_per_px,
             100 * c.scale_sigma_um_per_px / c.scale_um_per_px);
  if (c.edge_bias_fitted) {
    fmt::print("edge bias {:+.4f} ± {:.4f} px\n", c.edge_bias_px, c.edge_bias_sigma_px);
  }
  if (c.distortion_fitted) {
    fmt::print("second-order term {:+.5f} ± {:.5f} px per index²\n", c.distortion_px,
               c.distortion_sigma_px);
  }
  fmt::print(
      "residuals: RMS {:.4f} px = {:.4f} µm, worst {:+.4f} px = {:+.4f} µm, outliers {} of {}\n",
      c.rms_residual_px, c.rms_residual_um, c.worst_residual_px, c.worst_residual_um, c.outliers,
      c.targets);
  if (!c.message.empty()) fmt::print("note: {}\n", c.message);
  fmt::print("{:>24} {:>12} {:>12} {:>12} {:>12} {:>12}\n", "target", "nominal µm", "measured px",
             "model px", "residual px", "residual µm");
  for (const auto& r : c.residuals) {
    fmt::print("{:>24} {:>12.3f} {:>12.4f} {:>12.4f} {:>+12.4f} {:>+12.4f}{}\n", r.name,
               r.nominal_um, r.measured_px, r.model_px, r.residual_px, r.residual_um,
               r.outlier ? "  OUTLIER" : "");
  }
}

}  // namespace

bool CalibrateCommandOptions::Validate(std::string* why) const {
  if (!targets.Validate(why)) return false;
  if (out.empty()) {
    *why = "--out is required";
    return false;
  }
  return true;
}

int RunCalibrate(int argc, char** argv) {
  CLI::App app{"Fit the pixel scale (µm/px) from images of pin gauges or a stage micrometer.",
               "clogscope calibrate"};
  CalibrateCommandOptions o;
  std::string roi, polarity = "auto";
  double expect = 0;
  app.add_option("--pins", o.targets.pins_csv,
                 "CSV image,diameter_um[,tolerance_um] (paths relative to the CSV)");
  app.add_option("--micrometer", o.targets.micrometer_images, "Stage micrometer image(s)");
  app.add_option("--pitch-um", o.targets.pitch_um, "Micrometer line pitch");
  app.add_flag("--distortion", o.targets.fit_distortion, "Micrometer: fit a second-order term too");
  app.add_option("--expect-scale-um-per-px", expect,
                 "Micrometer: refuse a result more than 25 % from this");
  app.add_option("--out", o.out, "Calibration file to write (YAML)")->required();
  app.add_option("--plot", o.plot,
                 "Residual plot PNG (default: OUT without extension + _residuals.png)");
  app.add_option("--roi", roi, "Search only inside x,y,w,h (px)");
  app.add_option("--polarity", polarity, "Pins: auto, bright or dark")->capture_default_str();
  app.footer(
      "Examples:\n"
      "  clogscope calibrate --pins pins/pins.csv --out calib.yaml\n"
      "  clogscope calibrate --micrometer stage.png --pitch-um 100 --out calib.yaml\n"
      "  clogscope measure step1.mp4 --calib calib.yaml --out-frames frames.csv\n"
      "Pins give the scale and the edge bias b (width_um = (width_px - b) * scale); a micrometer\n"
      "gives the scale only.");
  if (!ParseCommandLine(app, argc, argv)) return 0;  // --help printed
  if (!roi.empty()) o.targets.pin_measure.roi = pipeline::ParseRoi(roi);
  o.targets.pin_measure.polarity = vision::ParsePolarity(polarity);
  if (app.count("--expect-scale-um-per-px")) o.targets.expect_scale_um_per_px = expect;
  std::string why;
  if (!o.Validate(&why)) throw std::invalid_argument(why);
  const pipeline::TargetCalibration r = pipeline::CalibrateFromTargets(o.targets);
  for (const std::string& note : r.notes) spdlog::info("{}", note);
  PrintReport(r.calibration);
  if (!r.calibration.usable) {
    spdlog::error("calibration not usable: {}; no file written", r.calibration.message);
    return 1;
  }
  calib::WriteCalibrationFile(o.out, r.calibration, CurrentProvenance(), r.inputs);
  const std::string plot_path =
      !o.plot.empty()
          ? o.plot
          : (fs::path(o.out).parent_path() / (fs::path(o.out).stem().string() + "_residuals.png"))
                .string();
  PlotSpec spec;
  spec.title =
      fmt::format("Calibration residuals ({}): scale {:.5f} ± {:.5f} µm/px", r.calibration.method,
                  r.calibration.scale_um_per_px, r.calibration.scale_sigma_um_per_px);
  spec.x_label =
      r.calibration.method == "pins" ? "pin diameter (µm)" : "position on the scale (µm)";
  spec.y_label = "measured − model (px)";
  spec.zero_line = true;
  PlotSeries series{"residual", {}, {}, {}, "points pt 7 ps 1.5"};
  for (const auto& t : r.calibration.residuals) {
    series.x.push_back(t.nominal_um);
    series.y.push_back(t.residual_px);
  }
  spec.series.push_back(series);
  if (!PlotToPng(spec, plot_path, &why)) spdlog::warn("residual plot not drawn: {}", why);
  spdlog::info("wrote {}", o.out);
  return 0;
}

}  // namespace clogscope::apps
