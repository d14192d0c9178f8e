#include "model/fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "model/io.h"
#include "tests/model/reference_data.h"

namespace clogscope::model {
namespace {

using testing::ExampleAmplitudes;
using testing::ReferenceSteps;

TEST(FitTest, ExampleDataGivesAboutTwoAndAHalfPercent) {
  FitOptions o;
  o.params = {Param::kActivationTemperatureK, Param::kGainMS2PerN};
  const FitSummary s =
      FitParameters(ExtruderParams::Preset("direct-pla"), ReferenceSteps(), ExampleAmplitudes(), o);
  ASSERT_TRUE(s.usable) << s.message;
  EXPECT_NEAR(s.rms_relative, 0.025, 0.002);
  ASSERT_EQ(s.values.size(), 2u);
  EXPECT_GT(s.values[0].sigma, 0);
  EXPECT_LT(s.values[0].sigma, 0.1 * s.values[0].value);
  EXPECT_GT(s.values[1].sigma, 0);
  EXPECT_LE(s.worst_relative, 0.05);
  EXPECT_EQ(s.residuals.size(), 6u);
  // The fitted set predicts what the fit reports.
  const Prediction pr = Predict(s.fitted, ReferenceSteps());
  for (const auto& r : s.residuals) {
    EXPECT_NEAR(*pr.steps[r.step - 1].amplitude_m_s2, r.model, 1e-9);
  }
}

// Exact synthetic data from known values: the fit must find them again from another start.
TEST(FitTest, RecoversKnownParametersFromExactData) {
  ExtruderParams truth = ExtruderParams::Preset("direct-pla");
  truth.Set(Param::kActivationTemperatureK, 15000);
  truth.Set(Param::kZone3LengthM, 1.1e-3);
  truth.Set(Param::kGainMS2PerN, 0.0071);
  truth.Set(Param::kCurrentOffsetMa, 410);
  truth.Set(Param::kCurrentGainMaPerN, 3.2);
  const auto steps = ReferenceSteps();
  const Prediction pr = Predict(truth, steps);
  std::vector<Measurement> meas;
  for (const auto& r : pr.steps) {
    Measurement m;
    m.step = r.step;
    m.amplitude_m_s2 = *r.amplitude_m_s2;
    m.current_ma = *r.current_ma;
    meas.push_back(m);
  }
  ExtruderParams start =
      ExtruderParams::Preset("direct-pla");  // β 17200, L3 0.8 mm, no gain, no current law
  FitOptions o;
  o.params = {Param::kActivationTemperatureK, Param::kGainMS2PerN, Param::kCurrentOffsetMa,
              Param::kCurrentGainMaPerN};
  const FitSummary s = FitParameters(start, steps, meas, o);
  ASSERT_TRUE(s.usable) << s.message;
  EXPECT_LT(s.rms_relative, 0.3);  // L3 is wrong on purpose: the others absorb it
  o.params.push_back(Param::kZone3LengthM);
  const FitSummary full = FitParameters(start, steps, meas, o);
  ASSERT_TRUE(full.usable) << full.message;
  EXPECT_LT(full.rms_relative, 1e-8);
  EXPECT_NEAR(full.fitted.Get(Param::kActivationTemperatureK), 15000, 1e-3);
  EXPECT_NEAR(full.fitted.Get(Param::kZone3LengthM), 1.1e-3, 1e-10);
  EXPECT_NEAR(full.fitted.Get(Param::kGainMS2PerN), 0.0071, 1e-9);
  EXPECT_NEAR(full.fitted.Get(Param::kCurrentOffsetMa), 410, 1e-4);
  EXPECT_NEAR(full.fitted.Get(Param::kCurrentGainMaPerN), 3.2, 1e-7);
}

// σ must mean something: on noisy data its average agrees with the spread of the fitted values.
TEST(FitTest, SigmaMatchesSpreadOverNoisyRepeats) {
  ExtruderParams truth = ExtruderParams::Preset("direct-pla");
  truth.Set(Param::kGainMS2PerN, 0.006);
  const auto steps = ReferenceSteps();
  const Prediction pr = Predict(truth, steps);
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0, 0.02);
  FitOptions o;
  o.params = {Param::kActivationTemperatureK, Param::kGainMS2PerN};
  double s1 = 0, s2 = 0, sig = 0;
  const int n = 200;
  for (int i = 0; i < n; ++i) {
    std::vector<Measurement> meas;
    for (const auto& r : pr.steps) {
      Measurement m;
      m.step = r.step;
      m.amplitude_m_s2 = *r.amplitude_m_s2 * (1 + noise(rng));
      meas.push_back(m);
    }
    const FitSummary s = FitParameters(ExtruderParams::Preset("direct-pla"), steps, meas, o);
    ASSERT_TRUE(s.usable);
    s1 += s.values[0].value;
    s2 += s.values[0].value * s.values[0].value;
    sig += s.values[0].sigma;
  }
  const double sd = std::sqrt(s2 / n - (s1 / n) * (s1 / n));
  // With 4 degrees of freedom the scaled σ is itself uncertain: agree within 30 %.
  EXPECT_NEAR(sig / n / sd, 1.0, 0.3);
}

TEST(FitTest, ContractViolationsThrow) {
  const auto steps = ReferenceSteps();
  const ExtruderParams p = ExtruderParams::Preset("direct-pla");
  FitOptions o;
  EXPECT_THROW(FitParameters(p, steps, ExampleAmplitudes(), o),
               std::invalid_argument);  // no unknowns
  o.params = {Param::kActivationTemperatureK};
  EXPECT_THROW(FitParameters(p, steps, ExampleAmplitudes(), o),
               std::invalid_argument);  // gain unknown
  auto two = ExampleAmplitudes();
  two.resize(2);
  o.params = {Param::kActivationTemperatureK, Param::kGainMS2PerN};
  EXPECT_THROW(FitParameters(p, steps, two, o), std::invalid_argument);  // 2 unknowns, 2 values
  auto stray = ExampleAmplitudes();
  stray[0].step = 42;
  EXPECT_THROW(FitParameters(p, steps, stray, o), std::invalid_argument);
  o.params = {Param::kGainMS2PerN, Param::kGainMS2PerN};
  EXPECT_THROW(FitParameters(p, steps, ExampleAmplitudes(), o), std::invalid_argument);
}

TEST(FitTest, InseparableUnknownsAreNotUsable) {
  // Gain and baseline scale the amplitude the same way: a flat direction.
  ExtruderParams p = ExtruderParams::Preset("direct-pla");
  p.Set(Param::kGainMS2PerN, 0.006);
  p.Set(Param::kMotorTorqueNm, 0.285);
  FitOptions o;
  o.params = {Param::kGainMS2PerN, Param::kMotorTorqueNm, Param::kDriveRollerRadiusM};
  const FitSummary s = FitParameters(p, ReferenceSteps(), ExampleAmplitudes(), o);
  EXPECT_FALSE(s.usable);
  EXPECT_FALSE(s.message.empty());
}

}  // namespace
}  // namespace clogscope::model
