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

#include "core/scene_io.h"
#include "solver/augmented_lagrangian.h"
#include "solver/validity.h"

namespace spacetime {
namespace {

double analyticParticleMinimum(const Scene& scene) {
  const double h = 0.5, m = 1.0;
  const Eigen::Vector3d p[3] = {{0, 0, 0}, {2, 1, 1}, {-2, 2, 1}};
  double total = 0;
  for (int axis = 0; axis < 3; ++axis) {
    double y[3];
    for (int i = 0; i < 3; ++i) {
      const double t = i * h;
      y[i] = p[i][axis] - scene.gravity[axis] * t * t / 2;
    }
    const double M1 = 6 * (y[0] - 2 * y[1] + y[2]) / (4 * h * h);
    total += m * m * 2 * h * M1 * M1 / 3;
  }
  return total;
}

class Particle : public ::testing::TestWithParam<const char*> {};

TEST_P(Particle, OptimumEqualsAnalyticMinimum) {
  const SceneLoadResult r = loadSceneFile(std::string(SPACETIME_SOURCE_DIR) + "/resources/scenes/" + GetParam());
  ASSERT_TRUE(r.scene) << r.error;
  std::string error;
  auto problem = SpacetimeProblem::build(*r.scene, &error);
  ASSERT_TRUE(problem) << error;
  SolverOptions options;
  options.tolerance = 1e-10;
  const SolverSummary s = solveSpacetime(*problem, options);
  EXPECT_TRUE(s.converged) << s.reason;
  const double expected = analyticParticleMinimum(*r.scene);
  EXPECT_NEAR(s.objective / expected, 1.0, 1e-6) << s.objective << " vs " << expected;
  const ValidityReport v = checkValidity(*problem);
  EXPECT_LT(v.maxPinError, 1e-8);
}

INSTANTIATE_TEST_SUITE_P(Scenes, Particle, ::testing::Values("particle.json", "particle_gravity.json"));

}  // namespace
}  // namespace spacetime
