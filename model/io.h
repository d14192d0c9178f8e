#pragma once

#include <optional>
#include <string>
#include <vector>

#include "common/provenance.h"
#include "model/fit.h"
#include "model/parameters.h"
#include "model/predictor.h"

namespace clogscope::model {

// The diameter table of `measure` (CSV): columns step, mean_um and optionally temperature_c (the
// reference temperature when absent); other columns are ignored. Throws std::invalid_argument
// naming the file and line for a missing column, an empty or non-numeric value, or a duplicate
// step.
std::vector<StepInput> ReadDiameterTable(const std::string& path, double default_temperature_c);

// An optional per-step column of the diameter table (e.g. slip_pct), matched to `steps` by step
// number: empty when the column is absent, else one value per step (none where the cell is empty).
// Throws std::invalid_argument naming the file and line of a value that is not a number.
std::vector<std::optional<double>> ReadStepColumn(const std::string& path,
                                                  const std::vector<StepInput>& steps,
                                                  const std::string& column);

// Measured values (CSV): amplitude_m_s2 and/or current_ma, with step or temperature_c to match the
// rows of `steps`. Throws std::invalid_argument naming the file and line on a problem.
std::vector<Measurement> ReadMeasurements(const std::string& path,
                                          const std::vector<StepInput>& steps);

// A preset name or a YAML parameter file (keys: any parameter name, `preset` for the base set,
// `load_model`). Throws std::invalid_argument naming the file and line of an unknown key or a value
// of the wrong type.
ExtruderParams LoadExtruder(const std::string& preset_or_file);
ExtruderParams ParseExtruderYaml(const std::string& text, const std::string& source_name);

// The parameter set as YAML that LoadExtruder reads back; fitted values carry their σ in a comment.
std::string ExtruderToYaml(const ExtruderParams& params, const Provenance& provenance,
                           const std::vector<FittedValue>& fitted = {});

// predictor.md §8's table.
std::string PredictionsCsv(const Prediction& prediction, const Provenance& provenance);
std::string PredictionsJson(const Prediction& prediction, const ExtruderParams& params,
                            const Provenance& provenance, const FitSummary* fit = nullptr);

}  // namespace clogscope::model
