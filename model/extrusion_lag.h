#pragma once

// Extrusion lag and linear advance (pressure-advance study): the filament between drive gear and
// nozzle is a spring against a flow-proportional nozzle resistance, so the outlet flow follows the
// commanded flow through K·dQ_out/dt + Q_out = Q_in. Equations: docs/clog-physics.md §3.
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace clogscope::model {

// A commanded flow, piecewise linear through its knots (mm³/s against s); two knots at the same
// time make a step. Before the first knot the flow is the first value (steady state), after the
// last the last value.
struct FlowProfile {
  std::vector<double> time_s;
  std::vector<double> flow_mm3_s;
  // Times ascending (equal allowed), values finite, at least one knot; else false and why.
  bool Validate(std::string* why) const;
  double At(double t_s) const;  // the right-hand value at a step
  double StartS() const { return time_s.front(); }
  double EndS() const { return time_s.back(); }
};

// Rows (t_i, q_i) where q_i holds until t_(i+1), as G-code moves do: knots with a step at every
// row. Throws std::invalid_argument when times do not increase strictly.
FlowProfile ProfileFromMoves(const std::vector<double>& start_s, const std::vector<double>& flow);

// Firmware linear advance on a move list: ΔD_n = K_LA·(ΔD⁰_n/Δt_n − ΔD⁰_(n−1)/Δt_(n−1)) + ΔD⁰_n,
// i.e. each move's rate gains K_LA·(q_n − q_(n−1))/Δt_n. `start_s` has one more entry than `flow`
// (the end of the last move). Returns the corrected rates.
std::vector<double> LinearAdvanceMoves(const std::vector<double>& start_s,
                                       const std::vector<double>& flow, double k_la_s);

namespace lag_detail {
// The state after time h on a linear input u(t) = u_a + m·(t − t_a) with inlet u + K_LA·m:
// y(h) = u(h) + (K_LA − K)·m + (y_a − u_a − (K_LA − K)·m)·exp(−h/K). Exact.
template <typename T>
T Advance(const T& y_a, const T& u_a, double m, const T& h, const T& k, double k_la) {
  using std::exp;
  const T u_b = u_a + m * h;
  const T shift = (k_la - k) * m;
  return u_b + shift + (y_a - u_a - shift) * exp(-h / k);
}
}  // namespace lag_detail

// Outlet flow at `times` (ascending) for lag K (s) and linear advance K_LA (s; 0: none), from
// steady state before the profile. With linear advance the inlet is Q + K_LA·dQ/dt: a ramp adds
// K_LA·slope, a step adds the volume K_LA·ΔQ at once (the state jumps by K_LA·ΔQ/K). A negative
// outlet flow is clamped to zero (the nozzle empties, it does not suck back); the state is not.
// T = double or ceres::Jet (K and the times may carry derivatives).
template <typename T>
std::vector<T> OutletFlow(const FlowProfile& p, const T& k, double k_la_s,
                          const std::vector<T>& times) {
  const size_t n = p.time_s.size();
  std::vector<T> out;
  out.reserve(times.size());
  size_t j = 0;  // the state is at time tc inside segment j: [t_j, t_(j+1))
  T tc = T(p.time_s[0]);
  T y = T(p.flow_mm3_s[0]);
  bool started = false;
  auto slope = [&](size_t i) {
    return i + 1 < n ? (p.flow_mm3_s[i + 1] - p.flow_mm3_s[i]) / (p.time_s[i + 1] - p.time_s[i])
                     : 0.0;
  };
  auto jumps = [&] {  // steps at the current knot: the linear advance impulse moves the state
    while (j + 1 < n && p.time_s[j + 1] == p.time_s[j]) {
      y += (k_la_s / k) * (p.flow_mm3_s[j + 1] - p.flow_mm3_s[j]);
      ++j;
    }
  };
  for (const T& t : times) {
    if (!started) {
      if (t < T(p.time_s[0])) {
        out.push_back(T(p.flow_mm3_s[0]));
        continue;
      }
      started = true;
      jumps();
    }
    if (t < tc) throw std::invalid_argument("OutletFlow: times must ascend");
    while (j + 1 < n && T(p.time_s[j + 1]) <= t) {
      const T u_a = p.flow_mm3_s[j] + slope(j) * (tc - p.time_s[j]);
      y = lag_detail::Advance(y, u_a, slope(j), T(p.time_s[j + 1]) - tc, k, k_la_s);
      tc = T(p.time_s[j + 1]);
      ++j;
      jumps();
    }
    const T u_a = p.flow_mm3_s[j] + slope(j) * (tc - p.time_s[j]);
    y = lag_detail::Advance(y, u_a, slope(j), t - tc, k, k_la_s);
    tc = t;
    out.push_back(y < T(0) ? T(0) : y);
  }
  return out;
}

// Evenly spaced times from the profile's start − 5K to its end + 5K (the response settles).
std::vector<double> SimulationTimes(const FlowProfile& p, double k_s, double dt_s);

}  // namespace clogscope::model
