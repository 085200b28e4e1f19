// One step of feasibility restoration with the inequalities held as inequalities: at the
// problem's current motion x, the convex quadratic program
//     min 1/2 |c(x) + J_c dx|^2 + damping/2 |dx|^2   subject to   g(x) + J_g dx <= 0
// (c the equality rows, g the inequality rows - contact pushes and cones, clearances, limits)
// solved by the interior point of quadratic_program.h, and x <- x (+) dx.
//
// This is the restoration both halves of Witkin & Kass's projected Newton method need, and the
// Gauss-Newton step of "minimising the violation alone" that a restoration phase repeats. The
// damped least-squares restoration measured in docs/design.md, which held no inequality, pushed
// clearances and cones over their bounds at every step and reached at best 5.7e-4 from an
// augmented-Lagrangian iterate at 1e-3; with the inequalities in the program two steps reach
// below 1e-6 from there (tests/solver/restoration_test.cpp).
//
// The linearised inequalities must admit a point: a motion that violates inequalities by much
// (a stalled solve) can leave the program without one, and the step then fails, changing
// nothing.
#pragma once

#include <string>

#include "solver/spacetime_problem.h"

namespace spacetime {

struct RestorationStep {
  bool taken = false;  // the program was solved and the step applied
  double violationBefore = 0, violationAfter = 0;  // largest constraint row, before and after
  int qpIterations = 0;
  double qpSeconds = 0, seconds = 0;
  std::string reason;  // why no step was taken
};

RestorationStep restorationStep(SpacetimeProblem& problem, double damping, int threads = 1);

}  // namespace spacetime
