#include "model/extrusion_lag.h"

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace clogscope::model {
namespace {

std::vector<double> Grid(double t0, double t1, double dt) {
  std::vector<double> t;
  for (double x = t0; x <= t1 + 1e-12; x += dt) t.push_back(x);
  return t;
}

TEST(ExtrusionLagTest, StepResponseReaches63PercentAtK) {
  const FlowProfile p = ProfileFromMoves({0, 1}, {2, 12});
  for (double k : {0.02, 0.1, 0.3, 1.5}) {
    const auto y = OutletFlow(p, k, 0.0, std::vector<double>{0.5, 1.0, 1 + k, 1 + 3 * k});
    EXPECT_DOUBLE_EQ(y[0], 2);
    EXPECT_NEAR(y[1], 2, 1e-12);
    EXPECT_NEAR((y[2] - 2) / 10, 1 - std::exp(-1.0), 1e-12);  // 63.2 %
    EXPECT_NEAR((y[3] - 2) / 10, 1 - std::exp(-3.0), 1e-12);
  }
}

// A ramp u = m·t from 0: y = m·(t − K + K·e^(−t/K)), the textbook lag of a first-order system.
TEST(ExtrusionLagTest, RampResponseLagsByK) {
  const double k = 0.25, m = 4;
  const FlowProfile p{{0, 10}, {0, m * 10}};
  const auto t = Grid(0, 10, 0.137);
  const auto y = OutletFlow(p, k, 0.0, t);
  for (size_t i = 0; i < t.size(); ++i)
    EXPECT_NEAR(y[i], m * (t[i] - k + k * std::exp(-t[i] / k)), 1e-10) << t[i];
}

// With K_LA = K the outlet follows any positive command exactly: ramps and steps.
TEST(ExtrusionLagTest, LinearAdvanceEqualToKMakesTheOutletFollowTheCommand) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> flow(0.5, 15), dt(0.01, 0.4);
  FlowProfile p;
  double t = 0;
  for (int i = 0; i < 40; ++i) {
    p.time_s.push_back(t);
    p.flow_mm3_s.push_back(flow(rng));
    if (i % 3 == 0) {  // a step: a second knot at the same time
      p.time_s.push_back(t);
      p.flow_mm3_s.push_back(flow(rng));
    }
    t += dt(rng);
  }
  std::string why;
  ASSERT_TRUE(p.Validate(&why)) << why;
  for (double k : {0.05, 0.4}) {
    const auto times = Grid(-1, t + 1, 0.0037);
    const auto y = OutletFlow(p, k, k, times);
    for (size_t i = 0; i < times.size(); ++i) ASSERT_NEAR(y[i], p.At(times[i]), 1e-9) << times[i];
    // Without it the outlet lags visibly.
    const auto lagging = OutletFlow(p, k, 0.0, times);
    double worst = 0;
    for (size_t i = 0; i < times.size(); ++i)
      worst = std::max(worst, std::abs(lagging[i] - p.At(times[i])));
    EXPECT_GT(worst, 1.0);
  }
}

// A retraction: the linear state goes negative, the outlet stops at zero.
TEST(ExtrusionLagTest, NegativeOutletFlowIsClampedToZero) {
  const FlowProfile p = ProfileFromMoves({0, 1, 1.2, 2}, {5, -30, 0, 5});
  const double k = 0.1;
  const auto t = Grid(0, 3, 0.01);
  const auto y = OutletFlow(p, k, 0.0, t);
  bool clamped = false;
  for (size_t i = 0; i < t.size(); ++i) {
    EXPECT_GE(y[i], 0.0);
    if (t[i] > 1.05 && t[i] < 1.2) {
      // y_lin = −30 + 35·e^(−(t−1)/K) < 0 here.
      EXPECT_EQ(y[i], 0.0) << t[i];
      clamped = true;
    }
  }
  EXPECT_TRUE(clamped);
}

// Firmware's discrete form on short moves converges to the continuous linear advance.
TEST(ExtrusionLagTest, DiscreteLinearAdvanceOnShortMovesApproachesTheContinuousForm) {
  const double k = 0.2, dt = 0.001;
  std::vector<double> start, q;
  for (double t = 0; t < 2; t += dt) {
    start.push_back(t);
    q.push_back(t < 0.5 ? 2.0 : t < 1.2 ? 2.0 + 10 * (t - 0.5) : 9.0);
  }
  std::vector<double> bounds = start;
  bounds.push_back(start.back() + dt);
  const auto corrected = LinearAdvanceMoves(bounds, q, k);
  const auto y = OutletFlow(ProfileFromMoves(start, corrected), k, 0.0, Grid(0.0, 1.9, 0.05));
  const auto target = Grid(0.0, 1.9, 0.05);
  for (size_t i = 0; i < target.size(); ++i) {
    const double command = target[i] < 0.5   ? 2.0
                           : target[i] < 1.2 ? 2.0 + 10 * (target[i] - 0.5)
                                             : 9.0;
    EXPECT_NEAR(y[i], command, 0.02) << target[i];  // O(dt·slope) from the move sampling
  }
  // The extra volume telescopes: K_LA·(q_last − q_first).
  double extra = 0;
  for (size_t n = 0; n < q.size(); ++n) extra += (corrected[n] - q[n]) * dt;
  EXPECT_NEAR(extra, k * (q.back() - q.front()), 1e-9);
}

// Ceres differentiates the simulation: the Jet's dQ/dK matches a central difference.
TEST(ExtrusionLagTest, DerivativeInKMatchesFiniteDifference) {
  const FlowProfile p = ProfileFromMoves({0, 0.3, 0.9}, {1, 8, 3});
  using J = ceres::Jet<double, 2>;
  const double k = 0.17, h = 1e-6;
  const std::vector<double> t = {0.35, 0.6, 1.0, 1.4};
  std::vector<J> tj;
  for (double x : t) tj.push_back(J(x, 1));  // derivative 1 in slot 1: d/dt
  const auto yj = OutletFlow(p, J(k, 0), 0.0, tj);
  const auto up = OutletFlow(p, k + h, 0.0, t), down = OutletFlow(p, k - h, 0.0, t);
  std::vector<double> t_up = t, t_down = t;
  for (auto& x : t_up) x += h;
  for (auto& x : t_down) x -= h;
  const auto later = OutletFlow(p, k, 0.0, t_up), earlier = OutletFlow(p, k, 0.0, t_down);
  for (size_t i = 0; i < t.size(); ++i) {
    EXPECT_NEAR(yj[i].v[0], (up[i] - down[i]) / (2 * h), 1e-5);
    EXPECT_NEAR(yj[i].v[1], (later[i] - earlier[i]) / (2 * h), 1e-5);
  }
}

TEST(ExtrusionLagTest, BadProfilesAreRefused) {
  EXPECT_THROW(ProfileFromMoves({0, 1, 1}, {1, 2, 3}), std::invalid_argument);
  std::string why;
  EXPECT_FALSE((FlowProfile{{0, 2, 1}, {1, 2, 3}}.Validate(&why)));
  EXPECT_NE(why.find("goes back"), std::string::npos) << why;
  EXPECT_FALSE((FlowProfile{{}, {}}.Validate(&why)));
}

}  // namespace
}  // namespace clogscope::model
