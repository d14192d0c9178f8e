#pragma once

// The equations of predictor.md §3–§7, templated on the scalar so that Ceres can differentiate
// them (T = double or ceres::Jet). Parameters come as an array indexed by Param.
#include <cmath>

#include "model/parameters.h"

namespace clogscope::model::physics {

constexpr double kPi = 3.14159265358979323846;
constexpr double kZeroCelsiusInK = 273.15;

template <typename T>
const T& P(const T* p, Param id) {
  return p[static_cast<int>(id)];
}

template <typename T>
struct Pressures {
  T dp1, dp2, dp3;  // zone drops at the reference temperature, Pa
  T arrhenius;      // exp(beta (1/T - 1/T0))
  T total;          // (dp1 + dp2 + dp3) · arrhenius, Pa
};

// Volumetric flow Q = print speed · layer height · D_0: the slicer's flow, unchanged by a clog.
template <typename T>
T FlowRate(const T* p) {
  return P(p, Param::kPrintSpeedMS) * P(p, Param::kLayerHeightM) * P(p, Param::kNozzleDiameterM);
}

// Wall shear stress of a power-law fluid in a tube of radius r: K (c / r³)^n, c = (3n+1)/n · Q/π.
template <typename T>
T WallShearStress(const T* p, const T& r) {
  using std::pow;
  const T& n = P(p, Param::kFlowIndex);
  const T c = (3.0 * n + 1.0) / n * FlowRate(p) / kPi;
  return P(p, Param::kConsistencyPaSn) * pow(c / (r * r * r), n);
}

// Three-zone back-pressure (§3) for an effective exit diameter (m) at a temperature (°C).
template <typename T>
Pressures<T> BackPressure(const T* p, const T& diameter_m, const T& temperature_c) {
  using std::exp;
  using std::pow;
  using std::tan;
  const T& n = P(p, Param::kFlowIndex);
  const T& k = P(p, Param::kConsistencyPaSn);
  const T& r1 = P(p, Param::kNozzleEntryRadiusM);
  const T r2 = 0.5 * diameter_m;
  const T c = (3.0 * n + 1.0) / n * FlowRate(p) / kPi;
  const T theta = 0.5 * P(p, Param::kNozzleAngleDeg) * (kPi / 180.0);
  Pressures<T> out;
  out.dp1 = 2.0 * P(p, Param::kZone1LengthM) * WallShearStress(p, r1) / r1;
  out.dp2 = 2.0 * k * pow(c, n) / (3.0 * n * tan(theta)) * (pow(r2, -3.0 * n) - pow(r1, -3.0 * n));
  out.dp3 = 2.0 * P(p, Param::kZone3LengthM) * WallShearStress(p, r2) / r2;
  const T t_k = temperature_c + kZeroCelsiusInK;
  const T t0_k = P(p, Param::kReferenceTemperatureC) + kZeroCelsiusInK;
  out.arrhenius = exp(P(p, Param::kActivationTemperatureK) * (1.0 / t_k - 1.0 / t0_k));
  out.total = (out.dp1 + out.dp2 + out.dp3) * out.arrhenius;
  return out;
}

template <typename T>
T FilamentArea(const T* p) {
  const T& d = P(p, Param::kFilamentDiameterM);
  return kPi * d * d / 4.0;
}

// Back-pressure force on the filament, N.
template <typename T>
T BackPressureForce(const T* p, const T& diameter_m, const T& temperature_c) {
  return BackPressure(p, diameter_m, temperature_c).total * FilamentArea(p);
}

// Feed force of two rollers: 2 T_z / R_rol.
template <typename T>
T FeedForce(const T* p) {
  return 2.0 * P(p, Param::kMotorTorqueNm) / P(p, Param::kDriveRollerRadiusM);
}

// Load on the bar mount (§4).
template <typename T>
T Load(const T* p, const T& f_bp, LoadModel model) {
  using std::abs;
  return model == LoadModel::kSum ? FeedForce(p) + f_bp : abs(FeedForce(p) - f_bp);
}

// Load at the nominal diameter and reference temperature: W_0.
template <typename T>
T ReferenceLoad(const T* p, LoadModel model) {
  return Load(
      p, BackPressureForce(p, P(p, Param::kNozzleDiameterM), P(p, Param::kReferenceTemperatureC)),
      model);
}

// Motor current (§7): min(I_max, I_0 + g F_bp).
template <typename T>
T MotorCurrent(const T* p, const T& f_bp) {
  const T i = P(p, Param::kCurrentOffsetMa) + P(p, Param::kCurrentGainMaPerN) * f_bp;
  return i < P(p, Param::kCurrentLimitMa) ? i : P(p, Param::kCurrentLimitMa);
}

}  // namespace clogscope::model::physics
