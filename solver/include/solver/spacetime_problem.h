// The spacetime transcription of a Scene (Witkin & Kass 1988, with Cohen's 1992 B-spline
// degrees of freedom): variables, terms and the Ceres problem that holds them.
//
// Variables: for each character, the actuated dofs' B-spline control points and the root dofs'
// Hermite data (see DofGroup); for each contact, the points' ground forces at every sample of
// the contact interval and the points' ground anchors (x, z). Terms: at every collocation
// sample, inverse dynamics (the unactuated generalized forces must vanish - physics - and the
// actuated ones enter the objective), a small smoothness integrand and joint limits; pins,
// keyframes, rests, contacts (anchored points, forces in the friction cone), clearances and
// formula terms at their times.
//
// Held stances: a contact whose points fix the floating root (held_stances.cpp) holds the root
// still by construction - one pose, zero velocity - instead of by anchor rows at the samples.
// Any other contact with a fixed end keeps its points still by their motion: anchored and at
// rest at its first instant, zero acceleration at every collocation sample.
// Lift-off: a contact that ends before the clip does lets go with zero force (letsGo).
//
// Free contact ends (the scene's `freeEnd`): the lift-off instant T of such a contact is one
// more variable. The root's breakpoint at the contact's end becomes T, inside a window
// [left, right] of root breakpoints around it (the scene's `freeEndWindow` either side); the
// window's breakpoints and collocation samples before T keep their places relative to
// [left, T], those after it relative to [T, right] (a two-phase time scaling), so they move
// with T, and every residual imposed at one of them is rebuilt from T at each evaluation
// (TermResidual's moving inputs, with exact slopes). The problem's times (breakpoints, samples,
// the contact's end and sample times) are brought to the solved T by syncFreeEnds, which the
// solver calls when it stops and restore() calls. The window's code is in free_ends.cpp.
#pragma once

#include <ceres/problem.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/scene.h"
#include "dynamics/model.h"
#include "solver/term_residual.h"
#include "solver/transcription.h"

namespace spacetime {

class MotionSource;

// Which root (Hermite) interval an instant on a breakpoint reads; the root's acceleration jumps
// there. Contacts: the interval whose contacts are those active at t (the instant a contact ends
// belongs to the contact phase, one that begins to it too). Before: the interval that ends at t
// (the state just before an impact; the flight just before a touch-down). After: the interval
// that starts at t (the flight just after a lift-off).
enum class Side { Contacts, Before, After };

// Degrees of freedom are split in two groups.
// - Actuated dofs: uniform cubic B-splines (C2) at the scene's control-point rate; their shape
//   is what the animator sees and the smoothness term acts on.
// - Unactuated dofs (the floating root): C1 piecewise polynomials of degree s + 1 collocated at
//   the s Gauss points of each interval (s = samples per segment) - the convergent collocation
//   of de Boor & Swartz (1973) for second-order ODEs, with as many unknowns as physics
//   equations, so the root follows the dynamics the joints drive. Each interval is a cubic
//   Hermite curve (a position and a velocity per breakpoint, shared with the neighbours) plus
//   s - 2 "bubbles" u^2 (1-u)^2 (2u-1)^j that vanish with their slope at both ends. A C2 spline
//   collocated once per segment would have a null mode (alternating control points vanish at
//   segment midpoints) and could wiggle freely between samples; a C2 spline collocated more
//   often would have fewer unknowns than equations. The root's acceleration may jump at
//   breakpoints, as it must where a contact begins or ends. The interval that starts a flight
//   after a lift-off has s - 1 bubbles and s + 1 Radau nodes, the first at the lift-off read on
//   the flight side (Transcription::flightStarts): physics holds from the flight's first instant.
//
// - Leg bubbles (legBubbles): extra shapes added to some actuated dofs inside stances on several
//   legs (leg_bubbles.cpp). A contact that does not hold the root is kept still by zero
//   acceleration of its points at every collocation node; the root's coefficients meet those rows
//   for as many contacts as it has dofs, and each further contact on a leg of its own gets s - 1
//   bubbles 64 u^3 (1-u)^3 (2u-1)^j per interval on that leg's joints, so that the leg has as many
//   unknowns per interval as its foot has rows there. These dofs keep their B-spline (in group 0);
//   the bubbles add to it, vanish with their first two derivatives at the interval's ends (the
//   joint stays C2) and are zero outside those intervals.
struct DofGroup {
  bool hermite = false;
  bool legBubbles = false;
  CubicBSpline spline;         // B-spline group
  std::vector<double> breaks;    // Hermite and leg-bubble groups: breakpoints (the root's)
  int bubbles = 0;               // Hermite group: interior coefficients per interval and dof
  // Hermite: intervals with one more bubble (1), where a flight starts after a lift-off and the
  // transcription collocates s + 1 Radau nodes (Sample::after); empty: none. Leg bubbles: each
  // interval's bubble count (s - 1 inside the leg's stances, 0 elsewhere).
  std::vector<int> extraBubble;
  std::vector<int> bubbleStarts;  // interval k's bubbles start at x[bubbleStarts[k]]
  std::vector<int> dofs;         // dof indices in this group
  int offset = 0;  // B-spline: control point k at offset + k * n; Hermite: breakpoint k holds
                   // positions then velocities at offset + k * 2n (n = dofs.size())
  int bubbleOffset = 0;  // Hermite: the intervals' bubbles from here, interval k's at
                         // bubbleStart(k), bubble j of dof d at + j * n + d
  // Hermite: held stances (see SpacetimeProblem::layoutHeldStances). poseOf[k] is the breakpoint
  // whose positions hold breakpoint k's pose while a contact holds the root still (-1: free);
  // heldInterval[k] says interval k lies inside such a stance (the root is constant there).
  std::vector<int> poseOf;
  std::vector<char> heldInterval;
  bool heldAt(int k) const { return !poseOf.empty() && poseOf[k] >= 0; }
  // Hermite: breakpoint k is the first of an impact's repeated pair (the state before it).
  bool beforeImpact(size_t k) const {
    return k + 1 < breaks.size() && std::abs(breaks[k + 1] - breaks[k]) < kTimeTolerance;
  }
  int blockSize() const { return legBubbles ? 0 : (hermite ? 2 : 1) * static_cast<int>(dofs.size()); }
  int blockCount() const {
    return hermite || legBubbles ? static_cast<int>(breaks.size()) : spline.controlPointCount();
  }
  // Whether the group is laid out on breakpoint intervals with bubbles (Hermite or leg bubbles).
  bool hasBubbles() const { return hermite || legBubbles; }
  int bubblesIn(int k) const {
    return bubbles + (k < static_cast<int>(extraBubble.size()) ? extraBubble[k] : 0);
  }
  int bubbleBlockSize(int k) const { return bubblesIn(k) * static_cast<int>(dofs.size()); }
  int bubbleStart(int k) const { return bubbleStarts[k]; }
  // Lays out the bubbles from bubbleOffset (SpacetimeProblem::assemble, once breaks and
  // extraBubble are final; bubbleStart reads only this layout).
  void layoutBubbles() {
    bubbleStarts.clear();
    int at = bubbleOffset;
    for (int k = 0; k + 1 < blockCount(); ++k) {
      bubbleStarts.push_back(at);
      at += bubbleBlockSize(k);
    }
    bubbleValues = at - bubbleOffset;
  }
  int bubbleValues = 0;  // Hermite: how many, set by layoutBubbles
  // All of the group's values: blocks, then (Hermite) bubbles.
  int variableCount() const { return blockSize() * blockCount() + bubbleValues; }
};

// The linear map from a group's parameter blocks to its dofs' derivative of some order at a
// time: dof k of the group = sum over i of weight[i] * x[start[i] + index[i] + k], where
// x[start[i] .. start[i] + size[i]) is one parameter block.
struct GroupBasis {
  static constexpr int kCapacity = 4 + TranscriptionSpec::kMaxSamplesPerSegment - 1;  // + a flight start's extra bubble
  int count = 0;
  std::array<int, kCapacity> start{}, size{}, index{};
  std::array<double, kCapacity> weight{};
};

// A time at which a residual is imposed. Inside a free end's window it moves with the event's
// instant T: t(T) = time + rate (T - eventTime), and it stays in the root interval `interval`.
struct TimeRef {
  double time = 0;
  double rate = 0;        // dt/dT: 1 at the event itself, 0 at the window's ends
  int event = -1;         // index into SpacetimeProblem::freeEnds(); -1: a fixed time
  double eventTime = 0;   // T at which t = time
  int interval = -1;      // root interval holding it (event refs of floating characters)
  double intervalStart = 0, intervalEnd = 0;  // its ends when T = eventTime
  int side = 0;           // -1: in [left, T), +1: in (T, right], 0: at T
  Side rootSide = Side::Contacts;  // the root interval read at a breakpoint (it also chose `interval`)
  double at(double T) const { return event < 0 ? time : time + rate * (T - eventTime); }
};

// A free contact end: the lift-off instant of contacts()[contact] is variables()[offset],
// bounded to [lower, upper] inside the window [left, right] of root breakpoints around it.
// Breakpoints are shared, so every character's times in the window move with it.
struct FreeEnd {
  int contact = -1, character = -1;
  int offset = 0;
  double left = 0, right = 0, lower = 0, upper = 0;
  double current = 0;  // the instant the problem's times reflect (see syncFreeEnds)
  // Where a time t0 of the window at T = from lies at T = to, and its rate d/dT.
  double map(double t0, double from, double to) const;
  double rate(double t0, double from) const;
};

struct CharacterVariables {
  std::shared_ptr<const Model<double>> model;
  int dofs = 0;
  double weight = 1;  // m |g| (or m * 1 m/s^2 without gravity): the force scale
  int forceDims = 3;  // 2 for planar characters
  std::vector<DofGroup> groups;  // [0] actuated (B-spline), [1] unactuated (Hermite) if any
};

// Contact forces are one value per collocation sample inside the interval (linearly
// interpolated between samples): physics then holds exactly at every sample, and the friction
// cone, imposed at every sample, holds at every instant because the cone is convex.
struct ContactVariables {
  int term = -1;  // index into scene.terms
  int character = -1;
  ContactPoints points;
  double start = 0, end = 0, friction = 1;
  std::vector<double> times;  // sample times in [start, end]
  int forceDims = 3;
  int forceOffset = 0;   // sample i at sampleOffset(i)
  int anchorOffset = 0;  // 2 values (x, z) per point
  // A contact that begins after the clip's start on a floating character touches down with an
  // impact: the root's velocity jumps at `start` (its Hermite data has two breakpoints there)
  // and the points receive a ground impulse (pointForceSize() values, N s, world axes).
  int impulseOffset = -1;  // -1: no impact
  bool impact() const { return impulseOffset >= 0; }
  int freeEnd = -1;  // index into SpacetimeProblem::freeEnds() if the end is a variable
  // The points fix the floating root's pose (its body is the root body and they are not
  // collinear): the root is held constant over the contact (see layoutHeldStances).
  bool holdsRoot = false;
  // A planar contact of two points on one body is carried as its resultant: per sample
  // u = (Fx, Fy, D), the points' forces f0 = (Fx/2, Fy/2 - D), f1 = (Fx/2, Fy/2 + D). Both
  // points are on the ground, so horizontal forces of the same sum give the same wrench and
  // this split loses nothing; the per-point variables it replaces had a direction no row
  // reads (the squeeze: equal and opposite horizontal forces), which made the programs'
  // minimisers non-unique (docs/design.md, SQP). The cone is then the contact wrench cone
  // (ContactWrenchConeKernel).
  bool resultant = false;
  int pointForceSize() const { return forceDims * static_cast<int>(points.points.size()); }
  int blockSize() const { return resultant ? 3 : pointForceSize(); }
  int sampleOffset(int sample) const { return forceOffset + sample * blockSize(); }  // into the variables
  // The points' forces of one sample from its variables: f = split() u (pointForceSize x
  // blockSize), and the variables whose split has the same resultant as f: u = gather() f.
  Eigen::MatrixXd split() const;
  Eigen::MatrixXd gather() const;
  int sampleIndex(double t) const;  // -1 if t is not one of `times`
  // The sample at or before t and the weight of the next one (forces are linear between
  // samples; t is clamped to the samples' span).
  std::pair<int, double> interpolation(double t) const;
};

// What a solve produces and what warm-starts the next one.
struct SolutionState {
  std::vector<double> variables;
  std::vector<double> multipliers;
  double rho = 0;
  // The KKT factorisation at these multipliers' optimum (AugmentedLagrangianState::newtonFactors),
  // shared, never written to a file.
  std::shared_ptr<const NewtonFactors> newtonFactors;
};

class SpacetimeProblem {
 public:
  // How a planar two-point contact's forces are carried: as its resultant (ContactVariables::
  // resultant), or - the layout of states stored before that, which warm starts still read -
  // as the points' forces.
  enum class ContactLayout { Resultants, PointForces };
  // Builds the problem; on an impossible scene returns null and a reason.
  static std::unique_ptr<SpacetimeProblem> build(const Scene& scene, std::string* error,
                                                  ContactLayout layout = ContactLayout::Resultants);

  const Scene& scene() const { return scene_; }
  const Transcription& transcription() const { return transcription_; }
  const std::vector<CharacterVariables>& characters() const { return characters_; }
  const std::vector<ContactVariables>& contacts() const { return contacts_; }
  const std::vector<FreeEnd>& freeEnds() const { return freeEnds_; }
  // Whether some character has leg bubbles (DofGroup::legBubbles).
  bool hasLegBubbles() const;
  // Whether leg bubbles would add unknowns to this problem's transcription (a character standing
  // on more feet than its root meets), whether or not the scene asks for them.
  bool legBubblesWouldApply() const;
  // Moves the problem's times (root breakpoints, samples and their weights, contact ends and
  // sample times) to the free ends' current values; residuals need no update.
  void syncFreeEnds();
  ceres::Problem& ceresProblem() { return *problem_; }
  const std::vector<TermResidual*>& residuals() const { return residuals_; }
  AugmentedLagrangianState& augmentedLagrangian() { return al_; }

  std::vector<double>& variables() { return x_; }
  const std::vector<double>& variables() const { return x_; }

  // q, qd, qdd (order 0, 1, 2) of a character at time t.
  Eigen::VectorXd jointState(int character, double t, int order) const;
  // q, qd of a character just before t: differs from jointState at an impact.
  Eigen::VectorXd jointStateBefore(int character, double t, int order) const;
  // On a chosen side of t: Side::After reads the root interval that starts at t (the flight side
  // of a lift-off, where the root's acceleration jumps), Side::Contacts is jointState.
  Eigen::VectorXd jointStateOnSide(int character, double t, int order, Side side) const;
  // World force of each point of a contact at time t (zero outside its interval).
  std::vector<Eigen::Vector3d> contactForces(int contact, double t) const;
  // Sets the variables of a contact's sample to the given points' forces (a resultant: to
  // theirs, which the points then share as contactForces reports).
  void setSampleForces(int contact, int sample, const std::vector<Eigen::Vector3d>& forces);
  // Whether contact j's points leave the ground at its end: it ends before the clip does and no
  // other contact carries any of its points on. Their force is then zero at that instant.
  bool letsGo(int j) const;
  // Whether physics is imposed on character c at sample s: at every collocation node and the
  // clip's ends; at a contact edge only for the contact's own character; at a stance sample
  // (Sample::stance) only inside the contacts that hold c's root.
  bool physicsAt(int c, const Sample& s) const;
  // The contacts of the same character that touch down with an impact at the same instant as
  // contact j (j included, in contact order): they share one velocity jump.
  std::vector<int> simultaneousImpacts(int j) const;
  // World impulse of each point of a contact at its touch-down (empty without an impact).
  std::vector<Eigen::Vector3d> contactImpulses(int contact) const;

  // Index of the character with this id (0 if none: ids are validated by the loader).
  int characterIndex(const std::string& id) const;
  // The contacts (indices into contacts()) of character c active at t, interval ends included;
  // with afterEnds, those ending at t left out (the flight side of a lift-off, Sample::after).
  std::vector<int> activeContacts(int character, double t, bool afterEnds = false) const;
  // Whether body `body` (a model index) of character c must be above the ground at t: the floor
  // is on, the character is not bolted to the world (a fixed root: where its base meets the
  // floor is the animator's setup, not something a motion can fix), and no contact of its own
  // holds that body there at t (the contact's anchors put its points on the ground, and a
  // resting box touches it along a face). The solver's ground clearances and the validity
  // report's ground check both ask this.
  bool mustClearGround(int character, int body, double t) const;
  // The maximal intervals of the clip in which character c touches nothing: the whole clip for
  // a character without contacts.
  std::vector<std::pair<double, double>> flightPhases(int character) const;

  // Starts from another problem's solution when the shapes differ (a finer transcription, a
  // moved contact edge, an added term): each character's motion (matched by id) is re-fitted -
  // joint splines by least squares on a dense grid, root Hermite data read off the old motion -
  // and each contact's forces, anchors and impulse (matched by term id) are resampled. What has
  // no counterpart keeps this problem's default guess; multipliers start at zero and the
  // penalty at the previous one's. Returns the number of characters matched.
  int initializeFrom(const SpacetimeProblem& previous);
  // The same from any earlier motion (motion_source.h: a sampled Animation read back from a
  // motion file); the penalty stays this problem's own.
  int initializeFrom(const MotionSource& previous);

  // Starts from `state`, a solution of the problem of `source`: exactly (restore) when this
  // problem has that layout - a resumed solve, an edit that moved a pin - and otherwise re-fitted
  // to this transcription (initializeFrom; multipliers start at zero), a state stored with the
  // points' forces too. None when neither applies (no character in common); this problem then
  // keeps its default guess.
  enum class WarmStart { None, Exact, Refitted };
  WarmStart warmStartFrom(const Scene& source, const SolutionState& state);

  // The variables with the held stances settled (settleHeldStances), so a state reads the same
  // as restoring it: a solve's steps move a stance's pose block, not the held copies no term
  // reads, which would otherwise lag behind by the pose's last step (up to 6.3e-9 measured).
  SolutionState state() const;
  // Restores a state of the same problem shape; false if the shapes differ.
  bool restore(const SolutionState& s);

 private:
  explicit SpacetimeProblem(const Scene& scene);
  bool assemble(std::string* error);
  ContactLayout contactLayout_ = ContactLayout::Resultants;
  void initialGuess();
  void addResidual(std::shared_ptr<const Kernel> kernel, const InputMap& inputs);
  // A residual whose inputs `fill` builds at the event time T of free end `event`: built once
  // when event < 0, rebuilt at every evaluation otherwise.
  using Fill = std::function<void(InputMap&, double T)>;
  void addResidualAt(std::shared_ptr<const Kernel> kernel, int event, const Fill& fill);
  // Every body's geometry above the ground outside its contacts (SolverSpec::bodiesAboveGround).
  void addGroundClearances();
  void addJointSpeedLimits();
  // Leg bubbles (leg_bubbles.cpp, see DofGroup): appends each character's leg-bubble groups,
  // laid out from *size on, when the scene asks for them.
  void layoutLegBubbles(int* size);
  // Character c's legs that get bubbles (their dofs) and each one's bubble count per root interval.
  std::map<std::vector<int>, std::vector<int>> legBubbleCounts(int c) const;
  // The time reference of t for character c (see TimeRef): moving inside a free end's window.
  // The root interval is the one `side` picks at a breakpoint (Side::After: a flight's first
  // instant reads the interval that starts there).
  TimeRef timeRef(int character, double t, Side side = Side::Contacts) const;
  // Input map helpers: append z rows for a character's q^(order)(t), a contact's forces at t,
  // the anchors.
  void addMotionInputs(InputMap& in, int character, double t, int order, Side side = Side::Contacts);
  void addMotionInputs(InputMap& in, int character, const TimeRef& r, double T, int order);
  void addForceInputs(InputMap& in, int contact, double t, double scale = 1.0);
  // Forces at a contact's sample i, or between samples i and i + 1 with weight a on the next
  // (fixed when the sample moves: forces are per-sample variables).
  void addForceInputs(InputMap& in, int contact, std::pair<int, double> at, double scale = 1.0);
  // Objective rows of a moving sample scale with the square root of its interval's length.
  void setQuadratureScale(InputMap& in, const TimeRef& r, double T) const;
  void addAnchorInputs(InputMap& in, int contact);
  // z rows equal to (scale times) the variables x[offset .. offset + size).
  void addBlockInputs(InputMap& in, int offset, int size, double scale = 1.0);
  // The basis of a group at t, on the root interval `side` picks (see Side).
  GroupBasis groupBasis(int character, const DofGroup& g, double t, int order,
                        Side side = Side::Contacts) const;
  // A leg-bubble group's basis on its interval k at t (empty where it has no bubbles).
  GroupBasis legBubbleBasis(const DofGroup& g, int k, double t, int order) const;
  // The root interval holding t (the rule of groupBasis).
  int hermiteInterval(int character, const DofGroup& g, double t, Side side) const;
  // The basis of a Hermite group's interval k = [a, b] at t, and in `slope` its derivative in
  // the event time T given dt/dT, da/dT and db/dT.
  GroupBasis hermiteBasis(const DofGroup& g, int k, double a, double b, double t, int order,
                          double rate, double da, double db, GroupBasis* slope) const;
  // The basis of a group at a (possibly moving) time with the event at T, and its slope in T.
  GroupBasis groupBasisAt(int character, const DofGroup& g, const TimeRef& r, double T,
                          int order, GroupBasis* slope) const;
  // The character's root (Hermite) group, or null.
  const DofGroup* rootGroup(int character) const;
  // Held stances (held_stances.cpp). A contact whose points fix the floating root's pose holds
  // the root still by construction: over the contact the root's Hermite breakpoints share one
  // pose (the first one's positions), their velocities are zero and the intervals' bubbles
  // vanish, so the root's acceleration is exactly zero between samples too and one anchor row
  // set per contact ties the pose to the ground. Otherwise anchors imposed only at samples on a
  // root polynomial of degree s + 1 let a violation of ~1e-5 m buy a large root acceleration at
  // a sample, and the augmented Lagrangian stalls on the anchor before lift-off.
  void layoutHeldStances();
  // Whether contact points on this character fix its floating root (held_stances.cpp).
  bool fixesRoot(int character, const ContactPoints& points) const;
  // Whether a held stance keeps the character's root still at t (from its touch-down's after
  // side to its lift-off): rows saying the root is at rest there hold by construction, with a
  // zero Jacobian, and are left out (a KKT system cannot have them).
  bool rootHeldAt(int character, double t) const;
  // Moves held breakpoints' data in `x` (this problem's layout) to their stance's pose
  // (velocities and bubbles zero), so the variables read the same through any path.
  void settleHeldStances(std::vector<double>* x) const;
  // The velocities of each stance's pose block stay constant (zero) in the Ceres problem.
  void fixHeldVelocities();
  // Redirects a Hermite basis on interval k to the stances' poses.
  void applyHeldStances(const DofGroup& g, int k, GroupBasis* gb, GroupBasis* slope) const;
  // Lays out the free ends' variables from *size on (after the contacts).
  bool addFreeEnds(std::string* error, int* size);
  // An error if a term's instant t lies strictly inside a free end's window (other than at the
  // free end itself).
  bool checkOutsideWindows(double t, const std::string& label, std::string* error) const;
  void addImpactTerms(int contact);
  // Sets a Hermite group's bubbles so that the group interpolates target(t) (a full joint
  // vector) at interior points of each interval, its breakpoint data already set.
  void fitBubbles(int character, const DofGroup& g, const std::function<Eigen::VectorXd(double)>& target);
  // What a sample's inputs are made of, fixed when the problem is built: its time, the active
  // contacts and where their forces are read.
  struct SampleInputs {
    int character = 0;
    TimeRef ref;
    std::vector<int> active;
    std::vector<std::pair<int, double>> forces;
  };
  SampleInputs sampleInputs(int character, double t, bool after = false) const;
  void addSampleInputs(InputMap& in, const SampleInputs& s, double T);
  // A formula of character c compiled for the given active contacts (cached); null and an
  // error on a bad formula.
  std::shared_ptr<const expr::Tape> formulaTape(int character, const std::vector<int>& active,
                                                const std::string& expression, std::string* error);
  bool addFormulaTerms(std::string* error);
  bool checkFormulasFinite(std::string* error) const;  // after the initial guess

  Scene scene_;
  Transcription transcription_;
  std::vector<CharacterVariables> characters_;
  std::vector<ContactVariables> contacts_;
  std::vector<FreeEnd> freeEnds_;
  std::vector<double> x_;
  std::unique_ptr<ceres::Problem> problem_;
  std::vector<TermResidual*> residuals_;
  AugmentedLagrangianState al_;
  std::map<std::string, std::shared_ptr<const expr::Tape>> formulaTapes_;
};

}  // namespace spacetime
