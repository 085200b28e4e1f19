// Reading and writing scene files. Loading never throws and never crashes on bad input: it
// returns either a Scene or a one-line error naming the file, the field, the value and what is
// allowed. Saving is atomic.
#pragma once

#include <optional>
#include <string>

#include "core/scene.h"

namespace spacetime {

inline constexpr int kSceneFormatVersion = 1;

struct SceneLoadResult {
  std::optional<Scene> scene;
  std::string error;  // empty on success
};

SceneLoadResult parseScene(const std::string& text, const std::string& sourceName);
SceneLoadResult loadSceneFile(const std::string& path);

// Canonical JSON text of a scene (every field, fixed order).
std::string sceneToJson(const Scene& scene);
bool saveSceneFile(const Scene& scene, const std::string& path, std::string* error);

}  // namespace spacetime
