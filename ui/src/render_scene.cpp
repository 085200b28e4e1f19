#include "ui/render_scene.h"

#include <algorithm>
#include <cmath>
#include <glm/gtc/constants.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "dynamics/algorithms.h"

namespace spacetime::ui {

glm::vec3 toGlm(const Eigen::Vector3d& v) {
  return {static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z())};
}

namespace {

// World pose of a body: Featherstone's X_world maps world to body coordinates, so the body's
// orientation in the world is E^T and its origin is r.
glm::mat4 bodyPose(const Data<double>& d, int body) {
  const Transform<double>& X = d.X_world[body];
  glm::mat4 m(1.0f);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m[c][r] = static_cast<float>(X.E(c, r));  // column-major E^T
  m[3] = glm::vec4(toGlm(X.r), 1.0f);
  return m;
}

void addGeometry(RenderScene& rs, const Geometry& g, const glm::mat4& pose, const glm::vec4& color,
                 int character, const std::string& body, bool ghost) {
  auto add = [&](Mesh mesh, const glm::mat4& m) { rs.solids.push_back({mesh, m, color, character, body, ghost}); };
  if (g.kind == GeometryKind::None) {  // a small marker so the body stays visible and pickable
    add(Mesh::Sphere, glm::scale(glm::translate(pose, toGlm(g.offset)), glm::vec3(0.02f)));
    return;
  }
  for (const ShapePiece& piece : geometryPieces(g)) {
    glm::mat4 placement;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) placement[c][r] = static_cast<float>(piece.placement.matrix()(r, c));
    add(piece.shape, pose * placement);
  }
}

// An arrow from `from` to `to` as a cylinder shaft and a cone head.
void addArrow(RenderScene& rs, const glm::vec3& from, const glm::vec3& to, const glm::vec4& color) {
  const glm::vec3 d = to - from;
  const float length = glm::length(d);
  if (length < 1e-4f) return;
  const glm::vec3 y = d / length;
  const glm::vec3 helper = std::abs(y.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
  const glm::vec3 x = glm::normalize(glm::cross(helper, y));
  const glm::vec3 z = glm::cross(x, y);
  glm::mat4 frame(glm::vec4(x, 0), glm::vec4(y, 0), glm::vec4(z, 0), glm::vec4(from, 1));
  const float head = std::min(0.04f, 0.4f * length), radius = 0.006f;
  const float shaft = length - head;
  rs.solids.push_back({Mesh::Cylinder,
                       glm::scale(glm::translate(frame, glm::vec3(0, shaft / 2, 0)), glm::vec3(radius, shaft, radius)),
                       color, -1, {}, false});
  rs.solids.push_back({Mesh::Cone,
                       glm::scale(glm::translate(frame, glm::vec3(0, shaft + head / 2, 0)), glm::vec3(2.5f * radius, head, 2.5f * radius)),
                       color, -1, {}, false});
}

void grow(RenderScene& rs, const glm::vec3& p, bool& first) {
  if (first) {
    rs.boundsMin = rs.boundsMax = p;
    first = false;
  }
  rs.boundsMin = glm::min(rs.boundsMin, p);
  rs.boundsMax = glm::max(rs.boundsMax, p);
}

// A unit cube stretched over the axis-aligned box [lo, hi].
glm::mat4 boxTransform(const glm::vec3& lo, const glm::vec3& hi) {
  return glm::scale(glm::translate(glm::mat4(1.0f), (lo + hi) * 0.5f), glm::max(hi - lo, glm::vec3(1e-4f)));
}

}  // namespace

namespace {
// Character c's pose at t: the motion's, or the zero pose without one.
Eigen::VectorXd characterPose(const std::vector<Model<double>>& models, const SolvedMotion* motion,
                              size_t c, double t) {
  if (motion && c < motion->animation.characters.size()) return poseAt(motion->animation.characters[c], t);
  return Eigen::VectorXd::Zero(models[c].dofCount());
}
}  // namespace

std::vector<Eigen::VectorXd> posesAt(const Scene&, const std::vector<Model<double>>& models,
                                     const SolvedMotion* motion, double t) {
  std::vector<Eigen::VectorXd> poses;
  for (size_t c = 0; c < models.size(); ++c) poses.push_back(characterPose(models, motion, c, t));
  return poses;
}

RenderScene buildRenderScene(const Scene& scene, const std::vector<Model<double>>& models,
                             const SolvedMotion* motion, const RenderOptions& o) {
  RenderScene rs;
  rs.ground = scene.groundEnabled;
  rs.groundHeight = static_cast<float>(scene.groundHeight);
  bool firstBound = true;
  if (models.size() != scene.characters.size()) return rs;

  // A preview (an iterate still being refined, or the starting guess) is drawn washed out towards
  // grey, so it is never taken for the result: mid-solve the lamp showed tilted 50 degrees at
  // t = 0, breaking its own start key, in its final colours.
  const bool preview = motion && !motion->solved;
  // The poses at t, with the unkeyed pose at the current time.
  auto posesShown = [&](double t, bool ghost) {
    std::vector<Eigen::VectorXd> poses = posesAt(scene, models, motion, t);
    if (!ghost && o.posedCharacter >= 0 && static_cast<size_t>(o.posedCharacter) < poses.size() &&
        o.posedQ.size() == poses[o.posedCharacter].size())
      poses[o.posedCharacter] = o.posedQ;
    return poses;
  };
  auto drawCharacters = [&](double t, bool ghost, float alpha) {
    const std::vector<Eigen::VectorXd> poses = posesShown(t, ghost);
    for (size_t c = 0; c < models.size(); ++c) {
      Data<double> d(models[c]);
      forwardKinematics(models[c], d, poses[c].data());
      for (const BodySpec& b : scene.characters[c].bodies) {
        const int i = models[c].bodyIndex(b.id);
        if (i < 0) continue;
        glm::vec4 color(toGlm(b.color), alpha);
        if (preview) color = glm::vec4(glm::mix(glm::vec3(color), glm::vec3(0.55f), kPreviewWash), alpha);
        if (!ghost && static_cast<int>(c) == o.selectedCharacter && b.id == o.selectedBody)
          color = glm::vec4(glm::mix(glm::vec3(color), glm::vec3(1.0f, 0.55f, 0.1f), 0.6f), 1.0f);
        addGeometry(rs, b.geometry, bodyPose(d, i), color, static_cast<int>(c), b.id, ghost);
      }
    }
  };
  drawCharacters(o.time, false, 1.0f);
  // The bodies' whole shapes at the current time belong in the bounds, not only their origins:
  // a biped's torso box reaches 0.5 m above its root, and Frame all cut it off.
  for (const Solid& s : rs.solids)
    if (!s.body.empty())
      for (int corner = 0; corner < 8; ++corner) {
        const glm::vec3 unit((corner & 1) ? 0.5f : -0.5f, (corner & 2) ? 0.5f : -0.5f, (corner & 4) ? 0.5f : -0.5f);
        grow(rs, glm::vec3(s.transform * glm::vec4(unit, 1.0f)), firstBound);
      }
  if (motion && o.ghosts > 0)
    for (int k = -o.ghosts; k <= o.ghosts; ++k) {
      const double t = o.time + k * o.ghostSpacing;
      if (k == 0 || t < scene.startTime - 1e-9 || t > scene.endTime + 1e-9) continue;
      drawCharacters(t, true, 0.35f - 0.05f * std::abs(k));
    }

  // Trails and bounds over the whole clip.
  const int frames = 121;
  for (size_t c = 0; c < models.size(); ++c) {
    const Model<double>& model = models[c];
    Data<double> d(model);
    Polyline com{{}, glm::vec4(0.95f, 0.3f, 0.25f, 1.0f)};
    Polyline trail{{}, glm::vec4(0.2f, 0.6f, 1.0f, 1.0f)};
    const bool trailHere = static_cast<int>(c) == o.selectedCharacter && !o.selectedBody.empty();
    const int trailBody = trailHere ? model.bodyIndex(o.selectedBody) : -1;
    for (int f = 0; f < frames; ++f) {
      const double t = scene.startTime + (scene.endTime - scene.startTime) * f / (frames - 1);
      const Eigen::VectorXd q = characterPose(models, motion, c, t);
      forwardKinematics(model, d, q.data());
      for (int b = 0; b < model.bodyCount(); ++b)
        if (!model.bodies[b].isVirtual) grow(rs, toGlm(d.X_world[b].r), firstBound);
      if (o.centerOfMass && model.totalMass() > 0) com.points.push_back(toGlm(centerOfMass(model, d)));
      if (o.trail && trailBody >= 0) trail.points.push_back(toGlm(d.X_world[trailBody].r));
    }
    if (motion && com.points.size() > 1) rs.lines.push_back(com);
    if (motion && trail.points.size() > 1) rs.lines.push_back(trail);
  }

  // Contact forces at the current time: arrows from each point, scaled by the weight.
  if (motion && o.forces)
    for (size_t c = 0; c < motion->animation.characters.size() && c < models.size(); ++c) {
      const CharacterAnimation& a = motion->animation.characters[c];
      if (a.times.empty()) continue;
      const double weight = models[c].totalMass() * std::max(1.0, scene.gravity.norm());
      const auto it = std::lower_bound(a.times.begin(), a.times.end(), o.time);
      const size_t f = std::min<size_t>(it - a.times.begin(), a.times.size() - 1);
      for (const ContactTrack& track : a.contacts) {
        const Eigen::Vector3d F = track.force[f];
        if (F.norm() < 1e-6 * weight) continue;
        const glm::vec3 from = toGlm(track.position[f]);
        addArrow(rs, from, from + toGlm(F / weight) * 0.5f, glm::vec4(0.2f, 0.85f, 0.3f, 1.0f));
      }
    }

  // Clearance obstacles. A height clearance is drawn as a block from the ground (or 1 cm below
  // the height without a ground) up to the height, under the point's path over the interval:
  // one box per path segment, as long as the segment and kObstacleDepth wide across it. A point
  // that barely moves (the zero pose before a solve) gets a kObstacleDepth square block. A
  // clearance at or below the ground is the ground itself and adds nothing.
  constexpr float kObstacleDepth = 0.3f;
  for (const TermSpec& t : scene.terms) {
    if (t.kind != TermKind::Clearance) continue;
    const glm::vec4 color = t.id == o.selectedTerm ? glm::vec4(1.0f, 0.55f, 0.1f, 0.45f) : glm::vec4(0.85f, 0.32f, 0.28f, 0.3f);
    Obstacle obstacle{t.id, {}};
    auto addBox = [&](const glm::mat4& m) { obstacle.boxes.push_back({Mesh::Cube, m, color, -1, {}, true}); };
    if (t.box) {
      const glm::vec3 lo = toGlm(t.boxMin), hi = toGlm(t.boxMax);
      addBox(boxTransform(lo, hi));
      grow(rs, lo, firstBound);
      grow(rs, hi, firstBound);
    } else {
      const CharacterSpec* ch = scene.character(t.character);
      const int c = ch ? static_cast<int>(ch - scene.characters.data()) : -1;
      const int b = c >= 0 ? models[c].bodyIndex(t.body) : -1;
      const float top = static_cast<float>(t.height);
      const float bottom = scene.groundEnabled ? static_cast<float>(scene.groundHeight) : top - 0.01f;
      if (b < 0 || top - bottom < 1e-3f) continue;
      std::vector<glm::vec2> path;  // the point's (x, z) over the interval
      const int steps = 24;
      Data<double> data(models[c]);  // one for the whole path: this runs at every rebuild
      for (int k = 0; k <= steps; ++k) {
        const double time = t.start + (t.end - t.start) * k / steps;
        const Eigen::VectorXd q = characterPose(models, motion, c, time);
        forwardKinematics(models[c], data, q.data());
        const glm::vec3 p = toGlm(pointPosition(data, b, t.point));
        path.emplace_back(p.x, p.z);
      }
      float travel = 0;
      for (size_t k = 1; k < path.size(); ++k) travel += glm::length(path[k] - path[k - 1]);
      if (travel < 0.02f) path = {path.front() - glm::vec2(kObstacleDepth / 2, 0), path.front() + glm::vec2(kObstacleDepth / 2, 0)};
      for (size_t k = 1; k < path.size(); ++k) {
        const glm::vec2 a = path[k - 1], d = path[k] - a;
        const float length = glm::length(d);
        if (length < 1e-5f) continue;
        const glm::vec2 mid = a + d * 0.5f, u = d / length;
        // Columns: the segment's direction, up, across; then the centre.
        glm::mat4 m(glm::vec4(u.x, 0, u.y, 0), glm::vec4(0, 1, 0, 0), glm::vec4(-u.y, 0, u.x, 0),
                    glm::vec4(mid.x, (top + bottom) / 2, mid.y, 1));
        addBox(glm::scale(m, glm::vec3(length, top - bottom, kObstacleDepth)));
      }
      grow(rs, glm::vec3(path.front().x, top, path.front().y), firstBound);
      grow(rs, glm::vec3(path.back().x, top, path.back().y), firstBound);
    }
    if (!obstacle.boxes.empty()) rs.obstacles.push_back(std::move(obstacle));
  }

  // Pin handles: the target, and where the pinned point is at the current time.
  const std::vector<Eigen::VectorXd> poses = posesShown(o.time, false);
  for (const TermSpec& t : scene.terms) {
    if (t.kind != TermKind::Pin) continue;
    const CharacterSpec* ch = scene.character(t.character);
    if (!ch) continue;
    const int c = static_cast<int>(ch - scene.characters.data());
    const int b = models[c].bodyIndex(t.body);
    if (b < 0) continue;
    Handle h;
    h.position = toGlm(t.position);
    h.bodyPoint = toGlm(bodyToWorld(models[c], poses[c], b, t.point));
    h.term = t.id;
    h.selected = t.id == o.selectedTerm;
    rs.handles.push_back(h);
    grow(rs, h.position, firstBound);
  }
  // The pose gizmo: a ring around the selected body's joint, perpendicular to its axis, a bit
  // larger than the body's reach from the joint, so a drag around it reads as turning the joint.
  if (o.poseGizmo && o.selectedCharacter >= 0 && static_cast<size_t>(o.selectedCharacter) < models.size()) {
    const int c = o.selectedCharacter;
    const int b = models[c].bodyIndex(o.selectedBody);
    const BodySpec* spec = scene.characters[c].body(o.selectedBody);
    if (const std::optional<PoseJoint> j = b >= 0 && spec ? poseJoint(models[c], poses[c], b) : std::nullopt) {
      const float radius = std::clamp(1.1f * static_cast<float>(geometryTip(spec->geometry).norm()), 0.08f, 0.6f);
      const Eigen::Vector3d helper = std::abs(j->axis.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
      const Eigen::Vector3d u = j->axis.cross(helper).normalized(), v = j->axis.cross(u);
      Polyline ring{{}, glm::vec4(1.0f, 0.8f, 0.15f, 1.0f)};
      for (int k = 0; k <= 48; ++k) {
        const double a = 2 * M_PI * k / 48;
        ring.points.push_back(toGlm(j->pivot + radius * (std::cos(a) * u + std::sin(a) * v)));
      }
      rs.lines.push_back(std::move(ring));
    }
  }
  return rs;
}

std::optional<PoseJoint> poseJoint(const Model<double>& model, const Eigen::VectorXd& q, int body) {
  if (body < 0 || body >= model.bodyCount()) return std::nullopt;
  const Body<double>& b = model.bodies[body];
  if (b.joint.type != JointType::Revolute || b.dofIndex < 0) return std::nullopt;
  Data<double> d(model);
  forwardKinematics(model, d, q.data());
  PoseJoint j;
  j.dof = b.dofIndex;
  j.pivot = d.X_world[body].r;
  j.axis = (d.X_world[body].E.transpose() * b.joint.axis).normalized();
  return j;
}

Eigen::Vector3d bodyToWorld(const Model<double>& model, const Eigen::VectorXd& q, int body,
                            const Eigen::Vector3d& local) {
  Data<double> d(model);
  forwardKinematics(model, d, q.data());
  return pointPosition(d, body, local);
}

Eigen::Vector3d worldToBody(const Model<double>& model, const Eigen::VectorXd& q, int body,
                            const Eigen::Vector3d& world) {
  Data<double> d(model);
  forwardKinematics(model, d, q.data());
  const Transform<double>& X = d.X_world[body];
  return X.E * (world - X.r);
}

std::optional<Pick> pickSolid(const RenderScene& rs, const glm::vec3& origin, const glm::vec3& direction) {
  std::optional<Pick> best;
  for (size_t i = 0; i < rs.solids.size(); ++i) {
    const Solid& s = rs.solids[i];
    if (s.ghost || s.character < 0) continue;
    // The ray in the unit mesh's coordinates; the parameter s is the same in both frames.
    const glm::mat4 inv = glm::inverse(s.transform);
    const glm::vec3 o = glm::vec3(inv * glm::vec4(origin, 1.0f));
    const glm::vec3 d = glm::vec3(inv * glm::vec4(direction, 0.0f));
    float hit = -1;
    if (s.mesh == Mesh::Cube) {  // slab test against [-0.5, 0.5]^3
      float t0 = -1e30f, t1 = 1e30f;
      bool miss = false;
      for (int a = 0; a < 3 && !miss; ++a) {
        if (std::abs(d[a]) < 1e-12f) {
          miss = std::abs(o[a]) > 0.5f;
          continue;
        }
        float ta = (-0.5f - o[a]) / d[a], tb = (0.5f - o[a]) / d[a];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
      }
      if (!miss && t0 <= t1 && t1 > 0) hit = t0 > 0 ? t0 : t1;
    } else {
      // Sphere: |o + s d| = 1. Cylinder and cone: x^2 + z^2 = 1 with |y| <= 0.5 (the cone's
      // bounding cylinder is close enough for picking).
      const bool sphere = s.mesh == Mesh::Sphere;
      const float a = sphere ? glm::dot(d, d) : d.x * d.x + d.z * d.z;
      const float b = sphere ? glm::dot(o, d) : o.x * d.x + o.z * d.z;
      const float c = sphere ? glm::dot(o, o) - 1 : o.x * o.x + o.z * o.z - 1;
      const float disc = b * b - a * c;
      if (a > 1e-12f && disc >= 0) {
        for (float t : {(-b - std::sqrt(disc)) / a, (-b + std::sqrt(disc)) / a})
          if (t > 0 && (sphere || std::abs(o.y + t * d.y) <= 0.5f)) {
            hit = t;
            break;
          }
      }
      if (!sphere && std::abs(d.y) > 1e-12f)  // the caps
        for (float yc : {-0.5f, 0.5f}) {
          const float t = (yc - o.y) / d.y;
          const glm::vec3 p = o + t * d;
          if (t > 0 && p.x * p.x + p.z * p.z <= 1 && (hit < 0 || t < hit)) hit = t;
        }
    }
    if (hit > 0 && (!best || hit < best->distance)) best = Pick{static_cast<int>(i), hit, origin + hit * direction};
  }
  return best;
}

}  // namespace spacetime::ui
