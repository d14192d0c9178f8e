#include "apps/run_command.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "apps/calibrate_command.h"
#include "apps/cli_util.h"
#include "apps/measure_command.h"
#include "calib/calibration_file.h"
#include "common/atomic_file.h"
#include "common/library_text.h"
#include "common/path_check.h"
#include "common/provenance.h"

namespace clogscope::apps {
namespace {

namespace fs = std::filesystem;

std::atomic<bool> g_cancel{false};
// The first Ctrl-C (or SIGTERM) asks to stop after the running steps, keeping them; a second one
// stops at once with the interrupted status 130 (files being written stay under .partial names).
extern "C" void OnSigint(int) {
  if (g_cancel.exchange(true)) _exit(130);
}

// Progress on stderr: a bar redrawn in place on a terminal, one log line per step otherwise.
class Progress {
 public:
  explicit Progress(int total) : tty_(isatty(STDERR_FILENO) != 0), total_(total) {}
  void Step(const pipeline::StepResult& r, int done) {
    std::lock_guard<std::mutex> lock(mu_);
    const std::string what = fmt::format(
        "step {} ({:g} °C): {}, {} valid of {} examined{}", r.spec.step, r.spec.temperature_c,
        r.status, r.n_valid, r.n_examined, r.resumed ? " (kept from the earlier run)" : "");
    if (tty_) {
      const int width = 30, filled = total_ ? width * done / total_ : width;
      std::fprintf(clogscope::ToolStderr(), "\r[%s%s] %d/%d  %-60.60s",
                   std::string(filled, '#').c_str(), std::string(width - filled, '.').c_str(), done,
                   total_, what.c_str());
      if (done == total_) std::fprintf(clogscope::ToolStderr(), "\n");
      std::fflush(clogscope::ToolStderr());
    } else {
      spdlog::info("[{}/{}] {}", done, total_, what);
    }
    if (r.status != "ok" && !r.detail.empty()) {
      if (tty_) std::fprintf(clogscope::ToolStderr(), "\n");
      spdlog::warn("step {}: {}", r.spec.step, r.detail);
    }
  }

 private:
  std::mutex mu_;
  bool tty_;
  int total_;
};

// "filament 1749.91 ± 0.07 µm (10 of 10 pairs), feed 4.502 mm/s, gear 5.001 mm/s, slip 9.98 ±
// 0.31 % (10 pairs)", or why not.
std::string FeedstockLine(const pipeline::FeedstockResult& f) {
  if (f.n_diameter == 0) return fmt::format("feedstock {}: {}", f.status, f.detail);
  std::string out =
      f.has_um ? fmt::format("filament {:.2f} ± {:.2f} µm", f.diameter_um, f.diameter_ci95_um)
               : fmt::format("filament {:.3f} px", f.diameter_px);
  out += fmt::format(" ({} of {} pairs)", f.n_diameter, f.n_pairs);
  if (f.speed_mm_s) out += fmt::format(", feed {:.3f} mm/s", *f.speed_mm_s);
  if (f.gear_mm_s) out += fmt::format(", gear {:.3f} mm/s", *f.gear_mm_s);
  if (f.slip_pct) {
    out += fmt::format(", slip {:.2f}{} % ({} pairs)", *f.slip_pct,
                       f.slip_ci95_pct ? fmt::format(" ± {:.2f}", *f.slip_ci95_pct) : "", f.n_slip);
  }
  if (f.status != "ok") out += fmt::format("; {}: {}", f.status, f.detail);
  return out;
}

std::string Summary(const ExperimentReport& rep, const Provenance& prov) {
  std::string md = fmt::format("# {}\n\nclogscope {} — {} — `{}`\n\n", rep.manifest.name,
                               prov.version, prov.created_utc, prov.command_line);
  if (rep.conversion) {
    md += fmt::format("Pixel scale ({}): {:.6f} ± {:.6f} µm/px, edge bias {:+.4f} ± {:.4f} px.\n\n",
                      rep.conversion->method, rep.conversion->scale_um_per_px,
                      rep.conversion->scale_sigma_um_per_px, rep.conversion->edge_bias_px,
                      rep.conversion->edge_bias_sigma_px);
  } else {
    md += "No pixel scale: widths in px only.\n\n";
  }
  md +=
      "| step | T °C | n | mean µm | ± 95 % CI µm | std µm | rejected | status "
      "|\n|---|---|---|---|---|---|---|---|\n";
  for (const auto& r : rep.steps) {
    md += fmt::format("| {} | {:g} | {} | {} | {} | {} | {} | {}{} |\n", r.spec.step,
                      r.spec.temperature_c, r.n_used,
                      r.has_um && r.n_used ? fmt::format("{:.2f}", r.mean_um) : "",
                      r.has_um && r.n_used ? fmt::format("{:.2f}", r.ci95_um) : "",
                      r.has_um && r.n_used ? fmt::format("{:.2f}", r.std_um) : "", r.n_rejected,
                      r.status, r.detail.empty() ? "" : ": " + r.detail);
  }
  bool feedstock_header = false;
  for (const auto& r : rep.steps) {
    if (!r.feedstock) continue;
    if (!feedstock_header) md += "\n## Feedstock (95 % CI)\n\n";
    feedstock_header = true;
    md += fmt::format("- step {}: {}\n", r.spec.step, FeedstockLine(*r.feedstock));
  }
  if (rep.prediction) {
    const auto& pr = rep.prediction->prediction;
    md += fmt::format(
        "\n## Predicted bar-mount vibration ({})\n\n| step | D µm | F_bp N | A/A0 | +% "
        "|{}\n|---|---|---|---|---|{}\n",
        rep.prediction->params.origin, pr.gain_m_s2_per_n ? " A m/s² |" : "",
        pr.gain_m_s2_per_n ? "---|" : "");
    for (const auto& s : pr.steps) {
      md += fmt::format("| {} | {:.1f} | {:.3f} | {:.4f} | {:.1f} |{}\n", s.step, s.diameter_um,
                        s.f_bp_n, s.relative_amplitude, s.amplitude_increase_pct,
                        s.amplitude_m_s2 ? fmt::format(" {:.4f} |", *s.amplitude_m_s2) : "");
    }
  }
  md += "\n## Files\n\n";
  for (const auto& f : rep.files) md += "- " + f + "\n";
  if (rep.cancelled)
    md += "\n**Interrupted**: only the steps above finished; run again with --resume.\n";
  return md;
}

}  // namespace

bool ExperimentCommandOptions::Validate(std::string* why) const {
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

namespace {

// How the manifest's feedstock is measured: as a filament (its whole straight stretch) inside its
// ROI, one frame pair per sample, with its gear when it names one. A gear needs a scale (its
// radius is in mm).
pipeline::FeedstockOptions FeedstockOptionsFor(const pipeline::Manifest& m,
                                               const std::optional<calib::ScaleCalibration>& conv,
                                               int samples) {
  const pipeline::FeedstockSpec& f = m.feedstock;
  pipeline::FeedstockOptions fo;
  fo.pairs = samples;
  // The feedstock camera's own scale, else the strand camera's (the feedstock in the same view).
  if (f.scale_um_per_px) {
    fo.conversion = pipeline::PlainScale(*f.scale_um_per_px);
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
    if (!f.gear_centre.empty()) {
      const cv::Rect c = where("gear_centre", f.gear_centre + ",1,1");
      g.centre_px = cv::Point2d(c.x, c.y);
    }
    g.outer_radius_px = f.gear_radius_mm * 1e3 / fo.conversion->scale_um_per_px;
    fo.gear = g;
    fo.gear_radius_mm = f.gear_radius_mm;
  }
  std::string why;
  if (!fo.Validate(&why)) throw std::invalid_argument(m.path + ": feedstock: " + why);
  return fo;
}

}  // namespace

ExperimentReport RunExperimentCommand(const ExperimentCommandOptions& o,
                                      std::atomic<bool>* cancel) {
  std::string why;
  if (!o.Validate(&why)) throw std::invalid_argument(why);
  ExperimentReport rep;
  rep.manifest = pipeline::LoadManifest(o.manifest);
  const pipeline::Manifest& m = rep.manifest;
  CreateOutputDirectory(o.out_dir);

  // The conversion: command line first, then the manifest; `run` calibrates when the manifest
  // names reference images.
  if (o.scale_um_per_px) {
    rep.conversion = pipeline::PlainScale(*o.scale_um_per_px);
  } else if (!o.calib_path.empty()) {
    rep.conversion = calib::ReadCalibrationFile(o.calib_path);
  } else if (o.full_pipeline &&
             (!m.calibrate_pins_csv.empty() || !m.calibrate_micrometer.empty())) {
    CalibrateCommandOptions co;
    co.pins_csv = m.calibrate_pins_csv;
    co.micrometer_images = m.calibrate_micrometer;
    co.pitch_um = m.calibrate_pitch_um;
    co.out = (fs::path(o.out_dir) / "calibration.yaml").string();
    const CalibrateResult cr = ComputeCalibration(co);
    if (!cr.calibration.usable)
      throw std::invalid_argument("calibration not usable: " + cr.calibration.message);
    calib::WriteCalibrationFile(co.out, cr.calibration, CurrentProvenance(), cr.inputs);
    rep.files.push_back(co.out);
    rep.conversion = cr.calibration;
    spdlog::info("calibrated from {} targets: {:.6f} ± {:.6f} µm/px, edge bias {:+.4f} px",
                 cr.calibration.targets, cr.calibration.scale_um_per_px,
                 cr.calibration.scale_sigma_um_per_px, cr.calibration.edge_bias_px);
  } else if (!m.calibration_file.empty()) {
    rep.conversion = calib::ReadCalibrationFile(m.calibration_file);
  } else if (m.scale_um_per_px) {
    if (!(*m.scale_um_per_px > 0))
      throw std::invalid_argument(m.path + ": scale_um_per_px must be positive");
    rep.conversion = pipeline::PlainScale(*m.scale_um_per_px);
  }

  pipeline::ExperimentOptions eo;
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
  Progress progress(static_cast<int>(m.steps.size()));
  eo.on_step = [&](const pipeline::StepResult& r, int done, int) { progress.Step(r, done); };
  rep.steps = pipeline::RunExperiment(m, eo);
  rep.cancelled = cancel && cancel->load();
  if (rep.steps.empty()) {
    if (rep.cancelled) return rep;
    throw std::invalid_argument(m.path + ": no step finished");
  }
  const auto tables = pipeline::WriteExperimentTables(m, rep.steps, eo, &rep.warnings);
  rep.files.insert(rep.files.end(), tables.begin(), tables.end());
  if (!o.full_pipeline) return rep;

  // Stopped while the tables were written: no prediction, the summary says so.
  rep.cancelled = rep.cancelled || (cancel && cancel->load());
  if (!m.extruder.empty() && !rep.cancelled) {
    PredictCommandOptions po;
    po.extruder = m.extruder;
    po.set = m.extruder_set;
    po.diameters = (fs::path(o.out_dir) / "diameters.csv").string();
    po.out_dir = (fs::path(o.out_dir) / "predict").string();
    if (!rep.conversion) {
      rep.warnings.push_back(
          "no pixel scale: the predictor needs diameters in µm; prediction skipped");
    } else {
      PredictResult pr = ComputePrediction(po);
      const auto written = WritePredictionOutputs(pr, po.out_dir, true, &rep.warnings);
      rep.files.insert(rep.files.end(), written.begin(), written.end());
      rep.prediction = std::move(pr);
    }
  }
  rep.cancelled = rep.cancelled || (cancel && cancel->load());
  const Provenance prov = CurrentProvenance();
  const std::string md_path = (fs::path(o.out_dir) / "summary.md").string();
  const std::string json_path = (fs::path(o.out_dir) / "summary.json").string();
  rep.files.push_back(md_path);
  rep.files.push_back(json_path);
  WriteFileAtomically(md_path, Summary(rep, prov));
  nlohmann::ordered_json j;
  j["experiment"] = m.name;
  j["provenance"] = {{"version", prov.version},
                     {"created_utc", prov.created_utc},
                     {"command_line", prov.command_line}};
  j["cancelled"] = rep.cancelled;
  if (rep.conversion) {
    j["scale_um_per_px"] = rep.conversion->scale_um_per_px;
    j["scale_sigma_um_per_px"] = rep.conversion->scale_sigma_um_per_px;
    j["edge_bias_px"] = rep.conversion->edge_bias_px;
  }
  auto steps = nlohmann::ordered_json::array();
  for (const auto& r : rep.steps) {
    nlohmann::ordered_json s = {{"step", r.spec.step}, {"temperature_c", r.spec.temperature_c},
                                {"n", r.n_used},       {"n_rejected", r.n_rejected},
                                {"status", r.status},  {"detail", r.detail}};
    if (r.has_um && r.n_used) {
      s["mean_um"] = r.mean_um;
      s["ci95_um"] = r.ci95_um;
      s["std_um"] = r.std_um;
    }
    steps.push_back(s);
  }
  j["steps"] = steps;
  if (rep.prediction) {
    auto pred = nlohmann::ordered_json::array();
    for (const auto& s : rep.prediction->prediction.steps) {
      pred.push_back(
          {{"step", s.step}, {"relative_amplitude", s.relative_amplitude}, {"f_bp_n", s.f_bp_n}});
    }
    j["prediction"] = pred;
  }
  j["files"] = rep.files;
  WriteFileAtomically(json_path,
                      j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
  return rep;
}

// Shared by `run` and `measure --manifest`: Ctrl-C stops after the running steps, keeping them.
int RunExperimentCli(const ExperimentCommandOptions& o) {
  g_cancel.store(false);
  std::signal(SIGINT, OnSigint);
  std::signal(SIGTERM, OnSigint);
  ExperimentReport rep = RunExperimentCommand(o, &g_cancel);
  // A Ctrl-C during the prediction or the summary counts too.
  rep.cancelled = rep.cancelled || g_cancel.load();
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
  for (const auto& w : rep.warnings) spdlog::warn("{}", w);
  fmt::print("{:>4} {:>7} {:>4} {:>10} {:>8} {:>8} {:>4}  {}\n", "step", "T °C", "n", "mean µm",
             "±95%", "std µm", "rej", "status");
  int failed = 0;
  for (const auto& r : rep.steps) {
    failed += r.status != "ok";
    if (r.has_um && r.n_used) {
      fmt::print("{:>4} {:>7.1f} {:>4} {:>10.2f} {:>8.2f} {:>8.2f} {:>4}  {}\n", r.spec.step,
                 r.spec.temperature_c, r.n_used, r.mean_um, r.ci95_um, r.std_um, r.n_rejected,
                 r.status);
    } else {
      fmt::print("{:>4} {:>7.1f} {:>4} {:>10} {:>8} {:>8} {:>4}  {}{}\n", r.spec.step,
                 r.spec.temperature_c, r.n_used,
                 r.n_used ? fmt::format("{:.3f}px", r.mean_px) : "-", "", "", r.n_rejected,
                 r.status, r.detail.empty() ? "" : ": " + r.detail);
    }
  }
  for (const auto& r : rep.steps) {
    if (r.feedstock)
      fmt::print("step {} feedstock: {}\n", r.spec.step, FeedstockLine(*r.feedstock));
  }
  spdlog::info("wrote {} file(s) in {}", rep.files.size(), o.out_dir);
  if (rep.cancelled) {
    spdlog::warn("interrupted: {} finished step(s) kept in {}; run again with --resume",
                 rep.steps.size(), o.out_dir);
    return 130;
  }
  return failed == static_cast<int>(rep.steps.size()) ? 1 : (failed ? 2 : 0);
}

int RunRun(int argc, char** argv) {
  CLI::App app{
      "Run the whole pipeline from one manifest: calibrate (when the manifest names reference "
      "images), "
      "measure every step, predict (when it names an extruder), and summarise.",
      "clogscope run"};
  ExperimentCommandOptions o;
  o.full_pipeline = true;
  int samples = 0;
  app.add_option("manifest", o.manifest, "Experiment manifest (YAML, or CSV step list)")
      ->required();
  app.add_option("--out", o.out_dir, "Output folder")->required();
  app.add_option("--samples", samples, "Valid frames per step (default: the manifest's, else 50)");
  app.add_option("--jobs", o.jobs, "Steps measured at once (default: all cores)");
  app.add_flag("--resume", o.resume, "Keep steps already measured in --out");
  app.add_option("--scale-um-per-px", o.scale_um_per_px, "Pixel scale (overrides the manifest)");
  app.add_option("--calib", o.calib_path, "Calibration file (overrides the manifest)");
  app.footer(
      "Examples:\n"
      "  clogscope run experiment.yaml --out results/\n"
      "  clogscope run experiment.yaml --out results/ --resume --jobs 2\n"
      "Outputs: calibration.yaml, frames.csv, diameters.csv/.json, diameter_vs_temperature.png,\n"
      "overlays/, steps/ (per-step results for --resume), predict/, summary.md, summary.json.\n"
      "Exit status: 0 all steps ok, 2 some steps short or failed, 1 all failed, 130 interrupted.");
  if (!ParseCommandLine(app, argc, argv)) return 0;  // --help printed
  if (samples) o.samples = samples;
  return RunExperimentCli(o);
}

}  // namespace clogscope::apps
