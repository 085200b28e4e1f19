// One restoration step (see restoration.h).
#include "solver/restoration.h"

#include <algorithm>
#include <cmath>

#include "raw_rows.h"
#include "solver/quadratic_program.h"

namespace spacetime {

using raw::Clock;
using raw::RawEvaluator;
using raw::RawRows;
using raw::secondsSince;
using raw::SpMat;
using raw::SpRow;
using raw::Variables;
using raw::Vec;

namespace {

double largestViolation(const RawEvaluator& evaluator, const Vec& values) {
  double worst = 0;
  for (int r = 0; r < evaluator.rows(); ++r) {
    if (evaluator.kind(r) == RowKind::Equality) worst = std::max(worst, std::abs(values[r]));
    if (evaluator.kind(r) == RowKind::Inequality) worst = std::max(worst, values[r]);
  }
  return worst;
}

}  // namespace

RestorationStep restorationStep(SpacetimeProblem& problem, double damping, int threads) {
  const Clock::time_point start = Clock::now();
  RestorationStep step;
  auto finish = [&](const std::string& reason) {
    step.reason = reason;
    step.seconds = secondsSince(start);
    return step;
  };
  if (!problem.freeEnds().empty()) return finish("free contact ends are bounded variables");
  const Variables vars(problem.ceresProblem());
  RawEvaluator evaluator(problem, vars, std::max(1, threads));
  if (evaluator.anyMoving()) return finish("a residual moves with a free contact end");
  RawRows rows;
  if (!evaluator.evaluate(&rows, true)) return finish("a row is not finite");
  step.violationBefore = step.violationAfter = largestViolation(evaluator, rows.values);

  std::vector<int> equality, inequality;
  for (int r = 0; r < evaluator.rows(); ++r) {
    if (evaluator.kind(r) == RowKind::Equality) equality.push_back(r);
    if (evaluator.kind(r) == RowKind::Inequality) inequality.push_back(r);
  }
  const int n = vars.tangent;
  const SpRow Jc = raw::selectRows(rows.jacobian, equality);
  Vec c(static_cast<Eigen::Index>(equality.size()));
  for (size_t i = 0; i < equality.size(); ++i) c[static_cast<Eigen::Index>(i)] = rows.values[equality[i]];
  QuadraticProgram qp;
  SpMat identity(n, n);
  identity.setIdentity();
  qp.hessian = SpMat(SpMat(Jc.transpose()) * Jc) + damping * identity;
  qp.gradient = Jc.transpose() * c;
  qp.equalities.resize(0, n);
  qp.equalityTargets.resize(0);
  qp.inequalities = raw::selectRows(rows.jacobian, inequality);
  qp.inequalityBounds.resize(static_cast<Eigen::Index>(inequality.size()));
  for (size_t i = 0; i < inequality.size(); ++i) qp.inequalityBounds[static_cast<Eigen::Index>(i)] = -rows.values[inequality[i]];
  // Tight: near a feasible point the step is of the size of the violation, and an inexact
  // interior point leaves rows whose multipliers are nearly zero off by mu / z.
  QpOptions options;
  options.tolerance = 1e-13;
  const Clock::time_point qpStart = Clock::now();
  const QpResult result = solveQuadraticProgram(qp, options);
  step.qpSeconds = secondsSince(qpStart);
  step.qpIterations = result.iterations;
  if (!result.converged) return finish("the restoration program was not solved: " + result.reason);

  const std::vector<double> before = vars.save();
  vars.plus(before, result.x);
  RawRows after;
  if (!evaluator.evaluate(&after, false)) {
    vars.load(before);
    return finish("the step leads to rows that are not finite");
  }
  step.taken = true;
  step.violationAfter = largestViolation(evaluator, after.values);
  return finish("");
}

}  // namespace spacetime
