// The validity report: is a solved motion physically valid between the samples too?
//
// A collocation transcription can look converged while the motion between samples is
// unphysical, so the report judges on a grid `denseFactor` times denser than the samples (and
// ten times finer again next to every contact's start and end, where the ground force switches):
// the largest unactuated generalized force (as a fraction of the character's weight), pin
// errors, contact slip and penetration, contact forces' sign and friction, clearance, rest at
// the rest terms, and - the independent check - the error of forward-simulating the solved
// actuated torques with the articulated-body algorithm over each flight phase, the impulse
// balance of every touch-down, and every formula constraint.
#pragma once

#include <atomic>
#include <optional>
#include <string>
#include <vector>

#include "solver/spacetime_problem.h"

namespace spacetime {

struct FlightCheck {
  std::string character;
  double start = 0, end = 0;
  double maxPositionError = 0;  // max |q_sim - q_solution| over the phase (m or rad)
  double maxRootLift = 0;       // highest the lowest contact point of the root rises (m)
  // The simulation left the solution by more than kDivergence (or stopped being finite) at
  // divergenceTime; maxPositionError is then the deviation up to that instant.
  bool diverged = false;
  double divergenceTime = 0;
  static constexpr double kDivergence = 100;  // m or rad: far beyond any error of a valid motion
};

// A touch-down with an impact, checked with the CRBA mass matrix and the contact Jacobian
// (independent of the RNEA the solver differentiates): M (qd+ - qd-) = J^T L on the root rows.
struct ImpactCheck {
  std::string contact;
  double time = 0;
  double speedBefore = 0;       // fastest contact point just before (m/s)
  double minNormalImpulse = 0;  // N s (negative would mean the ground pulls)
  double maxFrictionRatio = 0;  // |L_t| / (mu L_n)
  double maxBalanceError = 0;   // root rows of M dqd - J^T L, N s
  double maxSpeedAfter = 0;     // fastest contact point just after (m/s)
  double maxJointImpulse = 0;   // largest impulsive joint torque, N m s
};

// A formula constraint (`expression relation value`) re-evaluated on the motion: at its time,
// or at every dense-grid instant of its interval.
struct FormulaCheck {
  std::string term;
  double maxViolation = 0;  // |f - v| for =, max(0, f - v) for <=, max(0, v - f) for >=
  double worstTime = 0;
  std::string error;        // the formula no longer applies to the character (not expected)
};

// The largest unactuated residual the dense grid allows (fraction of weight): the engine issue's.
inline constexpr double kDenseResidualLimit = 0.01;

struct ValidityReport {
  int denseFactor = 10;
  double maxUnactuatedResidualSamples = 0;  // fraction of weight, at the collocation samples
  double maxUnactuatedResidualDense = 0;    // fraction of weight, on the dense grid (+ contact edges)
  double worstDenseTime = 0;
  // The largest of those within each spline segment (Transcription::motion): where the
  // refinement splits segments (solver/refinement.h).
  std::vector<double> segmentResidualDense;
  double maxPinError = 0;                   // m
  double maxContactSlip = 0;                // m, horizontal distance from the anchor
  double maxContactPenetration = 0;         // m, below the ground
  double minNormalForce = 0;                // N (negative would mean pulling)
  double maxFrictionRatio = 0;              // |f_t| / (mu f_n) where f_n >= 1 % of weight
  double maxConeViolation = 0;              // max(0, |f_t| - mu f_n), fraction of weight
  double maxClearanceViolation = 0;         // m
  double worstClearanceTime = 0;            // when, and which term
  std::string worstClearanceTerm;
  double maxRestSpeed = 0;                  // largest |qd| at the rest terms
  // How far any body's geometry dips below the ground on the dense grid (m; 0 when none does),
  // outside the contacts that hold that body on it; when and which body. Passes at <= 1 mm.
  double maxGroundPenetration = 0;
  double worstGroundPenetrationTime = 0;
  std::string worstGroundPenetrationBody;
  // How far any joint goes beyond its position limits (rad or m) and its speed limit (rad/s or
  // m/s) on the dense grid; when and which joint. Reported when some joint has such a limit.
  bool hasPositionLimits = false, hasSpeedLimits = false;
  double maxJointLimitExcess = 0;
  double worstJointLimitTime = 0;
  std::string worstJointLimit;
  double maxJointSpeedExcess = 0;
  double worstJointSpeedTime = 0;
  std::string worstJointSpeed;
  std::vector<FlightCheck> flights;
  std::vector<ImpactCheck> impacts;
  std::vector<FormulaCheck> formulas;
  double maxFormulaViolation = 0;
  double maxForwardSimulationError = 0;
  bool forwardSimulationDiverged = false;  // some flight's simulation diverged (see FlightCheck)
  bool contactsPushOnly = true;
  bool contactsInFrictionCone = true;
  bool cancelled = false;  // stopped early through checkValidity's cancel flag: incomplete
};

// `cancel` (optional) stops the checks early: the report then has `cancelled` set and is
// incomplete (the editor drops the report of a motion an edit has already replaced).
ValidityReport checkValidity(const SpacetimeProblem& problem, int denseFactor = kDenseGridFactor,
                             const std::atomic<bool>* cancel = nullptr);

// Only the unactuated residual of checkValidity's report (maxUnactuatedResidualSamples,
// maxUnactuatedResidualDense, worstDenseTime, segmentResidualDense), at a fraction of its cost:
// what a solve reads to see a transcription too coarse for its task (SolverOptions::
// coarseDenseResidual).
ValidityReport checkDenseResidual(const SpacetimeProblem& problem, int denseFactor = kDenseGridFactor);

// The largest unactuated generalized force of character c at sample s (fraction of weight), on
// the side the problem imposes physics there: a flight's first instant (Sample::after) with the
// flight interval's motion and without the contacts ending at s.time. Ground forces are the
// admissible ones that explain the most (groundForcesAt), not the solver's variables.
double sampleUnactuatedResidual(const SpacetimeProblem& problem, int c, const Sample& s);

// The report as a checklist for people: each check's value against its limit. The limits are
// the engine issue's (1 % of weight on the dense grid, 1e-6 at the samples) and, where it names
// none, tolerances well above the solver's and well below what an animator would see (0.1 mm,
// 1 cm or 0.01 rad for a forward simulation, 1e-5 for formulas).
struct ValidityCheck {
  std::string name;   // what is checked, e.g. "unactuated residual, dense grid"
  double value = 0;   // the measured value (1 or 0 for yes/no checks)
  double limit = 0;   // pass when value <= limit
  std::string unit;   // "× weight", "m", "N s", ... ("" for yes/no checks)
  bool pass = true;
  std::optional<double> time;  // where it is worst, when the check knows (to go and look)
  bool yesNo = false;          // a yes/no check: its value and limit mean nothing to show
};
std::vector<ValidityCheck> validityChecklist(const ValidityReport& report);

}  // namespace spacetime
