// BVH export (see bvh_export.h).
#include "solver/bvh_export.h"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "dynamics/algorithms.h"

namespace spacetime {
namespace {

constexpr double kDegrees = 180.0 / M_PI;

// Angles (z, x, y) in degrees with R = Rz(z) Rx(x) Ry(y): row 2 of Rz Rx Ry is
// (-cos x sin y, sin x, cos x cos y) and column 1 is (-sin z cos x, cos z cos x, sin x).
Eigen::Vector3d zxyAngles(const Eigen::Matrix3d& R) {
  const double x = std::asin(std::clamp(R(2, 1), -1.0, 1.0));
  const double z = std::atan2(-R(0, 1), R(1, 1));
  const double y = std::atan2(-R(2, 0), R(2, 2));
  return Eigen::Vector3d(z, x, y) * kDegrees;
}

// The angle equal to a modulo 360 that is closest to `previous`: keyframe interpolation in the
// importing package must not spin the long way round where atan2 wraps.
double unwrap(double a, double previous) {
  return a + 360.0 * std::round((previous - a) / 360.0);
}

std::string number(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.9g", std::abs(v) < 1e-12 ? 0.0 : v);
  return buffer;
}

struct BvhJoint {
  int body = -1;
  int parent = -1;  // index into the joints, -1 for the root
  bool translates = false;
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  Eigen::Vector3d endSite = Eigen::Vector3d::Zero();
  std::vector<int> children;
};

}  // namespace

std::string motionBvh(const Model<double>& model, const CharacterSpec& character,
                      const CharacterAnimation& animation) {
  // The real bodies, each hung from its nearest real ancestor.
  std::vector<BvhJoint> joints;
  std::vector<int> jointOf(model.bodies.size(), -1);
  for (size_t b = 0; b < model.bodies.size(); ++b) {
    const Body<double>& body = model.bodies[b];
    if (body.isVirtual) continue;
    BvhJoint j;
    j.body = static_cast<int>(b);
    for (int p = body.parent; p >= 0; p = model.bodies[p].parent)
      if (jointOf[p] >= 0) {
        j.parent = jointOf[p];
        break;
      }
    const bool root = j.parent < 0;
    j.translates = root || body.joint.type == JointType::Prismatic || body.joint.type == JointType::Helical;
    jointOf[b] = static_cast<int>(joints.size());
    if (!root) joints[j.parent].children.push_back(jointOf[b]);
    if (const BodySpec* spec = character.body(body.name)) j.endSite = 2 * spec->geometry.offset;
    joints.push_back(j);
  }

  // Offsets: body origins in their parent's frame with every dof at zero.
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(model.dofCount());
  Data<double> data(model);
  forwardKinematics(model, data, zero.data());
  for (BvhJoint& j : joints) {
    if (j.parent < 0) continue;
    const Transform<double>& parent = data.X_world[joints[j.parent].body];
    j.offset = parent.E * (data.X_world[j.body].r - parent.r);
  }

  std::ostringstream out;
  out << "HIERARCHY\n";
  std::vector<int> order;  // joints in the order their channels appear
  auto write = [&](auto&& self, int index, int depth) -> void {
    const BvhJoint& j = joints[index];
    const std::string indent(2 * depth, ' ');
    out << indent << (j.parent < 0 ? "ROOT " : "JOINT ") << model.bodies[j.body].name << "\n"
        << indent << "{\n"
        << indent << "  OFFSET " << number(j.offset.x()) << " " << number(j.offset.y()) << " "
        << number(j.offset.z()) << "\n"
        << indent << "  CHANNELS " << (j.translates ? "6 Xposition Yposition Zposition " : "3 ")
        << "Zrotation Xrotation Yrotation\n";
    order.push_back(index);
    for (int child : j.children) self(self, child, depth + 1);
    if (j.children.empty())
      out << indent << "  End Site\n" << indent << "  {\n" << indent << "    OFFSET "
          << number(j.endSite.x()) << " " << number(j.endSite.y()) << " " << number(j.endSite.z())
          << "\n" << indent << "  }\n";
    out << indent << "}\n";
  };
  for (size_t i = 0; i < joints.size(); ++i)
    if (joints[i].parent < 0) write(write, static_cast<int>(i), 0);

  const int frames = static_cast<int>(animation.times.size());
  const double frameTime = frames > 1 ? animation.times[1] - animation.times[0] : 1.0 / 30.0;
  out << "MOTION\nFrames: " << frames << "\nFrame Time: " << number(frameTime) << "\n";
  std::vector<Eigen::Vector3d> previous(joints.size(), Eigen::Vector3d::Zero());
  for (int f = 0; f < frames; ++f) {
    const Eigen::VectorXd q = animation.q.row(f).transpose();
    forwardKinematics(model, data, q.data());
    std::string line;
    for (int index : order) {
      const BvhJoint& j = joints[index];
      const Transform<double>& X = data.X_world[j.body];
      Eigen::Matrix3d R = X.E.transpose();  // body orientation in the world
      Eigen::Vector3d p = X.r;
      if (j.parent >= 0) {
        const Transform<double>& P = data.X_world[joints[j.parent].body];
        R = P.E * R;           // relative to the parent body
        p = P.E * (X.r - P.r);
      }
      if (j.translates)
        for (int k = 0; k < 3; ++k) line += number(p[k]) + " ";
      Eigen::Vector3d angles = zxyAngles(R);
      if (f > 0)
        for (int k = 0; k < 3; ++k) angles[k] = unwrap(angles[k], previous[index][k]);
      previous[index] = angles;
      for (int k = 0; k < 3; ++k) line += number(angles[k]) + " ";
    }
    line.back() = '\n';
    out << line;
  }
  return out.str();
}

}  // namespace spacetime
