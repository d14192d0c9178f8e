#include "pipeline/calibrate_targets.h"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <stdexcept>

#include "calib/line_lattice.h"
#include "common/atomic_file.h"
#include "common/csv.h"
#include "common/path_check.h"
#include "vision/io/video_io.h"
#include "vision/scene/micrometer.h"

namespace clogscope::pipeline {
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

calib::ScaleCalibration CalibrateFromPins(const TargetCalibrationOptions& o,
                                          std::vector<std::string>* inputs,
                                          std::vector<std::string>* notes) {
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
    notes->push_back(fmt::format("{}: {:.1f} µm pin is {:.4f} ± {:.4f} px wide ({} calipers)",
                                 row[c_img], pin.diameter_um, m.width_px, m.width_sigma_px,
                                 m.calipers_used));
    pins.push_back(pin);
    inputs->push_back(path);
  }
  return calib::FitPinScale(pins, {});
}

calib::ScaleCalibration CalibrateFromMicrometer(const TargetCalibrationOptions& o,
                                                std::vector<std::string>* inputs,
                                                std::vector<std::string>* log) {
  std::vector<calib::LineObservation> all;
  std::vector<std::string> left_out_notes;
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
    log->push_back(fmt::format("{}: {} lines, spacing {:.3f} px, tilt {:.2f}°; {}", path,
                               lattice.lines.size(), lattice.pitch_px, found.angle_deg, left_out));
    if (lattice.left_out() > 0) left_out_notes.push_back(path + ": " + left_out);
    all.insert(all.end(), lattice.lines.begin(), lattice.lines.end());
    inputs->push_back(path);
  }
  calib::ScaleFitOptions fo;
  fo.fit_distortion = o.fit_distortion;
  calib::ScaleCalibration cal = calib::FitMicrometerScale(all, o.pitch_um, fo);
  for (const std::string& note : left_out_notes) cal.message += "; " + note;
  const double s = cal.scale_um_per_px;
  if (o.expect_scale_um_per_px && std::abs(s / *o.expect_scale_um_per_px - 1) > 0.25) {
    throw std::invalid_argument(fmt::format(
        "--pitch-um {} does not fit the line spacing: it gives {:.4g} µm/px, far from the expected "
        "{:.4g} µm/px",
        o.pitch_um, s, *o.expect_scale_um_per_px));
  }
  return cal;
}

}  // namespace

bool TargetCalibrationOptions::Validate(std::string* why) const {
  const bool pins = !pins_csv.empty(), micro = !micrometer_images.empty();
  if (pins == micro)
    *why = "give either --pins CSV or --micrometer IMAGE…";
  else if (micro && !(pitch_um > 0))
    *why = "--pitch-um must be positive with --micrometer";
  else if (pins && fit_distortion)
    *why = "--distortion goes with --micrometer";
  else if (expect_scale_um_per_px && !(*expect_scale_um_per_px > 0))
    *why = "--expect-scale-um-per-px must be positive";
  else if (pins && !CheckInputPath("--pins", pins_csv, PathExpect::kFile, why))
    return false;
  else {
    for (const std::string& image : micrometer_images)
      if (!CheckInputPath("--micrometer", image, PathExpect::kFile, why)) return false;
    return true;
  }
  return false;
}

TargetCalibration CalibrateFromTargets(const TargetCalibrationOptions& o) {
  std::string why;
  if (!o.Validate(&why)) throw std::invalid_argument(why);
  TargetCalibration r;
  r.calibration = o.pins_csv.empty() ? CalibrateFromMicrometer(o, &r.inputs, &r.notes)
                                     : CalibrateFromPins(o, &r.inputs, &r.notes);
  const double s = r.calibration.scale_um_per_px;
  if (!(s >= kMinScaleUmPerPx && s <= kMaxScaleUmPerPx)) {
    throw std::invalid_argument(fmt::format(
        "the fit gives {:.4g} µm/px, outside any microscope's {}..{} µm/px: check the {}", s,
        kMinScaleUmPerPx, kMaxScaleUmPerPx, o.pins_csv.empty() ? "--pitch-um" : "diameters"));
  }
  return r;
}

}  // namespace clogscope::pipeline
