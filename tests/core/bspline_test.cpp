// Cubic B-splines, uniform and on non-uniform knots: partition of unity, derivatives against
// finite differences, exact reproduction of cubic polynomials (B-splines span the cubics), C2
// continuity at knots, the uniform spline as the non-uniform one on equal knots, and splitting a
// segment as an exact refinement (the coarse spline space lies inside the split one).
#include <gtest/gtest.h>

#include "core/bspline.h"

#include <cmath>
#include <stdexcept>

namespace spacetime {
namespace {

// The basis sums to one (so its derivatives to zero) and is non-negative, over [0, 1.2]; the
// tolerance grows by `scale` per derivative order (the shorter the segments, the larger those).
void expectPartitionOfUnity(const CubicBSpline& s, double scale) {
  for (double t = 0; t <= 1.2; t += 0.0137) {
    const BSplineBasis b = s.basis(t);
    double w = 0, d1 = 0, d2 = 0, d3 = 0;
    for (int j = 0; j < 4; ++j) {
      EXPECT_GE(b.w[j], -1e-14) << t;
      w += b.w[j];
      d1 += b.d1[j];
      d2 += b.d2[j];
      d3 += b.d3[j];
    }
    EXPECT_NEAR(w, 1, 1e-13) << t;
    EXPECT_NEAR(d1, 0, 1e-10 * scale) << t;
    EXPECT_NEAR(d2, 0, 1e-8 * scale * scale) << t;
    EXPECT_NEAR(d3, 0, 1e-6 * scale * scale * scale) << t;
  }
}

TEST(BSpline, PartitionOfUnityAndDerivativeSums) { expectPartitionOfUnity(CubicBSpline(0.0, 1.2, 7), 1); }

TEST(BSpline, DerivativesMatchFiniteDifferences) {
  CubicBSpline s(-0.5, 2.0, 9);
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
  CubicBSpline s(0.0, 1.0, 5);
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
  CubicBSpline s(0.0, 1.0, 4);
  Eigen::MatrixXd c = Eigen::MatrixXd::Random(s.controlPointCount(), 1);
  for (int k = 1; k < 4; ++k) {
    const double t = k * 0.25;
    for (int order = 0; order <= 2; ++order)
      EXPECT_NEAR(s.evaluate(c, t - 1e-12, order)(0), s.evaluate(c, t + 1e-12, order)(0), 1e-6);
  }
}

// Breakpoints of a refined transcription: uniform, then some segments split (not all equal).
std::vector<double> splitBreakpoints() { return {0.0, 0.2, 0.3, 0.35, 0.4, 0.6, 0.8, 0.9, 1.2}; }

TEST(BSpline, OnNonUniformKnotsPartitionOfUnityAndDerivativesMatchFiniteDifferences) {
  const CubicBSpline s(splitBreakpoints());
  ASSERT_FALSE(s.uniform());
  EXPECT_EQ(s.segmentCount(), 8);
  EXPECT_EQ(s.controlPointCount(), 11);
  expectPartitionOfUnity(s, 10);
  Eigen::MatrixXd c = Eigen::MatrixXd::Random(s.controlPointCount(), 2);
  const double h = 1e-6;
  for (double t = 0.013; t < 1.19; t += 0.031) {
    if (std::abs(t - s.knot(s.segmentOf(t))) < 2 * h || std::abs(t - s.knot(s.segmentOf(t) + 1)) < 2 * h) continue;
    for (int order = 1; order <= 3; ++order) {
      const Eigen::RowVectorXd fd =
          (s.evaluate(c, t + h, order - 1) - s.evaluate(c, t - h, order - 1)) / (2 * h);
      EXPECT_LT((fd - s.evaluate(c, t, order)).norm(), 1e-4 * (1 + fd.norm())) << t << " " << order;
    }
  }
}

TEST(BSpline, OnNonUniformKnotsReproducesCubicsAndIsC2AtEveryKnot) {
  const CubicBSpline s(splitBreakpoints());
  auto f = [](double t) { return 1 - 2 * t + 3 * t * t - 4 * t * t * t; };
  std::vector<double> times = s.sampleTimes(6);
  Eigen::MatrixXd values(times.size(), 1);
  for (size_t i = 0; i < times.size(); ++i) values(i, 0) = f(times[i]);
  const Eigen::MatrixXd c = s.fit(times, values, 0.0);
  for (double t = 0; t <= 1.2; t += 0.013) {
    EXPECT_NEAR(s.evaluate(c, t)(0), f(t), 1e-9);
    EXPECT_NEAR(s.evaluate(c, t, 1)(0), -2 + 6 * t - 12 * t * t, 1e-7);
    EXPECT_NEAR(s.evaluate(c, t, 2)(0), 6 - 24 * t, 1e-6);
  }
  const Eigen::MatrixXd r = Eigen::MatrixXd::Random(s.controlPointCount(), 1);
  for (int k = 1; k < s.segmentCount(); ++k)
    for (int order = 0; order <= 2; ++order)
      EXPECT_NEAR(s.evaluate(r, s.knot(k) - 1e-12, order)(0), s.evaluate(r, s.knot(k) + 1e-12, order)(0), 1e-6)
          << "knot " << k << " order " << order;
}

TEST(BSpline, EqualBreakpointsGiveTheUniformSpline) {
  const CubicBSpline uniform(0.0, 1.2, 6);
  std::vector<double> breaks;
  for (int k = 0; k <= 6; ++k) breaks.push_back(0.2 * k);
  const CubicBSpline general(breaks);
  for (double t = 0; t <= 1.2; t += 0.0093)
    for (int order = 0; order <= 3; ++order) {
      const BSplineBasis a = uniform.basis(t), b = general.basis(t);
      ASSERT_EQ(a.first, b.first) << t;
      for (int j = 0; j < 4; ++j)
        EXPECT_NEAR(a.derivative(order)[j], b.derivative(order)[j], 1e-10 * std::pow(5.0, order)) << t << " " << order;
    }
}

TEST(BSpline, SplittingSegmentsKeepsEveryCoarseSpline) {
  // Knot insertion (Boehm 1980): a spline on the coarse knots is one on the refined knots, so the
  // refinement's re-fit of a motion loses nothing of it.
  const CubicBSpline coarse(0.0, 1.2, 6);
  const CubicBSpline fine({0.0, 0.2, 0.3, 0.4, 0.6, 0.8, 0.9, 1.0, 1.2});
  const Eigen::MatrixXd c = Eigen::MatrixXd::Random(coarse.controlPointCount(), 3);
  const std::vector<double> times = fine.sampleTimes(8);
  Eigen::MatrixXd values(times.size(), 3);
  for (size_t i = 0; i < times.size(); ++i) values.row(i) = coarse.evaluate(c, times[i]);
  const Eigen::MatrixXd f = fine.fit(times, values, 0.0);
  for (double t = 0; t <= 1.2; t += 0.007)
    for (int order = 0; order <= 2; ++order)
      EXPECT_LT((fine.evaluate(f, t, order) - coarse.evaluate(c, t, order)).norm(), 1e-8 * std::pow(10.0, order))
          << t << " " << order;
}

TEST(BSpline, SampleTimesCoverEverySegmentEvenly) {
  const CubicBSpline s(splitBreakpoints());
  const std::vector<double> times = s.sampleTimes(4);
  ASSERT_EQ(times.size(), 8u * 4 + 1);
  EXPECT_DOUBLE_EQ(times.front(), 0.0);
  EXPECT_DOUBLE_EQ(times.back(), 1.2);
  EXPECT_NEAR(times[9] - times[8], 0.0125, 1e-15);  // the split segment [0.3, 0.35]
  const CubicBSpline u(0.0, 1.0, 5);
  EXPECT_EQ(u.sampleTimes(3).size(), 16u);
  EXPECT_THROW(CubicBSpline(std::vector<double>{0.0, 0.5, 0.5, 1.0}), std::invalid_argument);
}

}  // namespace
}  // namespace spacetime
