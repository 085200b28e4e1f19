// The seed's particle (Figure 7) against its analytic optimum.
//
// Minimising the integral of |F|^2 = m^2 |x'' - g|^2 over a path through p0, p1, p2 at
// t = 0, 1/2, 1: since the integral of (x'' - g)^2 differs from that of x''^2 only by
// boundary terms, x - g t^2 / 2 is the natural cubic spline through the shifted points
// (x'' = 0 at the ends). With knots 0, h, 2h (h = 1/2) its middle moment is
// M1 = 6 (y0 - 2 y1 + y2) / (4 h^2) and the integral of its squared second derivative
// (piecewise linear 0 -> M1 -> 0) is 2 h M1^2 / 3. The B-spline space contains this spline
// (t = 1/2 is a knot) and Gauss quadrature integrates the piecewise-quadratic integrand exactly,
// so the solver must reproduce the value, not approximate it.
#include <gtest/gtest.h>

#include <cstdio>
#include <stdexcept>

#include "../shipped_scene.h"
#include "particle_optimum.h"
#include "perturbed.h"
#include "core/scene_io.h"
#include "solver/augmented_lagrangian.h"
#include "dynamics/algorithms.h"
#include "solver/validity.h"

namespace spacetime {
namespace {

using testing::analyticParticleMinimum;

class Particle : public ::testing::TestWithParam<const char*> {};

// Builds and solves a scene to a tight tolerance; the test fails if it does not build or
// converge.
std::unique_ptr<SpacetimeProblem> solveTightly(const Scene& scene, SolverSummary* summary) {
  std::string error;
  auto problem = SpacetimeProblem::build(scene, &error);
  if (!problem) throw std::runtime_error(error);
  SolverOptions options;
  options.tolerance = 1e-10;
  *summary = solveSpacetime(*problem, options);
  EXPECT_TRUE(summary->converged) << summary->reason;
  return problem;
}

TEST_P(Particle, OptimumEqualsAnalyticMinimum) {
  const Scene shipped = testing::shippedScene(GetParam());
  SolverSummary s;
  const auto problem = solveTightly(shipped, &s);
  const double expected = analyticParticleMinimum(shipped);
  EXPECT_NEAR(s.objective / expected, 1.0, 1e-6) << s.objective << " vs " << expected;
  const ValidityReport v = checkValidity(*problem);
  EXPECT_LT(v.maxPinError, 1e-8);
}

// The same problem written only with formulas: pins as formula constraints, the effort as
// three formula objective terms. The optimum must be the same analytic value.
TEST_P(Particle, FormulaTermsReachTheSameOptimum) {
  const Scene shipped = testing::shippedScene(GetParam());
  Scene scene = shipped;
  std::vector<TermSpec> formulas;
  for (const TermSpec& pin : scene.terms)
    for (int axis = 0; axis < 3; ++axis) {
      TermSpec f;
      f.id = pin.id + "_" + std::string(1, static_cast<char>('x' + axis));
      f.kind = TermKind::Formula;
      f.character = pin.character;
      f.expression = "pos(ball)." + std::string(1, static_cast<char>('x' + axis));
      f.value = pin.position[axis];
      f.time = pin.time;
      formulas.push_back(f);
    }
  scene.terms = formulas;
  scene.objective.effort = 0;
  for (const char* dof : {"ball_x", "ball_y", "ball_z"})
    scene.objective.formulas.push_back({"particle", std::string("tau.") + dof, 1.0});
  SolverSummary s;
  const auto problem = solveTightly(scene, &s);
  EXPECT_NEAR(s.objective / analyticParticleMinimum(shipped), 1.0, 1e-6);
  // The validity report re-evaluates every formula constraint: met at the optimum, and at a
  // perturbed motion equal to the particle's own distance from its pins, axis by axis.
  ValidityReport v = checkValidity(*problem);
  ASSERT_EQ(v.formulas.size(), formulas.size());
  EXPECT_LT(v.maxFormulaViolation, 1e-6);
  testing::perturb(*problem, 2, 0.2);
  v = checkValidity(*problem);
  for (size_t k = 0; k < formulas.size(); ++k) {
    const TermSpec& f = formulas[k];
    const double position = problem->jointState(0, f.time, 0)[static_cast<Eigen::Index>(k % 3)];
    EXPECT_EQ(v.formulas[k].term, f.id);
    EXPECT_NEAR(v.formulas[k].maxViolation, std::abs(position - f.value), 1e-12) << f.id;
  }
}

// A solution carries over to a problem of another shape (here a transcription twice as fine):
// re-fitted, it starts the finer solve at the old optimum, which the finer spline space also
// contains, so the solve ends at the same analytic minimum with no least-squares iteration and
// at most the one Newton step a cold start of this quadratic program takes.
TEST(ParticleWarmStart, CarriesOverToAFinerTranscription) {
  const Scene coarse = testing::shippedScene("particle_gravity.json");
  SolverSummary s;
  const auto solved = solveTightly(coarse, &s);
  Scene fine = coarse;
  fine.transcription.controlPointsPerSecond *= 2;
  SolverSummary cold;
  solveTightly(fine, &cold);
  std::string error;
  auto problem = SpacetimeProblem::build(fine, &error);
  ASSERT_TRUE(problem) << error;
  ASSERT_NE(problem->state().variables.size(), solved->state().variables.size());
  EXPECT_EQ(problem->initializeFrom(*solved), 1);
  SolverOptions options;
  options.tolerance = 1e-10;
  options.warmStart = true;
  const SolverSummary warm = solveSpacetime(*problem, options);
  EXPECT_TRUE(warm.converged) << warm.reason;
  EXPECT_NEAR(warm.objective / analyticParticleMinimum(coarse), 1.0, 1e-6);
  EXPECT_EQ(warm.iterations, 0);
  EXPECT_LE(warm.newtonSteps, cold.newtonSteps);
  EXPECT_LE(warm.iterations + warm.newtonSteps, cold.iterations + cold.newtonSteps);
  std::printf("finer transcription: %d iterations + %d Newton steps warm, %d + %d from the default guess\n",
              warm.iterations, warm.newtonSteps, cold.iterations, cold.newtonSteps);
}

TEST(ParticleFormula, BadFormulaFailsTheBuildWithItsColumn) {
  Scene scene = testing::shippedScene("particle.json");
  TermSpec f;
  f.id = "typo";
  f.kind = TermKind::Formula;
  f.character = "particle";
  f.expression = "pos(bal).x";
  scene.terms.push_back(f);
  std::string error;
  EXPECT_FALSE(SpacetimeProblem::build(scene, &error));
  EXPECT_NE(error.find("term 'typo'"), std::string::npos) << error;
  EXPECT_NE(error.find("column 5: unknown body 'bal'"), std::string::npos) << error;
}

// Clearance outside a box. Through (0,0,0), (1,0.6,0) and (2,0,0), the unconstrained optimum
// clips a box's top corner; with the clearance it must pass over the box at a higher cost. (Outside a box is not convex: from a guess on the wrong side the
// solver can also find a path that tunnels through it between samples, which the validity
// report flags.)
TEST(ParticleClearance, PassesOverABox) {
  Scene scene = testing::shippedScene("particle.json");
  scene.terms[1].position = Eigen::Vector3d(1, 0.6, 0);
  scene.terms[2].position = Eigen::Vector3d(2, 0, 0);
  scene.transcription.controlPointsPerSecond = 40;
  TermSpec box;
  box.id = "box";
  box.kind = TermKind::Clearance;
  box.character = "particle";
  box.body = "ball";
  box.start = 0;
  box.end = 1;
  box.box = true;
  box.boxMin = Eigen::Vector3d(0.6, -0.3, -0.3);
  box.boxMax = Eigen::Vector3d(0.9, 0.58, 0.3);
  auto solve = [&](bool withBox, SolverSummary* summary) {
    Scene sc = scene;
    if (withBox) sc.terms.push_back(box);
    const SceneLoadResult again = parseScene(sceneToJson(sc), "box.json");  // the format carries boxes
    EXPECT_TRUE(again.scene) << again.error;
    std::string error;
    auto problem = SpacetimeProblem::build(*again.scene, &error);
    *summary = solveSpacetime(*problem, SolverOptions());
    // Judge both motions against the box on the dense grid.
    double worst = 0;
    const Model<double>& model = *problem->characters()[0].model;
    Data<double> data(model);
    for (double t = 0; t <= 1; t += 0.001) {
      const Eigen::VectorXd q = problem->jointState(0, t, 0);
      forwardKinematics(model, data, q.data());
      const Eigen::Vector3d p = pointPosition(data, 0 + model.bodyIndex("ball"), Eigen::Vector3d::Zero().eval());
      worst = std::max(worst, -std::max((p - box.boxMax).maxCoeff(), (box.boxMin - p).maxCoeff()));
    }
    return worst;
  };
  SolverSummary free, cleared;
  const double insideFree = solve(false, &free);
  const double insideCleared = solve(true, &cleared);
  ASSERT_TRUE(free.converged && cleared.converged) << free.reason << " / " << cleared.reason;
  std::printf("inside the box: free %.4f m, with clearance %.4f m\n", insideFree, insideCleared);
  EXPECT_GT(insideFree, 1e-3);      // the box matters
  // A box clearance holds at ten instants per sample gap; between them the path may still cut
  // the box's corner (measured: 68 mm into the box without the term, 0.4 mm with it at 40
  // control points/s; 8 mm when it held at the samples only).
  EXPECT_LT(insideCleared, 1.5e-3);
  EXPECT_LT(insideCleared, insideFree / 5);
  EXPECT_GT(cleared.objective, free.objective);
}

INSTANTIATE_TEST_SUITE_P(Scenes, Particle, ::testing::Values("particle.json", "particle_gravity.json"));

}  // namespace
}  // namespace spacetime
