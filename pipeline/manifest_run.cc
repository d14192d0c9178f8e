#include "pipeline/manifest_run.h"

#include <fmt/format.h>

#include <filesystem>
#include <stdexcept>

#include "calib/calibration_file.h"
#include "common/atomic_file.h"
#include "common/path_check.h"
#include "common/provenance.h"
#include "pipeline/calibrate_targets.h"
#include "pipeline/run_summary.h"

namespace clogscope::pipeline {
namespace {

namespace fs = std::filesystem;

void Note(const ManifestRunOptions& o, const std::string& line) {
  if (o.on_note) o.on_note(line);
}

// How the manifest's feedstock is measured: as a filament (its whole straight stretch) inside its
// ROI, one frame pair per sample, with its gear when it names one. A gear needs a scale (its
// radius is in mm).
FeedstockOptions FeedstockOptionsFor(const Manifest& m,
                                     const std::optional<calib::ScaleCalibration>& conv,
                                     int samples) {
  const FeedstockSpec& f = m.feedstock;
  FeedstockOptions fo;
  fo.pairs = samples;
  // The feedstock camera's own scale, else the strand camera's (the feedstock in the same view).
  if (f.scale_um_per_px) {
    fo.conversion = PlainScale(*f.scale_um_per_px);
  } else if (!f.calibration_file.empty()) {
    fo.conversion = calib::ReadCalibrationFile(f.calibration_file);
  } else {
    fo.conversion = conv;
  }
  fo.strand.target = vision::MeasureTarget::kFilament;
  ApplyBandPx({}, fo.conversion, &fo.strand);  // a filament's default band: never a problem
  const auto where = [&](const std::string& key, const std::string& text) {
    try {
      return ParseRoi(text);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(fmt::format("{}: feedstock: {}: {}", m.path, key, e.what()));
    }
  };
  if (!f.roi.empty()) fo.strand.roi = where("roi", f.roi);
  fo.strand.polarity = vision::ParsePolarity(f.polarity);
  if (!f.gear_roi.empty()) {
    if (!fo.conversion) {
      throw std::invalid_argument(m.path +
                                  ": feedstock: gear_roi: needs a pixel scale (the gear's radius "
                                  "is in mm): give feedstock: scale_um_per_px: or calibration:");
    }
    vision::GearSpeedOptions g;
    g.roi = where("gear_roi", f.gear_roi);
    if (!f.gear_centre.empty())
      g.centre_px = cv::Point2d(ParsePoint(f.gear_centre, m.path + ": feedstock: gear_centre"));
    g.outer_radius_px = f.gear_radius_mm * 1e3 / fo.conversion->scale_um_per_px;
    fo.gear = g;
    fo.gear_radius_mm = f.gear_radius_mm;
  }
  std::string why;
  if (!fo.Validate(&why)) throw std::invalid_argument(m.path + ": feedstock: " + why);
  return fo;
}

}  // namespace

bool ManifestRunOptions::Validate(std::string* why) const {
  if (manifest.empty())
    *why = "a manifest is required";
  else if (out_dir.empty())
    *why = "--out is required";
  else if (samples && *samples < 2)
    *why = "--samples must be at least 2";
  else if (jobs < 0)
    *why = "--jobs must not be negative";
  else if (scale_um_per_px && !(*scale_um_per_px > 0))
    *why = "--scale-um-per-px must be positive";
  else if (scale_um_per_px && !calib_path.empty())
    *why = "give either --scale-um-per-px or --calib, not both";
  else if (!CheckInputPath(full_pipeline ? "" : "--manifest", manifest, PathExpect::kFile, why))
    return false;
  else if (!calib_path.empty() && !CheckInputPath("--calib", calib_path, PathExpect::kFile, why))
    return false;
  else
    return true;
  return false;
}

ManifestRunReport RunManifest(const ManifestRunOptions& o) {
  std::atomic<bool>* cancel = o.cancel;
  std::string why;
  if (!o.Validate(&why)) throw std::invalid_argument(why);
  ManifestRunReport rep;
  rep.manifest = LoadManifest(o.manifest);
  const Manifest& m = rep.manifest;
  CreateOutputDirectory(o.out_dir);

  // The conversion: command line first, then the manifest; `run` calibrates when the manifest
  // names reference images.
  if (o.scale_um_per_px) {
    rep.conversion = PlainScale(*o.scale_um_per_px);
  } else if (!o.calib_path.empty()) {
    rep.conversion = calib::ReadCalibrationFile(o.calib_path);
  } else if (o.full_pipeline &&
             (!m.calibrate_pins_csv.empty() || !m.calibrate_micrometer.empty())) {
    TargetCalibrationOptions co;
    co.pins_csv = m.calibrate_pins_csv;
    co.micrometer_images = m.calibrate_micrometer;
    co.pitch_um = m.calibrate_pitch_um;
    const std::string out = (fs::path(o.out_dir) / "calibration.yaml").string();
    const TargetCalibration cr = CalibrateFromTargets(co);
    if (!cr.calibration.usable)
      throw std::invalid_argument("calibration not usable: " + cr.calibration.message);
    calib::WriteCalibrationFile(out, cr.calibration, CurrentProvenance(), cr.inputs);
    rep.files.push_back(out);
    rep.conversion = cr.calibration;
    for (const std::string& note : cr.notes) Note(o, note);
    Note(o, fmt::format("calibrated from {} targets: {:.6f} ± {:.6f} µm/px, edge bias {:+.4f} px",
                        cr.calibration.targets, cr.calibration.scale_um_per_px,
                        cr.calibration.scale_sigma_um_per_px, cr.calibration.edge_bias_px));
  } else if (!m.calibration_file.empty()) {
    rep.conversion = calib::ReadCalibrationFile(m.calibration_file);
  } else if (m.scale_um_per_px) {
    if (!(*m.scale_um_per_px > 0))
      throw std::invalid_argument(m.path + ": scale_um_per_px must be positive");
    rep.conversion = PlainScale(*m.scale_um_per_px);
  }

  ExperimentOptions eo;
  eo.samples = o.samples.value_or(m.samples);
  eo.jobs = o.jobs;
  eo.resume = o.resume;
  eo.out_dir = o.out_dir;
  eo.conversion = rep.conversion;
  eo.cancel = cancel;
  eo.overlay_dir = o.overlay_dir;
  // The command line's measurement settings over the manifest's.
  eo.strand = o.strand;
  if (!o.roi_given) eo.strand.roi = m.roi.empty() ? cv::Rect() : ParseRoi(m.roi);
  if (!o.polarity_given) eo.strand.polarity = vision::ParsePolarity(m.polarity);
  if (!o.target_given) eo.strand.target = vision::ParseMeasureTarget(m.target);
  BandRequest manifest_band;
  manifest_band.start_um = m.band_start_um;
  manifest_band.height_um = m.band_height_um;
  manifest_band.start_um_name = m.path + ": band_start_um";
  manifest_band.height_um_name = m.path + ": band_height_um";
  ApplyBandPx(BandOver(manifest_band, o.band), rep.conversion, &eo.strand);
  if (m.feedstock.enabled) eo.feedstock = FeedstockOptionsFor(m, rep.conversion, eo.samples);
  eo.on_step = o.on_step;
  rep.steps = RunExperiment(m, eo);
  rep.cancelled = cancel && cancel->load();
  if (rep.steps.empty()) {
    if (rep.cancelled) return rep;
    throw std::invalid_argument(m.path + ": no step finished");
  }
  const auto tables = WriteExperimentTables(m, rep.steps, eo, &rep.warnings);
  rep.files.insert(rep.files.end(), tables.begin(), tables.end());
  if (!o.full_pipeline) return rep;

  // Stopped while the tables were written: no prediction, the summary says so.
  rep.cancelled = rep.cancelled || (cancel && cancel->load());
  if (!m.extruder.empty() && !rep.cancelled) {
    if (!rep.conversion) {
      rep.warnings.push_back(
          "no pixel scale: the predictor needs diameters in µm; prediction skipped");
    } else {
      const model::ExtruderParams params =
          model::LoadExtruderWithOverrides(m.extruder, m.extruder_set);
      model::PredictionRun pr = model::PredictSteps(params, PredictorSteps(rep.steps));
      const auto written = model::WritePredictionOutputs(
          pr, (fs::path(o.out_dir) / "predict").string(), true, &rep.warnings);
      rep.files.insert(rep.files.end(), written.begin(), written.end());
      rep.prediction = std::move(pr);
    }
  }
  rep.cancelled = rep.cancelled || (cancel && cancel->load());
  WriteRunSummary(o.out_dir, &rep);
  return rep;
}

std::vector<model::StepInput> PredictorSteps(const std::vector<StepResult>& steps) {
  std::vector<model::StepInput> out;
  for (const StepResult& r : steps) {
    if (r.status == model::StepStatus::kFailed) continue;  // as the table's reader skips them
    if (!(r.has_um && r.n_used > 0)) {
      throw std::invalid_argument(
          fmt::format("step {}: mean_um is missing (no diameter in µm)", r.spec.step));
    }
    model::StepInput s;
    s.step = r.spec.step;
    s.temperature_c = TableValue(r.spec.temperature_c, kTableTemperatureDecimals);
    s.diameter_m = TableValue(r.mean_um, kTableUmDecimals) * 1e-6;
    const FeedstockResult* f = r.feedstock ? &*r.feedstock : nullptr;
    if (f && f->n_diameter > 0 && f->has_um)
      s.filament_diameter_m = TableValue(f->diameter_um, kTableUmDecimals) * 1e-6;
    out.push_back(s);
  }
  if (out.empty()) throw std::invalid_argument("no step has a diameter (all failed)");
  return out;
}

}  // namespace clogscope::pipeline
