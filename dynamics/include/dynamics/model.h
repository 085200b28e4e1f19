// Model / Data: the immutable description of an articulated character and the per-evaluation
// workspace the algorithms write into (the split of Pinocchio and MuJoCo).
//
// A Model is a tree of bodies numbered so that parent < child. Every body hangs from its parent
// by one joint with at most one degree of freedom (revolute, prismatic, helical or fixed).
// Floating bases are chains of such joints on massless virtual bodies, as the seed's "virtual
// bones" were: a planar root is (x, y, rz), a 3D root is (x, y, z, ry, rz, rx) - translation,
// then yaw about the vertical, pitch, roll (intrinsic Y-Z-X Euler angles; singular only at a
// pitch of +-90 degrees, which no shipped motion approaches). This keeps every algorithm a plain
// 1-dof recursion and makes the URDF export exact.
#pragma once

#include <string>
#include <vector>

#include "dynamics/spatial.h"

namespace spacetime {

enum class JointType { Revolute, Prismatic, Helical, Fixed };

template <class S>
struct Joint {
  JointType type = JointType::Fixed;
  Vec3<S> axis = Vec3<S>::UnitZ();  // unit axis in the joint frame
  S pitch = S(0);                   // helical: translation along the axis per radian

  int dofCount() const { return type == JointType::Fixed ? 0 : 1; }

  // Motion subspace S (RBDA Table 4.1), in the child frame (the axis is invariant under q).
  Motion<S> motionSubspace() const {
    switch (type) {
      case JointType::Revolute: return {axis, Vec3<S>::Zero()};
      case JointType::Prismatic: return {Vec3<S>::Zero(), axis};
      case JointType::Helical: return {axis, axis * pitch};
      case JointType::Fixed: break;
    }
    return {};
  }

  // Joint transform X_J(q) from the joint (predecessor) frame to the child frame (RBDA Table 4.1).
  template <class T>
  Transform<T> transform(const T& q) const {
    Transform<T> X;
    switch (type) {
      case JointType::Revolute: X.E = rotationCoordinates<T>(axis, q); break;
      case JointType::Prismatic:
        for (int i = 0; i < 3; ++i) X.r(i) = q * axis(i);
        break;
      case JointType::Helical:
        X.E = rotationCoordinates<T>(axis, q);
        for (int i = 0; i < 3; ++i) X.r(i) = q * (pitch * axis(i));
        break;
      case JointType::Fixed: break;
    }
    return X;
  }

  template <class U>
  Joint<U> cast() const {
    Joint<U> j;
    j.type = type;
    j.axis = axis.template cast<U>();
    j.pitch = U(pitch);
    return j;
  }
};

template <class S>
struct Body {
  std::string name;       // the body's id in the scene (virtual bodies: "<root>_x" and so on)
  std::string jointName;  // the degree of freedom's name; empty for fixed joints
  int parent = -1;        // -1: the world
  Joint<S> joint;
  Transform<S> X_tree;    // parent body frame -> joint frame (constant placement)
  Inertia<S> inertia;     // about the body frame origin, in body coordinates
  bool actuated = false;  // joint torque/force supplied by a muscle/motor
  bool isVirtual = false; // massless link of a floating-base chain
  int dofIndex = -1;      // index in q, or -1 for a fixed joint
  // Inequality data for the joint (used by the solver and exported to URDF).
  bool hasPositionLimits = false;
  S lower = S(0), upper = S(0);
  bool hasEffortLimit = false;
  S effortLimit = S(0);
  bool hasSpeedLimit = false;  // |qd| <= speedLimit
  S speedLimit = S(0);

  template <class U>
  Body<U> cast() const {
    Body<U> b;
    b.name = name;
    b.jointName = jointName;
    b.parent = parent;
    b.joint = joint.template cast<U>();
    b.X_tree = X_tree.template cast<U>();
    b.inertia = inertia.template cast<U>();
    b.actuated = actuated;
    b.isVirtual = isVirtual;
    b.dofIndex = dofIndex;
    b.hasPositionLimits = hasPositionLimits;
    b.lower = U(lower);
    b.upper = U(upper);
    b.hasEffortLimit = hasEffortLimit;
    b.effortLimit = U(effortLimit);
    b.hasSpeedLimit = hasSpeedLimit;
    b.speedLimit = U(speedLimit);
    return b;
  }
};

template <class S>
struct Model {
  std::string name;
  std::vector<Body<S>> bodies;
  std::vector<int> dofBody;  // body index of each degree of freedom
  Vec3<S> gravity = Vec3<S>(S(0), S(-9.81), S(0));

  int dofCount() const { return static_cast<int>(dofBody.size()); }
  int bodyCount() const { return static_cast<int>(bodies.size()); }
  int bodyIndex(const std::string& n) const {
    for (int i = 0; i < bodyCount(); ++i)
      if (bodies[i].name == n) return i;
    return -1;
  }
  int dofIndex(const std::string& jointName) const {
    for (int d = 0; d < dofCount(); ++d)
      if (bodies[dofBody[d]].jointName == jointName) return d;
    return -1;
  }
  std::vector<std::string> dofNames() const {
    std::vector<std::string> names;
    for (int b : dofBody) names.push_back(bodies[b].jointName);
    return names;
  }
  std::vector<bool> actuatedDofs() const {
    std::vector<bool> a;
    for (int b : dofBody) a.push_back(bodies[b].actuated);
    return a;
  }
  S totalMass() const {
    S m = S(0);
    for (const auto& b : bodies) m += b.inertia.mass;
    return m;
  }
  // Appends a body and gives its joint the next dof index. Returns its index.
  int addBody(Body<S> b) {
    b.dofIndex = b.joint.dofCount() ? dofCount() : -1;
    bodies.push_back(b);
    if (b.dofIndex >= 0) dofBody.push_back(bodyCount() - 1);
    return bodyCount() - 1;
  }
  template <class U>
  Model<U> cast() const {
    Model<U> m;
    m.name = name;
    for (const auto& b : bodies) m.bodies.push_back(b.template cast<U>());
    m.dofBody = dofBody;
    m.gravity = gravity.template cast<U>();
    return m;
  }
};

// A force applied at a world point on a body (a ground contact force), in world coordinates.
// The point is given in world coordinates, or (pointIsLocal) in body coordinates, which lets
// the solver apply a force at a body-fixed contact point without a separate kinematics pass.
template <class T>
struct PointForce {
  int body = -1;
  Vec3<T> pointWorld = Vec3<T>::Zero();
  Vec3<T> forceWorld = Vec3<T>::Zero();
  bool pointIsLocal = false;
};

// Per-evaluation workspace. Body quantities are in body coordinates.
template <class T>
struct Data {
  std::vector<Transform<T>> X_parent;  // parent -> body
  std::vector<Transform<T>> X_world;   // world -> body (body pose: E^T is its orientation)
  std::vector<Motion<T>> v, a;         // spatial velocity and acceleration (a excludes gravity)
  std::vector<Force<T>> f;             // RNEA: force transmitted through the body's joint
  VecX<T> tau;

  Data() = default;
  template <class S>
  explicit Data(const Model<S>& m) {
    resize(m);
  }
  template <class S>
  void resize(const Model<S>& m) {
    const size_t n = m.bodies.size();
    X_parent.assign(n, Transform<T>());
    X_world.assign(n, Transform<T>());
    v.assign(n, Motion<T>());
    a.assign(n, Motion<T>());
    f.assign(n, Force<T>());
    tau = VecX<T>::Constant(m.dofCount(), T(0));
  }
};

}  // namespace spacetime
