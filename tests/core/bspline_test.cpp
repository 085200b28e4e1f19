// Uniform cubic B-spline: partition of unity, derivatives against finite differences, exact
// reproduction of cubic polynomials (B-splines span the cubics), C2 continuity at knots.
#include <gtest/gtest.h>

#include "core/bspline.h"

namespace spacetime {
namespace {

TEST(BSpline, PartitionOfUnityAndDerivativeSums) {
  UniformBSpline s(0.0, 1.2, 7);
  for (double t = 0; t <= 1.2; t += 0.0137) {
    const BSplineBasis b = s.basis(t);
    double w = 0, d1 = 0, d2 = 0, d3 = 0;
    for (int j = 0; j < 4; ++j) {
      w += b.w[j];
      d1 += b.d1[j];
      d2 += b.d2[j];
      d3 += b.d3[j];
    }
    EXPECT_NEAR(w, 1, 1e-14);
    EXPECT_NEAR(d1, 0, 1e-10);
    EXPECT_NEAR(d2, 0, 1e-8);
    EXPECT_NEAR(d3, 0, 1e-6);
  }
}

TEST(BSpline, DerivativesMatchFiniteDifferences) {
  UniformBSpline s(-0.5, 2.0, 9);
  Eigen::MatrixXd c = Eigen::MatrixXd::Random(s.controlPointCount(), 2);
  const double h = 1e-5;
  for (double t = -0.4; t < 1.9; t += 0.091) {
    for (int order = 1; order <= 3; ++order) {
      const Eigen::RowVectorXd fd =
          (s.evaluate(c, t + h, order - 1) - s.evaluate(c, t - h, order - 1)) / (2 * h);
      EXPECT_LT((fd - s.evaluate(c, t, order)).norm(), 1e-4 * (1 + fd.norm())) << t << " " << order;
    }
  }
}

TEST(BSpline, ReproducesCubicsExactly) {
  UniformBSpline s(0.0, 1.0, 5);
  auto f = [](double t) { return 1 - 2 * t + 3 * t * t - 4 * t * t * t; };
  std::vector<double> times;
  Eigen::MatrixXd values(41, 1);
  for (int i = 0; i <= 40; ++i) {
    times.push_back(i / 40.0);
    values(i, 0) = f(i / 40.0);
  }
  const Eigen::MatrixXd c = s.fit(times, values, 0.0);
  for (double t = 0; t <= 1; t += 0.013) {
    EXPECT_NEAR(s.evaluate(c, t)(0), f(t), 1e-8);
    EXPECT_NEAR(s.evaluate(c, t, 2)(0), 6 - 24 * t, 1e-6);
  }
}

TEST(BSpline, SecondDerivativeContinuousAtKnots) {
  UniformBSpline s(0.0, 1.0, 4);
  Eigen::MatrixXd c = Eigen::MatrixXd::Random(s.controlPointCount(), 1);
  for (int k = 1; k < 4; ++k) {
    const double t = k * 0.25;
    for (int order = 0; order <= 2; ++order)
      EXPECT_NEAR(s.evaluate(c, t - 1e-12, order)(0), s.evaluate(c, t + 1e-12, order)(0), 1e-6);
  }
}

}  // namespace
}  // namespace spacetime
