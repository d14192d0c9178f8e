#include "vision/edges/fit_shapes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <type_traits>

// What the profile fits share (fitcore): their normal equations, small solver and exp.
namespace clogscope::vision {
namespace {

// e^x against libm's over the range the fits' Gaussians use and beyond: within 1e-15 relative
// (libm is within 1 ulp of the truth); 0 below −700 and NaN for NaN, where libm's has no errno
// to set.
TEST(FitExpTest, MatchesLibmWhereverTheFitsCallIt) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> gaussian(-60.0, 0.0), wide(-700.0, 700.0);
  double worst = 0;
  for (int i = 0; i < 200000; ++i) {
    const double x = i % 2 ? gaussian(rng) : wide(rng);
    worst = std::max(worst, std::abs(fitcore::Exp(x) / std::exp(x) - 1.0));
  }
  EXPECT_LT(worst, 1e-15);
  // Where the table's entries meet (n a multiple of 32 and not) and at the ends.
  for (const double x : {0.0, -0.5 * std::log(2.0), -std::log(2.0), 1.0, -1e-300, -700.0, 700.0})
    EXPECT_NEAR(fitcore::Exp(x) / std::exp(x), 1.0, 1e-15) << x;
  EXPECT_EQ(fitcore::Exp(-700.5), 0.0);
  EXPECT_EQ(fitcore::Exp(-1e6), 0.0);
  EXPECT_TRUE(std::isnan(fitcore::Exp(std::numeric_limits<double>::quiet_NaN())));
}

// The lit cylinder's normal equations (fit_shapes.h), two rows at a time in a vector register,
// against JᵀWJ and JᵀWr formed by Eigen from the same rows: for row counts even and odd (the last
// odd row is added on its own), set row by row or all at once.
TEST(NormalSystemTest, ProductsAreTheWeightedJacobiansOwn) {
  constexpr int kN = 8;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> value(-2.0, 2.0), weight(0.1, 3.0);
  for (const int n : {1, 2, 7, 80, 81}) {
    Eigen::Matrix<double, Eigen::Dynamic, kN> j(n, kN);
    Eigen::VectorXd r(n), w(n);
    for (int i = 0; i < n; ++i) {
      for (int k = 0; k < kN; ++k) j(i, k) = value(rng);
      r(i) = value(rng);
      w(i) = weight(rng);
    }
    const Eigen::Matrix<double, kN, kN> want_jtj = j.transpose() * w.asDiagonal() * j;
    const Eigen::Matrix<double, kN, 1> want_jtr = j.transpose() * w.asDiagonal() * r;
    fitcore::NormalSystem<kN> by_row(n), at_once(0);
    for (int i = 0; i < n; ++i) {
      const Eigen::Matrix<double, 1, kN> row = j.row(i);
      by_row.Set(i, row.data(), r(i), w(i));
    }
    at_once.SetRows(j, r.array(), w.array());
    for (auto* system : {&by_row, &at_once}) {
      fitcore::Mat<kN> jtj;
      fitcore::Vec<kN> jtr;
      system->Get(&jtj, &jtr);
      EXPECT_LT((jtj - want_jtj).cwiseAbs().maxCoeff(), 1e-12 * n) << n;
      EXPECT_LT((jtr - want_jtr).cwiseAbs().maxCoeff(), 1e-12 * n) << n;
    }
  }
}

// The fits' small solver against a truth made first: b = A·x for a random x, A symmetric positive
// definite with condition numbers up to 1e8, and each column of A⁻¹ against Eigen's LU inverse.
TEST(SmallCholeskyTest, SolvesWhatTheProductMade) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  const auto check = [&](auto n_tag) {
    constexpr int kN = decltype(n_tag)::value;
    for (const double condition : {1.0, 1e3, 1e8}) {
      // A = Q·diag(λ)·Qᵀ, λ spread evenly in log from 1 to `condition`.
      fitcore::Mat<kN> m;
      for (int i = 0; i < kN; ++i)
        for (int k = 0; k < kN; ++k) m(i, k) = value(rng);
      const fitcore::Mat<kN> q = Eigen::HouseholderQR<fitcore::Mat<kN>>(m).householderQ();
      fitcore::Vec<kN> lambda;
      for (int i = 0; i < kN; ++i) lambda(i) = std::pow(condition, i / (kN - 1.0));
      const fitcore::Mat<kN> a = q * lambda.asDiagonal() * q.transpose();
      fitcore::Vec<kN> x;
      for (int i = 0; i < kN; ++i) x(i) = value(rng);
      fitcore::SmallCholesky<kN> chol;
      ASSERT_TRUE(chol.Factor(a)) << kN << " " << condition;
      // A backward-stable solve's bound, a few n·ε·κ (x and A⁻¹'s entries are at most ~1).
      const double tol = 4 * kN * 2.2e-16 * condition;
      EXPECT_LT((fitcore::SolveSymmetric<kN>(a, a * x) - x).cwiseAbs().maxCoeff(), tol)
          << kN << " " << condition;
      const fitcore::Mat<kN> inverse = a.inverse();
      for (int i = 0; i < kN; ++i)
        EXPECT_LT((fitcore::InverseColumn<kN>(a, i) - inverse.col(i)).cwiseAbs().maxCoeff(), tol)
            << kN << " " << condition << " column " << i;
    }
  };
  check(std::integral_constant<int, 2>{});
  check(std::integral_constant<int, 5>{});
  check(std::integral_constant<int, 6>{});
  check(std::integral_constant<int, 8>{});
}

// Not positive definite, the factor refuses and the solve is LDLT's: an indefinite system solved
// exactly, a singular one's empty direction left at zero.
TEST(SmallCholeskyTest, LeavesWhatIsNotPositiveDefiniteToLdlt) {
  fitcore::Mat<3> indefinite;
  indefinite << 2, 0, 0, 0, -1, 0, 0, 0, 4;
  fitcore::SmallCholesky<3> chol;
  EXPECT_FALSE(chol.Factor(indefinite));
  const fitcore::Vec<3> x = fitcore::SolveSymmetric<3>(indefinite, fitcore::Vec<3>(2, 3, 2));
  EXPECT_NEAR(x(0), 1.0, 1e-15);
  EXPECT_NEAR(x(1), -3.0, 1e-15);
  EXPECT_NEAR(x(2), 0.5, 1e-15);
  fitcore::Mat<3> singular;
  singular << 2, 0, 0, 0, 0, 0, 0, 0, 4;
  EXPECT_FALSE(chol.Factor(singular));
  const fitcore::Vec<3> y = fitcore::SolveSymmetric<3>(singular, fitcore::Vec<3>(2, 3, 2));
  EXPECT_NEAR(y(0), 1.0, 1e-15);
  EXPECT_EQ(y(1), 0.0);
  EXPECT_NEAR(y(2), 0.5, 1e-15);
}

}  // namespace
}  // namespace clogscope::vision
