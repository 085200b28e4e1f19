// The Scene: the editable document that says what a motion must do and how. Plain values only
// (no Qt, no solver types) so the editor, the command-line tool and the tests share it.
//
// A scene holds characters (a tree of bodies with joints, geometry and mass), the time range,
// gravity, the ground plane (y = height, y is up), the transcription settings, the constraint
// terms (pins, keyframes, rests, contacts, clearances) and the weighted objective terms.
// Joint position, speed and torque limits live on the joints. Ids are stable strings.
#pragma once

#include <Eigen/Core>
#include <array>
#include <map>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace spacetime {

enum class RootKind {
  Fixed,          // bolted to the world
  Planar,         // x, y translation and rotation about z (dofs <root>_x, <root>_y, <root>_rz)
  Floating3D,     // x, y, z then yaw (y), pitch (z), roll (x) Euler angles
  Translation3D,  // x, y, z only: a point mass (the seed's particle)
};

enum class GeometryKind { None, Box, Sphere, Capsule, Cylinder };

struct Geometry {
  GeometryKind kind = GeometryKind::None;
  // Box: full extents (x, y, z). Sphere: radius in [0]. Capsule/cylinder: radius in [0],
  // length (of the cylindrical part) in [1], along `axis`.
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
  int axis = 1;  // 0 = x, 1 = y, 2 = z (capsule and cylinder)
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  // centre in the body frame
};

enum class JointKind { Revolute, Prismatic, Helical, Fixed };

struct JointSpec {
  std::string id;  // the degree of freedom's name
  JointKind kind = JointKind::Revolute;
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // joint position in the parent body frame
  Eigen::Vector3d rpy = Eigen::Vector3d::Zero();     // joint frame orientation (URDF roll-pitch-yaw)
  double pitch = 0;                                  // helical: metres per radian
  bool actuated = true;
  std::optional<std::pair<double, double>> limits;  // [lower, upper]
  std::optional<double> torqueLimit;                // |tau| <= limit
  std::optional<double> speedLimit;                 // |qd| <= limit (rad/s or m/s)
};

struct BodySpec {
  std::string id;
  std::string parent;  // empty for the root body
  JointSpec joint;     // ignored for the root body (its root kind decides)
  Geometry geometry;
  std::optional<double> mass;     // kg; with geometry and no inertia: inertia from the shape
  std::optional<double> density;  // kg/m^3; mass from the shape's volume
  std::optional<Eigen::Vector3d> com;      // centre of mass in the body frame
  std::optional<Eigen::Matrix3d> inertia;  // about the centre of mass, body axes
  Eigen::Vector3d color = Eigen::Vector3d(0.8, 0.8, 0.8);
};

struct CharacterSpec {
  std::string id;
  RootKind root = RootKind::Planar;
  bool rootActuated = false;  // true for a thruster-driven particle
  std::vector<BodySpec> bodies;

  // Names of the degrees of freedom in order (root dofs, then joints in body order).
  std::vector<std::string> dofNames() const;
  const BodySpec* body(const std::string& id) const;
};

enum class TermKind { Pin, Keyframe, Rest, Contact, Clearance, Formula };

struct TermSpec {
  std::string id;
  TermKind kind = TermKind::Pin;
  bool enabled = true;
  std::string character;
  std::string body;  // pin, rest (optional), contact, clearance
  double time = 0;   // pin, keyframe, rest
  std::optional<double> until;  // pin: held over [time, until]
  Eigen::Vector3d point = Eigen::Vector3d::Zero();     // pin, clearance: in the body frame
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // pin: world target
  std::array<bool, 3> axes{true, true, true};          // pin: which world axes are held
  std::vector<std::pair<std::string, double>> values;  // keyframe: dof name -> value
  std::vector<Eigen::Vector3d> points;                 // contact: body-frame points
  double start = 0, end = 0;                           // contact, clearance interval
  double friction = 1.0;                               // contact: Coulomb coefficient mu
  // contact beginning after the clip's start: the points touch down with an impact (a
  // velocity jump of the root, with a ground impulse) rather than already at rest
  bool impact = true;
  // contact: the solver chooses when the points leave the ground - `end` is only where the
  // search starts (a lift-off instant as a variable; times of other terms equal to `end` move
  // with it, and no other term's time may lie inside its window). The window: the root
  // breakpoints next to `end` (0, the default: only the lift-off moves, between two knots), or
  // those at least freeEndWindow seconds either side (the breakpoints inside then move too)
  bool freeEnd = false;
  double freeEndWindow = 0;
  double height = 0;                                   // clearance: minimum world y
  bool box = false;  // clearance: stay outside the axis-aligned box [boxMin, boxMax] instead
  Eigen::Vector3d boxMin = Eigen::Vector3d::Zero(), boxMax = Eigen::Vector3d::Zero();
  // formula: `expression relation value` at `time`, or at every sample of [start, end] when
  // `interval` is set (see core/expr/formula.h for the language).
  std::string expression;
  char relation = '=';  // '=', '<' (<=) or '>' (>=)
  double value = 0;
  bool interval = false;
};

// A user objective term: weight * integral of expression^2 dt.
struct FormulaObjective {
  std::string character;
  std::string expression;
  double weight = 1;
};

struct ObjectiveSpec {
  double effort = 1.0;       // weight of the integral of sum tau^2 over actuated joints
  double power = 0.0;        // weight of the integral of sum (tau * qd)^2
  double smoothness = 1e-3;  // weight of the integral of |q^(order)|^2 (relative, see solver)
  int smoothnessOrder = 2;   // 2: acceleration, 3: jerk
  double contactForce = 1e-3;  // weight of the integral of sum |f / (m g)|^2: load sharing
  std::vector<FormulaObjective> formulas;
};

// Bounds the loader enforces, so that no file can make a solve allocate without bound, run for
// hours before its time budget starts, or overflow a double: far beyond any animation scene
// (a humanoid has 20-60 bodies; a 60 s clip at 40 control points per second is 2400 segments),
// far below what the machine cannot hold (1000 bodies ran out of memory in Ceres; 1e6 control
// points per second took minutes inside the transcription before --max-seconds started).
struct SceneLimits {
  static constexpr double kMaxMagnitude = 1e9;  // any number of the scene, in SI units
  static constexpr std::size_t kMaxIdLength = 64;
  static constexpr std::size_t kMaxCharacters = 16;
  static constexpr std::size_t kMaxBodies = 100;  // per character
  static constexpr std::size_t kMaxTerms = 10000;
  static constexpr double kMaxSegments = 4000;  // (time.end - time.start) x controlPointsPerSecond
  // Summed over the characters: (bodies + 6)^2 x segments x samplesPerSegment, the size of the
  // dynamics' Jacobians the solve holds (a chain of 100 bodies over 10 s at 80 control points per
  // second and 8 samples per segment, 7.2e7, took 4.5 GB and 30 s for its first iteration; a
  // 30-body humanoid over 60 s at 40 control points per second and 6 samples, 3.1e6).
  static constexpr double kMaxWork = 1e7;
};

struct TranscriptionSpec {
  // Gauss points between breakpoints; the floating root's curves have degree samples + 1 (2:
  // C1 cubics, de Boor-Swartz). At most kMaxSamplesPerSegment.
  static constexpr int kMaxSamplesPerSegment = 8;
  double controlPointsPerSecond = 20;
  int samplesPerSegment = 2;
  // The spline's interior knots (s, increasing, inside the clip), when the automatic refinement
  // has split some segments (solver/refinement.h): they then replace the uniform knots of
  // controlPointsPerSecond, which stays the rate the refinement started from. Empty: uniform.
  std::vector<double> knots;
  static constexpr double kMinKnotSpacing = 1e-4;  // s, between knots and from the clip's ends
  // Whether a knot at t may follow the knot (or the clip's start) at `after` in a clip ending at
  // `end`: the loader's rule, which the transcription also applies to scenes built in code.
  static bool knotFollows(double after, double t, double end) {
    return t >= after + kMinKnotSpacing && t <= end - kMinKnotSpacing;
  }
  // Spline segments on [t0, t1]: the knots', or the rate's.
  double segments(double t0, double t1) const {
    return knots.empty() ? (t1 - t0) * controlPointsPerSecond : static_cast<double>(knots.size() + 1);
  }
  // Leg bubbles (solver/leg_bubbles.cpp): extra unknowns on the legs of a character standing on
  // several feet, so that each leg can follow its foot between the knots. The refinement turns
  // them on after a stall where they apply.
  bool legBubbles = false;
};

struct SolverSpec {
  // The method (solver/augmented_lagrangian.h, SolverMethod): "al", the augmented Lagrangian
  // with Newton polish, "ipopt", the interior point through IPOPT, "sqp", the SQP, or
  // "witkin-kass", the projected Newton method whose every iterate is restored.
  static constexpr const char* kMethods[] = {"al", "ipopt", "sqp", "witkin-kass"};
  std::string method = "al";
  int maxOuterIterations = 30;
  int maxInnerIterations = 60;
  double tolerance = 1e-7;  // on scaled constraint rows (metres, radians, fraction of weight)
  // Cap of the augmented Lagrangian's penalty rho. Capped at 1e7 (it was 1e10), the
  // multipliers, not the penalty, meet the constraints, and Levenberg-Marquardt is not driven
  // into the nearest feasible point: luxo_jump's effort optimum fell from 134.5 to 17.53.
  static constexpr double kMinPenalty = 100;  // the penalty a cold solve starts from
  double maxPenalty = 1e7;
  // Keep every body's geometry above the ground outside its own contacts (automatic ground
  // clearances on each shape's lowest-point features; characters with a fixed root excepted).
  bool bodiesAboveGround = true;
  // Finer transcriptions a solve may try after the scene's own when the motion fails its
  // validity checks (solver/refinement.h); 0 turns the refinement off.
  static constexpr int kMaxRefinements = 10;
  int maxRefinements = 3;
  // Wall-clock budget of a whole solve, its refinements included (s, at most kMaxSeconds).
  static constexpr double kMaxSeconds = 1e7;
  double maxSeconds = 300;
};

// A solved motion saved with the scene so reopening shows it: the solver's variables and
// augmented-Lagrangian multipliers exactly as the transcription of this scene lays them out
// (see solver/spacetime_problem.h). A solution whose size no longer fits the scene is ignored
// by the solver and the editor, never an error.
struct StoredSolution {
  std::vector<double> variables;
  std::vector<double> multipliers;
  double rho = 0;
  bool converged = false;
};

struct Scene {
  std::string name;
  double startTime = 0, endTime = 1;
  // Frames per second of the animation as shown and exported: the timeline's stepping, PNG
  // frames, BVH frames and glTF's key grid (scene file: time.frameRate). Not part of the problem.
  // 24 by default, film's rate and a new Blender scene's: its BVH importer makes one scene frame
  // of each BVH frame, so a 24 fps file imports with the clip's own duration.
  static constexpr double kMaxFrameRate = 1000;
  double frameRate = 24;
  Eigen::Vector3d gravity = Eigen::Vector3d(0, -9.81, 0);
  bool groundEnabled = true;
  double groundHeight = 0;
  TranscriptionSpec transcription;
  SolverSpec solver;
  std::vector<CharacterSpec> characters;
  std::vector<TermSpec> terms;
  ObjectiveSpec objective;
  std::optional<StoredSolution> solution;

  const CharacterSpec* character(const std::string& id) const;
};

std::string toString(RootKind k);
std::string toString(GeometryKind k);
std::string toString(JointKind k);
std::string toString(TermKind k);

}  // namespace spacetime
