// The BVH exporter against our forward kinematics: a small, independent BVH reader (hierarchy,
// offsets, channels, the Rz Rx Ry convention) rebuilds every joint's world position from the
// exported text, which must equal the body origins our FK gives at random poses of the planar
// and the 3D lamp (3D root rotations exercise all three Euler angles).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>
#include <sstream>

#include "../shipped_scene.h"
#include "dynamics/algorithms.h"
#include "dynamics/build_model.h"
#include "interop/bvh_export.h"

namespace spacetime {
namespace {

struct ReadJoint {
  std::string name;
  int parent = -1;
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  std::vector<std::string> channels;
};

struct ReadBvh {
  std::vector<ReadJoint> joints;
  int frames = 0;
  double frameTime = 0;
  std::vector<std::vector<double>> values;  // per frame, every channel in hierarchy order
};

ReadBvh readBvh(const std::string& text) {
  ReadBvh bvh;
  std::istringstream in(text);
  std::string token;
  std::vector<int> stack;
  bool endSite = false;
  while (in >> token) {
    if (token == "ROOT" || token == "JOINT") {
      ReadJoint j;
      in >> j.name;
      j.parent = stack.empty() ? -1 : stack.back();
      bvh.joints.push_back(j);
    } else if (token == "End") {
      in >> token;  // Site
      endSite = true;
    } else if (token == "{") {
      if (!endSite) stack.push_back(static_cast<int>(bvh.joints.size()) - 1);
    } else if (token == "}") {
      if (endSite) endSite = false;
      else stack.pop_back();
    } else if (token == "OFFSET") {
      Eigen::Vector3d o;
      in >> o.x() >> o.y() >> o.z();
      if (!endSite) bvh.joints.back().offset = o;
    } else if (token == "CHANNELS") {
      int n;
      in >> n;
      bvh.joints.back().channels.resize(n);
      for (auto& c : bvh.joints.back().channels) in >> c;
    } else if (token == "Frames:") {
      in >> bvh.frames >> token >> token >> bvh.frameTime;  // Frame Time: t
      int channels = 0;
      for (const ReadJoint& j : bvh.joints) channels += static_cast<int>(j.channels.size());
      bvh.values.assign(bvh.frames, std::vector<double>(channels));
      for (auto& frame : bvh.values)
        for (double& v : frame) in >> v;
    }
  }
  return bvh;
}

// World positions of every joint at one frame: translation = position channels if present,
// else OFFSET; rotation = the rotation channels' product in their listed order.
std::vector<Eigen::Vector3d> bvhPositions(const ReadBvh& bvh, int frame) {
  std::vector<Eigen::Vector3d> position(bvh.joints.size());
  std::vector<Eigen::Matrix3d> rotation(bvh.joints.size());
  size_t k = 0;
  for (size_t i = 0; i < bvh.joints.size(); ++i) {
    const ReadJoint& j = bvh.joints[i];
    Eigen::Vector3d t = j.offset;
    Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
    for (const std::string& c : j.channels) {
      const double v = bvh.values[frame][k++];
      if (c == "Xposition") t.x() = v;
      else if (c == "Yposition") t.y() = v;
      else if (c == "Zposition") t.z() = v;
      else {
        const Eigen::Vector3d axis = c == "Xrotation" ? Eigen::Vector3d::UnitX()
                                     : c == "Yrotation" ? Eigen::Vector3d::UnitY()
                                                        : Eigen::Vector3d::UnitZ();
        R = R * Eigen::AngleAxisd(v * M_PI / 180.0, axis).toRotationMatrix();
      }
    }
    if (j.parent < 0) {
      position[i] = t;
      rotation[i] = R;
    } else {
      position[i] = position[j.parent] + rotation[j.parent] * t;
      rotation[i] = rotation[j.parent] * R;
    }
  }
  return position;
}

class BvhExport : public ::testing::TestWithParam<const char*> {};

TEST_P(BvhExport, ReproducesForwardKinematics) {
  const Scene scene = testing::shippedScene(GetParam());
  const CharacterSpec& character = scene.characters[0];
  const Model<double> model = buildModel(character, scene.gravity);
  CharacterAnimation animation;
  const int frames = 12;
  animation.q.resize(frames, model.dofCount());
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> angle(-2.5, 2.5);
  for (int f = 0; f < frames; ++f) {
    animation.times.push_back(f / 30.0);
    for (int d = 0; d < model.dofCount(); ++d) animation.q(f, d) = angle(rng);
  }
  const ReadBvh bvh = readBvh(motionBvh(model, character, animation));
  ASSERT_EQ(bvh.frames, frames);
  EXPECT_NEAR(bvh.frameTime, 1.0 / 30.0, 1e-9);
  ASSERT_EQ(bvh.joints.size(), character.bodies.size());
  Data<double> data(model);
  for (int f = 0; f < frames; ++f) {
    const Eigen::VectorXd q = animation.q.row(f).transpose();
    forwardKinematics(model, data, q.data());
    const std::vector<Eigen::Vector3d> p = bvhPositions(bvh, f);
    for (size_t i = 0; i < bvh.joints.size(); ++i) {
      const int body = model.bodyIndex(bvh.joints[i].name);
      ASSERT_GE(body, 0) << bvh.joints[i].name;
      EXPECT_LT((p[i] - data.X_world[body].r).norm(), 1e-6) << bvh.joints[i].name << " frame " << f;
    }
  }
}

// Rotation channels are unwrapped: a joint turning steadily past 180 degrees never jumps by
// about 360 between frames.
TEST(BvhExportAngles, AreContinuousAcrossTheWrap) {
  const Scene scene = testing::shippedScene("luxo_jump.json");
  const CharacterSpec& character = scene.characters[0];
  const Model<double> model = buildModel(character, scene.gravity);
  CharacterAnimation animation;
  const int frames = 100;
  animation.q = Eigen::MatrixXd::Zero(frames, model.dofCount());
  for (int f = 0; f < frames; ++f) {
    animation.times.push_back(f / 30.0);
    animation.q(f, 2) = 0.1 * f;  // base_rz: 10 rad = 1.6 turns
  }
  const ReadBvh bvh = readBvh(motionBvh(model, character, animation));
  for (int f = 1; f < frames; ++f)
    EXPECT_NEAR(bvh.values[f][3] - bvh.values[f - 1][3], 0.1 * 180 / M_PI, 1e-6) << f;  // root Zrotation
}

INSTANTIATE_TEST_SUITE_P(Lamps, BvhExport, ::testing::Values("luxo_jump.json", "luxo_3d.json"));

}  // namespace
}  // namespace spacetime
