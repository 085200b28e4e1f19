// Spatial algebra identities (RBDA ch. 2): transforms against their 6x6 matrices, composition,
// inverses, invariance of power, the force cross product as the dual of the motion one, and the
// inertia change of frame against X^T I X.
#include <gtest/gtest.h>

#include <random>

#include "dynamics/spatial.h"
#include "random_model.h"

namespace spacetime {
namespace {

Transform<double> randomTransform(std::mt19937& rng) {
  const Eigen::Quaterniond q = Eigen::Quaterniond::UnitRandom();
  return Transform<double>(q.toRotationMatrix(), testing::randomVec(rng));
}
Motion<double> randomMotion(std::mt19937& rng) {
  return {testing::randomVec(rng), testing::randomVec(rng)};
}
Force<double> randomForce(std::mt19937& rng) {
  return {testing::randomVec(rng), testing::randomVec(rng)};
}

TEST(Spatial, TransformMatchesMatrixForm) {
  std::mt19937 rng(1);
  for (int k = 0; k < 50; ++k) {
    const auto X = randomTransform(rng);
    const auto m = randomMotion(rng);
    const auto f = randomForce(rng);
    EXPECT_LT((X.apply(m).vector() - X.matrix() * m.vector()).norm(), 1e-12);
    // Force transform X* = X^{-T} (RBDA eq. 2.26).
    EXPECT_LT((X.apply(f).vector() - X.matrix().inverse().transpose() * f.vector()).norm(), 1e-12);
    EXPECT_LT((X.applyInverse(X.apply(m)).vector() - m.vector()).norm(), 1e-12);
    EXPECT_LT((X.applyInverse(X.apply(f)).vector() - f.vector()).norm(), 1e-12);
    EXPECT_LT((X.inverse().apply(m).vector() - X.applyInverse(m).vector()).norm(), 1e-12);
  }
}

TEST(Spatial, CompositionAndPowerInvariance) {
  std::mt19937 rng(2);
  for (int k = 0; k < 50; ++k) {
    const auto A = randomTransform(rng), B = randomTransform(rng);
    const auto m = randomMotion(rng);
    const auto f = randomForce(rng);
    EXPECT_LT(((A * B).apply(m).vector() - A.apply(B.apply(m)).vector()).norm(), 1e-12);
    EXPECT_LT(((A * B).matrix() - A.matrix() * B.matrix()).norm(), 1e-12);
    EXPECT_NEAR(dot(A.apply(m), A.apply(f)), dot(m, f), 1e-12);
    EXPECT_LT((compose(A, B).matrix() - (A * B).matrix()).norm(), 1e-12);
  }
}

TEST(Spatial, CrossProductsAreDual) {
  std::mt19937 rng(3);
  for (int k = 0; k < 50; ++k) {
    const auto v = randomMotion(rng), m = randomMotion(rng);
    const auto f = randomForce(rng);
    // (v x m) . f = -m . (v x* f)  (RBDA eq. 2.34)
    EXPECT_NEAR(dot(crossMotion(v, m), f), -dot(m, crossForce(v, f)), 1e-12);
    EXPECT_LT(crossMotion(v, v).vector().norm(), 1e-12);
  }
}

TEST(Spatial, InertiaChangeOfFrame) {
  std::mt19937 rng(4);
  for (int k = 0; k < 20; ++k) {
    const auto I = Inertia<double>::fromMassCom(1.7, testing::randomVec(rng),
                                                Eigen::Vector3d(0.3, 0.4, 0.5).asDiagonal());
    const auto X = randomTransform(rng);  // B_X_A
    const Mat6<double> expected = X.matrix().transpose() * I.matrix() * X.matrix();
    EXPECT_LT((I.expressedInParent(X).matrix() - expected).norm(), 1e-12);
    const auto v = randomMotion(rng);
    EXPECT_LT((multiply(I, v).vector() - I.matrix() * v.vector()).norm(), 1e-12);
  }
}

TEST(Spatial, RotationCoordinatesIsTheTransposedRotation) {
  const Eigen::Vector3d axis = Eigen::Vector3d(1, 2, 3).normalized();
  const Mat3<double> E = rotationCoordinates<double>(axis, 0.7);
  EXPECT_LT((E - Eigen::AngleAxisd(0.7, axis).toRotationMatrix().transpose()).norm(), 1e-14);
}

}  // namespace
}  // namespace spacetime
