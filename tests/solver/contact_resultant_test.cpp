// A planar contact of two points carried as its resultant (ContactVariables::resultant): the
// split the dynamics reads has the resultant's wrench, the contact wrench cone is exactly the
// set of resultants of forces in the points' own cones (checked by sampling both ways), the
// reported forces lie in the points' cones, and the solved jump is the jump solved with the
// points' forces, its objective no higher, warm-started from a state stored in that layout.
#include <gtest/gtest.h>

#include <random>

#include "../shipped_scene.h"
#include "solver/augmented_lagrangian.h"
#include "solver/kernels.h"
#include "solver/validity.h"

namespace spacetime {
namespace {

using Layout = SpacetimeProblem::ContactLayout;

std::unique_ptr<SpacetimeProblem> jump(Layout layout) {
  std::string error;
  auto problem = SpacetimeProblem::build(testing::shippedScene("luxo_jump.json"), &error, layout);
  EXPECT_TRUE(problem) << error;
  return problem;
}

// Resultant force and moment about the origin of two points' forces f = (f0x, f0y, f1x, f1y),
// the points on the ground at x = -a and +a.
Eigen::Vector3d wrench(const Eigen::VectorXd& f, double a) {
  return {f[0] + f[2], f[1] + f[3], -a * f[1] + a * f[3]};
}

TEST(ContactResultant, TheSplitHasTheWrenchOfThePointsForces) {
  auto problem = jump(Layout::Resultants);
  const ContactVariables& ct = problem->contacts()[0];
  ASSERT_TRUE(ct.resultant);
  EXPECT_EQ(ct.blockSize(), 3);
  EXPECT_EQ(ct.pointForceSize(), 4);
  EXPECT_LT((ct.gather() * ct.split() - Eigen::Matrix3d::Identity()).norm(), 1e-15);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> force(-50, 50);
  for (int trial = 0; trial < 100; ++trial) {
    Eigen::VectorXd f(4);
    for (int k = 0; k < 4; ++k) f[k] = force(rng);
    const Eigen::VectorXd split = ct.split() * (ct.gather() * f);
    EXPECT_LT((wrench(split, 0.07) - wrench(f, 0.07)).norm(), 1e-12);
    EXPECT_LT((ct.gather() * split - ct.gather() * f).norm(), 1e-12);
  }
}

TEST(ContactResultant, TheConeIsTheResultantsOfTheConesOfThePoints) {
  auto problem = jump(Layout::Resultants);
  const ContactVariables& ct = problem->contacts()[0];
  const double mu = ct.friction, weight = problem->characters()[0].weight;
  const ContactWrenchConeKernel cone(mu, 1.0 / weight, "cone");
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0, 1), any(-1, 1);
  double rows[4];
  // Forces in the points' own cones have a resultant in the wrench cone.
  for (int trial = 0; trial < 200; ++trial) {
    Eigen::VectorXd f(4);
    for (int p = 0; p < 2; ++p) {
      f[2 * p + 1] = weight * unit(rng);
      f[2 * p] = mu * f[2 * p + 1] * any(rng);
    }
    const Eigen::VectorXd split = ct.split() * (ct.gather() * f);
    cone.evaluate(split.data(), rows);
    for (double r : rows) EXPECT_LE(r, 1e-12);
  }
  // A resultant in the wrench cone is reported as forces in the points' own cones; one outside
  // it has a row above zero.
  const int sample = static_cast<int>(ct.times.size()) / 2;
  int inside = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const Eigen::Vector3d u(2 * weight * any(rng), weight * (0.2 + unit(rng)), weight * any(rng));
    for (int d = 0; d < 3; ++d) problem->variables()[ct.sampleOffset(sample) + d] = u[d];
    const Eigen::VectorXd split = ct.split() * u;
    cone.evaluate(split.data(), rows);
    const bool inCone = std::max({rows[0], rows[1], rows[2], rows[3]}) <= 0;
    bool pointsInCones = true;
    for (const Eigen::Vector3d& f : problem->contactForces(0, ct.times[sample]))
      pointsInCones = pointsInCones && f.y() >= 0 && std::abs(f.x()) <= mu * f.y() + 1e-12;
    EXPECT_EQ(inCone, pointsInCones) << u.transpose();
    inside += inCone;
  }
  EXPECT_GT(inside, 40);
  EXPECT_LT(inside, 360);
}

// The same jump solved cold with the points' forces and with the resultant (one thread: one
// path each): the same optimum, the resultant's no higher - its cone is the points' cones'
// resultants, and the load-sharing term reads the even split. A state stored with the points'
// forces warm-starts the resultant's problem with the same wrench at every sample.
TEST(ContactResultant, SolvesTheJumpNoHigherAndReadsStatesOfThePointsForces) {
  auto points = jump(Layout::PointForces);
  ASSERT_FALSE(points->contacts()[0].resultant);
  SolverOptions options = solverOptionsFor(points->scene().solver);
  options.threads = 1;
  const SolverSummary withPoints = solveSpacetime(*points, options);
  ASSERT_TRUE(withPoints.converged) << withPoints.reason;
  auto cold = jump(Layout::Resultants);
  const SolverSummary withResultant = solveSpacetime(*cold, options);
  ASSERT_TRUE(withResultant.converged) << withResultant.reason;
  EXPECT_LE(withResultant.objective, withPoints.objective * (1 + 1e-9));
  EXPECT_NEAR(withResultant.objective, withPoints.objective, 1e-5 * withPoints.objective);
  const ValidityReport v = checkValidity(*cold);
  EXPECT_TRUE(v.contactsPushOnly);
  EXPECT_TRUE(v.contactsInFrictionCone);
  for (const ValidityCheck& check : validityChecklist(v)) EXPECT_TRUE(check.pass) << check.name;

  auto warm = jump(Layout::Resultants);
  ASSERT_EQ(warm->warmStartFrom(points->scene(), points->state()), SpacetimeProblem::WarmStart::Refitted);
  const ContactVariables& ct = warm->contacts()[0];
  for (double t : ct.times) {
    Eigen::VectorXd was(4), is(4);
    const auto a = points->contactForces(0, t), b = warm->contactForces(0, t);
    for (int p = 0; p < 2; ++p) was.segment<2>(2 * p) = a[p].head<2>(), is.segment<2>(2 * p) = b[p].head<2>();
    EXPECT_LT((wrench(was, 1) - wrench(is, 1)).norm(), 1e-9 * points->characters()[0].weight) << t;
  }
}

}  // namespace
}  // namespace spacetime
