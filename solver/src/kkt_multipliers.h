// Multipliers of the problem's rows at an evaluated point (multiplier_estimate.cpp): the
// least-squares ones, which estimateMultipliers hands to the augmented-Lagrangian state, and the
// most stationary of those and the state's own, which the second-order check (second_order.cpp)
// weighs the constraints' curvature by.
#pragma once

#include "raw_rows.h"
#include "solver/multiplier_estimate.h"

namespace spacetime {

// y (one per row; zero on objective rows and on inequalities away from their bound or pulling)
// minimising |grad f + J_A^T y| over the equalities and the inequalities at their bound, with
// `out` filled in (ok, stationarity, active, dropped). Empty, with out->ok false, if no row is a
// constraint or the normal equations do not factorise. `rows` carries every row's Jacobian.
raw::Vec leastSquaresMultipliers(const raw::RawEvaluator& evaluator, const raw::RawRows& rows, MultiplierEstimate* out);

// The least-squares multipliers or the augmented-Lagrangian state's lambda (which a converged
// Newton polish leaves at its KKT multipliers), whichever meet stationarity better - the state's
// by far after a converged solve (the jump: 2.8e-10 against 2.7e-6; the quadruped, whose nearly
// dependent rows make the least-squares system ill-conditioned: 5.7e-9 against 6.3e-5). Same
// contract as leastSquaresMultipliers; out->stationarity is the chosen ones'.
raw::Vec stationaryMultipliers(SpacetimeProblem& problem, const raw::RawEvaluator& evaluator,
                               const raw::RawRows& rows, MultiplierEstimate* out);

}  // namespace spacetime
