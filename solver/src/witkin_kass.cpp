// The `witkin-kass` method (see witkin_kass.h): restored iterates, projected Newton steps on the
// objective, the augmented Lagrangian to finish.
#include "solver/witkin_kass.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "program_steps.h"
#include "solver/quadratic_program.h"
#include "solver/restoration.h"

namespace spacetime {
namespace {

using raw::Clock;
using raw::kMargin;
using raw::kMaxRounds;
using raw::RawEvaluator;
using raw::RawRows;
using raw::secondsSince;
using raw::SpRow;
using raw::Triplets;
using raw::Variables;
using raw::Vec;

// The restoration's metric (restoration.h): I + kEffortMetric J_r^T J_r. Measured against the
// identity metric from the default guesses: the biped restores (25 steps to 1879.454 in 20 s,
// against 33 s through the augmented Lagrangian) and so does the heavy lamp (21 steps to the
// sqp's 110.292856); the jump and the hurdle, which restored in the identity metric, go through
// the approach instead (the jump to the same 28.0987, the hurdle to the augmented Lagrangian's
// lower 28.5685 instead of the sqp's 33.3150).
constexpr double kEffortMetric = 100;
// A motion is restored when its largest row is within this: the restoration programs' own
// accuracy (restoration.h; asked for 1e-8 they stop near 1e-7). The polish finishes to the
// solve's tolerance.
constexpr double kRestored = 1e-6;
// Restoration steps from the starting motion (the default guess: far from the constraints), and
// from a trial point (its linearised rows met: the violation is second order in the step).
constexpr int kFirstRestorationSteps = 25, kTrialRestorationSteps = 8;
// Multiplier updates of the augmented Lagrangian that bring a guess the restoration cannot
// restore near the constraints (measured in the identity metric: the heavy lamp to 2.8e-3 after
// 4, from where it restored in one step; after 2, at 0.054, the restoration crawled).
constexpr int kApproachUpdates = 4;
constexpr int kMaxHalvings = 12;
constexpr double kArmijo = 1e-4;
// Witkin and Kass's Newton step uses the objective's Hessian; here its Gauss-Newton part J_r^T
// J_r (the effort is a sum of squares), plus this multiple of the identity for directions the
// objective does not see. The exact Hessian of the Lagrangian measured worse on the jump: its
// programs needed inertia shifts of 0.7-11 far from the optimum and 0.01-0.1 near it, and the
// steps crept (60 steps from 264 to 40, against 12 to 28.2 with Gauss-Newton; docs/design.md).
constexpr double kObjectiveCurvatureFloor = 1e-6;
// Stationarity (relative, as sqp.cpp) at which the steps stop.
constexpr double kStationary = 1e-6;
// Gauss-Newton steps converge linearly: once the objective falls by less than this fraction
// over kStallWindow steps, the augmented Lagrangian's Newton polish and multiplier updates
// finish (the jump: 28.1003 after 40 steps, -4e-6 per step; finished at 28.0987).
constexpr double kStallFraction = 1e-4;
constexpr int kStallWindow = 5;

double largestRow(const Vec& values, const raw::RowKinds& kinds) {
  double v = 0;
  for (int r : kinds.equality) v = std::max(v, std::abs(values[r]));
  for (int r : kinds.inequality) v = std::max(v, values[r]);
  return v;
}

}  // namespace

SolverSummary solveWitkinKass(SpacetimeProblem& problem, const SolverOptions& options, const ProgressCallback& callback,
                              const std::atomic<bool>* cancel) {
  const Clock::time_point start = Clock::now();
  SolverOptions al = options;
  al.method = SolverMethod::AugmentedLagrangian;
  auto viaAugmentedLagrangian = [&] {
    SolverSummary s = solveSpacetime(problem, al, callback, cancel);
    s.method = SolverMethod::WitkinKass;
    return s;
  };
  // Warm starts (an edit, a refined transcription) take the augmented Lagrangian's path, whose
  // warm start begins with the Newton polish: a 2 cm edit of the jump in 0.15 s, against 1.5 s
  // through restored steps (7 steps and the augmented Lagrangian to finish).
  if (!options.validate().empty() || options.warmStart || !problem.freeEnds().empty()) return viaAugmentedLagrangian();
  const int threads = std::max(1, options.threads);
  Restoration restoration(problem, threads, kEffortMetric);
  if (!restoration.ready()) return viaAugmentedLagrangian();
  const Clock::time_point deadline = options.deadlineFrom(start);
  const SolutionState initial = problem.state();
  const Variables vars(problem.ceresProblem());
  RawEvaluator evaluator(problem, vars, threads);
  const raw::RowKinds kinds(evaluator);
  const std::vector<int>&objective = kinds.objective, &equality = kinds.equality, &inequality = kinds.inequality;
  const int n = vars.tangent, rowCount = evaluator.rows(), me = static_cast<int>(equality.size());

  SolverSummary summary;
  summary.method = SolverMethod::WitkinKass;
  AugmentedLagrangianState& state = problem.augmentedLagrangian();
  // Multipliers per row (equalities free, inequalities >= 0): the programs', for the augmented
  // Lagrangian that finishes.
  Vec y = Vec::Zero(rowCount);
  auto restore = [&](int maxSteps) {
    const Clock::time_point t0 = Clock::now();
    const RestorationResult r = restoration.minimiseViolation(kRestored, maxSteps, deadline, cancel);
    summary.restorationSteps += r.steps;
    summary.restorationSeconds += secondsSince(t0);
    return r;
  };

  std::string why, approached;
  RestorationResult first = restore(kFirstRestorationSteps);
  if (first.violation > kRestored && !(cancel && cancel->load())) {
    // Gauss-Newton on the violation alone crawls from some guesses far from the constraints
    // (the jump: 0.053 after 25 steps): a few multiplier updates of the augmented Lagrangian,
    // without its polish, bring the motion near them, and the restoration starts from there.
    SolverOptions approach = al;
    approach.maxOuterIterations = kApproachUpdates;
    approach.newtonPolish = false;
    approach.interiorPointAfterStall = false;
    approach.spentSeconds += budgetSecondsSince(start);
    const SolverSummary a = solveSpacetime(problem, approach, callback, cancel);
    raw::addPhaseTo(a, &summary);
    std::ostringstream s;
    s << "the restoration from the starting motion stopped at a largest row of " << first.violation << "; "
      << a.outerIterations << " multiplier updates of the augmented Lagrangian brought it to " << a.maxViolation;
    approached = s.str();
    if (a.status == SolveStatus::Cancelled) why = "cancelled";
    else first = restore(kFirstRestorationSteps);
  }
  if (cancel && cancel->load()) why = "cancelled";
  const bool restored = why.empty() && first.violation <= kRestored;
  if (why.empty() && !restored) {
    std::ostringstream s;
    s << (approached.empty() ? "the restoration from the starting motion" : approached + ", and the restoration from there")
      << " stopped at a largest row of " << first.violation;
    why = s.str();
  }
  QpWorkspace workspace;
  double lastReport = -1;
  std::vector<double> objectives;  // of the restored iterates
  RawRows rows;
  for (int step = 0; why.empty(); ++step) {
    Clock::time_point phase = Clock::now();
    if (!evaluator.evaluate(&rows, true)) {
      why = "the rows of a restored motion are not finite";
      break;
    }
    summary.jacobianSeconds += secondsSince(phase);
    const SpRow A = raw::selectRows(rows.jacobian, equality);
    const Vec r = raw::selectValues(rows.values, objective), c = raw::selectValues(rows.values, equality);
    const Vec g = raw::selectValues(rows.values, inequality);
    const Vec grad = raw::transposeTimes(rows.jacobian, objective, r);  // J_r^T r, J_r not copied
    const double f = 0.5 * r.squaredNorm();
    const double kkt = (grad + rows.jacobian.transpose() * y).lpNorm<Eigen::Infinity>() /
                       std::max(1.0, grad.lpNorm<Eigen::Infinity>());
    objectives.push_back(f);
    summary.sqpSteps = step;
    if (callback && secondsSince(start) - lastReport >= 0.1) {
      lastReport = secondsSince(start);
      IterationReport report;
      report.iterations = step;
      report.objective = 2 * f;  // the problem's objective is |r|^2
      report.maxViolation = largestRow(rows.values, kinds);
      if (!callback(report)) {
        why = "cancelled";
        break;
      }
    }
    if (kkt <= kStationary) {
      why = "a KKT point";
      break;
    }
    if (step >= kStallWindow && objectives[step - kStallWindow] - f < kStallFraction * f) {
      why = "converging linearly";
      break;
    }
    if (step >= options.sqpMaxSteps) {
      why = "the step budget spent";
      break;
    }
    if (cancel && cancel->load()) {
      why = "cancelled";
      break;
    }
    if (Clock::now() > deadline) {
      why = "out of time";
      break;
    }

    // The projected Newton step: the program on the equalities and the held inequalities.
    phase = Clock::now();
    Triplets ht;
    for (int i = 0; i < n; ++i) ht.emplace_back(i, i, kObjectiveCurvatureFloor);
    evaluator.appendGaussNewton(rows, &ht);
    summary.hessianSeconds += secondsSince(phase);
    phase = Clock::now();
    std::vector<int> held;  // indices into `inequality`
    for (size_t i = 0; i < inequality.size(); ++i)
      if (g[static_cast<Eigen::Index>(i)] > -kMargin || y[inequality[i]] > 0) held.push_back(static_cast<int>(i));
    const SpRow Cfull = raw::selectRows(rows.jacobian, inequality);
    QuadraticProgram program;
    program.hessian.resize(n, n);
    program.hessian.setFromTriplets(ht.begin(), ht.end());
    program.gradient = grad;
    program.equalities = A;
    program.equalityTargets = -c;
    QpOptions programOptions;
    programOptions.maxIterations = 100;
    programOptions.convex = true;
    QpResult qp;
    std::vector<int> heldRows;
    bool solved = false;
    for (int round = 0; round < kMaxRounds && !solved; ++round) {
      heldRows.clear();
      for (int i : held) heldRows.push_back(inequality[i]);
      program.inequalities = raw::selectRows(rows.jacobian, heldRows);
      program.inequalityBounds = -raw::selectValues(rows.values, heldRows);
      qp = solveQuadraticProgram(program, programOptions, &workspace);
      if (!qp.converged) break;
      // Rows outside the program the step crosses join it, and it is solved again.
      solved = !raw::holdCrossedRows(g + Cfull * qp.x, &held);
    }
    summary.qpSeconds += secondsSince(phase);
    if (!solved) {
      why = qp.converged ? "a step's quadratic program kept gaining rows" : "a step's quadratic program failed: " + qp.reason;
      break;
    }
    const Vec d = qp.x;
    Vec yNew = Vec::Zero(rowCount);
    for (int i = 0; i < me; ++i) yNew[equality[i]] = qp.y[i];
    for (size_t i = 0; i < heldRows.size(); ++i) yNew[heldRows[i]] = qp.z[static_cast<Eigen::Index>(i)];

    // Armijo's rule on the objective over restored points. The program's minimum lies below its
    // value at the (nearly zero) correction of the rows, so grad.d < 0 up to that correction.
    phase = Clock::now();
    const double slope = grad.dot(d);
    if (slope >= -1e-14 * std::max(1.0, f)) {
      why = "a KKT point";
      break;
    }
    const std::vector<double> x0 = vars.save();
    bool accepted = false;
    double alpha = 1;
    for (int halving = 0; halving < kMaxHalvings && !(cancel && cancel->load()); ++halving) {
      if (halving > 0) alpha *= 0.5;
      vars.plus(x0, alpha * d);
      if (restore(kTrialRestorationSteps).violation > kRestored) continue;
      RawRows trial;
      if (!evaluator.evaluate(&trial, false)) continue;
      if (0.5 * raw::selectValues(trial.values, objective).squaredNorm() <= f + kArmijo * alpha * slope) {
        accepted = true;
        break;
      }
    }
    summary.lineSearchSeconds += secondsSince(phase);
    if (!accepted) {
      vars.load(x0);
      why = cancel && cancel->load() ? "cancelled" : "no restored step lowered the objective";
      break;
    }
    y += alpha * (yNew - y);
  }
  summary.sqpSeconds = secondsSince(start);

  if (why == "cancelled") {
    summary.reason = restored ? "cancelled by the user; the last restored motion is kept" : "cancelled by the user";
    return raw::finishedAs(SolveStatus::Cancelled, problem, start, summary);
  }
  // The augmented Lagrangian finishes: warm from the last restored motion with the programs'
  // multipliers (its warm start begins with the Newton polish), or cold from the starting motion
  // when no motion was restored. Not on from its approach's multiplier updates, made without
  // the polish: the biped continued from there stalled at 1.1e-4 where `al` converges in 33 s.
  std::ostringstream reason;
  if (restored && !approached.empty()) reason << approached << "; ";
  reason << summary.sqpSteps << " projected Newton steps (" << why << ")";
  RawRows here;
  if (restored && evaluator.evaluate(&here, false)) {
    reason << " to an objective of " << raw::selectValues(here.values, objective).squaredNorm()
           << ", then the augmented Lagrangian from that motion: ";
    raw::handOverMultipliers(evaluator, y, here.values, std::min(options.maxPenalty, options.warmRestartPenalty), &state);
    al.warmStart = true;
  } else {
    problem.restore(initial);
    reason << ", then the augmented Lagrangian from the starting motion: ";
  }
  al.spentSeconds += budgetSecondsSince(start);
  SolverSummary finished = solveSpacetime(problem, al, callback, cancel);
  finished.method = SolverMethod::WitkinKass;
  raw::addPhaseTo(summary, &finished);
  finished.reason = reason.str() + finished.reason;
  finished.solveSeconds = secondsSince(start);
  return finished;
}

}  // namespace spacetime
