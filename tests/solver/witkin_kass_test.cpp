// The witkin-kass method (solver/witkin_kass.h) against independent truths: the particle's
// analytic optimum in one projected step, the shipped jump's iterates each meeting the
// constraints (the method's promise to the live view) while the effort falls, ending at the
// optimum the SQP finds from the same guess, and a task whose constraints truly conflict, named.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "../shipped_scene.h"
#include "clashing_pin.h"
#include "particle_optimum.h"
#include "solver/augmented_lagrangian.h"
#include "solver/validity.h"

namespace spacetime {
namespace {

SolverOptions witkinKass() {
  SolverOptions o;
  o.method = SolverMethod::WitkinKass;
  o.threads = 2;
  return o;
}

// Linear dynamics, quadratic effort, point constraints: the restoration meets the pins, and the
// first projected step lands on the analytic optimum (with gravity too).
TEST(WitkinKass, ParticleReachesTheAnalyticOptimumInOneStep) {
  for (const char* name : {"particle.json", "particle_gravity.json"}) {
    const Scene scene = testing::shippedScene(name);
    std::string error;
    auto problem = SpacetimeProblem::build(scene, &error);
    ASSERT_TRUE(problem) << error;
    const SolverSummary s = solveSpacetime(*problem, witkinKass());
    ASSERT_TRUE(s.converged) << name << ": " << s.reason;
    EXPECT_EQ(s.method, SolverMethod::WitkinKass);
    EXPECT_EQ(s.sqpSteps, 1) << name << ": " << s.reason;
    EXPECT_EQ(s.iterations, 0) << name << ": no augmented-Lagrangian iteration";
    const double expected = testing::analyticParticleMinimum(scene);
    EXPECT_NEAR(s.objective, expected, expected * 1e-9) << name;
    EXPECT_LT(checkValidity(*problem).maxPinError, 1e-9) << name;
  }
}

// The shipped jump from the default guess. Every iterate the projected steps report meets every
// constraint row to 1e-6 and has less effort than the one before; the finished motion passes
// every validity check at the objective the SQP reaches (measured: both 28.0987211).
TEST(WitkinKass, LuxoJumpIteratesMeetTheConstraintsAndEndAtTheSqpOptimum) {
  const Scene scene = testing::shippedScene("luxo_jump.json");
  std::string error;
  auto problem = SpacetimeProblem::build(scene, &error);
  auto reference = SpacetimeProblem::build(scene, &error);
  ASSERT_TRUE(problem && reference) << error;
  std::vector<IterationReport> steps;  // the projected steps' reports: the augmented Lagrangian's have a penalty
  const SolverSummary s = solveSpacetime(*problem, witkinKass(), [&](const IterationReport& r) {
    if (r.rho == 0) steps.push_back(r);
    return true;
  });
  ASSERT_TRUE(s.converged) << s.reason;
  EXPECT_GT(s.sqpSteps, 5) << s.reason;
  ASSERT_GE(steps.size(), 3u);
  for (size_t i = 0; i < steps.size(); ++i) {
    EXPECT_LE(steps[i].maxViolation, 1e-6) << "step " << steps[i].iterations;
    if (i > 0) {
      EXPECT_LT(steps[i].objective, steps[i - 1].objective) << "step " << steps[i].iterations;
    }
  }
  for (const ValidityCheck& c : validityChecklist(checkValidity(*problem)))
    EXPECT_TRUE(c.pass) << c.name << ": " << c.value << " > " << c.limit;
  SolverOptions o = witkinKass();
  o.method = SolverMethod::Sqp;
  const SolverSummary sqp = solveSpacetime(*reference, o);
  ASSERT_TRUE(sqp.converged) << sqp.reason;
  EXPECT_NEAR(s.objective, sqp.objective, 1e-4 * sqp.objective);
}

// The heavy lamp: the projected steps end near the optimum, and the hand-over's warm polish
// (PolishOptions::settleActiveSet) finishes it with no Levenberg-Marquardt iteration, at the
// optimum `sqp` and IPOPT reach (110.2928; test Sqp.TheHeavyLamp...). A polish whose line search
// cut every step that violated a row it did not hold, with those rows' Jacobians left zero (its
// second step crossed one by 0.075 unseen), failed and left it to the augmented Lagrangian: 194
// iterations.
TEST(WitkinKass, TheHeavyLampsHandOverEndsInItsPolish) {
  std::string error;
  auto problem = SpacetimeProblem::build(testing::shippedScene("luxo_heavy.json"), &error);
  ASSERT_TRUE(problem) << error;
  const SolverSummary s = solveSpacetime(*problem, witkinKass());
  ASSERT_TRUE(s.converged) << s.reason;
  EXPECT_TRUE(s.polished) << s.reason;
  EXPECT_EQ(s.iterations, 0) << s.reason;
  EXPECT_NEAR(s.objective, 110.2928, 1e-3) << s.reason;
  for (const ValidityCheck& c : validityChecklist(checkValidity(*problem)))
    EXPECT_TRUE(c.pass) << c.name << ": " << c.value << " > " << c.limit;
}

// Stopped at its first projected step (the editor's Stop), the method keeps that restored motion:
// within 1e-6 of every constraint, reported as cancelled.
TEST(WitkinKass, AStopKeepsTheLastRestoredMotion) {
  std::string error;
  auto problem = SpacetimeProblem::build(testing::shippedScene("luxo_jump.json"), &error);
  ASSERT_TRUE(problem) << error;
  const SolverSummary s = solveSpacetime(*problem, witkinKass(), [](const IterationReport& r) { return r.rho > 0; });
  EXPECT_EQ(s.status, SolveStatus::Cancelled) << s.reason;
  EXPECT_NE(s.reason.find("the last restored motion is kept"), std::string::npos) << s.reason;
  EXPECT_LE(measure(*problem).maxViolation, 1e-6);
  EXPECT_LE(s.maxViolation, 1e-6);
}

// Two pins at one instant in two places: the restoration cannot meet both, the augmented
// Lagrangian solves from the starting motion, stalls, says the constraints conflict and names
// the two pins.
TEST(WitkinKass, ContradictoryPinsAreNamed) {
  Scene scene = testing::shippedScene("particle.json");
  testing::addClashingPin(scene);
  std::string error;
  auto problem = SpacetimeProblem::build(scene, &error);
  ASSERT_TRUE(problem) << error;
  testing::expectTheClashNamed(solveSpacetime(*problem, witkinKass()), *problem, scene,
                               "the restoration from the starting motion");
}

}  // namespace
}  // namespace spacetime
