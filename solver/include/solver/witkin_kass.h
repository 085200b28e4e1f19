// The `witkin-kass` method: the seed's projected Newton method (Witkin & Kass, "Spacetime
// Constraints", SIGGRAPH 1988, section 4) made globally convergent as a feasible-path SQP.
//
// Every iterate is first restored onto the constraints - the equalities and the inequalities
// (contact pushes and cones, clearances, limits) held as inequalities - by the restoration
// phase (restoration.h: Gauss-Newton steps on the violation alone, nearly undamped, so the
// minimum-norm correction Witkin and Kass take). From a restored motion x a step solves one
// quadratic program (quadratic_program.h)
//     min 1/2 d^T W d + grad f . d   subject to   c + A d = 0,   g + C d <= 0
// with W the exact Hessian of the Lagrangian (the previous program's multipliers; inertia
// corrected where it is not convex on the constraints' tangent space) and the inequalities
// within a margin of their bound: the Newton step on the objective in the constraints' null
// space. The trial point x + alpha d is restored again and accepted when the objective fell
// (Armijo's rule on f over restored points, alpha halved otherwise), so the live view shows a
// motion that meets every constraint to 1e-6 after each step, its effort falling. Near the
// optimum the Newton polish (newton_polish.h) finishes from the programs' multipliers and
// active set, as in `sqp`.
//
// Where the first restoration does not reach the constraints (the default guess too far from
// them) or the steps stop lowering the objective, the augmented Lagrangian finishes: from the
// starting motion in the first case, warm from the last restored motion and its multipliers in
// the second; the summary says so. Free contact ends go to the augmented Lagrangian directly.
#pragma once

#include <atomic>

#include "solver/augmented_lagrangian.h"

namespace spacetime {

SolverSummary solveWitkinKass(SpacetimeProblem& problem, const SolverOptions& options,
                              const ProgressCallback& callback = nullptr, const std::atomic<bool>* cancel = nullptr);

}  // namespace spacetime
