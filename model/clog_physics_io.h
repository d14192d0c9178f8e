#pragma once

// Output files of the thermal, drive and lag commands: CSV with provenance comments, JSON with a
// provenance object, as predict's.
#include <optional>
#include <string>
#include <vector>

#include "common/provenance.h"
#include "model/lag_fit.h"
#include "model/roller_drive.h"
#include "model/thermal.h"

namespace clogscope::model {

std::string ThermalJson(const std::vector<ThermalAssessment>& assessments,
                        const std::vector<SofteningStep>& softening,
                        const std::optional<SofteningOptions>& softening_options,
                        const Provenance& provenance);
std::string SofteningCsv(const std::vector<SofteningStep>& rows, const Provenance& provenance);

std::string DriveCsv(const DrivePrediction& drive, const Provenance& provenance);
std::string DriveJson(const DrivePrediction& drive, const DriveOptions& options,
                      const Provenance& provenance);

// The fit's numbers (K ± σ, gain, offset, RMS, worst residual, outliers N of M, K_LA to set).
std::string LagFitJson(const LagFitSummary& fit, const std::string& width_unit,
                       const Provenance& provenance);
// Per frame: time, measured and fitted width, the outlet flow and command behind it, outlier.
std::string LagFitCsv(const FlowProfile& commanded, const std::vector<WidthSample>& samples,
                      const LagFitSummary& fit, const std::string& width_unit,
                      const Provenance& provenance);
// A simulation: time, command, outlet without and (when given) with linear advance.
std::string LagSimulationCsv(const FlowProfile& commanded, const std::vector<double>& times,
                             const std::vector<double>& outlet,
                             const std::vector<double>& outlet_with_advance,
                             const Provenance& provenance);

}  // namespace clogscope::model
