// Automatic refinement of the transcription (solver/refinement.h): a motion the scene's
// transcription cannot resolve is solved again on finer ones until the validity report passes,
// and a valid one is left alone.
#include <gtest/gtest.h>

#include "../shipped_scene.h"
#include "solver/interior_point.h"
#include "solver/refinement.h"

namespace spacetime {
namespace {

std::unique_ptr<SpacetimeProblem> built(const Scene& scene) {
  std::string error;
  auto problem = SpacetimeProblem::build(scene, &error);
  EXPECT_TRUE(problem) << error;
  return problem;
}

TEST(Refinement, TheSequenceRaisesSamplesThenTheRateUpToItsCap) {
  RefinementOptions options;
  TranscriptionSpec spec;
  spec.controlPointsPerSecond = 20;
  spec.samplesPerSegment = 2;
  TranscriptionSpec finer;
  ASSERT_TRUE(refineTranscription(spec, options, &finer));
  EXPECT_DOUBLE_EQ(finer.controlPointsPerSecond, 30);
  EXPECT_EQ(finer.samplesPerSegment, RefinementOptions::kMaxRefinedSamples);
  spec = finer;
  ASSERT_TRUE(refineTranscription(spec, options, &finer));
  EXPECT_DOUBLE_EQ(finer.controlPointsPerSecond, 45);
  spec.controlPointsPerSecond = 60;  // 90 > the cap of 80: the cap
  ASSERT_TRUE(refineTranscription(spec, options, &finer));
  EXPECT_DOUBLE_EQ(finer.controlPointsPerSecond, 80);
  spec = finer;
  EXPECT_FALSE(refineTranscription(spec, options, &finer));
  // After a stall the rate triples.
  spec.controlPointsPerSecond = 20;
  ASSERT_TRUE(refineTranscription(spec, options, &finer, RefinementOptions::kStallRateGrowth));
  EXPECT_DOUBLE_EQ(finer.controlPointsPerSecond, 60);
}

// The shipped particle and jump are valid at their own transcription: one solve, nothing refined.
TEST(Refinement, AValidMotionIsNotRefined) {
  const Scene scene = testing::shippedScene("particle.json");
  SolverOptions options = solverOptionsFor(scene.solver);
  const RefinedSolve r = solveRefined(built(scene), options, RefinementOptions{});
  ASSERT_EQ(r.attempts.size(), 1u);
  EXPECT_TRUE(r.valid);
  EXPECT_TRUE(r.attempts[0].kept);
  EXPECT_EQ(r.problem->scene().transcription.samplesPerSegment, scene.transcription.samplesPerSegment);
}

// The 1.2 m rung of the jump ladder: at the shipped 20 control points per second and s = 6 the
// solve converges, but 58 % of the lamp's weight is unexplained between the samples (the
// validity report fails; objective 376). Refined (30 control points per second, s = 8), the
// motion passes every check, on the dense grid too, and the summary says where it ended.
TEST(Refinement, TheLongerJumpBecomesValidOnAFinerTranscription) {
  const Scene scene = testing::testScene("ladder/luxo_jump_1.2m.json");
  SolverOptions options = solverOptionsFor(scene.solver);
  options.threads = 2;
  RefinementOptions off;
  off.enabled = false;
  const RefinedSolve coarse = solveRefined(built(scene), options, off);
  ASSERT_TRUE(coarse.summary.converged) << coarse.summary.reason;
  EXPECT_FALSE(coarse.valid);
  EXPECT_GT(coarse.validity.maxUnactuatedResidualDense, 0.01);

  const RefinedSolve refined = solveRefined(built(scene), options, RefinementOptions{});
  ASSERT_TRUE(refined.summary.converged) << refined.summary.reason;
  EXPECT_TRUE(refined.valid) << refined.summary.reason;
  EXPECT_LE(refined.validity.maxUnactuatedResidualDense, 0.01);
  ASSERT_GE(refined.attempts.size(), 2u);
  EXPECT_FALSE(refined.attempts.front().valid);
  EXPECT_TRUE(refined.attempts.back().kept);
  EXPECT_GT(refined.problem->scene().transcription.controlPointsPerSecond, scene.transcription.controlPointsPerSecond);
  EXPECT_NE(refined.summary.reason.find("finer transcription"), std::string::npos) << refined.summary.reason;
  // The refined motion is a better optimum, not only a finer one: the coarse one spent effort on
  // what its transcription could not resolve.
  EXPECT_LT(refined.summary.objective, coarse.summary.objective);
}

// The ladder's 1.5 m rung from the default guess, as `spacetime-cli solve` runs it: at the
// scene's 20 control points per second the augmented Lagrangian stalls (the transcription is too
// coarse for the jump); the stall triples the rate, where the augmented Lagrangian stalls again
// (violation ~0.05) and the interior point, started from that motion, converges to a motion that
// passes every validity check (objective 205.96). Without the hand-over every transcription
// stalls (docs/validation.md).
TEST(Refinement, TheLadders1_5mJumpIsValidAfterAStallAndTheInteriorPoint) {
  if (!interiorPointAvailable()) GTEST_SKIP() << "built without IPOPT (coinor-libipopt-dev)";
  const Scene scene = testing::testScene("ladder/luxo_jump_1.5m.json");
  SolverOptions options = solverOptionsFor(scene.solver);
  options.threads = 2;
  const RefinedSolve r = solveRefined(built(scene), options, RefinementOptions{});
  ASSERT_TRUE(r.summary.converged) << r.summary.reason;
  EXPECT_TRUE(r.valid) << r.summary.reason;
  for (const ValidityCheck& c : validityChecklist(r.validity)) EXPECT_TRUE(c.pass) << c.name << ": " << c.value;
  ASSERT_GE(r.attempts.size(), 2u);
  EXPECT_FALSE(r.attempts.front().converged);
  EXPECT_DOUBLE_EQ(r.attempts[1].controlPointsPerSecond,
                   scene.transcription.controlPointsPerSecond * RefinementOptions::kStallRateGrowth);
  EXPECT_TRUE(r.summary.rescued);
  EXPECT_GT(r.summary.interiorPointIterations, 0);
  EXPECT_NE(r.summary.reason.find("the augmented Lagrangian stalled"), std::string::npos) << r.summary.reason;
}

}  // namespace
}  // namespace spacetime
