// The glTF exporter checked two independent ways: tinygltf (Debian's libtinygltf) reads the .glb
// back, and the node tree evaluated at every frame - each node's keyed rotation and translation,
// composed down from the root - must put every body where our forward kinematics does, on the
// planar and the 3D lamp at random poses (two characters in one file); and the Khronos glTF
// Validator (npm gltf-validator, installed by scripts/install-deps.sh) must report no error and
// no warning on the exports of every shipped scene.
#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <Eigen/Geometry>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

#include "../shipped_scene.h"
#include "core/atomic_file.h"
#include "dynamics/algorithms.h"
#include "dynamics/build_model.h"
#include "interop/gltf_export.h"

namespace spacetime {
namespace {

// A scene's characters with random poses at `frames` frames, 1/30 s apart from t = 0.25 s.
struct PosedScene {
  Scene scene;
  std::vector<Model<double>> models;
  Animation animation;

  std::vector<const Model<double>*> modelPointers() const {
    std::vector<const Model<double>*> p;
    for (const auto& m : models) p.push_back(&m);
    return p;
  }
};

PosedScene randomlyPosed(Scene scene, int frames, unsigned seed) {
  PosedScene posed{std::move(scene), {}, {}};
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> value(-2.5, 2.5);
  for (const CharacterSpec& c : posed.scene.characters) {
    posed.models.push_back(buildModel(c, posed.scene.gravity));
    CharacterAnimation a;
    a.name = c.id;
    a.q.resize(frames, posed.models.back().dofCount());
    for (int f = 0; f < frames; ++f) {
      a.times.push_back(0.25 + f / 30.0);
      for (int d = 0; d < a.q.cols(); ++d) a.q(f, d) = value(rng);
    }
    posed.animation.characters.push_back(a);
  }
  return posed;
}

const float* accessorFloats(const tinygltf::Model& gm, int index, int components) {
  const tinygltf::Accessor& a = gm.accessors.at(index);
  EXPECT_EQ(a.componentType, TINYGLTF_COMPONENT_TYPE_FLOAT);
  const tinygltf::BufferView& v = gm.bufferViews.at(a.bufferView);
  EXPECT_TRUE(v.byteStride == 0 || v.byteStride == static_cast<size_t>(4 * components));
  return reinterpret_cast<const float*>(gm.buffers.at(v.buffer).data.data() + v.byteOffset + a.byteOffset);
}

// Node n's local transform at frame f: its own TRS, overridden by the animation's channels.
Eigen::Isometry3d nodeLocal(const tinygltf::Model& gm, int n, int f) {
  const tinygltf::Node& node = gm.nodes[n];
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  Eigen::Quaterniond r = Eigen::Quaterniond::Identity();
  if (node.translation.size() == 3) t = Eigen::Vector3d(node.translation[0], node.translation[1], node.translation[2]);
  if (node.rotation.size() == 4) r = Eigen::Quaterniond(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);
  for (const tinygltf::Animation& anim : gm.animations)
    for (const tinygltf::AnimationChannel& ch : anim.channels) {
      if (ch.target_node != n) continue;
      const tinygltf::AnimationSampler& s = anim.samplers[ch.sampler];
      if (ch.target_path == "translation") {
        const float* p = accessorFloats(gm, s.output, 3) + 3 * f;
        t = Eigen::Vector3d(p[0], p[1], p[2]);
      } else if (ch.target_path == "rotation") {
        const float* p = accessorFloats(gm, s.output, 4) + 4 * f;
        r = Eigen::Quaterniond(p[3], p[0], p[1], p[2]);
      }
    }
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = r.normalized().toRotationMatrix();
  X.translation() = t;
  return X;
}

class GltfExport : public ::testing::TestWithParam<const char*> {};

TEST_P(GltfExport, ReproducesForwardKinematics) {
  Scene scene = testing::shippedScene(GetParam());
  CharacterSpec twin = scene.characters[0];  // a second character in the same file
  twin.id += "_twin";
  scene.characters.push_back(twin);
  const int frames = 15;
  const PosedScene posed = randomlyPosed(scene, frames, 5);
  const std::string glb = motionGlb(posed.scene, posed.modelPointers(), posed.animation);

  tinygltf::TinyGLTF loader;
  tinygltf::Model gm;
  std::string err, warn;
  ASSERT_TRUE(loader.LoadBinaryFromMemory(&gm, &err, &warn, reinterpret_cast<const unsigned char*>(glb.data()),
                                          static_cast<unsigned>(glb.size())))
      << err;
  ASSERT_EQ(gm.scenes.size(), 1u);
  ASSERT_EQ(gm.scenes[0].nodes.size(), 2u);  // one root node per character
  ASSERT_EQ(gm.animations.size(), 1u);

  // The keyframe times start at 0 and step by the animation's.
  const tinygltf::AnimationSampler& sampler = gm.animations[0].samplers.at(0);
  ASSERT_EQ(gm.accessors[sampler.input].count, static_cast<size_t>(frames));
  const float* times = accessorFloats(gm, sampler.input, 1);
  for (int f = 0; f < frames; ++f) EXPECT_NEAR(times[f], f / 30.0, 1e-6);

  std::vector<int> parent(gm.nodes.size(), -1);
  for (size_t n = 0; n < gm.nodes.size(); ++n)
    for (int child : gm.nodes[n].children) parent[child] = static_cast<int>(n);

  for (size_t c = 0; c < posed.scene.characters.size(); ++c) {
    const CharacterSpec& spec = posed.scene.characters[c];
    const Model<double>& model = posed.models[c];
    const int characterNode = gm.scenes[0].nodes[c];
    EXPECT_EQ(gm.nodes[characterNode].name, spec.id);
    // Every real body is a node under its character's node.
    std::vector<std::pair<int, int>> bodyNodes;  // (node, body)
    for (size_t n = 0; n < gm.nodes.size(); ++n) {
      int top = static_cast<int>(n);
      while (parent[top] >= 0) top = parent[top];
      if (top != characterNode || static_cast<int>(n) == characterNode) continue;
      const int body = model.bodyIndex(gm.nodes[n].name);
      ASSERT_GE(body, 0) << gm.nodes[n].name;
      bodyNodes.emplace_back(static_cast<int>(n), body);
    }
    ASSERT_EQ(bodyNodes.size(), spec.bodies.size());

    Data<double> data(model);
    for (int f = 0; f < frames; ++f) {
      const Eigen::VectorXd q = posed.animation.characters[c].q.row(f).transpose();
      forwardKinematics(model, data, q.data());
      for (const auto& [node, body] : bodyNodes) {
        Eigen::Isometry3d world = Eigen::Isometry3d::Identity();
        for (int n = node; n >= 0; n = parent[n]) world = nodeLocal(gm, n, f) * world;
        const Transform<double>& X = data.X_world[body];
        EXPECT_LT((world.translation() - X.r).norm(), 2e-6) << gm.nodes[node].name << " frame " << f;
        EXPECT_LT((world.linear() - X.E.transpose()).norm(), 2e-6) << gm.nodes[node].name << " frame " << f;
      }
    }
  }

  // Rotations stay on one hemisphere from frame to frame, so slerp takes the short way.
  for (const tinygltf::AnimationChannel& ch : gm.animations[0].channels) {
    if (ch.target_path != "rotation") continue;
    const float* r = accessorFloats(gm, gm.animations[0].samplers[ch.sampler].output, 4);
    for (int f = 1; f < frames; ++f)
      EXPECT_GE(Eigen::Vector4f(r + 4 * f).dot(Eigen::Vector4f(r + 4 * (f - 1))), 0.0f);
  }

  // Each body with geometry has a mesh whose material carries its colour (linearised).
  for (const tinygltf::Node& node : gm.nodes) {
    if (node.mesh < 0) continue;
    const BodySpec* body = posed.scene.characters[0].body(node.name);
    ASSERT_NE(body, nullptr);
    const tinygltf::Primitive& p = gm.meshes[node.mesh].primitives.at(0);
    const std::vector<double>& colour = gm.materials.at(p.material).pbrMetallicRoughness.baseColorFactor;
    for (int k = 0; k < 3; ++k) {
      const double srgb = body->color[k];
      const double linear = srgb <= 0.04045 ? srgb / 12.92 : std::pow((srgb + 0.055) / 1.055, 2.4);
      EXPECT_NEAR(colour[k], linear, 1e-9);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Lamps, GltfExport, ::testing::Values("luxo_jump.json", "luxo_3d.json"));

// The Khronos glTF Validator on the export of every shipped scene (random poses at 30 frames).
TEST(GltfValidator, AcceptsEveryShippedScene) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "spacetime_gltf_validator_test";
  std::filesystem::create_directories(dir);
  std::string command = std::string(SPACETIME_NODE) + " " + SPACETIME_SOURCE_DIR "/tests/tools/validate_gltf.cjs " +
                        SPACETIME_SOURCE_DIR "/.cache/gltf-validator/node_modules/gltf-validator";
  unsigned seed = 1;
  for (const auto& entry : std::filesystem::directory_iterator(SPACETIME_SOURCE_DIR "/resources/scenes")) {
    const PosedScene posed = randomlyPosed(testing::shippedScene(entry.path().filename()), 30, seed++);
    const std::string file = (dir / entry.path().filename().replace_extension(".glb")).string();
    std::string error;
    ASSERT_TRUE(writeFileAtomically(file, motionGlb(posed.scene, posed.modelPointers(), posed.animation), &error)) << error;
    command += " " + file;
  }
  const std::string log = (dir / "validator.log").string();
  const int status = std::system((command + " > " + log + " 2>&1").c_str());
  std::ifstream in(log);
  const std::string report((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(status, 0) << command << "\n" << report;
  EXPECT_NE(report.find("0 errors, 0 warnings"), std::string::npos) << report;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace spacetime
