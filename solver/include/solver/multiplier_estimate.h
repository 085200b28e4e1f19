// First-order multiplier estimate: the multipliers a motion that did not come with its own
// (a motion.json read back, solver/motion_source.h) would have if it were a KKT point - the least-
// squares solution y of grad f + J_A^T y = 0 over the equalities and the inequalities at their
// bound (the least-squares multipliers IPOPT starts from, Waechter & Biegler 2006), those with a
// negative multiplier dropped until none is left (the active-set rule of Lawson and Hanson's
// non-negative least squares). Handed to the augmented-Lagrangian state with a penalty, they let
// the augmented Lagrangian and witkin-kass start warm: their Newton polish takes its active set
// from lambda + rho g.
#pragma once

namespace spacetime {

class SpacetimeProblem;

struct MultiplierEstimate {
  bool ok = false;            // false: the rows were not finite, or no row is a constraint
  double stationarity = 0;    // |grad f + J^T y|_inf / max(1, |grad f|_inf) at the estimate
  int active = 0;             // inequalities held at their bound with a positive multiplier
  int dropped = 0;            // inequalities at their bound whose multiplier came out negative
};

// Writes the estimate at the problem's current motion into its augmented-Lagrangian state with
// penalty rho (multipliers of rows away from their bound zero).
MultiplierEstimate estimateMultipliers(SpacetimeProblem& problem, double rho, int threads);

}  // namespace spacetime
