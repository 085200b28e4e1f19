// The solver as a job: cancel keeps a finite, consistent iterate; invalid options are reported,
// not crashed on; contradictory constraints end in a reason, never a crash or NaN.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "../shipped_scene.h"
#include "clashing_pin.h"
#include "core/scene_io.h"
#include "solver/augmented_lagrangian.h"

namespace spacetime {
namespace {

std::unique_ptr<SpacetimeProblem> load(const char* name, Scene* sceneOut = nullptr) {
  const Scene scene = testing::shippedScene(name);
  if (sceneOut) *sceneOut = scene;
  std::string error;
  return SpacetimeProblem::build(scene, &error);
}

TEST(SolverRobustness, CancelKeepsAFiniteIterate) {
  auto problem = load("luxo_jump.json");
  std::atomic<bool> cancel{false};
  int iterationsAtCancel = -1;
  const SolverSummary s = solveSpacetime(*problem, SolverOptions(), [&](const IterationReport& r) {
    EXPECT_TRUE(std::isfinite(r.objective));
    if (iterationsAtCancel < 0) {
      iterationsAtCancel = r.iterations;
      cancel = true;  // as a user pressing Stop during the first progress report
    }
    return true;
  }, &cancel);
  EXPECT_EQ(s.status, SolveStatus::Cancelled);
  EXPECT_FALSE(s.converged);
  for (double x : problem->variables()) ASSERT_TRUE(std::isfinite(x));
  ASSERT_GE(iterationsAtCancel, 1);
  EXPECT_LE(s.iterations, iterationsAtCancel + 1);  // stops at the next iteration
}

// Warm start: re-solving from a converged state (variables, multipliers, penalty) converges
// at once, to the same optimum.
TEST(SolverRobustness, WarmStartFromTheSolutionConvergesImmediately) {
  auto problem = load("particle_gravity.json");
  const SolverSummary cold = solveSpacetime(*problem, SolverOptions());
  ASSERT_TRUE(cold.converged) << cold.reason;
  const SolutionState state = problem->state();
  auto again = load("particle_gravity.json");
  ASSERT_TRUE(again->restore(state));
  SolverOptions warm;
  warm.warmStart = true;
  const SolverSummary s = solveSpacetime(*again, warm);
  EXPECT_TRUE(s.converged) << s.reason;
  // The warm start's Newton polish finds the KKT conditions met where it starts: no
  // Levenberg-Marquardt iteration, no multiplier update, at most one Newton step.
  EXPECT_TRUE(s.polished) << s.reason;
  EXPECT_EQ(s.outerIterations, 0);
  EXPECT_EQ(s.iterations, 0);
  EXPECT_LE(s.newtonSteps, 1);
  EXPECT_NEAR(s.objective, cold.objective, 1e-9 * cold.objective);
  EXPECT_LT(cold.iterations + cold.outerIterations, 100);
}

// The time limit holds inside the Newton polish too: a warm re-solve after a pin moved (the
// editor's case, where the polish runs first) with its budget already spent stops with the
// time limit as the reason, takes no Newton step and keeps the variables it started from.
TEST(SolverRobustness, TheTimeLimitStopsTheNewtonPolish) {
  Scene scene;
  auto problem = load("particle_gravity.json", &scene);
  ASSERT_TRUE(solveSpacetime(*problem, SolverOptions()).converged);
  const SolutionState solved = problem->state();
  for (TermSpec& t : scene.terms)
    if (t.kind == TermKind::Pin && t.time > 0.4 && t.time < 0.6) t.position.x() += 0.05;
  std::string error;
  auto moved = SpacetimeProblem::build(scene, &error);
  ASSERT_TRUE(moved) << error;
  ASSERT_TRUE(moved->restore(solved));
  const std::vector<double> before = moved->variables();

  SolverOptions warm;
  warm.warmStart = true;
  warm.maxSeconds = 1e-9;
  const SolverSummary s = solveSpacetime(*moved, warm);
  EXPECT_EQ(s.status, SolveStatus::TimeLimit) << s.reason;
  EXPECT_FALSE(s.converged);
  EXPECT_EQ(s.newtonSteps, 0);
  EXPECT_EQ(s.chordSteps, 0);
  EXPECT_EQ(s.iterations, 0);
  EXPECT_EQ(moved->variables(), before);

  // With time, the same warm re-solve is the polish's: it converges in Newton steps alone (on
  // the factorisation the first solve's polish kept, chord_steps.h).
  ASSERT_TRUE(moved->restore(solved));
  warm.maxSeconds = 300;
  const SolverSummary full = solveSpacetime(*moved, warm);
  EXPECT_TRUE(full.converged && full.polished) << full.reason;
  EXPECT_GT(full.newtonSteps + full.chordSteps, 0);
  EXPECT_EQ(full.iterations, 0);
}

TEST(SolverRobustness, InvalidOptionsAreReported) {
  auto problem = load("particle.json");
  SolverOptions o;
  o.tolerance = -1;
  const SolverSummary s = solveSpacetime(*problem, o);
  EXPECT_EQ(s.status, SolveStatus::InvalidOptions);
  EXPECT_NE(s.reason.find("tolerance"), std::string::npos);
}

// Two pins at one instant in two places cannot both hold. The solve stops at the stall, long
// before its update limit, and names exactly the two pins: at the final projection's least-squares
// point each is off by half their distance, and every other constraint holds. The restoration
// phase certifies the conflict: minimising the violation alone ends at a positive minimum.
TEST(SolverRobustness, ContradictoryPinsStopAndAreNamed) {
  Scene scene;
  auto unused = load("particle.json", &scene);
  const TermSpec clash = testing::addClashingPin(scene);
  std::string error;
  auto problem = SpacetimeProblem::build(scene, &error);
  ASSERT_TRUE(problem) << error;
  SolverOptions o;
  o.maxOuterIterations = 100;
  const SolverSummary s = solveSpacetime(*problem, o);
  EXPECT_FALSE(s.converged);
  EXPECT_EQ(s.status, SolveStatus::Stalled) << s.reason;
  EXPECT_LT(s.outerIterations, 30);
  EXPECT_TRUE(std::isfinite(s.objective));
  for (double x : problem->variables()) ASSERT_TRUE(std::isfinite(x));
  // The pins' distance per axis: |(5, 5, 5) - p1|; each pin misses its point by half of it.
  const Eigen::Vector3d gap = clash.position - scene.terms[1].position;
  const double half = 0.5 * gap.cwiseAbs().maxCoeff();
  ASSERT_EQ(s.violated.size(), 2u) << s.reason;
  std::vector<std::string> labels;
  for (const ViolatedConstraint& v : s.violated) {
    labels.push_back(v.label);
    EXPECT_NEAR(v.violation, half, 1e-6 * half) << v.label;
  }
  std::sort(labels.begin(), labels.end());
  EXPECT_NE(labels[0].find("'clash'"), std::string::npos) << labels[0];
  EXPECT_NE(labels[1].find("'" + scene.terms[1].id + "'"), std::string::npos) << labels[1];
  EXPECT_NEAR(s.maxViolation, half, 1e-6 * half);
  EXPECT_NE(s.reason.find("'clash'"), std::string::npos) << s.reason;
  EXPECT_NE(s.reason.find("they conflict (minimising the violation alone ends at a positive minimum"), std::string::npos)
      << s.reason;
  EXPECT_GE(s.restorationSteps, 1);
  std::printf("%d multiplier updates: %s\n", s.outerIterations, s.reason.c_str());
}

}  // namespace
}  // namespace spacetime
