// Automatic refinement of the transcription (solver/refinement.h): a motion the scene's
// transcription cannot resolve is solved again on finer ones until the validity report passes,
// and a valid one is left alone.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

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

// Splitting where the dense grid fails (refineWhereResidual): the segments above half the limit
// are halved and no others; the rate stays, s rises to 8. Nothing is split where the residual
// passes, where more segments fail than the uniform refinement would add (it is then the
// better refinement), or where a segment is already as short as two intervals of the rate cap.
TEST(Refinement, SegmentsAreSplitWhereTheDenseResidualIsLarge) {
  TranscriptionSpec spec;
  spec.controlPointsPerSecond = 20;
  spec.samplesPerSegment = 6;
  const CubicBSpline motion(0.0, 1.2, 24);
  ValidityReport report;
  report.maxUnactuatedResidualDense = 0.03;
  report.segmentResidualDense.assign(24, 0.001);
  report.segmentResidualDense[7] = 0.03;
  report.segmentResidualDense[8] = 0.006;
  report.segmentResidualDense[12] = 0.004;  // below half the limit
  const RefinementOptions options;
  TranscriptionSpec finer;
  ASSERT_TRUE(refineWhereResidual(spec, motion, report, options, &finer));
  EXPECT_EQ(finer.controlPointsPerSecond, 20);
  EXPECT_EQ(finer.samplesPerSegment, RefinementOptions::kMaxRefinedSamples);
  ASSERT_EQ(finer.knots.size(), 23u + 2);
  for (int k = 1; k < 24; ++k)
    EXPECT_TRUE(std::any_of(finer.knots.begin(), finer.knots.end(), [&](double t) { return std::abs(t - 0.05 * k) < 1e-12; })) << k;
  EXPECT_NEAR(finer.knots[7], 0.375, 1e-12);
  EXPECT_NEAR(finer.knots[9], 0.425, 1e-12);
  EXPECT_TRUE(std::is_sorted(finer.knots.begin(), finer.knots.end()));
  // Without the rounding of start + k h (0.049999999999999996 for 0.05): scene.json keeps them.
  for (double t : finer.knots) EXPECT_EQ(t, std::round(t * 1000) / 1000) << "a knot with rounding noise";
  // The uniform refinement after it starts from the rate again.
  TranscriptionSpec uniform;
  ASSERT_TRUE(refineTranscription(finer, options, &uniform));
  EXPECT_TRUE(uniform.knots.empty());
  EXPECT_EQ(uniform.controlPointsPerSecond, 30);

  ValidityReport passing = report;
  passing.maxUnactuatedResidualDense = 0.009;
  EXPECT_FALSE(refineWhereResidual(spec, motion, passing, options, &finer));
  ValidityReport everywhere = report;
  for (int k = 0; k < 13; ++k) everywhere.segmentResidualDense[static_cast<size_t>(k)] = 0.02;
  EXPECT_FALSE(refineWhereResidual(spec, motion, everywhere, options, &finer));  // 13 > 24 / 2
  const CubicBSpline fine(0.0, 1.2, 96);  // 12.5 ms segments: the cap's rate (80 per second)
  ValidityReport atTheCap;
  atTheCap.maxUnactuatedResidualDense = 0.03;
  atTheCap.segmentResidualDense.assign(96, 0.0);
  atTheCap.segmentResidualDense[30] = 0.03;
  EXPECT_FALSE(refineWhereResidual(spec, fine, atTheCap, options, &finer));
}

// The 1.2 m rung of the jump ladder: at the shipped 20 control points per second and s = 6 the
// solve converges, but 58 % of the lamp's weight is unexplained between the samples (the
// validity report fails; objective 376). Where a finer transcription follows, that solve stops
// once its motion nears the constraints and the residual between the samples does not fall with
// the violation (2.97 x the weight at 2.7e-4, 1.87 at 2.6e-5: after 1620 of its 3442 LM
// iterations); its segments are split where that residual is (24 → 34 segments, s = 8; then once
// more, 35), and the motion passes every check, on the dense grid too, at a lower objective than
// the uniform 30 control points per second reach (97.45 against 136.82 at 36 segments), and the
// summary says where it ended.
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
  EXPECT_TRUE(refined.attempts.front().tooCoarse);
  EXPECT_GT(refined.attempts.front().maxUnactuatedResidualDense, RefinementOptions::kCoarseFactor * kDenseResidualLimit);
  EXPECT_LT(refined.attempts.front().iterations, coarse.summary.iterations / 2);
  EXPECT_NE(refined.attempts[1].why.find("before its solve converged"), std::string::npos) << refined.attempts[1].why;
  EXPECT_TRUE(refined.attempts.back().kept);
  // Split where the residual was, fewer segments than a uniform refinement would have at the
  // kept transcription's level (1.5x per level).
  const TranscriptionAttempt& kept = refined.attempts.back();
  EXPECT_TRUE(kept.nonUniform);
  EXPECT_FALSE(refined.problem->scene().transcription.knots.empty());
  EXPECT_GT(kept.segments, 24);
  EXPECT_LT(kept.segments, 24 * std::pow(RefinementOptions::kRateGrowth, refined.attempts.size() - 1));
  EXPECT_NE(refined.summary.reason.find("finer transcription"), std::string::npos) << refined.summary.reason;
  // The refined motion is a better optimum, not only a finer one: the coarse one spent effort on
  // what its transcription could not resolve.
  EXPECT_LT(refined.summary.objective, coarse.summary.objective);
  EXPECT_LT(refined.summary.objective, 136.8);  // the uniform refinement's optimum (30 per second, s = 8)

  // The last transcription follows a converged one: its re-fitted motion misses mostly the rows
  // the split added, and the SQP's damped exact-Hessian steps (RefinementOptions::warmSqpSteps)
  // finish it without a multiplier update, at the optimum the augmented Lagrangian's updates
  // reach from the same start.
  ASSERT_TRUE(refined.attempts[refined.attempts.size() - 2].converged);
  EXPECT_EQ(kept.iterations, 0);
  EXPECT_NE(refined.summary.reason.find("warm from the starting motion"), std::string::npos) << refined.summary.reason;
  RefinementOptions withoutSteps;
  withoutSteps.warmSqpSteps = 0;
  const RefinedSolve updated = solveRefined(built(scene), options, withoutSteps);
  ASSERT_TRUE(updated.valid) << updated.summary.reason;
  ASSERT_EQ(updated.attempts.size(), refined.attempts.size());
  EXPECT_GT(updated.attempts.back().iterations, 0);
  EXPECT_NEAR(refined.summary.objective, updated.summary.objective, 1e-6 * updated.summary.objective);
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
