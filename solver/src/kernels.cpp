// Kernel implementations. This translation unit instantiates the dynamics for JetChunk; keep
// the other Jet-heavy code out of it and it out of headers so builds stay fast.
#include "solver/kernels.h"

#include <algorithm>
#include <cmath>
#include <mutex>

#include "dynamics/algorithms.h"
#include "dynamics/compiled_dynamics.h"

namespace spacetime {

namespace {
// Jets of z with unit directions seeded on inputs [start, end) (forward mode, one chunk).
void seedChunk(const double* z, int n, int start, int end, JetChunk* zj) {
  for (int i = 0; i < n; ++i) {
    zj[i] = JetChunk(z[i]);
    if (i >= start && i < end) zj[i].v[i - start] = 1.0;
  }
}
// This thread's reusable Data for one scalar type, sized for the model. Kernels run on Ceres's
// worker threads for every sample of every iteration, and allocating Data's vectors on each call
// was ~8 % of a Jacobian evaluation (perf, luxo_jump). A kernel may use it for one computation
// at a time (sequential reuse within a call is fine).
template <class T>
Data<T>& scratchData(const Model<double>& model) {
  thread_local Data<T> data;
  data.resize(model);
  return data;
}
// The compiled inverse dynamics of a model with a set of active contacts, built once and shared
// by every sample with that set (a problem has a few such sets and hundreds of samples). The
// model is held weakly: an entry whose model is gone is stale even if another model later
// lives at the same address.
// `weighted`: compileWeightedInverseDynamics (the Hessians) instead of compileInverseDynamics.
std::shared_ptr<const expr::Tape> inverseDynamicsTape(const std::shared_ptr<const Model<double>>& model,
                                                      const std::vector<ContactPoints>& contacts,
                                                      int forceDims, bool weighted = false) {
  struct Entry {
    std::weak_ptr<const Model<double>> model;
    std::vector<ContactPoints> contacts;
    int forceDims;
    bool weighted;
    std::shared_ptr<const expr::Tape> tape;
  };
  static std::mutex mutex;
  static std::vector<Entry> cache;
  auto same = [&](const std::vector<ContactPoints>& a) {
    if (a.size() != contacts.size()) return false;
    for (size_t i = 0; i < a.size(); ++i)
      if (a[i].body != contacts[i].body || a[i].points != contacts[i].points) return false;
    return true;
  };
  std::lock_guard<std::mutex> lock(mutex);
  std::erase_if(cache, [](const Entry& e) { return e.model.expired(); });
  for (const Entry& e : cache)
    if (e.model.lock() == model && e.forceDims == forceDims && e.weighted == weighted && same(e.contacts))
      return e.tape;
  auto tape = std::make_shared<const expr::Tape>(
      weighted ? compileWeightedInverseDynamics(*model, contacts, forceDims)
               : compileInverseDynamics(*model, contacts, forceDims));
  cache.push_back({model, contacts, forceDims, weighted, tape});
  return tape;
}
// One body's pose and spatial Jacobian at q (bodyPoseAndJacobian): its points' world positions
// and their slopes in q, dp/dq_d = v_d + w_d x p (the body's motion per unit speed of dof d), in
// doubles - the kinematic kernels' Jacobians without Jets along the chain.
// One at a time per thread: the columns live in the thread's work space.
struct BodySlopes {
  Transform<double> X;
  const std::vector<Motion<double>>* columns;
  BodySlopes(const Model<double>& model, const double* q, int body) {
    thread_local std::vector<Motion<double>> work;
    X = bodyPoseAndJacobian(model, q, body, &work);
    columns = &work;
  }
  Eigen::Vector3d position(const Eigen::Vector3d& local) const { return pointPosition(X, local); }
  const Motion<double>& motion(int dof) const { return (*columns)[static_cast<size_t>(dof)]; }
  Eigen::Vector3d slope(int dof, const Eigen::Vector3d& world) const {
    const Motion<double>& m = motion(dof);
    return m.lin + m.ang.cross(world);
  }
};
}  // namespace

void Kernel::weightedHessian(const double* z, const double* w, double* hessian) const {
  const int n = inputs_, m = rowCount(), k = nonlinearInputs();
  std::fill(hessian, hessian + n * n, 0.0);
  if (k == 0) return;
  std::vector<double> rows(m), J0(m * n), J1(m * n), zp(z, z + n);
  evaluateWithJacobian(z, rows.data(), J0.data());
  for (int i = 0; i < k; ++i) {
    const double h = 1e-7 * (1 + std::abs(z[i]));
    zp[i] = z[i] + h;
    evaluateWithJacobian(zp.data(), rows.data(), J1.data());
    zp[i] = z[i];
    // Column i: d/dz_i of the gradient sum_r w_r d rows_r / dz_j. Within the nonlinear block
    // both (i, j) and (j, i) are measured; their mean is the symmetric part.
    for (int j = 0; j < n; ++j) {
      double d = 0;
      for (int r = 0; r < m; ++r) d += w[r] * (J1[r * n + j] - J0[r * n + j]);
      d /= h;
      if (j < k) {
        hessian[i * n + j] += 0.5 * d;
        hessian[j * n + i] += 0.5 * d;
      } else {
        hessian[i * n + j] = d;
        hessian[j * n + i] = d;
      }
    }
  }
}

void Kernel::evaluateWithJacobian(const double* z, double* rows, double* jacobian) const {
  const int n = inputs_, m = rowCount();
  std::vector<JetChunk> zj(n), out(m);
  if (n == 0) {
    evaluate(z, rows);
    return;
  }
  // Forward mode in chunks of kJetWidth seeded directions.
  for (int start = 0; start < n; start += kJetWidth) {
    seedChunk(z, n, start, std::min(start + kJetWidth, n), zj.data());
    evaluate(zj.data(), out.data());
    const int width = std::min(kJetWidth, n - start);
    for (int r = 0; r < m; ++r) {
      if (start == 0) rows[r] = out[r].a;
      for (int k = 0; k < width; ++k) jacobian[r * n + start + k] = out[r].v[k];
    }
  }
}

#define SPACETIME_DEFINE_EVALUATORS(K)                                                   \
  void K::evaluate(const double* z, double* rows) const { compute(z, rows); }            \
  void K::evaluate(const JetChunk* z, JetChunk* rows) const { compute(z, rows); }

// --- DynamicsKernel ----------------------------------------------------------------------

DynamicsKernel::DynamicsKernel(std::shared_ptr<const Model<double>> model,
                               std::vector<ContactPoints> contacts, int forceDims,
                               const Options& options, std::string label)
    : model_(std::move(model)), contacts_(std::move(contacts)), forceDims_(forceDims),
      options_(options) {
  label_ = std::move(label);
  tau_ = inverseDynamicsTape(model_, contacts_, forceDims_);
  weightedTau_ = inverseDynamicsTape(model_, contacts_, forceDims_, /*weighted=*/true);
  const int n = model_->dofCount();
  inputs_ = 3 * n;
  for (const auto& c : contacts_) inputs_ += forceDims_ * static_cast<int>(c.points.size());
  for (int d = 0; d < n; ++d) {
    const Body<double>& b = model_->bodies[model_->dofBody[d]];
    if (!b.actuated) {
      if (options_.physics) rows_.push_back({Row::Physics, d});
      continue;
    }
    if (options_.effortWeight > 0) rows_.push_back({Row::Effort, d});
    if (options_.powerWeight > 0) rows_.push_back({Row::Power, d});
    if (options_.torqueLimits && b.hasEffortLimit) {
      rows_.push_back({Row::TorqueUpper, d});
      rows_.push_back({Row::TorqueLower, d});
    }
  }
  for (const auto& [row, dof] : rows_)
    kinds_.push_back(row == Row::Physics                                  ? RowKind::Equality
                     : (row == Row::Effort || row == Row::Power) ? RowKind::Objective
                                                                          : RowKind::Inequality);
}

template <class T>
VecX<T> DynamicsKernel::generalizedForces(const T* z) const {
  thread_local std::vector<T> work;  // the tape's slots; tapes hold no scratch of their own
  VecX<T> tau(model_->dofCount());
  tau_->evaluate(z, T(0.0), tau.data(), work);
  return tau;
}

template <class T>
T DynamicsKernel::rowValue(size_t r, const VecX<T>& tau, const T* qd) const {
  const auto [row, d] = rows_[r];
  const double limit = model_->bodies[model_->dofBody[d]].effortLimit;
  switch (row) {
    case Row::Physics: return tau[d] * options_.weightScale;
    case Row::Effort: return tau[d] * std::sqrt(options_.effortWeight);
    case Row::Power: return tau[d] * qd[d] * std::sqrt(options_.powerWeight);
    case Row::TorqueUpper: return (tau[d] - limit) * options_.weightScale;
    case Row::TorqueLower: return (-tau[d] - limit) * options_.weightScale;
  }
  return T(0.0);
}

double DynamicsKernel::rowSlope(size_t r, const double* qd) const {
  const auto [row, d] = rows_[r];
  switch (row) {
    case Row::Physics:
    case Row::TorqueUpper: return options_.weightScale;
    case Row::TorqueLower: return -options_.weightScale;
    case Row::Effort: return std::sqrt(options_.effortWeight);
    case Row::Power: return qd[d] * std::sqrt(options_.powerWeight);
  }
  return 0;
}

template <class T>
void DynamicsKernel::compute(const T* z, T* rows) const {
  const VecX<T> tau = generalizedForces(z);
  for (size_t r = 0; r < rows_.size(); ++r) rows[r] = rowValue(r, tau, z + model_->dofCount());
}

void DynamicsKernel::evaluateWithJacobian(const double* z, double* rows, double* jacobian) const {
  const int n = model_->dofCount(), nz = inputs_;
  Eigen::MatrixXd dtau = Eigen::MatrixXd::Zero(n, nz);
  Eigen::VectorXd tau(n);
  // Forward mode over (q, qd); qdd and forces enter as constants.
  std::vector<JetChunk> zj(nz);
  for (int start = 0; start < 2 * n; start += kJetWidth) {
    seedChunk(z, nz, start, std::min(start + kJetWidth, 2 * n), zj.data());
    const VecX<JetChunk> t = generalizedForces(zj.data());
    const int width = std::min(kJetWidth, 2 * n - start);
    for (int d = 0; d < n; ++d) {
      tau[d] = t[d].a;
      for (int k = 0; k < width; ++k) dtau(d, start + k) = t[d].v[k];
    }
  }
  // d tau / d qdd = M(q) (RBDA Table 6.2).
  Data<double>& data = scratchData<double>(*model_);
  dtau.block(0, 2 * n, n, n) = crba(*model_, data, z);
  // d tau / d f_k = -J^T e_k: the unit force k alone, along its body's chain (crba left the poses
  // in data).
  int k = 3 * n;
  for (const ContactPoints& c : contacts_)
    for (const Eigen::Vector3d& p : c.points)
      for (int axis = 0; axis < forceDims_; ++axis, ++k) {
        PointForce<double> unit;
        unit.body = c.body;
        unit.pointIsLocal = true;
        unit.pointWorld = p;
        unit.forceWorld = Eigen::Vector3d::Unit(axis);
        addPointForceGeneralized(*model_, data, unit, dtau.col(k).data());
      }
  // Every row is slope * tau[d] (+ a constant), except that power also depends on qd[d].
  const double* qd = z + n;
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> J(
      jacobian, rowCount(), nz);
  for (size_t r = 0; r < rows_.size(); ++r) {
    const auto [row, d] = rows_[r];
    rows[r] = rowValue(r, tau, qd);
    J.row(r) = dtau.row(d) * rowSlope(r, qd);
    if (row == Row::Power) J(r, n + d) += tau[d] * std::sqrt(options_.powerWeight);
  }
}
void DynamicsKernel::weightedHessian(const double* z, const double* w, double* hessian) const {
  // Power rows (tau_d qd_d) are not a weighted sum of tau: differences of the Jacobian.
  if (options_.powerWeight > 0) {
    Kernel::weightedHessian(z, w, hessian);
    return;
  }
  const int n = model_->dofCount(), nz = inputs_, k = nonlinearInputs();
  // sum_r w_r rows_r = sum_d a_d tau_d + constants: every other row is slope * tau[d].
  std::vector<double> a(n, 0.0);
  for (size_t r = 0; r < rows_.size(); ++r) a[rows_[r].second] += w[r] * rowSlope(r, z + n);
  thread_local std::vector<JetChunk> vars, grad, work, adjoint;
  vars.resize(nz + n);
  grad.resize(nz);
  for (int d = 0; d < n; ++d) vars[nz + d] = JetChunk(a[d]);
  std::fill(hessian, hessian + nz * nz, 0.0);
  // Forward over reverse: the gradient of phi on Jets seeded on inputs [start, start + width)
  // carries the Hessian columns of those inputs; the linear inputs' columns follow by symmetry.
  for (int start = 0; start < k; start += kJetWidth) {
    const int width = std::min(kJetWidth, k - start);
    for (int i = 0; i < nz; ++i) {
      vars[i] = JetChunk(z[i]);
      if (i >= start && i < start + width) vars[i].v[i - start] = 1.0;
    }
    weightedTau_->gradient(vars.data(), JetChunk(0.0), 0, grad.data(), nz, work, adjoint);
    for (int j = 0; j < nz; ++j)
      for (int c = 0; c < width; ++c) {
        hessian[j * nz + start + c] = grad[j].v[c];
        if (j >= k) hessian[(start + c) * nz + j] = grad[j].v[c];
      }
  }
}
SPACETIME_DEFINE_EVALUATORS(DynamicsKernel)

// --- WeightedValueKernel -----------------------------------------------------------------

WeightedValueKernel::WeightedValueKernel(int size, double weight, std::string label)
    : sqrtWeight_(std::sqrt(weight)) {
  label_ = std::move(label);
  inputs_ = size;
  kinds_.assign(size, RowKind::Objective);
}

template <class T>
void WeightedValueKernel::compute(const T* z, T* rows) const {
  for (int i = 0; i < inputs_; ++i) rows[i] = z[i] * sqrtWeight_;
}
SPACETIME_DEFINE_EVALUATORS(WeightedValueKernel)

// --- TargetKernel ------------------------------------------------------------------------

TargetKernel::TargetKernel(int size, std::vector<std::pair<int, double>> targets, std::string label)
    : targets_(std::move(targets)) {
  label_ = std::move(label);
  inputs_ = size;
  kinds_.assign(targets_.size(), RowKind::Equality);
}

template <class T>
void TargetKernel::compute(const T* z, T* rows) const {
  for (size_t i = 0; i < targets_.size(); ++i) rows[i] = z[targets_[i].first] - targets_[i].second;
}
SPACETIME_DEFINE_EVALUATORS(TargetKernel)

// --- BodyRestKernel ----------------------------------------------------------------------

BodyRestKernel::BodyRestKernel(std::shared_ptr<const Model<double>> model, int body,
                               std::string label)
    : model_(std::move(model)), body_(body) {
  label_ = std::move(label);
  inputs_ = 2 * model_->dofCount();
  kinds_.assign(6, RowKind::Equality);
}

template <class T>
void BodyRestKernel::compute(const T* z, T* rows) const {
  Data<T>& data = scratchData<T>(*model_);
  chainKinematics(*model_, data, body_, z, z + model_->dofCount(), static_cast<const T*>(nullptr));
  const Vec6<T> v = data.v[body_].vector();
  for (int i = 0; i < 6; ++i) rows[i] = v[i];
}
SPACETIME_DEFINE_EVALUATORS(BodyRestKernel)

// --- PinKernel ---------------------------------------------------------------------------

PinKernel::PinKernel(std::shared_ptr<const Model<double>> model, int body,
                     const Eigen::Vector3d& point, const Eigen::Vector3d& target,
                     std::array<bool, 3> axes, std::string label)
    : model_(std::move(model)), body_(body), point_(point), target_(target) {
  label_ = std::move(label);
  inputs_ = model_->dofCount();
  for (int a = 0; a < 3; ++a)
    if (axes[a]) axes_.push_back(a);
  kinds_.assign(axes_.size(), RowKind::Equality);
}

template <class T>
void PinKernel::compute(const T* z, T* rows) const {
  const Vec3<T> p = pointPosition(bodyPose(*model_, z, body_), point_);
  for (size_t i = 0; i < axes_.size(); ++i) rows[i] = p[axes_[i]] - target_[axes_[i]];
}
SPACETIME_DEFINE_EVALUATORS(PinKernel)

void PinKernel::rawJacobian(const double* z, double* rows, double* jacobian) const {
  const int n = inputs_;
  const BodySlopes body(*model_, z, body_);
  const Eigen::Vector3d p = body.position(point_);
  for (size_t i = 0; i < axes_.size(); ++i) rows[i] = p[axes_[i]] - target_[axes_[i]];
  for (int d = 0; d < n; ++d) {
    const Eigen::Vector3d slope = body.slope(d, p);
    for (size_t i = 0; i < axes_.size(); ++i) jacobian[i * n + d] = slope[axes_[i]];
  }
}

// --- ContactAnchorKernel -----------------------------------------------------------------

ContactAnchorKernel::ContactAnchorKernel(std::shared_ptr<const Model<double>> model,
                                         const ContactPoints& contact, int forceDims,
                                         double groundHeight, std::string label)
    : model_(std::move(model)), contact_(contact), heightPoints_(heightPoints(contact, forceDims == 2)),
      ground_(groundHeight) {
  label_ = std::move(label);
  inputs_ = model_->dofCount() + 2 * static_cast<int>(contact_.points.size());
  kinds_.assign(2 * contact_.points.size() + heightPoints_.size(), RowKind::Equality);
}

template <class T>
void ContactAnchorKernel::compute(const T* z, T* rows) const {
  const Transform<T> X = bodyPose(*model_, z, contact_.body);
  const T* anchors = z + model_->dofCount();
  const size_t n = contact_.points.size();
  for (size_t i = 0; i < n; ++i) {
    const Vec3<T> p = pointPosition(X, contact_.points[i]);
    rows[2 * i + 0] = p.x() - anchors[2 * i];
    rows[2 * i + 1] = p.z() - anchors[2 * i + 1];
  }
  for (size_t k = 0; k < heightPoints_.size(); ++k)
    rows[2 * n + k] = pointPosition(X, contact_.points[heightPoints_[k]]).y() - ground_;
}
SPACETIME_DEFINE_EVALUATORS(ContactAnchorKernel)

void ContactAnchorKernel::rawJacobian(const double* z, double* rows, double* jacobian) const {
  const int dofs = model_->dofCount(), nz = inputs_, m = rowCount();
  const BodySlopes body(*model_, z, contact_.body);
  const double* anchors = z + dofs;
  const size_t n = contact_.points.size();
  std::fill(jacobian, jacobian + static_cast<size_t>(m) * nz, 0.0);
  // Row r is axis `axis` of point `point` (less its anchor, input `anchor`, or the ground).
  auto write = [&](int r, size_t point, int axis, int anchor) {
    const Eigen::Vector3d p = body.position(contact_.points[point]);
    rows[r] = p[axis] - (anchor >= 0 ? anchors[anchor] : ground_);
    for (int d = 0; d < dofs; ++d) jacobian[r * nz + d] = body.slope(d, p)[axis];
    if (anchor >= 0) jacobian[r * nz + dofs + anchor] = -1;
  };
  for (size_t i = 0; i < n; ++i) {
    write(static_cast<int>(2 * i), i, 0, static_cast<int>(2 * i));
    write(static_cast<int>(2 * i + 1), i, 2, static_cast<int>(2 * i + 1));
  }
  for (size_t k = 0; k < heightPoints_.size(); ++k)
    write(static_cast<int>(2 * n + k), static_cast<size_t>(heightPoints_[k]), 1, -1);
}

// --- ContactStillRows ---------------------------------------------------------------------

ContactStillRows::ContactStillRows(ContactPoints contact, int forceDims)
    : contact_(std::move(contact)), forceDims_(forceDims), reach_(contactReach(contact_)),
      turns_(contactTurns(contact_, forceDims == 2)) {}

template <class T>
T* ContactStillRows::write(const Data<T>& data, int order, T* rows) const {
  const Eigen::Vector3d& p0 = contact_.points.front();
  const Vec3<T> v = order == 2 ? pointAcceleration(data, contact_.body, p0) : pointVelocity(data, contact_.body, p0);
  for (int k = 0; k < forceDims_; ++k) *rows++ = v[k];
  const Vec3<T>& w = order == 2 ? data.a[contact_.body].ang : data.v[contact_.body].ang;
  for (const Eigen::Vector3d& e : turns_) *rows++ = reach_ * (e.x() * w[0] + e.y() * w[1] + e.z() * w[2]);
  return rows;
}

// --- ContactPointMotionKernel ------------------------------------------------------------

ContactPointMotionKernel::ContactPointMotionKernel(std::shared_ptr<const Model<double>> model,
                                                   const ContactPoints& contact, int forceDims,
                                                   int order, std::string label)
    : model_(std::move(model)), still_(contact, forceDims), order_(order) {
  label_ = std::move(label);
  inputs_ = (order_ + 1) * model_->dofCount();
  kinds_.assign(still_.count(), RowKind::Equality);
}

template <class T>
void ContactPointMotionKernel::compute(const T* z, T* rows) const {
  const int n = model_->dofCount();
  Data<T>& data = scratchData<T>(*model_);
  chainKinematics(*model_, data, still_.body(), z, z + n, order_ == 2 ? z + 2 * n : static_cast<const T*>(nullptr));
  still_.write(data, order_, rows);
}
SPACETIME_DEFINE_EVALUATORS(ContactPointMotionKernel)

// --- FrictionConeKernel ------------------------------------------------------------------

FrictionConeKernel::FrictionConeKernel(int points, int forceDims, double mu, double weightScale,
                                       std::string label)
    : points_(points), dims_(forceDims), mu_(mu), scale_(weightScale) {
  label_ = std::move(label);
  inputs_ = points * forceDims;
  kinds_.assign(points * (forceDims == 3 ? 5 : 3), RowKind::Inequality);
}

template <class T>
void FrictionConeKernel::compute(const T* z, T* rows) const {
  int r = 0;
  const double muFacet = dims_ == 3 ? mu_ / std::sqrt(2.0) : mu_;
  for (int i = 0; i < points_; ++i) {
    const T* f = z + i * dims_;
    rows[r++] = -f[1] * scale_;  // push only
    rows[r++] = (f[0] - muFacet * f[1]) * scale_;
    rows[r++] = (-f[0] - muFacet * f[1]) * scale_;
    if (dims_ == 3) {
      rows[r++] = (f[2] - muFacet * f[1]) * scale_;
      rows[r++] = (-f[2] - muFacet * f[1]) * scale_;
    }
  }
}
SPACETIME_DEFINE_EVALUATORS(FrictionConeKernel)

// --- ContactWrenchConeKernel -------------------------------------------------------------

ContactWrenchConeKernel::ContactWrenchConeKernel(double mu, double weightScale, std::string label)
    : mu_(mu), scale_(weightScale) {
  label_ = std::move(label);
  inputs_ = 4;
  kinds_.assign(4, RowKind::Inequality);
}

template <class T>
void ContactWrenchConeKernel::compute(const T* z, T* rows) const {
  const T fx = z[0] + z[2], fy = z[1] + z[3];
  rows[0] = -z[1] * scale_;  // each point pushes: |M| <= a F_y
  rows[1] = -z[3] * scale_;
  rows[2] = (fx - mu_ * fy) * scale_;
  rows[3] = (-fx - mu_ * fy) * scale_;
}
SPACETIME_DEFINE_EVALUATORS(ContactWrenchConeKernel)

// --- ImpactKernel ------------------------------------------------------------------------

ImpactKernel::ImpactKernel(std::shared_ptr<const Model<double>> model, std::vector<ContactPoints> contacts,
                           const std::vector<char>& held, int forceDims, double impulseScale,
                           double torqueWeight, std::string label)
    : model_(std::move(model)), contacts_(std::move(contacts)), forceDims_(forceDims),
      impulseScale_(impulseScale), sqrtTorqueWeight_(std::sqrt(torqueWeight)) {
  label_ = std::move(label);
  const int n = model_->dofCount();
  size_t points = 0;
  size_t stillRows = 0;
  for (size_t c = 0; c < contacts_.size(); ++c) {
    points += contacts_[c].points.size();
    if (held[c]) continue;
    still_.emplace_back(contacts_[c], forceDims_);
    stillRows += still_.back().count();
  }
  inputs_ = 4 * n + forceDims_ * static_cast<int>(points);
  for (int d = 0; d < n; ++d)
    (model_->bodies[model_->dofBody[d]].actuated ? actuated_ : unactuated_).push_back(d);
  parts_.insert(parts_.end(), unactuated_.size(), Part::Continuity);
  parts_.insert(parts_.end(), unactuated_.size(), Part::Balance);
  parts_.insert(parts_.end(), actuated_.size(), Part::JointImpulse);
  parts_.insert(parts_.end(), stillRows, Part::PostVelocity);
  for (Part p : parts_)
    kinds_.push_back(p == Part::JointImpulse ? RowKind::Objective : RowKind::Equality);
}

template <class T>
void ImpactKernel::compute(const T* z, T* rows) const {
  const int n = model_->dofCount();
  const T *qMinus = z, *qPlus = z + n, *qdMinus = z + 2 * n, *qdPlus = z + 3 * n;
  // M (qd+ - qd-) - sum J^T L is the RNEA of the velocity jump as an acceleration, with no
  // velocity and no gravity (RBDA eq. 11.58); the configuration is the one before the impact.
  VecX<T> jump(n);
  for (int d = 0; d < n; ++d) jump[d] = qdPlus[d] - qdMinus[d];
  Data<T>& data = scratchData<T>(*model_);
  const T* none = nullptr;
  const VecX<T> impulse =
      rnea(*model_, data, qMinus, none, jump.data(), contactPointForces(contacts_, z + 4 * n, forceDims_), false,
           /*allWorldPoses=*/false);
  int r = 0;
  for (int d : unactuated_) rows[r++] = qPlus[d] - qMinus[d];
  for (int d : unactuated_) rows[r++] = impulse[d] * impulseScale_;
  for (int d : actuated_) rows[r++] = impulse[d] * sqrtTorqueWeight_;
  forwardKinematics(*model_, data, qPlus, qdPlus, none);
  T* next = rows + r;
  for (const ContactStillRows& still : still_) next = still.write(data, 1, next);
}
SPACETIME_DEFINE_EVALUATORS(ImpactKernel)

// --- ClearanceKernel ---------------------------------------------------------------------

ClearanceKernel::ClearanceKernel(std::shared_ptr<const Model<double>> model, int body,
                                 const Eigen::Vector3d& point, double height, std::string label)
    : model_(std::move(model)), body_(body), point_(point), height_(height) {
  label_ = std::move(label);
  inputs_ = model_->dofCount();
  kinds_.assign(1, RowKind::Inequality);
}

ClearanceKernel::ClearanceKernel(std::shared_ptr<const Model<double>> model, int body,
                                 const Eigen::Vector3d& point, const Eigen::Vector3d& boxMin,
                                 const Eigen::Vector3d& boxMax, std::string label)
    : ClearanceKernel(std::move(model), body, point, 0.0, std::move(label)) {
  box_ = true;
  boxMin_ = boxMin;
  boxMax_ = boxMax;
}

template <class T>
T ClearanceKernel::row(const Vec3<T>& p, int* axis, double* sign) const {
  *axis = 1, *sign = -1;
  if (!box_) return height_ - p.y();
  T outside = p.x() - boxMax_.x();
  *axis = 0;  // the row is -outside
  for (int k = 0; k < 3; ++k) {
    const T above = p[k] - boxMax_[k], below = boxMin_[k] - p[k];
    if (above > outside) outside = above, *axis = k, *sign = -1;
    if (below > outside) outside = below, *axis = k, *sign = 1;
  }
  return -outside;
}

template <class T>
void ClearanceKernel::compute(const T* z, T* rows) const {
  int axis;
  double sign;
  rows[0] = row(pointPosition(bodyPose(*model_, z, body_), point_), &axis, &sign);
}
SPACETIME_DEFINE_EVALUATORS(ClearanceKernel)

void ClearanceKernel::rawJacobian(const double* z, double* rows, double* jacobian) const {
  const BodySlopes body(*model_, z, body_);
  const Eigen::Vector3d p = body.position(point_);
  int axis;
  double sign;
  rows[0] = row(p, &axis, &sign);
  for (int d = 0; d < inputs_; ++d) jacobian[d] = sign * body.slope(d, p)[axis];
}

// --- GroundClearanceKernel ---------------------------------------------------------------

GroundClearanceKernel::GroundClearanceKernel(std::shared_ptr<const Model<double>> model, int body,
                                             std::vector<LowestPointFeature> features,
                                             double groundHeight, std::string label)
    : model_(std::move(model)), body_(body), features_(std::move(features)), ground_(groundHeight) {
  label_ = std::move(label);
  inputs_ = model_->dofCount();
  kinds_.assign(features_.size(), RowKind::Inequality);
}

template <class T>
void GroundClearanceKernel::compute(const T* z, T* rows) const {
  const Transform<T> X = bodyPose(*model_, z, body_);  // world point = E^T p + r
  const Mat3<T> rotation = X.E.transpose();
  for (size_t i = 0; i < features_.size(); ++i)
    rows[i] = T(ground_) - features_[i].lowestHeight(rotation, X.r, kDiscSmoothing);
}
SPACETIME_DEFINE_EVALUATORS(GroundClearanceKernel)

void GroundClearanceKernel::rawJacobian(const double* z, double* rows, double* jacobian) const {
  const int n = inputs_;
  const BodySlopes body(*model_, z, body_);
  const Mat3<double> rotation = body.X.E.transpose();
  const Eigen::Vector3d& origin = body.X.r;
  for (size_t i = 0; i < features_.size(); ++i) {
    const LowestPointFeature& f = features_[i];
    rows[i] = ground_ - f.lowestHeight(rotation, origin, kDiscSmoothing);
    // The height's slope in a world rotation w of the body, (w x a)_y for a = R p, and in a move
    // of its origin, e_y; a disc adds r n_y / sqrt(1 - n_y^2 + eps^2) times the slope of
    // n_y = (R n)_y, (w x b)_y for b = R n, while 1 - n_y^2 is not clamped at 0.
    const Eigen::Vector3d a = rotation * f.point;
    Eigen::Vector3d slopeTurn(-a.z(), 0, a.x());
    if (f.isDisc()) {
      const Eigen::Vector3d b = rotation * f.discNormal;
      const double across = 1 - b.y() * b.y();
      if (!(across < 0)) slopeTurn += f.discRadius * b.y() / std::sqrt(across + kDiscSmoothing * kDiscSmoothing) * Eigen::Vector3d(-b.z(), 0, b.x());
    }
    // Column d: the body turns at w_d and its origin moves at v_d + w_d x origin; the row is
    // ground - height.
    for (int d = 0; d < n; ++d) jacobian[i * n + d] = -(slopeTurn.dot(body.motion(d).ang) + body.slope(d, origin).y());
  }
}

// --- JointLimitKernel --------------------------------------------------------------------

JointLimitKernel::JointLimitKernel(std::shared_ptr<const Model<double>> model, std::string label)
    : model_(std::move(model)) {
  label_ = std::move(label);
  inputs_ = model_->dofCount();
  for (int d = 0; d < model_->dofCount(); ++d)
    if (model_->bodies[model_->dofBody[d]].hasPositionLimits) dofs_.push_back(d);
  kinds_.assign(2 * dofs_.size(), RowKind::Inequality);
}

template <class T>
void JointLimitKernel::compute(const T* z, T* rows) const {
  for (size_t i = 0; i < dofs_.size(); ++i) {
    const Body<double>& b = model_->bodies[model_->dofBody[dofs_[i]]];
    rows[2 * i] = z[dofs_[i]] - b.upper;
    rows[2 * i + 1] = b.lower - z[dofs_[i]];
  }
}
SPACETIME_DEFINE_EVALUATORS(JointLimitKernel)

// --- JointSpeedLimitKernel ---------------------------------------------------------------

JointSpeedLimitKernel::JointSpeedLimitKernel(std::shared_ptr<const Model<double>> model, std::string label)
    : model_(std::move(model)) {
  label_ = std::move(label);
  inputs_ = model_->dofCount();
  for (int d = 0; d < model_->dofCount(); ++d)
    if (model_->bodies[model_->dofBody[d]].hasSpeedLimit) dofs_.push_back(d);
  kinds_.assign(2 * dofs_.size(), RowKind::Inequality);
}

template <class T>
void JointSpeedLimitKernel::compute(const T* z, T* rows) const {
  for (size_t i = 0; i < dofs_.size(); ++i) {
    const double limit = model_->bodies[model_->dofBody[dofs_[i]]].speedLimit;
    rows[2 * i] = z[dofs_[i]] - limit;
    rows[2 * i + 1] = -z[dofs_[i]] - limit;
  }
}
SPACETIME_DEFINE_EVALUATORS(JointSpeedLimitKernel)

// --- FormulaKernel -----------------------------------------------------------------------

FormulaKernel::FormulaKernel(std::shared_ptr<const expr::Tape> tape, int inputs, double time,
                             RowKind kind, double scale, double offset, std::string label, std::string source)
    : tape_(std::move(tape)), time_(time), scale_(scale), offset_(offset), source_(std::move(source)) {
  label_ = std::move(label);
  inputs_ = inputs;
  kinds_.assign(1, kind);
}

template <class T>
void FormulaKernel::compute(const T* z, T* rows) const {
  std::vector<T> work;
  T out;
  tape_->evaluate(z, T(time_), &out, work);
  rows[0] = (out - offset_) * scale_;
}
SPACETIME_DEFINE_EVALUATORS(FormulaKernel)

}  // namespace spacetime
