#include "model/roller_drive.h"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/model/reference_data.h"

namespace clogscope::model {
namespace {

// √(k_s / (0.1 k)) by hand for every roller; the study's printed column agrees within its σ except
// for #3 (Hobb-Goblin: 77 N printed, 54.8 N from its own k_s and k).
TEST(RollerDriveTest, MinimalPinchForceRecomputedForEveryRoller) {
  const double expected[] = {127.35, 111.88, 54.77, 44.33, 99.45, 128.49, 170.96};
  const bool agrees[] = {true, true, false, true, true, true, true};
  ASSERT_EQ(RollerPresets().size(), 7u);
  for (size_t i = 0; i < 7; ++i) {
    const auto m = MinimalPinchForce(RollerPresets()[i]);
    EXPECT_NEAR(m.computed_n, expected[i], 0.01) << RollerPresets()[i].name;
    EXPECT_EQ(m.agrees, agrees[i]) << RollerPresets()[i].name << ": printed " << m.printed_n
                                   << ", computed " << m.computed_n << " ± " << m.sigma_n;
  }
}

TEST(RollerDriveTest, SlipOfRoller3FromThePinchForceForm) {
  const Slip s = SlipPinchForm(RollerByName("3"), 80, 20);
  EXPECT_NEAR(s.pct, (96.0 / 6400 + 0.32) * 20, 1e-12);  // 6.70 %
  EXPECT_NEAR(s.pct, 6.70, 1e-9);
  EXPECT_NEAR(s.sigma_pct, 20 * std::hypot(3.0 / 6400, 0.01), 1e-12);
  EXPECT_NEAR(SlipPinchForm(RollerByName("3"), 80, 20, 1.5).pct, 8.20, 1e-9);  // k_p offset
  EXPECT_THROW(SlipPinchForm(RollerByName("3"), 0, 20), std::invalid_argument);
  EXPECT_THROW(SlipPinchForm(RollerByName("3"), -5, 20), std::invalid_argument);
}

TEST(RollerDriveTest, VelocityFormFallsToItsSlowAndFastLimits) {
  const auto& r1 = RollerByName("1-straight-knurl");
  EXPECT_NEAR(SlipVelocityForm(r1, 0, 10).pct, (0.14 + 0.16) * 10, 1e-12);
  EXPECT_NEAR(SlipVelocityForm(r1, 1e4, 10).pct, 0.14 * 10, 1e-12);
  EXPECT_NEAR(SlipVelocityForm(r1, 5, 10).pct, (0.14 + 0.16 * std::exp(-0.4)) * 10, 1e-12);
  // #6 and #7: no speed dependence.
  EXPECT_NEAR(SlipVelocityForm(RollerByName("6"), 0, 10).pct, 4.3, 1e-12);
  EXPECT_NEAR(SlipVelocityForm(RollerByName("6"), 9, 10).pct, 4.3, 1e-12);
}

TEST(RollerDriveTest, NamesAreFoundOrListed) {
  EXPECT_EQ(RollerByName("#3").number, 3);
  EXPECT_EQ(RollerByName("hobb-goblin").number, 3);
  EXPECT_EQ(RollerByName("3-hobb-goblin").number, 3);
  EXPECT_EQ(RollerByName("plain").number, 4);
  for (const char* bad : {"straight-knurl", "mk8", "9"}) {
    try {
      RollerByName(bad);
      ADD_FAILURE() << bad;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("7-straight-knurl"), std::string::npos) << e.what();
    }
  }
}

// Against numbers worked out by hand, not the calls PredictDrive makes: direct-pla prints 50 mm/s
// × 0.2 mm × 0.4 mm = 4 mm³/s from 1.75 mm filament, and its back-pressure at the first reference
// step is the 1.2622 N (PredictorTest.DirectPlaReferenceNumbers); roller #3 has
// k_s = 96 %·N and k = 0.32 %/N.
TEST(RollerDriveTest, ClogRaisesFeedForceAndSlip) {
  const auto p = ExtruderParams::Preset("direct-pla");
  const auto steps = testing::ReferenceSteps();
  DriveOptions o;
  o.roller = "3";
  o.pinch_force_n = 60;
  o.friction_n = 2;
  const auto d = PredictDrive(p, steps, o);
  ASSERT_EQ(d.steps.size(), steps.size());
  EXPECT_TRUE(d.velocity_form_extrapolated);  // 60 N is below the 80–130 N of the fit
  const double flow_mm3_s = 50 * 0.2 * 0.4;
  const double filament_area_mm2 = M_PI * 1.75 * 1.75 / 4;                   // 2.4053 mm²
  EXPECT_NEAR(d.filament_speed_mm_s, flow_mm3_s / filament_area_mm2, 1e-9);  // 1.6630 mm/s
  EXPECT_NEAR(d.steps[0].f_bp_n, 1.2622, 5e-5);
  EXPECT_NEAR(d.steps[0].feed_force_n, 1.2622 + 2, 5e-5);
  EXPECT_NEAR(d.steps[0].slip_pinch.pct, (96.0 / (60 * 60) + 0.32) * (1.2622 + 2), 5e-5);
  for (size_t i = 0; i < steps.size(); ++i) {
    const auto& s = d.steps[i];
    EXPECT_NEAR(s.commanded_flow_mm3_s, flow_mm3_s, 1e-9);
    EXPECT_NEAR(s.feed_force_n, s.f_bp_n + 2, 1e-12);
    EXPECT_NEAR(s.slip_pinch.pct, (96.0 / 3600 + 0.32) * s.feed_force_n, 1e-12);
    EXPECT_NEAR(s.delivered_flow_mm3_s, flow_mm3_s * (1 - s.slip_pinch.pct / 100), 1e-9);
    // The narrowing nozzle (0.400 to 0.345 mm) raises the back-pressure, so the feed force and
    // slip.
    if (i > 0) {
      EXPECT_GT(s.f_bp_n, d.steps[i - 1].f_bp_n);
      EXPECT_GT(s.slip_pinch.pct, d.steps[i - 1].slip_pinch.pct);
    }
  }
  o.pinch_force_n = 0;
  EXPECT_THROW(PredictDrive(p, steps, o), std::invalid_argument);
}

}  // namespace
}  // namespace clogscope::model
