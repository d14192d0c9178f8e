#include "apps/run_command.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <mutex>

#include "apps/cli_util.h"
#include "common/library_text.h"
#include "pipeline/run_summary.h"

namespace clogscope::apps {
namespace {

std::atomic<bool> g_cancel{false};
// The first Ctrl-C (or SIGTERM) asks to stop after the running steps, keeping them; a second one
// stops at once with the interrupted status 130 (files being written stay under .partial names).
extern "C" void OnSigint(int) {
  if (g_cancel.exchange(true)) _exit(130);
}

// Progress on stderr: a bar redrawn in place on a terminal, one log line per step otherwise.
class Progress {
 public:
  void Step(const pipeline::StepResult& r, int done, int total) {
    std::lock_guard<std::mutex> lock(mu_);
    const std::string what =
        fmt::format("step {} ({:g} °C): {}, {} valid of {} examined{}", r.spec.step,
                    r.spec.temperature_c, model::StepStatusName(r.status), r.n_valid, r.n_examined,
                    r.resumed ? " (kept from the earlier run)" : "");
    if (tty_) {
      const int width = 30, filled = total ? width * done / total : width;
      std::fprintf(clogscope::ToolStderr(), "\r[%s%s] %d/%d  %-60.60s",
                   std::string(filled, '#').c_str(), std::string(width - filled, '.').c_str(), done,
                   total, what.c_str());
      if (done == total) std::fprintf(clogscope::ToolStderr(), "\n");
      std::fflush(clogscope::ToolStderr());
    } else {
      spdlog::info("[{}/{}] {}", done, total, what);
    }
    if (r.status != model::StepStatus::kOk && !r.detail.empty()) {
      if (tty_) std::fprintf(clogscope::ToolStderr(), "\n");
      spdlog::warn("step {}: {}", r.spec.step, r.detail);
    }
  }

 private:
  std::mutex mu_;
  const bool tty_ = isatty(STDERR_FILENO) != 0;
};

}  // namespace

// Shared by `run` and `measure --manifest`: Ctrl-C stops after the running steps, keeping them.
int RunExperimentCli(pipeline::ManifestRunOptions o) {
  Progress progress;
  o.cancel = &g_cancel;
  o.on_step = [&](const pipeline::StepResult& r, int done, int total) {
    progress.Step(r, done, total);
  };
  o.on_note = [](const std::string& line) { spdlog::info("{}", line); };
  g_cancel.store(false);
  std::signal(SIGINT, OnSigint);
  std::signal(SIGTERM, OnSigint);
  pipeline::ManifestRunReport rep = pipeline::RunManifest(o);
  // A Ctrl-C during the prediction or the summary counts too.
  rep.cancelled = rep.cancelled || g_cancel.load();
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
  for (const auto& w : rep.warnings) spdlog::warn("{}", w);
  fmt::print("{:>4} {:>7} {:>4} {:>10} {:>8} {:>8} {:>4}  {}\n", "step", "T °C", "n", "mean µm",
             "±95%", "std µm", "rej", "status");
  int failed = 0;
  for (const auto& r : rep.steps) {
    failed += r.status != model::StepStatus::kOk;
    if (r.has_um && r.n_used) {
      fmt::print("{:>4} {:>7.1f} {:>4} {:>10.2f} {:>8.2f} {:>8.2f} {:>4}  {}\n", r.spec.step,
                 r.spec.temperature_c, r.n_used, r.mean_um, r.ci95_um, r.std_um, r.n_rejected,
                 model::StepStatusName(r.status));
    } else {
      fmt::print("{:>4} {:>7.1f} {:>4} {:>10} {:>8} {:>8} {:>4}  {}{}\n", r.spec.step,
                 r.spec.temperature_c, r.n_used,
                 r.n_used ? fmt::format("{:.3f}px", r.mean_px) : "-", "", "", r.n_rejected,
                 model::StepStatusName(r.status), r.detail.empty() ? "" : ": " + r.detail);
    }
  }
  for (const auto& r : rep.steps) {
    if (r.feedstock)
      fmt::print("step {} feedstock: {}\n", r.spec.step, pipeline::FeedstockLine(*r.feedstock));
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
  pipeline::ManifestRunOptions o;
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
