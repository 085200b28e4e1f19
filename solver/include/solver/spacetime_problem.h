// The spacetime transcription of a Scene (Witkin & Kass 1988, with Cohen's 1992 B-spline
// degrees of freedom): variables, terms and the Ceres problem that holds them.
//
// Variables: for each character, the control points of one uniform cubic B-spline per degree
// of freedom (one parameter block per knot index and dof group); for each contact, the points'
// ground forces at every sample of the contact interval and the points' ground anchors (x, z). Terms: at every collocation sample, inverse dynamics (the unactuated
// generalized forces must vanish - physics - and the actuated ones enter the objective), a small
// smoothness integrand and joint limits; pins, keyframes, rests, contacts (anchored points,
// forces in the friction cone, forces vanishing where contact begins or ends mid-clip) and
// clearances at their times.
#pragma once

#include <ceres/problem.h>

#include <memory>
#include <string>
#include <vector>

#include "core/scene.h"
#include "dynamics/model.h"
#include "solver/term_residual.h"
#include "solver/transcription.h"

namespace spacetime {

// Degrees of freedom are split into spline groups. Actuated dofs share one coarse spline (the
// scene's control-point rate) over the whole clip. Unactuated dofs (the floating root) get a
// finer spline (samplesPerSegment times the rate) and one spline per contact phase, joined by
// continuity of position and velocity only:
// - physics imposes the unactuated equations at every sample; with one shared spline those
//   would outnumber the unknowns (3 equations x 3 samples against 6 control points per segment
//   for a planar lamp) and no motion could satisfy them. In flight the root's motion follows
//   from the joints through momentum, so it gets the resolution;
// - when a foot leaves or meets the ground the contact force jumps and so does the root's
//   acceleration; a C2 spline across the instant would force both to vanish there.
struct DofGroup {
  UniformBSpline spline;
  std::vector<int> dofs;  // dof indices in this group
  int offset = 0;         // control point k of this group at offset + k * dofs.size()
  double start = 0, end = 0;
};

struct CharacterVariables {
  std::shared_ptr<const Model<double>> model;
  int dofs = 0;
  double weight = 1;  // m |g| (or m * 1 m/s^2 without gravity): the force scale
  int forceDims = 3;  // 2 for planar characters
  // [0]: actuated dofs over the clip; then the unactuated dofs' phases in time order.
  std::vector<DofGroup> groups;
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
  int forceOffset = 0;   // sample i at + i * blockSize()
  int anchorOffset = 0;  // 2 values (x, z) per point
  int blockSize() const { return forceDims * static_cast<int>(points.points.size()); }
  int sampleIndex(double t) const;  // -1 if t is not one of `times`
};

// What a solve produces and what warm-starts the next one.
struct SolutionState {
  std::vector<double> variables;
  std::vector<double> multipliers;
  double rho = 0;
};

class SpacetimeProblem {
 public:
  // Builds the problem; on an impossible scene returns null and a reason.
  static std::unique_ptr<SpacetimeProblem> build(const Scene& scene, std::string* error);

  const Scene& scene() const { return scene_; }
  const Transcription& transcription() const { return transcription_; }
  const std::vector<CharacterVariables>& characters() const { return characters_; }
  const std::vector<ContactVariables>& contacts() const { return contacts_; }
  ceres::Problem& ceresProblem() { return *problem_; }
  const std::vector<TermResidual*>& residuals() const { return residuals_; }
  AugmentedLagrangianState& augmentedLagrangian() { return al_; }

  std::vector<double>& variables() { return x_; }
  const std::vector<double>& variables() const { return x_; }

  // q, qd, qdd (order 0, 1, 2) of a character at time t.
  Eigen::VectorXd jointState(int character, double t, int order) const;
  // World force of each point of a contact at time t (zero outside its interval).
  std::vector<Eigen::Vector3d> contactForces(int contact, double t) const;

  SolutionState state() const { return {x_, al_.lambda, al_.rho}; }
  // Restores a state of the same problem shape; false if the shapes differ.
  bool restore(const SolutionState& s);

 private:
  explicit SpacetimeProblem(const Scene& scene);
  bool assemble(std::string* error);
  void initialGuess();
  void addResidual(std::shared_ptr<const Kernel> kernel, const InputMap& inputs);
  // Input map helpers: append z rows for a character's q^(order)(t), a contact's forces at t,
  // the anchors.
  void addMotionInputs(InputMap& in, int character, double t, int order);
  void addForceInputs(InputMap& in, int contact, double t, double scale = 1.0);
  void addAnchorInputs(InputMap& in, int contact);
  // The spline groups that describe a character at time t: the actuated group and the phase of
  // the unactuated dofs (at a phase boundary, the phase whose contacts are those active at t).
  std::vector<const DofGroup*> groupsAt(int character, double t) const;
  std::vector<bool> activeContacts(int character, double t) const;
  void addGroupInputs(InputMap& in, int character, const DofGroup& g, double t, int order,
                      double scale);

  Scene scene_;
  Transcription transcription_;
  std::vector<CharacterVariables> characters_;
  std::vector<ContactVariables> contacts_;
  std::vector<double> x_;
  std::unique_ptr<ceres::Problem> problem_;
  std::vector<TermResidual*> residuals_;
  AugmentedLagrangianState al_;
};

}  // namespace spacetime
