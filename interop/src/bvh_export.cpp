// BVH export (see bvh_export.h).
#include "interop/bvh_export.h"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "dynamics/algorithms.h"
#include "dynamics/skeleton.h"

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

}  // namespace

std::string motionBvh(const Model<double>& model, const CharacterSpec& character,
                      const CharacterAnimation& animation) {
  const std::vector<Bone> bones = skeletonOf(model);

  // OFFSETs are the local translations with every dof at zero.
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(model.dofCount());
  Data<double> data(model);
  forwardKinematics(model, data, zero.data());

  std::ostringstream out;
  out << "HIERARCHY\n";
  std::vector<int> order;  // bones in the order their channels appear
  auto write = [&](auto&& self, int index, int depth) -> void {
    const Bone& bone = bones[index];
    const std::string indent(2 * depth, ' ');
    const Eigen::Vector3d offset =
        bone.parent < 0 ? Eigen::Vector3d::Zero() : Eigen::Vector3d(localPose(bones, data, index).translation());
    out << indent << (bone.parent < 0 ? "ROOT " : "JOINT ") << model.bodies[bone.body].name << "\n"
        << indent << "{\n"
        << indent << "  OFFSET " << number(offset.x()) << " " << number(offset.y()) << " "
        << number(offset.z()) << "\n"
        << indent << "  CHANNELS " << (bone.translates ? "6 Xposition Yposition Zposition " : "3 ")
        << "Zrotation Xrotation Yrotation\n";
    order.push_back(index);
    for (int child : bone.children) self(self, child, depth + 1);
    if (bone.children.empty()) {
      const BodySpec* spec = character.body(model.bodies[bone.body].name);
      const Eigen::Vector3d end = spec ? Eigen::Vector3d(2 * spec->geometry.offset) : Eigen::Vector3d::Zero();
      out << indent << "  End Site\n" << indent << "  {\n" << indent << "    OFFSET "
          << number(end.x()) << " " << number(end.y()) << " " << number(end.z()) << "\n"
          << indent << "  }\n";
    }
    out << indent << "}\n";
  };
  for (size_t i = 0; i < bones.size(); ++i)
    if (bones[i].parent < 0) write(write, static_cast<int>(i), 0);

  const int frames = static_cast<int>(animation.times.size());
  const double frameTime = frames > 1 ? animation.times[1] - animation.times[0] : 1.0 / 30.0;
  out << "MOTION\nFrames: " << frames << "\nFrame Time: " << number(frameTime) << "\n";
  std::vector<Eigen::Vector3d> previous(bones.size(), Eigen::Vector3d::Zero());
  for (int f = 0; f < frames; ++f) {
    const Eigen::VectorXd q = animation.q.row(f).transpose();
    forwardKinematics(model, data, q.data());
    std::string line;
    for (int index : order) {
      const Eigen::Isometry3d pose = localPose(bones, data, index);
      if (bones[index].translates)
        for (int k = 0; k < 3; ++k) line += number(pose.translation()[k]) + " ";
      Eigen::Vector3d angles = zxyAngles(pose.linear());
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
