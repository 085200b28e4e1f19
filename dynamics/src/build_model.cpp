// Scene character -> Model<double>.
#include "dynamics/build_model.h"

#include "dynamics/inertia_from_geometry.h"

namespace spacetime {

Transform<double> placement(const Eigen::Vector3d& origin, const Eigen::Vector3d& rpy) {
  // URDF: the joint frame is rotated by Rz(yaw) Ry(pitch) Rx(roll) in its parent; the coordinate
  // transform parent -> joint is the transpose.
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  return Transform<double>(R.transpose(), origin);
}

namespace {
Joint<double> makeJoint(JointType type, const Eigen::Vector3d& axis, double pitch = 0) {
  Joint<double> j;
  j.type = type;
  j.axis = axis;
  j.pitch = pitch;
  return j;
}
}  // namespace

Model<double> buildModel(const CharacterSpec& c, const Eigen::Vector3d& gravity) {
  Model<double> m;
  m.name = c.id;
  m.gravity = gravity;
  const BodySpec& rootSpec = c.bodies.front();
  const std::string& r = rootSpec.id;

  // The root's virtual chain: (name suffix, joint) pairs; the last one carries the root body.
  std::vector<std::pair<std::string, Joint<double>>> chain;
  const Eigen::Vector3d X = Eigen::Vector3d::UnitX(), Y = Eigen::Vector3d::UnitY(),
                        Z = Eigen::Vector3d::UnitZ();
  switch (c.root) {
    case RootKind::Fixed: chain = {{"", makeJoint(JointType::Fixed, Z)}}; break;
    case RootKind::Planar:
      chain = {{"_x", makeJoint(JointType::Prismatic, X)},
               {"_y", makeJoint(JointType::Prismatic, Y)},
               {"_rz", makeJoint(JointType::Revolute, Z)}};
      break;
    case RootKind::Translation3D:
      chain = {{"_x", makeJoint(JointType::Prismatic, X)},
               {"_y", makeJoint(JointType::Prismatic, Y)},
               {"_z", makeJoint(JointType::Prismatic, Z)}};
      break;
    case RootKind::Floating3D:
      chain = {{"_x", makeJoint(JointType::Prismatic, X)},
               {"_y", makeJoint(JointType::Prismatic, Y)},
               {"_z", makeJoint(JointType::Prismatic, Z)},
               {"_ry", makeJoint(JointType::Revolute, Y)},
               {"_rz", makeJoint(JointType::Revolute, Z)},
               {"_rx", makeJoint(JointType::Revolute, X)}};
      break;
  }
  for (size_t k = 0; k < chain.size(); ++k) {
    Body<double> b;
    const bool last = k + 1 == chain.size();
    b.name = last ? r : r + chain[k].first;
    b.jointName = chain[k].second.type == JointType::Fixed ? "" : r + chain[k].first;
    b.parent = k == 0 ? -1 : m.bodyCount() - 1;
    b.joint = chain[k].second;
    b.actuated = c.rootActuated && b.joint.type != JointType::Fixed;
    b.isVirtual = !last;
    if (last) b.inertia = bodyInertia(rootSpec);
    m.addBody(b);
  }
  // Map scene body ids to model body indices as we go (parents come first).
  std::vector<std::pair<std::string, int>> index = {{r, m.bodyCount() - 1}};
  auto lookup = [&](const std::string& id) {
    for (const auto& [name, i] : index)
      if (name == id) return i;
    return -1;
  };
  for (size_t i = 1; i < c.bodies.size(); ++i) {
    const BodySpec& s = c.bodies[i];
    Body<double> b;
    b.name = s.id;
    b.parent = lookup(s.parent);
    const JointType type = s.joint.kind == JointKind::Revolute    ? JointType::Revolute
                           : s.joint.kind == JointKind::Prismatic ? JointType::Prismatic
                           : s.joint.kind == JointKind::Helical   ? JointType::Helical
                                                                  : JointType::Fixed;
    b.joint = makeJoint(type, s.joint.axis, s.joint.pitch);
    b.jointName = type == JointType::Fixed ? "" : s.joint.id;
    b.X_tree = placement(s.joint.origin, s.joint.rpy);
    b.inertia = bodyInertia(s);
    b.actuated = s.joint.actuated && type != JointType::Fixed;
    if (s.joint.limits) {
      b.hasPositionLimits = true;
      b.lower = s.joint.limits->first;
      b.upper = s.joint.limits->second;
    }
    if (s.joint.torqueLimit) {
      b.hasEffortLimit = true;
      b.effortLimit = *s.joint.torqueLimit;
    }
    if (s.joint.speedLimit) {
      b.hasSpeedLimit = true;
      b.speedLimit = *s.joint.speedLimit;
    }
    index.emplace_back(s.id, m.addBody(b));
  }
  return m;
}

}  // namespace spacetime
