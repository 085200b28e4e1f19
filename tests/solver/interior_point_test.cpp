// The interior-point method (IPOPT, interior_point.h) against independent truths: the particle's
// analytic optimum, the augmented Lagrangian's optimum of the shipped jump (no worse) and the
// validity report on the dense grid, and a task whose constraints truly conflict.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "../shipped_scene.h"
#include "clashing_pin.h"
#include "particle_optimum.h"
#include "solver/augmented_lagrangian.h"
#include "solver/interior_point.h"
#include "solver/validity.h"

namespace spacetime {
namespace {

SolverOptions interiorPoint() {
  SolverOptions o;
  o.method = SolverMethod::InteriorPoint;
  o.threads = 2;
  return o;
}

// A quadratic program: the interior point lands on the analytic optimum (with gravity too).
TEST(InteriorPoint, ParticleReachesTheAnalyticOptimum) {
  if (!interiorPointAvailable()) GTEST_SKIP() << "built without IPOPT (coinor-libipopt-dev)";
  for (const char* name : {"particle.json", "particle_gravity.json"}) {
    const Scene scene = testing::shippedScene(name);
    std::string error;
    auto problem = SpacetimeProblem::build(scene, &error);
    ASSERT_TRUE(problem) << error;
    const SolverSummary s = solveSpacetime(*problem, interiorPoint());
    ASSERT_TRUE(s.converged) << name << ": " << s.reason;
    const double expected = testing::analyticParticleMinimum(scene);
    EXPECT_NEAR(s.objective, expected, expected * 1e-7) << name;
    EXPECT_LT(s.maxViolation, 1e-7) << name;
    EXPECT_LT(checkValidity(*problem).maxPinError, 1e-7) << name;
    // Its iterations are counted once, as iterations: there is no Newton polish after IPOPT.
    EXPECT_GT(s.iterations, 0) << name;
    EXPECT_EQ(s.newtonSteps, 0) << name;
  }
}

// The shipped jump: a motion every validity check passes, at an objective no higher than the
// augmented Lagrangian's (measured: 28.0987 against 28.7735 - another local optimum; the
// interior point keeps away from the inequalities' boundaries until the end).
TEST(InteriorPoint, LuxoJumpIsValidAndNoWorseThanTheAugmentedLagrangian) {
  if (!interiorPointAvailable()) GTEST_SKIP() << "built without IPOPT (coinor-libipopt-dev)";
  const Scene scene = testing::shippedScene("luxo_jump.json");
  std::string error;
  auto ip = SpacetimeProblem::build(scene, &error);
  auto al = SpacetimeProblem::build(scene, &error);
  ASSERT_TRUE(ip && al) << error;
  SolverOptions o = interiorPoint();
  const SolverSummary s = solveSpacetime(*ip, o);
  ASSERT_TRUE(s.converged) << s.reason;
  EXPECT_LE(s.maxViolation, o.tolerance);
  o.method = SolverMethod::AugmentedLagrangian;
  const SolverSummary reference = solveSpacetime(*al, o);
  ASSERT_TRUE(reference.converged) << reference.reason;
  EXPECT_LE(s.objective, reference.objective + 1e-6);
  for (const ValidityCheck& c : validityChecklist(checkValidity(*ip)))
    EXPECT_TRUE(c.pass) << c.name << ": " << c.value << " > " << c.limit;
  // The multipliers are handed back: a warm augmented-Lagrangian solve from the interior
  // point's result is a KKT point already (Newton steps only, no least-squares iteration).
  o.warmStart = true;
  const SolverSummary warm = solveSpacetime(*ip, o);
  EXPECT_TRUE(warm.converged && warm.polished) << warm.reason;
  EXPECT_EQ(warm.iterations, 0);
  EXPECT_NEAR(warm.objective, s.objective, 1e-5 * s.objective);
}

// Two pins at one instant in two places: the restoration phase ends at a positive minimum of
// the violation, the solve says the constraints conflict and names the two pins.
TEST(InteriorPoint, ContradictoryPinsAreNamed) {
  if (!interiorPointAvailable()) GTEST_SKIP() << "built without IPOPT (coinor-libipopt-dev)";
  Scene scene = testing::shippedScene("particle.json");
  testing::addClashingPin(scene);
  std::string error;
  auto problem = SpacetimeProblem::build(scene, &error);
  ASSERT_TRUE(problem) << error;
  const SolverSummary s = solveSpacetime(*problem, interiorPoint());
  EXPECT_FALSE(s.converged);
  EXPECT_EQ(s.status, SolveStatus::Stalled) << s.reason;
  EXPECT_NE(s.reason.find("conflict"), std::string::npos) << s.reason;
  for (double x : problem->variables()) ASSERT_TRUE(std::isfinite(x));
  std::vector<std::string> labels;
  for (const ViolatedConstraint& v : s.violated) labels.push_back(v.label);
  ASSERT_FALSE(labels.empty()) << s.reason;
  const bool namesClash = std::any_of(labels.begin(), labels.end(), [](const std::string& l) { return l.find("'clash'") != std::string::npos; });
  const bool namesPin = std::any_of(labels.begin(), labels.end(), [&](const std::string& l) {
    return l.find("'" + scene.terms[1].id + "'") != std::string::npos;
  });
  EXPECT_TRUE(namesClash || namesPin) << s.reason;
  for (const std::string& l : labels)
    EXPECT_TRUE(l.find("'clash'") != std::string::npos || l.find("'" + scene.terms[1].id + "'") != std::string::npos) << l;
}

// A problem with free contact ends is refused with a reason, and nothing moves.
TEST(InteriorPoint, FreeContactEndsAreRefusedAndNothingMoves) {
  if (!interiorPointAvailable()) GTEST_SKIP() << "built without IPOPT (coinor-libipopt-dev)";
  Scene scene = testing::shippedScene("luxo_jump.json");
  bool freed = false;
  for (TermSpec& t : scene.terms)
    if (t.id == "takeoff") t.freeEnd = freed = true;
  ASSERT_TRUE(freed);
  std::string error;
  auto problem = SpacetimeProblem::build(scene, &error);
  ASSERT_TRUE(problem) << error;
  const std::vector<double> before = problem->variables();
  const SolverSummary s = solveSpacetime(*problem, interiorPoint());
  EXPECT_EQ(s.status, SolveStatus::InvalidOptions);
  EXPECT_NE(s.reason.find("free contact ends"), std::string::npos) << s.reason;
  EXPECT_EQ(problem->variables(), before);
}

}  // namespace
}  // namespace spacetime
