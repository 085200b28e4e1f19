// Rigid-body algorithms on a Model, writing into a Data: forward kinematics, body-point
// kinematics, inverse dynamics (RNEA, RBDA Table 5.1), the joint-space inertia matrix (CRBA,
// RBDA Table 6.2), forward dynamics (ABA, RBDA Table 7.1), centre of mass, momentum and energy.
//
// Templates on two scalars: S for the model's constants and T for the state (double, Jet, ...).
// Joint-space arrays are passed as raw pointers of length model.dofCount(); a null qd or qdd
// means zero. Gravity is the model's and enters as a fictitious base acceleration -g
// (RBDA section 5.3), so after rnea() the Data's accelerations include it.
#pragma once

#include <Eigen/Cholesky>
#include <vector>

#include "dynamics/model.h"

namespace spacetime {

namespace detail {
template <class T, class S>
Motion<T> baseAcceleration(const Model<S>& model, bool withGravity) {
  Motion<T> a0;
  if (withGravity)
    for (int k = 0; k < 3; ++k) a0.lin(k) = T(-model.gravity(k));
  return a0;
}

// One body's step of the forward sweep (RBDA Table 5.1, first loop): its parent's entries in d
// must be current. worldPoses = false leaves X_world alone (RNEA itself needs only X_parent).
template <class T, class S>
void sweepBody(const Model<S>& model, Data<T>& d, int i, const T* q, const T* qd, const T* qdd, const Motion<T>& a0,
               bool worldPoses) {
  const Body<S>& b = model.bodies[i];
  const int k = b.dofIndex;
  const Transform<T> XJ = k >= 0 ? b.joint.template transform<T>(q[k]) : Transform<T>();
  d.X_parent[i] = compose(XJ, b.X_tree);
  if (worldPoses) d.X_world[i] = b.parent >= 0 ? d.X_parent[i] * d.X_world[b.parent] : d.X_parent[i];
  Motion<T> vJ, aJ;
  if (k >= 0) {
    const Motion<S> Sj = b.joint.motionSubspace();
    const T qdk = qd ? qd[k] : T(0), qddk = qdd ? qdd[k] : T(0);
    for (int c = 0; c < 3; ++c) {
      vJ.ang(c) = Sj.ang(c) * qdk;
      vJ.lin(c) = Sj.lin(c) * qdk;
      aJ.ang(c) = Sj.ang(c) * qddk;
      aJ.lin(c) = Sj.lin(c) * qddk;
    }
  }
  if (b.parent >= 0) {
    d.v[i] = d.X_parent[i].apply(d.v[b.parent]) + vJ;
    d.a[i] = d.X_parent[i].apply(d.a[b.parent]) + aJ + crossMotion(d.v[i], vJ);
  } else {
    d.v[i] = vJ;
    d.a[i] = d.X_parent[i].apply(a0) + aJ;
  }
}

// The forward sweep shared by FK and RNEA, every body in order (parents first).
template <class T, class S>
void forwardSweep(const Model<S>& model, Data<T>& d, const T* q, const T* qd, const T* qdd,
                  const Motion<T>& a0, bool worldPoses = true) {
  for (int i = 0; i < model.bodyCount(); ++i) sweepBody(model, d, i, q, qd, qdd, a0, worldPoses);
}

// A body's world pose from the sweep's X_parent along its chain.
template <class T, class S>
Transform<T> chainPose(const Model<S>& model, const Data<T>& d, int body) {
  const int parent = model.bodies[body].parent;
  return parent >= 0 ? d.X_parent[body] * chainPose(model, d, parent) : d.X_parent[body];
}
// A point force as a spatial force in body coordinates (after the forward sweep).
template <class T>
Force<T> bodyForce(const Data<T>& d, const PointForce<T>& pf) {
  const Transform<T>& X = d.X_world[pf.body];
  if (pf.pointIsLocal) {
    const Vec3<T> F = X.E * pf.forceWorld;
    return Force<T>(pf.pointWorld.cross(F), F);
  }
  // As a spatial force about the world origin, then in body coordinates.
  return X.apply(Force<T>(pf.pointWorld.cross(pf.forceWorld), pf.forceWorld));
}
}  // namespace detail

// Body poses only.
template <class T, class S>
void forwardKinematics(const Model<S>& model, Data<T>& d, const T* q) {
  detail::forwardSweep<T, S>(model, d, q, nullptr, nullptr, Motion<T>());
}

// Body poses, spatial velocities and (true, gravity-free) spatial accelerations.
template <class T, class S>
void forwardKinematics(const Model<S>& model, Data<T>& d, const T* q, const T* qd, const T* qdd) {
  detail::forwardSweep<T, S>(model, d, q, qd, qdd, Motion<T>());
}

// forwardKinematics for one body's chain only: its ancestors and itself, root first, get the
// poses, velocities and accelerations the full sweep gives them (the same operations in the
// same order); the other bodies' entries in d are left as they were. Kernels that read one
// body's motion (a contact point kept still) skip the rest of the tree: on the quadruped squat
// the sweep on Jets fell from 13 % to 9 % of the solve's profile.
template <class T, class S>
void chainKinematics(const Model<S>& model, Data<T>& d, int body, const T* q, const T* qd, const T* qdd) {
  const int parent = model.bodies[body].parent;
  if (parent >= 0) chainKinematics(model, d, parent, q, qd, qdd);
  detail::sweepBody(model, d, body, q, qd, qdd, Motion<T>(), true);
}

// The pose (world -> body, as Data::X_world) of one body from q alone: the joint and tree
// transforms of its ancestors composed root first (the X_world recursion of RBDA Table 5.1 along
// one chain). Kernels that need one body's pose (pins, clearances, contact anchors) skip the other
// bodies and the velocities forwardKinematics computes: with Jets, a third of the cost on Luxo.
template <class T, class S>
Transform<T> bodyPose(const Model<S>& model, const T* q, int body) {
  const Body<S>& b = model.bodies[body];
  const Transform<T> XJ = b.dofIndex >= 0 ? b.joint.template transform<T>(q[b.dofIndex]) : Transform<T>();
  const Transform<T> X_parent = compose(XJ, b.X_tree);
  return b.parent >= 0 ? X_parent * bodyPose(model, q, b.parent) : X_parent;
}

// bodyPose's pose of one body, and the body's spatial Jacobian in world coordinates: column d is
// the body's spatial velocity per unit speed of dof d (zero off its chain), the motion subspace
// S_d of the dof's body carried to world coordinates by the inverse of that body's X_world - the
// velocity recursion v_i = v_parent + S_i qd_i of RBDA Table 5.1 unrolled along the chain, every
// joint's S constant (Plucker coordinates at the world origin: the angular velocity and the
// velocity of the body-fixed point at the origin). A body-fixed point at world position p then
// moves at v + w x p per column. In doubles, for kernels that differentiate a function of one
// body's pose through it instead of carrying Jets along the chain.
namespace detail {
template <class S>
Transform<S> chainPoseAndJacobian(const Model<S>& model, const S* q, int body, std::vector<Motion<S>>* jacobian) {
  const Body<S>& b = model.bodies[body];
  const Transform<S> XJ = b.dofIndex >= 0 ? b.joint.template transform<S>(q[b.dofIndex]) : Transform<S>();
  const Transform<S> X_parent = compose(XJ, b.X_tree);
  const Transform<S> X = b.parent >= 0 ? X_parent * chainPoseAndJacobian(model, q, b.parent, jacobian) : X_parent;
  if (b.dofIndex >= 0) (*jacobian)[b.dofIndex] = X.applyInverse(b.joint.motionSubspace());
  return X;
}
}  // namespace detail
template <class S>
Transform<S> bodyPoseAndJacobian(const Model<S>& model, const S* q, int body, std::vector<Motion<S>>* jacobian) {
  jacobian->assign(static_cast<size_t>(model.dofCount()), Motion<S>());
  return detail::chainPoseAndJacobian(model, q, body, jacobian);
}

// World position of a point given in body coordinates, from the body's pose.
template <class T, class S>
Vec3<T> pointPosition(const Transform<T>& X, const Vec3<S>& p) {
  Vec3<T> out;
  for (int i = 0; i < 3; ++i)
    out(i) = X.E(0, i) * p(0) + X.E(1, i) * p(1) + X.E(2, i) * p(2) + X.r(i);
  return out;
}

// World position of a point given in body coordinates (after forwardKinematics).
template <class T, class S>
Vec3<T> pointPosition(const Data<T>& d, int body, const Vec3<S>& p) {
  return pointPosition(d.X_world[body], p);
}

// World velocity of a body-fixed point: E^T (v + w x p).
template <class T, class S>
Vec3<T> pointVelocity(const Data<T>& d, int body, const Vec3<S>& p) {
  const Motion<T>& v = d.v[body];
  const Vec3<T> vb = v.lin + cross3<T>(v.ang, p);
  return d.X_world[body].E.transpose() * vb;
}

// World (classical) acceleration of a body-fixed point from the spatial acceleration
// (RBDA eq. 2.42 rearranged): a_p = a_lin + alpha x p + w x (v_lin + w x p).
// Valid after forwardKinematics with qdd (not after rnea, whose accelerations include -g).
template <class T, class S>
Vec3<T> pointAcceleration(const Data<T>& d, int body, const Vec3<S>& p) {
  const Motion<T>& v = d.v[body];
  const Motion<T>& a = d.a[body];
  const Vec3<T> vb = v.lin + cross3<T>(v.ang, p);
  const Vec3<T> ab = a.lin + cross3<T>(a.ang, p) + v.ang.cross(vb);
  return d.X_world[body].E.transpose() * ab;
}

// Recursive Newton-Euler inverse dynamics (RBDA Table 5.1) with external point forces.
// Writes the generalized forces into d.tau and returns them. allWorldPoses = false fills X_world
// only for the bodies external forces act on: the solver's per-sample dynamics read nothing
// else, and composing every world pose was ~30 % of a forward sweep with Jets.
template <class T, class S>
const VecX<T>& rnea(const Model<S>& model, Data<T>& d, const T* q, const T* qd, const T* qdd,
                    const std::vector<PointForce<T>>& fext = {}, bool withGravity = true,
                    bool allWorldPoses = true) {
  detail::forwardSweep<T, S>(model, d, q, qd, qdd,
                             detail::baseAcceleration<T, S>(model, withGravity), allWorldPoses);
  if (!allWorldPoses)
    for (size_t k = 0; k < fext.size(); ++k)
      if (k == 0 || fext[k].body != fext[k - 1].body)
        d.X_world[fext[k].body] = detail::chainPose(model, d, fext[k].body);
  for (int i = 0; i < model.bodyCount(); ++i) {
    const Inertia<S>& I = model.bodies[i].inertia;
    if (model.bodies[i].isVirtual && I.mass == S(0)) {
      d.f[i] = Force<T>();
      continue;
    }
    d.f[i] = multiply(I, d.a[i]) + crossForce(d.v[i], multiply(I, d.v[i]));
  }
  for (const PointForce<T>& pf : fext) d.f[pf.body] -= detail::bodyForce(d, pf);
  for (int i = model.bodyCount() - 1; i >= 0; --i) {
    const Body<S>& b = model.bodies[i];
    if (b.dofIndex >= 0) {
      const Motion<S> Sj = b.joint.motionSubspace();
      T t = T(0);
      for (int c = 0; c < 3; ++c) t += Sj.ang(c) * d.f[i].ang(c) + Sj.lin(c) * d.f[i].lin(c);
      d.tau(b.dofIndex) = t;
    }
    if (b.parent >= 0) d.f[b.parent] += d.X_parent[i].applyInverse(d.f[i]);
  }
  return d.tau;
}

// Adds the generalized force of one external point force alone, -J^T F, to tau: the backward
// pass of RBDA Table 5.1 with the force as the only body force (no motion, no gravity), along
// the force body's chain only. Needs the sweep's X_parent and the force body's X_world (after
// forwardKinematics or crba). The solver's d tau / d f columns, one per force component.
template <class T, class S>
void addPointForceGeneralized(const Model<S>& model, const Data<T>& d, const PointForce<T>& pf,
                              T* tau) {
  Force<T> f = Force<T>() - detail::bodyForce(d, pf);
  for (int i = pf.body; i >= 0; i = model.bodies[i].parent) {
    const Body<S>& b = model.bodies[i];
    if (b.dofIndex >= 0) tau[b.dofIndex] += dot(b.joint.motionSubspace().template cast<T>(), f);
    if (b.parent >= 0) f = d.X_parent[i].applyInverse(f);
  }
}

// Joint-space inertia matrix by the composite-rigid-body algorithm (RBDA Table 6.2).
template <class T, class S>
MatX<T> crba(const Model<S>& model, Data<T>& d, const T* q) {
  forwardKinematics(model, d, q);
  const int n = model.dofCount();
  MatX<T> H = MatX<T>::Zero(n, n);
  std::vector<Inertia<T>> Ic;
  for (const auto& b : model.bodies) Ic.push_back(b.inertia.template cast<T>());
  for (int i = model.bodyCount() - 1; i >= 0; --i) {
    const Body<S>& b = model.bodies[i];
    if (b.parent >= 0) Ic[b.parent] = Ic[b.parent] + Ic[i].expressedInParent(d.X_parent[i]);
  }
  for (int i = 0; i < model.bodyCount(); ++i) {
    const Body<S>& bi = model.bodies[i];
    if (bi.dofIndex < 0) continue;
    const Motion<T> Si = bi.joint.motionSubspace().template cast<T>();
    Force<T> F = multiply(Ic[i], Si);
    H(bi.dofIndex, bi.dofIndex) = dot(Si, F);
    int j = i;
    while (model.bodies[j].parent >= 0) {
      F = d.X_parent[j].applyInverse(F);
      j = model.bodies[j].parent;
      const Body<S>& bj = model.bodies[j];
      if (bj.dofIndex < 0) continue;
      const Motion<T> Sj = bj.joint.motionSubspace().template cast<T>();
      H(bi.dofIndex, bj.dofIndex) = H(bj.dofIndex, bi.dofIndex) = dot(Sj, F);
    }
  }
  return H;
}

// Forward dynamics by the articulated-body algorithm (RBDA Table 7.1), with external forces.
template <class T, class S>
VecX<T> aba(const Model<S>& model, Data<T>& d, const T* q, const T* qd, const T* tau,
            const std::vector<PointForce<T>>& fext = {}) {
  const int nb = model.bodyCount();
  detail::forwardSweep<T, S>(model, d, q, qd, nullptr, Motion<T>());
  std::vector<Mat6<T>> IA(nb);
  std::vector<Vec6<T>> pA(nb), c(nb), U(nb);
  std::vector<T> D(nb, T(0)), u(nb, T(0));
  std::vector<Mat6<T>> X(nb);
  for (int i = 0; i < nb; ++i) {
    const Body<S>& b = model.bodies[i];
    X[i] = d.X_parent[i].matrix();
    const Mat6<T> I = b.inertia.template cast<T>().matrix();
    IA[i] = I;
    const Vec6<T> v = d.v[i].vector();
    Motion<T> vJ;
    if (b.dofIndex >= 0) vJ = b.joint.motionSubspace().template cast<T>() * qd[b.dofIndex];
    c[i] = crossMotion(d.v[i], vJ).vector();
    const Vec6<T> Iv = I * v;
    pA[i] = crossForce(d.v[i], Force<T>(Iv.template head<3>(), Iv.template tail<3>())).vector();
  }
  for (const PointForce<T>& pf : fext) pA[pf.body] -= detail::bodyForce(d, pf).vector();
  for (int i = nb - 1; i >= 0; --i) {
    const Body<S>& b = model.bodies[i];
    // I^a = I^A - U D^-1 U^T and p^a = p^A + I^a c + U D^-1 u (RBDA Table 7.1).
    Mat6<T> Ia = IA[i];
    Vec6<T> Ud = Vec6<T>::Zero();
    if (b.dofIndex >= 0) {
      const Vec6<T> Sv = b.joint.motionSubspace().template cast<T>().vector();
      U[i] = IA[i] * Sv;
      D[i] = Sv.dot(U[i]);
      u[i] = tau[b.dofIndex] - Sv.dot(pA[i]);
      Ia -= U[i] * U[i].transpose() / D[i];
      Ud = U[i] * (u[i] / D[i]);
    }
    const Vec6<T> pa = pA[i] + Ia * c[i] + Ud;
    if (b.parent >= 0) {
      IA[b.parent] += X[i].transpose() * Ia * X[i];
      pA[b.parent] += X[i].transpose() * pa;
    }
  }
  VecX<T> qdd = VecX<T>::Zero(model.dofCount());
  std::vector<Vec6<T>> a(nb);
  const Vec6<T> a0 = detail::baseAcceleration<T, S>(model, true).vector();
  for (int i = 0; i < nb; ++i) {
    const Body<S>& b = model.bodies[i];
    const Vec6<T> ap = X[i] * (b.parent >= 0 ? a[b.parent] : a0) + c[i];
    a[i] = ap;
    if (b.dofIndex >= 0) {
      const Vec6<T> Sv = b.joint.motionSubspace().template cast<T>().vector();
      qdd(b.dofIndex) = (u[i] - U[i].dot(ap)) / D[i];
      a[i] += Sv * qdd(b.dofIndex);
    }
  }
  return qdd;
}

// Centre of mass in world coordinates (after forwardKinematics).
template <class T, class S>
Vec3<T> centerOfMass(const Model<S>& model, const Data<T>& d) {
  Vec3<T> sum = Vec3<T>::Zero();
  S mass = S(0);
  for (int i = 0; i < model.bodyCount(); ++i) {
    const Inertia<S>& I = model.bodies[i].inertia;
    if (I.mass == S(0)) continue;
    sum += pointPosition(d, i, I.com()) * I.mass;
    mass += I.mass;
  }
  return mass > S(0) ? Vec3<T>(sum / mass) : sum;
}

// Spatial momentum about the world origin in world coordinates (after forwardKinematics with qd):
// ang is the angular momentum about the origin, lin the linear momentum.
template <class T, class S>
Force<T> spatialMomentum(const Model<S>& model, const Data<T>& d) {
  Force<T> h;
  for (int i = 0; i < model.bodyCount(); ++i)
    h += d.X_world[i].applyInverse(multiply(model.bodies[i].inertia, d.v[i]));
  return h;
}

template <class T, class S>
T kineticEnergy(const Model<S>& model, const Data<T>& d) {
  T e = T(0);
  for (int i = 0; i < model.bodyCount(); ++i)
    e += dot(d.v[i], multiply(model.bodies[i].inertia, d.v[i]));
  return e * T(0.5);
}

// Potential energy -m g . c, zero at the world origin.
template <class T, class S>
T potentialEnergy(const Model<S>& model, const Data<T>& d) {
  const Vec3<T> c = centerOfMass(model, d);
  T e = T(0);
  for (int k = 0; k < 3; ++k) e -= model.totalMass() * model.gravity(k) * c(k);
  return e;
}

}  // namespace spacetime
