// Small queries on the Scene value and the names of its enumerations (used by the file format).
#include "core/scene.h"

namespace spacetime {

std::vector<std::string> CharacterSpec::dofNames() const {
  std::vector<std::string> names;
  if (bodies.empty()) return names;
  const std::string& r = bodies.front().id;
  switch (root) {
    case RootKind::Fixed: break;
    case RootKind::Planar: names = {r + "_x", r + "_y", r + "_rz"}; break;
    case RootKind::Floating3D:
      names = {r + "_x", r + "_y", r + "_z", r + "_ry", r + "_rz", r + "_rx"};
      break;
    case RootKind::Translation3D: names = {r + "_x", r + "_y", r + "_z"}; break;
  }
  for (size_t i = 1; i < bodies.size(); ++i)
    if (bodies[i].joint.kind != JointKind::Fixed) names.push_back(bodies[i].joint.id);
  return names;
}

const BodySpec* CharacterSpec::body(const std::string& id) const {
  for (const auto& b : bodies)
    if (b.id == id) return &b;
  return nullptr;
}

const CharacterSpec* Scene::character(const std::string& id) const {
  for (const auto& c : characters)
    if (c.id == id) return &c;
  return nullptr;
}

std::string toString(RootKind k) {
  switch (k) {
    case RootKind::Fixed: return "fixed";
    case RootKind::Planar: return "planar";
    case RootKind::Floating3D: return "floating3d";
    case RootKind::Translation3D: return "translation3d";
  }
  return "?";
}
std::string toString(GeometryKind k) {
  switch (k) {
    case GeometryKind::None: return "none";
    case GeometryKind::Box: return "box";
    case GeometryKind::Sphere: return "sphere";
    case GeometryKind::Capsule: return "capsule";
    case GeometryKind::Cylinder: return "cylinder";
  }
  return "?";
}
std::string toString(JointKind k) {
  switch (k) {
    case JointKind::Revolute: return "revolute";
    case JointKind::Prismatic: return "prismatic";
    case JointKind::Helical: return "helical";
    case JointKind::Fixed: return "fixed";
  }
  return "?";
}
std::string toString(TermKind k) {
  switch (k) {
    case TermKind::Pin: return "pin";
    case TermKind::Keyframe: return "keyframe";
    case TermKind::Rest: return "rest";
    case TermKind::Contact: return "contact";
    case TermKind::Clearance: return "clearance";
    case TermKind::Formula: return "formula";
  }
  return "?";
}

}  // namespace spacetime
