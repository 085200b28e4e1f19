// MotionSource: an earlier motion a solve starts from when its variables cannot be restored
// one for one (SpacetimeProblem::initializeFrom re-fits it to the new transcription). Two kinds:
// another problem's solution (a finer transcription, an edited scene: exact splines and the
// solver's own forces), and a sampled Animation (a motion.json read back without the solver
// state beside it: joint positions and velocities interpolated between frames, the recovered
// ground forces per point). Characters are matched by id and dof count, contacts by term id and
// point count; what has no counterpart keeps the problem's default guess.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "solver/augmented_lagrangian.h"
#include "solver/multiplier_estimate.h"

namespace spacetime {

class SpacetimeProblem;
struct Animation;

class MotionSource {
 public:
  virtual ~MotionSource() = default;
  // The span of time the motion covers; times outside it read its ends.
  virtual double start() const = 0;
  virtual double end() const = 0;
  // The index of the character with this id and this many dofs, -1 if there is none.
  virtual int character(const std::string& id, int dofs) const = 0;
  // Joint positions (order 0) or velocities (order 1) of character c at t; `before`: the left
  // limit at a touch-down's impact, where the velocities jump.
  virtual Eigen::VectorXd jointState(int c, double t, int order, bool before = false) const = 0;
  // The interval of the contact with this term id, if the motion has one.
  virtual std::optional<std::pair<double, double>> contactInterval(const std::string& term) const = 0;
  // The world force on each of its `points` points at t (empty when the motion has no such
  // contact, or it has another number of points or force components: `forceDims` per point).
  virtual std::vector<Eigen::Vector3d> contactForces(const std::string& term, int points, int forceDims,
                                                     double t) const = 0;
  // Where each point rests on the ground (world x, z; 2 values per point), empty if unknown.
  virtual std::vector<double> anchors(const std::string& term, int points, int forceDims) const = 0;
  // Each point's world impulse at the touch-down, empty without one.
  virtual std::vector<Eigen::Vector3d> impulses(const std::string& term, int points, int forceDims) const = 0;
  // Whether the motion is sampled frames (a motion file) rather than another problem's splines.
  virtual bool sampled() const { return false; }
};

// The solution `problem` holds now (it must outlive the source).
std::unique_ptr<MotionSource> motionSourceOf(const SpacetimeProblem& problem);
// A sampled motion (it must outlive the source); frames in increasing time.
std::unique_ptr<MotionSource> motionSourceOf(const Animation& animation);

// Starts `problem` from a sampled motion: SpacetimeProblem::initializeFrom, then each contact
// sample's forces balanced on the fitted motion (groundForcesAt, tie-broken towards the file's):
// the file's forces are linear between frames, which a push-off outruns (0.10 x weight off at
// the jump's samples from 120 Hz frames). Returns the number of characters matched.
int startFromMotion(SpacetimeProblem& problem, const Animation& animation);

// The method a solve started by startFromMotion runs when `method` was the scene's: a motion
// file has no multipliers, and even from estimated ones (motionStartReadsMultipliers below) the
// augmented Lagrangian's Newton polish does not always finish (from its own motion file the 3D
// lamp took 120 LM iterations and 17 Newton steps, 2.8 s), where sqp's first program computes
// them and its steps end at the motion's optimum in 0-2 (the 3D lamp 1.55 s; the biped 1.06 s,
// where the polish alone takes 0.68 s; docs/performance.md, "Starting from a motion file"). So
// `al` becomes `sqp`; the other methods stay.
SolverMethod methodForMotionStart(SolverMethod method);

// Whether `method`, started from a motion file, reads the multipliers from the problem's state,
// so that they are estimated first (estimateMultipliers, solver/multiplier_estimate.h): the
// augmented Lagrangian (its warm start is the Newton polish, whose active set is lambda + rho g)
// and witkin-kass (whose warm start is the augmented Lagrangian's). From the jump's own motion
// file both then end at its optimum in 3 Newton steps instead of re-running the whole path (375
// LM iterations) to another. `sqp` computes them in its first program: started warm from the
// estimate, the 3D lamp took 7 steps instead of 2. The interior point computes its own.
bool motionStartReadsMultipliers(SolverMethod method);

// The multipliers of a motion-file start for the method `options` solves it with: estimated
// (estimateMultipliers) at the penalty a near-feasible augmented Lagrangian holds when that
// method reads them (motionStartReadsMultipliers), nothing otherwise. The CLI and the editor's
// import both start this way.
std::optional<MultiplierEstimate> multipliersForMotionStart(SpacetimeProblem& problem, const SolverOptions& options);

}  // namespace spacetime
