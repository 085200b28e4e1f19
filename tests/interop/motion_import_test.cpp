// A motion file read back (interop/motion_import.h) and a solve started from it
// (SpacetimeProblem::initializeFrom with a sampled motion, solver/motion_source.h): the file
// round-trips what the writer put in it to the last bit; the motion fitted to a fresh problem of
// the same scene is the solved one to within the frames' interpolation error, with the same
// contact resultants; from it `sqp` ends at the same optimum in a few steps; and a malformed file
// names the field that is wrong.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "../shipped_scene.h"
#include "core/scene_io.h"
#include "interop/motion_import.h"
#include "interop/outputs.h"
#include "solver/augmented_lagrangian.h"
#include "solver/motion_source.h"

namespace spacetime {
namespace {

SolverOptions sqp() {
  SolverOptions o;
  o.method = SolverMethod::Sqp;
  o.threads = 2;
  return o;
}

struct SolvedJump {
  std::unique_ptr<SpacetimeProblem> problem;
  SolverSummary summary;
};

const SolvedJump& solvedJump() {
  static const SolvedJump solved = [] {
    std::string error;
    SolvedJump s{SpacetimeProblem::build(testing::shippedScene("luxo_jump.json"), &error), {}};
    if (!s.problem) throw std::runtime_error(error);
    s.summary = solveSpacetime(*s.problem, sqp());
    return s;
  }();
  return solved;
}

TEST(MotionImport, RoundTripsTheWrittenMotion) {
  const SolvedJump& jump = solvedJump();
  ASSERT_TRUE(jump.summary.converged) << jump.summary.reason;
  const Animation written = sampleAnimation(*jump.problem, 1000);
  const MotionLoadResult read = parseMotionJson(motionJson(written), "motion.json");
  ASSERT_TRUE(read.animation) << read.error;
  ASSERT_EQ(read.animation->characters.size(), written.characters.size());
  const CharacterAnimation &a = written.characters[0], &b = read.animation->characters[0];
  EXPECT_EQ(b.name, a.name);
  EXPECT_EQ(b.dofs, a.dofs);
  EXPECT_EQ(b.times, a.times);
  EXPECT_EQ(b.q, a.q);
  EXPECT_EQ(b.qd, a.qd);
  EXPECT_EQ(b.tau, a.tau);
  ASSERT_EQ(b.contacts.size(), a.contacts.size());
  for (size_t k = 0; k < a.contacts.size(); ++k) {
    EXPECT_EQ(b.contacts[k].term, a.contacts[k].term);
    EXPECT_EQ(b.contacts[k].pointIndex, a.contacts[k].pointIndex);
    EXPECT_EQ(b.contacts[k].start, a.contacts[k].start);
    EXPECT_EQ(b.contacts[k].end, a.contacts[k].end);
    EXPECT_EQ(b.contacts[k].impact, a.contacts[k].impact);
    EXPECT_EQ(b.contacts[k].impulse, a.contacts[k].impulse);
    EXPECT_EQ(b.contacts[k].force, a.contacts[k].force);
    EXPECT_EQ(b.contacts[k].position, a.contacts[k].position);
  }
  EXPECT_TRUE(looksLikeMotionJson(motionJson(written)));
  EXPECT_FALSE(looksLikeMotionJson(sceneToJson(jump.problem->scene())));
}

// The jump's motion at 1 kHz fitted to a fresh problem of its scene: the joints' B-splines and the
// root's Hermite data follow the frames (linear between them: an error of h^2/8 |q''|, ~1e-5 rad
// at 1 ms and the push-off's accelerations), each contact's resultant at its samples is the
// solved one to the same interpolation (the file holds the ground forces recovered per point,
// which split the same resultant), and sqp from there ends at the solved optimum within a few steps.
TEST(MotionImport, AFittedMotionRestartsTheSolveAtItsOptimum) {
  const SolvedJump& jump = solvedJump();
  ASSERT_TRUE(jump.summary.converged) << jump.summary.reason;
  const MotionLoadResult read = parseMotionJson(motionJson(sampleAnimation(*jump.problem, 1000)), "motion.json");
  ASSERT_TRUE(read.animation) << read.error;
  std::string error;
  auto fresh = SpacetimeProblem::build(jump.problem->scene(), &error);
  ASSERT_TRUE(fresh) << error;
  ASSERT_EQ(fresh->initializeFrom(*motionSourceOf(*read.animation)), 1);

  double worstQ = 0;
  for (double t : fresh->transcription().denseGrid(4))
    worstQ = std::max(worstQ, (fresh->jointState(0, t, 0) - jump.problem->jointState(0, t, 0)).cwiseAbs().maxCoeff());
  EXPECT_LT(worstQ, 1e-4);
  const double weight = fresh->characters()[0].weight;
  double worstForce = 0;
  for (size_t j = 0; j < fresh->contacts().size(); ++j)
    for (double t : fresh->contacts()[j].times) {
      Eigen::Vector3d a = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero();
      for (const Eigen::Vector3d& f : fresh->contactForces(static_cast<int>(j), t)) a += f;
      for (const Eigen::Vector3d& f : jump.problem->contactForces(static_cast<int>(j), t)) b += f;
      worstForce = std::max(worstForce, (a - b).norm() / weight);
    }
  // 1.75e-3 measured, at 0.39 s: the push-off's forces fall fastest before the lift-off at 0.4 s,
  // and a sample between two frames reads their line across the kink the solver's forces (linear
  // between samples) have there.
  EXPECT_LT(worstForce, 3e-3);

  SolverOptions o = sqp();
  o.warmStart = true;
  const SolverSummary s = solveSpacetime(*fresh, o);
  ASSERT_TRUE(s.converged) << s.reason;
  EXPECT_LE(s.sqpSteps, 3) << s.reason;
  EXPECT_EQ(s.iterations, 0) << s.reason;
  EXPECT_NEAR(s.objective, jump.summary.objective, 1e-6 * jump.summary.objective);
  // Nothing in common: a motion of another character leaves the default guess.
  Animation other = *read.animation;
  other.characters[0].name = "someone_else";
  auto untouched = SpacetimeProblem::build(jump.problem->scene(), &error);
  const std::vector<double> guess = untouched->variables();
  EXPECT_EQ(untouched->initializeFrom(*motionSourceOf(other)), 0);
  EXPECT_EQ(untouched->variables(), guess);
}

TEST(MotionImport, AMalformedFileNamesTheField) {
  const nlohmann::json good = nlohmann::json::parse(motionJson(sampleAnimation(*solvedJump().problem, 100)));
  auto errorOf = [](const nlohmann::json& j) {
    const MotionLoadResult r = parseMotionJson(j.dump(), "m.json");
    EXPECT_FALSE(r.animation);
    return r.error;
  };
  nlohmann::json j = good;
  j["characters"][0]["q"][3].erase(0);
  EXPECT_EQ(errorOf(j), "m.json: field 'characters[0].q[3]': expected 6 numbers, one per dof");
  j = good;
  j["characters"][0]["qd"].erase(0);
  EXPECT_EQ(errorOf(j), "m.json: field 'characters[0].qd': expected 121 rows, one per time");
  j = good;
  j["characters"][0].erase("times");
  EXPECT_EQ(errorOf(j), "m.json: field 'characters[0].times': missing required field");
  j = good;
  j["characters"][0]["times"][5] = j["characters"][0]["times"][4];
  EXPECT_EQ(errorOf(j), "m.json: field 'characters[0].times[5]': not after the frame before");
  j = good;
  j["characters"][0]["contacts"][1]["force"][7] = "up";
  EXPECT_EQ(errorOf(j), "m.json: field 'characters[0].contacts[1].force[7]': expected 3 numbers");
  j = good;
  j["formatVersion"] = 2;
  EXPECT_EQ(errorOf(j), "m.json: field 'formatVersion': expected 1 (a motion file this version writes)");
  EXPECT_EQ(parseMotionJson("{\"formatVersion\": 1,", "m.json").error, "m.json: not valid JSON");
}

}  // namespace
}  // namespace spacetime
