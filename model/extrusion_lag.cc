#include "model/extrusion_lag.h"

#include <fmt/format.h>

#include <algorithm>

namespace clogscope::model {

bool FlowProfile::Validate(std::string* why) const {
  if (time_s.empty() || time_s.size() != flow_mm3_s.size()) {
    *why = "the profile needs at least one row, with a time and a flow each";
    return false;
  }
  for (size_t i = 0; i < time_s.size(); ++i) {
    if (!std::isfinite(time_s[i]) || !std::isfinite(flow_mm3_s[i])) {
      *why = fmt::format("row {}: time and flow must be numbers", i + 1);
      return false;
    }
    if (i > 0 && time_s[i] < time_s[i - 1]) {
      *why = fmt::format("row {}: time {:g} s goes back (previous {:g} s)", i + 1, time_s[i],
                         time_s[i - 1]);
      return false;
    }
  }
  return true;
}

double FlowProfile::At(double t) const {
  if (t < time_s.front()) return flow_mm3_s.front();
  // The last knot at or before t; between it and the next the flow is linear.
  const size_t j = std::upper_bound(time_s.begin(), time_s.end(), t) - time_s.begin() - 1;
  if (j + 1 >= time_s.size()) return flow_mm3_s.back();
  const double f = (t - time_s[j]) / (time_s[j + 1] - time_s[j]);
  return flow_mm3_s[j] + f * (flow_mm3_s[j + 1] - flow_mm3_s[j]);
}

FlowProfile ProfileFromMoves(const std::vector<double>& start_s, const std::vector<double>& flow) {
  if (start_s.empty() || start_s.size() != flow.size()) {
    throw std::invalid_argument("profile: one flow per move start expected");
  }
  FlowProfile p;
  for (size_t i = 0; i < start_s.size(); ++i) {
    if (i > 0 && !(start_s[i] > start_s[i - 1])) {
      throw std::invalid_argument(
          fmt::format("profile row {}: time {:g} s does not increase", i + 1, start_s[i]));
    }
    if (i > 0) {  // the previous rate holds up to this start, then steps
      p.time_s.push_back(start_s[i]);
      p.flow_mm3_s.push_back(flow[i - 1]);
    }
    p.time_s.push_back(start_s[i]);
    p.flow_mm3_s.push_back(flow[i]);
  }
  return p;
}

std::vector<double> LinearAdvanceMoves(const std::vector<double>& start_s,
                                       const std::vector<double>& flow, double k_la_s) {
  if (start_s.size() != flow.size() + 1) {
    throw std::invalid_argument("linear advance: move boundaries must number moves + 1");
  }
  std::vector<double> out(flow.size());
  for (size_t n = 0; n < flow.size(); ++n) {
    const double dt = start_s[n + 1] - start_s[n];
    if (!(dt > 0)) throw std::invalid_argument("linear advance: every move must last > 0 s");
    const double previous = n > 0 ? flow[n - 1] : flow[0];
    out[n] = flow[n] + k_la_s * (flow[n] - previous) / dt;
  }
  return out;
}

std::vector<double> SimulationTimes(const FlowProfile& p, double k_s, double dt_s) {
  if (!(dt_s > 0)) throw std::invalid_argument("simulation step must be positive");
  const double t0 = p.StartS() - 5 * k_s, t1 = p.EndS() + 5 * k_s;
  const size_t count = static_cast<size_t>(std::floor((t1 - t0) / dt_s)) + 1;
  if (count > 10'000'000) {
    throw std::invalid_argument(fmt::format(
        "simulation: {} samples of {:g} s is too many; use a larger step", count, dt_s));
  }
  std::vector<double> t(count);
  for (size_t i = 0; i < count; ++i) t[i] = t0 + i * dt_s;
  return t;
}

}  // namespace clogscope::model
