// Feasibility restoration with the inequalities held as inequalities: Gauss-Newton steps on
// the violation alone, each a convex quadratic program solved by the interior point of
// quadratic_program.h. At the problem's current motion x, a step solves
//     min 1/2 |c(x) + J_c dx|^2 + damping/2 |dx|^2   subject to   g(x) + J_g dx <= 0
// (c the equality rows, g the inequality rows - contact pushes and cones, clearances, limits)
// and sets x <- x (+) dx. Where some inequality is violated now, or the linearised inequalities
// admit no point, the rows that are violated or within 0.05 of their bound become elastic:
// 1/2 |max(0, g + J_g dx)|^2 joins the objective instead (the Gauss-Newton model of the merit
// below; the hard program is one only where every inequality holds, as dx = 0 is then in it).
//
// This is the restoration both halves of Witkin & Kass's projected Newton method need, and the
// restoration phase that decides whether a stalled solve's constraints conflict:
// minimiseViolation repeats damped steps (Levenberg-Marquardt's rule on the damping) on the
// merit 1/2 |c|^2 + 1/2 |max(0, g)|^2 until the violation meets the tolerance (the
// constraints do not conflict) or the merit stops falling at a positive value with its
// projected gradient near zero (a positive minimum: they conflict, locally).
//
// Gauss-Newton creeps where the rows stay far from zero: it leaves out the rows' own curvature
// sum_i c_i grad^2 c_i, which a positive minimum's violation makes as large as J^T J. Asked for a
// verdict, steps that end undecided continue on the second-order model (that curvature added,
// the exact Hessian of the merit): where it is convex with little damping (the program needs no
// inertia correction) and its minimum lies within kSecondOrderStationary of the merit, the
// motion is an approximate second-order stationary point of the violation (the conditions of
// Nocedal & Wright's Theorem 2.4 to that accuracy): a positive minimum, locally.
//
// The damped least-squares restoration measured in docs/design.md, which held no inequality,
// pushed clearances and cones over their bounds at every step and reached at best 5.7e-4 from
// an augmented-Lagrangian iterate at 1e-3; with the inequalities in the program two steps reach
// below 1e-6 from there (tests/solver/restoration_test.cpp).
#pragma once

#include <atomic>
#include <chrono>
#include <memory>
#include <string>

#include "solver/spacetime_problem.h"

namespace spacetime {

struct RestorationStep {
  bool taken = false;    // a program was solved and its step applied
  bool elastic = false;  // the step needed elastic rows (the linearised inequalities had no point)
  double violationBefore = 0, violationAfter = 0;  // largest constraint row, before and after
  double meritBefore = 0, meritAfter = 0;          // 1/2 |c|^2 + 1/2 |max(0, g)|^2
  double meritPredicted = 0;  // the model's merit at the step (without the damping term)
  double shift = 0;           // the program's inertia correction (second-order model only)
  int qpIterations = 0;
  double qpSeconds = 0, seconds = 0;
  std::string reason;  // why no step was taken
};

struct RestorationResult {
  enum class Outcome { Feasible, PositiveMinimum, Undecided };
  Outcome outcome = Outcome::Undecided;
  double violation = 0, merit = 0;
  double stationarity = 0;  // the last step's |dx|_inf, relative: how far from a minimum it stopped
  int steps = 0;
  double seconds = 0;
  std::string reason;
};

class Restoration {
 public:
  // Free contact ends are refused (ready() false): their instants are bounded variables.
  // effortMetric > 0 measures the damping term in the metric I + effortMetric J_r^T J_r (the
  // objective's Gauss-Newton Hessian) instead of I: among the corrections that meet the rows the
  // steps then prefer those that change the effort least, which Witkin and Kass's restoration
  // takes (witkin_kass.h). In the identity metric a 2 cm edit of the jump's end pose crawled
  // (25 steps from 0.02 to 5.7e-4); with effortMetric 100 it restored in 4 steps.
  explicit Restoration(SpacetimeProblem& problem, int threads = 1, double effortMetric = 0);
  ~Restoration();
  bool ready() const;
  const std::string& error() const;

  // One step with the given damping, on the Gauss-Newton model of the merit or (secondOrder)
  // its exact second-order model; a step whose program fails changes nothing.
  RestorationStep step(double damping, bool secondOrder = false);

  // Damped steps until the violation is within `tolerance`, a positive minimum of the merit, or
  // maxSteps / the deadline / `cancel` (checked between steps). The motion is the last accepted
  // step's (lower merit than before).
  RestorationResult minimiseViolation(double tolerance, int maxSteps,
                                      std::chrono::steady_clock::time_point deadline,
                                      const std::atomic<bool>* cancel = nullptr);

  // The second-order verdict on an undecided `result` of minimiseViolation (see above): damped
  // steps on the merit's exact second-order model (Levenberg-Marquardt's rule), until one whose
  // model, nearly undamped, is convex and falls by less than kSecondOrderStationary of the merit
  // - then true, and `result` says the positive minimum - or kSecondOrderSteps / the deadline.
  // Steps that lower the merit are kept (and counted in `result`); the certifying one only
  // measures.
  bool certifySecondOrderMinimum(RestorationResult* result, std::chrono::steady_clock::time_point deadline);

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace spacetime
