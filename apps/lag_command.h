#pragma once

// `clogscope lag`: extrusion lag K from video widths and a commanded flow; linear advance.

#include <optional>
#include <string>
#include <vector>

#include "model/lag_io.h"

namespace clogscope::apps {

// Parses argv (argv[0] is the subcommand name) into the options below and calls the typed
// function; returns the process exit code (main.cc dispatches to it).
int RunLag(int argc, char** argv);

struct LagCommandOptions {
  std::string commanded;  // profile CSV: time_s, flow_mm3_s or filament_speed_mm_s
  model::ProfileForm profile_form = model::ProfileForm::kMoves;
  double filament_diameter_mm = 1.75;
  std::string frames;         // measure's frames CSV: fit K to it
  std::optional<double> k_s;  // or simulate with this K
  double k_la_s = 0;          // simulation: linear advance
  double dt_s = 0.001;        // simulation step
  model::LagFitOptions fit;
  std::string out_dir = "lag-out";
  bool plots = true;
  bool Validate(std::string* why) const;
};

struct LagReport {
  model::FlowProfile commanded;
  model::WidthSeries widths;                               // fit only
  std::optional<model::LagFitSummary> fit;                 // fit only
  std::vector<double> times, outlet, outlet_with_advance;  // simulation only
};

// Fits K to the frames, or simulates; writes nothing. Throws std::invalid_argument for bad input.
LagReport ComputeLag(const LagCommandOptions& options);
// lag.json, lag_fit.csv and lag_fit.png (fit) or outlet.csv and outlet.png (simulation), each
// written atomically. Plot problems go to `warnings`.
std::vector<std::string> WriteLagOutputs(const LagReport& report, const LagCommandOptions& options,
                                         std::vector<std::string>* warnings);

}  // namespace clogscope::apps
