// A Ceres covariance with a parameter held fixed (a constant block; a coordinate held by a
// manifold, as the lag fit's --max-offset-s 0 does), against its closed form. Kept for the
// sanitizer build: there Eigen's header allocator must match the one inside the prebuilt libceres,
// or memory Ceres allocates one way is freed the other ("bad-free" in
// CovarianceImpl::GetCovarianceBlockInTangentOrAmbientSpace).
#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <vector>

namespace clogscope::model {
namespace {

// y = a·x + b, one residual per point.
struct Line {
  double x, y;
  template <typename T>
  bool operator()(const T* a, const T* b, T* r) const {
    r[0] = a[0] * x + b[0] - y;
    return true;
  }
};

// The same with both parameters in one block.
struct LineInOneBlock {
  double x, y;
  template <typename T>
  bool operator()(const T* ab, T* r) const {
    r[0] = ab[0] * x + ab[1] - y;
    return true;
  }
};

std::vector<double> Xs() { return {0.5, 1.0, 1.5, 2.0, 3.0, 4.5, 5.0, 7.0}; }

// With b held, the covariance of a for unit residual weights is (JᵀJ)⁻¹ with J the column of x:
// 1 / Σx². J is sized through an out-of-line copy of Eigen's PlainObjectBase<MatrixXd>::resize, as
// any file of a program may have one (model/fit.cc does): the linker keeps one copy of that inline
// function for the whole program, libceres's covariance code included, which frees what it
// allocated through it with its own inline idea of Eigen's allocator.
double ClosedFormVarianceOfA() {
  using Base = Eigen::PlainObjectBase<Eigen::MatrixXd>;
  void (Base::*volatile resize_held)(Eigen::Index, Eigen::Index) = &Base::resize;
  void (Base::*const resize)(Eigen::Index, Eigen::Index) = resize_held;
  const std::vector<double> xs = Xs();
  Eigen::MatrixXd j;
  (j.*resize)(static_cast<Eigen::Index>(xs.size()), 1);
  for (size_t i = 0; i < xs.size(); ++i) j(static_cast<Eigen::Index>(i), 0) = xs[i];
  const Eigen::MatrixXd jtj = j.transpose() * j;
  return 1 / jtj(0, 0);
}

::testing::AssertionResult Converges(ceres::Problem* problem) {
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(so, problem, &summary);
  if (summary.termination_type == ceres::CONVERGENCE) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << summary.BriefReport();
}

TEST(CeresCovarianceTest, AConstantParameterBlockLeavesTheOthersCovarianceItsClosedForm) {
  for (auto algorithm : {ceres::DENSE_SVD, ceres::SPARSE_QR}) {
    double a = 1.0, b = 0.25;
    ceres::Problem problem;
    for (double x : Xs()) {
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<Line, 1, 1, 1>(new Line{x, 2 * x + 0.25 + 0.01 * x * x}),
          nullptr, &a, &b);
    }
    problem.SetParameterBlockConstant(&b);
    ASSERT_TRUE(Converges(&problem));
    ceres::Covariance::Options co;
    co.algorithm_type = algorithm;
    if (algorithm == ceres::DENSE_SVD) co.null_space_rank = -1;
    ceres::Covariance covariance(co);
    const std::vector<std::pair<const double*, const double*>> blocks = {{&a, &a}};
    ASSERT_TRUE(covariance.Compute(blocks, &problem));
    double var_a = 0;
    ASSERT_TRUE(covariance.GetCovarianceBlock(&a, &a, &var_a));
    EXPECT_NEAR(var_a, ClosedFormVarianceOfA(), 1e-12);
    EXPECT_EQ(b, 0.25);
  }
}

TEST(CeresCovarianceTest, AHeldCoordinateOfABlockHasNoVariance) {
  double ab[2] = {1.0, 0.25};
  ceres::Problem problem;
  for (double x : Xs()) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<LineInOneBlock, 1, 2>(
                                 new LineInOneBlock{x, 2 * x + 0.25 + 0.01 * x * x}),
                             nullptr, ab);
  }
  problem.SetManifold(ab, new ceres::SubsetManifold(2, {1}));
  ASSERT_TRUE(Converges(&problem));
  ceres::Covariance::Options co;
  co.algorithm_type = ceres::DENSE_SVD;
  co.null_space_rank = -1;
  ceres::Covariance covariance(co);
  const std::vector<std::pair<const double*, const double*>> blocks = {{ab, ab}};
  ASSERT_TRUE(covariance.Compute(blocks, &problem));
  double c[4];
  ASSERT_TRUE(covariance.GetCovarianceBlock(ab, ab, c));
  EXPECT_NEAR(c[0], ClosedFormVarianceOfA(), 1e-12);
  EXPECT_EQ(c[1], 0.0);
  EXPECT_EQ(c[2], 0.0);
  EXPECT_EQ(c[3], 0.0);
  EXPECT_EQ(ab[1], 0.25);
}

}  // namespace
}  // namespace clogscope::model
