#include "calib/calibration_file.h"

#include <cmath>
#include <opencv2/core.hpp>
#include <stdexcept>

#include "common/atomic_file.h"

namespace clogscope::calib {

void WriteCalibrationFile(const std::string& path, const ScaleCalibration& cal,
                          const Provenance& prov, const std::vector<std::string>& inputs) {
  cv::FileStorage fs(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
  fs << "clogscope_calibration_version" << kCalibrationFileVersion;
  fs << "tool_version" << prov.version << "created_utc" << prov.created_utc << "command_line"
     << prov.command_line;
  fs << "inputs"
     << "[";
  for (const auto& in : inputs) fs << in;
  fs << "]";
  fs << "method" << cal.method << "usable" << static_cast<int>(cal.usable) << "message"
     << cal.message;
  fs << "scale_um_per_px" << cal.scale_um_per_px << "scale_sigma_um_per_px"
     << cal.scale_sigma_um_per_px;
  fs << "edge_bias_px" << cal.edge_bias_px << "edge_bias_sigma_px" << cal.edge_bias_sigma_px
     << "edge_bias_fitted" << static_cast<int>(cal.edge_bias_fitted);
  fs << "distortion_px" << cal.distortion_px << "distortion_sigma_px" << cal.distortion_sigma_px
     << "distortion_fitted" << static_cast<int>(cal.distortion_fitted);
  fs << "rms_residual_px" << cal.rms_residual_px << "rms_residual_um" << cal.rms_residual_um;
  fs << "worst_residual_px" << cal.worst_residual_px << "worst_residual_um"
     << cal.worst_residual_um;
  fs << "outliers" << cal.outliers << "targets" << cal.targets;
  fs << "residuals"
     << "[";
  for (const auto& r : cal.residuals) {
    fs << "{"
       << "name" << r.name << "nominal_um" << r.nominal_um << "measured_px" << r.measured_px
       << "model_px" << r.model_px << "residual_px" << r.residual_px << "residual_um"
       << r.residual_um << "outlier" << static_cast<int>(r.outlier) << "}";
  }
  fs << "]";
  WriteFileAtomically(path, fs.releaseAndGetString());
}

ScaleCalibration ReadCalibrationFile(const std::string& path) {
  const std::string text = ReadFile(path);  // names the file when it cannot be read
  cv::FileStorage fs;
  try {
    if (!fs.open(text,
                 cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML)) {
      throw std::invalid_argument(path + ": not a calibration file (unreadable YAML)");
    }
  } catch (const cv::Exception&) {
    throw std::invalid_argument(path + ": not a calibration file (unreadable YAML)");
  }
  const cv::FileNode version = fs["clogscope_calibration_version"];
  if (version.empty()) throw std::invalid_argument(path + ": not a clogscope calibration file");
  if (static_cast<int>(version) != kCalibrationFileVersion) {
    throw std::invalid_argument(
        path + ": calibration file version " + std::to_string(static_cast<int>(version)) +
        ", this clogscope reads version " + std::to_string(kCalibrationFileVersion));
  }
  ScaleCalibration cal;
  cal.method = static_cast<std::string>(fs["method"]);
  cal.usable = static_cast<int>(fs["usable"]) != 0;
  cal.message = static_cast<std::string>(fs["message"]);
  cal.scale_um_per_px = static_cast<double>(fs["scale_um_per_px"]);
  cal.scale_sigma_um_per_px = static_cast<double>(fs["scale_sigma_um_per_px"]);
  cal.edge_bias_px = static_cast<double>(fs["edge_bias_px"]);
  cal.edge_bias_sigma_px = static_cast<double>(fs["edge_bias_sigma_px"]);
  cal.edge_bias_fitted = static_cast<int>(fs["edge_bias_fitted"]) != 0;
  cal.distortion_px = static_cast<double>(fs["distortion_px"]);
  cal.rms_residual_px = static_cast<double>(fs["rms_residual_px"]);
  cal.rms_residual_um = static_cast<double>(fs["rms_residual_um"]);
  cal.targets = static_cast<int>(fs["targets"]);
  cal.outliers = static_cast<int>(fs["outliers"]);
  if (!(cal.scale_um_per_px > 0) || !std::isfinite(cal.scale_um_per_px)) {
    throw std::invalid_argument(path + ": scale_um_per_px must be positive");
  }
  if (!std::isfinite(cal.edge_bias_px) || !(cal.scale_sigma_um_per_px >= 0)) {
    throw std::invalid_argument(path +
                                ": edge_bias_px or scale_sigma_um_per_px is not a valid number");
  }
  if (!cal.usable)
    throw std::invalid_argument(path + ": calibration marked not usable: " + cal.message);
  return cal;
}

}  // namespace clogscope::calib
