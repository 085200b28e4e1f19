// URDF writer. Link frames are our body frames; a joint's origin is the body's tree placement
// (parent frame -> joint frame) and its axis is given in the joint frame, exactly URDF's
// convention. Inertials are the full tensors about each body's centre of mass.
#include "interop/urdf_export.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

namespace spacetime {
namespace {

std::string fmt(double v) {
  std::ostringstream s;
  s << std::setprecision(17) << v;
  return s.str();
}
std::string vec(const Eigen::Vector3d& v) { return fmt(v.x()) + " " + fmt(v.y()) + " " + fmt(v.z()); }

// URDF roll-pitch-yaw of a rotation R = Rz(yaw) Ry(pitch) Rx(roll).
Eigen::Vector3d rpyOf(const Eigen::Matrix3d& R) {
  const double pitch = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
  double roll, yaw;
  if (std::abs(std::cos(pitch)) > 1e-9) {
    roll = std::atan2(R(2, 1), R(2, 2));
    yaw = std::atan2(R(1, 0), R(0, 0));
  } else {
    roll = 0;
    yaw = std::atan2(-R(0, 1), R(1, 1));
  }
  return {roll, pitch, yaw};
}

std::string originTag(const Eigen::Vector3d& xyz, const Eigen::Vector3d& rpy) {
  return "<origin xyz=\"" + vec(xyz) + "\" rpy=\"" + vec(rpy) + "\"/>";
}

// Rotation taking the URDF cylinder's z axis to the shape's axis.
Eigen::Vector3d cylinderRpy(int axis) {
  if (axis == 0) return {0, M_PI / 2, 0};
  if (axis == 1) return {-M_PI / 2, 0, 0};
  return Eigen::Vector3d::Zero();
}

void writeVisual(std::ostringstream& out, const Geometry& g, const Eigen::Vector3d& color) {
  auto visual = [&](const std::string& origin, const std::string& shape) {
    out << "    <visual>\n      " << origin << "\n      <geometry>" << shape
        << "</geometry>\n      <material name=\"\"><color rgba=\"" << vec(color)
        << " 1\"/></material>\n    </visual>\n";
  };
  const double r = g.size[0], L = g.size[1];
  switch (g.kind) {
    case GeometryKind::Box:
      visual(originTag(g.offset, Eigen::Vector3d::Zero()), "<box size=\"" + vec(g.size) + "\"/>");
      break;
    case GeometryKind::Sphere:
      visual(originTag(g.offset, Eigen::Vector3d::Zero()), "<sphere radius=\"" + fmt(r) + "\"/>");
      break;
    case GeometryKind::Cylinder:
    case GeometryKind::Capsule: {
      visual(originTag(g.offset, cylinderRpy(g.axis)),
             "<cylinder radius=\"" + fmt(r) + "\" length=\"" + fmt(L) + "\"/>");
      if (g.kind == GeometryKind::Capsule)
        for (double s : {-0.5, 0.5}) {
          Eigen::Vector3d c = g.offset;
          c[g.axis] += s * L;
          visual(originTag(c, Eigen::Vector3d::Zero()), "<sphere radius=\"" + fmt(r) + "\"/>");
        }
      break;
    }
    case GeometryKind::None: break;
  }
}

}  // namespace

Eigen::Matrix3d yUpToZUp() { return Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix(); }

UrdfExport exportUrdf(const Model<double>& model, const CharacterSpec& character, const UrdfOptions& options) {
  UrdfExport result;
  std::ostringstream out;
  const std::string world = model.name + "_world";
  // The parent of the tree's roots: the world link, or in a Z-up file the scene's Y-up frame.
  const std::string rootParent = options.zUp ? model.name + "_y_up" : world;
  const Eigen::Vector3d gravity = options.zUp ? Eigen::Vector3d(yUpToZUp() * model.gravity) : model.gravity;
  auto hint = [](double v) {  // 6 digits for people; rounding noise of the turn shows as 0
    std::ostringstream s;
    s << (std::abs(v) < 1e-12 ? 0.0 : v);
    return s.str();
  };
  out << "<?xml version=\"1.0\"?>\n";
  out << "<!-- Exported by Spacetime. Movable joints are the character's degrees of freedom in"
         " order; virtual links of the floating base are massless. -->\n";
  out << "<!-- " << (options.zUp ? "Z up (the scene's Y-up frame is link " + rootParent + ")" : std::string("Y up"))
      << ": gravity is (" << hint(gravity.x()) << " " << hint(gravity.y()) << " " << hint(gravity.z())
      << ") m/s^2 in this file's frame"
      << (options.zUp ? "" : "; URDF readers pull along -Z unless told (spacetime-cli --urdf-z-up writes a Z-up file)")
      << ". -->\n";
  out << "<robot name=\"" << model.name << "\">\n";
  // MuJoCo refuses moving bodies without mass; its own extension lifts only the massless
  // virtual links to 1e-12 kg, and carries the gravity, which MuJoCo then needs no setting for
  // (other URDF readers ignore the element).
  out << "  <mujoco><option gravity=\"" << vec(gravity)
      << "\"/><compiler boundmass=\"1e-12\" boundinertia=\"1e-14\" discardvisual=\"true\"/></mujoco>\n";
  out << "  <link name=\"" << world << "\"/>\n";
  if (options.zUp) out << "  <link name=\"" << rootParent << "\"/>\n";
  for (int i = 0; i < model.bodyCount(); ++i) {
    const Body<double>& b = model.bodies[i];
    out << "  <link name=\"" << b.name << "\">\n";
    if (b.inertia.mass > 0) {
      const Eigen::Matrix3d Ic = b.inertia.inertiaAboutCom();
      out << "    <inertial>\n      " << originTag(b.inertia.com(), Eigen::Vector3d::Zero())
          << "\n      <mass value=\"" << fmt(b.inertia.mass) << "\"/>\n"
          << "      <inertia ixx=\"" << fmt(Ic(0, 0)) << "\" ixy=\"" << fmt(Ic(0, 1))
          << "\" ixz=\"" << fmt(Ic(0, 2)) << "\" iyy=\"" << fmt(Ic(1, 1)) << "\" iyz=\""
          << fmt(Ic(1, 2)) << "\" izz=\"" << fmt(Ic(2, 2)) << "\"/>\n    </inertial>\n";
    }
    if (const BodySpec* spec = b.isVirtual ? nullptr : character.body(b.name))
      writeVisual(out, spec->geometry, spec->color);
    out << "  </link>\n";
  }
  for (int i = 0; i < model.bodyCount(); ++i) {
    const Body<double>& b = model.bodies[i];
    std::string type;
    switch (b.joint.type) {
      case JointType::Revolute: type = b.hasPositionLimits ? "revolute" : "continuous"; break;
      case JointType::Prismatic: type = "prismatic"; break;
      case JointType::Helical:
        type = "continuous";
        result.warning = "URDF has no helical joint: joint '" + b.jointName +
                         "' was exported as continuous and its pitch is lost";
        break;
      case JointType::Fixed: type = "fixed"; break;
    }
    const std::string name = b.jointName.empty() ? b.name + "_fixed" : b.jointName;
    out << "  <joint name=\"" << name << "\" type=\"" << type << "\">\n";
    out << "    <parent link=\"" << (b.parent >= 0 ? model.bodies[b.parent].name : rootParent)
        << "\"/>\n    <child link=\"" << b.name << "\"/>\n";
    out << "    " << originTag(b.X_tree.r, rpyOf(b.X_tree.E.transpose())) << "\n";
    if (b.joint.type != JointType::Fixed) {
      out << "    <axis xyz=\"" << vec(b.joint.axis) << "\"/>\n";
      const double effort = b.hasEffortLimit ? b.effortLimit : 1e6;
      const std::string velocity = fmt(b.hasSpeedLimit ? b.speedLimit : 1e6);
      if (type == "revolute" || type == "prismatic") {
        const double lo = b.hasPositionLimits ? b.lower : -1e3, hi = b.hasPositionLimits ? b.upper : 1e3;
        out << "    <limit lower=\"" << fmt(lo) << "\" upper=\"" << fmt(hi) << "\" effort=\""
            << fmt(effort) << "\" velocity=\"" << velocity << "\"/>\n";
      } else {
        out << "    <limit effort=\"" << fmt(effort) << "\" velocity=\"" << velocity << "\"/>\n";
      }
    }
    out << "  </joint>\n";
  }
  if (options.zUp) {  // the scene's frame under the Z-up world: Y becomes Z
    out << "  <joint name=\"" << rootParent << "\" type=\"fixed\">\n    <parent link=\"" << world
        << "\"/>\n    <child link=\"" << rootParent << "\"/>\n    "
        << originTag(Eigen::Vector3d::Zero(), rpyOf(yUpToZUp())) << "\n  </joint>\n";
  }
  out << "</robot>\n";
  result.xml = out.str();
  return result;
}

}  // namespace spacetime
