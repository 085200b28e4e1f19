// The scene file format (JSON, "format": "spacetime-scene", integer "formatVersion").
//
// The reader validates as it goes and stops at the first problem with a message that names the
// file, the field (as a JSON path), the value and what is allowed; it never throws to the caller
// and never crashes on malformed input. Unknown fields are rejected so typos do not silently
// vanish. The writer emits every field in a fixed order, so save -> load -> save is identical.
#include "core/scene_io.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "core/atomic_file.h"

namespace spacetime {
namespace {

using json = nlohmann::ordered_json;

struct SceneFormatError {
  std::string message;
};

class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  // Paths hold the file's own keys, which may be any length: messages stay one short line.
  [[noreturn]] void fail(const std::string& path, const std::string& what) const {
    throw SceneFormatError{file_ + ": field '" + shortened(path, 100) + "': " + what};
  }
  // Objects and arrays are described, not printed: printing recurses through their nesting,
  // and 100 000 levels of [ overflowed the stack.
  [[noreturn]] void badValue(const std::string& path, const json& v,
                             const std::string& expected) const {
    const std::string shown = v.is_object()  ? "an object"
                              : v.is_array() ? "an array of " + std::to_string(v.size()) + " elements"
                                             : shortened(v.dump(), 60);
    fail(path, "value " + shown + " is not allowed; expected " + expected);
  }
  static std::string shortened(const std::string& text, size_t limit) {
    return text.size() > limit ? text.substr(0, limit - 3) + "..." : text;
  }

  void allowKeys(const json& obj, const std::string& path,
                 std::initializer_list<const char*> keys) const {
    if (!obj.is_object()) badValue(path, obj, "an object");
    std::set<std::string> allowed(keys.begin(), keys.end());
    for (auto it = obj.begin(); it != obj.end(); ++it) {
      if (!allowed.count(it.key())) {
        std::string list;
        for (const auto& k : keys) list += std::string(list.empty() ? "" : ", ") + k;
        fail(join(path, it.key()), "unknown field; expected one of: " + list);
      }
    }
  }

  static std::string join(const std::string& path, const std::string& key) {
    return path.empty() ? key : path + "." + key;
  }
  static std::string index(const std::string& path, size_t i) {
    return path + "[" + std::to_string(i) + "]";
  }

  const json& required(const json& obj, const std::string& path, const char* key) const {
    if (!obj.contains(key)) fail(join(path, key), "missing required field");
    return obj.at(key);
  }

  double number(const json& v, const std::string& path) const {
    if (!v.is_number()) badValue(path, v, "a number");
    const double d = v.get<double>();
    if (!std::isfinite(d)) badValue(path, v, "a finite number");
    if (std::abs(d) > SceneLimits::kMaxMagnitude) badValue(path, v, "a number of magnitude at most 1e9");
    return d;
  }
  // A solver variable or multiplier: any finite number (a stopped solve's may be large).
  double finite(const json& v, const std::string& path) const {
    if (!v.is_number()) badValue(path, v, "a number");
    const double d = v.get<double>();
    if (!std::isfinite(d)) badValue(path, v, "a finite number");
    return d;
  }
  double positive(const json& v, const std::string& path) const {
    const double d = number(v, path);
    if (!(d > 0)) badValue(path, v, "a number > 0");
    return d;
  }
  double nonNegative(const json& v, const std::string& path) const {
    const double d = number(v, path);
    if (d < 0) badValue(path, v, "a number >= 0");
    return d;
  }
  int integer(const json& v, const std::string& path, int lo, int hi) const {
    if (!v.is_number_integer() || v.get<long long>() < lo || v.get<long long>() > hi)
      badValue(path, v, "an integer from " + std::to_string(lo) + " to " + std::to_string(hi));
    return v.get<int>();
  }
  bool boolean(const json& v, const std::string& path) const {
    if (!v.is_boolean()) badValue(path, v, "true or false");
    return v.get<bool>();
  }
  std::string string(const json& v, const std::string& path) const {
    if (!v.is_string()) badValue(path, v, "a string");
    return v.get<std::string>();
  }
  std::string identifier(const json& v, const std::string& path) const {
    const std::string s = string(v, path);
    bool ok = !s.empty();
    for (char c : s) ok = ok && (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-');
    if (!ok) badValue(path, v, "a non-empty id of letters, digits, '_' or '-'");
    // Ids name output files (<character>.urdf): a 300-character one solved, then failed to write.
    if (s.size() > SceneLimits::kMaxIdLength) badValue(path, v, "an id of at most 64 characters");
    return s;
  }
  Eigen::Vector3d vec3(const json& v, const std::string& path) const {
    if (!v.is_array() || v.size() != 3) badValue(path, v, "an array of 3 numbers");
    return {number(v[0], index(path, 0)), number(v[1], index(path, 1)),
            number(v[2], index(path, 2))};
  }
  template <class Enum>
  Enum choice(const json& v, const std::string& path,
              std::initializer_list<std::pair<const char*, Enum>> options) const {
    const std::string s = v.is_string() ? v.get<std::string>() : std::string();
    std::string list;
    for (const auto& [name, value] : options) {
      if (s == name) return value;
      list += std::string(list.empty() ? "" : ", ") + "\"" + name + "\"";
    }
    badValue(path, v, "one of " + list);
  }

 private:
  std::string file_;
};

Geometry readGeometry(const Reader& r, const json& g, const std::string& path) {
  r.allowKeys(g, path, {"type", "size", "radius", "length", "axis", "offset"});
  Geometry geo;
  geo.kind = r.choice<GeometryKind>(r.required(g, path, "type"), Reader::join(path, "type"),
                                    {{"none", GeometryKind::None},
                                     {"box", GeometryKind::Box},
                                     {"sphere", GeometryKind::Sphere},
                                     {"capsule", GeometryKind::Capsule},
                                     {"cylinder", GeometryKind::Cylinder}});
  switch (geo.kind) {
    case GeometryKind::Box: {
      geo.size = r.vec3(r.required(g, path, "size"), Reader::join(path, "size"));
      for (int i = 0; i < 3; ++i)
        if (!(geo.size[i] > 0))
          r.badValue(Reader::join(path, "size"), g["size"], "three extents > 0");
      break;
    }
    case GeometryKind::Sphere:
      geo.size[0] = r.positive(r.required(g, path, "radius"), Reader::join(path, "radius"));
      break;
    case GeometryKind::Capsule:
    case GeometryKind::Cylinder:
      geo.size[0] = r.positive(r.required(g, path, "radius"), Reader::join(path, "radius"));
      geo.size[1] = r.positive(r.required(g, path, "length"), Reader::join(path, "length"));
      if (g.contains("axis"))
        geo.axis = r.choice<int>(g["axis"], Reader::join(path, "axis"),
                                 {{"x", 0}, {"y", 1}, {"z", 2}});
      break;
    case GeometryKind::None: break;
  }
  if (g.contains("offset")) geo.offset = r.vec3(g["offset"], Reader::join(path, "offset"));
  return geo;
}

JointSpec readJoint(const Reader& r, const json& j, const std::string& path) {
  r.allowKeys(j, path,
              {"id", "type", "axis", "origin", "rpy", "pitch", "actuated", "limits",
               "torqueLimit", "speedLimit"});
  JointSpec js;
  js.id = r.identifier(r.required(j, path, "id"), Reader::join(path, "id"));
  js.kind = r.choice<JointKind>(r.required(j, path, "type"), Reader::join(path, "type"),
                                {{"revolute", JointKind::Revolute},
                                 {"prismatic", JointKind::Prismatic},
                                 {"helical", JointKind::Helical},
                                 {"fixed", JointKind::Fixed}});
  if (j.contains("axis")) {
    js.axis = r.vec3(j["axis"], Reader::join(path, "axis"));
    // Scaled by its largest component first: the squared norm of [0, 0, 1e200] overflows, and
    // normalising by it gave [0, 0, 0].
    const double largest = js.axis.cwiseAbs().maxCoeff();
    if (!(largest > 1e-9)) r.badValue(Reader::join(path, "axis"), j["axis"], "a non-zero vector");
    // An axis of unit length to rounding is kept as written: normalising it again can move its
    // last bit ([5, 0, 2] normalised, saved and reopened: 0.9284766908852592 became ...594), and a
    // saved scene must reopen as it was saved.
    if (!(std::abs(js.axis.norm() - 1) <= 4 * std::numeric_limits<double>::epsilon()))
      js.axis = (js.axis / largest).normalized();
  }
  if (j.contains("origin")) js.origin = r.vec3(j["origin"], Reader::join(path, "origin"));
  if (j.contains("rpy")) js.rpy = r.vec3(j["rpy"], Reader::join(path, "rpy"));
  if (j.contains("pitch")) js.pitch = r.number(j["pitch"], Reader::join(path, "pitch"));
  if (j.contains("actuated")) js.actuated = r.boolean(j["actuated"], Reader::join(path, "actuated"));
  if (j.contains("limits")) {
    const std::string p = Reader::join(path, "limits");
    const json& l = j["limits"];
    if (!l.is_array() || l.size() != 2) r.badValue(p, l, "[lower, upper]");
    const double lo = r.number(l[0], Reader::index(p, 0)), hi = r.number(l[1], Reader::index(p, 1));
    if (!(lo < hi)) r.badValue(p, l, "[lower, upper] with lower < upper");
    js.limits = std::make_pair(lo, hi);
  }
  if (j.contains("torqueLimit"))
    js.torqueLimit = r.positive(j["torqueLimit"], Reader::join(path, "torqueLimit"));
  if (j.contains("speedLimit"))
    js.speedLimit = r.positive(j["speedLimit"], Reader::join(path, "speedLimit"));
  return js;
}

BodySpec readBody(const Reader& r, const json& b, const std::string& path, bool isRoot) {
  r.allowKeys(b, path,
              {"id", "parent", "joint", "geometry", "mass", "density", "com", "inertia", "color"});
  BodySpec bs;
  bs.id = r.identifier(r.required(b, path, "id"), Reader::join(path, "id"));
  if (!isRoot) {
    bs.parent = r.identifier(r.required(b, path, "parent"), Reader::join(path, "parent"));
    bs.joint = readJoint(r, r.required(b, path, "joint"), Reader::join(path, "joint"));
  } else if (b.contains("parent") && !b["parent"].is_null()) {
    r.badValue(Reader::join(path, "parent"), b["parent"],
               "null: the first body is the root of the character");
  }
  if (b.contains("geometry"))
    bs.geometry = readGeometry(r, b["geometry"], Reader::join(path, "geometry"));
  if (b.contains("mass")) bs.mass = r.positive(b["mass"], Reader::join(path, "mass"));
  if (b.contains("density")) bs.density = r.positive(b["density"], Reader::join(path, "density"));
  if (bs.mass && bs.density)
    r.fail(Reader::join(path, "density"), "give either mass or density, not both");
  if (!bs.mass && !bs.density)
    r.fail(Reader::join(path, "mass"), "missing: every body needs a mass or a density");
  if (bs.density && bs.geometry.kind == GeometryKind::None)
    r.fail(Reader::join(path, "density"), "a density needs a geometry to give a volume");
  if (b.contains("com")) bs.com = r.vec3(b["com"], Reader::join(path, "com"));
  if (b.contains("inertia")) {
    const std::string p = Reader::join(path, "inertia");
    const json& I = b["inertia"];
    if (!I.is_array() || (I.size() != 3 && I.size() != 6))
      r.badValue(p, I, "[Ixx, Iyy, Izz] or [Ixx, Iyy, Izz, Ixy, Ixz, Iyz]");
    Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
    for (int i = 0; i < 3; ++i) m(i, i) = r.number(I[i], Reader::index(p, i));
    if (I.size() == 6) {
      m(0, 1) = m(1, 0) = r.number(I[3], Reader::index(p, 3));
      m(0, 2) = m(2, 0) = r.number(I[4], Reader::index(p, 4));
      m(1, 2) = m(2, 1) = r.number(I[5], Reader::index(p, 5));
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(m);
    const Eigen::Vector3d ev = es.eigenvalues();
    if (ev.minCoeff() < 0 || ev[0] + ev[1] < ev[2] * (1 - 1e-9))
      r.badValue(p, I, "a positive semi-definite inertia satisfying the triangle inequality");
    bs.inertia = m;
  } else if (bs.geometry.kind == GeometryKind::None && !isRoot) {
    // A point mass is allowed (zero rotational inertia) only where no rotation acts on it alone.
  }
  if (b.contains("color")) bs.color = r.vec3(b["color"], Reader::join(path, "color"));
  return bs;
}

// The transcription's size (SceneLimits): checked before anything grows with it.
void checkSize(const Reader& r, const Scene& s) {
  const double segments = s.transcription.segments(s.startTime, s.endTime);
  char what[200];
  if (segments > SceneLimits::kMaxSegments) {
    std::snprintf(what, sizeof what,
                  "%.3g spline segments ((time.end - time.start) x controlPointsPerSecond); at most %.0f",
                  segments, SceneLimits::kMaxSegments);
    r.fail("transcription.controlPointsPerSecond", what);
  }
  double work = 0;
  for (const CharacterSpec& c : s.characters)
    work += std::pow(static_cast<double>(c.bodies.size() + 6), 2) * std::max(1.0, segments) * s.transcription.samplesPerSegment;
  if (work > SceneLimits::kMaxWork) {
    std::snprintf(what, sizeof what,
                  "a problem of size %.3g ((bodies + 6)^2 x segments x samplesPerSegment, summed over the "
                  "characters); at most %.3g",
                  work, SceneLimits::kMaxWork);
    r.fail("transcription", what);
  }
}

CharacterSpec readCharacter(const Reader& r, const json& c, const std::string& path) {
  r.allowKeys(c, path, {"id", "root", "rootActuated", "bodies"});
  CharacterSpec cs;
  cs.id = r.identifier(r.required(c, path, "id"), Reader::join(path, "id"));
  cs.root = r.choice<RootKind>(r.required(c, path, "root"), Reader::join(path, "root"),
                               {{"fixed", RootKind::Fixed},
                                {"planar", RootKind::Planar},
                                {"floating3d", RootKind::Floating3D},
                                {"translation3d", RootKind::Translation3D}});
  if (c.contains("rootActuated"))
    cs.rootActuated = r.boolean(c["rootActuated"], Reader::join(path, "rootActuated"));
  const std::string bp = Reader::join(path, "bodies");
  const json& bodies = r.required(c, path, "bodies");
  if (!bodies.is_array() || bodies.empty()) r.badValue(bp, bodies, "a non-empty array of bodies");
  if (bodies.size() > SceneLimits::kMaxBodies)
    r.fail(bp, std::to_string(bodies.size()) + " bodies; a character has at most " + std::to_string(SceneLimits::kMaxBodies));
  std::set<std::string> seen, dofs;
  for (size_t i = 0; i < bodies.size(); ++i) {
    BodySpec b = readBody(r, bodies[i], Reader::index(bp, i), i == 0);
    if (seen.count(b.id)) r.badValue(Reader::join(Reader::index(bp, i), "id"), b.id, "a unique body id");
    if (i > 0 && !seen.count(b.parent))
      r.badValue(Reader::join(Reader::index(bp, i), "parent"), b.parent,
                 "the id of a body listed before this one");
    seen.insert(b.id);
    cs.bodies.push_back(std::move(b));
  }
  for (const auto& n : cs.dofNames()) {
    if (dofs.count(n)) r.fail(bp, "two degrees of freedom are named '" + n + "'");
    dofs.insert(n);
  }
  return cs;
}

TermSpec readTerm(const Reader& r, const json& t, const std::string& path, const Scene& scene) {
  TermSpec ts;
  ts.kind = r.choice<TermKind>(r.required(t, path, "type"), Reader::join(path, "type"),
                               {{"pin", TermKind::Pin},
                                {"keyframe", TermKind::Keyframe},
                                {"rest", TermKind::Rest},
                                {"contact", TermKind::Contact},
                                {"clearance", TermKind::Clearance},
                                {"formula", TermKind::Formula}});
  switch (ts.kind) {
    case TermKind::Pin:
      r.allowKeys(t, path, {"id", "type", "enabled", "character", "body", "point", "position",
                            "time", "until", "axes"});
      break;
    case TermKind::Keyframe:
      r.allowKeys(t, path, {"id", "type", "enabled", "character", "time", "values"});
      break;
    case TermKind::Rest:
      r.allowKeys(t, path, {"id", "type", "enabled", "character", "body", "time"});
      break;
    case TermKind::Contact:
      r.allowKeys(t, path, {"id", "type", "enabled", "character", "body", "points", "start",
                            "end", "friction", "impact", "freeEnd", "freeEndWindow"});
      break;
    case TermKind::Clearance:
      r.allowKeys(t, path, {"id", "type", "enabled", "character", "body", "point", "start",
                            "end", "height", "box"});
      break;
    case TermKind::Formula:
      r.allowKeys(t, path, {"id", "type", "enabled", "character", "expression", "relation",
                            "value", "time", "start", "end"});
      break;
  }
  ts.id = r.identifier(r.required(t, path, "id"), Reader::join(path, "id"));
  if (t.contains("enabled")) ts.enabled = r.boolean(t["enabled"], Reader::join(path, "enabled"));
  const std::string cp = Reader::join(path, "character");
  ts.character = r.string(r.required(t, path, "character"), cp);
  const CharacterSpec* ch = scene.character(ts.character);
  if (!ch) r.badValue(cp, ts.character, "the id of a character in this scene");

  auto readTime = [&](const char* key) {
    const std::string p = Reader::join(path, key);
    const double v = r.number(r.required(t, path, key), p);
    if (v < scene.startTime - 1e-12 || v > scene.endTime + 1e-12)
      r.badValue(p, t[key], "a time within the scene's range [" +
                                std::to_string(scene.startTime) + ", " +
                                std::to_string(scene.endTime) + "]");
    return v;
  };
  auto readBodyRef = [&](bool required) {
    if (!required && !t.contains("body")) return;
    const std::string p = Reader::join(path, "body");
    ts.body = r.string(r.required(t, path, "body"), p);
    if (!ch->body(ts.body)) r.badValue(p, ts.body, "the id of a body of character '" + ch->id + "'");
  };

  switch (ts.kind) {
    case TermKind::Pin: {
      readBodyRef(true);
      if (t.contains("point")) ts.point = r.vec3(t["point"], Reader::join(path, "point"));
      ts.position = r.vec3(r.required(t, path, "position"), Reader::join(path, "position"));
      ts.time = readTime("time");
      if (t.contains("until")) {
        ts.until = readTime("until");
        if (!(*ts.until > ts.time))
          r.badValue(Reader::join(path, "until"), t["until"], "a time after 'time'");
      }
      if (t.contains("axes")) {
        const std::string p = Reader::join(path, "axes");
        const std::string a = r.string(t["axes"], p);
        ts.axes = {false, false, false};
        for (char c : a) {
          if (c < 'x' || c > 'z') r.badValue(p, t["axes"], "a subset of \"xyz\", such as \"xz\"");
          ts.axes[c - 'x'] = true;
        }
        if (a.empty()) r.badValue(p, t["axes"], "a non-empty subset of \"xyz\"");
      }
      break;
    }
    case TermKind::Keyframe: {
      ts.time = readTime("time");
      const std::string p = Reader::join(path, "values");
      const json& v = r.required(t, path, "values");
      if (!v.is_object() || v.empty()) r.badValue(p, v, "an object mapping joint names to values");
      const auto names = ch->dofNames();
      for (auto it = v.begin(); it != v.end(); ++it) {
        if (std::find(names.begin(), names.end(), it.key()) == names.end()) {
          std::string list;
          for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
          r.fail(Reader::join(p, it.key()), "unknown degree of freedom; expected one of: " + list);
        }
        ts.values.emplace_back(it.key(), r.number(it.value(), Reader::join(p, it.key())));
      }
      break;
    }
    case TermKind::Rest:
      readBodyRef(false);
      ts.time = readTime("time");
      break;
    case TermKind::Contact: {
      readBodyRef(true);
      const std::string p = Reader::join(path, "points");
      const json& pts = r.required(t, path, "points");
      if (!pts.is_array() || pts.empty()) r.badValue(p, pts, "a non-empty array of body points");
      for (size_t i = 0; i < pts.size(); ++i) ts.points.push_back(r.vec3(pts[i], Reader::index(p, i)));
      ts.start = readTime("start");
      ts.end = readTime("end");
      if (!(ts.end > ts.start)) r.badValue(Reader::join(path, "end"), t["end"], "a time after 'start'");
      if (t.contains("friction"))
        ts.friction = r.nonNegative(t["friction"], Reader::join(path, "friction"));
      if (t.contains("impact")) ts.impact = r.boolean(t["impact"], Reader::join(path, "impact"));
      if (t.contains("freeEnd")) ts.freeEnd = r.boolean(t["freeEnd"], Reader::join(path, "freeEnd"));
      if (t.contains("freeEndWindow")) {
        ts.freeEndWindow = r.nonNegative(t["freeEndWindow"], Reader::join(path, "freeEndWindow"));
      }
      break;
    }
    case TermKind::Clearance:
      readBodyRef(true);
      if (t.contains("point")) ts.point = r.vec3(t["point"], Reader::join(path, "point"));
      ts.start = readTime("start");
      ts.end = readTime("end");
      if (!(ts.end > ts.start)) r.badValue(Reader::join(path, "end"), t["end"], "a time after 'start'");
      if (t.contains("box")) {
        const std::string p = Reader::join(path, "box");
        const json& b = t["box"];
        r.allowKeys(b, p, {"min", "max"});
        ts.box = true;
        ts.boxMin = r.vec3(r.required(b, p, "min"), Reader::join(p, "min"));
        ts.boxMax = r.vec3(r.required(b, p, "max"), Reader::join(p, "max"));
        if (!(ts.boxMin.array() < ts.boxMax.array()).all())
          r.badValue(Reader::join(p, "max"), b["max"], "a corner above 'min' on every axis");
        if (t.contains("height")) r.fail(Reader::join(path, "height"), "give either 'height' or 'box', not both");
      } else {
        ts.height = r.number(r.required(t, path, "height"), Reader::join(path, "height"));
      }
      break;
    case TermKind::Formula: {
      ts.expression = r.string(r.required(t, path, "expression"), Reader::join(path, "expression"));
      if (ts.expression.empty()) r.badValue(Reader::join(path, "expression"), t["expression"], "a formula");
      if (t.contains("relation"))
        ts.relation = r.choice<char>(t["relation"], Reader::join(path, "relation"),
                                     {{"=", '='}, {"<=", '<'}, {">=", '>'}});
      if (t.contains("value")) ts.value = r.number(t["value"], Reader::join(path, "value"));
      if (t.contains("time")) {
        ts.time = readTime("time");
        if (t.contains("start") || t.contains("end"))
          r.fail(Reader::join(path, "time"), "give either 'time' or 'start' and 'end', not both");
      } else {
        ts.start = readTime("start");
        ts.end = readTime("end");
        if (!(ts.end > ts.start)) r.badValue(Reader::join(path, "end"), t["end"], "a time after 'start'");
        ts.interval = true;
      }
      break;
    }
  }
  return ts;
}

Scene readScene(const Reader& r, const json& root) {
  r.allowKeys(root, "",
              {"format", "formatVersion", "name", "units", "time", "gravity", "ground",
               "transcription", "solver", "characters", "terms", "objective", "solution"});
  const json& fmt = r.required(root, "", "format");
  if (fmt != "spacetime-scene") r.badValue("format", fmt, "\"spacetime-scene\"");
  const int version = r.integer(r.required(root, "", "formatVersion"), "formatVersion", 1, 1 << 20);
  if (version > kSceneFormatVersion)
    r.badValue("formatVersion", version,
               "a version up to " + std::to_string(kSceneFormatVersion) +
                   " (this file was written by a newer Spacetime)");
  Scene s;
  if (root.contains("name")) s.name = r.string(root["name"], "name");
  if (root.contains("units")) {
    const json& u = root["units"];
    r.allowKeys(u, "units", {"length", "mass", "time", "angle"});
    const std::pair<const char*, const char*> expected[] = {
        {"length", "m"}, {"mass", "kg"}, {"time", "s"}, {"angle", "rad"}};
    for (const auto& [key, unit] : expected)
      if (u.contains(key) && u[key] != unit)
        r.badValue(std::string("units.") + key, u[key], std::string("\"") + unit + "\" (SI units only)");
  }
  const json& time = r.required(root, "", "time");
  r.allowKeys(time, "time", {"start", "end", "frameRate"});
  s.startTime = r.number(r.required(time, "time", "start"), "time.start");
  s.endTime = r.number(r.required(time, "time", "end"), "time.end");
  if (!(s.endTime > s.startTime)) r.badValue("time.end", time["end"], "a time after time.start");
  if (time.contains("frameRate")) {
    s.frameRate = r.number(time["frameRate"], "time.frameRate");
    if (!(s.frameRate >= 1 && s.frameRate <= Scene::kMaxFrameRate))
      r.badValue("time.frameRate", time["frameRate"], "a number of frames per second from 1 to 1000");
  }
  if (root.contains("gravity")) s.gravity = r.vec3(root["gravity"], "gravity");
  if (root.contains("ground")) {
    const json& g = root["ground"];
    r.allowKeys(g, "ground", {"enabled", "height"});
    if (g.contains("enabled")) s.groundEnabled = r.boolean(g["enabled"], "ground.enabled");
    if (g.contains("height")) s.groundHeight = r.number(g["height"], "ground.height");
  }
  if (root.contains("transcription")) {
    const json& t = root["transcription"];
    r.allowKeys(t, "transcription", {"controlPointsPerSecond", "samplesPerSegment", "legBubbles", "knots"});
    if (t.contains("controlPointsPerSecond"))
      s.transcription.controlPointsPerSecond =
          r.positive(t["controlPointsPerSecond"], "transcription.controlPointsPerSecond");
    if (t.contains("samplesPerSegment"))
      s.transcription.samplesPerSegment =
          r.integer(t["samplesPerSegment"], "transcription.samplesPerSegment", 1,
                    TranscriptionSpec::kMaxSamplesPerSegment);
    if (t.contains("legBubbles")) s.transcription.legBubbles = r.boolean(t["legBubbles"], "transcription.legBubbles");
    if (t.contains("knots")) {
      const json& k = t["knots"];
      if (!k.is_array()) r.badValue("transcription.knots", k, "an array of increasing times inside the clip");
      for (size_t i = 0; i < k.size(); ++i) {
        const std::string path = Reader::index("transcription.knots", i);
        const double v = r.number(k[i], path);
        const double after = s.transcription.knots.empty() ? s.startTime : s.transcription.knots.back();
        if (!TranscriptionSpec::knotFollows(after, v, s.endTime))
          r.badValue(path, k[i], "a time at least 1e-4 s after " + std::string(i ? "the knot before it" : "time.start") +
                                     " and before time.end");
        s.transcription.knots.push_back(v);
      }
    }
  }
  if (root.contains("solver")) {
    const json& t = root["solver"];
    r.allowKeys(t, "solver", {"method", "maxOuterIterations", "maxInnerIterations", "tolerance", "maxPenalty",
                                  "bodiesAboveGround", "maxRefinements", "maxSeconds"});
    if (t.contains("method")) {
      s.solver.method = r.string(t["method"], "solver.method");
      if (std::find(std::begin(SolverSpec::kMethods), std::end(SolverSpec::kMethods), s.solver.method) ==
          std::end(SolverSpec::kMethods))
        r.badValue("solver.method", t["method"], "\"al\", \"ipopt\", \"sqp\" or \"witkin-kass\"");
    }
    if (t.contains("bodiesAboveGround"))
      s.solver.bodiesAboveGround = r.boolean(t["bodiesAboveGround"], "solver.bodiesAboveGround");
    if (t.contains("maxSeconds")) {
      s.solver.maxSeconds = r.positive(t["maxSeconds"], "solver.maxSeconds");
      if (s.solver.maxSeconds > SolverSpec::kMaxSeconds)
        r.badValue("solver.maxSeconds", t["maxSeconds"], "a number of seconds in (0, 1e7]");
    }
    if (t.contains("maxRefinements"))
      s.solver.maxRefinements =
          r.integer(t["maxRefinements"], "solver.maxRefinements", 0, SolverSpec::kMaxRefinements);
    if (t.contains("maxOuterIterations"))
      s.solver.maxOuterIterations = r.integer(t["maxOuterIterations"], "solver.maxOuterIterations", 1, 1000);
    if (t.contains("maxInnerIterations"))
      s.solver.maxInnerIterations = r.integer(t["maxInnerIterations"], "solver.maxInnerIterations", 1, 100000);
    if (t.contains("tolerance")) s.solver.tolerance = r.positive(t["tolerance"], "solver.tolerance");
    if (t.contains("maxPenalty")) {
      s.solver.maxPenalty = r.number(t["maxPenalty"], "solver.maxPenalty");
      if (!(s.solver.maxPenalty >= SolverSpec::kMinPenalty))
        r.badValue("solver.maxPenalty", t["maxPenalty"],
                   "a number >= " + std::to_string(static_cast<int>(SolverSpec::kMinPenalty)) +
                       " (the starting penalty)");
    }
  }
  const json& chars = r.required(root, "", "characters");
  if (!chars.is_array() || chars.empty()) r.badValue("characters", chars, "a non-empty array");
  if (chars.size() > SceneLimits::kMaxCharacters)
    r.fail("characters", std::to_string(chars.size()) + " characters; a scene has at most " +
                             std::to_string(SceneLimits::kMaxCharacters));
  for (size_t i = 0; i < chars.size(); ++i) {
    CharacterSpec c = readCharacter(r, chars[i], Reader::index("characters", i));
    if (s.character(c.id))
      r.badValue(Reader::join(Reader::index("characters", i), "id"), c.id, "a unique character id");
    s.characters.push_back(std::move(c));
  }
  if (root.contains("terms")) {
    const json& terms = root["terms"];
    if (!terms.is_array()) r.badValue("terms", terms, "an array");
    if (terms.size() > SceneLimits::kMaxTerms)
      r.fail("terms", std::to_string(terms.size()) + " terms; a scene has at most " + std::to_string(SceneLimits::kMaxTerms));
    std::set<std::string> ids;
    for (size_t i = 0; i < terms.size(); ++i) {
      TermSpec t = readTerm(r, terms[i], Reader::index("terms", i), s);
      if (ids.count(t.id)) r.badValue(Reader::join(Reader::index("terms", i), "id"), t.id, "a unique term id");
      ids.insert(t.id);
      s.terms.push_back(std::move(t));
    }
  }
  if (root.contains("objective")) {
    const json& o = root["objective"];
    r.allowKeys(o, "objective",
                {"effort", "power", "smoothness", "smoothnessOrder", "contactForce", "formulas"});
    if (o.contains("contactForce"))
      s.objective.contactForce = r.nonNegative(o["contactForce"], "objective.contactForce");
    if (o.contains("formulas")) {
      const json& fs = o["formulas"];
      if (!fs.is_array()) r.badValue("objective.formulas", fs, "an array of {character, expression, weight}");
      for (size_t i = 0; i < fs.size(); ++i) {
        const std::string p = Reader::index("objective.formulas", i);
        r.allowKeys(fs[i], p, {"character", "expression", "weight"});
        FormulaObjective f;
        f.character = r.string(r.required(fs[i], p, "character"), Reader::join(p, "character"));
        if (!s.character(f.character))
          r.badValue(Reader::join(p, "character"), f.character, "the id of a character in this scene");
        f.expression = r.string(r.required(fs[i], p, "expression"), Reader::join(p, "expression"));
        if (fs[i].contains("weight")) f.weight = r.nonNegative(fs[i]["weight"], Reader::join(p, "weight"));
        s.objective.formulas.push_back(f);
      }
    }
    if (o.contains("effort")) s.objective.effort = r.nonNegative(o["effort"], "objective.effort");
    if (o.contains("power")) s.objective.power = r.nonNegative(o["power"], "objective.power");
    if (o.contains("smoothness"))
      s.objective.smoothness = r.nonNegative(o["smoothness"], "objective.smoothness");
    if (o.contains("smoothnessOrder"))
      s.objective.smoothnessOrder = r.integer(o["smoothnessOrder"], "objective.smoothnessOrder", 2, 3);
    if (s.objective.effort + s.objective.power + s.objective.smoothness <= 0 &&
        s.objective.formulas.empty())
      r.fail("objective", "at least one objective weight must be > 0");
  }
  if (root.contains("solution")) {
    const json& j = root["solution"];
    r.allowKeys(j, "solution", {"variables", "multipliers", "rho", "converged"});
    StoredSolution sol;
    auto numbers = [&](const char* key, std::vector<double>& out) {
      const std::string path = Reader::join("solution", key);
      const json& a = r.required(j, "solution", key);
      if (!a.is_array()) r.badValue(path, a, "an array of numbers");
      out.reserve(a.size());
      for (size_t i = 0; i < a.size(); ++i) out.push_back(r.finite(a[i], Reader::index(path, i)));
    };
    numbers("variables", sol.variables);
    numbers("multipliers", sol.multipliers);
    if (j.contains("rho")) sol.rho = std::max(0.0, r.finite(j["rho"], "solution.rho"));
    if (j.contains("converged")) sol.converged = r.boolean(j["converged"], "solution.converged");
    s.solution = std::move(sol);
  }
  checkSize(r, s);
  return s;
}

json vec(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

json writeBody(const BodySpec& b, bool isRoot) {
  json j;
  j["id"] = b.id;
  if (!isRoot) {
    j["parent"] = b.parent;
    json jt;
    jt["id"] = b.joint.id;
    jt["type"] = toString(b.joint.kind);
    jt["axis"] = vec(b.joint.axis);
    jt["origin"] = vec(b.joint.origin);
    if (b.joint.rpy != Eigen::Vector3d::Zero()) jt["rpy"] = vec(b.joint.rpy);
    if (b.joint.kind == JointKind::Helical) jt["pitch"] = b.joint.pitch;
    jt["actuated"] = b.joint.actuated;
    if (b.joint.limits) jt["limits"] = json::array({b.joint.limits->first, b.joint.limits->second});
    if (b.joint.torqueLimit) jt["torqueLimit"] = *b.joint.torqueLimit;
    if (b.joint.speedLimit) jt["speedLimit"] = *b.joint.speedLimit;
    j["joint"] = jt;
  }
  if (b.geometry.kind != GeometryKind::None) {
    json g;
    g["type"] = toString(b.geometry.kind);
    switch (b.geometry.kind) {
      case GeometryKind::Box: g["size"] = vec(b.geometry.size); break;
      case GeometryKind::Sphere: g["radius"] = b.geometry.size[0]; break;
      default:
        g["radius"] = b.geometry.size[0];
        g["length"] = b.geometry.size[1];
        g["axis"] = std::string(1, static_cast<char>('x' + b.geometry.axis));
    }
    g["offset"] = vec(b.geometry.offset);
    j["geometry"] = g;
  }
  if (b.mass) j["mass"] = *b.mass;
  if (b.density) j["density"] = *b.density;
  if (b.com) j["com"] = vec(*b.com);
  if (b.inertia) {
    const auto& I = *b.inertia;
    j["inertia"] = json::array({I(0, 0), I(1, 1), I(2, 2), I(0, 1), I(0, 2), I(1, 2)});
  }
  j["color"] = vec(b.color);
  return j;
}

json writeTerm(const TermSpec& t) {
  json j;
  j["id"] = t.id;
  j["type"] = toString(t.kind);
  if (!t.enabled) j["enabled"] = false;
  j["character"] = t.character;
  switch (t.kind) {
    case TermKind::Pin: {
      j["body"] = t.body;
      j["point"] = vec(t.point);
      j["position"] = vec(t.position);
      j["time"] = t.time;
      if (t.until) j["until"] = *t.until;
      std::string axes;
      for (int i = 0; i < 3; ++i)
        if (t.axes[i]) axes += static_cast<char>('x' + i);
      j["axes"] = axes;
      break;
    }
    case TermKind::Keyframe: {
      j["time"] = t.time;
      json v = json::object();
      for (const auto& [k, val] : t.values) v[k] = val;
      j["values"] = v;
      break;
    }
    case TermKind::Rest:
      if (!t.body.empty()) j["body"] = t.body;
      j["time"] = t.time;
      break;
    case TermKind::Contact: {
      j["body"] = t.body;
      json pts = json::array();
      for (const auto& p : t.points) pts.push_back(vec(p));
      j["points"] = pts;
      j["start"] = t.start;
      j["end"] = t.end;
      j["friction"] = t.friction;
      j["impact"] = t.impact;
      if (t.freeEnd) {
        j["freeEnd"] = true;
        j["freeEndWindow"] = t.freeEndWindow;
      }
      break;
    }
    case TermKind::Clearance:
      j["body"] = t.body;
      j["point"] = vec(t.point);
      j["start"] = t.start;
      j["end"] = t.end;
      if (t.box)
        j["box"] = {{"min", vec(t.boxMin)}, {"max", vec(t.boxMax)}};
      else
        j["height"] = t.height;
      break;
    case TermKind::Formula:
      j["expression"] = t.expression;
      j["relation"] = t.relation == '=' ? "=" : t.relation == '<' ? "<=" : ">=";
      j["value"] = t.value;
      if (t.interval) {
        j["start"] = t.start;
        j["end"] = t.end;
      } else {
        j["time"] = t.time;
      }
      break;
  }
  return j;
}

// How deeply arrays and objects nest in JSON text (brackets inside strings skipped). The JSON
// library parses and copies nested values recursively: 100 000 levels overflowed the stack.
int nestingDepth(const std::string& text) {
  int depth = 0, deepest = 0;
  bool inString = false, escaped = false;
  for (char ch : text) {
    if (inString) {
      if (escaped) escaped = false;
      else if (ch == '\\') escaped = true;
      else if (ch == '"') inString = false;
    } else if (ch == '"') {
      inString = true;
    } else if (ch == '[' || ch == '{') {
      deepest = std::max(deepest, ++depth);
    } else if (ch == ']' || ch == '}') {
      --depth;
    }
  }
  return deepest;
}

// An error as one line of at most kMaxErrorLength bytes, cut at a character boundary: the JSON
// library quotes what it last read ("last read: '...'"), which can be a whole line of the file
// (found by the loader's fuzzer: a 400-character message).
constexpr size_t kMaxErrorLength = 300;
std::string oneLine(std::string message) {
  for (char& c : message)
    if (c == '\n' || c == '\r' || c == '\t') c = ' ';
  if (message.size() <= kMaxErrorLength) return message;
  size_t cut = kMaxErrorLength - 3;
  while (cut > 0 && (static_cast<unsigned char>(message[cut]) & 0xC0) == 0x80) --cut;  // not inside a character
  return message.substr(0, cut) + "...";
}

// The scene in `text`, or its error as the reader words it (parseScene makes it one short line).
SceneLoadResult parseSceneText(const std::string& text, const std::string& sourceName) {
  constexpr int kMaxNesting = 64;  // a scene needs 6
  SceneLoadResult result;
  if (const int depth = nestingDepth(text); depth > kMaxNesting) {
    result.error = sourceName + ": not a scene: arrays and objects nested " + std::to_string(depth) +
                   " levels deep (at most " + std::to_string(kMaxNesting) + ")";
    return result;
  }
  json root;
  try {
    root = json::parse(text);
  } catch (const json::exception& e) {  // parse_error, and out_of_range for 1e999
    result.error = sourceName + ": not valid JSON: " + e.what();
    return result;
  }
  try {
    result.scene = readScene(Reader(sourceName), root);
  } catch (const SceneFormatError& e) {
    result.error = e.message;
  } catch (const std::exception& e) {
    result.error = sourceName + ": " + e.what();
  }
  return result;
}

}  // namespace

SceneLoadResult parseScene(const std::string& text, const std::string& sourceName) {
  SceneLoadResult result = parseSceneText(text, sourceName);
  if (!result.scene) result.error = oneLine(std::move(result.error));
  return result;
}

SceneLoadResult loadSceneFile(const std::string& path) {
  std::string text, error;
  if (!readWholeFile(path, &text, &error)) return {std::nullopt, error};
  return parseScene(text, path);
}

std::string sceneToJson(const Scene& s) {
  json root;
  root["format"] = "spacetime-scene";
  root["formatVersion"] = kSceneFormatVersion;
  root["name"] = s.name;
  root["units"] = {{"length", "m"}, {"mass", "kg"}, {"time", "s"}, {"angle", "rad"}};
  root["time"] = {{"start", s.startTime}, {"end", s.endTime}, {"frameRate", s.frameRate}};
  root["gravity"] = vec(s.gravity);
  root["ground"] = {{"enabled", s.groundEnabled}, {"height", s.groundHeight}};
  root["transcription"] = {{"controlPointsPerSecond", s.transcription.controlPointsPerSecond},
                           {"samplesPerSegment", s.transcription.samplesPerSegment}};
  if (s.transcription.legBubbles) root["transcription"]["legBubbles"] = true;
  if (!s.transcription.knots.empty()) root["transcription"]["knots"] = s.transcription.knots;
  root["solver"] = {{"method", s.solver.method},
                    {"maxOuterIterations", s.solver.maxOuterIterations},
                    {"maxInnerIterations", s.solver.maxInnerIterations},
                    {"tolerance", s.solver.tolerance},
                    {"maxPenalty", s.solver.maxPenalty},
                    {"bodiesAboveGround", s.solver.bodiesAboveGround},
                    {"maxRefinements", s.solver.maxRefinements},
                    {"maxSeconds", s.solver.maxSeconds}};
  json chars = json::array();
  for (const auto& c : s.characters) {
    json jc;
    jc["id"] = c.id;
    jc["root"] = toString(c.root);
    if (c.rootActuated) jc["rootActuated"] = true;
    json bodies = json::array();
    for (size_t i = 0; i < c.bodies.size(); ++i) bodies.push_back(writeBody(c.bodies[i], i == 0));
    jc["bodies"] = bodies;
    chars.push_back(jc);
  }
  root["characters"] = chars;
  json terms = json::array();
  for (const auto& t : s.terms) terms.push_back(writeTerm(t));
  root["terms"] = terms;
  root["objective"] = {{"effort", s.objective.effort},
                       {"power", s.objective.power},
                       {"smoothness", s.objective.smoothness},
                       {"smoothnessOrder", s.objective.smoothnessOrder},
                       {"contactForce", s.objective.contactForce}};
  if (!s.objective.formulas.empty()) {
    json fs = json::array();
    for (const FormulaObjective& f : s.objective.formulas)
      fs.push_back({{"character", f.character}, {"expression", f.expression}, {"weight", f.weight}});
    root["objective"]["formulas"] = fs;
  }
  if (s.solution)
    root["solution"] = {{"variables", s.solution->variables},
                        {"multipliers", s.solution->multipliers},
                        {"rho", s.solution->rho},
                        {"converged", s.solution->converged}};
  return root.dump(2) + "\n";
}

bool saveSceneFile(const Scene& scene, const std::string& path, std::string* error) {
  return writeFileAtomically(path, sceneToJson(scene), error);
}

}  // namespace spacetime
