#pragma once

#include <array>
#include <string>
#include <vector>

namespace clogscope::model {

// Every parameter of the predictor (predictor.md §2, §5–§7), SI units, by index so that files,
// --set and fits can address any of them by name.
enum class Param : int {
  kMotorTorqueNm,
  kDriveRollerRadiusM,
  kFilamentDiameterM,
  kNozzleDiameterM,
  kNozzleEntryRadiusM,
  kZone1LengthM,
  kZone3LengthM,
  kNozzleAngleDeg,
  kPrintSpeedMS,
  kLayerHeightM,
  kConsistencyPaSn,
  kFlowIndex,
  kActivationTemperatureK,
  kReferenceTemperatureC,
  kNaturalFrequencyHz,
  kBeamLengthM,
  kBeamWidthM,
  kBeamHeightM,
  kBeamModulusPa,
  kBeamDensityKgM3,
  kDampingRatio,
  kCurrentLimitMa,
  // Optional: absent unless given (or fitted).
  kGainMS2PerN,
  kBaselineAmplitudeMS2,
  kCurrentOffsetMa,
  kCurrentGainMaPerN,
  kFilamentModulusPa,
  kUnsupportedLengthM,
  kCount
};
constexpr int kParamCount = static_cast<int>(Param::kCount);

struct ParamInfo {
  Param id;
  const char* name;  // as in files and --set
  const char* meaning;
  bool optional;        // may be absent
  double lower, upper;  // physical range: values outside are refused, fits are bounded to it
};

// All parameters in file order.
const std::vector<ParamInfo>& AllParams();
const ParamInfo& InfoOf(Param p);
// The parameter called `name` (also "gain" for gain_m_s2_per_n); throws std::invalid_argument
// listing the valid names when there is none.
Param ParamByName(const std::string& name);

// W = F_feed + F_bp (the study's measured trend) or |F_feed − F_bp| (its printed Eq. 10).
enum class LoadModel { kSum, kDifference };

// A complete parameter set.
class ExtruderParams {
 public:
  // "direct-pla" or "bowden-pla"; throws std::invalid_argument for another name.
  static ExtruderParams Preset(const std::string& name);
  static std::vector<std::string> PresetNames();

  double Get(Param p) const { return values_[static_cast<int>(p)]; }
  bool Has(Param p) const { return has_[static_cast<int>(p)]; }
  // Every value by Param index (absent optional ones are 0): the array physics.h reads.
  const std::array<double, kParamCount>& Values() const { return values_; }
  void Set(Param p, double value);
  void Unset(Param p);
  // Sets by name; "load_model" takes "sum" or "difference". Throws std::invalid_argument naming the
  // parameter for an unknown name or a value that is not a number.
  void SetByName(const std::string& name, const std::string& value);

  LoadModel load_model = LoadModel::kSum;
  std::string origin;  // preset name or file it came from, for reports

  // True when every value is finite and within its range and the geometry is consistent
  // (nozzle smaller than the entry bore); otherwise says which parameter is wrong.
  bool Validate(std::string* why) const;

 private:
  std::array<double, kParamCount> values_{};
  std::array<bool, kParamCount> has_{};
};

const char* LoadModelName(LoadModel m);

}  // namespace clogscope::model
