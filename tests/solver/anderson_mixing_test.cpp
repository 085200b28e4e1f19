// Anderson mixing (solver/src/anderson_mixing.h) against what it is on a linear iteration:
// GMRES's step (Walker and Ni 2011, section 4), exact after dimension + 1 steps, where the plain
// iteration's error falls by its contraction each step.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>

#include "../../solver/src/anderson_mixing.h"

namespace spacetime {
namespace {

// The linear fixed-point iteration z <- z + f(z), f(z) = b - A z, with A = I - G for a
// symmetric contraction G of the given eigenvalues (a chord method's iteration on a linear
// problem): its fixed point is A^-1 b.
struct LinearIteration {
  Eigen::MatrixXd A;
  Eigen::VectorXd b;
  LinearIteration(int d, const Eigen::VectorXd& spectrum) {
    std::mt19937 random(7);
    std::normal_distribution<double> normal;
    Eigen::MatrixXd Q = Eigen::MatrixXd::NullaryExpr(d, d, [&] { return normal(random); });
    Q = Eigen::HouseholderQR<Eigen::MatrixXd>(Q).householderQ();
    A = Eigen::MatrixXd::Identity(d, d) - Q * spectrum.asDiagonal() * Q.transpose();
    b = Eigen::VectorXd::NullaryExpr(d, [&] { return normal(random); });
  }
  Eigen::VectorXd step(const Eigen::VectorXd& z) const { return b - A * z; }
  double error(const Eigen::VectorXd& z) const { return (z - A.lu().solve(b)).norm(); }
};

TEST(AndersonMixing, OnALinearIterationIsExactAfterDimensionPlusOneSteps) {
  const int d = 4;
  const LinearIteration it(d, Eigen::VectorXd::LinSpaced(d, -0.9, 0.9));
  raw::AndersonMixing mixing(d);
  Eigen::VectorXd z = Eigen::VectorXd::Zero(d), plain = z;
  for (int k = 0; k < d + 1; ++k) {
    z += mixing.mix(it.step(z));
    plain += it.step(plain);
  }
  EXPECT_LT(it.error(z), 1e-10 * it.error(Eigen::VectorXd::Zero(d)));
  EXPECT_GT(it.error(plain), 0.1 * it.error(Eigen::VectorXd::Zero(d)));  // 0.9^5: the plain steps
}

// A chord method's error is mostly in the few directions its kept matrix gets wrong: with three
// slow eigenvalues (0.9, 0.7 and -0.6) among fast ones (0.05), a memory of three steps reaches in
// 12 steps what the plain steps have not in 30; a reset makes the next step the plain one. (Its
// memory must cover the slow directions: with a spectrum spread over [-0.9, 0.9], three steps'
// memory does no better than the plain steps.)
TEST(AndersonMixing, AShortMemoryRemovesTheFewSlowDirections) {
  const int d = 12;
  Eigen::VectorXd spectrum = Eigen::VectorXd::Constant(d, 0.05);
  spectrum.head(3) << 0.9, 0.7, -0.6;
  const LinearIteration it(d, spectrum);
  raw::AndersonMixing mixing(3);
  Eigen::VectorXd z = Eigen::VectorXd::Zero(d), plain = z;
  for (int k = 0; k < 30; ++k) {
    if (k < 12) z += mixing.mix(it.step(z));
    plain += it.step(plain);
  }
  EXPECT_LT(it.error(z), it.error(plain));
  EXPECT_LT(it.error(z), 1e-8 * it.error(Eigen::VectorXd::Zero(d)));
  mixing.reset();
  const Eigen::VectorXd f = it.step(z);
  EXPECT_EQ(mixing.mix(f), f);
}

}  // namespace
}  // namespace spacetime
