#include "model/predictor.h"

#include <gtest/gtest.h>

#include <cmath>

#include "model/physics.h"
#include "tests/model/reference_data.h"

namespace clogscope::model {
namespace {

using testing::ReferenceSteps;

constexpr double kPi = 3.14159265358979323846;

std::array<double, kParamCount> Values(const ExtruderParams& p) {
  std::array<double, kParamCount> v{};
  for (int i = 0; i < kParamCount; ++i) v[i] = p.Get(static_cast<Param>(i));
  return v;
}

// For n = 1 the power-law drops are Hagen–Poiseuille's: 8 μ L Q / (π R⁴) in the cylinders, and
// its integral along the cone, 8 μ Q (R2⁻³ − R1⁻³) / (3 π tanθ).
// A step's measured feedstock diameter replaces d_f and R1 = d_f/2 for that step only: its
// prediction equals one made with an extruder of that filament, the other steps and W_0 stay.
TEST(PredictorTest, MeasuredFilamentDiameterIsUsedPerStep) {
  const auto params = ExtruderParams::Preset("direct-pla");
  auto steps = ReferenceSteps();
  steps[3].filament_diameter_m = 1.80e-3;
  const Prediction with = Predict(params, steps);
  const Prediction plain = Predict(params, ReferenceSteps());
  auto thick = params;
  thick.Set(Param::kFilamentDiameterM, 1.80e-3);
  thick.Set(Param::kNozzleEntryRadiusM, 0.90e-3);
  const Prediction all_thick = Predict(thick, ReferenceSteps());
  EXPECT_NEAR(with.steps[3].f_bp_n, all_thick.steps[3].f_bp_n, 1e-12 * all_thick.steps[3].f_bp_n);
  EXPECT_NEAR(with.steps[3].dp_total_pa, all_thick.steps[3].dp_total_pa, 1e-6);
  EXPECT_GT(with.steps[3].f_bp_n, plain.steps[3].f_bp_n);  // a larger area under similar pressure
  EXPECT_DOUBLE_EQ(*with.steps[3].filament_diameter_um, 1800);
  EXPECT_FALSE(with.steps[2].filament_diameter_um.has_value());
  EXPECT_DOUBLE_EQ(with.steps[2].f_bp_n, plain.steps[2].f_bp_n);
  EXPECT_DOUBLE_EQ(with.reference_load_n, plain.reference_load_n);
  steps[3].filament_diameter_m = -1;
  EXPECT_THROW(Predict(params, steps), std::invalid_argument);
}

TEST(PredictorTest, NewtonianLimitIsHagenPoiseuille) {
  ExtruderParams p = ExtruderParams::Preset("direct-pla");
  p.Set(Param::kFlowIndex, 1.0);
  const auto v = Values(p);
  const double mu = p.Get(Param::kConsistencyPaSn);
  const double q =
      p.Get(Param::kPrintSpeedMS) * p.Get(Param::kLayerHeightM) * p.Get(Param::kNozzleDiameterM);
  const double r1 = p.Get(Param::kNozzleEntryRadiusM), d = 0.37e-3, r2 = d / 2;
  const double tan_theta = std::tan(55.0 * kPi / 180);
  const auto bp = physics::BackPressure(v.data(), d, 220.0);
  EXPECT_NEAR(bp.dp1 / (8 * mu * p.Get(Param::kZone1LengthM) * q / (kPi * std::pow(r1, 4))), 1.0,
              1e-12);
  EXPECT_NEAR(bp.dp3 / (8 * mu * p.Get(Param::kZone3LengthM) * q / (kPi * std::pow(r2, 4))), 1.0,
              1e-12);
  EXPECT_NEAR(bp.dp2 / (8 * mu * q * (std::pow(r2, -3) - std::pow(r1, -3)) / (3 * kPi * tan_theta)),
              1.0, 1e-12);
}

// The cone term is the integral of dp/dz = 2 τ_w(R(z)) / R(z) along the cone, R(z) = R1 − z tanθ.
TEST(PredictorTest, ConeTermMatchesNumericalIntegration) {
  for (double n : {0.3, 0.66, 1.0, 1.4}) {
    ExtruderParams p = ExtruderParams::Preset("direct-pla");
    p.Set(Param::kFlowIndex, n);
    const auto v = Values(p);
    const double r1 = p.Get(Param::kNozzleEntryRadiusM), r2 = 0.35e-3 / 2;
    const double tan_theta = std::tan(55.0 * kPi / 180);
    // Integrate over u = ln R (the integrand is a power of R: smooth in u), composite Simpson.
    const int m = 20000;
    const double a = std::log(r2), b = std::log(r1), h = (b - a) / m;
    double sum = 0;
    for (int i = 0; i <= m; ++i) {
      const double r = std::exp(a + i * h);
      // dp = 2 τ_w(R)/R dz, dz = dR / tanθ, dR = R du.
      const double f = 2 * physics::WallShearStress(v.data(), r) / r * r / tan_theta;
      sum += f * (i == 0 || i == m ? 1 : (i % 2 ? 4 : 2));
    }
    const double numeric = sum * h / 3;
    const double closed = physics::BackPressure(v.data(), 2 * r2, 220.0).dp2;
    EXPECT_NEAR(closed / numeric, 1.0, 1e-9) << "n " << n;
  }
}

TEST(PredictorTest, ArrheniusFactorIsOneAtReferenceTemperature) {
  const ExtruderParams p = ExtruderParams::Preset("direct-pla");
  const auto v = Values(p);
  EXPECT_DOUBLE_EQ(physics::BackPressure(v.data(), 0.4e-3, 220.0).arrhenius, 1.0);
  const double expected = std::exp(17200 * (1 / (200 + 273.15) - 1 / (220 + 273.15)));
  EXPECT_NEAR(physics::BackPressure(v.data(), 0.4e-3, 200.0).arrhenius, expected, 1e-12 * expected);
}

// The reference numbers (the study's diameters, direct-pla preset).
TEST(PredictorTest, DirectPlaReferenceNumbers) {
  const Prediction pr = Predict(ExtruderParams::Preset("direct-pla"), ReferenceSteps());
  const double expected[] = {1, 1.0130, 1.0430, 1.1153, 1.3077, 1.8590};
  ASSERT_EQ(pr.steps.size(), 6u);
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(pr.steps[i].relative_amplitude, expected[i], 5e-5) << i;
  EXPECT_NEAR(pr.steps[0].f_bp_n, 1.2622, 5e-5);
  EXPECT_NEAR(pr.feed_force_n, 105.56, 0.005);
  EXPECT_NEAR(pr.steps[5].amplitude_increase_pct, 85.90, 0.005);
  EXPECT_FALSE(pr.gain_m_s2_per_n.has_value());
  EXPECT_FALSE(pr.steps[0].amplitude_m_s2.has_value());
  // Bar alone: 41 kHz for the Direct bar (predictor.md §5).
  EXPECT_NEAR(pr.beam_frequency_hz, 41046, 5);
  // The pressure behind the 1.2622 N on 1.75 mm filament (π·1.75²/4 = 2.4053 mm²): 0.5248 MPa.
  const double filament_area_m2 = M_PI * 1.75e-3 * 1.75e-3 / 4;
  EXPECT_NEAR(pr.steps[0].dp_total_pa, 1.2622 / filament_area_m2, 5e-5 / filament_area_m2);
}

TEST(PredictorTest, DifferenceModelFallsAsTheNozzleClogs) {
  ExtruderParams p = ExtruderParams::Preset("direct-pla");
  p.load_model = LoadModel::kDifference;
  const Prediction pr = Predict(p, ReferenceSteps());
  for (size_t i = 1; i < pr.steps.size(); ++i) {
    EXPECT_LT(pr.steps[i].relative_amplitude, pr.steps[i - 1].relative_amplitude);
    EXPECT_NEAR(pr.steps[i].load_n, std::abs(pr.feed_force_n - pr.steps[i].f_bp_n), 1e-9);
  }
}

TEST(PredictorTest, GainGivenOrFromBaseline) {
  ExtruderParams p = ExtruderParams::Preset("direct-pla");
  p.Set(Param::kBaselineAmplitudeMS2, 0.65);
  Prediction pr = Predict(p, ReferenceSteps());
  ASSERT_TRUE(pr.steps[0].amplitude_m_s2.has_value());
  EXPECT_NEAR(*pr.steps[0].amplitude_m_s2, 0.65, 1e-12);  // step 1 is at D_0, T_0
  EXPECT_EQ(pr.gain_source, "baseline_amplitude_m_s2");
  p.Set(Param::kGainMS2PerN, 0.01);  // a given gain wins
  pr = Predict(p, ReferenceSteps());
  EXPECT_NEAR(*pr.steps[2].amplitude_m_s2, 0.01 * pr.steps[2].load_n, 1e-12);
}

TEST(PredictorTest, SpectrumPeaksAtNaturalFrequencyWithHeightA) {
  const double fn = 203.6, a = 0.8;
  double best_f = 0, best = 0;
  for (double f = 150; f <= 250; f += 0.001) {
    const double v = SpectrumAt(f, fn, 0.002, a);
    if (v > best) {
      best = v;
      best_f = f;
    }
  }
  EXPECT_NEAR(best_f, fn, 0.01);
  EXPECT_NEAR(best / a, 1.0, 1e-5);
  EXPECT_DOUBLE_EQ(SpectrumAt(fn, fn, 0.02, a), a);
  // The prediction's grid spans f_n·[0.5, 1.5] and each step's curve peaks at its amplitude.
  const Prediction pr = Predict(ExtruderParams::Preset("bowden-pla"), ReferenceSteps());
  EXPECT_NEAR(pr.spectrum_frequency_hz.front(), 0.5 * 16.5, 1e-12);
  EXPECT_NEAR(pr.spectrum_frequency_hz.back(), 1.5 * 16.5, 1e-12);
  EXPECT_NEAR(pr.spectra[3][100], pr.steps[3].relative_amplitude, 1e-12);  // grid midpoint = f_n
}

TEST(PredictorTest, MotorCurrentSaturatesAndBucklingRatio) {
  ExtruderParams p = ExtruderParams::Preset("direct-pla");
  p.Set(Param::kCurrentOffsetMa, 300);
  p.Set(Param::kCurrentGainMaPerN, 10);
  p.Set(Param::kCurrentLimitMa, 900);
  p.Set(Param::kFilamentModulusPa, 3.5e9);
  p.Set(Param::kUnsupportedLengthM, 0.01);
  const Prediction pr = Predict(p, ReferenceSteps());
  EXPECT_NEAR(*pr.steps[0].current_ma, 300 + 10 * pr.steps[0].f_bp_n, 1e-9);
  EXPECT_NEAR(*pr.steps[5].current_ma, 900, 1e-12);  // 300 + 10·93 N saturates
  const double f_cr = kPi * kPi * 3.5e9 * (kPi * std::pow(1.75e-3, 4) / 64) / (0.01 * 0.01);
  EXPECT_NEAR(*pr.steps[4].buckling_ratio, pr.steps[4].f_bp_n / f_cr, 1e-12);
}

TEST(PredictorTest, BadStepsNameTheStep) {
  const ExtruderParams p = ExtruderParams::Preset("direct-pla");
  auto message = [&](StepInput s) {
    try {
      Predict(p, {s});
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(message({3, 200, 0.0, 7, std::nullopt}).find("step 3 (line 7)"), std::string::npos);
  EXPECT_NE(message({3, 200, -1e-4, 0, std::nullopt}).find("positive"), std::string::npos);
  EXPECT_NE(message({4, 200, 2e-3, 0, std::nullopt}).find("entry bore"), std::string::npos);
  EXPECT_NE(message({5, -273.15, 0.4e-3, 0, std::nullopt}).find("absolute zero"),
            std::string::npos);
  ExtruderParams bad = p;
  bad.Set(Param::kFlowIndex, -1);
  EXPECT_THROW(Predict(bad, ReferenceSteps()), std::invalid_argument);
}

}  // namespace
}  // namespace clogscope::model
