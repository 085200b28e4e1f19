// The skeleton of a character as animation packages see it: its real bodies, each hung from its
// nearest real ancestor, with the floating base's virtual links folded into the root. The BVH
// and glTF exports both write this tree; a bone's local pose is its body frame relative to its
// parent bone's (or to the world for a root), read off forward kinematics, so any joint axis and
// any fixed placement rotation is exact.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "dynamics/model.h"

namespace spacetime {

struct Bone {
  int body = -1;
  int parent = -1;          // index into the skeleton's bones; -1 for a root
  bool translates = false;  // root, prismatic or helical: the local translation varies
  std::vector<int> children;
};

// Bones in body order (a parent before its children).
std::vector<Bone> skeletonOf(const Model<double>& model);

// The local pose of bone `index` (body frame -> parent bone frame, or -> world for a root) from
// forward kinematics already run on `data`.
Eigen::Isometry3d localPose(const std::vector<Bone>& bones, const Data<double>& data, int index);

}  // namespace spacetime
