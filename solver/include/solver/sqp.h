// The `sqp` method: Cohen's sequential quadratic programming on the spacetime problem, made
// globally convergent (Nocedal & Wright, Numerical Optimization, 2nd ed., chapter 18).
//
// Each step solves one quadratic program (quadratic_program.h) on the rows as Ceres evaluates
// them: the objective's quadratic model, every equality linearised, and the inequalities
// (contact pushes and cones, clearances, limits) linearised as inequalities - those within a
// margin of their bound, re-solved with any a step crosses. Far from feasibility the program is
// elastic (Fletcher's Sl1QP: the equalities and the violated inequalities get l1-penalised
// slacks, weight nu, so it always has a point) and its Hessian is Gauss-Newton; near it the rows
// are hard and the Hessian is the exact one of the Lagrangian. Steps are accepted by a line
// search on the l1 merit f + nu (|c|_1 + |max(0, g)|_1) (N&W 18.3) with a second-order
// correction (N&W 18.3, "Maratos effect"). Once the violation is small the Newton polish
// (newton_polish.h: the KKT steps on the active rows, quadratically convergent) finishes from
// the programs' multipliers and active set.
//
// Where the steps fail (a line search finds no decrease, the step budget ends) the method
// restores the starting point and the augmented Lagrangian solves from there, so `sqp` solves
// whatever `al` solves; the summary says so. A warm start (an edit in the editor, a refined
// transcription) steps with the exact Hessian from the stored multipliers, the first program
// guessing their active rows: the jump's end pose moved 2 or 10 cm lands on the cold solve's
// optimum in 2 or 4 steps. Free contact ends go to the augmented Lagrangian's path directly.
#pragma once

#include <atomic>

#include "solver/augmented_lagrangian.h"

namespace spacetime {

SolverSummary solveSqp(SpacetimeProblem& problem, const SolverOptions& options,
                       const ProgressCallback& callback = nullptr, const std::atomic<bool>* cancel = nullptr);

// The steps alone, warm from the problem's augmented-Lagrangian multipliers, for the augmented
// Lagrangian where its Newton polish failed near feasibility (docs/design.md, Solver item 1):
// the exact-Hessian programs damped proximally (delta times the shift metric on the Hessian,
// grown after steps the line search cuts and shrunk after full ones). Converged, the problem
// holds the KKT point; otherwise (status IterationLimit) its start is restored and the reason
// says why the steps stopped. Not run with free contact ends.
SolverSummary sqpStepsNearFeasible(SpacetimeProblem& problem, const SolverOptions& options,
                                   const std::atomic<bool>* cancel = nullptr);

}  // namespace spacetime
