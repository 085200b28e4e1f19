// Reading motion.json back into an Animation (see motion_import.h). Every field the writer
// (outputs.cpp, motionJson) puts there is checked: a wrong one is named with its path, e.g.
// "field 'characters[0].q[12]': expected 6 numbers, one per dof".
#include "interop/motion_import.h"

#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <utility>

#include "core/atomic_file.h"

namespace spacetime {
namespace {

using json = nlohmann::json;

// A field's path (e.g. "characters[0].q[12]") and what is wrong with it.
struct FieldError : std::runtime_error {
  FieldError(std::string path, const std::string& what) : std::runtime_error(what), path(std::move(path)) {}
  std::string path;
};

const json& field(const json& parent, const std::string& name, const std::string& at) {
  if (!parent.is_object() || !parent.contains(name)) throw FieldError(at + name, "missing required field");
  return parent[name];
}

double number(const json& v, const std::string& at) {
  if (!v.is_number() || !std::isfinite(v.get<double>())) throw FieldError(at, "expected a finite number");
  return v.get<double>();
}

Eigen::Vector3d vec3(const json& v, const std::string& at) {
  if (!v.is_array() || v.size() != 3) throw FieldError(at, "expected 3 numbers");
  return {number(v[0], at), number(v[1], at), number(v[2], at)};
}

// frames x cols numbers, one array per frame.
Eigen::MatrixXd rows(const json& v, size_t frames, size_t cols, const std::string& at) {
  if (!v.is_array() || v.size() != frames)
    throw FieldError(at, "expected " + std::to_string(frames) + " rows, one per time");
  Eigen::MatrixXd m(static_cast<Eigen::Index>(frames), static_cast<Eigen::Index>(cols));
  for (size_t f = 0; f < frames; ++f) {
    const std::string row = at + "[" + std::to_string(f) + "]";
    if (!v[f].is_array() || v[f].size() != cols)
      throw FieldError(row, "expected " + std::to_string(cols) + " numbers, one per dof");
    for (size_t d = 0; d < cols; ++d)
      m(static_cast<Eigen::Index>(f), static_cast<Eigen::Index>(d)) = number(v[f][d], row);
  }
  return m;
}

std::vector<Eigen::Vector3d> vectors(const json& v, size_t frames, const std::string& at) {
  if (!v.is_array() || v.size() != frames)
    throw FieldError(at, "expected " + std::to_string(frames) + " vectors, one per time");
  std::vector<Eigen::Vector3d> out;
  for (size_t f = 0; f < frames; ++f) out.push_back(vec3(v[f], at + "[" + std::to_string(f) + "]"));
  return out;
}

ContactTrack track(const json& j, const CharacterAnimation& ca, const std::string& at) {
  ContactTrack t;
  const json& term = field(j, "term", at);
  if (!term.is_string()) throw FieldError(at + "term", "expected a string");
  t.term = term.get<std::string>();
  if (j.contains("link") && j["link"].is_string()) t.link = j["link"].get<std::string>();
  const json& index = field(j, "pointIndex", at);
  if (!index.is_number_integer() || index.get<int>() < 0) throw FieldError(at + "pointIndex", "expected an integer >= 0");
  t.pointIndex = index.get<int>();
  t.position = vectors(field(j, "point", at), ca.times.size(), at + "point");
  t.force = vectors(field(j, "force", at), ca.times.size(), at + "force");
  if (j.contains("start") && j.contains("end")) {
    t.start = number(j["start"], at + "start");
    t.end = number(j["end"], at + "end");
  } else {
    // A file written before the interval was: the frames with a force on the point.
    bool any = false;
    for (size_t f = 0; f < ca.times.size(); ++f)
      if (t.force[f].squaredNorm() > 0) {
        if (!any) t.start = ca.times[f];
        t.end = ca.times[f];
        any = true;
      }
    if (!any) t.start = t.end = ca.times.front();
  }
  if (t.end < t.start) throw FieldError(at + "end", "before its start");
  t.freeEnd = j.contains("freeEnd") && j["freeEnd"].is_boolean() && j["freeEnd"].get<bool>();
  if (j.contains("impact")) {
    t.impact = true;
    t.impactTime = number(field(j["impact"], "time", at + "impact."), at + "impact.time");
    t.impulse = vec3(field(j["impact"], "impulse", at + "impact."), at + "impact.impulse");
  }
  return t;
}

CharacterAnimation character(const json& j, const std::string& at) {
  CharacterAnimation ca;
  const json& name = field(j, "name", at);
  if (!name.is_string() || name.get<std::string>().empty()) throw FieldError(at + "name", "expected a character id");
  ca.name = name.get<std::string>();
  if (j.contains("gravity")) ca.gravity = vec3(j["gravity"], at + "gravity");
  const json& dofs = field(j, "dofs", at);
  if (!dofs.is_array() || dofs.empty()) throw FieldError(at + "dofs", "expected the dofs' names");
  for (const json& d : dofs) {
    if (!d.is_string()) throw FieldError(at + "dofs", "expected the dofs' names");
    ca.dofs.push_back(d.get<std::string>());
  }
  const json& times = field(j, "times", at);
  if (!times.is_array() || times.size() < 2) throw FieldError(at + "times", "expected at least 2 frame times");
  for (size_t f = 0; f < times.size(); ++f) {
    ca.times.push_back(number(times[f], at + "times[" + std::to_string(f) + "]"));
    if (f > 0 && !(ca.times[f] > ca.times[f - 1]))
      throw FieldError(at + "times[" + std::to_string(f) + "]", "not after the frame before");
  }
  const size_t frames = ca.times.size(), n = ca.dofs.size();
  ca.q = rows(field(j, "q", at), frames, n, at + "q");
  ca.qd = rows(field(j, "qd", at), frames, n, at + "qd");
  ca.qdBefore = ca.qd;
  if (j.contains("qdBefore")) {  // q-dot's left limit at the frames where it differs (impacts)
    const json& before = j["qdBefore"];
    if (!before.is_array()) throw FieldError(at + "qdBefore", "expected an array");
    for (size_t k = 0; k < before.size(); ++k) {
      const std::string entry = at + "qdBefore[" + std::to_string(k) + "]";
      const json& frame = field(before[k], "frame", entry + ".");
      if (!frame.is_number_integer() || frame.get<long>() < 0 || frame.get<size_t>() >= frames)
        throw FieldError(entry + ".frame", "expected a frame index below " + std::to_string(frames));
      ca.qdBefore.row(frame.get<Eigen::Index>()) = rows(json::array({field(before[k], "qd", entry + ".")}), 1, n, entry + ".qd");
    }
  }
  if (j.contains("qdd")) ca.qdd = rows(j["qdd"], frames, n, at + "qdd");
  if (j.contains("tau")) ca.tau = rows(j["tau"], frames, n, at + "tau");
  if (j.contains("actuated") && j["actuated"].is_array())
    for (const json& a : j["actuated"]) ca.actuated.push_back(a.is_boolean() && a.get<bool>());
  if (j.contains("contacts")) {
    if (!j["contacts"].is_array()) throw FieldError(at + "contacts", "expected an array");
    for (size_t k = 0; k < j["contacts"].size(); ++k)
      ca.contacts.push_back(track(j["contacts"][k], ca, at + "contacts[" + std::to_string(k) + "]."));
  }
  return ca;
}

bool motionShaped(const json& j) {
  return j.is_object() && j.contains("formatVersion") && j.contains("characters") && !j.contains("format");
}

}  // namespace

bool looksLikeMotionJson(const std::string& text) { return motionShaped(json::parse(text, nullptr, false)); }

MotionLoadResult parseMotionJson(const std::string& text, const std::string& sourceName) {
  const json root = json::parse(text, nullptr, false);
  if (root.is_discarded()) return {std::nullopt, sourceName + ": not valid JSON"};
  const bool motionFile = motionShaped(root);
  try {
    const json& version = field(root, "formatVersion", "");
    if (!version.is_number_integer() || version.get<int>() != 1)
      throw FieldError("formatVersion", "expected 1 (a motion file this version writes)");
    const json& chars = field(root, "characters", "");
    if (!chars.is_array() || chars.empty()) throw FieldError("characters", "expected at least one character");
    Animation a;
    for (size_t c = 0; c < chars.size(); ++c)
      a.characters.push_back(character(chars[c], "characters[" + std::to_string(c) + "]."));
    return {std::move(a), {}, motionFile};
  } catch (const FieldError& e) {
    return {std::nullopt, sourceName + ": field '" + e.path + "': " + e.what(), motionFile};
  }
}

MotionLoadResult loadMotionFile(const std::string& path) {
  std::string text, error;
  if (!readWholeFile(path, &text, &error)) return {std::nullopt, error};
  return parseMotionJson(text, path);
}

}  // namespace spacetime
