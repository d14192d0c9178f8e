#pragma once

// What the profile fits (edge_fit, cylinder_fit, cylinder_track) share: the blurred step and
// blurred √d shapes with the exp under them, a small dense Levenberg–Marquardt loop, its normal
// equations and its solver. Internal to the vision module.
#include <Eigen/Dense>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

namespace clogscope::vision::fitcore {

constexpr double kInvSqrt2 = 0.70710678118654752440;
constexpr double kInvSqrt2Pi = 0.39894228040143267794;

// e^x for x ≤ 700 (0 below −700, where e^x < 1e-304; NaN for NaN), to 4e-16 relative: inline,
// without libm's call and errno. The fits' Gaussians call it for every group at every step
// (glibc's exp took ~9 % of a tracked frame's instructions, 60 a call against 38 here).
// e^x = 2^(n/32)·e^r, n the integer nearest x·32/ln 2, |r| ≤ ln 2/64, e^r by its Taylor series to
// r⁶ (the rest below 4e-18).
inline double Exp(double x) {
  assert(!(x > 700.0));
  if (!(x >= -700.0)) return x < -700.0 ? 0.0 : x;
  static constexpr double kTwoToJ32[32] = {
      0x1.0000000000000p+0, 0x1.059b0d3158574p+0, 0x1.0b5586cf9890fp+0, 0x1.11301d0125b51p+0,
      0x1.172b83c7d517bp+0, 0x1.1d4873168b9aap+0, 0x1.2387a6e756238p+0, 0x1.29e9df51fdee1p+0,
      0x1.306fe0a31b715p+0, 0x1.371a7373aa9cbp+0, 0x1.3dea64c123422p+0, 0x1.44e086061892dp+0,
      0x1.4bfdad5362a27p+0, 0x1.5342b569d4f82p+0, 0x1.5ab07dd485429p+0, 0x1.6247eb03a5585p+0,
      0x1.6a09e667f3bcdp+0, 0x1.71f75e8ec5f74p+0, 0x1.7a11473eb0187p+0, 0x1.82589994cce13p+0,
      0x1.8ace5422aa0dbp+0, 0x1.93737b0cdc5e5p+0, 0x1.9c49182a3f090p+0, 0x1.a5503b23e255dp+0,
      0x1.ae89f995ad3adp+0, 0x1.b7f76f2fb5e47p+0, 0x1.c199bdd85529cp+0, 0x1.cb720dcef9069p+0,
      0x1.d5818dcfba487p+0, 0x1.dfc97337b9b5fp+0, 0x1.ea4afa2a490dap+0, 0x1.f50765b6e4540p+0};
  constexpr double k32OverLn2 = 0x1.71547652b82fep+5;
  // ln 2/32 in two parts, the first with 20 zero bits at its end, so that n·its first is exact.
  constexpr double kLn2Over32Hi = 0x1.62e42fee00000p-6, kLn2Over32Lo = 0x1.a39ef35793c76p-38;
  // Adding 1.5·2⁵² rounds to the nearest integer and leaves it in the low bits.
  constexpr double kRound = 0x1.8p52;
  const double shifted = x * k32OverLn2 + kRound;
  const double n = shifted - kRound;
  int64_t bits;
  std::memcpy(&bits, &shifted, sizeof bits);
  const int32_t ni = static_cast<int32_t>(bits);
  const double r = (x - n * kLn2Over32Hi) - n * kLn2Over32Lo;
  const double p =
      1.0 +
      r * (1.0 + r * (0.5 + r * (1.0 / 6 + r * (1.0 / 24 + r * (1.0 / 120 + r * (1.0 / 720))))));
  const int64_t exponent = static_cast<int64_t>((ni >> 5) + 1023) << 52;
  double scale;
  std::memcpy(&scale, &exponent, sizeof scale);
  return kTwoToJ32[ni & 31] * p * scale;
}

// Phi(z) and phi(z) from one exp: Abramowitz & Stegun 7.1.26 gives erf to 1.5e-7, i.e. 2e-5 grey
// levels on a 160-level step, far below the noise; glibc's erfc costs about as much as the rest of
// a fit.
inline void StepShape(double z, double* f, double* df) {
  // Beyond 10: φ < 1e-22 and 1 − Φ < 1e-23, nothing at double precision on 1. Most of a whole
  // profile's samples lie there, and exp's underflow path (errno, ~100 ns) was 12 % of the time.
  if (std::abs(z) > 10.0) {
    *f = z > 0 ? 1.0 : 0.0;
    *df = 0.0;
    return;
  }
  const double g = Exp(-0.5 * z * z);
  *df = kInvSqrt2Pi * g;
  const double x = std::abs(z) * kInvSqrt2;
  const double t = 1.0 / (1.0 + 0.3275911 * x);
  const double poly =
      t *
      (0.254829592 + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))));
  const double half_erfc = 0.5 * poly * g;  // (1 - erf(x)) / 2
  *f = z >= 0 ? 1.0 - half_erfc : half_erfc;
}

// G(z) = ∫₀^∞ √t·φ(z − t) dt: a √d ramp starting at an edge, blurred by a unit Gaussian. Near its
// silhouette a lit cylinder of radius R shows n·v ≈ √(2d/R) at depth d, so a Lambertian object's
// brightness rises like √d from the edge inwards; this is that rise, blurred. Tabulated once and
// interpolated; past the table G ≈ √z − 1/(8 z^1.5). Also the identity the cylinder fit uses:
// ∫₀^∞ √t·(t − z)·φ(z − t) dt = G'(z) (by parts).
class BlurredSqrt {
 public:
  static const BlurredSqrt& Get();
  // G(z) and G'(z).
  void operator()(double z, double* g, double* dg) const {
    if (OffTable(z, g, dg, nullptr)) return;
    int i;
    double t;
    Locate(z, &i, &t);
    *g = Hermite(g_, dg_, i, t);
    *dg = dg_[i] + t * (dg_[i + 1] - dg_[i]);
  }
  // G, G' and G'' (G' then interpolated with its own derivative, for fits whose Jacobian needs
  // G''), past the table from the same expansion.
  void WithCurvature(double z, double* g, double* dg, double* d2g) const {
    if (OffTable(z, g, dg, d2g)) return;
    int i;
    double t;
    Locate(z, &i, &t);
    *g = Hermite(g_, dg_, i, t);
    *dg = Hermite(dg_, d2g_, i, t);
    *d2g = d2g_[i] + t * (d2g_[i + 1] - d2g_[i]);
  }

 private:
  static constexpr double kZMin = -8.0, kZMax = 60.0, kH = 0.02;
  BlurredSqrt();
  // Before the table G is 0; past it, from the expansion. Returns false inside the table.
  static bool OffTable(double z, double* g, double* dg, double* d2g) {
    if (z <= kZMin) {
      *g = *dg = 0;
      if (d2g) *d2g = 0;
      return true;
    }
    if (z < kZMax) return false;
    const double r = std::sqrt(z);
    *g = r - 1.0 / (8 * z * r);
    *dg = 0.5 / r + 3.0 / (16 * z * z * r);
    if (d2g) *d2g = -0.25 / (z * r) - 15.0 / (32 * z * z * z * r);
    return true;
  }
  static void Locate(double z, int* i, double* t) {
    const double x = (z - kZMin) / kH;
    *i = static_cast<int>(x);
    *t = x - *i;
  }
  // Cubic Hermite interpolation of table f with derivative table df between nodes i and i + 1.
  static double Hermite(const std::vector<double>& f, const std::vector<double>& df, int i,
                        double t) {
    const double t2 = t * t, t3 = t2 * t;
    return (2 * t3 - 3 * t2 + 1) * f[i] + (t3 - 2 * t2 + t) * df[i] * kH +
           (-2 * t3 + 3 * t2) * f[i + 1] + (t3 - t2) * df[i + 1] * kH;
  }
  std::vector<double> g_, dg_, d2g_;
};

template <int N>
using Mat = Eigen::Matrix<double, N, N>;
template <int N>
using Vec = Eigen::Matrix<double, N, 1>;

// A symmetric N×N system's Cholesky factor L·Lᵀ, written out for the fits' few parameters.
// Eigen's LDLT at these sizes runs its dynamic-size block kernels and pivots: ~11 % of a tracked
// frame's instructions went to it. Reads the lower triangle, as Eigen's LDLT does.
template <int N>
class SmallCholesky {
 public:
  // False when a is not positive definite to rounding (a pivot not above 0).
  bool Factor(const Mat<N>& a) {
    for (int j = 0; j < N; ++j) {
      double d = a(j, j);
      for (int k = 0; k < j; ++k) d -= l_[j][k] * l_[j][k];
      if (!(d > 0)) return false;  // NaN too
      inv_diag_[j] = 1.0 / std::sqrt(d);
      for (int i = j + 1; i < N; ++i) {
        double s = a(i, j);
        for (int k = 0; k < j; ++k) s -= l_[i][k] * l_[j][k];
        l_[i][j] = s * inv_diag_[j];
      }
    }
    return true;
  }
  // a⁻¹·b, once Factor(a) has returned true.
  Vec<N> Solve(const Vec<N>& b) const {
    double y[N];
    for (int i = 0; i < N; ++i) {
      double s = b[i];
      for (int k = 0; k < i; ++k) s -= l_[i][k] * y[k];
      y[i] = s * inv_diag_[i];
    }
    Vec<N> x;
    for (int i = N - 1; i >= 0; --i) {
      double s = y[i];
      for (int k = i + 1; k < N; ++k) s -= l_[k][i] * x[k];
      x[i] = s * inv_diag_[i];
    }
    return x;
  }

 private:
  double l_[N][N];  // below the diagonal
  double inv_diag_[N];
};

// a⁻¹·b for a symmetric a: by Cholesky where a is positive definite (a damped or regularised
// normal matrix always is but for rounding), else by Eigen's LDLT, whose pseudo-inverse of a
// singular D the callers relied on.
template <int N>
Vec<N> SolveSymmetric(const Mat<N>& a, const Vec<N>& b) {
  SmallCholesky<N> c;
  if (c.Factor(a)) return c.Solve(b);
  return a.ldlt().solve(b);
}

// Columns cols of a⁻¹ (a symmetric) from one factorisation, as SolveSymmetric: a covariance's
// columns from its normal matrix.
template <int N, int M>
Eigen::Matrix<double, N, M> InverseColumns(const Mat<N>& a, const int (&cols)[M]) {
  Eigen::Matrix<double, N, M> unit = Eigen::Matrix<double, N, M>::Zero();
  for (int m = 0; m < M; ++m) unit(cols[m], m) = 1.0;
  SmallCholesky<N> c;
  if (!c.Factor(a)) return a.ldlt().solve(unit);
  Eigen::Matrix<double, N, M> out;
  for (int m = 0; m < M; ++m) out.col(m) = c.Solve(unit.col(m));
  return out;
}
template <int N>
Vec<N> InverseColumn(const Mat<N>& a, int i) {
  return InverseColumns<N, 1>(a, {i});
}

template <int N>
struct LmResult {
  Vec<N> p;
  Mat<N> jtj;  // at p: with the cost, the parameters' covariance
  double cost = 0;
  int iterations = 0;
  bool converged = false;
};

// Levenberg–Marquardt from p. `evaluate(p, &jtj, &jtr)` returns the sum of squared residuals and
// fills the Gauss–Newton system; `bound(&p)` keeps a trial inside the model's domain;
// `small_step(delta)` says when the parameters that matter have stopped moving. Written by hand
// rather than with Ceres: the fits run ~100 times per frame in a 1 ms budget, where a dense solve
// of ≤ 8 parameters costs less than Ceres' per-problem set-up.
template <int N, typename Evaluate, typename Bound, typename SmallStep>
LmResult<N> MinimiseLm(Vec<N> p, const Evaluate& evaluate, const Bound& bound,
                       const SmallStep& small_step, int max_iterations = 30) {
  LmResult<N> out;
  Vec<N> jtr;
  double cost = evaluate(p, &out.jtj, &jtr);
  double lambda = 1e-3;
  for (int it = 0; it < max_iterations; ++it) {
    out.iterations = it + 1;
    Mat<N> a = out.jtj;
    a.diagonal() *= 1.0 + lambda;
    a.diagonal().array() += 1e-12;
    const Vec<N> delta = SolveSymmetric<N>(a, -jtr);
    Vec<N> trial = p + delta;
    bound(&trial);
    // One pass gives the trial's cost and, if it is accepted, the next step's system.
    Mat<N> trial_jtj;
    Vec<N> trial_jtr;
    const double trial_cost = evaluate(trial, &trial_jtj, &trial_jtr);
    if (trial_cost <= cost) {
      // Converged when the parameters that matter stop moving (LM converges quadratically here,
      // so what remains is far smaller), or the cost no longer falls: noisy real profiles
      // otherwise crawl along a flat valley in the nuisance parameters until the iteration cap.
      const bool done = small_step(delta) || cost - trial_cost < 1e-9 * cost;
      p = trial;
      cost = trial_cost;
      out.jtj = trial_jtj;
      jtr = trial_jtr;
      lambda = std::max(lambda * 0.2, 1e-9);
      if (done) {
        out.converged = true;
        break;
      }
    } else {
      lambda *= 8.0;
      if (lambda > 1e8) {
        // No step lowers the cost: we are at the minimum to rounding precision.
        out.converged = true;
        break;
      }
    }
  }
  out.p = p;
  out.cost = cost;
  return out;
}

// Adds one residual r with Jacobian row j (weight w) to the upper triangle of h and to g. The
// triangle is accumulated by hand: these loops are most of the measurement's time.
template <int N>
inline void Accumulate(const double* j, double r, double w, double (*h)[N], double* g) {
  for (int i = 0; i < N; ++i) {
    const double wj = w * j[i];
    g[i] += wj * r;
    for (int k = i; k < N; ++k) h[i][k] += wj * j[k];
  }
}

// The Gauss–Newton system of many weighted residuals as one matrix product: each row of the
// Jacobian and its residual are kept scaled by √w, column by column, then each entry of JᵀJ and
// Jᵀr is one vectorised dot product of two columns. For the fits over a few hundred samples (the
// lit cylinder's) this is faster than adding each row's outer product into a triangle
// (Accumulate), whose loads and stores were most of the fit's time, and than Eigen's blocked
// product, whose packing costs more than the product at 8 columns.
template <int N>
class NormalSystem {
 public:
  // For n residuals.
  explicit NormalSystem(size_t n) : j_(static_cast<Eigen::Index>(n), N), r_(n) {}
  size_t size() const { return static_cast<size_t>(r_.size()); }
  void Resize(size_t n) {
    j_.resize(static_cast<Eigen::Index>(n), N);
    r_.resize(static_cast<Eigen::Index>(n));
  }
  void Set(size_t i, const double* j, double r, double w) {
    const double s = std::sqrt(w);
    const auto row = static_cast<Eigen::Index>(i);
    for (int k = 0; k < N; ++k) j_(row, k) = s * j[k];
    r_(row) = s * r;
  }
  // All rows at once, row i as Set(i, j.row(i), r(i), w(i)).
  void SetRows(const Eigen::Matrix<double, Eigen::Dynamic, N>& j, const Eigen::ArrayXd& r,
               const Eigen::ArrayXd& w) {
    const Eigen::ArrayXd s = w.sqrt();
    j_ = (j.array().colwise() * s).matrix();
    r_ = (s * r).matrix();
  }
  // All rows at once with one weight for JᵀJ (w_curvature > 0) and none for Jᵀr (r carries it):
  // a robust loss's Newton system, whose curvature is not its gradient's weight.
  void SetNewtonRows(const Eigen::Matrix<double, Eigen::Dynamic, N>& j, const Eigen::ArrayXd& r,
                     const Eigen::ArrayXd& w_curvature) {
    const Eigen::ArrayXd s = w_curvature.sqrt();
    j_ = (j.array().colwise() * s).matrix();
    r_ = (1.0 / s * r).matrix();
  }
  void Get(Mat<N>* jtj, Vec<N>* jtr) const {
    const double* cols[N + 1];
    for (int k = 0; k < N; ++k) cols[k] = j_.col(k).data();
    cols[N] = r_.data();
    Columns(cols, jtj, jtr, std::make_integer_sequence<int, N>{});
  }

 private:
  // Two rows at a time in one vector register (SSE2 on x86-64, NEON on arm64; GCC's and Clang's
  // vector extension).
  typedef double Pair __attribute__((vector_size(16)));
  static Pair Load(const double* p) {
    Pair v;
    std::memcpy(&v, p, sizeof v);
    return v;
  }
  template <int... A>
  void Columns(const double* const* cols, Mat<N>* jtj, Vec<N>* jtr,
               std::integer_sequence<int, A...>) const {
    (Column<A>(cols, jtj, jtr), ...);
  }
  // Column A's products with columns A … N − 1 and with r, in one pass over the rows: each
  // column's pair of rows is loaded once for all of A's products (Eigen's dot products loaded
  // both columns for each, and summed each across its register at its end), with the
  // accumulators in registers (A fixed, so their number is).
  template <int A>
  void Column(const double* const* cols, Mat<N>* jtj, Vec<N>* jtr) const {
    constexpr int kSums = N + 1 - A;
    Pair acc[kSums] = {};
    const Eigen::Index n = r_.size();
    Eigen::Index i = 0;
    for (; i + 1 < n; i += 2) {
      const Pair a = Load(cols[A] + i);
      for (int b = 0; b < kSums; ++b) acc[b] += a * Load(cols[A + b] + i);
    }
    for (int b = 0; b < kSums; ++b) {
      double sum = acc[b][0] + acc[b][1];
      if (i < n) sum += cols[A][i] * cols[A + b][i];
      if (A + b == N)
        (*jtr)(A) = sum;
      else
        (*jtj)(A, A + b) = (*jtj)(A + b, A) = sum;
    }
  }

  Eigen::Matrix<double, Eigen::Dynamic, N> j_;
  Eigen::VectorXd r_;
};

template <int N>
inline void Symmetric(const double (*h)[N], const double* g, Mat<N>* jtj, Vec<N>* jtr) {
  for (int i = 0; i < N; ++i) {
    (*jtr)(i) = g[i];
    for (int k = i; k < N; ++k) (*jtj)(i, k) = (*jtj)(k, i) = h[i][k];
  }
}

}  // namespace clogscope::vision::fitcore
