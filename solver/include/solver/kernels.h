// Term kernels: the per-sample functions a spacetime problem is made of.
//
// A kernel maps a small input vector z (a sample's joint positions, velocities, accelerations,
// contact forces, anchors - whatever it declares) to a few rows, each tagged as part of the
// objective (a least-squares residual), an equality (= 0) or an inequality (<= 0). Kernels are
// templates on the scalar; derivatives come from Jets through the templated dynamics, seeded on
// z in chunks of kJetWidth. The map from the optimisation variables (spline control points) to
// z is linear and lives in TermResidual, so kernels never see splines.
#pragma once

#include <ceres/jet.h>

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "core/expr/tape.h"
#include "core/shape_mesh.h"
#include "dynamics/contact_points.h"
#include "dynamics/model.h"

namespace spacetime {

inline constexpr int kJetWidth = 12;
using JetChunk = ceres::Jet<double, kJetWidth>;

enum class RowKind : unsigned char { Objective, Equality, Inequality };

// How far a row of that kind is from holding: |c| for an equality, max(0, g) for an inequality
// g <= 0, 0 for an objective row.
inline double rowViolation(RowKind kind, double row) {
  switch (kind) {
    case RowKind::Objective: return 0;
    case RowKind::Equality: return row < 0 ? -row : row;
    case RowKind::Inequality: return row > 0 ? row : 0.0;
  }
  return 0;
}

class Kernel {
 public:
  virtual ~Kernel() = default;
  int inputSize() const { return inputs_; }
  int rowCount() const { return static_cast<int>(kinds_.size()); }
  const std::vector<RowKind>& rowKinds() const { return kinds_; }
  bool allInequalities() const {
    return !kinds_.empty() && std::all_of(kinds_.begin(), kinds_.end(), [](RowKind k) { return k == RowKind::Inequality; });
  }
  const std::string& label() const { return label_; }

  virtual void evaluate(const double* z, double* rows) const = 0;
  virtual void evaluate(const JetChunk* z, JetChunk* rows) const = 0;
  // Rows and their row-major Jacobian (rowCount x inputSize) with respect to z. The default
  // seeds Jets on every input; kernels with linear structure override it.
  virtual void evaluateWithJacobian(const double* z, double* rows, double* jacobian) const;
  // The same rows and Jacobian as the raw rows' evaluator reads them (the Newton-type steps:
  // solver/src/raw_rows.h): evaluateWithJacobian's, or where a kernel has a cheaper form equal
  // to rounding, that. Ceres's evaluations (the augmented Lagrangian's Levenberg-Marquardt)
  // keep evaluateWithJacobian's: their path flips with the last bit (the 3D lamp's from 360 to
  // 720 iterations with the kinematic kernels' form below; docs/design.md).
  virtual void rawJacobian(const double* z, double* rows, double* jacobian) const { evaluateWithJacobian(z, rows, jacobian); }
  // How many leading inputs the rows are nonlinear in; the rest enter linearly (the forces,
  // anchors and accelerations of most kernels), so second derivatives among them vanish.
  virtual int nonlinearInputs() const { return inputs_; }
  // The Hessian of sum_r w[r] rows_r(z) (inputSize x inputSize, row-major, symmetric): forward
  // differences of the exact Jacobian in the nonlinear inputs, step 1e-7 (1 + |z_i|). The
  // Newton polish's Lagrangian Hessian (newton_polish.h) is built from these.
  virtual void weightedHessian(const double* z, const double* w, double* hessian) const;

 protected:
  int inputs_ = 0;
  std::vector<RowKind> kinds_;
  std::string label_;
};

#define SPACETIME_KERNEL_EVALUATORS                                       \
  void evaluate(const double* z, double* rows) const override;          \
  void evaluate(const JetChunk* z, JetChunk* rows) const override;      \
  template <class T>                                                    \
  void compute(const T* z, T* rows) const;

// Inverse dynamics at a sample. z = [q, qd, qdd, f_1 .. f_m] (each contact's points' forces,
// forceDims components each: x, y or x, y, z in world axes). The generalized forces come from
// the RNEA compiled to a tape (compiled_dynamics.h), shared by every sample with the same
// contacts: with Jets it is ~4x faster than the native RNEA. Rows: the unactuated generalized
// forces divided by the character's weight (equalities: physics); sqrt(w_effort * dt) tau for
// actuated dofs (objective); sqrt(w_power * dt) tau qd (objective); torque limits (inequalities).
class DynamicsKernel : public Kernel {
 public:
  struct Options {
    bool physics = true;
    double effortWeight = 0;  // already multiplied by the quadrature weight
    double powerWeight = 0;
    bool torqueLimits = true;
    double weightScale = 1;   // 1 / (m g): unactuated rows become fractions of the weight
  };
  DynamicsKernel(std::shared_ptr<const Model<double>> model, std::vector<ContactPoints> contacts,
                 int forceDims, const Options& options, std::string label);
  SPACETIME_KERNEL_EVALUATORS
  // tau is linear in qdd and the contact forces (tau = M qdd + h(q, qd) - J^T f), so Jets are
  // seeded on (q, qd) only (through the compiled tape); d tau / d qdd is the CRBA mass matrix and
  // d tau / d f_k = -J^T e_k one backward pass along the force's chain (addPointForceGeneralized).
  void evaluateWithJacobian(const double* z, double* rows, double* jacobian) const override;
  int nonlinearInputs() const override { return 2 * model_->dofCount(); }  // q, qd
  // Exact, by forward-over-reverse on the compiled weighted sum sum_d a_d tau_d (one reverse
  // pass on 12-wide Jets instead of 13 Jacobians); power rows fall back to the differences.
  void weightedHessian(const double* z, const double* w, double* hessian) const override;

 private:
  template <class T>
  VecX<T> generalizedForces(const T* z) const;
  // Row r's value from the generalized forces and qd; its slope in tau[dof of r].
  template <class T>
  T rowValue(size_t r, const VecX<T>& tau, const T* qd) const;
  double rowSlope(size_t r, const double* qd) const;
  enum class Row { Physics, Effort, Power, TorqueUpper, TorqueLower };
  std::shared_ptr<const Model<double>> model_;
  std::shared_ptr<const expr::Tape> tau_;  // compiled RNEA (compiled_dynamics.h), shared
  std::shared_ptr<const expr::Tape> weightedTau_;  // sum_d a_d tau_d, for reverse mode
  std::vector<ContactPoints> contacts_;
  int forceDims_;
  Options options_;
  std::vector<std::pair<Row, int>> rows_;  // kind and dof
};

// sqrt(weight) * z: a smoothness integrand (z = a derivative of q) or any quadratic penalty.
class WeightedValueKernel : public Kernel {
 public:
  WeightedValueKernel(int size, double weight, std::string label);
  SPACETIME_KERNEL_EVALUATORS
  int nonlinearInputs() const override { return 0; }  // linear rows

 private:
  double sqrtWeight_;
};

// z_i - target_i = 0 for chosen entries (keyframes: z = q; joint-space rest: z = qd).
class TargetKernel : public Kernel {
 public:
  TargetKernel(int size, std::vector<std::pair<int, double>> targets, std::string label);
  SPACETIME_KERNEL_EVALUATORS
  int nonlinearInputs() const override { return 0; }  // linear rows

 private:
  std::vector<std::pair<int, double>> targets_;
};

// A body's spatial velocity is zero. z = [q, qd]; six rows.
class BodyRestKernel : public Kernel {
 public:
  BodyRestKernel(std::shared_ptr<const Model<double>> model, int body, std::string label);
  SPACETIME_KERNEL_EVALUATORS
  int nonlinearInputs() const override { return model_->dofCount(); }  // v = J(q) qd: q only

 private:
  std::shared_ptr<const Model<double>> model_;
  int body_;
};

// A body point's world coordinates on chosen axes equal a target. z = q.
class PinKernel : public Kernel {
 public:
  PinKernel(std::shared_ptr<const Model<double>> model, int body, const Eigen::Vector3d& point,
            const Eigen::Vector3d& target, std::array<bool, 3> axes, std::string label);
  SPACETIME_KERNEL_EVALUATORS
  // Through the body's spatial Jacobian (bodyPoseAndJacobian) in doubles, as
  // GroundClearanceKernel, instead of Jets along the chain.
  void rawJacobian(const double* z, double* rows, double* jacobian) const override;

 private:
  std::shared_ptr<const Model<double>> model_;
  int body_;
  Eigen::Vector3d point_, target_;
  std::vector<int> axes_;
};

// Contact points stay at their ground anchors. z = [q, anchors (x, z per point)]; rows: each
// point's x and z at its anchor, then the heights of the points that decide every point's height
// (heightPoints) at the ground: a flat sole of four points has three such rows, not four.
class ContactAnchorKernel : public Kernel {
 public:
  ContactAnchorKernel(std::shared_ptr<const Model<double>> model, const ContactPoints& contact,
                      int forceDims, double groundHeight, std::string label);
  SPACETIME_KERNEL_EVALUATORS
  // Through the body's spatial Jacobian (bodyPoseAndJacobian) in doubles, as
  // GroundClearanceKernel, instead of Jets along the chain.
  void rawJacobian(const double* z, double* rows, double* jacobian) const override;
  int nonlinearInputs() const override { return model_->dofCount(); }  // q, not anchors

 private:
  std::shared_ptr<const Model<double>> model_;
  ContactPoints contact_;
  std::vector<int> heightPoints_;
  double ground_;
};

// The rows that keep a contact's points still - at rest (order 1) or without acceleration
// (order 2): the first point's world velocity or acceleration (forceDims rows), then the contact's
// reach (contactReach) times the body's angular velocity or acceleration along each of its turns
// (contactTurns, body frame), in the same units. They vanish exactly when every point is still,
// with one row per independent motion: the points' own rows would be redundant (a four-point sole:
// 12 rows of rank 6, which stalled the 3D humanoid; two points in the plane: 4 of rank 3).
class ContactStillRows {
 public:
  ContactStillRows(ContactPoints contact, int forceDims);
  int count() const { return forceDims_ + static_cast<int>(turns_.size()); }
  int body() const { return contact_.body; }  // the body whose motion write() reads
  // Writes count() rows from kinematics already run to `order`; returns the next row.
  template <class T>
  T* write(const Data<T>& data, int order, T* rows) const;

 private:
  ContactPoints contact_;
  int forceDims_;
  double reach_ = 0;
  std::vector<Eigen::Vector3d> turns_;
};

// Contact points are at rest (order 1: their world velocity is zero) or do not accelerate
// (order 2: their world acceleration is zero, RBDA eq. 2.42 via pointAcceleration). z = [q, qd]
// or [q, qd, qdd]; ContactStillRows. Keeps the points of a contact that does not hold the root
// still between its anchor and its lift-off (SpacetimeProblem).
class ContactPointMotionKernel : public Kernel {
 public:
  ContactPointMotionKernel(std::shared_ptr<const Model<double>> model, const ContactPoints& contact,
                           int forceDims, int order, std::string label);
  SPACETIME_KERNEL_EVALUATORS
  // Velocity J(q) qd is linear in qd; acceleration J(q) qdd + Jdot(q, qd) qd linear in qdd.
  int nonlinearInputs() const override { return order_ * model_->dofCount(); }

 private:
  std::shared_ptr<const Model<double>> model_;
  ContactStillRows still_;
  int order_;
};

// The contact forces of one sample lie in the friction cone (the ground only pushes). Forces
// are linear between samples and the cone is convex, so they then lie in the cone at every
// instant, not only at samples. Planar: the exact cone |fx| <= mu fy; 3D: the inscribed
// pyramid |fx|, |fz| <= mu / sqrt(2) fy. z = the sample's forces (forceDims per point); rows
// scaled by 1 / (m g).
class FrictionConeKernel : public Kernel {
 public:
  FrictionConeKernel(int points, int forceDims, double mu, double weightScale, std::string label);
  SPACETIME_KERNEL_EVALUATORS
  int nonlinearInputs() const override { return 0; }  // linear rows

 private:
  int points_, dims_;
  double mu_, scale_;
};

// The contact wrench cone of a planar contact of two points on one body (Caron, Pham and
// Nakamura 2015, "Stability of surface contacts for humanoid robots", in the plane): the
// resultant (F_x, F_y, M) of forces in the points' cones is exactly the set with
// |F_x| <= mu F_y and |M| <= a F_y (the points at +-a on the ground), the latter being both
// points' normal forces >= 0. z = the two points' forces (any split of the resultant); rows
// -f0y, -f1y, +-(f0x + f1x) - mu (f0y + f1y), scaled by 1 / (m g).
class ContactWrenchConeKernel : public Kernel {
 public:
  ContactWrenchConeKernel(double mu, double weightScale, std::string label);
  SPACETIME_KERNEL_EVALUATORS
  int nonlinearInputs() const override { return 0; }  // linear rows

 private:
  double mu_, scale_;
};

// Contacts that begin in flight: a rigid impact at the touch-down instant (Featherstone RBDA
// section 11.6; Witkin & Kass' spacetime with an instantaneous collision). Velocities jump, the
// configuration does not: M(q) (qd+ - qd-) = sum_c J_c(q)^T L_c, with L_c the ground impulses of
// the points of every contact of the character touching down at that instant (two feet landing
// together share one velocity jump), and those points are at rest just after.
// z = [q-, q+, qd-, qd+, L_1, ..., L_k] (L_c: forceDims per point, world axes). Rows: q+ - q- for the unactuated dofs (equalities: the root does not
// teleport); the unactuated rows of M (qd+ - qd-) - J^T L times impulseScale (equalities: the
// impulse alone stops the root); the actuated rows - the impulsive joint torques that keep the
// joints' velocities continuous (the joints' splines are C2) - times sqrt(torqueWeight)
// (objective); each contact's points at rest after the jump (equalities, ContactStillRows),
// except those of a contact that holds the root still (`held`: a held stance starts at rest).
class ImpactKernel : public Kernel {
 public:
  ImpactKernel(std::shared_ptr<const Model<double>> model, std::vector<ContactPoints> contacts,
               const std::vector<char>& held, int forceDims, double impulseScale, double torqueWeight,
               std::string label);
  SPACETIME_KERNEL_EVALUATORS
  // q- and q+: the velocities enter linearly (M(q-) (qd+ - qd-), J(q+) qd+), so do impulses.
  int nonlinearInputs() const override { return 2 * model_->dofCount(); }
  // The rows' parts: root continuity, root impulse balance, impulsive joint torques, and the
  // contact points' velocity after the impact.
  enum class Part { Continuity, Balance, JointImpulse, PostVelocity };
  Part part(int row) const { return parts_[row]; }

 private:
  std::shared_ptr<const Model<double>> model_;
  std::vector<ContactPoints> contacts_;
  std::vector<ContactStillRows> still_;
  int forceDims_;
  double impulseScale_, sqrtTorqueWeight_;
  std::vector<int> unactuated_, actuated_;
  std::vector<Part> parts_;
};

// A body point stays at or above a height (height - p_y <= 0), or outside an axis-aligned box:
// -max(p - boxMax, boxMin - p) <= 0, i.e. beyond at least one face (the active face's row is
// differentiated; the set outside a box is not convex, so this is a local condition). z = q.
class ClearanceKernel : public Kernel {
 public:
  ClearanceKernel(std::shared_ptr<const Model<double>> model, int body,
                  const Eigen::Vector3d& point, double height, std::string label);
  ClearanceKernel(std::shared_ptr<const Model<double>> model, int body,
                  const Eigen::Vector3d& point, const Eigen::Vector3d& boxMin,
                  const Eigen::Vector3d& boxMax, std::string label);
  SPACETIME_KERNEL_EVALUATORS
  // Through the body's spatial Jacobian (bodyPoseAndJacobian) in doubles, as
  // GroundClearanceKernel, instead of Jets along the chain.
  void rawJacobian(const double* z, double* rows, double* jacobian) const override;

 private:
  // The row at the point's world position p, and the coordinate it follows: the row is
  // sign * p[axis] plus a constant (height - p_y, or the face whose distance is first the largest).
  template <class T>
  T row(const Vec3<T>& p, int* axis, double* sign) const;
  std::shared_ptr<const Model<double>> model_;
  int body_;
  Eigen::Vector3d point_;
  double height_ = 0;
  bool box_ = false;
  Eigen::Vector3d boxMin_, boxMax_;
};

// A body's geometry stays above the ground: one row per place its lowest point can be
// (core/shape_mesh.h, LowestPointFeature): ground - lowest <= 0. A disc's rim term
// r sqrt(1 - n_y^2) is smoothed to r sqrt(1 - n_y^2 + eps^2), eps = 1e-3, which keeps the row
// differentiable when the disc lies flat and errs on the safe side by at most r eps. z = q.
class GroundClearanceKernel : public Kernel {
 public:
  GroundClearanceKernel(std::shared_ptr<const Model<double>> model, int body,
                        std::vector<LowestPointFeature> features, double groundHeight, std::string label);
  SPACETIME_KERNEL_EVALUATORS
  // Each row's slope in the body's pose (a small world rotation w and move of its origin),
  // chained through the body's spatial Jacobian (bodyPoseAndJacobian), in doubles: Jets carried
  // along the chain were a fifth of a warm edit's evaluations on the jump.
  void rawJacobian(const double* z, double* rows, double* jacobian) const override;

 private:
  static constexpr double kDiscSmoothing = 1e-3;  // eps above
  std::shared_ptr<const Model<double>> model_;
  int body_;
  std::vector<LowestPointFeature> features_;
  double ground_;
};

// Joint position limits: q - upper <= 0 and lower - q <= 0 for limited dofs. z = q.
class JointLimitKernel : public Kernel {
 public:
  JointLimitKernel(std::shared_ptr<const Model<double>> model, std::string label);
  SPACETIME_KERNEL_EVALUATORS
  int nonlinearInputs() const override { return 0; }  // linear rows

 private:
  std::shared_ptr<const Model<double>> model_;
  std::vector<int> dofs_;
};

// Joint speed limits: qd - limit <= 0 and -qd - limit <= 0 for every dof whose joint has a
// speed limit (Body::hasSpeedLimit). z = qd.
class JointSpeedLimitKernel : public Kernel {
 public:
  JointSpeedLimitKernel(std::shared_ptr<const Model<double>> model, std::string label);
  SPACETIME_KERNEL_EVALUATORS
  int nonlinearInputs() const override { return 0; }  // linear rows

 private:
  std::shared_ptr<const Model<double>> model_;
  std::vector<int> dofs_;
};

// A user formula compiled to a tape, at one time: scale * (f(z, t) - offset). Its inputs are
// the dynamics kernel's (q, qd, qdd, then the active contacts' forces).
class FormulaKernel : public Kernel {
 public:
  // `source` names the formula in messages: "term 'id': formula \"...\"".
  FormulaKernel(std::shared_ptr<const expr::Tape> tape, int inputs, double time, RowKind kind,
                double scale, double offset, std::string label, std::string source);
  SPACETIME_KERNEL_EVALUATORS
  const expr::Tape& tape() const { return *tape_; }
  double time() const { return time_; }
  const std::string& source() const { return source_; }

 private:
  std::shared_ptr<const expr::Tape> tape_;
  double time_, scale_, offset_;
  std::string source_;
};

}  // namespace spacetime
