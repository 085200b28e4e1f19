// The scene format: shipped scenes load; save -> load -> save is identical; malformed files get
// an error naming the file, the field, the value and what is allowed - never a crash.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "core/scene_io.h"

namespace spacetime {
namespace {

const std::string kScenes = std::string(SPACETIME_SOURCE_DIR) + "/resources/scenes/";

// The shipped jump's file as text, and its first joint's axis ([0, 0, 1]) in it.
const std::string& jumpText() {
  static const std::string text = [] {
    std::ifstream in(kScenes + "luxo_jump.json");
    std::stringstream buffer;
    buffer << in.rdbuf();
    return buffer.str();
  }();
  return text;
}
const std::regex& firstJointAxis() {
  static const std::regex axis(R"("axis": \[\s*0,\s*0,\s*1\s*\])");
  return axis;
}
// The shipped jump parsed with its first joint's axis written as `axis`, e.g. R"("axis": [5, 0, 2])".
SceneLoadResult jumpWithFirstAxis(const char* axis) {
  return parseScene(std::regex_replace(jumpText(), firstJointAxis(), axis, std::regex_constants::format_first_only),
                    "axis.json");
}

TEST(SceneIo, ShippedScenesLoadAndRoundTrip) {
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(kScenes)) {
    if (entry.path().extension() != ".json") continue;
    ++count;
    const SceneLoadResult r = loadSceneFile(entry.path().string());
    ASSERT_TRUE(r.scene) << r.error;
    const std::string text = sceneToJson(*r.scene);
    const SceneLoadResult again = parseScene(text, "roundtrip");
    ASSERT_TRUE(again.scene) << again.error;
    EXPECT_EQ(sceneToJson(*again.scene), text) << entry.path();
  }
  EXPECT_GE(count, 5);
}

// A free contact end (the lift-off instant as a variable) and its window survive a save.
TEST(SceneIo, FreeContactEndRoundTrips) {
  const SceneLoadResult r = loadSceneFile(std::string(kScenes) + "/luxo_jump.json");
  ASSERT_TRUE(r.scene) << r.error;
  Scene scene = *r.scene;
  for (TermSpec& t : scene.terms)
    if (t.id == "takeoff") {
      t.freeEnd = true;
      t.freeEndWindow = 0.05;
    }
  const SceneLoadResult again = parseScene(sceneToJson(scene), "roundtrip");
  ASSERT_TRUE(again.scene) << again.error;
  int free = 0;
  for (const TermSpec& t : again.scene->terms)
    if (t.freeEnd) {
      ++free;
      EXPECT_EQ(t.id, "takeoff");
      EXPECT_EQ(t.freeEndWindow, 0.05);
    }
  EXPECT_EQ(free, 1);
}

// The solver method and the frame rate a scene asks for are saved and read back.
TEST(SceneIo, SolverMethodFrameRateLegBubblesAndKnotsRoundTrip) {
  const SceneLoadResult r = loadSceneFile(std::string(kScenes) + "/luxo_jump.json");
  ASSERT_TRUE(r.scene) << r.error;
  EXPECT_EQ(r.scene->solver.method, "al");  // the default
  EXPECT_FALSE(r.scene->transcription.legBubbles);  // the default
  Scene scene = *r.scene;
  scene.solver.method = "ipopt";
  EXPECT_EQ(scene.frameRate, 24);  // the default
  scene.frameRate = 30;
  scene.transcription.legBubbles = true;
  EXPECT_EQ(scene.solver.maxRefinements, 3);  // the default
  scene.solver.maxRefinements = 0;
  EXPECT_EQ(scene.solver.maxSeconds, 300);  // the default
  scene.solver.maxSeconds = 1200.5;
  const SceneLoadResult again = parseScene(sceneToJson(scene), "roundtrip");
  ASSERT_TRUE(again.scene) << again.error;
  EXPECT_EQ(again.scene->solver.method, "ipopt");
  EXPECT_EQ(again.scene->frameRate, 30);
  EXPECT_TRUE(again.scene->transcription.legBubbles);
  EXPECT_EQ(again.scene->solver.maxRefinements, 0);
  EXPECT_EQ(again.scene->solver.maxSeconds, 1200.5);
  EXPECT_TRUE(again.scene->transcription.knots.empty());  // uniform: none written
  // The refinement's non-uniform knots (TranscriptionSpec::knots) round-trip exactly.
  scene.transcription.knots = {0.1, 0.35, 0.4125, 0.475, 0.6 + 1e-13};
  const SceneLoadResult knotted = parseScene(sceneToJson(scene), "roundtrip");
  ASSERT_TRUE(knotted.scene) << knotted.error;
  EXPECT_EQ(knotted.scene->transcription.knots, scene.transcription.knots);
  scene.transcription.knots.clear();
  for (const char* method : SolverSpec::kMethods) {
    scene.solver.method = method;
    const SceneLoadResult each = parseScene(sceneToJson(scene), "roundtrip");
    ASSERT_TRUE(each.scene) << each.error;
    EXPECT_EQ(each.scene->solver.method, method);
  }
  scene.solver.method = "ipopt";
  std::string text = sceneToJson(scene);
  const size_t flag = text.find("true", text.find("\"legBubbles\""));
  ASSERT_NE(flag, std::string::npos);
  text.replace(flag, 4, "1");
  const std::string error = parseScene(text, "x.json").error;
  EXPECT_NE(error.find("transcription.legBubbles"), std::string::npos) << error;
}

// A joint axis beyond the loader's magnitude bound is refused, naming the component (its
// squared norm overflowed a double and it became [0, 0, 0]: the solve failed and the saved file
// would not load again); a large one within the bound normalises to its direction.
TEST(SceneIo, HugeJointAxisIsRefusedOrNormalised) {
  ASSERT_TRUE(std::regex_search(jumpText(), firstJointAxis()));
  const SceneLoadResult huge = jumpWithFirstAxis(R"("axis": [0, 3e200, 4e200])");
  ASSERT_FALSE(huge.scene);
  EXPECT_NE(huge.error.find("axis.json: field 'characters[0].bodies[1].joint.axis[1]'"), std::string::npos) << huge.error;
  EXPECT_NE(huge.error.find("magnitude at most 1e9"), std::string::npos) << huge.error;
  const SceneLoadResult large = jumpWithFirstAxis(R"("axis": [0, 3e8, 4e8])");
  ASSERT_TRUE(large.scene) << large.error;
  const Eigen::Vector3d a = large.scene->characters[0].bodies[1].joint.axis;
  EXPECT_NEAR((a - Eigen::Vector3d(0, 0.6, 0.8)).norm(), 0, 1e-15);
  const SceneLoadResult again = parseScene(sceneToJson(*large.scene), "again.json");
  EXPECT_TRUE(again.scene) << again.error;
}

// A joint axis is normalised when loaded, and a saved scene reopens as it was saved: the axis
// written is kept, not normalised again (that moved [5, 0, 2]'s last bits, which the loader's
// fuzzer found: the reopened scene saved differently).
TEST(SceneIo, ANormalisedJointAxisReopensUnchanged) {
  ASSERT_TRUE(std::regex_search(jumpText(), firstJointAxis()));
  for (const char* axis : {R"("axis": [5, 0, 2])", R"("axis": [1, 1, 1])", R"("axis": [0.3, -7, 2.5])", R"("axis": [3e8, 1, 1e-3])"}) {
    const SceneLoadResult loaded = jumpWithFirstAxis(axis);
    ASSERT_TRUE(loaded.scene) << loaded.error;
    EXPECT_NEAR(loaded.scene->characters[0].bodies[1].joint.axis.norm(), 1, 1e-15) << axis;
    const std::string saved = sceneToJson(*loaded.scene);
    const SceneLoadResult reopened = parseScene(saved, "saved.json");
    ASSERT_TRUE(reopened.scene) << reopened.error;
    EXPECT_EQ(sceneToJson(*reopened.scene), saved) << axis;
  }
}

TEST(SceneIo, AtomicSaveThenLoad) {
  const SceneLoadResult r = loadSceneFile(kScenes + "luxo_jump.json");
  ASSERT_TRUE(r.scene) << r.error;
  const std::string path = ::testing::TempDir() + "/saved_scene.json";
  std::string error;
  ASSERT_TRUE(saveSceneFile(*r.scene, path, &error)) << error;
  const SceneLoadResult back = loadSceneFile(path);
  ASSERT_TRUE(back.scene) << back.error;
  EXPECT_EQ(sceneToJson(*back.scene), sceneToJson(*r.scene));
  EXPECT_FALSE(saveSceneFile(*r.scene, "/nonexistent-dir/x.json", &error));
  EXPECT_NE(error.find("/nonexistent-dir/x.json"), std::string::npos);
}

// A solution saved with the scene comes back bit for bit (the editor reopens the same motion).
TEST(SceneIo, StoredSolutionRoundTripsExactly) {
  const SceneLoadResult r = loadSceneFile(kScenes + "particle.json");
  ASSERT_TRUE(r.scene) << r.error;
  Scene s = *r.scene;
  s.solution = StoredSolution{{0.1, -1.0 / 3.0, 1e-300, 123456.789012345678}, {2.0 / 7.0}, 1e4, true};
  const SceneLoadResult back = parseScene(sceneToJson(s), "mem");
  ASSERT_TRUE(back.scene && back.scene->solution) << back.error;
  EXPECT_EQ(back.scene->solution->variables, s.solution->variables);
  EXPECT_EQ(back.scene->solution->multipliers, s.solution->multipliers);
  EXPECT_EQ(back.scene->solution->rho, 1e4);
  EXPECT_TRUE(back.scene->solution->converged);
  EXPECT_EQ(sceneToJson(*back.scene), sceneToJson(s));
}

struct BadCase {
  std::string json;
  std::string mustMention;
};

std::string minimalWith(const std::string& characterBody, const std::string& terms = "[]",
                        const std::string& extra = "") {
  return R"({"format": "spacetime-scene", "formatVersion": 1, "time": {"start": 0, "end": 1},)" +
         extra + R"("characters": [{"id": "c", "root": "planar", "bodies": [)" + characterBody +
         R"(]}], "terms": )" + terms + "}";
}

TEST(SceneIo, BadFilesNameFileFieldAndValue) {
  const std::string body = R"({"id": "base", "mass": 1})";
  const std::vector<BadCase> cases = {
      {"{not json", "not valid JSON"},
      {R"({"format": "other", "formatVersion": 1})", "'format'"},
      {R"({"format": "spacetime-scene", "formatVersion": 99, "time": {"start":0,"end":1}, "characters": []})",
       "newer Spacetime"},
      {R"({"format": "spacetime-scene", "formatVersion": 1, "characters": []})", "'time'"},
      {R"({"format": "spacetime-scene", "formatVersion": 1, "time": {"start": 0, "end": 1, "frameRate": 0}, "characters": []})",
       "time.frameRate': value 0 is not allowed; expected a number of frames per second from 1 to 1000"},
      {minimalWith(R"({"id": "base", "mass": -1})"), "characters[0].bodies[0].mass': value -1"},
      {minimalWith(R"({"id": "base"})"), "needs a mass or a density"},
      {minimalWith(body + R"(, {"id": "arm", "parent": "nope", "mass": 1, "joint": {"id": "j", "type": "revolute"}})"),
       "characters[0].bodies[1].parent': value \"nope\""},
      {minimalWith(body + R"(, {"id": "arm", "parent": "base", "mass": 1, "joint": {"id": "j", "type": "ball"}})"),
       "one of \"revolute\""},
      {minimalWith(body, R"([{"id": "k", "type": "keyframe", "character": "c", "time": 0.5, "values": {"elbow": 1}}])"),
       "terms[0].values.elbow': unknown degree of freedom"},
      {minimalWith(body, R"([{"id": "p", "type": "pin", "character": "c", "body": "base", "position": [0,0,0], "time": 3}])"),
       "terms[0].time': value 3"},
      {minimalWith(body, R"([{"id": "p", "type": "contact", "character": "c", "body": "base", "points": [[0,0,0]], "start": 0.5, "end": 0.2}])"),
       "terms[0].end'"},
      {minimalWith(body, R"([{"id": "p", "type": "contact", "character": "c", "body": "base", "points": [[0,0,0]], "start": 0, "end": 0.5, "freeEnd": true, "freeEndWindow": -0.1}])"),
       "terms[0].freeEndWindow': value -0.1"},
      {minimalWith(body, R"([{"id": "p", "type": "contact", "character": "c", "body": "base", "points": [[0,0,0]], "start": 0, "end": 0.5, "freeEnd": "yes"}])"),
       "terms[0].freeEnd'"},
      {minimalWith(R"({"id": "base", "mass": 1, "masss": 2})"), "bodies[0].masss': unknown field"},
      {minimalWith(body, "[]", R"("solution": {"variables": [1, "x"], "multipliers": []},)"),
       "solution.variables[1]': value \"x\""},
      {minimalWith(R"({"id": "base", "mass": 1, "inertia": [1, 1, 5]})"), "triangle inequality"},
      {minimalWith(body, "[]", R"("gravity": [0, "down", 0],)"), "gravity[1]"},
      {minimalWith(body, "[]", R"("solver": {"maxPenalty": 10},)"), "solver.maxPenalty': value 10"},
      {minimalWith(body, "[]", R"("solver": {"bodiesAboveGround": 1},)"), "solver.bodiesAboveGround': value 1"},
      {minimalWith(body, "[]", R"("solver": {"maxRefinements": 11},)"), "solver.maxRefinements': value 11"},
      {minimalWith(body, "[]", R"("solver": {"maxSeconds": 0},)"), "solver.maxSeconds': value 0"},
      {minimalWith(body, "[]", R"("solver": {"maxSeconds": 2e7},)"), "solver.maxSeconds': value 2"},
      {minimalWith(body, "[]", R"("transcription": {"knots": 0.5},)"), "transcription.knots': value 0.5"},
      {minimalWith(body, "[]", R"("transcription": {"knots": [0.5, 0.4]},)"),
       "transcription.knots[1]': value 0.4 is not allowed; expected a time at least 1e-4 s after the knot before it"},
      {minimalWith(body, "[]", R"("transcription": {"knots": [1.0]},)"), "transcription.knots[0]': value 1"},
      {minimalWith(body, "[]", R"("solver": {"method": "sqp2"},)"), "solver.method': value \"sqp2\" is not allowed; expected \"al\", \"ipopt\", \"sqp\" or \"witkin-kass\""},
      // A number beyond a double (nlohmann's out_of_range, which used to abort).
      {minimalWith(R"({"id": "base", "mass": 1e999})"), "not valid JSON"},
      // 100 000 levels of nesting (parsing and printing them overflowed the stack), and a few
      // where an object belongs, described rather than printed.
      {std::string(100000, '[') + std::string(100000, ']'), "nested 100000 levels deep (at most 64)"},
      {minimalWith(body, "[]", R"("gravity": )" + std::string(100000, '[') + std::string(100000, ']') + ","),
       "levels deep (at most 64)"},
      {minimalWith(body, "[]", R"("gravity": [[[[1]]]], "name": "]]]]]]]]",)"), "gravity': value an array of 1 elements"},
  };
  for (const auto& c : cases) {
    const SceneLoadResult r = parseScene(c.json, "bad.json");
    EXPECT_FALSE(r.scene) << c.json;
    EXPECT_EQ(r.error.rfind("bad.json", 0), 0u) << r.error;
    EXPECT_NE(r.error.find(c.mustMention), std::string::npos) << r.error;
  }
  // A 100 kB unknown key is named, shortened: the message stays one short line.
  const std::string longKey(100000, 'k');
  const SceneLoadResult longName = parseScene(
      minimalWith(body, R"([{"id": "k", "type": "keyframe", "character": "c", "time": 0.5, "values": {")" + longKey + R"(": 1}}])"),
      "bad.json");
  EXPECT_FALSE(longName.scene);
  EXPECT_LT(longName.error.size(), 400u) << longName.error.size();
  EXPECT_NE(longName.error.find("unknown degree of freedom"), std::string::npos) << longName.error.substr(0, 300);
  const SceneLoadResult missing = loadSceneFile("/no/such/scene.json");
  EXPECT_FALSE(missing.scene);
  EXPECT_NE(missing.error.find("/no/such/scene.json"), std::string::npos);
}

// Found by the loader's fuzzer (tests/fuzz): the JSON library quotes what it last read, which
// can be a long line of the file; every error stays one line of at most 300 characters, cut at a
// character boundary.
TEST(SceneIo, EveryErrorIsOneShortLine) {
  const std::string longKey = "{\"" + std::string(400, 'M') + "\u00e9" + "\n";
  for (const std::string& text : {longKey, "{\"characters\": [" + std::string(500, ' ') + "\u00e9\u00e9\u00e9" + std::string(500, 'x')}) {
    const SceneLoadResult r = parseScene(text, "fuzz.json");
    ASSERT_FALSE(r.scene);
    EXPECT_LE(r.error.size(), 300u) << r.error;
    EXPECT_EQ(r.error.find('\n'), std::string::npos) << r.error;
    EXPECT_EQ(r.error.rfind("fuzz.json: not valid JSON", 0), 0u) << r.error;
    // Valid UTF-8 at the cut: no lead byte without its continuation bytes at the end.
    size_t i = r.error.size();
    while (i > 0 && (static_cast<unsigned char>(r.error[i - 1]) & 0xC0) == 0x80) --i;
    if (i > 0) {
      const unsigned char lead = static_cast<unsigned char>(r.error[i - 1]);
      const size_t need = lead < 0x80 ? 1 : lead >= 0xF0 ? 4 : lead >= 0xE0 ? 3 : 2;
      EXPECT_EQ(r.error.size() - (i - 1), need) << r.error;
    }
  }
}

}  // namespace
}  // namespace spacetime
