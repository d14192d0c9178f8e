#include "apps/lag_command.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <stdexcept>

#include "apps/cli_util.h"
#include "common/atomic_file.h"
#include "common/path_check.h"
#include "common/plot.h"
#include "common/provenance.h"
#include "model/clog_physics_io.h"

namespace clogscope::apps {
namespace {

namespace fs = std::filesystem;

void PrintFit(const model::LagFitSummary& f, const std::string& unit) {
  const std::string u = unit == "um" ? "µm" : "px";
  fmt::print(
      "fit {}: K = {:.5f} ± {:.2g} s, gain {:.5g} ± {:.2g} {} per mm³/s, time offset {:+.5f} ± "
      "{:.2g} s\n",
      f.usable ? "converged" : "NOT USABLE", f.k_s, f.k_sigma_s, f.gain, f.gain_sigma, u,
      f.offset_s, f.offset_sigma_s);
  fmt::print(
      "  {} of {} frames used ({} left out as outliers), RMS {:.3f} {}, worst {:+.3f} {} "
      "at {:.3f} s, {} iterations\n",
      f.samples_used, f.samples_total, f.outliers, f.rms, u, f.worst_residual, u, f.worst_time_s,
      f.iterations);
  if (f.usable) {
    fmt::print("  linear advance to set: K_LA = {:.4f} s (Klipper pressure_advance, Marlin K)\n",
               f.k_la_s);
  } else {
    fmt::print("  {}\n", f.message);
  }
}

}  // namespace

bool LagCommandOptions::Validate(std::string* why) const {
  if (commanded.empty())
    *why = "--commanded is required";
  else if (frames.empty() == !k_s.has_value())
    *why = "give either --frames (fit K to a video's widths) or --k-s (simulate)";
  else if (k_s && !(*k_s > 0))
    *why = "--k-s must be positive";
  else if (!(k_la_s >= 0))
    *why = "--k-la-s must be ≥ 0";
  else if (!(dt_s > 0))
    *why = "--dt-s must be positive";
  else if (!(filament_diameter_mm > 0))
    *why = "--filament-diameter-mm must be positive";
  else if (out_dir.empty())
    *why = "--out must not be empty";
  else if (!fit.Validate(why))
    return false;
  else if (!CheckInputPath("--commanded", commanded, PathExpect::kFile, why))
    return false;
  else if (!frames.empty() && !CheckInputPath("--frames", frames, PathExpect::kFile, why))
    return false;
  else
    return true;
  return false;
}

LagReport ComputeLag(const LagCommandOptions& o) {
  std::string why;
  if (!o.Validate(&why)) throw std::invalid_argument(why);
  LagReport r;
  r.commanded = model::ReadFlowProfile(o.commanded, o.profile_form, o.filament_diameter_mm);
  if (o.k_s) {
    r.times = model::SimulationTimes(r.commanded, *o.k_s, o.dt_s);
    r.outlet = model::OutletFlow(r.commanded, *o.k_s, 0.0, r.times);
    if (o.k_la_s > 0)
      r.outlet_with_advance = model::OutletFlow(r.commanded, *o.k_s, o.k_la_s, r.times);
    return r;
  }
  r.widths = model::ReadWidthSeries(o.frames);
  try {
    r.fit = model::FitLag(r.commanded, r.widths.samples, o.fit);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(fmt::format("{} with {}: {}", o.frames, o.commanded, e.what()));
  }
  return r;
}

std::vector<std::string> WriteLagOutputs(const LagReport& r, const LagCommandOptions& o,
                                         std::vector<std::string>* warnings) {
  CreateOutputDirectory(o.out_dir);
  const Provenance prov = CurrentProvenance();
  auto path = [&](const char* name) { return (fs::path(o.out_dir) / name).string(); };
  std::vector<std::string> written;
  auto plot = [&](const PlotSpec& spec, const char* name) {
    if (!o.plots) return;
    std::string why;
    if (PlotToPng(spec, path(name), &why))
      written.push_back(path(name));
    else
      warnings->push_back(fmt::format("{}: not drawn: {}", name, why));
  };
  if (!r.fit) {
    WriteFileAtomically(path("outlet.csv"), model::LagSimulationCsv(r.commanded, r.times, r.outlet,
                                                                    r.outlet_with_advance, prov));
    written.push_back(path("outlet.csv"));
    PlotSpec spec;
    spec.title = fmt::format("Outlet flow, first-order lag K = {:g} s", *o.k_s);
    spec.x_label = "time (s)";
    spec.y_label = "flow (mm³/s)";
    std::vector<double> command;
    for (double t : r.times) command.push_back(r.commanded.At(t));
    spec.series.push_back({"commanded", r.times, command, {}, "lines lw 2"});
    spec.series.push_back({"outlet", r.times, r.outlet, {}, "lines lw 2"});
    if (!r.outlet_with_advance.empty()) {
      spec.series.push_back({fmt::format("outlet, linear advance {:g} s", o.k_la_s),
                             r.times,
                             r.outlet_with_advance,
                             {},
                             "lines lw 2"});
    }
    plot(spec, "outlet.png");
    return written;
  }
  const auto& f = *r.fit;
  const auto& s = r.widths.samples;
  WriteFileAtomically(path("lag.json"), model::LagFitJson(f, r.widths.unit, prov));
  written.push_back(path("lag.json"));
  WriteFileAtomically(path("lag_fit.csv"),
                      model::LagFitCsv(r.commanded, s, f, r.widths.unit, prov));
  written.push_back(path("lag_fit.csv"));
  PlotSpec spec;
  spec.title = fmt::format("Width against the fitted lag: K = {:.5f} ± {:.2g} s, RMS {:.3g} {}",
                           f.k_s, f.k_sigma_s, f.rms, r.widths.unit == "um" ? "µm" : "px");
  spec.x_label = "time (s)";
  spec.y_label = fmt::format("width ({})", r.widths.unit == "um" ? "µm" : "px");
  PlotSeries measured{"measured", {}, {}, {}, "points pt 7 ps 0.6"};
  PlotSeries outliers{"left out", {}, {}, {}, "points pt 2 ps 1.2"};
  PlotSeries fitted{"gain × outlet flow (t − offset)", {}, {}, {}, "lines lw 2"};
  for (size_t i = 0; i < s.size(); ++i) {
    auto& series = f.outlier[i] ? outliers : measured;
    series.x.push_back(s[i].time_s);
    series.y.push_back(s[i].width);
    fitted.x.push_back(s[i].time_s);
    fitted.y.push_back(f.fitted_width[i]);
  }
  spec.series.push_back(measured);
  if (!outliers.x.empty()) spec.series.push_back(outliers);
  spec.series.push_back(fitted);
  plot(spec, "lag_fit.png");
  return written;
}

int RunLag(int argc, char** argv) {
  CLI::App app{
      "Extrusion lag (pressure-advance study): fit the first-order lag K of the outlet flow to a "
      "measured width series and a commanded flow profile, or simulate the outlet flow for a "
      "given K, with or without linear advance.",
      "clogscope lag"};
  LagCommandOptions o;
  std::string form = "moves";
  bool no_plots = false;
  app.add_option("--commanded", o.commanded,
                 "Profile CSV: time_s and flow_mm3_s (or filament_speed_mm_s)")
      ->required();
  app.add_option("--profile-form", form,
                 "moves: each row's flow holds until the next row; linear: linear between rows")
      ->capture_default_str();
  app.add_option("--filament-diameter-mm", o.filament_diameter_mm,
                 "Converts filament_speed_mm_s to flow")
      ->capture_default_str();
  app.add_option("--frames", o.frames, "measure's frames CSV (time_s, width): fit K");
  app.add_option("--k-s", o.k_s, "Simulate with this lag K");
  app.add_option("--k-la-s", o.k_la_s, "Simulation: linear advance K_LA")->capture_default_str();
  app.add_option("--dt-s", o.dt_s, "Simulation: time step")->capture_default_str();
  app.add_option("--max-offset-s", o.fit.max_offset_s,
                 "Fit: largest clock offset between profile and video")
      ->capture_default_str();
  app.add_option("--max-k-s", o.fit.max_k_s, "Fit: largest K considered")->capture_default_str();
  app.add_option("--out", o.out_dir, "Output directory")->capture_default_str();
  app.add_flag("--no-plots", no_plots, "Skip the PNG plots");
  app.footer(
      "Examples:\n"
      "  clogscope lag --frames frames.csv --commanded profile.csv --out lag/\n"
      "  clogscope lag --commanded profile.csv --k-s 0.1 --k-la-s 0.1 --out sim/\n"
      "Equations and sources: docs/clog-physics.md §3.");
  if (!ParseCommandLine(app, argc, argv)) return 0;
  o.profile_form = model::ParseProfileForm(form);
  o.plots = !no_plots;
  const LagReport r = ComputeLag(o);
  if (r.fit) {
    if (r.widths.skipped > 0) {
      spdlog::info("{}: {} of {} frames not valid, skipped", o.frames, r.widths.skipped,
                   r.widths.rows);
    }
    PrintFit(*r.fit, r.widths.unit);
    if (!r.fit->usable) {
      spdlog::error("fit not usable; nothing written");
      return 1;
    }
  } else {
    fmt::print("simulated {} samples of {:g} s with K = {:g} s{}\n", r.times.size(), o.dt_s, *o.k_s,
               o.k_la_s > 0 ? fmt::format(", linear advance {:g} s", o.k_la_s) : "");
  }
  std::vector<std::string> warnings;
  const auto written = WriteLagOutputs(r, o, &warnings);
  for (const auto& w : warnings) spdlog::warn("{}", w);
  spdlog::info("wrote {}", fmt::join(written, ", "));
  return 0;
}

}  // namespace clogscope::apps
