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

std::vector<double> gltfKeyTimes(const SpacetimeProblem& problem, double rateHz) {
  const Scene& scene = problem.scene();
  const int intervals = std::max(1, static_cast<int>(std::lround((scene.endTime - scene.startTime) * rateHz)));
  auto fastest = [&](double t) {  // the largest dof speed at t, either side of an impact
    double v = 0;
    for (size_t c = 0; c < problem.characters().size(); ++c) {
      const int ci = static_cast<int>(c);
      v = std::max(v, problem.jointState(ci, t, 1).lpNorm<Eigen::Infinity>());
      if (t > scene.startTime) v = std::max(v, problem.jointStateOnSide(ci, t, 1, Side::Before).lpNorm<Eigen::Infinity>());
    }
    return v;
  };
  // The grid, and every instant where a dof's polynomial piece changes (the B-splines' knots, the
  // root's breakpoints): a key interval across one has a jump in the third derivative inside,
  // which a cubic cannot follow (measured: 2e-3 off in the head's rotation across the knot at
  // 0.25 s of the jump's push-off).
  std::vector<double> grid;
  for (int k = 0; k <= intervals; ++k) grid.push_back(scene.startTime + (scene.endTime - scene.startTime) * k / intervals);
  for (const CharacterVariables& c : problem.characters())
    for (const DofGroup& g : c.groups) {
      if (g.hasBubbles()) grid.insert(grid.end(), g.breaks.begin(), g.breaks.end());
      else
        for (int k = 0; k <= g.spline.segmentCount(); ++k) grid.push_back(g.spline.knot(k));
    }
  std::sort(grid.begin(), grid.end());
  // Keys closer than a microsecond are one (float seconds in the file; an impact's repeated
  // breakpoint).
  std::vector<double> merged;
  for (double t : grid)
    if (t >= scene.startTime - kTimeTolerance && t <= scene.endTime + kTimeTolerance && (merged.empty() || t - merged.back() > 1e-6))
      merged.push_back(std::clamp(t, scene.startTime, scene.endTime));
  std::vector<double> times = {merged[0]};
  double speedBefore = fastest(merged[0]);
  for (size_t k = 1; k < merged.size(); ++k) {
    const double a = times.back(), b = merged[k];
    const double speedAfter = fastest(b);
    // The speed inside the interval: its ends' and its middle's.
    const double speed = std::max({speedBefore, speedAfter, fastest(0.5 * (a + b))});
    const int pieces = std::clamp(static_cast<int>(std::ceil((b - a) * speed / kMaxKeyTurn)), 1, 64);
    for (int p = 1; p < pieces; ++p) times.push_back(a + (b - a) * p / pieces);
    times.push_back(b);
    speedBefore = speedAfter;
  }
  return times;
}

std::string motionGlb(const Scene& scene, const std::vector<const Model<double>*>& models,
                      const Animation& animation) {
  GlbWriter w;
  const std::vector<double>& grid =
      animation.characters.empty() ? std::vector<double>{} : animation.characters[0].times;
  std::vector<Eigen::Matrix<float, 1, 1>> times;
  for (double t : grid) times.push_back(Eigen::Matrix<float, 1, 1>(static_cast<float>(t - grid[0])));
  const int input = times.size() >= 2 ? w.floats(times, 0, true) : -1;

  // Cubic Hermite keys with the motion's own tangents when it has velocities (glTF 2.0 Appendix C:
  // each key an in-tangent, the value and an out-tangent, in units per second), so a player is
  // exact to O(h^4) between keys; linear keys otherwise.
  bool cubic = !animation.characters.empty();
  for (const CharacterAnimation& a : animation.characters)
    cubic = cubic && a.qd.rows() == static_cast<Eigen::Index>(a.times.size()) && a.qdBefore.rows() == a.qd.rows();
  json roots = json::array(), channels = json::array(), samplers = json::array();
  auto animate = [&](int node, const char* path, int output) {
    samplers.push_back({{"input", input}, {"output", output}, {"interpolation", cubic ? "CUBICSPLINE" : "LINEAR"}});
    channels.push_back({{"sampler", samplers.size() - 1}, {"target", {{"node", node}, {"path", path}}}});
  };

  for (size_t c = 0; c < scene.characters.size(); ++c) {
    const CharacterSpec& spec = scene.characters[c];
    const Model<double>& model = *models[c];
    const CharacterAnimation& track = animation.characters[c];
    const std::vector<Bone> bones = skeletonOf(model);

    // Every bone's local pose at every frame: with cubic keys (in-tangent, value, out-tangent)
    // per frame, the tangents being the pose's derivative along q-dot before and after it.
    const int frames = static_cast<int>(track.times.size());
    std::vector<std::vector<Eigen::Vector3f>> translation(bones.size());
    std::vector<std::vector<Eigen::Vector4f>> rotation(bones.size());  // x, y, z, w
    Data<double> data(model);
    std::vector<Eigen::Vector3d> t0(bones.size());
    std::vector<Eigen::Vector4d> r0(bones.size());
    auto poses = [&](const Eigen::VectorXd& q, std::vector<Eigen::Vector3d>& t, std::vector<Eigen::Vector4d>& r) {
      forwardKinematics(model, data, q.data());
      for (size_t b = 0; b < bones.size(); ++b) {
        const Eigen::Isometry3d pose = localPose(bones, data, static_cast<int>(b));
        t[b] = pose.translation();
        r[b] = Eigen::Quaterniond(pose.linear()).normalized().coeffs();
      }
    };
    // d/dt of every bone's pose along q-dot = v: central differences in q along v, exact to
    // O(h^2) (h |v| = 1e-6), quaternions taken on the key's hemisphere.
    auto tangents = [&](const Eigen::VectorXd& q, const Eigen::VectorXd& v, std::vector<Eigen::Vector3f>& dt,
                        std::vector<Eigen::Vector4f>& dr) {
      dt.assign(bones.size(), Eigen::Vector3f::Zero());
      dr.assign(bones.size(), Eigen::Vector4f::Zero());
      const double speed = v.lpNorm<Eigen::Infinity>();
      if (!(speed > 0)) return;
      const double h = 1e-6 / speed;
      std::vector<Eigen::Vector3d> tp(bones.size()), tm(bones.size());
      std::vector<Eigen::Vector4d> rp(bones.size()), rm(bones.size());
      poses(q + h * v, tp, rp);
      poses(q - h * v, tm, rm);
      for (size_t b = 0; b < bones.size(); ++b) {
        if (rp[b].dot(r0[b]) < 0) rp[b] = -rp[b];
        if (rm[b].dot(r0[b]) < 0) rm[b] = -rm[b];
        dt[b] = ((tp[b] - tm[b]) / (2 * h)).cast<float>();
        dr[b] = ((rp[b] - rm[b]) / (2 * h)).cast<float>();
      }
    };
    std::vector<Eigen::Vector3f> inT, outT;
    std::vector<Eigen::Vector4f> inR, outR;
    for (int f = 0; f < frames; ++f) {
      const Eigen::VectorXd q = track.q.row(f).transpose();
      poses(q, t0, r0);
      for (size_t b = 0; b < bones.size(); ++b)  // one hemisphere from key to key
        if (f > 0 && r0[b].cast<float>().dot(rotation[b][cubic ? rotation[b].size() - 2 : rotation[b].size() - 1]) < 0)
          r0[b] = -r0[b];
      if (cubic) {
        tangents(q, track.qdBefore.row(f).transpose(), inT, inR);
        tangents(q, track.qd.row(f).transpose(), outT, outR);
      }
      for (size_t b = 0; b < bones.size(); ++b) {
        if (cubic) {
          translation[b].push_back(inT[b]);
          rotation[b].push_back(inR[b]);
        }
        translation[b].push_back(t0[b].cast<float>());
        rotation[b].push_back(r0[b].cast<float>());
        if (cubic) {
          translation[b].push_back(outT[b]);
          rotation[b].push_back(outR[b]);
        }
      }
    }
    const int valueAt = cubic ? 1 : 0;  // the first key's value in the output arrays

    // Nodes: the character, then its bones (children listed after the fact).
    const int characterNode = w.push("nodes", {{"name", spec.id}});
    roots.push_back(characterNode);
    std::vector<int> nodeOf(bones.size());
    for (size_t b = 0; b < bones.size(); ++b) {
      const std::string& name = model.bodies[bones[b].body].name;
      json node = {{"name", name}};
      if (frames > 0) {
        node["translation"] = std::vector<float>(translation[b][valueAt].data(), translation[b][valueAt].data() + 3);
        node["rotation"] = std::vector<float>(rotation[b][valueAt].data(), rotation[b][valueAt].data() + 4);
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
