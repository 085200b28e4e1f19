// glTF 2.0 binary export (see gltf_export.h). Layout follows the glTF 2.0 specification: a GLB
// header, a JSON chunk and a BIN chunk holding every accessor's data, each view 4-byte aligned.
#include "interop/gltf_export.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <nlohmann/json.hpp>

#include "core/shape_mesh.h"
#include "dynamics/algorithms.h"
#include "dynamics/skeleton.h"

namespace spacetime {
namespace {

using nlohmann::json;

// glTF's enumerations (specification §5.1.2, §5.11.3).
constexpr int kFloat = 5126, kUnsignedInt = 5125;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

// The scene's colours are display (sRGB) values as the viewport shows them; glTF's base colour
// factor is linear (specification §3.9.2).
double linearFromSrgb(double c) {
  c = std::clamp(c, 0.0, 1.0);
  return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}

class GlbWriter {
 public:
  json gltf = {{"asset", {{"version", "2.0"}, {"generator", "Spacetime"}}}};

  // A view of `bytes` appended to the binary chunk; target 0 for animation data.
  int view(const void* data, size_t bytes, int target) {
    while (bin_.size() % 4) bin_.push_back('\0');
    json v = {{"buffer", 0}, {"byteOffset", bin_.size()}, {"byteLength", bytes}};
    if (target) v["target"] = target;
    bin_.append(static_cast<const char*>(data), bytes);
    return push("bufferViews", v);
  }

  // Float vectors (VEC3, VEC4) or scalars with their bounds (required for positions and for
  // animation inputs, §5.1.5).
  template <int N>
  int floats(const std::vector<Eigen::Matrix<float, N, 1>>& values, int target, bool bounds) {
    json a = {{"bufferView", view(values.data(), values.size() * sizeof(values[0]), target)},
              {"componentType", kFloat},
              {"count", values.size()},
              {"type", N == 1 ? "SCALAR" : "VEC" + std::to_string(N)}};
    if (bounds && !values.empty()) {
      Eigen::Matrix<float, N, 1> lo = values[0], hi = values[0];
      for (const auto& v : values) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
      a["min"] = std::vector<float>(lo.data(), lo.data() + N);
      a["max"] = std::vector<float>(hi.data(), hi.data() + N);
    }
    return push("accessors", a);
  }

  int indices(const std::vector<std::uint32_t>& values) {
    return push("accessors", {{"bufferView", view(values.data(), values.size() * 4, kElementArrayBuffer)},
                              {"componentType", kUnsignedInt},
                              {"count", values.size()},
                              {"type", "SCALAR"}});
  }

  int push(const char* array, json value) {
    json& a = gltf[array];
    a.push_back(std::move(value));
    return static_cast<int>(a.size()) - 1;
  }

  std::string glb() {
    while (bin_.size() % 4) bin_.push_back('\0');
    gltf["buffers"] = json::array({{{"byteLength", bin_.size()}}});
    std::string text = gltf.dump();
    while (text.size() % 4) text.push_back(' ');  // the JSON chunk pads with spaces (§4.4.3.1)
    std::string out;
    auto word = [&](std::uint32_t w) { out.append(reinterpret_cast<const char*>(&w), 4); };
    word(0x46546C67);  // "glTF"
    word(2);
    word(static_cast<std::uint32_t>(12 + 8 + text.size() + 8 + bin_.size()));
    word(static_cast<std::uint32_t>(text.size()));
    word(0x4E4F534A);  // "JSON"
    out += text;
    word(static_cast<std::uint32_t>(bin_.size()));
    word(0x004E4942);  // "BIN\0"
    out += bin_;
    return out;
  }

 private:
  std::string bin_;
};

int bodyMesh(GlbWriter& w, const BodySpec& body) {
  const TriangleMesh mesh = geometryMesh(body.geometry);
  if (mesh.indices.empty()) return -1;
  const int material = w.push(
      "materials", {{"name", body.id},
                    {"pbrMetallicRoughness",
                     {{"baseColorFactor", {linearFromSrgb(body.color.x()), linearFromSrgb(body.color.y()),
                                           linearFromSrgb(body.color.z()), 1.0}},
                      {"metallicFactor", 0.0},
                      {"roughnessFactor", 0.6}}}});
  json attributes = {{"POSITION", w.floats(mesh.positions, kArrayBuffer, true)},
                     {"NORMAL", w.floats(mesh.normals, kArrayBuffer, false)}};
  return w.push("meshes", {{"name", body.id},
                           {"primitives", json::array({{{"attributes", attributes},
                                                        {"indices", w.indices(mesh.indices)},
                                                        {"material", material}}})}});
}

}  // namespace

std::string motionGlb(const Scene& scene, const std::vector<const Model<double>*>& models,
                      const Animation& animation) {
  GlbWriter w;
  const std::vector<double>& grid =
      animation.characters.empty() ? std::vector<double>{} : animation.characters[0].times;
  std::vector<Eigen::Matrix<float, 1, 1>> times;
  for (double t : grid) times.push_back(Eigen::Matrix<float, 1, 1>(static_cast<float>(t - grid[0])));
  const int input = times.size() >= 2 ? w.floats(times, 0, true) : -1;

  json roots = json::array(), channels = json::array(), samplers = json::array();
  auto animate = [&](int node, const char* path, int output) {
    samplers.push_back({{"input", input}, {"output", output}, {"interpolation", "LINEAR"}});
    channels.push_back({{"sampler", samplers.size() - 1}, {"target", {{"node", node}, {"path", path}}}});
  };

  for (size_t c = 0; c < scene.characters.size(); ++c) {
    const CharacterSpec& spec = scene.characters[c];
    const Model<double>& model = *models[c];
    const CharacterAnimation& track = animation.characters[c];
    const std::vector<Bone> bones = skeletonOf(model);

    // Every bone's local pose at every frame.
    const int frames = static_cast<int>(track.times.size());
    std::vector<std::vector<Eigen::Vector3f>> translation(bones.size());
    std::vector<std::vector<Eigen::Vector4f>> rotation(bones.size());  // x, y, z, w
    Data<double> data(model);
    for (int f = 0; f < frames; ++f) {
      const Eigen::VectorXd q = track.q.row(f).transpose();
      forwardKinematics(model, data, q.data());
      for (size_t b = 0; b < bones.size(); ++b) {
        const Eigen::Isometry3d pose = localPose(bones, data, static_cast<int>(b));
        Eigen::Vector4f r = Eigen::Quaterniond(pose.linear()).normalized().coeffs().cast<float>();
        if (f > 0 && r.dot(rotation[b].back()) < 0) r = -r;
        translation[b].push_back(pose.translation().cast<float>());
        rotation[b].push_back(r);
      }
    }

    // Nodes: the character, then its bones (children listed after the fact).
    const int characterNode = w.push("nodes", {{"name", spec.id}});
    roots.push_back(characterNode);
    std::vector<int> nodeOf(bones.size());
    for (size_t b = 0; b < bones.size(); ++b) {
      const std::string& name = model.bodies[bones[b].body].name;
      json node = {{"name", name}};
      if (frames > 0) {
        node["translation"] = std::vector<float>(translation[b][0].data(), translation[b][0].data() + 3);
        node["rotation"] = std::vector<float>(rotation[b][0].data(), rotation[b][0].data() + 4);
      }
      if (const BodySpec* body = spec.body(name)) {
        const int mesh = bodyMesh(w, *body);
        if (mesh >= 0) node["mesh"] = mesh;
      }
      nodeOf[b] = w.push("nodes", node);
      const int parentNode = bones[b].parent < 0 ? characterNode : nodeOf[bones[b].parent];
      w.gltf["nodes"][parentNode]["children"].push_back(nodeOf[b]);
      if (frames < 2) continue;
      animate(nodeOf[b], "rotation", w.floats(rotation[b], 0, false));
      if (bones[b].translates) animate(nodeOf[b], "translation", w.floats(translation[b], 0, false));
    }
  }

  w.gltf["scenes"] = json::array({{{"name", scene.name}, {"nodes", roots}}});
  w.gltf["scene"] = 0;
  if (!channels.empty())
    w.gltf["animations"] = json::array({{{"name", "motion"}, {"channels", channels}, {"samplers", samplers}}});
  return w.glb();
}

}  // namespace spacetime
