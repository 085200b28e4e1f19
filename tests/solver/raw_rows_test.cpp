// The raw rows' evaluator (solver/src/raw_rows.h), which the Newton polish, the SQP, the
// restoration, Witkin-Kass and the interior point share, against Ceres's own
// Problem::Evaluate of the same residual blocks in the same columns: the evaluator calls each
// cost function itself and scatters its block Jacobians into a row pattern fixed once, so its
// rows and its Jacobian must be Ceres's to the last bit (to rounding for the kinematic kernels,
// whose Jacobian it takes through the body's spatial Jacobian) - on the held stances' partly constant
// blocks (SubsetManifold), on a free lift-off's moving rows, with one and with two threads, and
// with the Jacobians of the inequalities a caller does not need left out.
#include <gtest/gtest.h>

#include <ceres/ceres.h>

#include <Eigen/Dense>

#include "../../solver/src/raw_rows.h"
#include "../shipped_scene.h"
#include "perturbed.h"
#include "solver/spacetime_problem.h"

namespace spacetime {
namespace {

// Ceres's rows and dense Jacobian of every residual block in the tangent columns of `vars`.
// Without `jacobian`, the rows alone (the kernels' double path, which may differ from their Jets'
// values in the last bit).
void ceresRows(SpacetimeProblem& problem, const raw::Variables& vars, Eigen::VectorXd* rows,
               Eigen::MatrixXd* jacobian) {
  ceres::Problem::EvaluateOptions options;
  options.parameter_blocks = vars.blocks;
  problem.ceresProblem().GetResidualBlocks(&options.residual_blocks);
  AugmentedLagrangianState& al = problem.augmentedLagrangian();
  al.raw = true;
  double cost = 0;
  std::vector<double> values;
  ceres::CRSMatrix J;
  ASSERT_TRUE(problem.ceresProblem().Evaluate(options, &cost, &values, nullptr, jacobian ? &J : nullptr));
  al.raw = false;
  *rows = Eigen::Map<const Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size()));
  if (!jacobian) return;
  *jacobian = Eigen::MatrixXd::Zero(J.num_rows, J.num_cols);
  for (int r = 0; r < J.num_rows; ++r)
    for (int k = J.rows[r]; k < J.rows[r + 1]; ++k) (*jacobian)(r, J.cols[k]) = J.values[k];
}

// How far each of the evaluator's rows may be from Ceres's, values and Jacobian: 0, but to
// rounding (1e-12 of the row's largest entry) for the kinematic kernels, whose Jacobian the
// evaluator takes through the body's spatial Jacobian (Kernel::rawJacobian) and Ceres through Jets.
std::vector<double> rowTolerance(const raw::RawEvaluator& evaluator, const Eigen::MatrixXd& expected) {
  std::vector<double> tolerance(static_cast<size_t>(evaluator.rows()), 0.0);
  for (size_t k = 0; k < evaluator.terms().size(); ++k) {
    const Kernel& kernel = evaluator.terms()[k]->kernel();
    const bool kinematic = dynamic_cast<const GroundClearanceKernel*>(&kernel) || dynamic_cast<const ClearanceKernel*>(&kernel) ||
                           dynamic_cast<const PinKernel*>(&kernel) || dynamic_cast<const ContactAnchorKernel*>(&kernel);
    if (!kinematic) continue;
    for (int r = evaluator.firstRow(k); r < evaluator.firstRow(k) + kernel.rowCount(); ++r)
      tolerance[static_cast<size_t>(r)] = 1e-12 * std::max(1.0, expected.row(r).cwiseAbs().maxCoeff());
  }
  return tolerance;
}

// The evaluator's rows and Jacobian are Ceres's (within rowTolerance).
void expectRowsWithin(const raw::RawRows& rows, const Eigen::VectorXd& expectedRows, const Eigen::MatrixXd& expected,
                      const std::vector<double>& tolerance) {
  const Eigen::MatrixXd J(rows.jacobian);
  ASSERT_EQ(rows.values.size(), expectedRows.size());
  ASSERT_EQ(J.rows(), expected.rows());
  ASSERT_EQ(J.cols(), expected.cols());
  int kinematic = 0;
  for (int r = 0; r < J.rows(); ++r) {
    EXPECT_LE(std::abs(rows.values[r] - expectedRows[r]), tolerance[static_cast<size_t>(r)]) << "row " << r;
    EXPECT_LE((J.row(r) - expected.row(r)).cwiseAbs().maxCoeff(), tolerance[static_cast<size_t>(r)]) << "row " << r;
    kinematic += tolerance[static_cast<size_t>(r)] > 0;
  }
  EXPECT_GT(kinematic, 0);
}

void expectCeresRows(SpacetimeProblem& problem) {
  testing::perturb(problem, 7, 0.05);
  const raw::Variables vars(problem.ceresProblem());
  Eigen::VectorXd expectedRows;
  Eigen::MatrixXd expected;
  ceresRows(problem, vars, &expectedRows, &expected);
  Eigen::VectorXd expectedValuesOnly;
  ceresRows(problem, vars, &expectedValuesOnly, nullptr);
  for (int threads : {1, 2}) {
    SCOPED_TRACE(threads);
    raw::RawEvaluator evaluator(problem, vars, threads);
    const std::vector<double> tolerance = rowTolerance(evaluator, expected);
    raw::RawRows rows;
    ASSERT_TRUE(evaluator.evaluate(&rows, true));
    expectRowsWithin(rows, expectedRows, expected, tolerance);
    EXPECT_GT(expected.cwiseAbs().maxCoeff(), 0.0);
    // A second evaluation into the same rows reuses their pattern and overwrites every value.
    rows.jacobian.coeffs() *= 3;
    ASSERT_TRUE(evaluator.evaluate(&rows, true));
    expectRowsWithin(rows, expectedRows, expected, tolerance);
    // Without the Jacobian: the same rows.
    raw::RawRows valuesOnly;
    ASSERT_TRUE(evaluator.evaluate(&valuesOnly, false));
    EXPECT_EQ((valuesOnly.values - expectedValuesOnly).cwiseAbs().maxCoeff(), 0.0);
  }
  // Inequalities no caller needs and none near its bound: the blocks of such rows alone are
  // evaluated without their Jets and get zero Jacobian rows; every other row is Ceres's.
  raw::RawEvaluator evaluator(problem, vars, 2);
  std::vector<char> needed(evaluator.rows(), 1);
  for (int r = 0; r < evaluator.rows(); ++r)
    if (evaluator.kind(r) == RowKind::Inequality) needed[r] = 0;
  evaluator.limitJacobians(needed, 1e9);
  raw::RawRows limited;
  ASSERT_TRUE(evaluator.evaluate(&limited, true));
  EXPECT_LT((limited.values - expectedRows).cwiseAbs().maxCoeff(), 1e-12);  // some by the double path
  const Eigen::MatrixXd J(limited.jacobian);
  const std::vector<double> tolerance = rowTolerance(evaluator, expected);
  int dropped = 0;
  for (int r = 0; r < evaluator.rows(); ++r) {
    if ((J.row(r) - expected.row(r)).cwiseAbs().maxCoeff() <= tolerance[static_cast<size_t>(r)]) continue;
    EXPECT_EQ(evaluator.kind(r), RowKind::Inequality) << "row " << r;
    EXPECT_EQ(J.row(r).cwiseAbs().maxCoeff(), 0.0) << "row " << r;
    ++dropped;
  }
  EXPECT_GT(dropped, evaluator.rows() / 10);
}

TEST(RawRows, TheEvaluatorGivesCeressRowsAndJacobian) {
  for (const char* name : {"luxo_jump.json", "luxo_3d.json", "biped_jump.json"}) {
    SCOPED_TRACE(name);
    std::string error;
    auto problem = SpacetimeProblem::build(testing::shippedScene(name), &error);
    ASSERT_TRUE(problem) << error;
    expectCeresRows(*problem);
  }
}

TEST(RawRows, AFreeLiftOffsMovingRowsAreCeressToo) {
  Scene scene = testing::shippedScene("luxo_jump.json");
  for (TermSpec& t : scene.terms)
    if (t.id == "takeoff") t.freeEnd = true;
  std::string error;
  auto problem = SpacetimeProblem::build(scene, &error);
  ASSERT_TRUE(problem) << error;
  ASSERT_FALSE(problem->freeEnds().empty());
  expectCeresRows(*problem);
}

// An evaluator of a problem rebuilt after an edit of a target (the jump's end pose moved: the same
// structure) takes the last evaluator's layout (RowLayout) and gives the rows and Jacobian of an
// evaluator that built its own, to the bit; one of another structure (the jump at another
// control-point rate) builds its own.
TEST(RawRows, AnEditOfATargetReusesTheRowLayout) {
  Scene scene = testing::shippedScene("luxo_jump.json");
  std::string error;
  auto first = SpacetimeProblem::build(scene, &error);
  ASSERT_TRUE(first) << error;
  const raw::Variables firstVars(first->ceresProblem());
  const raw::RawEvaluator firstEvaluator(*first, firstVars, 1);
  for (TermSpec& t : scene.terms)
    if (t.id == "end_pose")
      for (auto& [dof, value] : t.values)
        if (dof == "base_x") value += 0.02;
  auto moved = SpacetimeProblem::build(scene, &error);
  ASSERT_TRUE(moved) << error;
  testing::perturb(*moved, 5, 0.05);
  const raw::Variables vars(moved->ceresProblem());
  raw::RawEvaluator reusing(*moved, vars, 2, firstEvaluator.layout());
  EXPECT_EQ(reusing.layout(), firstEvaluator.layout());
  raw::RawEvaluator own(*moved, vars, 2);
  EXPECT_NE(own.layout(), firstEvaluator.layout());
  raw::RawRows a, b;
  ASSERT_TRUE(reusing.evaluate(&a, true));
  ASSERT_TRUE(own.evaluate(&b, true));
  EXPECT_EQ((a.values - b.values).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(Eigen::MatrixXd(a.jacobian), Eigen::MatrixXd(b.jacobian));
  EXPECT_GT(a.jacobian.nonZeros(), 0);

  scene.transcription.controlPointsPerSecond += 5;
  auto finer = SpacetimeProblem::build(scene, &error);
  ASSERT_TRUE(finer) << error;
  const raw::Variables finerVars(finer->ceresProblem());
  raw::RawEvaluator other(*finer, finerVars, 1, firstEvaluator.layout());
  EXPECT_NE(other.layout(), firstEvaluator.layout());
  raw::RawRows c;
  ASSERT_TRUE(other.evaluate(&c, true));
  EXPECT_EQ(c.jacobian.cols(), finerVars.tangent);
  EXPECT_EQ(c.values.size(), other.rows());
}

}  // namespace
}  // namespace spacetime
