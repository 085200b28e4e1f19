// Augmented-Lagrangian outer loop around Ceres (see augmented_lagrangian.h).
#include "solver/augmented_lagrangian.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>

#include "solver/interior_point.h"
#include "solver/newton_polish.h"
#include "solver/sqp.h"
#include "solver/validity.h"
#include "solver/witkin_kass.h"
#include "solver/restoration.h"
#include "program_steps.h"

namespace spacetime {
namespace {

// Multiplier updates after which a coarseness check is repeated though the violation has not
// fallen tenfold (SolverOptions::coarseDenseResidual).
constexpr int kCoarseRecheckUpdates = 5;
// The warm start's SQP steps (SolverOptions::warmSqpSteps) stop after this many programs in a
// row needed a large shift (SolverOptions::sqpShiftedStepsLimit): the shipped jump at s = 3,
// split after its converged solve, then stops them at its third program instead of taking 20.
constexpr int kWarmShiftedStepsLimit = 3;

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Forwards Ceres iterations to the user's callback and implements cancel and the time limit.
class ProgressForwarder : public ceres::IterationCallback {
 public:
  ProgressForwarder(SpacetimeProblem& problem, const ProgressCallback& callback,
                    const std::atomic<bool>* cancel, Clock::time_point start, Clock::time_point deadline)
      : problem_(problem), callback_(callback), cancel_(cancel), start_(start), deadline_(deadline) {}

  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    if (s.iteration > 0) ++iterations;
    if (cancel_ && cancel_->load()) {
      cancelled = true;
      return ceres::SOLVER_ABORT;
    }
    if (Clock::now() > deadline_) {
      timedOut = true;
      return ceres::SOLVER_ABORT;
    }
    // Measuring re-evaluates every residual, so reports are throttled to one per 100 ms:
    // plenty for a progress display, and the solve does not pay for it at every iteration.
    const double now = secondsSince(start_);
    if (callback_ && s.iteration > 0 && now - lastReport_ >= 0.1) {
      lastReport_ = now;
      // The callback may sample the iterate's motion (the editor's live view): its times must
      // follow the iterate's lift-off instants. No residual is being evaluated now, and
      // residuals do not read the times sync moves.
      problem_.syncFreeEnds();
      const ProblemMeasures m = measure(problem_);
      IterationReport r;
      r.outer = outer;
      r.iterations = iterations;
      r.objective = m.objective;
      r.maxViolation = m.maxViolation;
      r.rho = rho;
      if (!callback_(r)) {
        cancelled = true;
        return ceres::SOLVER_ABORT;
      }
    }
    return ceres::SOLVER_CONTINUE;
  }

  int outer = 0;
  int iterations = 0;
  double rho = 0;
  bool cancelled = false, timedOut = false;

 private:
  SpacetimeProblem& problem_;
  const ProgressCallback& callback_;
  const std::atomic<bool>* cancel_;
  Clock::time_point start_, deadline_;
  double lastReport_ = -1;
};

bool allFinite(const std::vector<double>& v) {
  for (double x : v)
    if (!std::isfinite(x)) return false;
  return true;
}

}  // namespace

SolverOptions solverOptionsFor(const SolverSpec& spec) {
  SolverOptions options;
  options.maxOuterIterations = spec.maxOuterIterations;
  options.maxInnerIterations = spec.maxInnerIterations;
  options.tolerance = spec.tolerance;
  options.maxPenalty = spec.maxPenalty;
  options.maxSeconds = spec.maxSeconds;
  parseSolverMethod(spec.method, &options.method);  // the loader accepts only known names
  return options;
}

std::string SolverOptions::validate() const {
  if (maxOuterIterations < 1) return "maxOuterIterations must be at least 1";
  if (maxInnerIterations < 1) return "maxInnerIterations must be at least 1";
  if (!(tolerance > 0)) return "tolerance must be > 0";
  if (!(initialPenalty > 0) || !(maxPenalty >= initialPenalty)) return "penalties must satisfy 0 < initialPenalty <= maxPenalty";
  if (!(penaltyGrowth > 1)) return "penaltyGrowth must be > 1";
  if (!(nearFeasible >= 0) || !(nearFeasiblePenalty >= initialPenalty))
    return "nearFeasible must be >= 0 and nearFeasiblePenalty >= initialPenalty";
  if (!(warmRestartPenalty > 0)) return "warmRestartPenalty must be > 0";
  if (!(penaltyPerObjective >= 0)) return "penaltyPerObjective must be >= 0";
  if (!(maxSeconds > 0)) return "maxSeconds must be > 0";
  if (threads < 1) return "threads must be at least 1";
  if (!(releaseFreeEndsAt > 0)) return "releaseFreeEndsAt must be > 0";
  if (!(polishBelow > 0)) return "polishBelow must be > 0";
  if (maxPolishIterations < 1) return "maxPolishIterations must be at least 1";
  if (sqpMaxSteps < 1) return "sqpMaxSteps must be at least 1";
  if (warmSqpSteps < 0) return "warmSqpSteps must not be negative";
  if (sqpShiftedStepsLimit < 0) return "sqpShiftedStepsLimit must not be negative";
  if (!(coarseDenseResidual >= 0) || !(coarseCheckBelow > 0))
    return "coarseDenseResidual must be >= 0 and coarseCheckBelow > 0";
  if (coldNewtonSteps < 0) return "coldNewtonSteps must not be negative";
  if (stallUpdates < 1) return "stallUpdates must be at least 1";
  if (interiorPointAfterStallIterations < 1 || interiorPointMaxIterations < 1)
    return "the interior point's iteration limits must be at least 1";
  return "";
}

double instrumentedTimeScale() {
  static const double scale = [] {
    const char* v = std::getenv("SPACETIME_TIME_SCALE");
    const double s = v ? std::strtod(v, nullptr) : 1.0;
    return std::isfinite(s) ? std::clamp(s, 1.0, 1000.0) : 1.0;
  }();
  return scale;
}

double budgetSecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / instrumentedTimeScale();
}

std::chrono::steady_clock::time_point SolverOptions::deadlineFrom(std::chrono::steady_clock::time_point start) const {
  using Clock = std::chrono::steady_clock;
  const double seconds = std::clamp((maxSeconds - spentSeconds) * instrumentedTimeScale(), 0.0, 1e9);
  return start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

std::string toString(SolveStatus s) {
  switch (s) {
    case SolveStatus::Converged: return "converged";
    case SolveStatus::IterationLimit: return "iteration limit";
    case SolveStatus::Stalled: return "stalled";
    case SolveStatus::TimeLimit: return "time limit";
    case SolveStatus::Cancelled: return "cancelled";
    case SolveStatus::NumericalFailure: return "numerical failure";
    case SolveStatus::InvalidOptions: return "invalid options";
  }
  return "?";
}

std::string toString(SolverMethod m) {
  switch (m) {
    case SolverMethod::InteriorPoint: return "ipopt";
    case SolverMethod::Sqp: return "sqp";
    case SolverMethod::WitkinKass: return "witkin-kass";
    case SolverMethod::AugmentedLagrangian: break;
  }
  return "al";
}

bool parseSolverMethod(const std::string& name, SolverMethod* method) {
  for (SolverMethod m : {SolverMethod::AugmentedLagrangian, SolverMethod::InteriorPoint, SolverMethod::Sqp, SolverMethod::WitkinKass})
    if (name == toString(m)) {
      *method = m;
      return true;
    }
  return false;
}

namespace {

// Every residual's raw rows at the current variables, residual by residual.
std::vector<std::vector<double>> rawRows(const SpacetimeProblem& problem) {
  std::vector<std::vector<double>> rows;
  rows.reserve(problem.residuals().size());
  for (const TermResidual* r : problem.residuals()) rows.push_back(r->rawRowsNow());
  return rows;
}

}  // namespace

ProblemMeasures measure(std::span<const TermResidual* const> terms, const std::vector<std::vector<double>>& rows) {
  ProblemMeasures m;
  for (size_t k = 0; k < rows.size(); ++k) {
    const TermResidual* r = terms[k];
    const auto& kinds = r->kernel().rowKinds();
    for (size_t i = 0; i < rows[k].size(); ++i) {
      const double row = rows[k][i];
      if (kinds[i] == RowKind::Objective) {
        m.objective += row * row;
        continue;
      }
      const double v = rowViolation(kinds[i], row);
      if (!(v <= m.maxViolation)) {  // also catches NaN
        m.maxViolation = v;
        m.worstConstraint = r->kernel().label();
      }
    }
  }
  return m;
}

ProblemMeasures measure(const SpacetimeProblem& problem) { return measure(problem.residuals(), rawRows(problem)); }

std::vector<ViolatedConstraint> mostViolated(const SpacetimeProblem& problem, double floor, int limit) {
  std::vector<ViolatedConstraint> out;
  for (const TermResidual* r : problem.residuals()) {
    const std::vector<double> rows = r->rawRowsNow();
    const auto& kinds = r->kernel().rowKinds();
    double worst = 0;
    for (size_t i = 0; i < rows.size(); ++i) worst = std::max(worst, rowViolation(kinds[i], rows[i]));
    if (worst > floor) out.push_back({r->kernel().label(), worst});
  }
  std::stable_sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.violation > b.violation; });
  if (static_cast<int>(out.size()) > limit) out.resize(static_cast<size_t>(limit));
  return out;
}

std::vector<ViolatedConstraint> unmetConstraints(const SpacetimeProblem& problem, double tolerance, double maxViolation) {
  if (!(maxViolation > tolerance)) return {};
  return mostViolated(problem, std::max(tolerance, 0.1 * maxViolation), 5);
}

std::string describeViolated(const std::vector<ViolatedConstraint>& violated) {
  std::ostringstream most;
  for (size_t i = 0; i < violated.size(); ++i)
    most << (i ? ", " : "; most violated: ") << violated[i].label << " (" << violated[i].violation << ")";
  return most.str();
}

// A stalled solve's verdict on its constraints (solver/restoration.h): minimising the
// violation alone from the stalled motion, with the inequalities held as inequalities. At a
// positive minimum the constraints conflict and the stalled motion is kept; where it meets the
// constraints they do not, and the motion it reached - physically valid, its effort not
// minimal - replaces the stalled one; otherwise they are not shown to conflict. Measured: the
// clashing pins of tests/solver/clashing_pin.h are certified in one step; the ladder's 1.5 m
// rung creeps (300 steps, 22 s: 1/2 |c|^2 0.0119 -> 0.0114) and stays undecided - rightly: the
// jump is feasible, and the interior point after the phase finds it. Undecided steps then get
// the second-order verdict: the speed-limited jump's stall (15 rad/s) is a positive minimum by
// it, while the 1.5 m rung's stalls are not convex there and stay undecided.
namespace {

// Returns false when the constraints were shown to conflict.
bool restorationPhase(SpacetimeProblem& problem, const SolverOptions& options, Clock::time_point stepsDeadline,
                      Clock::time_point deadline, SolverSummary* summary) {
  constexpr int kSteps = 15;
  Restoration restoration(problem, options.threads);
  if (!restoration.ready()) {
    summary->reason += ": some of them may conflict";
    return true;
  }
  const SolutionState stalled = problem.state();
  const Clock::time_point start = Clock::now();
  RestorationResult r = restoration.minimiseViolation(options.tolerance, kSteps, stepsDeadline);
  // Undecided steps get the second-order verdict within the solve's own deadline.
  restoration.certifySecondOrderMinimum(&r, deadline);
  summary->restorationSteps = r.steps;
  summary->restorationSeconds = secondsSince(start);
  switch (r.outcome) {
    case RestorationResult::Outcome::PositiveMinimum:
      problem.restore(stalled);
      summary->reason += ": they conflict (" + r.reason + ")";
      break;
    case RestorationResult::Outcome::Feasible:
      summary->reason += ", but they do not conflict: " + r.reason +
                         "; that motion is kept, meeting them with an effort that is not minimal";
      break;
    case RestorationResult::Outcome::Undecided:
      problem.restore(stalled);
      summary->reason += "; " + r.reason + ", so they are not shown to conflict";
      break;
  }
  return r.outcome != RestorationResult::Outcome::PositiveMinimum;
}

// The interior point from a stalled motion (SolverOptions::interiorPointAfterStall), for the rest
// of the budget. Converged, its KKT point is the result; otherwise the stalled (or restored)
// motion and the stall's verdict stay, and the reason says what it reached.
void interiorPointAfterStall(SpacetimeProblem& problem, const SolverOptions& options, Clock::time_point start,
                             const ProgressCallback& callback, const std::atomic<bool>* cancel,
                             SolverSummary* summary) {
  SolverOptions ip = options;
  ip.method = SolverMethod::InteriorPoint;
  ip.interiorPointMaxIterations = options.interiorPointAfterStallIterations;
  ip.spentSeconds = options.spentSeconds + budgetSecondsSince(start);
  if (!(ip.spentSeconds < ip.maxSeconds)) return;
  const SolutionState stalled = problem.state();
  const SolverSummary r = solveInteriorPoint(problem, ip, callback, cancel);
  summary->interiorPointIterations = r.iterations;
  summary->interiorPointSeconds = r.solveSeconds;
  summary->jacobianSeconds += r.jacobianSeconds;
  summary->hessianSeconds += r.hessianSeconds;
  if (r.converged) {
    summary->status = SolveStatus::Converged;
    summary->converged = true;
    summary->rescued = true;
    summary->reason = "the augmented Lagrangian stalled (" + summary->reason + "); the interior point from its motion: " +
                      r.reason;
    return;
  }
  problem.restore(stalled);
  if (r.status == SolveStatus::Cancelled) summary->status = SolveStatus::Cancelled;
  summary->reason += "; the interior point from there stopped too (" + r.reason + ")";
}

}  // namespace

void addPolishTo(const PolishResult& result, SolverSummary* summary) {
  summary->newtonSteps += result.iterations;
  summary->newtonSolves += result.solves;
  summary->chordSteps += result.chordSteps;
  summary->jacobianSeconds += result.jacobianSeconds;
  summary->polishSeconds += result.seconds;
  summary->polishEvaluationSeconds += result.jacobianSeconds;
  summary->hessianSeconds += result.hessianSeconds;
  summary->factorisationSeconds += result.factorisationSeconds;
  summary->lineSearchSeconds += result.lineSearchSeconds;
  summary->qpSeconds += result.programSeconds;
}

SolverSummary solveSpacetime(SpacetimeProblem& problem, const SolverOptions& options,
                             const ProgressCallback& callback, const std::atomic<bool>* cancel) {
  const Clock::time_point start = Clock::now();
  SolverSummary summary;
  if (const std::string err = options.validate(); !err.empty()) {
    summary.status = SolveStatus::InvalidOptions;
    summary.reason = "invalid solver options: " + err;
    return summary;
  }
  if (options.method == SolverMethod::InteriorPoint) return solveInteriorPoint(problem, options, callback, cancel);
  if (options.method == SolverMethod::Sqp) return solveSqp(problem, options, callback, cancel);
  if (options.method == SolverMethod::WitkinKass) return solveWitkinKass(problem, options, callback, cancel);
  AugmentedLagrangianState& al = problem.augmentedLagrangian();
  const bool coldStart = !options.warmStart || !(al.rho > 0);
  if (coldStart) std::fill(al.lambda.begin(), al.lambda.end(), 0.0);

  ceres::Solver::Options co;
  co.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  co.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  co.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  co.max_num_iterations = options.maxInnerIterations;
  co.function_tolerance = 1e-10;
  co.gradient_tolerance = 1e-10;
  co.parameter_tolerance = 1e-10;
  co.num_threads = options.threads;
  co.logging_type = ceres::SILENT;
  co.update_state_every_iteration = true;
  // Start from (nearly) Gauss-Newton steps and allow non-monotonic progress: measured on the
  // standing lamp, 164 instead of 253 Levenberg-Marquardt iterations.
  co.initial_trust_region_radius = options.initialTrustRegionRadius;
  co.use_nonmonotonic_steps = true;
  // Bounds (free contact ends) make Ceres follow every step with a projected Armijo line search
  // that re-evaluates the Jacobian; its steps are projected onto the bounds without it. Measured
  // on luxo_jump with a free lift-off (2 threads): 80.0 s, 4796 iterations with the line search,
  // 20.0 s, 3903 iterations without, the same optimum (objective 16.8563).
  co.max_num_line_search_step_size_iterations = 0;
  // The solve's wall-clock limit, for the Ceres iterations and the Newton polish alike.
  const Clock::time_point deadline = options.deadlineFrom(start);
  ProgressForwarder forwarder(problem, callback, cancel, start, deadline);
  co.callbacks.push_back(&forwarder);

  // A warm start the polish finishes needs no measure of its start (the polish evaluates it; a
  // measure, every row once on one thread, is ~5 % of a 2 cm edit's time on 2 threads): it is
  // measured only if the polish fails.
  const bool measureLater = options.newtonPolish && options.warmStart && !coldStart && problem.freeEnds().empty();
  ProblemMeasures m = measureLater ? ProblemMeasures() : measure(problem);
  if (coldStart)
    al.rho = std::min(options.maxPenalty, std::max(options.initialPenalty, options.penaltyPerObjective * m.objective));
  SolutionState lastGood = problem.state();
  // The Newton polish (newton_polish.h); true if it reached a KKT point, which ends the solve.
  // It stops at the solve's own time limit.
  int polishAttempts = 0;
  double lastPolishViolation = 1e300;
  bool lastPolishSettled = false;  // its active set was settled by a program (PolishOptions)
  auto polish = [&](int maxIterations, bool settleActiveSet = false) {
    PolishOptions po;
    po.settleActiveSet = settleActiveSet;
    po.tolerance = options.tolerance;
    po.maxIterations = maxIterations;
    po.threads = options.threads;
    po.deadline = deadline;
    const PolishResult result = polishNewton(problem, po, cancel);
    addPolishTo(result, &summary);
    lastPolishSettled = result.settledActiveSet;
    if (!result.converged) return false;
    m = result.measures;
    summary.status = SolveStatus::Converged;
    summary.converged = true;
    summary.polished = true;
    summary.reason = "constraints within tolerance and the KKT conditions met after " +
                     std::to_string(summary.newtonSteps) + " Newton steps with the exact Hessian";
    return true;
  };
  // The SQP's damped steps from the current point and multipliers (sqpStepsNearFeasible, at most
  // maxSteps); true if they reached a KKT point, which ends the solve (its reason then ends
  // with `from`). Where they stop, the point they started from is restored.
  auto sqpSteps = [&](int maxSteps, int shiftedStepsLimit, const std::string& from) {
    SolverOptions stepOptions = options;
    stepOptions.sqpMaxSteps = maxSteps;
    stepOptions.sqpShiftedStepsLimit = shiftedStepsLimit;
    stepOptions.spentSeconds += budgetSecondsSince(start);
    const SolverSummary steps = sqpStepsNearFeasible(problem, stepOptions, cancel);
    raw::addPhaseTo(steps, &summary);
    if (!steps.converged) return false;
    m = measure(problem);
    summary.status = SolveStatus::Converged;
    summary.converged = true;
    summary.polished = steps.polished;
    summary.reason = steps.reason + from;
    return true;
  };
  auto holdFreeEnds = [&](bool hold) {
    for (const FreeEnd& e : problem.freeEnds()) {
      double* T = problem.variables().data() + e.offset;
      if (!problem.ceresProblem().HasParameterBlock(T)) continue;
      if (hold) problem.ceresProblem().SetParameterBlockConstant(T);
      else problem.ceresProblem().SetParameterBlockVariable(T);
    }
  };
  bool freeEndsHeld = !problem.freeEnds().empty() && m.maxViolation > options.releaseFreeEndsAt;
  holdFreeEnds(freeEndsHeld);
  summary.status = SolveStatus::IterationLimit;
  summary.reason = "reached the limit of " + std::to_string(options.maxOuterIterations) +
                   " multiplier updates before the constraints met the tolerance";
  // A warm start (the editor re-solving after an edit) begins next to the new optimum, with the
  // old one's multipliers and active set: Newton steps go straight there, where the augmented
  // Lagrangian at the old, large penalty would crawl (luxo_jump with its end pose moved 2 cm:
  // 606 LM iterations); where the edit changes which inequalities are active, a quadratic
  // program finds the new active set before the steps (PolishOptions::settleActiveSet), and where
  // the steps from it fail, they run once more finding it a row at a time. If they fail, the
  // outer loop starts as it would have.
  const bool polishedWarm = options.newtonPolish && options.warmStart && !freeEndsHeld &&
                            (polish(options.maxPolishIterations, true) ||
                             (lastPolishSettled && polish(options.maxPolishIterations)));
  // A cold start tries a few Newton steps first as well: where the task is a quadratic program
  // (the particle scenes: linear dynamics, quadratic effort, point constraints) the first step
  // lands on the optimum. Elsewhere they fail at once and restore the default guess (the jump:
  // one rejected step).
  const bool polishedCold = options.newtonPolish && !options.warmStart && !freeEndsHeld &&
                            options.coldNewtonSteps > 0 && polish(options.coldNewtonSteps);
  if (measureLater && !polishedWarm) m = measure(problem);  // a failed polish restored the start
  // A warm start the Newton steps could not finish: the damped SQP steps from the same start
  // (SolverOptions::warmSqpSteps) before the multiplier updates.
  const bool steppedWarm =
      options.warmStart && !polishedWarm && options.warmSqpSteps > 0 && problem.freeEnds().empty() &&
      sqpSteps(options.warmSqpSteps, kWarmShiftedStepsLimit, ", warm from the starting motion");
  const bool polishedFirst = polishedWarm || polishedCold || steppedWarm;
  // A warm start far from feasible (a large edit the Newton steps could not finish) keeps its
  // multipliers but restarts the penalty (at warmRestartPenalty): the old one was grown for a
  // violation near zero, and at 1e7 the inner problems are stiff (luxo_jump, end pose moved 10 cm:
  // 844 LM iterations, 14.8 s with the old penalty; 360, 5.4 s restarted at 100; 240 at 1e4).
  if (!polishedWarm && options.warmStart && m.maxViolation > options.polishBelow)
    al.rho = std::min(al.rho, std::min(options.warmRestartPenalty, options.maxPenalty));
  double previousViolation = m.maxViolation;
  double stallReference = m.maxViolation;  // the violation when the current stall began
  int stalledUpdates = 0;
  // The violation and the dense-grid residual at the last coarseness check.
  double lastCoarseCheck = std::numeric_limits<double>::infinity();
  double lastCoarseResidual = 0;
  int updatesSinceCoarseCheck = 0;
  for (int outer = 0; !polishedFirst && outer < options.maxOuterIterations; ++outer) {
    forwarder.outer = outer;
    forwarder.rho = al.rho;
    ceres::Solver::Summary cs;
    ceres::Solve(co, &problem.ceresProblem(), &cs);
    summary.outerIterations = outer + 1;
    summary.jacobianSeconds += cs.residual_evaluation_time_in_seconds + cs.jacobian_evaluation_time_in_seconds;
    summary.linearSolverSeconds += cs.linear_solver_time_in_seconds;
    if (forwarder.cancelled) {
      summary.status = SolveStatus::Cancelled;
      summary.reason = "cancelled by the user; the last accepted iterate is kept";
      break;
    }
    if (forwarder.timedOut) {
      summary.status = SolveStatus::TimeLimit;
      std::ostringstream limit;  // 0.5, 300: not std::to_string's 0.500000
      limit << options.maxSeconds;
      summary.reason = "stopped after the time limit of " + limit.str() + " s; the last accepted iterate is kept";
      break;
    }
    const std::vector<std::vector<double>> rows = rawRows(problem);
    m = measure(problem.residuals(), rows);
    if (cs.termination_type == ceres::FAILURE || !std::isfinite(m.objective) ||
        !std::isfinite(m.maxViolation) || !allFinite(problem.variables())) {
      problem.restore(lastGood);
      summary.status = SolveStatus::NumericalFailure;
      summary.reason = "numerical failure in the inner solve (" + cs.message +
                       "); the last good iterate is kept";
      break;
    }
    lastGood = problem.state();
    const bool innerConverged = cs.termination_type == ceres::CONVERGENCE;
    const bool release = freeEndsHeld && m.maxViolation <= options.releaseFreeEndsAt;
    if (release) {
      freeEndsHeld = false;
      holdFreeEnds(false);
    }
    if (m.maxViolation <= options.tolerance && innerConverged && !release) {
      summary.status = SolveStatus::Converged;
      summary.converged = true;
      summary.reason = "constraints within tolerance and the augmented Lagrangian stationary";
      break;
    }
    // A transcription too coarse for the task (SolverOptions::coarseDenseResidual): a few
    // dense-grid scans a solve. The ladder's 1.2 m rung at the scene's 24 segments: 2.97 x the
    // weight unexplained at a violation of 2.7e-4, 1.87 at 2.6e-5 (0.58 where its solve ends,
    // 1822 LM iterations later); on one thread its violation holds at 2e-5 after the first check
    // (3.00 at 1.7e-4), and only the count of updates brings the second. A single check is not
    // enough: the planar quadruped's squat with leg bubbles leaves 0.32 at
    // 5.3e-4, then 0.036 at 3.2e-5, and converges valid.
    ++updatesSinceCoarseCheck;
    if (options.coarseDenseResidual > 0 && m.maxViolation <= options.coarseCheckBelow &&
        (m.maxViolation <= 0.1 * lastCoarseCheck || updatesSinceCoarseCheck >= kCoarseRecheckUpdates)) {
      lastCoarseCheck = m.maxViolation;
      updatesSinceCoarseCheck = 0;
      const double residual = checkDenseResidual(problem).maxUnactuatedResidualDense;
      const bool stays = residual > options.coarseDenseResidual && lastCoarseResidual > options.coarseDenseResidual &&
                         residual > 0.5 * lastCoarseResidual;
      lastCoarseResidual = residual;
      if (stays) {
        std::ostringstream why;
        why << "stopped at a violation of " << m.maxViolation << ": the motion leaves " << residual
            << " x the weight unexplained between the samples, a transcription too coarse for the task";
        summary.status = SolveStatus::IterationLimit;
        summary.tooCoarse = true;
        summary.reason = why.str();
        break;
      }
    }
    // A failed polish is tried once more after the violation has dropped tenfold: its first
    // step can fail by a hair (luxo_jump with the end pose moved 2 cm: the first attempt stopped
    // at KKT 9e-5, the AL alone then took 740 iterations to an objective 3e-6 above the optimum
    // the second attempt reaches after 420).
    if (options.newtonPolish && polishAttempts < options.maxPolishAttempts && !freeEndsHeld &&
        m.maxViolation <= options.polishBelow && m.maxViolation <= 0.1 * lastPolishViolation) {
      ++polishAttempts;
      lastPolishViolation = m.maxViolation;
      if (polish(options.maxPolishIterations)) break;
      // Where the polish fails, the SQP's steps (sqp.h) from here and these multipliers: the
      // Newton steps need the point inside their basin, while along the constraints the
      // objective may still have far to fall - the 0.9 m rung's 70.49 at a violation of 3.3e-5,
      // its optimum 65.649, which the updates at 1e6 then crawl to in 730 LM iterations, the
      // damped SQP steps in 13 (docs/design.md, Solver item 1).
      if (options.sqpAfterFailedPolish) {
        std::ostringstream from;
        from << ", from the augmented Lagrangian's iterate at a violation of " << lastPolishViolation;
        if (sqpSteps(options.sqpMaxSteps, options.sqpShiftedStepsLimit, from.str())) break;
      }
    }
    // First-order multiplier update (Nocedal & Wright eq. 17.39; 17.67 for inequalities).
    for (size_t k = 0; k < rows.size(); ++k) {
      const TermResidual* r = problem.residuals()[k];
      const auto& kinds = r->kernel().rowKinds();
      for (size_t i = 0; i < rows[k].size(); ++i) {
        double& lambda = al.lambda[r->firstMultiplier() + i];
        if (kinds[i] == RowKind::Equality) lambda += al.rho * rows[k][i];
        else if (kinds[i] == RowKind::Inequality) lambda = std::max(0.0, lambda + al.rho * rows[k][i]);
      }
    }
    const double cap = m.maxViolation <= options.nearFeasible ? std::min(options.maxPenalty, options.nearFeasiblePenalty)
                                                              : options.maxPenalty;
    if (m.maxViolation > 0.25 * previousViolation && al.rho < cap) al.rho = std::min(al.rho * options.penaltyGrowth, cap);
    previousViolation = m.maxViolation;
    // A stall: the penalty at its cap and the violation no longer falling. Below nearFeasible the
    // multiplier updates are closing a small gap, slowly, and are left to it.
    if (al.rho < cap || m.maxViolation <= options.nearFeasible || m.maxViolation < 0.99 * stallReference) {
      stallReference = m.maxViolation;
      stalledUpdates = 0;
    } else if (++stalledUpdates >= options.stallUpdates) {
      std::ostringstream why;
      why << "the constraints stopped improving at a violation of " << m.maxViolation << " over the last "
          << stalledUpdates << " multiplier updates at the largest penalty";
      summary.status = SolveStatus::Stalled;
      summary.reason = why.str();
      break;
    }
  }
  // Constraint projection: land exactly on the constraints from the AL's near-optimal point.
  // m is current here: the loop measured after the last inner solve and nothing moved since.
  if ((summary.status == SolveStatus::IterationLimit && !summary.tooCoarse) || summary.status == SolveStatus::Stalled ||
      summary.status == SolveStatus::Converged) {
    if (m.maxViolation > options.tolerance) {
      ceres::Solver::Options po = co;
      po.max_num_iterations = options.maxProjectionIterations;
      po.function_tolerance = 1e-20;
      po.gradient_tolerance = 1e-20;
      po.parameter_tolerance = 1e-14;
      al.projectOnly = true;
      ceres::Solver::Summary ps;
      ceres::Solve(po, &problem.ceresProblem(), &ps);
      al.projectOnly = false;
      summary.jacobianSeconds += ps.residual_evaluation_time_in_seconds + ps.jacobian_evaluation_time_in_seconds;
      summary.linearSolverSeconds += ps.linear_solver_time_in_seconds;
      const ProblemMeasures after = measure(problem);
      if (!std::isfinite(after.maxViolation) || !allFinite(problem.variables())) {
        problem.restore(lastGood);
        summary.status = SolveStatus::NumericalFailure;
        summary.reason = "numerical failure in the constraint projection; the last good iterate is kept";
      } else if (after.maxViolation <= options.tolerance && !forwarder.cancelled && !forwarder.timedOut) {
        summary.status = SolveStatus::Converged;
        summary.converged = true;
        summary.reason = "constraints within tolerance after the augmented-Lagrangian iterations "
                         "and a Gauss-Newton projection onto the constraints";
      } else if (forwarder.cancelled) {
        summary.status = SolveStatus::Cancelled;
        summary.reason = "cancelled by the user; the last accepted iterate is kept";
      }
    }
  }
  holdFreeEnds(false);
  // The problem's times follow the solved lift-off instants; m is current unless they moved (a
  // polish that finished the solve measured its point from its last evaluation).
  problem.syncFreeEnds();
  if (!(summary.polished && problem.freeEnds().empty())) m = measure(problem);
  if (summary.status == SolveStatus::Stalled && m.maxViolation > options.tolerance) {
    // A tenth of the time the solve took (at least a second): where Gauss-Newton crawls at a
    // positive residual, longer buys little (the 1.5 m rung at 45 control points per second:
    // 1/2 |c|^2 1.1e-4 -> 1.0e-4 in 400 more steps). The rung's four phases: 45 steps, 3.5 s.
    const Clock::time_point cap = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                                     std::chrono::duration<double>(std::max(1.0, 0.1 * secondsSince(start))));
    const bool mayHold = restorationPhase(problem, options, std::min(deadline, cap), deadline, &summary);
    if (mayHold && options.interiorPointAfterStall && interiorPointAvailable() && problem.freeEnds().empty() &&
        !(cancel && cancel->load()))
      interiorPointAfterStall(problem, options, start, callback, cancel, &summary);
    m = measure(problem);
  }
  if (summary.status == SolveStatus::IterationLimit && m.maxViolation <= options.tolerance)
    summary.reason = "constraints within tolerance, but the augmented Lagrangian was not yet "
                     "stationary after " + std::to_string(options.maxOuterIterations) +
                     " multiplier updates (the objective may still improve)";
  if (!summary.converged) {
    summary.violated = unmetConstraints(problem, options.tolerance, m.maxViolation);
    if ((summary.status == SolveStatus::IterationLimit && !summary.tooCoarse) || summary.status == SolveStatus::Stalled)
      summary.reason += describeViolated(summary.violated);
  }
  summary.objective = m.objective;
  summary.maxViolation = m.maxViolation;
  summary.worstConstraint = m.worstConstraint;
  summary.iterations = forwarder.iterations;
  summary.solveSeconds = secondsSince(start);
  return summary;
}

}  // namespace spacetime
