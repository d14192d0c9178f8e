#include "vision/profile_shift.h"

#include <algorithm>
#include <cmath>

namespace clogscope::vision {
namespace {

// Running mean over ±r with the count of samples inside, so the ends are not pulled toward zero.
std::vector<double> BoxMean(const std::vector<double>& v, int r) {
  const int n = static_cast<int>(v.size());
  std::vector<double> prefix(n + 1, 0.0), out(n);
  for (int i = 0; i < n; ++i) prefix[i + 1] = prefix[i] + v[i];
  for (int i = 0; i < n; ++i) {
    const int lo = std::max(0, i - r), hi = std::min(n, i + r + 1);
    out[i] = (prefix[hi] - prefix[lo]) / (hi - lo);
  }
  return out;
}

// Catmull–Rom interpolation and its derivative at x; circular profiles wrap, open ones need
// 1 ≤ x < n − 2.
void Cubic(const std::vector<double>& v, double x, bool circular, double* value, double* slope) {
  const int n = static_cast<int>(v.size());
  const int i = static_cast<int>(std::floor(x));
  const double t = x - i;
  auto at = [&](int k) { return circular ? v[((k % n) + n) % n] : v[k]; };
  const double p0 = at(i - 1), p1 = at(i), p2 = at(i + 1), p3 = at(i + 2);
  const double a = -0.5 * p0 + 1.5 * p1 - 1.5 * p2 + 0.5 * p3;
  const double b = p0 - 2.5 * p1 + 2 * p2 - 0.5 * p3;
  const double c = -0.5 * p0 + 0.5 * p2;
  *value = ((a * t + b) * t + c) * t + p1;
  *slope = (3 * a * t + 2 * b) * t + c;
}

}  // namespace

WholeShift BestWholeShift(const std::vector<double>& a, const std::vector<double>& b, int limit,
                          bool circular) {
  const int n = static_cast<int>(a.size());
  WholeShift best;
  for (int k = -limit; k <= limit; ++k) {
    double ab = 0, aa = 0, bb = 0;
    const int lo = circular ? 0 : std::max(0, -k), hi = circular ? n : std::min(n, n - k);
    for (int i = lo; i < hi; ++i) {
      const double vb = b[circular ? ((i + k) % n + n) % n : i + k];
      ab += a[i] * vb;
      aa += a[i] * a[i];
      bb += vb * vb;
    }
    const double ncc = aa > 0 && bb > 0 ? ab / std::sqrt(aa * bb) : 0;
    if (ncc > best.correlation) best = {k, ncc};
  }
  return best;
}

FineShift RefineShift(const std::vector<double>& a, const std::vector<double>& b, double start,
                      bool circular) {
  // Gauss–Newton on r(x) = a(x − d/2) − b(x + d/2).
  const int n = static_cast<int>(a.size());
  double d = start, sum_g2 = 0;
  std::vector<double> residuals;
  for (int iter = 0; iter < 20; ++iter) {
    double num = 0;
    sum_g2 = 0;
    residuals.clear();
    for (int i = 0; i < n; ++i) {
      const double xa = i - 0.5 * d, xb = i + 0.5 * d;
      if (!circular && (xa < 1 || xb < 1 || xa >= n - 2 || xb >= n - 2)) continue;
      double va, ga, vb, gb;
      Cubic(a, xa, circular, &va, &ga);
      Cubic(b, xb, circular, &vb, &gb);
      const double r = va - vb, g = -0.5 * (ga + gb);  // dr/dd
      num += g * r;
      sum_g2 += g * g;
      residuals.push_back(r);
    }
    if (!(sum_g2 > 0)) break;
    const double step = -num / sum_g2;
    d += std::clamp(step, -0.5, 0.5);
    if (std::abs(step) < 1e-5) break;
  }
  const size_t m = residuals.size();
  if (m < 2 || !(sum_g2 > 0)) return {d, NAN};
  // Neighbouring residuals are correlated (the optics' blur, interpolation, a polar grid finer than
  // the pixels): the plain formula would claim too much. An AR(1) model's variance inflation
  // (1 + ρ)/(1 − ρ), ρ the lag-1 correlation of the residuals, accounts for it.
  double r2 = 0, r1 = 0;
  for (size_t i = 0; i < m; ++i) {
    r2 += residuals[i] * residuals[i];
    if (i + 1 < m) r1 += residuals[i] * residuals[i + 1];
  }
  const double rho = std::clamp(r2 > 0 ? r1 / r2 : 0.0, 0.0, 0.95);
  return {d, std::sqrt(r2 / (m - 1) / sum_g2 * (1 + rho) / (1 - rho))};
}

std::vector<double> HighPass(const std::vector<double>& v, double sigma) {
  // Three boxes of half-width r have variance 3·((2r+1)² − 1)/12 = r(r+1).
  const int r =
      std::max(1, static_cast<int>(std::lround(0.5 * (std::sqrt(1 + 4 * sigma * sigma) - 1))));
  std::vector<double> mean = BoxMean(BoxMean(BoxMean(v, r), r), r);
  for (size_t i = 0; i < v.size(); ++i) mean[i] = v[i] - mean[i];
  return mean;
}

double StdDev(const std::vector<double>& v) {
  double m = 0, q = 0;
  for (double x : v) m += x / v.size();
  for (double x : v) q += (x - m) * (x - m);
  return v.size() > 1 ? std::sqrt(q / (v.size() - 1)) : 0.0;
}

}  // namespace clogscope::vision
