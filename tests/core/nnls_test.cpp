// NNLS against two independent truths: the KKT conditions of min |Ax - b|^2, x >= 0, and the
// best of all 2^n unconstrained least-squares solutions on a subset that happen to be feasible.
#include "core/nnls.h"

#include <gtest/gtest.h>

#include <Eigen/QR>
#include <random>

namespace spacetime {
namespace {

double bruteForceOptimum(const Eigen::MatrixXd& A, const Eigen::VectorXd& b) {
  const int n = static_cast<int>(A.cols());
  double best = b.norm();  // x = 0
  for (int mask = 1; mask < (1 << n); ++mask) {
    std::vector<int> idx;
    for (int i = 0; i < n; ++i)
      if (mask & (1 << i)) idx.push_back(i);
    Eigen::MatrixXd As(A.rows(), idx.size());
    for (size_t k = 0; k < idx.size(); ++k) As.col(k) = A.col(idx[k]);
    const Eigen::VectorXd z = As.colPivHouseholderQr().solve(b);
    if ((z.array() >= 0).all()) best = std::min(best, (As * z - b).norm());
  }
  return best;
}

TEST(Nnls, MeetsTheKktConditionsAndTheBruteForceOptimum) {
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  int withActiveBounds = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const int m = 2 + trial % 7, n = 1 + trial % 6;  // over- and under-determined
    Eigen::MatrixXd A(m, n);
    Eigen::VectorXd b(m);
    for (int i = 0; i < m; ++i) {
      b[i] = normal(rng);
      for (int j = 0; j < n; ++j) A(i, j) = normal(rng);
    }
    const NnlsResult r = nnls(A, b);
    ASSERT_TRUE(r.converged);
    const Eigen::VectorXd w = A.transpose() * (b - A * r.x);
    for (int j = 0; j < n; ++j) {
      EXPECT_GE(r.x[j], 0.0);
      if (r.x[j] > 0)
        EXPECT_NEAR(w[j], 0.0, 1e-9) << "trial " << trial;
      else
        EXPECT_LE(w[j], 1e-9) << "trial " << trial;
    }
    if ((r.x.array() == 0).any()) ++withActiveBounds;
    EXPECT_NEAR(r.residualNorm, bruteForceOptimum(A, b), 1e-9) << "trial " << trial;
  }
  EXPECT_GT(withActiveBounds, 50);  // the bounds mattered in many trials
}

TEST(Nnls, ReturnsTheUnconstrainedSolutionWhenItIsFeasible) {
  Eigen::MatrixXd A(3, 2);
  A << 1, 0, 0, 1, 1, 1;
  const Eigen::VectorXd x(Eigen::Vector2d(0.5, 2.0));
  const NnlsResult r = nnls(A, A * x);
  EXPECT_NEAR((r.x - x).norm(), 0.0, 1e-12);
  EXPECT_NEAR(r.residualNorm, 0.0, 1e-12);
}

}  // namespace
}  // namespace spacetime
