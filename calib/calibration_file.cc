#include "calib/calibration_file.h"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "common/atomic_file.h"
#include "common/csv.h"

namespace clogscope::calib {
namespace {

// Files written before yaml-cpp (by OpenCV's FileStorage) open with "%YAML:1.0", a directive
// only OpenCV knows; the rest is plain YAML.
std::string WithoutOpenCvDirective(const std::string& text) {
  const std::string directive = "%YAML:1.0";
  if (text.compare(0, directive.size(), directive) != 0) return text;
  const size_t eol = text.find('\n');
  return eol == std::string::npos ? std::string() : text.substr(eol + 1);
}

class Reader {
 public:
  Reader(const std::string& path, YAML::Node root) : path_(path), root_(std::move(root)) {}
  bool Has(const char* key) const { return root_[key].IsDefined() && !root_[key].IsNull(); }
  std::string Text(const char* key) const {
    const YAML::Node n = root_[key];
    if (!n.IsDefined() || n.IsNull()) return "";
    if (!n.IsScalar()) Fail(key, "expected a single value");
    return n.Scalar();
  }
  // Through the tool's one number parser: finite numbers only.
  double Number(const char* key, bool required) const {
    const YAML::Node n = root_[key];
    if (!n.IsDefined() || n.IsNull()) {
      if (required) Fail(key, "missing");
      return 0.0;
    }
    if (!n.IsScalar()) Fail(key, "expected a number");
    return ParseNumberField(n.Scalar(), path_, key);
  }
  int Whole(const char* key, bool required) const {
    const double v = Number(key, required);
    if (v != std::floor(v) || std::abs(v) > 1e9) Fail(key, "expected a whole number");
    return static_cast<int>(v);
  }
  [[noreturn]] void Fail(const char* key, const std::string& what) const {
    throw std::invalid_argument(fmt::format("{}: {}: {}", path_, key, what));
  }

 private:
  std::string path_;
  YAML::Node root_;
};

}  // namespace

void WriteCalibrationFile(const std::string& path, const ScaleCalibration& cal,
                          const Provenance& prov, const std::vector<std::string>& inputs) {
  YAML::Emitter y;
  y.SetDoublePrecision(std::numeric_limits<double>::max_digits10);
  y << YAML::BeginMap;
  y << YAML::Key << "clogscope_calibration_version" << YAML::Value << kCalibrationFileVersion;
  y << YAML::Key << "tool_version" << YAML::Value << prov.version;
  y << YAML::Key << "created_utc" << YAML::Value << prov.created_utc;
  y << YAML::Key << "command_line" << YAML::Value << prov.command_line;
  y << YAML::Key << "inputs" << YAML::Value << YAML::BeginSeq;
  for (const auto& in : inputs) y << in;
  y << YAML::EndSeq;
  y << YAML::Key << "method" << YAML::Value << cal.method;
  y << YAML::Key << "usable" << YAML::Value << static_cast<int>(cal.usable);
  y << YAML::Key << "message" << YAML::Value << cal.message;
  const std::pair<const char*, double> numbers[] = {
      {"scale_um_per_px", cal.scale_um_per_px},
      {"scale_sigma_um_per_px", cal.scale_sigma_um_per_px},
      {"edge_bias_px", cal.edge_bias_px},
      {"edge_bias_sigma_px", cal.edge_bias_sigma_px},
      {"edge_bias_fitted", static_cast<double>(cal.edge_bias_fitted)},
      {"distortion_px", cal.distortion_px},
      {"distortion_sigma_px", cal.distortion_sigma_px},
      {"distortion_fitted", static_cast<double>(cal.distortion_fitted)},
      {"rms_residual_px", cal.rms_residual_px},
      {"rms_residual_um", cal.rms_residual_um},
      {"worst_residual_px", cal.worst_residual_px},
      {"worst_residual_um", cal.worst_residual_um},
      {"outliers", static_cast<double>(cal.outliers)},
      {"targets", static_cast<double>(cal.targets)},
  };
  for (const auto& [key, value] : numbers) y << YAML::Key << key << YAML::Value << value;
  y << YAML::Key << "residuals" << YAML::Value << YAML::BeginSeq;
  for (const auto& r : cal.residuals) {
    y << YAML::BeginMap;
    y << YAML::Key << "name" << YAML::Value << r.name;
    y << YAML::Key << "nominal_um" << YAML::Value << r.nominal_um;
    y << YAML::Key << "measured_px" << YAML::Value << r.measured_px;
    y << YAML::Key << "model_px" << YAML::Value << r.model_px;
    y << YAML::Key << "residual_px" << YAML::Value << r.residual_px;
    y << YAML::Key << "residual_um" << YAML::Value << r.residual_um;
    y << YAML::Key << "outlier" << YAML::Value << static_cast<int>(r.outlier);
    y << YAML::EndMap;
  }
  y << YAML::EndSeq << YAML::EndMap;
  if (!y.good())
    throw std::invalid_argument(path + ": cannot write calibration: " + y.GetLastError());
  WriteFileAtomically(path, std::string(y.c_str()) + "\n");
}

ScaleCalibration ReadCalibrationFile(const std::string& path) {
  const std::string text = ReadFile(path);  // names the file when it cannot be read
  YAML::Node root;
  try {
    // yaml-cpp refuses nesting deeper than it can recurse safely (a throw, not a stack overflow).
    root = YAML::Load(WithoutOpenCvDirective(text));
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument(fmt::format("{}: not a calibration file (unreadable YAML, line {})",
                                            path, e.mark.line + 1));
  }
  if (!root.IsMap() || !root["clogscope_calibration_version"].IsDefined())
    throw std::invalid_argument(path + ": not a clogscope calibration file");
  const Reader r(path, root);
  const int version = r.Whole("clogscope_calibration_version", true);
  if (version != kCalibrationFileVersion) {
    throw std::invalid_argument(
        fmt::format("{}: calibration file version {}, this clogscope reads version {}", path,
                    version, kCalibrationFileVersion));
  }
  ScaleCalibration cal;
  cal.method = r.Text("method");
  cal.usable = r.Whole("usable", true) != 0;
  cal.message = r.Text("message");
  cal.scale_um_per_px = r.Number("scale_um_per_px", true);
  cal.scale_sigma_um_per_px = r.Number("scale_sigma_um_per_px", false);
  cal.edge_bias_px = r.Number("edge_bias_px", false);
  cal.edge_bias_sigma_px = r.Number("edge_bias_sigma_px", false);
  cal.edge_bias_fitted = r.Whole("edge_bias_fitted", false) != 0;
  cal.distortion_px = r.Number("distortion_px", false);
  cal.distortion_sigma_px = r.Number("distortion_sigma_px", false);
  cal.distortion_fitted = r.Whole("distortion_fitted", false) != 0;
  cal.rms_residual_px = r.Number("rms_residual_px", false);
  cal.rms_residual_um = r.Number("rms_residual_um", false);
  cal.worst_residual_px = r.Number("worst_residual_px", false);
  cal.worst_residual_um = r.Number("worst_residual_um", false);
  cal.targets = r.Whole("targets", false);
  cal.outliers = r.Whole("outliers", false);
  if (!(cal.scale_um_per_px > 0))
    throw std::invalid_argument(path + ": scale_um_per_px must be positive");
  if (!(cal.scale_sigma_um_per_px >= 0) || !(cal.edge_bias_sigma_px >= 0))
    throw std::invalid_argument(path + ": a σ must not be negative");
  if (!cal.usable)
    throw std::invalid_argument(path + ": calibration marked not usable: " + cal.message);
  return cal;
}

}  // namespace clogscope::calib
