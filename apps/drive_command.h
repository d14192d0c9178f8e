#pragma once

// `clogscope drive`: roller-drive slip against feed and pinch force.

#include <optional>
#include <string>
#include <vector>

#include "model/roller_drive.h"

namespace clogscope::apps {

// Parses argv (argv[0] is the subcommand name) into the options below and calls the typed
// function; returns the process exit code (main.cc dispatches to it).
int RunDrive(int argc, char** argv);

struct DriveCommandOptions {
  model::DriveOptions drive;
  std::optional<double> feed_force_n;         // one operating point
  std::optional<double> filament_speed_mm_s;  // for the velocity form at that point
  std::string diameters;                      // or every step of a diameter table
  std::string extruder = "direct-pla";
  std::vector<std::string> set;
  std::string out_dir;  // empty: print only
  bool Validate(std::string* why) const;
};

// Per-step slip from a diameter table (its slip_pct column, when present, as measured). Throws
// std::invalid_argument for bad input.
model::DrivePrediction ComputeDrive(const DriveCommandOptions& options);

}  // namespace clogscope::apps
