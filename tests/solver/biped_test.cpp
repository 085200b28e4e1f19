// The planar biped example (resources/scenes/biped_jump.json, also the builder's "Planar biped"
// preset): a 9-dof character whose root is the pelvis and whose two feet each stand on a
// two-point contact - contacts on bodies other than the root, unlike the lamps. From its default
// guess it must jump 0.3 m forward with both feet off the ground and pass every check of the
// validity report (the unactuated residual on the dense grid, the forward simulation of the
// flight, pushing contacts inside their cones, every body above the ground).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "../shipped_scene.h"
#include "dynamics/algorithms.h"
#include "solver/augmented_lagrangian.h"
#include "solver/validity.h"

namespace spacetime {
namespace {

TEST(ShippedBiped, JumpsForwardAndPassesEveryCheck) {
  const Scene scene = testing::shippedScene("biped_jump.json");
  std::string error;
  const auto problem = SpacetimeProblem::build(scene, &error);
  ASSERT_TRUE(problem) << error;
  SolverOptions options = solverOptionsFor(scene.solver);
  options.threads = 2;
  const SolverSummary s = solveSpacetime(*problem, options);
  ASSERT_TRUE(s.converged) << s.reason << " worst " << s.worstConstraint;
  const ValidityReport v = checkValidity(*problem);
  for (const ValidityCheck& c : validityChecklist(v))
    EXPECT_TRUE(c.pass) << c.name << ": " << c.value << " " << c.unit << " (limit " << c.limit << ")";
  EXPECT_LE(v.maxUnactuatedResidualDense, 0.01);

  // Both soles clear the ground in the flight (0.45-0.8 s): the lowest of their heel and toe
  // points at its highest.
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
  // It lands where its end key says, 0.3 m ahead, at rest.
  const Eigen::VectorXd end = problem->jointState(0, 1.2, 0);
  EXPECT_NEAR(end[0], 0.3, 1e-6);
  EXPECT_LT(problem->jointState(0, 1.2, 1).norm(), 1e-5);
  std::printf("biped: objective %.6g, %d iterations + %d Newton steps, %.1f s; feet clear the ground by %.3f m; "
              "dense residual %.3g of weight, forward simulation %.3g\n",
              s.objective, s.iterations, s.newtonSteps, s.solveSeconds, clearance, v.maxUnactuatedResidualDense,
              v.flights.empty() ? 0.0 : v.flights[0].maxPositionError);
}

}  // namespace
}  // namespace spacetime
