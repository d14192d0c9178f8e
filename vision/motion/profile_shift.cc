#include "vision/motion/profile_shift.h"

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

// Interpolating cubic B-spline of a profile (Unser's recursive prefilter, pole √3 − 2), with its
// derivative. Its phase error is far below Catmull–Rom's: with Catmull–Rom the shift carried a
// bias of ~0.01 px that repeats with the fractional shift, which at a slow feed (the same
// fractional shift every frame) did not average out. Circular profiles wrap; open ones mirror
// at their ends and need 1 ≤ x < n − 2.
class Spline {
 public:
  Spline(const std::vector<double>& v, bool circular) : c_(v), circular_(circular) {
    const int n = static_cast<int>(v.size());
    if (n < 4) return;
    constexpr double z = -0.2679491924311228;  // √3 − 2
    const int terms = std::min(n, 30);         // |z|^30 < 1e-17
    double sum = 0, zk = 1;
    for (int k = 0; k < terms; ++k, zk *= z) sum += zk * c_[circular ? (n - k) % n : k];
    c_[0] = sum;
    for (int k = 1; k < n; ++k) c_[k] += z * c_[k - 1];
    if (circular) {
      double last = 0;
      zk = z;
      for (int j = 0; j < terms; ++j, zk *= z) last -= zk * c_[(n - 1 + j) % n];
      c_[n - 1] = last;
    } else {
      c_[n - 1] = z / (z * z - 1) * (c_[n - 1] + z * c_[n - 2]);
    }
    for (int k = n - 2; k >= 0; --k) c_[k] = z * (c_[k + 1] - c_[k]);
    for (double& x : c_) x *= 6;
  }

  void At(double x, double* value, double* slope) const {
    const int n = static_cast<int>(c_.size());
    const int i = static_cast<int>(std::floor(x));
    const double t = x - i, u = 1 - t, t2 = t * t, t3 = t2 * t;
    auto at = [&](int k) { return circular_ ? c_[((k % n) + n) % n] : c_[k]; };
    const double c0 = at(i - 1), c1 = at(i), c2 = at(i + 1), c3 = at(i + 2);
    *value = (c0 * u * u * u + c1 * (3 * t3 - 6 * t2 + 4) + c2 * (-3 * t3 + 3 * t2 + 3 * t + 1) +
              c3 * t3) /
             6;
    *slope =
        -0.5 * c0 * u * u + c1 * (1.5 * t2 - 2 * t) + c2 * (-1.5 * t2 + t + 0.5) + 0.5 * c3 * t2;
  }

 private:
  std::vector<double> c_;
  bool circular_;
};

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
  const Spline sa(a, circular), sb(b, circular);
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
      sa.At(xa, &va, &ga);
      sb.At(xb, &vb, &gb);
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

std::vector<double> Smooth(const std::vector<double>& v, double sigma) {
  if (!(sigma > 0)) return v;
  const int n = static_cast<int>(v.size()), r = static_cast<int>(std::ceil(3.5 * sigma));
  std::vector<double> w(2 * r + 1), out(n);
  for (int j = -r; j <= r; ++j) w[j + r] = std::exp(-0.5 * j * j / (sigma * sigma));
  for (int i = 0; i < n; ++i) {
    double sum = 0, weight = 0;
    for (int j = std::max(-r, -i); j <= std::min(r, n - 1 - i); ++j) {
      sum += w[j + r] * v[i + j];
      weight += w[j + r];
    }
    out[i] = sum / weight;
  }
  return out;
}

double StdDev(const std::vector<double>& v) {
  double m = 0, q = 0;
  for (double x : v) m += x / v.size();
  for (double x : v) q += (x - m) * (x - m);
  return v.size() > 1 ? std::sqrt(q / (v.size() - 1)) : 0.0;
}

}  // namespace clogscope::vision
