// A motion file read back (interop/motion_import.h) and a solve started from it
// (SpacetimeProblem::initializeFrom with a sampled motion, solver/motion_source.h): the file
// round-trips what the writer put in it to the last bit; the motion fitted to a fresh problem of
// the same scene is the solved one to within the frames' interpolation error, with the same
// contact resultants; from it `sqp` ends at the same optimum in a few steps, and so do the
// augmented Lagrangian and witkin-kass from the multipliers estimated there; and a malformed file
// names the field that is wrong.
#include <gtest/gtest.h>

#include <cstdio>

#include <nlohmann/json.hpp>

#include "../shipped_scene.h"
#include "core/scene_io.h"
#include "interop/motion_import.h"
#include "interop/outputs.h"
#include "solver/augmented_lagrangian.h"
#include "solver/motion_source.h"
#include "solver/multiplier_estimate.h"

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
  // q-dot's left limit: written where it differs (the landing's impact), rounding elsewhere.
  ASSERT_EQ(b.qdBefore.rows(), a.qdBefore.rows());
  EXPECT_LT((b.qdBefore - a.qdBefore).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_GT((b.qdBefore - b.qd).cwiseAbs().maxCoeff(), 1);
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

// The jump's motion at 1 kHz (spacetime-cli's motion.json) and at 120 Hz (the editor's export)
// fitted to a fresh problem of its scene: the joints' B-splines and the root's Hermite data follow
// the frames (cubic Hermite between them, each side of the landing's velocity jump read from its
// own frames), each contact's resultant at its samples is the solved one (re-balanced on the
// fitted motion: read linearly between 120 Hz frames it was 0.10 x weight off before the
// lift-off), and sqp from there ends at the solved optimum within a few steps.
TEST(MotionImport, AFittedMotionRestartsTheSolveAtItsOptimum) {
  const SolvedJump& jump = solvedJump();
  ASSERT_TRUE(jump.summary.converged) << jump.summary.reason;
  for (double rate : {1000.0, 120.0}) {
    SCOPED_TRACE(rate);
    const MotionLoadResult read = parseMotionJson(motionJson(sampleAnimation(*jump.problem, rate)), "motion.json");
    ASSERT_TRUE(read.animation) << read.error;
    std::string error;
    auto fresh = SpacetimeProblem::build(jump.problem->scene(), &error);
    ASSERT_TRUE(fresh) << error;
    ASSERT_EQ(startFromMotion(*fresh, *read.animation), 1);

    double worstQ = 0, worstQd = 0;
    for (double t : fresh->transcription().denseGrid(4)) {
      worstQ = std::max(worstQ, (fresh->jointState(0, t, 0) - jump.problem->jointState(0, t, 0)).cwiseAbs().maxCoeff());
      worstQd = std::max(worstQd, (fresh->jointStateBefore(0, t, 1) - jump.problem->jointStateBefore(0, t, 1)).cwiseAbs().maxCoeff());
    }
    // Measured: q 9.4e-10 rad from 1 kHz, 5.3e-7 from 120 Hz (the joints' fit, exact but for
    // the file's sampling; with the fit's smoothing both were 4.6e-6), q-dot 1.4e-7 and 4.3e-5
    // (6.8e-4), the resultants 2.1e-4 x weight.
    std::printf("%g Hz: q %.2e rad, q-dot %.2e rad/s from the solved motion\n", rate, worstQ, worstQd);
    EXPECT_LT(worstQ, rate >= 1000 ? 1e-8 : 2e-6);
    EXPECT_LT(worstQd, rate >= 1000 ? 1e-6 : 2e-4);
    const double weight = fresh->characters()[0].weight;
    double worstForce = 0;
    for (size_t j = 0; j < fresh->contacts().size(); ++j)
      for (double t : fresh->contacts()[j].times) {
        Eigen::Vector3d a = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero();
        for (const Eigen::Vector3d& f : fresh->contactForces(static_cast<int>(j), t)) a += f;
        for (const Eigen::Vector3d& f : jump.problem->contactForces(static_cast<int>(j), t)) b += f;
        worstForce = std::max(worstForce, (a - b).norm() / weight);
      }
    EXPECT_LT(worstForce, 1e-3);

    SolverOptions o = sqp();
    o.warmStart = true;
    const SolverSummary s = solveSpacetime(*fresh, o);
    ASSERT_TRUE(s.converged) << s.reason;
    EXPECT_LE(s.sqpSteps, 3) << s.reason;
    EXPECT_EQ(s.iterations, 0) << s.reason;
    EXPECT_NEAR(s.objective, jump.summary.objective, 1e-6 * jump.summary.objective);
  }
  const MotionLoadResult read = parseMotionJson(motionJson(sampleAnimation(*jump.problem, 100)), "motion.json");
  ASSERT_TRUE(read.animation) << read.error;
  std::string error;
  // Nothing in common: a motion of another character leaves the default guess.
  Animation other = *read.animation;
  other.characters[0].name = "someone_else";
  auto untouched = SpacetimeProblem::build(jump.problem->scene(), &error);
  const std::vector<double> guess = untouched->variables();
  EXPECT_EQ(startFromMotion(*untouched, other), 0);
  EXPECT_EQ(untouched->variables(), guess);
}

// The first-order multiplier estimate (solver/multiplier_estimate.h) at the augmented
// Lagrangian's own optimum makes its Lagrangian stationary from the motion alone, and from a motion
// file of that optimum it lets the augmented Lagrangian and witkin-kass start warm: Newton steps
// to the same optimum, no LM iteration. Without it the warm polish's program settles the active
// set (before it did, the augmented Lagrangian re-ran its whole path: 375 LM iterations, to
// sqp's 28.0987 instead of its own 28.7735).
TEST(MotionImport, EstimatedMultipliersLetTheAugmentedLagrangianStartWarm) {
  std::string error;
  auto solved = SpacetimeProblem::build(testing::shippedScene("luxo_jump.json"), &error);
  ASSERT_TRUE(solved) << error;
  SolverOptions al;
  al.threads = 2;
  const SolverSummary cold = solveSpacetime(*solved, al);
  ASSERT_TRUE(cold.converged) << cold.reason;

  // At the optimum itself, from the motion alone: multipliers that make the Lagrangian stationary
  // (not the solve's own ones entry by entry: the rows at their bound and the equalities are
  // dependent there, so the multipliers are not unique).
  SolutionState zeroed = solved->state();
  std::fill(zeroed.multipliers.begin(), zeroed.multipliers.end(), 0.0);
  auto same = SpacetimeProblem::build(solved->scene(), &error);
  ASSERT_TRUE(same->restore(zeroed));
  const MultiplierEstimate atOptimum = estimateMultipliers(*same, 1e5, 2);
  ASSERT_TRUE(atOptimum.ok);
  EXPECT_LT(atOptimum.stationarity, 1e-5);  // measured 2.7e-6: the regularisation's bias
  EXPECT_GT(atOptimum.active, 0);

  const MotionLoadResult read = parseMotionJson(motionJson(sampleAnimation(*solved, 1000)), "motion.json");
  ASSERT_TRUE(read.animation) << read.error;
  for (SolverMethod method : {SolverMethod::AugmentedLagrangian, SolverMethod::WitkinKass}) {
    SCOPED_TRACE(static_cast<int>(method));
    ASSERT_TRUE(motionStartReadsMultipliers(method));
    auto fresh = SpacetimeProblem::build(solved->scene(), &error);
    ASSERT_EQ(startFromMotion(*fresh, *read.animation), 1);
    const MultiplierEstimate e = estimateMultipliers(*fresh, 1e5, 2);
    ASSERT_TRUE(e.ok);
    EXPECT_LT(e.stationarity, 1e-4);  // measured 2.7e-6
    SolverOptions o = al;
    o.method = method;
    o.warmStart = true;
    const SolverSummary s = solveSpacetime(*fresh, o);
    ASSERT_TRUE(s.converged) << s.reason;
    EXPECT_EQ(s.iterations, 0) << s.reason;
    EXPECT_LE(s.newtonSteps, 10) << s.reason;
    EXPECT_NEAR(s.objective, cold.objective, 1e-6 * cold.objective);
  }
  EXPECT_FALSE(motionStartReadsMultipliers(SolverMethod::Sqp));
  // Without the estimate the warm polish holds only the equalities; its first step crosses the
  // inequalities the optimum holds, and the quadratic program that settles its active set
  // (PolishOptions::settleActiveSet) finds them and their multipliers: the same optimum, no LM
  // iteration (measured 2 Newton passes), where the augmented Lagrangian used to re-run its whole
  // path (375 LM iterations, to sqp's 28.0987).
  auto bare = SpacetimeProblem::build(solved->scene(), &error);
  ASSERT_EQ(startFromMotion(*bare, *read.animation), 1);
  SolverOptions o = al;
  o.warmStart = true;
  const SolverSummary b = solveSpacetime(*bare, o);
  ASSERT_TRUE(b.converged) << b.reason;
  EXPECT_GT(b.qpSeconds, 0);
  EXPECT_EQ(b.iterations, 0) << b.reason;
  EXPECT_NEAR(b.objective, cold.objective, 1e-6 * cold.objective);
}

// The sampled motion reads each side of the landing's velocity jump from its own frames, also at
// instants a rounding away from the landing's frame (120 Hz frame 96 is at 0.7999999999999999 s,
// the impact at 0.8 s): the after side is the frame's q-dot, the before side its left limit.
TEST(MotionImport, ReadsEachSideOfTheLandingImpact) {
  const SolvedJump& jump = solvedJump();
  const Animation a = sampleAnimation(*jump.problem, 120);
  const MotionLoadResult read = parseMotionJson(motionJson(a), "motion.json");
  ASSERT_TRUE(read.animation) << read.error;
  const std::unique_ptr<MotionSource> source = motionSourceOf(*read.animation);
  const CharacterAnimation& ca = a.characters[0];
  ASSERT_NEAR(ca.times[96], 0.8, 1e-15);
  const double jump96 = (ca.qdBefore.row(96) - ca.qd.row(96)).cwiseAbs().maxCoeff();
  ASSERT_GT(jump96, 1);  // the root's velocity jumps there
  for (double t : {ca.times[96], 0.8, 0.8 - 1e-13, 0.8 + 1e-13}) {
    SCOPED_TRACE(t);
    EXPECT_LT((source->jointState(0, t, 1, false) - jump.problem->jointState(0, 0.8, 1)).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_LT((source->jointState(0, t, 1, true) - jump.problem->jointStateBefore(0, 0.8, 1)).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_LT((source->jointState(0, t, 0, false) - jump.problem->jointState(0, 0.8, 0)).cwiseAbs().maxCoeff(), 1e-9);
  }
  // Between frames: the cubic Hermite's error, far below linear interpolation's h^2/8 |q''|.
  double worst = 0;
  for (double t = 0.01; t < 1.19; t += 0.00137)
    worst = std::max(worst, (source->jointState(0, t, 0) - jump.problem->jointState(0, t, 0)).cwiseAbs().maxCoeff());
  EXPECT_LT(worst, 1e-5);
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
