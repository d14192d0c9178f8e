#include "apps/calibrate_command.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <stdexcept>

#include "apps/cli_util.h"
#include "calib/calibration_file.h"
#include "calib/line_lattice.h"
#include "common/atomic_file.h"
#include "common/csv.h"
#include "common/path_check.h"
#include "common/plot.h"
#include "common/provenance.h"
#include "vision/io/video_io.h"
#include "vision/scene/micrometer.h"

namespace clogscope::apps {
namespace {

namespace fs = std::filesystem;

// Plausible microscope scales: outside this a pitch or a diameter is surely mistyped.
constexpr double kMinScaleUmPerPx = 0.05, kMaxScaleUmPerPx = 100;

cv::Mat ReadImageOrThrow(const std::string& path, const std::string& where) {
  std::string why;
  if (!CheckInputPath("", path, PathExpect::kFile, &why))
    throw std::invalid_argument(where + ": " + why);
  std::string error;
  cv::Mat img = vision::ReadImage(path, &error);
  if (img.empty()) throw std::invalid_argument(where + ": " + path + ": " + error);
  return img;
}

calib::ScaleCalibration CalibrateFromPins(const CalibrateCommandOptions& o,
                                          std::vector<std::string>* inputs) {
  const CsvTable t = ParseCsv(ReadFile(o.pins_csv), o.pins_csv);
  const int c_img = t.Column("image"), c_d = t.Column("diameter_um"),
            c_tol = t.Column("tolerance_um");
  if (c_img < 0 || c_d < 0)
    throw std::invalid_argument(o.pins_csv + ": needs columns image,diameter_um[,tolerance_um]");
  if (t.rows.empty()) throw std::invalid_argument(o.pins_csv + ": no pins listed");
  inputs->push_back(o.pins_csv);
  const fs::path base = fs::path(o.pins_csv).parent_path();
  vision::StrandMeasureOptions mo = o.pin_measure;
  mo.target = vision::MeasureTarget::kFilament;
  mo.band_start_px = 8;
  mo.band_height_px = 1e6;  // the whole pin
  std::vector<calib::PinObservation> pins;
  for (size_t i = 0; i < t.rows.size(); ++i) {
    const auto& row = t.rows[i];
    const std::string where = fmt::format("{}:{}", o.pins_csv, t.row_line_numbers[i]);
    if (row[c_img].empty()) throw std::invalid_argument(where + ": image is missing");
    const std::string path =
        fs::path(row[c_img]).is_absolute() ? row[c_img] : (base / row[c_img]).string();
    calib::PinObservation pin;
    pin.name = row[c_img];
    pin.diameter_um = ParseNumberField(row[c_d], where, "diameter_um");
    if (c_tol >= 0 && !row[c_tol].empty())
      pin.tolerance_um = ParseNumberField(row[c_tol], where, "tolerance_um");
    const vision::StrandMeasurement m = vision::MeasureStrand(ReadImageOrThrow(path, where), mo);
    if (!m.valid()) {
      throw std::invalid_argument(fmt::format("{}: {}: pin not found ({}: {})", where, row[c_img],
                                              vision::FrameStatusName(m.status), m.detail));
    }
    pin.width_px = m.width_px;
    pin.width_sigma_px = m.width_sigma_px;
    spdlog::info("{}: {:.1f} µm pin is {:.4f} ± {:.4f} px wide ({} calipers)", row[c_img],
                 pin.diameter_um, m.width_px, m.width_sigma_px, m.calipers_used);
    pins.push_back(pin);
    inputs->push_back(path);
  }
  return calib::FitPinScale(pins, {});
}

calib::ScaleCalibration CalibrateFromMicrometer(const CalibrateCommandOptions& o,
                                                std::vector<std::string>* inputs) {
  std::vector<calib::LineObservation> all;
  std::vector<std::string> notes;
  vision::MicrometerOptions mo;
  mo.roi = o.pin_measure.roi;
  for (size_t i = 0; i < o.micrometer_images.size(); ++i) {
    const std::string& path = o.micrometer_images[i];
    const auto found = vision::FindMicrometerLines(ReadImageOrThrow(path, "--micrometer"), mo);
    if (!found.ok)
      throw std::invalid_argument(path + ": micrometer lines not found: " + found.reason);
    // Numerals, dust and marks between the lines are left out by the lattice, and said so.
    std::vector<calib::LineMark> marks;
    for (const auto& l : found.lines) marks.push_back({l.position_px, l.sigma_px, l.length_px});
    const calib::LatticeIndexing lattice = calib::IndexLinesOnLattice(marks, static_cast<int>(i));
    if (!lattice.ok()) throw std::invalid_argument(path + ": " + lattice.reason);
    const std::string left_out = lattice.LeftOutSummary();
    spdlog::info("{}: {} lines, spacing {:.3f} px, tilt {:.2f}°; {}", path, lattice.lines.size(),
                 lattice.pitch_px, found.angle_deg, left_out);
    if (lattice.left_out() > 0) notes.push_back(path + ": " + left_out);
    all.insert(all.end(), lattice.lines.begin(), lattice.lines.end());
    inputs->push_back(path);
  }
  calib::ScaleFitOptions fo;
  fo.fit_distortion = o.fit_distortion;
  calib::ScaleCalibration cal = calib::FitMicrometerScale(all, o.pitch_um, fo);
  for (const std::string& note : notes) cal.message += "; " + note;
  const double s = cal.scale_um_per_px;
  if (o.expect_scale_um_per_px && std::abs(s / *o.expect_scale_um_per_px - 1) > 0.25) {
    throw std::invalid_argument(fmt::format(
        "--pitch-um {} does not fit the line spacing: it gives {:.4g} µm/px, far from the expected "
        "{:.4g} µm/px",
        o.pitch_um, s, *o.expect_scale_um_per_px));
  }
  return cal;
}

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
  const bool pins = !pins_csv.empty(), micro = !micrometer_images.empty();
  if (pins == micro)
    *why = "give either --pins CSV or --micrometer IMAGE…";
  else if (micro && !(pitch_um > 0))
    *why = "--pitch-um must be positive with --micrometer";
  else if (pins && fit_distortion)
    *why = "--distortion goes with --micrometer";
  else if (expect_scale_um_per_px && !(*expect_scale_um_per_px > 0))
    *why = "--expect-scale-um-per-px must be positive";
  else if (out.empty())
    *why = "--out is required";
  else if (pins && !CheckInputPath("--pins", pins_csv, PathExpect::kFile, why))
    return false;
  else {
    for (const std::string& image : micrometer_images)
      if (!CheckInputPath("--micrometer", image, PathExpect::kFile, why)) return false;
    return true;
  }
  return false;
}

CalibrateResult ComputeCalibration(const CalibrateCommandOptions& o) {
  std::string why;
  if (!o.Validate(&why)) throw std::invalid_argument(why);
  CalibrateResult r;
  r.calibration =
      o.pins_csv.empty() ? CalibrateFromMicrometer(o, &r.inputs) : CalibrateFromPins(o, &r.inputs);
  const double s = r.calibration.scale_um_per_px;
  if (!(s >= kMinScaleUmPerPx && s <= kMaxScaleUmPerPx)) {
    throw std::invalid_argument(fmt::format(
        "the fit gives {:.4g} µm/px, outside any microscope's {}..{} µm/px: check the {}", s,
        kMinScaleUmPerPx, kMaxScaleUmPerPx, o.pins_csv.empty() ? "--pitch-um" : "diameters"));
  }
  return r;
}

int RunCalibrate(int argc, char** argv) {
  CLI::App app{"Fit the pixel scale (µm/px) from images of pin gauges or a stage micrometer.",
               "clogscope calibrate"};
  CalibrateCommandOptions o;
  std::string roi, polarity = "auto";
  double expect = 0;
  app.add_option("--pins", o.pins_csv,
                 "CSV image,diameter_um[,tolerance_um] (paths relative to the CSV)");
  app.add_option("--micrometer", o.micrometer_images, "Stage micrometer image(s)");
  app.add_option("--pitch-um", o.pitch_um, "Micrometer line pitch");
  app.add_flag("--distortion", o.fit_distortion, "Micrometer: fit a second-order term too");
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
  if (!roi.empty()) o.pin_measure.roi = ParseRoi(roi);
  o.pin_measure.polarity = vision::ParsePolarity(polarity);
  if (app.count("--expect-scale-um-per-px")) o.expect_scale_um_per_px = expect;
  const CalibrateResult r = ComputeCalibration(o);
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
  std::string why;
  if (!PlotToPng(spec, plot_path, &why)) spdlog::warn("residual plot not drawn: {}", why);
  spdlog::info("wrote {}", o.out);
  return 0;
}

}  // namespace clogscope::apps
