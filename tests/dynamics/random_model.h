// Random articulated models for property tests: random trees of revolute, prismatic, helical and
// fixed joints with random placements and inertias, optionally on a floating root.
#pragma once

#include <random>

#include "dynamics/build_model.h"
#include "dynamics/model.h"

namespace spacetime::testing {

inline Eigen::Vector3d randomVec(std::mt19937& rng, double s = 1.0) {
  std::uniform_real_distribution<double> u(-s, s);
  return {u(rng), u(rng), u(rng)};
}

inline CharacterSpec randomCharacter(std::mt19937& rng, int bodies, RootKind root,
                                     bool allowHelical = true, bool rotatedInertia = true,
                                     bool allowFixed = true) {
  std::uniform_real_distribution<double> u(0.2, 2.0);
  CharacterSpec c;
  c.id = "random";
  c.root = root;
  for (int i = 0; i < bodies; ++i) {
    BodySpec b;
    b.id = "b" + std::to_string(i);
    if (i > 0) {
      b.parent = "b" + std::to_string(std::uniform_int_distribution<int>(0, i - 1)(rng));
      const int kinds = allowHelical ? 4 : 3;
      const int k = std::uniform_int_distribution<int>(0, kinds - 1)(rng);
      b.joint.kind = k == 0 ? JointKind::Revolute
                     : k == 1 ? JointKind::Prismatic
                     : k == 2 ? (i % 3 == 0 && allowFixed ? JointKind::Fixed : JointKind::Revolute)
                              : JointKind::Helical;
      b.joint.id = "j" + std::to_string(i);
      b.joint.axis = randomVec(rng).normalized();
      b.joint.origin = randomVec(rng, 0.5);
      b.joint.rpy = randomVec(rng, 1.0);
      b.joint.pitch = 0.1;
    }
    b.mass = u(rng);
    b.com = randomVec(rng, 0.3);
    // Principal moments (b+c, a+c, a+b) of a positive mass spread always satisfy the triangle
    // inequality, as any physical body does.
    const Eigen::Vector3d spread(u(rng) * 0.05, u(rng) * 0.05, u(rng) * 0.05);
    const Eigen::Vector3d p(spread.y() + spread.z(), spread.x() + spread.z(), spread.x() + spread.y());
    const Eigen::Quaterniond qr(Eigen::AngleAxisd(u(rng), randomVec(rng).normalized()));
    b.inertia = rotatedInertia ? Eigen::Matrix3d(qr.toRotationMatrix() * p.asDiagonal() * qr.toRotationMatrix().transpose()) : Eigen::Matrix3d(p.asDiagonal());
    c.bodies.push_back(b);
  }
  return c;
}

inline Eigen::VectorXd randomVector(std::mt19937& rng, int n, double s = 1.0) {
  std::uniform_real_distribution<double> u(-s, s);
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i) v[i] = u(rng);
  return v;
}

}  // namespace spacetime::testing
