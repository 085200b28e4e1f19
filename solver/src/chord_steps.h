// Newton steps on a kept factorisation: the Newton polish's KKT matrix at the last optimum,
// factorised once, reused for the steps after an edit of the task.
//
// An edit that moves a target (a pin, the end pose) changes the rows' values and not their
// derivatives: at the old optimum the new problem's KKT matrix is the old one, and the first
// Newton step on it is the tangential predictor of parametric optimisation. The steps after it
// keep the matrix and evaluate only the rows and their Jacobians at each point: the right-hand
// side is the true KKT residual (the gradient of the Lagrangian with the current Jacobian, the
// rows' values), so their fixed points are the new problem's KKT points, and the fixed matrix
// only sets the rate (a chord method, as the real-time iterations of optimal control reuse a
// factorisation across sampling times: Diehl, Bock and Schloeder 2005). The rate is the matrix's
// error times the distance: on the jump's end pose moved 2 cm, the residual falls 10-40 times a
// step.
//
// An edit can change the active set. Rows outside the factorised block join it as a border (the
// Schur complement of the factorised block, one back-solve per bordered row, with the row's
// Jacobian where it joined), and a held row leaves it by a border that fixes its multiplier at
// zero and frees its equation. Each step solves the quadratic program of the kept matrix - the
// held rows as equalities, every other inequality linearised - by such changes: a row the step
// would violate joins (the most violated first), a held row whose multiplier would pull leaves
// (the most pulling first; each row once, as a degenerate contact's cone sides and normal force
// would otherwise leave and join in turn). At a KKT point of the held rows those that pull are
// released, as the polish does. These are the active-set steps of quadratic_program.h on a
// factorisation kept from another point.
//
// An edit too large for that (the first step's program does not settle: moved 10 cm, the jump's
// landing changes more than 25 rows of the active set) is made gradually, by continuation in the
// task (Allgower and Georg, Introduction to Numerical Continuation Methods, ch. 2): the edit's
// change e of the rows at the kept optimum (NewtonFactors::values) defines the problems with rows
// r(x) - (1 - theta) e, which the kept optimum solves at theta = 0 and which are the edited
// problem at theta = 1. Each step aims at theta + stride, the stride halved (before anything is
// evaluated) while its program does not settle; a stage's point takes further steps at its
// theta until it tracks the path (residual below 1e-3) before theta moves on. The steps stand
// on the kept factorisation throughout, as real-time iterations track a moving reference.
//
// The steps stop as soon as the residual stops falling fast (a large edit, a new active set
// the old matrix does not describe, the rounding floor of a matrix of another point): the
// caller then takes full Newton steps, which factorise the matrix at the current point, from
// where the steps stopped or from its start.
#pragma once

#include <Eigen/SparseCholesky>
#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "raw_rows.h"
#include "solver/newton_polish.h"

namespace spacetime {

// The KKT matrix K = [W A^T; A -dc I] of a Newton step (its lower triangle) and its LDL^T.
struct KktFactorisation {
  raw::SpMat matrix;
  Eigen::SimplicialLDLT<raw::SpMat, Eigen::Lower, Eigen::AMDOrdering<int>> ldlt;
};

// The KKT factorisation of a polish's last Newton step, the rows A holds (in K's order), and
// the rows' values at the optimum this travels with. Kept with the multipliers
// (AugmentedLagrangianState::newtonFactors), so a warm start from the solution finds it; a polish
// that reaches its optimum by steps on the factorisation passes it on, shared, with its own
// optimum's values.
struct NewtonFactors {
  int variables = 0, rows = 0;  // the problem's tangent size and its row count
  std::vector<int> constraint;  // K's constraint rows (problem rows), in order
  double constraintRegularisation = 0;  // dc
  std::shared_ptr<const KktFactorisation> kkt;
  // The raw rows' layout of the polish that factorised K: the next warm polish's evaluator takes
  // it where the problem's structure is the same (raw::RowLayout).
  std::shared_ptr<const raw::RowLayout> layout;
  // The rows' values at the optimum (one per row): an edit's change of the rows there is the
  // steps' continuation (chordSteps).
  raw::Vec values;
};

namespace raw {

struct ChordResult {
  bool converged = false;  // at a KKT point of the held rows with every held inequality pushing
  int steps = 0;           // steps taken (each one evaluation of the rows and Jacobians)
  // max(stationarity, violation) where the steps started and where they stopped
  double startResidual = 0, residual = 0;
  std::string reason;
};

// Steps on `factors` from the current variables (their rows `rows`, evaluated with the Jacobians
// of the rows held), the rows `held` (per row) and their `multipliers` (per row), towards a KKT
// point of min 1/2 |objective rows|^2 subject to the held rows at zero (newton_polish.h), to
// the options' tolerance on the rows and kktTolerance on the stationarity relative to
// max(1, |J_r^T r|); they stop at the options' deadline and when `cancel` is set.
// Rows the steps hold join `held` and `added`. On success the variables, `rows`, `held` and
// `multipliers` describe the KKT point; otherwise they are where the steps stopped, and the
// caller restores what it needs.
ChordResult chordSteps(const NewtonFactors& factors, RawEvaluator& evaluator, const Variables& vars,
                       const std::vector<int>& objective, const PolishOptions& options,
                       const std::atomic<bool>* cancel, RawRows* rows, std::vector<char>* held,
                       std::vector<char>* added, Vec* multipliers);

}  // namespace raw
}  // namespace spacetime
