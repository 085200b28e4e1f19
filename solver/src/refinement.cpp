// Automatic refinement of the transcription (see refinement.h).
#include "solver/refinement.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

namespace spacetime {
namespace {

using Clock = std::chrono::steady_clock;

// Whether a finer transcription may fix how this solve ended: a converged motion that fails
// between the samples, or constraints that stopped improving (a resolution too coarse to meet
// them all) or ran out of multiplier updates.
bool refinable(SolveStatus status, bool valid) {
  switch (status) {
    case SolveStatus::Converged: return !valid;
    case SolveStatus::Stalled:
    case SolveStatus::IterationLimit: return true;
    default: return false;  // cancelled, out of time, numerical failure, invalid options
  }
}

// Whether attempt a is at least as good as b: a valid motion, then a converged one, then the
// smaller violation. Ties go to a (the finer transcription).
bool atLeastAsGood(const TranscriptionAttempt& a, const TranscriptionAttempt& b) {
  const auto rank = [](const TranscriptionAttempt& t) { return t.valid ? 2 : t.converged ? 1 : 0; };
  if (rank(a) != rank(b)) return rank(a) > rank(b);
  return rank(a) > 0 || !(a.maxViolation > b.maxViolation);
}

// "20 control points per second, s = 6" (and ", with leg bubbles"), or "27 segments split
// from 20 control points per second, s = 8".
// Why the next transcription is tried: how this one's solve ended, or its first failing check.
std::string describe(const TranscriptionAttempt& a, const std::vector<ValidityCheck>& checks) {
  std::ostringstream why;
  if (a.tooCoarse) {
    why << "the motion at " << describeResolution(a) << " left " << a.maxUnactuatedResidualDense
        << " x the weight unexplained on the dense grid before its solve converged";
    return why.str();
  }
  if (!a.converged) {
    why << "the solve at " << describeResolution(a) << " stopped " << toString(a.status) << " (violation " << a.maxViolation
        << ")";
    return why.str();
  }
  why << "the motion at " << describeResolution(a) << " failed";
  for (const ValidityCheck& c : checks)
    if (!c.pass) {
      why << " " << c.name;
      if (!c.yesNo) why << " (" << c.value << " " << c.unit << ", limit " << c.limit << ")";
      break;
    }
  return why.str();
}

}  // namespace

RefinementOptions refinementOptionsFor(const SolverSpec& spec) {
  RefinementOptions options;
  options.maxRefinements = spec.maxRefinements;
  return options;
}

std::string describeResolution(const TranscriptionAttempt& a) {
  std::ostringstream s;
  if (a.nonUniform) s << a.segments << " segments split from ";
  s << a.controlPointsPerSecond << " control points per second, s = " << a.samplesPerSegment
    << (a.legBubbles ? ", with leg bubbles" : "");
  return s.str();
}

bool refineTranscription(const TranscriptionSpec& spec, const RefinementOptions& options, TranscriptionSpec* finer,
                         double growth) {
  *finer = spec;
  finer->samplesPerSegment = std::max(spec.samplesPerSegment, RefinementOptions::kMaxRefinedSamples);
  finer->knots.clear();
  const double cap = options.maxControlPointsPerSecond;
  if (spec.controlPointsPerSecond >= cap * (1 - 1e-9)) return false;
  finer->controlPointsPerSecond = std::min(spec.controlPointsPerSecond * growth, cap);
  return true;
}

bool refineWhereResidual(const TranscriptionSpec& spec, const CubicBSpline& motion, const ValidityReport& report,
                         const RefinementOptions& options, TranscriptionSpec* finer) {
  const int segments = motion.segmentCount();
  if (!(report.maxUnactuatedResidualDense > kDenseResidualLimit) ||
      static_cast<int>(report.segmentResidualDense.size()) != segments)
    return false;
  const double shortest = 2 / options.maxControlPointsPerSecond;  // two intervals at the cap
  // Knots on a nanosecond grid: the uniform breakpoints start + k h carry rounding (0.05 comes out
  // as 0.049999999999999996), which scene.json would keep digit for digit. Moving a knot by at
  // most 5e-10 s changes nothing the solve can see.
  const auto onGrid = [](double t) { return std::round(t * 1e9) / 1e9; };
  std::vector<double> knots;
  int split = 0;
  for (int k = 0; k < segments; ++k) {
    const double a = motion.knot(k), h = motion.segmentLength(k);
    if (k > 0) knots.push_back(onGrid(a));
    if (report.segmentResidualDense[static_cast<size_t>(k)] > RefinementOptions::kSplitFraction * kDenseResidualLimit &&
        h >= shortest * (1 - 1e-9)) {
      knots.push_back(onGrid(a + h / 2));
      ++split;
    }
  }
  if (split == 0 || split > (RefinementOptions::kRateGrowth - 1) * segments) return false;
  *finer = spec;
  finer->samplesPerSegment = std::max(spec.samplesPerSegment, RefinementOptions::kMaxRefinedSamples);
  finer->knots = std::move(knots);
  return true;
}

RefinedSolve solveRefined(std::unique_ptr<SpacetimeProblem> problem, SolverOptions options,
                          const RefinementOptions& refinement, const ProgressCallback& callback,
                          const std::atomic<bool>* cancel, const TranscriptionCallback& starting,
                          const TranscriptionSolvedCallback& solvedCallback) {
  const Clock::time_point start = Clock::now();
  const double spentBefore = options.spentSeconds;
  RefinedSolve best;
  int bestAttempt = -1;
  SolverSummary total;  // iterations and times of every solve
  std::string why = "the scene's transcription";
  for (int level = 0;; ++level) {
    TranscriptionAttempt attempt;
    const TranscriptionSpec spec = problem->scene().transcription;
    attempt.controlPointsPerSecond = spec.controlPointsPerSecond;
    attempt.samplesPerSegment = spec.samplesPerSegment;
    attempt.segments = problem->transcription().motion.segmentCount();
    attempt.nonUniform = !problem->transcription().motion.uniform();
    attempt.legBubbles = spec.legBubbles;
    attempt.why = why;
    // A stall at the scene's own transcription is refined before anything else: there it is
    // mostly a transcription too coarse for the task, which the interior point cannot finish
    // either (the 1.5 m rung at 20 control points per second: 200 IPOPT iterations, 15 s, in
    // vain). On a refined transcription, or where none is left, the interior point continues.
    TranscriptionSpec next;
    SolverOptions levelOptions = options;
    if (level == 0 && refinement.refines() &&
        refineTranscription(spec, refinement, &next, RefinementOptions::kStallRateGrowth))
      levelOptions.interiorPointAfterStall = false;
    if (refinement.enabled && level < refinement.maxRefinements)
      levelOptions.coarseDenseResidual = RefinementOptions::kCoarseFactor * kDenseResidualLimit;
    if (starting) starting(*problem);
    const SolverSummary summary = solveSpacetime(*problem, levelOptions, callback, cancel);
    ValidityReport validity = checkValidity(*problem, 10, cancel);
    const std::vector<ValidityCheck> checks = validityChecklist(validity);
    attempt.status = summary.status;
    attempt.converged = summary.converged;
    attempt.tooCoarse = summary.tooCoarse;
    attempt.valid = summary.converged && !validity.cancelled &&
                    std::all_of(checks.begin(), checks.end(), [](const ValidityCheck& c) { return c.pass; });
    attempt.objective = summary.objective;
    attempt.maxViolation = summary.maxViolation;
    attempt.maxUnactuatedResidualDense = validity.maxUnactuatedResidualDense;
    attempt.iterations = summary.iterations;
    attempt.newtonSteps = summary.newtonSteps;
    attempt.seconds = summary.solveSeconds;
    total.iterations += summary.iterations;
    total.outerIterations += summary.outerIterations;
    total.newtonSteps += summary.newtonSteps;
    total.newtonSolves += summary.newtonSolves;
    total.chordSteps += summary.chordSteps;
    total.sqpSteps += summary.sqpSteps;
    total.sqpSeconds += summary.sqpSeconds;
    total.qpSeconds += summary.qpSeconds;
    total.restorationSteps += summary.restorationSteps;
    total.restorationSeconds += summary.restorationSeconds;
    total.interiorPointIterations += summary.interiorPointIterations;
    total.interiorPointSeconds += summary.interiorPointSeconds;
    total.jacobianSeconds += summary.jacobianSeconds;
    total.linearSolverSeconds += summary.linearSolverSeconds;
    if (solvedCallback) solvedCallback(*problem, attempt, validity);
    const std::string failure = describe(attempt, checks);
    // A finer transcription's result replaces the best so far unless it is worse (a finer solve
    // that stalled never replaces a converged motion the user could already look at).
    if (bestAttempt < 0 || atLeastAsGood(attempt, best.attempts[bestAttempt])) {
      bestAttempt = static_cast<int>(best.attempts.size());
      best.problem = std::move(problem);
      best.summary = summary;
      best.validity = std::move(validity);
      best.valid = attempt.valid;
    }
    best.attempts.push_back(attempt);

    // In budget seconds (SolverOptions::deadlineFrom stretches budgets by the time scale).
    const double elapsed = budgetSecondsSince(start);
    if (!refinement.enabled || level >= refinement.maxRefinements || !refinable(attempt.status, attempt.valid) ||
        (cancel && cancel->load()) || spentBefore + elapsed >= options.maxSeconds)
      break;
    // After a stall, a character standing on several legs first gets leg bubbles at the same
    // rate: its legs could not follow their feet (the quadruped squat of
    // tests/solver/leg_bubbles_test.cpp stalls at any rate without them).
    const SpacetimeProblem& solved = problem ? *problem : *best.problem;  // this level's
    const ValidityReport& solvedValidity = problem ? validity : best.validity;
    TranscriptionSpec finer = spec;
    finer.legBubbles = true;
    const bool finished = attempt.converged || attempt.tooCoarse;
    if (finished && !spec.legBubbles &&
        refineWhereResidual(spec, solved.transcription().motion, solvedValidity, refinement, &finer)) {
      // Split where the dense grid failed; the rest keeps its resolution.
    } else if (finished || spec.legBubbles || !solved.legBubblesWouldApply()) {
      // With leg bubbles the rate grows by half and s stays: s - 1 = 7 bubbles per interval at
      // s = 8 move unseen between the nodes (the planar quadruped's hop: 20/6 slips 0.36 mm
      // between them, 30/6 is valid, 60/8 leaves 0.24 x the weight unexplained).
      const bool legs = spec.legBubbles;
      if (!refineTranscription(spec, refinement, &finer,
                               finished || legs ? RefinementOptions::kRateGrowth
                                                : RefinementOptions::kStallRateGrowth))
        break;
      if (legs) finer.samplesPerSegment = spec.samplesPerSegment;
    }
    // The next transcription starts from the best motion so far.
    Scene scene = best.problem->scene();
    scene.transcription = finer;
    std::string error;
    problem = SpacetimeProblem::build(scene, &error);
    if (!problem) break;  // a finer transcription of a scene that built: not expected
    // The motion always transfers. After a converged solve, or one stopped as too coarse, the
    // finer one starts warm (Newton steps first, then the penalty restarted at
    // warmRestartPenalty; the 1.2 m rung stopped at a single scan: its 32 segments 11 s warm,
    // 50 s started afresh); after a stalled one its multipliers and penalty start afresh, as a
    // cold solve's would: the stalled penalty only holds the iterate where it stalled. Measured on the ladder's 0.9 / 1.2 / 1.5 m rungs before
    // every body was kept above the ground (the 1.5 m motion then put the lamp's head 4.3 cm
    // under the floor): every rung valid this way (15 / 34 / 33 s); restarting after converged
    // solves too was faster on the first two (4.1 / 12.6 s) and left the 1.5 m rung stalled at 45
    // control points per second.
    const bool transferred = problem->initializeFrom(*best.problem) > 0;
    options.warmStart = transferred && (best.summary.converged || best.summary.tooCoarse);
    // From a converged motion the re-fitted one misses mostly the rows the split added, which
    // the SQP's exact-Hessian steps meet in a few (docs/design.md, Solver item 3); from one
    // stopped as too coarse, the motion is still far from this transcription's optimum.
    options.warmSqpSteps = options.warmStart && best.summary.converged && options.method == SolverMethod::AugmentedLagrangian
                               ? refinement.warmSqpSteps
                               : 0;
    // Where the augmented Lagrangian stalled and the interior point finished the solve, the
    // finer transcriptions go to the interior point at once: from the re-fitted motion the
    // augmented Lagrangian would stall again first.
    if (summary.rescued) options.method = SolverMethod::InteriorPoint;
    options.spentSeconds = spentBefore + elapsed;
    why = failure;
  }
  best.attempts[bestAttempt].kept = true;
  best.summary.iterations = total.iterations;
  best.summary.outerIterations = total.outerIterations;
  best.summary.newtonSteps = total.newtonSteps;
  best.summary.newtonSolves = total.newtonSolves;
  best.summary.chordSteps = total.chordSteps;
  best.summary.sqpSteps = total.sqpSteps;
  best.summary.sqpSeconds = total.sqpSeconds;
  best.summary.qpSeconds = total.qpSeconds;
  best.summary.restorationSteps = total.restorationSteps;
  best.summary.restorationSeconds = total.restorationSeconds;
  best.summary.interiorPointIterations = total.interiorPointIterations;
  best.summary.interiorPointSeconds = total.interiorPointSeconds;
  best.summary.jacobianSeconds = total.jacobianSeconds;
  best.summary.linearSolverSeconds = total.linearSolverSeconds;
  best.summary.solveSeconds = std::chrono::duration<double>(Clock::now() - start).count();
  if (best.attempts.size() > 1) {
    std::ostringstream note;
    note << "; " << best.attempts.size() - 1 << " finer transcription" << (best.attempts.size() > 2 ? "s" : "")
         << " tried, the motion kept is at " << describeResolution(best.attempts[bestAttempt]);
    best.summary.reason += note.str();
  }
  return best;
}

}  // namespace spacetime
