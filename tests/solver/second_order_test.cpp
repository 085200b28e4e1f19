// The second-order check (solver/second_order.h) against independent truths: a particle held on a
// circle at mid-clip, where the effort's level sets are spheres about the unconstrained motion's
// midpoint, so the nearest point of the circle is a strict minimum, the farthest a saddle, and a
// circle centred on that midpoint a family of equally good motions (a flat direction); the jump's
// reduced Hessian against a dense null space of its active constraints (singular value
// decomposition instead of sparse QR); the hurdle's two optima - the augmented Lagrangian's
// and `sqp`'s - each a strict local minimum, so the methods' different objectives there are two
// basins of one problem, not a failure of either; and the 3D lamp, whose flat directions move
// contact forces only, so its motion is a strict minimum while its forces are not decided.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "../../solver/src/kkt_multipliers.h"
#include "../../solver/src/program_steps.h"
#include "../shipped_scene.h"
#include "solver/augmented_lagrangian.h"
#include "solver/second_order.h"

namespace spacetime {
namespace {

// The shipped particle (no gravity, effort only) pinned at (-1, 0, 0) at t = 0 and (1, 0, 0) at
// t = 1, and at t = 0.5 either pinned at `through` or (circle) held on the circle
// (y - c)^2 + z^2 = r^2 of the plane x = const by a formula.
Scene particleScene(const Eigen::Vector3d* through, double c, double r) {
  Scene scene = testing::shippedScene("particle.json");
  TermSpec start = scene.terms.front();
  start.id = "start";
  start.time = 0.0;
  start.position = Eigen::Vector3d(-1, 0, 0);
  TermSpec end = start;
  end.id = "end";
  end.time = 1.0;
  end.position = Eigen::Vector3d(1, 0, 0);
  TermSpec middle = start;
  middle.time = 0.5;
  if (through) {
    middle.id = "through";
    middle.position = *through;
  } else {
    middle.id = "on_circle";
    middle.kind = TermKind::Formula;
    middle.expression = "(q.ball_y - " + std::to_string(c) + ") * (q.ball_y - " + std::to_string(c) + ") + q.ball_z * q.ball_z";
    middle.relation = '=';
    middle.value = r * r;
  }
  scene.terms = {start, middle, end};
  return scene;
}

// The check on the circle scene at the least-effort motion through the circle's point `point`
// (a KKT point of the circle scene: there the effort's gradient, along the point's offset from the
// midpoint (0, 0, 0), is normal to the circle).
SecondOrderCheck checkOnCircle(double c, double r, const Eigen::Vector3d& point) {
  std::string error;
  auto pinned = SpacetimeProblem::build(particleScene(&point, 0, 0), &error);
  EXPECT_TRUE(pinned) << error;
  SolverOptions options;
  options.threads = 1;
  const SolverSummary s = solveSpacetime(*pinned, options);
  EXPECT_TRUE(s.converged) << s.reason;
  auto circle = SpacetimeProblem::build(particleScene(nullptr, c, r), &error);
  EXPECT_TRUE(circle) << error;
  SolutionState state = pinned->state();
  state.multipliers.assign(circle->augmentedLagrangian().lambda.size(), 0.0);
  state.newtonFactors = nullptr;
  EXPECT_TRUE(circle->restore(state));
  return checkSecondOrder(*circle, 1);
}

// A shipped scene's problem, solved from the default guess (2 threads) to convergence.
std::unique_ptr<SpacetimeProblem> solvedShipped(const std::string& name) {
  std::string error;
  auto problem = SpacetimeProblem::build(testing::shippedScene(name), &error);
  EXPECT_TRUE(problem) << error;
  if (!problem) return problem;
  SolverOptions options;
  options.threads = 2;
  EXPECT_TRUE(solveSpacetime(*problem, options).converged) << name;
  return problem;
}

TEST(SecondOrder, OnACircleTheNearestPointIsAMinimumTheFarthestASaddleAndACentredCircleIsFlat) {
  // Circle of radius 0.5 about y = 0.3: the midpoint (0, 0, 0) lies inside it, nearest to y = -0.2
  // and farthest from y = 0.8. Along the circle the effort c0 |p|^2 has curvature 2 c0 + 2 lambda
  // with lambda = -c0 |p| / r: +1.2 c0 at the nearest point, -1.2 c0 at the farthest.
  const SecondOrderCheck nearest = checkOnCircle(0.3, 0.5, Eigen::Vector3d(0, -0.2, 0));
  ASSERT_TRUE(nearest.checked) << nearest.reason;
  EXPECT_LT(nearest.stationarity, 1e-9);
  EXPECT_TRUE(nearest.strictMinimum) << nearest.reason;
  EXPECT_GT(nearest.smallestEigenvalue, 0.0);

  const SecondOrderCheck farthest = checkOnCircle(0.3, 0.5, Eigen::Vector3d(0, 0.8, 0));
  ASSERT_TRUE(farthest.checked) << farthest.reason;
  EXPECT_LT(farthest.stationarity, 1e-9);
  EXPECT_FALSE(farthest.strictMinimum) << farthest.reason;
  EXPECT_LT(farthest.smallestEigenvalue, -farthest.roundingFloor) << farthest.reason;
  EXPECT_EQ(farthest.dependent, 0);  // unique multipliers: a saddle, not merely unproven
  EXPECT_NE(farthest.reason.find("saddle"), std::string::npos) << farthest.reason;

  // Centred on the midpoint, every point of the circle is as good: a flat direction.
  const SecondOrderCheck flat = checkOnCircle(0.0, 1.0, Eigen::Vector3d(0, 0.6, 0.8));
  ASSERT_TRUE(flat.checked) << flat.reason;
  EXPECT_LT(flat.stationarity, 1e-9);
  EXPECT_FALSE(flat.strictMinimum) << flat.reason;
  EXPECT_LE(std::abs(flat.smallestEigenvalue), flat.roundingFloor) << flat.reason;
  EXPECT_FALSE(flat.strictMotion) << "the flat direction moves the particle, not a force: " << flat.reason;
}

// The 3D lamp's base stands on four points, so its load is statically indeterminate; where the
// load-sharing term has no weight (samples of zero quadrature weight) nothing decides the split,
// and those directions are flat - but they move contact forces only, so the motion itself is
// still a strict minimum.
TEST(SecondOrder, The3DLampsMotionIsStrictThoughSomeOfItsForcesAreFree) {
  auto problem = solvedShipped("luxo_3d.json");
  ASSERT_TRUE(problem);
  const SecondOrderCheck check = checkSecondOrder(*problem, 2);
  ASSERT_TRUE(check.checked) << check.reason;
  EXPECT_FALSE(check.strictMinimum) << check.reason;
  EXPECT_TRUE(check.strictMotion) << check.reason;
  EXPECT_GT(check.freeForceDirections, 0);
  EXPECT_GT(check.motionEigenvalue, check.roundingFloor);
  ASSERT_FALSE(check.direction.empty());
  EXPECT_NE(check.direction.front().find("force"), std::string::npos) << check.direction.front();
}

// The same reduced Hessian from a dense orthonormal basis of null(A) (the right singular vectors
// of A beyond its numerical rank): the same number of free directions and the same eigenvalues.
TEST(SecondOrder, TheJumpsReducedHessianMatchesADenseNullSpace) {
  auto problem = solvedShipped("luxo_jump.json");
  ASSERT_TRUE(problem);
  const SecondOrderCheck check = checkSecondOrder(*problem, 2);
  ASSERT_TRUE(check.checked) << check.reason;
  EXPECT_TRUE(check.strictMinimum) << check.reason;

  const raw::Variables vars(problem->ceresProblem());
  raw::RawEvaluator evaluator(*problem, vars, 2);
  raw::RawRows rows;
  ASSERT_TRUE(evaluator.evaluate(&rows, true));
  MultiplierEstimate estimate;
  const Eigen::VectorXd y = stationaryMultipliers(*problem, evaluator, rows, &estimate);
  ASSERT_TRUE(estimate.ok);
  const int n = vars.tangent;
  const double largest = std::max(1.0, y.lpNorm<Eigen::Infinity>());
  std::vector<int> active;
  Eigen::VectorXd w = Eigen::VectorXd::Zero(evaluator.rows());
  for (int r = 0; r < evaluator.rows(); ++r) {
    const RowKind kind = evaluator.kind(r);
    if (kind == RowKind::Objective) {
      w[r] = rows.values[r];
    } else if (kind == RowKind::Equality ||
               (rows.values[r] > -raw::kAtBound && y[r] > 1e-9 * largest)) {
      active.push_back(r);
      w[r] = y[r];
    }
  }
  ASSERT_EQ(static_cast<int>(active.size()), check.constraints);
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(n, n);
  raw::Triplets t = evaluator.curvature(w, 2);
  evaluator.appendGaussNewton(rows, &t);
  for (const auto& e : t) {  // lower triangle
    W(e.row(), e.col()) += e.value();
    if (e.row() != e.col()) W(e.col(), e.row()) += e.value();
  }
  const Eigen::MatrixXd A = Eigen::MatrixXd(raw::SpMat(raw::selectRows(rows.jacobian, active)));
  const Eigen::BDCSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullV);
  int rank = 0;
  for (Eigen::Index i = 0; i < svd.singularValues().size(); ++i)
    rank += svd.singularValues()[i] > 1e-9 * svd.singularValues()[0];
  ASSERT_EQ(n - rank, check.nullity);
  const Eigen::MatrixXd Z = svd.matrixV().rightCols(n - rank);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(Z.transpose() * W * Z);
  EXPECT_NEAR(eigen.eigenvalues()[0], check.smallestEigenvalue, 1e-9 * std::abs(check.largestEigenvalue));
  EXPECT_NEAR(eigen.eigenvalues()[n - rank - 1], check.largestEigenvalue, 1e-9 * std::abs(check.largestEigenvalue));
}

TEST(SecondOrder, TheHurdlesTwoOptimaAreBothStrictMinima) {
  const Scene scene = testing::shippedScene("luxo_hurdle.json");
  std::vector<double> objectives;
  for (SolverMethod method : {SolverMethod::AugmentedLagrangian, SolverMethod::Sqp}) {
    std::string error;
    auto problem = SpacetimeProblem::build(scene, &error);
    ASSERT_TRUE(problem) << error;
    SolverOptions options;
    options.threads = 2;
    options.method = method;
    const SolverSummary s = solveSpacetime(*problem, options);
    ASSERT_TRUE(s.converged) << s.reason;
    objectives.push_back(s.objective);
    const SecondOrderCheck check = checkSecondOrder(*problem, 2);
    ASSERT_TRUE(check.checked) << check.reason;
    EXPECT_LT(check.stationarity, 1e-5) << toString(method);
    EXPECT_TRUE(check.strictMinimum) << toString(method) << ": " << check.reason;
  }
  // Two different minima (28.5685 and 33.3150 when measured), not one reached twice.
  EXPECT_GT(std::abs(objectives[0] - objectives[1]), 1.0);
}

}  // namespace
}  // namespace spacetime
