// The `witkin-kass` method: the seed's projected Newton method (Witkin & Kass, "Spacetime
// Constraints", SIGGRAPH 1988, section 4) made globally convergent as a feasible-path SQP.
//
// Every iterate is first restored onto the constraints - the equalities and the inequalities
// (contact pushes and cones, clearances, limits) held as inequalities - by the restoration
// phase (restoration.h: Gauss-Newton steps on the violation alone, nearly undamped, measured in
// the effort's metric, so the correction that changes the effort least). From a restored
// motion x a step solves one quadratic program (quadratic_program.h)
//     min 1/2 d^T W d + grad f . d   subject to   c + A d = 0,   g + C d <= 0
// with W = J_r^T J_r, the effort's Gauss-Newton Hessian, and the inequalities within a margin
// of their bound: the Newton step on the objective in the constraints' null space. The trial
// point x + alpha d is restored again and accepted when the objective fell (Armijo's rule on f
// over restored points, alpha halved otherwise), so the live view shows a motion that meets
// every constraint to 1e-6 after each step, its effort falling.
//
// The steps converge linearly; the augmented Lagrangian finishes (its warm start begins with
// the Newton polish), from the last restored motion and the programs' multipliers. Where the starting motion does not restore, a few
// multiplier updates of the augmented Lagrangian approach the constraints first; where that
// motion does not restore either, the augmented Lagrangian solves from the starting motion. The
// summary says which. Warm starts and free contact ends go to the augmented Lagrangian's path
// directly (its warm start begins with the Newton polish).
#pragma once

#include <atomic>

#include "solver/augmented_lagrangian.h"

namespace spacetime {

SolverSummary solveWitkinKass(SpacetimeProblem& problem, const SolverOptions& options,
                              const ProgressCallback& callback = nullptr, const std::atomic<bool>* cancel = nullptr);

}  // namespace spacetime
