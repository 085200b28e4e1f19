// What the two quadratic-program methods - `sqp` (sqp.cpp) and `witkin-kass` (witkin_kass.cpp) -
// share around their programs: the rows split by kind, the programs' multipliers handed to the
// augmented-Lagrangian state (where the Newton polish and any later warm start read them), the
// polish itself, and the accounting of a phase's time in the summary of the method that
// finishes the solve.
#pragma once

#include <algorithm>
#include <atomic>
#include <vector>

#include "raw_rows.h"
#include "solver/augmented_lagrangian.h"
#include "solver/newton_polish.h"

namespace spacetime::raw {

// An inequality this close to its bound is active for the polish.
constexpr double kAtBound = 1e-6;

// The triplets of M, shifted by (rowOffset, colOffset).
inline void appendTriplets(const SpRow& M, int rowOffset, int colOffset, Triplets* t) {
  for (int row = 0; row < M.outerSize(); ++row)
    for (SpRow::InnerIterator e(M, row); e; ++e)
      t->emplace_back(rowOffset + row, colOffset + static_cast<int>(e.col()), e.value());
}

// A linearised inequality above this is crossed by the step.
constexpr double kCrossed = 1e-9;

// Inequalities within this of their bound (or with a multiplier) join a step's program; rows a
// step then crosses join and it is solved again, up to kMaxRounds times. Of the jump's 4332
// inequality rows 415 are within 0.05 at its optimum and 22 active (docs/design.md, inequality
// screening).
constexpr double kMargin = 0.05;
constexpr int kMaxRounds = 10;

// From now on `evaluator` computes the Jacobians of the objective rows, the equalities, the
// inequalities `held` (one entry per row) and any row above `below` (RawEvaluator::limitJacobians):
// what the Newton-type steps on the held rows read.
inline void limitJacobiansToHeld(RawEvaluator& evaluator, const std::vector<char>& held, double below) {
  std::vector<char> needed(held.size());
  for (size_t row = 0; row < held.size(); ++row)
    needed[row] = evaluator.kind(static_cast<int>(row)) != RowKind::Inequality || held[row];
  evaluator.limitJacobians(needed, below);
}

// The KKT residual of min 1/2 |objective rows|^2 subject to the rows `held` (one entry per row)
// at zero, with their `multipliers` (one per row), at `rows` evaluated with the Jacobians of the
// objective rows and the held rows: what the Newton polish (newton_polish.cpp) and its steps on
// a kept factorisation (chord_steps.cpp) judge a point by.
struct HeldKkt {
  std::vector<int> constraint;  // the held rows, in order
  Vec y;                        // their multipliers
  Vec r, c;                     // the objective rows' values, the held rows'
  Vec grad;                     // J_r^T r
  Vec lagrangianGradient;       // J_r^T r + J_c^T y
  double kkt = 0;               // |J_r^T r + J_c^T y|_inf / max(1, |J_r^T r|_inf)
  double heldViolation = 0;     // |c|_inf
  double violation = 0;         // the held rows' and the other inequalities' above their bound
  double pull = 0;              // a held inequality whose multiplier is below this pulls
};
inline HeldKkt heldKkt(const RawEvaluator& evaluator, const RawRows& rows, const std::vector<int>& objective,
                       const std::vector<char>& held, const Vec& multipliers) {
  HeldKkt k;
  for (size_t row = 0; row < held.size(); ++row)
    if (held[row]) k.constraint.push_back(static_cast<int>(row));
  k.y = selectValues(multipliers, k.constraint);
  k.r = selectValues(rows.values, objective);
  k.c = selectValues(rows.values, k.constraint);
  k.grad = transposeTimes(rows.jacobian, objective, k.r);
  k.lagrangianGradient = k.grad + transposeTimes(rows.jacobian, k.constraint, k.y);
  k.kkt = k.lagrangianGradient.lpNorm<Eigen::Infinity>() / std::max(1.0, k.grad.lpNorm<Eigen::Infinity>());
  k.heldViolation = k.c.size() ? k.c.lpNorm<Eigen::Infinity>() : 0.0;
  k.violation = k.heldViolation;
  for (size_t row = 0; row < held.size(); ++row)
    if (evaluator.kind(static_cast<int>(row)) == RowKind::Inequality && !held[row])
      k.violation = std::max(k.violation, rows.values[static_cast<Eigen::Index>(row)]);
  k.pull = -1e-6 * std::max(1.0, k.y.size() ? k.y.lpNorm<Eigen::Infinity>() : 0.0);
  return k;
}

// The inequalities a step's program left out that its step crosses (linearised values
// `linear`, one per inequality) join `held` (indices into the inequalities, kept sorted);
// true if any did.
inline bool holdCrossedRows(const Vec& linear, std::vector<int>* held) {
  std::vector<char> isHeld(static_cast<size_t>(linear.size()), 0);
  for (int i : *held) isHeld[static_cast<size_t>(i)] = 1;
  const size_t before = held->size();
  for (Eigen::Index i = 0; i < linear.size(); ++i)
    if (!isHeld[static_cast<size_t>(i)] && linear[i] > kCrossed) held->push_back(static_cast<int>(i));
  std::sort(held->begin(), held->end());
  return held->size() != before;
}

// The metric of the programs' inertia shift (QuadraticProgram::shiftMetric): 1 per variable,
// 1 / weight^2 on each contact force - the variables in their natural units (forces as fractions
// of the character's weight, as the cones and the load sharing read them). With the identity a
// shift of 1e-3, which the jump's exact-Hessian programs need, weighs on the forces as 0.3 would
// on the angles and damps the flat directions the steps converge along (its curvature there is
// 1e-5 to 1e-4): 21 of the jump's 35 steps were that tail (docs/design.md, SQP).
inline Vec shiftMetric(const SpacetimeProblem& problem, const Variables& vars) {
  Vec metric = Vec::Ones(vars.tangent);
  const double* x = problem.variables().data();
  for (const ContactVariables& contact : problem.contacts()) {
    const double weight = problem.characters()[static_cast<size_t>(contact.character)].weight;
    for (size_t i = 0; i < contact.times.size(); ++i) {
      const auto block = vars.columns.find(x + contact.sampleOffset(static_cast<int>(i)));
      if (block == vars.columns.end()) continue;
      for (int column : block->second)
        if (column >= 0) metric[column] = 1 / (weight * weight);
    }
  }
  return metric;
}

// Hands the multipliers y (one per row: equalities free, inequalities >= 0) to the
// augmented-Lagrangian state as lambda + rho c, so rho = 0 makes them the estimates themselves.
// The polish holds at zero each inequality with a positive multiplier. An interior point leaves
// every row one of about mu/slack (the jump's first polish, holding them all, stepped to a
// violation of 3.7), so only the rows at their bound are handed over as active - with a tiny
// multiplier where theirs is zero (weakly active rows): dropping those left the polish's reduced
// Hessian indefinite at the jump's optimum, and every Newton step failed.
inline void handOverMultipliers(const RawEvaluator& evaluator, const Vec& y, const Vec& values, double rho,
                                AugmentedLagrangianState* state) {
  const double floor = 1e-8 * std::max(1.0, y.lpNorm<Eigen::Infinity>());
  for (int r = 0; r < evaluator.rows(); ++r) {
    if (evaluator.kind(r) == RowKind::Objective) continue;
    if (evaluator.kind(r) == RowKind::Equality) state->lambda[evaluator.multiplier(r)] = y[r];
    else state->lambda[evaluator.multiplier(r)] = values[r] > -kAtBound ? std::max(y[r], floor) : 0.0;
  }
  state->rho = rho;
}

// The Newton polish from the multipliers in the state, its time added to the summary; on
// failure it restores its start.
inline PolishResult polishInto(SpacetimeProblem& problem, const SolverOptions& options, int threads,
                               Clock::time_point deadline, const std::atomic<bool>* cancel, SolverSummary* summary) {
  PolishOptions po;
  po.tolerance = options.tolerance;
  po.maxIterations = options.maxPolishIterations;
  po.threads = threads;
  po.deadline = deadline;
  const PolishResult polished = polishNewton(problem, po, cancel);
  addPolishTo(polished, summary);
  return polished;
}

// A method's own ending: the status and the measures of the problem's current motion.
inline SolverSummary finishedAs(SolveStatus status, const SpacetimeProblem& problem, Clock::time_point start,
                                SolverSummary summary) {
  const ProblemMeasures m = measure(problem);
  summary.status = status;
  summary.converged = status == SolveStatus::Converged;
  summary.objective = m.objective;
  summary.maxViolation = m.maxViolation;
  summary.worstConstraint = m.worstConstraint;
  summary.solveSeconds = secondsSince(start);
  return summary;
}

// A method's own phase followed by the augmented Lagrangian: the phase's steps and times join
// the summary of the solve that finished.
inline void addPhaseTo(const SolverSummary& phase, SolverSummary* total) {
  total->iterations += phase.iterations;
  total->outerIterations += phase.outerIterations;
  total->linearSolverSeconds += phase.linearSolverSeconds;
  total->sqpSteps += phase.sqpSteps;
  total->sqpSeconds += phase.sqpSeconds;
  total->qpSeconds += phase.qpSeconds;
  total->restorationSteps += phase.restorationSteps;
  total->restorationSeconds += phase.restorationSeconds;
  total->newtonSteps += phase.newtonSteps;
  total->newtonSolves += phase.newtonSolves;
  total->jacobianSeconds += phase.jacobianSeconds;
  total->polishSeconds += phase.polishSeconds;
  total->polishEvaluationSeconds += phase.polishEvaluationSeconds;
  total->hessianSeconds += phase.hessianSeconds;
  total->factorisationSeconds += phase.factorisationSeconds;
  total->lineSearchSeconds += phase.lineSearchSeconds;
}

}  // namespace spacetime::raw
