#pragma once

// `clogscope thermal`: hot-end cooling, clog risk, critical softened length.

#include <optional>
#include <string>
#include <vector>

#include "model/thermal.h"

namespace clogscope::apps {

// Parses argv (argv[0] is the subcommand name) into the options below and calls the typed
// function; returns the process exit code (main.cc dispatches to it).
int RunThermal(int argc, char** argv);

struct ThermalCommandOptions {
  std::string material;                  // pla or abs
  std::vector<double> fan_velocity_m_s;  // assess these
  std::vector<double> t4_c;              // and these measured heat-sink temperatures
  std::string diameters;                 // optional: L_crt at every step of a diameter table
  std::string extruder = "direct-pla";
  std::vector<std::string> set;
  std::optional<double> filament_modulus_pa;  // else the extruder's filament_modulus_pa
  std::optional<double> viscosity_pa_s;       // else the study's value for the material
  std::optional<double> hp_length_mm;         // else the exit capillary (zone 3) length
  std::string out_dir;                        // empty: print only
  bool Validate(std::string* why) const;
};

struct ThermalReport {
  std::vector<model::ThermalAssessment> assessments;
  std::optional<model::SofteningOptions> softening_options;
  std::vector<model::SofteningStep> softening;
};

// Assesses every velocity and T4 and, with a diameter table, computes L_crt per step. Throws
// std::invalid_argument naming the option or file for bad input.
ThermalReport ComputeThermal(const ThermalCommandOptions& options);

}  // namespace clogscope::apps
