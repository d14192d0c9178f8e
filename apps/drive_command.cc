#include "apps/drive_command.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <stdexcept>

#include "apps/cli_util.h"
#include "common/atomic_file.h"
#include "common/provenance.h"
#include "model/clog_physics_io.h"
#include "model/io.h"
#include "model/prediction_run.h"

namespace clogscope::apps {
namespace {

namespace fs = std::filesystem;

std::string PinchLine(const model::RollerPreset& r) {
  const auto m = model::MinimalPinchForce(r);
  return fmt::format("F_p,min {:.1f} ± {:.1f} N from k_s and k; printed {:g} N{}", m.computed_n,
                     m.sigma_n, m.printed_n,
                     m.agrees ? "" : " — DISAGREES (the printed value is not √(k_s/(0.1 k)))");
}

void PrintRollers() {
  fmt::print("{:<18} {:>7} {:>15} {:>13} {:>5} {:>5} {:>5}  {}\n", "roller", "OD mm", "k_s %·N",
             "k %/N", "a", "b", "c", "minimal pinch force");
  for (const auto& r : model::RollerPresets()) {
    auto opt = [](const std::optional<double>& v) {
      return v ? fmt::format("{:5.2f}", *v) : std::string("    —");
    };
    fmt::print("{:<18} {:>7.2f} {:>8.1f} ± {:<4.1f} {:>6.2f} ± {:<4.2f} {:>5.2f} {} {}  {}\n",
               r.name, r.outer_diameter_mm, r.k_s_pct_n, r.k_s_sigma_pct_n, r.k_pct_per_n,
               r.k_sigma_pct_per_n, r.a_pct_per_n, opt(r.b_pct_per_n), opt(r.c_s_per_mm),
               PinchLine(r));
  }
}

void PrintDrive(const model::DrivePrediction& d, const DriveCommandOptions& o) {
  fmt::print("roller {}: {}\n", d.roller.name, PinchLine(d.roller));
  if (d.pinch_below_minimum) {
    fmt::print("  pinch {:g} N is below F_p,min: slip grows with 1/F_p² — tighten the idler\n",
               o.drive.pinch_force_n);
  }
  fmt::print("commanded filament speed {:.3f} mm/s; velocity form {}\n", d.filament_speed_mm_s,
             d.velocity_form_extrapolated
                 ? fmt::format("EXTRAPOLATED (fitted for {:g}–{:g} N of pinch)",
                               model::kVelocityFormMinPinchN, model::kVelocityFormMaxPinchN)
                 : std::string("within its pinch range"));
  const bool measured = !d.steps.empty() &&
                        std::any_of(d.steps.begin(), d.steps.end(),
                                    [](const auto& s) { return s.measured_slip_pct.has_value(); });
  fmt::print("{:>4} {:>7} {:>9} {:>9} {:>9} {:>15} {:>9} {:>13}{}\n", "step", "T °C", "D µm",
             "F_bp N", "F_f N", "slip %", "slip_v %", "delivered %",
             measured ? "  measured %" : "");
  for (const auto& s : d.steps) {
    fmt::print(
        "{:>4} {:>7.1f} {:>9.1f} {:>9.3f} {:>9.3f} {:>8.3f} ± {:<5.3f} {:>9.3f} {:>13.2f}{}\n",
        s.step, s.temperature_c, s.diameter_um, s.f_bp_n, s.feed_force_n, s.slip_pinch.pct,
        s.slip_pinch.sigma_pct, s.slip_velocity.pct,
        100 * s.delivered_flow_mm3_s / s.commanded_flow_mm3_s,
        !measured             ? ""
        : s.measured_slip_pct ? fmt::format(" {:>12.3f}", *s.measured_slip_pct)
                              : fmt::format(" {:>12}", "—"));
  }
}

}  // namespace

bool DriveCommandOptions::Validate(std::string* why) const {
  if (!drive.Validate(why)) return false;
  if (feed_force_n.has_value() == !diameters.empty())
    *why = "give either --feed-force-n (one operating point) or --diameters (every step)";
  else if (feed_force_n && !(*feed_force_n >= 0))
    *why = "--feed-force-n must be ≥ 0";
  else if (filament_speed_mm_s && !(*filament_speed_mm_s >= 0))
    *why = "--filament-speed-mm-s must be ≥ 0";
  else if (!CheckTableAndExtruderPaths(diameters, extruder, why))
    return false;
  else
    return true;
  return false;
}

model::DrivePrediction ComputeDrive(const DriveCommandOptions& o) {
  std::string why;
  if (!o.Validate(&why)) throw std::invalid_argument(why);
  const model::ExtruderParams params = model::LoadExtruderWithOverrides(o.extruder, o.set);
  const auto steps =
      model::ReadDiameterTable(o.diameters, params.Get(model::Param::kReferenceTemperatureC));
  return model::PredictDrive(params, steps, o.drive,
                             model::ReadStepColumn(o.diameters, steps, "slip_pct"));
}

int RunDrive(int argc, char** argv) {
  CLI::App app{
      "Roller-drive slip against feed and pinch force (roller filament drive study): at one "
      "operating point, or per step of a diameter table with the predictor's back-pressure as "
      "the feed force.",
      "clogscope drive"};
  DriveCommandOptions o;
  bool list = false;
  app.add_flag("--list-rollers", list, "The study's rollers and their constants");
  app.add_option("--roller", o.drive.roller, "Roller: name, number or kind (see --list-rollers)")
      ->capture_default_str();
  app.add_option("--pinch-force-n", o.drive.pinch_force_n, "Pinch force F_p");
  app.add_option("--feed-force-n", o.feed_force_n, "Feed force F_f at one operating point");
  app.add_option("--filament-speed-mm-s", o.filament_speed_mm_s,
                 "Filament speed for the velocity form at that point");
  app.add_option("--diameters", o.diameters,
                 "Diameter table CSV (a slip_pct column, when present, is shown as measured)");
  app.add_option("--extruder", o.extruder, "Preset or YAML file (for --diameters)")
      ->capture_default_str();
  app.add_option("--set", o.set, "Override an extruder parameter: name=value (repeatable)");
  app.add_option("--friction-n", o.drive.friction_n,
                 "Friction added to the back-pressure force (per step)")
      ->capture_default_str();
  app.add_option("--k-p-pct", o.drive.k_p_pct, "Slip offset of the printer (test-stand k_p)")
      ->capture_default_str();
  app.add_option("--out", o.out_dir, "Write drive.csv and drive.json here (with --diameters)");
  app.footer(
      "Examples:\n"
      "  clogscope drive --list-rollers\n"
      "  clogscope drive --roller 3 --pinch-force-n 80 --feed-force-n 20\n"
      "  clogscope drive --roller hobb-goblin --pinch-force-n 60 --diameters diameters.csv "
      "--out drive/\n"
      "Equations and sources: docs/clog-physics.md §2.");
  if (!ParseCommandLine(app, argc, argv)) return 0;
  if (list) {
    PrintRollers();
    return 0;
  }
  if (!app.count("--pinch-force-n")) throw std::invalid_argument("--pinch-force-n is required");
  std::string why;
  if (!o.Validate(&why)) throw std::invalid_argument(why);
  if (o.feed_force_n) {
    const auto& roller = model::RollerByName(o.drive.roller);
    const auto s =
        model::SlipPinchForm(roller, o.drive.pinch_force_n, *o.feed_force_n, o.drive.k_p_pct);
    fmt::print("roller {}: {}\n", roller.name, PinchLine(roller));
    fmt::print("slip at F_p {:g} N, F_f {:g} N: {:.3f} ± {:.3f} % (pinch-force form)\n",
               o.drive.pinch_force_n, *o.feed_force_n, s.pct, s.sigma_pct);
    if (o.filament_speed_mm_s) {
      const auto v =
          model::SlipVelocityForm(roller, *o.filament_speed_mm_s, *o.feed_force_n, o.drive.k_p_pct);
      const bool out = !model::VelocityFormFitted(o.drive.pinch_force_n);
      fmt::print("slip at {:g} mm/s: {:.3f} % (feed-velocity form{})\n", *o.filament_speed_mm_s,
                 v.pct, out ? ", EXTRAPOLATED: fitted for 80–130 N of pinch" : "");
    }
    return 0;
  }
  const auto d = ComputeDrive(o);
  PrintDrive(d, o);
  if (o.out_dir.empty()) return 0;
  CreateOutputDirectory(o.out_dir);
  const Provenance prov = CurrentProvenance();
  const std::string csv = (fs::path(o.out_dir) / "drive.csv").string();
  const std::string json = (fs::path(o.out_dir) / "drive.json").string();
  WriteFileAtomically(csv, model::DriveCsv(d, prov));
  WriteFileAtomically(json, model::DriveJson(d, o.drive, prov));
  spdlog::info("wrote {}, {}", csv, json);
  return 0;
}

}  // namespace clogscope::apps
