// Newton (SQP) polish of a nearly converged augmented-Lagrangian iterate.
//
// The augmented-Lagrangian inner solves are Levenberg-Marquardt steps with the Gauss-Newton
// Hessian, which drops the constraints' curvature sum_i y_i grad^2 c_i. Near the optimum that
// term is what is missing, so the last multiplier updates creep (luxo_jump: the last 366 of 858
// iterations move the objective from 27.6083 to 27.6066 at violations below 1e-6). The polish
// replaces them with Newton steps on the KKT conditions of
//     min 1/2 |r(x)|^2  subject to  c(x) = 0 and the active inequalities g_A(x) = 0,
// i.e. one solve per step of the symmetric system (Nocedal & Wright, Numerical Optimization,
// 2nd ed., eq. 18.9, the multipliers in full rather than as increments)
//     [ W    A^T ] [ dx ]   [ -J_r^T r ]
//     [ A   -dI  ] [ y+ ] = [ -c_A - d y ],  W = J_r^T J_r + sum r_k grad^2 r_k + sum y_i grad^2 c_i,
// which converges quadratically from a point whose active set is right. W is exact: each
// kernel's weighted Hessian is a forward difference of its exact Jacobian
// (Kernel::weightedHessian); the linear parts of the kernels (accelerations, forces, anchors)
// are skipped. W is shifted by a multiple of the identity until the LDL^T factorisation has the
// inertia of a local minimum (n positive, |A| negative eigenvalues; Waechter & Biegler 2006,
// section 3.1), and d regularises the constraint block so that redundant rows factorise.
//
// The active set starts as the inequalities whose multiplier estimate lambda + rho g is
// positive (with PolishOptions::settleActiveSet, a quadratic program settles it at every step
// the Newton step on it does not fit). An inequality a step violates is held from then on; one the
// polish added is released when its multiplier pulls (y < 0); the rows held from the start are
// released only at a KKT point of the held rows (where a contact force vanishes, the friction
// cone's sides and the normal force reach zero together and their multipliers are not unique
// mid-way). A step is accepted if it reduces max(KKT residual, violation of the held rows),
// halving up to 1/8.
//
// A polish either ends at a point that meets the tolerance with a relative KKT residual below
// kktTolerance and every held inequality pushing, with multipliers written back to the
// augmented-Lagrangian state (warm starts keep working), or it restores the variables it started
// from: it never makes a motion worse.
#pragma once

#include <atomic>
#include <chrono>
#include <string>

#include "solver/augmented_lagrangian.h"
#include "solver/spacetime_problem.h"

namespace spacetime {

struct PolishOptions {
  int maxIterations = 15;      // Newton steps and active-set changes together
  double tolerance = 1e-7;     // largest constraint row at the end (as SolverOptions::tolerance)
  double kktTolerance = 1e-8;  // |J_r^T r + A^T y|_inf relative to max(1, |J_r^T r|_inf)
  int threads = 1;
  // Where a Newton step crosses an inequality that is not held, or a held one's multiplier
  // pulls, settle the active set by one quadratic program (the step's model with the
  // inequalities near their bound linearised as inequalities, from the held rows as its guess)
  // and take its solution as the step, instead of finding the set a step at a time; the rows
  // near their bound keep their Jacobians for it. For a warm start after an edit, whose held
  // rows are the old optimum's: the rows the edit makes active or inactive are found by the
  // program's active-set steps, not by Newton steps that violate them first (the jump's end pose
  // moved 2 cm: 3 passes and 3 KKT solves instead of 18 and 11; 10 cm: 7 and 6, where the
  // row-at-a-time steps failed). A program the active-set steps cannot solve from the held rows
  // (more than 80 of them near their bound: the 3D lamp's) ends the settling, and the polish
  // goes on finding the set a row at a time. The program's active set is that of the
  // linearised rows: after a large edit the steps from it can fail where those finding the set
  // a row at a time succeed, so a caller whose settled polish fails polishes once more without
  // it.
  bool settleActiveSet = false;
  // Wall-clock deadline (the solve's maxSeconds): checked before every Newton step; past it the
  // polish restores its starting point and stops.
  std::chrono::steady_clock::time_point deadline = std::chrono::steady_clock::time_point::max();
};

struct PolishResult {
  bool converged = false;  // the variables moved to a KKT point; otherwise they are unchanged
  // Passes of the polish before the last: Newton steps and passes that only changed the active
  // set. `solves` counts the KKT systems factorised and solved (every step, accepted or not).
  int iterations = 0;
  int solves = 0;
  double kktResidual = 0;  // relative, at the last point reached
  double maxViolation = 0;
  std::string reason;      // why it stopped
  double seconds = 0;
  double jacobianSeconds = 0;       // rows and Jacobians, at the start and at every trial point
  double hessianSeconds = 0;        // the weighted curvature of the rows and J_r^T J_r
  double factorisationSeconds = 0;  // K assembled, LDL^T (with inertia correction), solves
  double lineSearchSeconds = 0;     // the trial points, their evaluations included
  double programSeconds = 0;        // the quadratic program settling the active set
  // Steps on the factorisation kept from an earlier optimum (chord_steps.h) before the Newton
  // steps: each one evaluation and back-solves. Counted whether they converged or not.
  int chordSteps = 0;
  double chordSeconds = 0;
  bool settledActiveSet = false;    // a program changed the held rows
  // The objective and violation at the KKT point, from the polish's last evaluation there (when
  // converged; measure() of the problem would evaluate every row once more).
  ProblemMeasures measures;
};

// Polishes the problem's current variables with the multiplier estimates of its
// augmented-Lagrangian state (lambda + rho * c). Problems with free contact ends (bounded
// variables) are left alone.
PolishResult polishNewton(SpacetimeProblem& problem, const PolishOptions& options,
                          const std::atomic<bool>* cancel = nullptr);

// Adds a polish's passes, solves and phase times to a solve's summary (the methods that run it:
// the augmented Lagrangian and the SQP).
void addPolishTo(const PolishResult& result, SolverSummary* summary);

}  // namespace spacetime
