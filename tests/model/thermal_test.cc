#include "model/thermal.h"

#include <gtest/gtest.h>

#include <cmath>

#include "model/physics.h"
#include "tests/model/reference_data.h"

namespace clogscope::model {
namespace {

// The study's tables: the correlations must reproduce every tested point within their own fit
// error (the tables print 0.1 °C; the largest difference is 0.05 °C).
TEST(ThermalTest, CorrelationsReproduceTheTables) {
  for (Material m : {Material::kPla, Material::kAbs}) {
    for (const auto& o : CoolingDataOf(m).observations) {
      const double t4 = CoolingDataOf(m).correlation.T4C(o.velocity_m_s);
      EXPECT_NEAR(t4, o.t4_c, 0.1) << MaterialName(m) << " at " << o.velocity_m_s << " m/s";
      std::printf("%s %.3f m/s: table %.1f °C, correlation %.3f °C (%+.3f)\n", MaterialName(m),
                  o.velocity_m_s, o.t4_c, t4, t4 - o.t4_c);
    }
  }
}

TEST(ThermalTest, InverseRoundTrips) {
  for (Material m : {Material::kPla, Material::kAbs}) {
    const auto& d = CoolingDataOf(m);
    for (double v = 0.0; v <= 3.0; v += 0.0371) {
      std::string why;
      const auto back = FanVelocityForT4(d, d.correlation.T4C(v), &why);
      ASSERT_TRUE(back.has_value()) << why;
      EXPECT_NEAR(*back, v, 1e-9) << MaterialName(m);
    }
  }
}

TEST(ThermalTest, InverseRefusesTemperaturesNoVelocityGives) {
  const auto& d = CoolingDataOf(Material::kPla);
  std::string why;
  EXPECT_FALSE(FanVelocityForT4(d, 95.0, &why));  // above still air (92.9 °C)
  EXPECT_NE(why.find("still air"), std::string::npos) << why;
  EXPECT_FALSE(FanVelocityForT4(d, -3.0, &why));
  EXPECT_THROW(AssessHeatSinkTemperature(Material::kPla, 95.0), std::invalid_argument);
  EXPECT_THROW(AssessFanVelocity(Material::kPla, -0.1), std::invalid_argument);
}

TEST(ThermalTest, RiskFollowsTheStudysObservations) {
  EXPECT_EQ(AssessFanVelocity(Material::kPla, 0.571).risk, ClogRisk::kSafe);
  EXPECT_EQ(AssessFanVelocity(Material::kPla, 0.289).risk, ClogRisk::kClogRisk);
  EXPECT_EQ(AssessFanVelocity(Material::kPla, 0.112).risk, ClogRisk::kClogRisk);
  EXPECT_EQ(AssessFanVelocity(Material::kPla, 0.35).risk, ClogRisk::kMarginal);
  EXPECT_EQ(AssessFanVelocity(Material::kAbs, 0.112).risk, ClogRisk::kSafe);
  EXPECT_EQ(AssessFanVelocity(Material::kAbs, 0.08).risk, ClogRisk::kMarginal);
  EXPECT_EQ(AssessFanVelocity(Material::kAbs, 0.048).risk, ClogRisk::kClogRisk);
  // The criterion's velocity: T4 = 40 °C exactly there.
  const auto a = AssessFanVelocity(Material::kPla, 0.5);
  EXPECT_NEAR(CoolingDataOf(Material::kPla).correlation.T4C(a.min_safe_velocity_m_s), 40.0, 1e-9);
  // From a measured T4 the same verdict and the velocity that gives it.
  const auto b = AssessHeatSinkTemperature(Material::kAbs, 75.0);
  EXPECT_EQ(b.risk, ClogRisk::kMarginal);
  EXPECT_NEAR(CoolingDataOf(Material::kAbs).correlation.T4C(b.velocity_m_s), 75.0, 1e-9);
}

TEST(ThermalTest, OutsideTheTestedVelocitiesIsFlagged) {
  EXPECT_FALSE(AssessFanVelocity(Material::kPla, 0.3).extrapolated);
  EXPECT_FALSE(AssessFanVelocity(Material::kPla, 0.571).extrapolated);
  EXPECT_TRUE(AssessFanVelocity(Material::kPla, 0.05).extrapolated);
  EXPECT_TRUE(AssessFanVelocity(Material::kAbs, 1.0).extrapolated);
  EXPECT_TRUE(AssessHeatSinkTemperature(Material::kPla, 80.0).extrapolated);  // V < 0.112
}

// L_crt is the pin-ended Euler length whose buckling force π²EI/L² (I = πR⁴/4) equals the force
// ΔP·πR² the filament supplies.
TEST(ThermalTest, CriticalLengthIsWhereEulerBucklingMeetsThePressureForce) {
  const double e = 2e7, r = 0.875e-3, dp = 3.1e6;
  const double l = CriticalSoftenedLengthM(e, r, dp);
  const double pi = physics::kPi;
  const double f_cr = pi * pi * e * (pi * std::pow(r, 4) / 4) / (l * l);
  EXPECT_NEAR(f_cr / (dp * pi * r * r), 1.0, 1e-12);
  EXPECT_THROW(CriticalSoftenedLengthM(e, r, 0), std::invalid_argument);
}

// Hagen–Poiseuille is the power-law tube drop with n = 1 and K = μ: 2 l τ_w / r.
TEST(ThermalTest, HagenPoiseuilleIsTheNewtonianPowerLaw) {
  auto p = ExtruderParams::Preset("direct-pla");
  p.Set(Param::kFlowIndex, 1.0);
  p.Set(Param::kConsistencyPaSn, 100.0);
  std::array<double, kParamCount> v{};
  for (int i = 0; i < kParamCount; ++i) v[i] = p.Get(static_cast<Param>(i));
  const double r = 0.18e-3, l = 1.5e-3;
  const double power_law = 2 * l * physics::WallShearStress(v.data(), r) / r;
  EXPECT_NEAR(HagenPoiseuillePressurePa(100, physics::FlowRate(v.data()), l, r) / power_law, 1.0,
              1e-12);
}

TEST(ThermalTest, AClogShortensTheCriticalLength) {
  const auto p = ExtruderParams::Preset("direct-pla");
  SofteningOptions o;
  o.modulus_pa = 5e7;
  o.viscosity_pa_s = 100;
  const auto steps = testing::ReferenceSteps();
  const auto rows = CriticalLengths(p, steps, o);
  ASSERT_EQ(rows.size(), steps.size());
  for (size_t i = 1; i < rows.size(); ++i) {
    EXPECT_LT(rows[i].l_crt_power_law_mm, rows[i - 1].l_crt_power_law_mm);
    EXPECT_LT(rows[i].l_crt_hagen_poiseuille_mm, rows[i - 1].l_crt_hagen_poiseuille_mm);
    // ΔP_HP ∝ D⁻⁴, so L_crt ∝ D²: the ratio of two steps is exact.
    const double d_ratio = rows[i].diameter_um / rows[0].diameter_um;
    EXPECT_NEAR(rows[i].l_crt_hagen_poiseuille_mm / rows[0].l_crt_hagen_poiseuille_mm,
                d_ratio * d_ratio, 1e-12);
  }
  o.modulus_pa = 0;
  EXPECT_THROW(CriticalLengths(p, steps, o), std::invalid_argument);
}

}  // namespace
}  // namespace clogscope::model
