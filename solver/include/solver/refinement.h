// Automatic refinement of the transcription: solve, check validity between the samples, and
// solve again on a finer transcription where it fails, warm-started from the coarser motion.
//
// A collocation transcription imposes physics at its samples only. A motion the samples cannot
// resolve (a long jump's push-off at the friction cone's edge, a fast swing after lift-off) then
// converges but leaves the dynamics unexplained between them (the validity report's dense grid),
// or stalls because no motion of that resolution meets every constraint. The animator should not
// have to know that the cure is more collocation points: the scene's transcription is where the
// solve starts, and each refinement multiplies the control points per second by kRateGrowth and
// raises the samples per segment to at least kMaxRefinedSamples (more Gauss points and
// per-sample forces per interval: the stance's ground forces and the root's polynomial follow
// the joints more closely), rebuilds the problem, starts it from the best motion so far
// (SpacetimeProblem::initializeFrom: joint splines re-fitted, root data and forces resampled)
// and solves it - warm after a converged solve, with fresh multipliers after a stalled one. It
// stops at the first
// transcription whose motion converges and passes every validity check, when the refinement
// budget is spent, or when a solve stops for a reason a finer transcription cannot change
// (cancelled, out of time, numerical failure, invalid options).
//
// A stall triples the rate instead (kStallRateGrowth), and on a refined transcription a stall
// the restoration phase does not show to conflict goes to the interior point
// (SolverOptions::interiorPointAfterStall), as do the finer transcriptions after it.
//
// Where a converged motion fails only between the samples in a few places, the refinement is
// local instead (refineWhereResidual): the spline segments whose dense-grid residual is large
// are split in two, the knots becoming non-uniform (TranscriptionSpec::knots), and the rest of
// the motion keeps its resolution. Measured on the jump ladder (tests/scenes/ladder/;
// docs/validation.md).
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "solver/augmented_lagrangian.h"
#include "solver/validity.h"

namespace spacetime {

struct RefinementOptions {
  bool enabled = true;
  int maxRefinements = 3;                  // finer transcriptions tried after the scene's own
  double maxControlPointsPerSecond = 80;   // no refinement beyond this rate
  static constexpr int kMaxRefinedSamples = 8;
  static constexpr double kRateGrowth = 1.5;
  // After a stall: the task needs a much finer transcription (the ladder's 1.5 m jump stalls at
  // 20, 30 and 45 control points per second and solves at 60, where 1.5x steps spent the budget
  // on the intermediate rates).
  static constexpr double kStallRateGrowth = 3;
  // Segments whose dense-grid residual is above this fraction of the limit are split
  // (refineWhereResidual), while they are fewer than the uniform refinement would add.
  static constexpr double kSplitFraction = 0.5;
  // Where a finer transcription follows, a solve stops once its motion, near the constraints,
  // leaves more than this times the limit unexplained on the dense grid
  // (SolverOptions::coarseDenseResidual).
  static constexpr double kCoarseFactor = 10;
  // After a converged solve, the finer transcription's augmented Lagrangian first takes up to
  // this many damped SQP steps where its warm Newton polish fails (SolverOptions::warmSqpSteps;
  // 0: none; the 1.2 m rung's last transcription takes 6).
  int warmSqpSteps = 20;

  // Whether any finer transcription may be tried at all.
  bool refines() const { return enabled && maxRefinements > 0; }
};

// The refinement a scene asks for (SolverSpec::maxRefinements).
RefinementOptions refinementOptionsFor(const SolverSpec& spec);

// One transcription the solve ran on, and how that solve ended.
struct TranscriptionAttempt {
  double controlPointsPerSecond = 0;
  int samplesPerSegment = 0;
  int segments = 0;               // spline segments
  bool nonUniform = false;       // on the refinement's knots (TranscriptionSpec::knots)
  bool legBubbles = false;       // with leg bubbles (TranscriptionSpec::legBubbles)
  std::string why;               // why this transcription was tried ("the scene's", or the failure)
  SolveStatus status = SolveStatus::InvalidOptions;
  bool converged = false;
  // Stopped before converging at a motion the dense grid showed too coarse a transcription for
  // (SolverSummary::tooCoarse): refined where its residual was, as a converged one would be.
  bool tooCoarse = false;
  bool valid = false;            // every validity check passes
  double objective = 0;
  double maxViolation = 0;
  double maxUnactuatedResidualDense = 0;
  int iterations = 0;            // Levenberg-Marquardt iterations
  int newtonSteps = 0;
  double seconds = 0;
  bool kept = false;             // its motion is the result
};

struct RefinedSolve {
  std::unique_ptr<SpacetimeProblem> problem;  // the kept transcription's problem and motion
  SolverSummary summary;                      // its solve, with the time and iterations of all
  ValidityReport validity;                    // of the final motion
  std::vector<TranscriptionAttempt> attempts; // in the order tried, the scene's transcription first
  bool valid = false;                         // the kept motion converged and passes every check
};

// The transcription an attempt ran on, in words: "20 control points per second, s = 6", or
// "32 segments split from 20 control points per second, s = 8".
std::string describeResolution(const TranscriptionAttempt& attempt);

// Called (from the solving thread) with each transcription's problem just before it is solved:
// the scene's own, then each finer one, already started from the best motion so far. A live
// view samples the iterates of this problem: the finer ones are not the problem it passed in.
using TranscriptionCallback = std::function<void(const SpacetimeProblem&)>;
// Called (from the solving thread) after each transcription's solve and check, with its problem
// (holding the motion it reached), what came of it and its validity report: an editor keeps the
// motion at the scene's own transcription this way, so undoing the refinement shows it again.
using TranscriptionSolvedCallback =
    std::function<void(const SpacetimeProblem&, const TranscriptionAttempt&, const ValidityReport&)>;

// The next finer transcription after `spec`: `growth` times its rate, at most the cap, uniform
// again, and at least kMaxRefinedSamples; false when its rate is at the cap already.
bool refineTranscription(const TranscriptionSpec& spec, const RefinementOptions& options, TranscriptionSpec* finer,
                         double growth = RefinementOptions::kRateGrowth);

// The local refinement after a converged motion whose dense-grid residual fails: `motion`'s
// segments whose residual (report.segmentResidualDense) is above kSplitFraction of the limit,
// split at their middle, at least kMaxRefinedSamples per segment. False (refine uniformly) when
// the residual passes, or when no segment may be split (none longer than two intervals of the
// rate cap) or more would be than kRateGrowth adds.
bool refineWhereResidual(const TranscriptionSpec& spec, const CubicBSpline& motion, const ValidityReport& report,
                         const RefinementOptions& options, TranscriptionSpec* finer);

// Solves `problem` (built from its scene) and refines as above. The progress callback and cancel
// flag apply to every solve; options.maxSeconds bounds them all together; `starting` hears of
// each transcription before its solve and `solved` after it. The returned problem is
// `problem` itself when no refinement ran.
RefinedSolve solveRefined(std::unique_ptr<SpacetimeProblem> problem, SolverOptions options,
                          const RefinementOptions& refinement, const ProgressCallback& callback = nullptr,
                          const std::atomic<bool>* cancel = nullptr, const TranscriptionCallback& starting = nullptr,
                          const TranscriptionSolvedCallback& solved = nullptr);

}  // namespace spacetime
