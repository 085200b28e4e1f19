// libFuzzer target for the scene loader (clang -fsanitize=fuzzer,address,undefined; built and
// run by scripts/fuzz.sh). Every input must end in a scene or in one error line of at most 300
// characters; and whatever the loader accepts, the editor can save and reopen unchanged (the
// canonical text of the reopened scene is the saved text). A violation aborts, which libFuzzer
// reports as a crash with the input that caused it.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "core/scene_io.h"

namespace {
[[noreturn]] void fail(const char* what, const std::string& detail) {
  std::fprintf(stderr, "scene_loader_fuzz: %s\n%s\n", what, detail.substr(0, 2000).c_str());
  std::abort();
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const spacetime::SceneLoadResult loaded = spacetime::parseScene(text, "fuzz.json");
  if (!loaded.scene) {
    if (loaded.error.empty()) fail("refused without a reason", text);
    if (loaded.error.find('\n') != std::string::npos) fail("an error of more than one line", loaded.error);
    if (loaded.error.size() > 300) fail("an error line over 300 characters", loaded.error);
    return 0;
  }
  const std::string saved = spacetime::sceneToJson(*loaded.scene);
  const spacetime::SceneLoadResult reopened = spacetime::parseScene(saved, "saved.json");
  if (!reopened.scene) fail("a scene the loader accepted cannot be reopened after saving", reopened.error + "\n" + saved);
  if (spacetime::sceneToJson(*reopened.scene) != saved) fail("a saved scene reopens different", saved);
  return 0;
}
