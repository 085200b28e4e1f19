// Joint speed limits (JointSpec::speedLimit): the solver holds |qd| <= limit on the validity
// report's dense grid, and the report measures how far a motion goes beyond them. Speeds are
// measured here independently, by central differences of the solved joint positions.
#include <gtest/gtest.h>

#include <cmath>

#include "../shipped_scene.h"
#include "core/scene_io.h"
#include "interop/urdf_export.h"
#include "solver/augmented_lagrangian.h"
#include "interop/outputs.h"
#include "solver/validity.h"

namespace spacetime {
namespace {

// A two-link arm hanging from a fixed shoulder swings 2 rad and -1.5 rad in one second, at rest
// at both ends, with the least effort. Its least-effort swing peaks at 5.4 and 8.5 rad/s.
const char* kArmSwing = R"({
  "format": "spacetime-scene", "formatVersion": 1, "name": "Arm swing",
  "time": {"start": 0.0, "end": 1.0},
  "gravity": [0, -9.81, 0],
  "ground": {"enabled": false, "height": 0.0},
  "transcription": {"controlPointsPerSecond": 10, "samplesPerSegment": 2},
  "characters": [{"id": "arm", "root": "fixed", "bodies": [
    {"id": "shoulder", "geometry": {"type": "sphere", "radius": 0.05}, "mass": 1.0},
    {"id": "upper", "parent": "shoulder", "joint": {"id": "a1", "type": "revolute", "axis": [0, 0, 1]},
     "geometry": {"type": "capsule", "radius": 0.03, "length": 0.3, "axis": "y", "offset": [0, 0.15, 0]}, "mass": 1.0},
    {"id": "fore", "parent": "upper", "joint": {"id": "a2", "type": "revolute", "axis": [0, 0, 1], "origin": [0, 0.3, 0]},
     "geometry": {"type": "capsule", "radius": 0.025, "length": 0.25, "axis": "y", "offset": [0, 0.125, 0]}, "mass": 0.6}]}],
  "terms": [
    {"id": "start", "type": "keyframe", "character": "arm", "time": 0.0, "values": {"a1": 0.0, "a2": 0.0}},
    {"id": "end", "type": "keyframe", "character": "arm", "time": 1.0, "values": {"a1": 2.0, "a2": -1.5}},
    {"id": "start_rest", "type": "rest", "character": "arm", "time": 0.0},
    {"id": "end_rest", "type": "rest", "character": "arm", "time": 1.0}
  ],
  "objective": {"effort": 1.0, "smoothness": 0.0}
})";

Scene armSwing() {
  const SceneLoadResult r = parseScene(kArmSwing, "arm.json");
  if (!r.scene) throw std::runtime_error(r.error);
  return *r.scene;
}

void limitEveryJoint(Scene& scene, double limit) {
  for (CharacterSpec& c : scene.characters)
    for (BodySpec& b : c.bodies)
      if (!b.parent.empty()) b.joint.speedLimit = limit;
}

std::unique_ptr<SpacetimeProblem> solved(const Scene& scene, SolverSummary* summary) {
  std::string error;
  auto problem = SpacetimeProblem::build(scene, &error);
  EXPECT_TRUE(problem) << error;
  SolverOptions options = solverOptionsFor(scene.solver);
  options.threads = 2;
  *summary = solveSpacetime(*problem, options);
  return problem;
}

// The largest |dq/dt| of `dof` over [t0, t1] on a grid of `n` intervals, by central differences
// of the joint positions (not the spline's own derivative).
double peakSpeed(const SpacetimeProblem& p, int dof, double t0, double t1, int n, double* when = nullptr) {
  constexpr double h = 1e-6;
  double peak = 0;
  for (int i = 0; i <= n; ++i) {
    const double t = std::clamp(t0 + (t1 - t0) * i / n, t0 + h, t1 - h);
    const double v = std::abs(p.jointState(0, t + h, 0)[dof] - p.jointState(0, t - h, 0)[dof]) / (2 * h);
    if (v > peak) {
      peak = v;
      if (when) *when = t;
    }
  }
  return peak;
}

TEST(SpeedLimit, ArmSwingStaysUnderItsLimitBetweenTheSamples) {
  SolverSummary free;
  const auto unlimited = solved(armSwing(), &free);
  ASSERT_TRUE(free.converged) << free.reason;
  const double freePeak = peakSpeed(*unlimited, 1, 0, 1, 4000);
  EXPECT_GT(freePeak, 8.0);
  const ValidityReport vf = checkValidity(*unlimited);
  EXPECT_FALSE(vf.hasSpeedLimits);

  Scene scene = armSwing();
  limitEveryJoint(scene, 3.0);
  SolverSummary s;
  const auto limited = solved(scene, &s);
  ASSERT_TRUE(s.converged) << s.reason;
  const ValidityReport v = checkValidity(*limited);
  ASSERT_TRUE(v.hasSpeedLimits);
  bool listed = false;
  for (const ValidityCheck& c : validityChecklist(v)) {
    EXPECT_TRUE(c.pass) << c.name << ": " << c.value;
    listed = listed || c.name.find("joint speed limits") != std::string::npos;
  }
  EXPECT_TRUE(listed);
  // Between the grid's instants a quadratic peak passes the limit by far less than the
  // report's 1e-4 rad/s; the limit binds (the free swing was almost three times as fast).
  for (int dof = 0; dof < 2; ++dof) EXPECT_LT(peakSpeed(*limited, dof, 0, 1, 20000), 3.0 + 1e-4) << dof;
  EXPECT_GT(peakSpeed(*limited, 1, 0, 1, 4000), 3.0 - 1e-3);
  EXPECT_GT(s.objective, free.objective * 1.05);

  // The limit is kept by the file and exported as the URDF joint's velocity limit.
  const SceneLoadResult again = parseScene(sceneToJson(scene), "again.json");
  ASSERT_TRUE(again.scene) << again.error;
  EXPECT_EQ(again.scene->characters[0].bodies[2].joint.speedLimit, 3.0);
  const std::string urdf = exportUrdf(*limited->characters()[0].model, scene.characters[0]).xml;
  EXPECT_NE(urdf.find("velocity=\"3\""), std::string::npos) << urdf;

  std::string text = kArmSwing;
  text.replace(text.find("\"axis\": [0, 0, 1]}"), 18, "\"axis\": [0, 0, 1], \"speedLimit\": -2}");
  const SceneLoadResult bad = parseScene(text, "arm.json");
  ASSERT_FALSE(bad.scene);
  EXPECT_NE(bad.error.find("speedLimit"), std::string::npos) << bad.error;
}

// The shipped jump whips j2 at about 37 rad/s just after lift-off. The same motion judged
// against a 15 rad/s limit fails only the speed check, by the excess measured independently.
TEST(SpeedLimit, ValidityMeasuresTheJumpsWhip) {
  SolverSummary s;
  const auto whip = solved(testing::shippedScene("luxo_jump.json"), &s);
  ASSERT_TRUE(s.converged) << s.reason;

  Scene scene = whip->scene();
  limitEveryJoint(scene, 15.0);
  std::string error;
  auto judged = SpacetimeProblem::build(scene, &error);
  ASSERT_TRUE(judged) << error;
  // The same variables; the speed rows bring multipliers of their own.
  ASSERT_TRUE(judged->restore({whip->state().variables, judged->state().multipliers, 0, nullptr}));
  const ValidityReport v = checkValidity(*judged);
  ASSERT_TRUE(v.hasSpeedLimits);
  EXPECT_EQ(v.worstJointSpeed, "luxo.j2");
  const int j2 = judged->characters()[0].model->dofIndex("j2");
  // The report samples the dense grid; the finite differences a grid 20 times finer.
  const std::vector<double> dense = judged->transcription().denseGrid(kDenseGridFactor);
  const double peak = peakSpeed(*judged, j2, dense.front(), dense.back(), 20 * static_cast<int>(dense.size() - 1));
  EXPECT_GT(peak, 30.0);
  EXPECT_NEAR(v.maxJointSpeedExcess, peak - 15.0, 0.01 * peak);
  EXPECT_LE(v.maxJointSpeedExcess, peak - 15.0 + 1e-4);
  int failing = 0;
  for (const ValidityCheck& c : validityChecklist(v))
    if (!c.pass) {
      ++failing;
      EXPECT_NE(c.name.find("joint speed limits"), std::string::npos) << c.name;
      EXPECT_NE(c.name.find("luxo.j2"), std::string::npos) << c.name;
      ASSERT_TRUE(c.time.has_value());
      EXPECT_EQ(*c.time, v.worstJointSpeedTime);
    }
  EXPECT_EQ(failing, 1);
  const std::string summary = summaryJson(SolverSummary(), v, *judged);
  EXPECT_NE(summary.find("\"worst_joint_speed\": \"luxo.j2\""), std::string::npos);
}

}  // namespace
}  // namespace spacetime
