// The two-footed examples. The planar biped (resources/scenes/biped_jump.json, also the
// builder's "Planar biped" preset): a 9-dof character whose root is the pelvis and whose two
// feet each stand on a two-point contact - contacts on bodies other than the root, unlike the
// lamps. From its default guess it must jump 0.3 m forward with both feet off the ground and pass
// every check of the validity report (the unactuated residual on the dense grid, the forward
// simulation of the flight, pushing contacts inside their cones, every body above the ground).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <utility>

#include "../shipped_scene.h"
#include "dynamics/algorithms.h"
#include "solver/augmented_lagrangian.h"
#include "solver/validity.h"

namespace spacetime {
namespace {

// Solves a shipped two-footed jump from its default guess and checks what the biped and the
// humanoid share: every validity check, both soles clear of the ground in the flight
// (0.45-0.8 s), the landing 0.3 m ahead at rest. Returns the problem for further checks.
std::unique_ptr<SpacetimeProblem> solveTwoFootedJump(const char* file) {
  const Scene scene = testing::shippedScene(file);
  std::string error;
  auto problem = SpacetimeProblem::build(scene, &error);
  EXPECT_TRUE(problem) << error;
  if (!problem) return problem;
  SolverOptions options = solverOptionsFor(scene.solver);
  options.threads = 2;
  const SolverSummary s = solveSpacetime(*problem, options);
  EXPECT_TRUE(s.converged) << s.reason << " worst " << s.worstConstraint;
  const ValidityReport v = checkValidity(*problem);
  for (const ValidityCheck& c : validityChecklist(v))
    EXPECT_TRUE(c.pass) << c.name << ": " << c.value << " " << c.unit << " (limit " << c.limit << ")";
  EXPECT_LE(v.maxUnactuatedResidualDense, 0.01);

  // The lowest of the heel and toe points of both soles, at its highest in the flight.
  const Model<double>& model = *problem->characters()[0].model;
  Data<double> data(model);
  const int feet[2] = {model.bodyIndex("l_foot"), model.bodyIndex("r_foot")};
  double clearance = 0;
  for (double t = 0.45; t <= 0.8; t += 0.005) {
    forwardKinematics(model, data, problem->jointState(0, t, 0).data());
    double lowest = 1e9;
    for (int foot : feet)
      for (double x : {-0.06, 0.16}) lowest = std::min(lowest, pointPosition(data, foot, Eigen::Vector3d(x, -0.05, 0)).y());
    clearance = std::max(clearance, lowest);
  }
  EXPECT_GE(clearance, 0.03);
  const Eigen::VectorXd end = problem->jointState(0, 1.2, 0);
  EXPECT_NEAR(end[0], 0.3, 1e-6);
  EXPECT_LT(problem->jointState(0, 1.2, 1).norm(), 1e-5);
  std::printf("%s: objective %.6g, %d iterations + %d Newton steps, %.1f s; feet clear the ground by %.3f m; "
              "dense residual %.3g of weight, forward simulation %.3g\n",
              file, s.objective, s.iterations, s.newtonSteps, s.solveSeconds, clearance, v.maxUnactuatedResidualDense,
              v.flights.empty() ? 0.0 : v.flights[0].maxPositionError);
  return problem;
}

TEST(ShippedBiped, JumpsForwardAndPassesEveryCheck) { solveTwoFootedJump("biped_jump.json"); }

// The 3D humanoid (resources/scenes/humanoid_jump.json, the builder's "3D humanoid"): a floating
// root with six dofs, legs and arms turning in the sagittal plane, four-point soles. The task is
// mirror-symmetric, so its optimum is too: the root's sideways dofs (z, yaw, roll) stay at zero
// and the legs move alike, though nothing in the problem ties them.
TEST(ShippedHumanoid, JumpsForwardSymmetricallyAndPassesEveryCheck) {
  const auto problem = solveTwoFootedJump("humanoid_jump.json");
  ASSERT_TRUE(problem);
  const Model<double>& model = *problem->characters()[0].model;
  const auto dof = [&](const char* body) { return model.bodies[model.bodyIndex(body)].dofIndex; };
  const std::pair<const char*, const char*> kMirrorBodies[] = {
      {"l_thigh", "r_thigh"}, {"l_shin", "r_shin"}, {"l_foot", "r_foot"}, {"l_arm", "r_arm"}};
  double sideways = 0, asymmetry = 0;
  for (double t = 0; t <= 1.2; t += 0.005) {
    const Eigen::VectorXd q = problem->jointState(0, t, 0);
    sideways = std::max({sideways, std::abs(q[2]), std::abs(q[3]), std::abs(q[5])});  // z, yaw, roll
    for (const auto& [left, right] : kMirrorBodies)
      asymmetry = std::max(asymmetry, std::abs(q[dof(left)] - q[dof(right)]));
  }
  std::printf("humanoid: largest sideways root dof %.3g, largest left-right difference %.3g rad\n", sideways, asymmetry);
  EXPECT_LT(sideways, 1e-3);
  EXPECT_LT(asymmetry, 1e-3);
}

// The biped of biped_jump.json with a 4 kg head fixed 0.62 m above its hips
// (tests/scenes/biped_heavy_head.json): its effort at the default guess is 3763, against the
// biped's 2901. The augmented Lagrangian's starting penalty follows that (SolverOptions::
// penaltyPerObjective); started at a fixed 100 the solve rose off its start key while the effort
// dominated and stalled at a violation of 0.13 (1910 iterations, 202 s).
TEST(ShippedBiped, WithAHeavyHeadItStillConvergesFromTheDefaultGuess) {
  const Scene scene = testing::testScene("biped_heavy_head.json");
  std::string error;
  const auto problem = SpacetimeProblem::build(scene, &error);
  ASSERT_TRUE(problem) << error;
  SolverOptions options = solverOptionsFor(scene.solver);
  options.threads = 2;
  const SolverSummary s = solveSpacetime(*problem, options);
  ASSERT_TRUE(s.converged) << s.reason;
  for (const ValidityCheck& c : validityChecklist(checkValidity(*problem)))
    EXPECT_TRUE(c.pass) << c.name << ": " << c.value << " " << c.unit << " (limit " << c.limit << ")";
  // On its start key (the stalled solve had lifted the pelvis 0.2 m off it).
  EXPECT_NEAR(problem->jointState(0, 0, 0)[1], 0.7520660495122983, 1e-6);
  std::printf("biped with a heavy head: objective %.6g, %d iterations + %d Newton steps, %.1f s\n", s.objective,
              s.iterations, s.newtonSteps, s.solveSeconds);
}

}  // namespace
}  // namespace spacetime
