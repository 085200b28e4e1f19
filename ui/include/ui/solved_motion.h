// The motion the editor shows: a solver iterate (or the final solution, or the initial guess)
// sampled for display, with the state that warm-starts the next solve and is saved with the
// scene. An immutable value handed from the solving thread to the interface (latest wins).
#pragma once

#include <memory>
#include <string>

#include "solver/animation.h"
#include "solver/augmented_lagrangian.h"
#include "solver/refinement.h"
#include "solver/spacetime_problem.h"
#include "solver/validity.h"

namespace spacetime::ui {

inline constexpr double kDisplayRateHz = 120;  // frames per second of the sampled motion

struct SolvedMotion {
  Animation animation;  // sampled at kDisplayRateHz
  SolutionState state;  // the problem's variables and multipliers
  // The scene `state` belongs to: after an edit that changes the problem's shape, the next
  // solve re-fits this motion instead of starting from the default guess.
  std::shared_ptr<const Scene> scene;
  // The scene a final solve was asked to solve, when it differs from `scene` only in the
  // transcription the refinement chose (null for iterates and guesses): the document adopts
  // that transcription only while its scene is still this one.
  std::shared_ptr<const Scene> asked;
  double objective = 0;
  double maxViolation = 0;
  int iterations = 0;
  bool solved = false;     // false: the initial guess, or an iterate still being refined
  // Fitted to a motion file's samples (File > Import): `state` holds no multipliers of its own
  // (estimated ones where the method reads them), so the next solve runs the method
  // methodForMotionStart chooses - sqp for a scene whose method is al (MainWindow::solve).
  bool fromMotionFile = false;
  bool converged = false;  // the final solve met its tolerance
  std::string reason;      // why the solve stopped (final motions)
  // The constraints a final solve left unmet, largest first (empty when it converged): when the
  // violation stalls, the ones in conflict.
  std::vector<ViolatedConstraint> violated;
  // The transcriptions a final solve ran on, the scene's first (solver/refinement.h): more than
  // one when it refined the transcription because a coarser motion failed its checks.
  std::vector<TranscriptionAttempt> transcriptions;
  // When a final motion is on a refined transcription: the motion the solve converged to at the
  // scene's own transcription (with its failed report), or null when that solve did not converge.
  // Undoing the refinement shows it again instead of solving the scene once more.
  std::shared_ptr<const SolvedMotion> unrefined;
  // The validity report of a final or loaded solution (null for iterates and guesses): is the
  // motion physical between the samples too?
  std::shared_ptr<const ValidityReport> validity;
};

// Samples the problem's current variables.
std::shared_ptr<SolvedMotion> sampleMotion(const SpacetimeProblem& problem);

// Joint positions (or velocities, order 1) of a character at time t, linear between frames,
// clamped to the clip.
Eigen::VectorXd poseAt(const CharacterAnimation& a, double t, int order = 0);

// Whether the motion's characters have the scene's characters' dofs (after a structural edit
// they do not, and the motion cannot be drawn).
bool motionFitsScene(const SolvedMotion& motion, const Scene& scene);

}  // namespace spacetime::ui
