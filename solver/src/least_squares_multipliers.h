// The least-squares multipliers of the problem's rows at an evaluated point (multiplier_estimate.cpp):
// what estimateMultipliers hands to the augmented-Lagrangian state, and what the second-order
// check (second_order.cpp) weighs the constraints' curvature by.
#pragma once

#include "raw_rows.h"
#include "solver/multiplier_estimate.h"

namespace spacetime {

// y (one per row; zero on objective rows and on inequalities away from their bound or pulling)
// minimising |grad f + J_A^T y| over the equalities and the inequalities at their bound, with
// `out` filled in (ok, stationarity, active, dropped). Empty, with out->ok false, if no row is a
// constraint or the normal equations do not factorise. `rows` carries every row's Jacobian.
raw::Vec leastSquaresMultipliers(const raw::RawEvaluator& evaluator, const raw::RawRows& rows, MultiplierEstimate* out);

}  // namespace spacetime
