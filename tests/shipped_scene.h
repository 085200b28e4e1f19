// Loads a scene shipped in resources/scenes/ for a test or benchmark. A scene that does not
// load throws with the loader's message, which fails the test that asked for it.
#pragma once

#include <stdexcept>
#include <string>

#include "core/scene_io.h"

namespace spacetime::testing {

// Loads `name` from a folder of the source tree.
inline Scene sceneIn(const std::string& folder, const std::string& name) {
  const SceneLoadResult r = loadSceneFile(std::string(SPACETIME_SOURCE_DIR) + "/" + folder + "/" + name);
  if (!r.scene) throw std::runtime_error(r.error);
  return *r.scene;
}

inline Scene shippedScene(const std::string& name) { return sceneIn("resources/scenes", name); }

// Loads a scene kept for tests only (tests/scenes/).
inline Scene testScene(const std::string& name) { return sceneIn("tests/scenes", name); }

}  // namespace spacetime::testing
