// The default solver: an augmented-Lagrangian method (Nocedal & Wright, Algorithm 17.4, with
// the Powell-Hestenes-Rockafellar treatment of inequalities) whose inner minimisations are
// Ceres Levenberg-Marquardt solves with exact Jacobians and a sparse Cholesky factorisation of
// the banded normal equations.
//
// Options and Summary follow Ceres: every knob has a default and a comment, validate() says
// what is wrong instead of crashing, and every run ends in a Summary that says why it stopped.
// The solver never throws on a diverging problem: it stops, says why, and leaves the last good
// iterate in the problem.
#pragma once

#include <atomic>
#include <chrono>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "solver/spacetime_problem.h"

namespace spacetime {

// The method that solves the problem: the augmented Lagrangian with Newton polish (the
// default), the interior-point method through IPOPT (interior_point.h) where it is built, or
// the SQP (sqp.h), or the projected Newton method of Witkin and Kass (witkin_kass.h).
enum class SolverMethod { AugmentedLagrangian, InteriorPoint, Sqp, WitkinKass };

struct SolverOptions {
  SolverMethod method = SolverMethod::AugmentedLagrangian;
  int maxOuterIterations = 30;   // multiplier updates
  int maxInnerIterations = 60;   // Levenberg-Marquardt iterations per outer iteration
  int maxProjectionIterations = 50;  // Gauss-Newton iterations of the final projection
  double tolerance = 1e-7;       // largest constraint row (metres, radians, fraction of weight)
  // rho at a cold start: initialPenalty, or penaltyPerObjective times the objective at the
  // starting point where that is larger. The objective (effort, N^2 m^2 s) grows with the square
  // of a character's weight and size while the constraint rows are scaled (metres, radians,
  // fractions of the weight), so a fixed starting penalty weighs the constraints less the heavier
  // the character. At 100 the biped with a 4 kg head (tests/scenes/biped_heavy_head.json,
  // objective 3763 at the default guess) lifted off its start key while the effort dominated and
  // stalled at a violation of 0.13; from 376 it converges (2537.963). The lamps (objective
  // 0.05-136 there) keep 100 (docs/design.md, Solver item 1).
  double initialPenalty = SolverSpec::kMinPenalty;
  double penaltyPerObjective = 0.1;
  double penaltyGrowth = 10;     // rho *= growth when the violation did not shrink enough
  double maxPenalty = SolverSpec{}.maxPenalty;  // see SolverSpec::maxPenalty
  // Once the violation is within nearFeasible, the penalty grows no further than
  // nearFeasiblePenalty (nor maxPenalty; one already higher stays): from there the multiplier
  // updates close the gap, and a larger penalty only stiffens the inner solves, whose
  // Gauss-Newton steps then crawl along the constraints (the head-rooted lamp, which no polish
  // ends: 3601 -> 1261 iterations; free lift-offs 23-35 % fewer).
  // Without any growth below nearFeasible, solves stalled at violations of 1e-7 - 1e-6 with the
  // penalty still at 1e4.
  double nearFeasible = 1e-4;
  double nearFeasiblePenalty = 1e5;
  // A warm start the Newton steps could not finish (a large edit) restarts its penalty here, not
  // at initialPenalty: its multipliers are already good, and at 100 the iterate drifted from the
  // previous motion into other optima (luxo_3d's end pose moved -10 cm: 998 LM iterations to
  // 34.530 against the cold solve's 32.094; the power-formula jump's moved +10 cm: 9908 to 6222
  // against 5410.85). At 1e4 both land on the cold optimum, in 299 and 300 iterations, and the
  // edits of the jump, hurdle and heavy lamp by -10 to +20 cm take 120-1140 LM iterations instead
  // of 300-3005.
  double warmRestartPenalty = 1e4;
  double maxSeconds = 300;       // wall-clock budget of the whole solve, Newton polish included
  // Seconds of that budget already spent before this solve (the CLI's setup, the coarser
  // transcriptions of a refined solve, a method's steps before it hands over), in budget
  // seconds (budgetSecondsSince): the solve stops at maxSeconds - spentSeconds, and its reason
  // names the whole budget.
  double spentSeconds = 0;
  int threads = 1;               // Ceres evaluation threads
  // The first trust-region radius of each Levenberg-Marquardt solve: large, so they start from
  // (nearly) Gauss-Newton steps. Another value perturbs the solve's path, which the tests use to
  // check that a solve does not depend on luck (newton_polish_test.cpp).
  double initialTrustRegionRadius = 1e10;
  bool warmStart = false;        // keep the problem's current multipliers and penalty
  // Free contact ends (lift-off instants) stay where they are until the constraints are within
  // this: far from feasibility the effort alone would drag them to a bound of their window.
  double releaseFreeEndsAt = 1e-4;
  // Newton polish (newton_polish.h): the first time the violation is below polishBelow after a
  // multiplier update, try Newton steps with the exact Lagrangian Hessian in place of the
  // Gauss-Newton multiplier updates that creep near the optimum (luxo_jump: 360 instead of 858
  // Levenberg-Marquardt iterations). A polish that fails changes nothing. It is tried at most
  // twice, the second time after the violation dropped tenfold: retrying after every update
  // cost more than it saved (luxo_3d, luxo_heavy, power formula: 194 Newton steps).
  bool newtonPolish = true;
  double polishBelow = 1e-4;
  // Each change of the active set costs one step: with every body kept above the ground the
  // lamp's head touches down at the landing, and a 2 cm warm edit of the jump needed 17 steps.
  int maxPolishIterations = 40;
  int maxPolishAttempts = 2;  // the second after the violation dropped tenfold
  // Where a polish attempt fails, the SQP's proximally damped steps from the same point and
  // multipliers (sqpStepsNearFeasible, sqp.h) before the multiplier updates go on: the Newton
  // steps need the point inside their basin, the SQP's line search does not (the 0.9 m rung:
  // 420 LM iterations and 13 steps instead of 1145 LM iterations, to the same optimum).
  bool sqpAfterFailedPolish = true;
  // A warm start whose Newton polish fails takes up to this many of the same damped SQP steps
  // from its start before the multiplier updates (0: none); where they stop, the start is
  // restored. solveRefined sets it on the transcription after a converged one, whose re-fitted
  // motion misses only the rows the split added (the 1.2 m rung's 35 segments: 0 LM iterations
  // and 6 steps, 0.7-0.9 s, instead of 300 LM iterations, 3.4 s; docs/design.md, Solver item 3).
  int warmSqpSteps = 0;
  // SQP steps stop after this many in a row whose programs needed the Hessian shifted by 0.1 or
  // more (0, the default: never; sqp.cpp, kLargeShift): they converge linearly. The warm-start
  // steps above use 3 (augmented_lagrangian.cpp, kWarmShiftedStepsLimit).
  int sqpShiftedStepsLimit = 0;
  // Newton steps tried from a cold start before the augmented Lagrangian (0: none). A quadratic
  // program (the particle scenes) is solved by the first; a failed attempt restores the guess.
  int coldNewtonSteps = 1;
  // Constraints that cannot all hold (two pins at one instant in two places, a contact held over
  // the whole clip under a jump's end pose) stall the violation while the penalty sits at its
  // cap. The solve stops as Stalled after stallUpdates such multiplier updates in which the
  // violation fell by less than 1 % in all, instead of spending the rest of maxOuterIterations.
  int stallUpdates = 10;
  // A stall whose restoration phase shows no conflict is handed to the interior point
  // (interior_point.h, where built; not with free contact ends), from the motion it stalled
  // at, for the rest of the budget: the augmented Lagrangian's Gauss-Newton inner steps crawl
  // where an exact-Hessian method with its own multiplier estimates converges (the ladder's
  // 1.5 m jump at 60 control points per second: stalled at 0.045, then 67 IPOPT iterations to
  // a valid motion).
  // It stops after interiorPointAfterStallIterations (converged hand-overs measured: 45-72
  // iterations; from a motion it cannot finish, such as a transcription too coarse for the
  // task, it wanders) or at the end of the budget.
  bool interiorPointAfterStall = true;
  int interiorPointAfterStallIterations = 200;
  int interiorPointMaxIterations = 3000;  // IPOPT's max_iter (SolverMethod::InteriorPoint)
  // SolverMethod::Sqp and WitkinKass: their steps before they hand over to the augmented
  // Lagrangian (the jump converges in 15-35; a long one that needs more is not converging).
  int sqpMaxSteps = 60;
  // A transcription too coarse for the task: the augmented Lagrangian checks its motion on the
  // dense grid (checkDenseResidual) the first time the violation is below coarseCheckBelow and
  // each time it fell tenfold or five multiplier updates passed since, and stops
  // (SolverSummary::tooCoarse) where two checks in a row leave more than coarseDenseResidual
  // (fraction of the weight; 0: never) unexplained and the second more than half the first: a
  // residual between the samples that does not fall with the violation, which finishing this
  // solve would not make valid. solveRefined sets it where a finer transcription follows.
  double coarseDenseResidual = 0;
  double coarseCheckBelow = 1e-3;

  std::string validate() const;  // empty if valid, else what is wrong
  // The wall-clock instant a solve started at `start` must stop: maxSeconds less spentSeconds,
  // times instrumentedTimeScale().
  std::chrono::steady_clock::time_point deadlineFrom(std::chrono::steady_clock::time_point start) const;
};

// How much slower than a Release build this process runs, from the environment variable
// SPACETIME_TIME_SCALE (1 to 1000; 1 when unset): the asan-ubsan preset sets 30 and the tsan
// preset 20, since such a build solves that much slower (measured under ASan + UBSan at -O1: the
// jump's augmented Lagrangian 32 times), and every wall-clock budget of a solve (maxSeconds,
// --max-seconds, the scene's limit) stretches by it. The tests' own waits read it too.
double instrumentedTimeScale();
// Wall-clock seconds since `start` in budget seconds (divided by instrumentedTimeScale()): what a
// phase of a solve adds to SolverOptions::spentSeconds before the next phase starts.
double budgetSecondsSince(std::chrono::steady_clock::time_point start);

// The options a scene asks for (its `solver` block); the rest keep their defaults.
SolverOptions solverOptionsFor(const SolverSpec& spec);

struct IterationReport {
  int outer = 0;
  int iterations = 0;       // Levenberg-Marquardt iterations so far
  double objective = 0;
  double maxViolation = 0;  // of the current iterate
  double rho = 0;
};

enum class SolveStatus { Converged, IterationLimit, Stalled, TimeLimit, Cancelled, NumericalFailure, InvalidOptions };

// A constraint (one term's rows at one instant) and its largest row violation.
struct ViolatedConstraint {
  std::string label;
  double violation = 0;
};

struct SolverSummary {
  SolverMethod method = SolverMethod::AugmentedLagrangian;  // the method that ran
  SolveStatus status = SolveStatus::InvalidOptions;
  bool converged = false;
  std::string reason;
  double objective = 0;
  double maxViolation = 0;
  std::string worstConstraint;  // label of the most violated row
  // When the solve stops with the constraints unmet: the most violated constraints, largest
  // first (those above a tenth of the largest, at most five). At a stall they are the ones that
  // conflict: the final projection minimises the violations' squares, and at its minimum the
  // unmet rows' gradients cancel.
  std::vector<ViolatedConstraint> violated;
  int outerIterations = 0;
  int iterations = 0;           // total Levenberg-Marquardt (interior point: IPOPT) iterations
  // The Newton polish, whether it succeeded or not: its passes (PolishResult::iterations:
  // steps and active-set changes) and the KKT systems it solved (the steps' cost).
  int newtonSteps = 0;
  int newtonSolves = 0;
  // Of a warm polish: steps on the factorisation kept with the multipliers (chord_steps.h).
  int chordSteps = 0;
  int sqpSteps = 0;             // SolverMethod::Sqp, WitkinKass: their steps (quadratic programs)
  double sqpSeconds = 0;        // the time of those steps, their polish and restorations included
  double qpSeconds = 0;         // of which in the quadratic programs (and the polish's, settling its active set)
  // Of the restoration phase (solver/restoration.h): after a stall, and every iterate of
  // SolverMethod::WitkinKass.
  int restorationSteps = 0;
  double restorationSeconds = 0;
  bool polished = false;        // the result is the Newton polish's KKT point
  // The interior point after a stall (SolverOptions::interiorPointAfterStall): its IPOPT
  // iterations and seconds (0 if it did not run), whether it converged.
  int interiorPointIterations = 0;
  double interiorPointSeconds = 0;
  bool rescued = false;
  // Stopped early at a motion the dense grid showed the transcription too coarse for
  // (SolverOptions::coarseDenseResidual); status IterationLimit.
  bool tooCoarse = false;
  double solveSeconds = 0;
  double jacobianSeconds = 0;   // Ceres's time in residual and Jacobian evaluation
  double linearSolverSeconds = 0;
  // The Newton polish's time (included in the above where it evaluates rows) split by phase.
  double polishSeconds = 0;
  double polishEvaluationSeconds = 0;  // its rows and Jacobians (also in jacobianSeconds)
  double hessianSeconds = 0;
  double factorisationSeconds = 0;
  double lineSearchSeconds = 0;
};

// Called after inner iterations, at most every 100 ms (from the solving thread). Return false
// to cancel.
using ProgressCallback = std::function<bool(const IterationReport&)>;

SolverSummary solveSpacetime(SpacetimeProblem& problem, const SolverOptions& options,
                             const ProgressCallback& callback = nullptr,
                             const std::atomic<bool>* cancel = nullptr);

// Objective value and largest violation of the problem's current variables.
struct ProblemMeasures {
  double objective = 0;
  double maxViolation = 0;
  std::string worstConstraint;
};
ProblemMeasures measure(const SpacetimeProblem& problem);
// The same of rows evaluated elsewhere: rows[k] holds terms[k]'s raw rows.
ProblemMeasures measure(std::span<const TermResidual* const> terms, const std::vector<std::vector<double>>& rows);

// The constraints violated by more than `floor` at the problem's current variables, largest
// first, at most `limit`.
std::vector<ViolatedConstraint> mostViolated(const SpacetimeProblem& problem, double floor, int limit);
// The unmet constraints of a solve that stopped short at `maxViolation`: those above the
// tolerance and a tenth of the largest, at most five (SolverSummary::violated).
std::vector<ViolatedConstraint> unmetConstraints(const SpacetimeProblem& problem, double tolerance, double maxViolation);
// "; most violated: LABEL (VIOLATION), ..." for a stop reason; empty for none.
std::string describeViolated(const std::vector<ViolatedConstraint>& violated);

std::string toString(SolveStatus s);
std::string toString(SolverMethod m);  // "al", "ipopt", "sqp", "witkin-kass": the names the CLI and scenes use
// The method with that name; false if there is none.
bool parseSolverMethod(const std::string& name, SolverMethod* method);

}  // namespace spacetime
