// The skeleton of real bodies (see skeleton.h).
#include "dynamics/skeleton.h"

namespace spacetime {

std::vector<Bone> skeletonOf(const Model<double>& model) {
  std::vector<Bone> bones;
  std::vector<int> boneOf(model.bodies.size(), -1);
  for (size_t b = 0; b < model.bodies.size(); ++b) {
    const Body<double>& body = model.bodies[b];
    if (body.isVirtual) continue;
    Bone bone;
    bone.body = static_cast<int>(b);
    for (int p = body.parent; p >= 0; p = model.bodies[p].parent)
      if (boneOf[p] >= 0) {
        bone.parent = boneOf[p];
        break;
      }
    bone.translates = bone.parent < 0 || body.joint.type == JointType::Prismatic ||
                      body.joint.type == JointType::Helical;
    boneOf[b] = static_cast<int>(bones.size());
    if (bone.parent >= 0) bones[bone.parent].children.push_back(boneOf[b]);
    bones.push_back(bone);
  }
  return bones;
}

Eigen::Isometry3d localPose(const std::vector<Bone>& bones, const Data<double>& data, int index) {
  // Featherstone's X_world maps world to body coordinates: the body's orientation is E^T and its
  // origin r, so relative to the parent P the orientation is P.E X.E^T at P.E (X.r - P.r).
  const Transform<double>& X = data.X_world[bones[index].body];
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = X.E.transpose();
  pose.translation() = X.r;
  if (bones[index].parent >= 0) {
    const Transform<double>& P = data.X_world[bones[bones[index].parent].body];
    pose.linear() = P.E * pose.linear();
    pose.translation() = P.E * (X.r - P.r);
  }
  return pose;
}

}  // namespace spacetime
