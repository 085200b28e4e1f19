// Leg bubbles (solver/leg_bubbles.cpp): a planar quadruped (front and hind legs of two joints,
// point feet, tests/scenes/legs/) standing on both feet. Its root meets one foot's still-rows;
// without leg bubbles the other foot's rows per interval outnumber what its leg's B-splines can
// meet, and a squat - the body lowered, moved and tilted between two equal poses - stalls at any
// rate. With them the hind leg gets s - 1 bubbles per stance interval and joint, the joints stay
// C2, the squat solves to a motion that passes every validity check, and so does a 0.3 m hop.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <random>

#include "../shipped_scene.h"
#include "solver/augmented_lagrangian.h"
#include "solver/refinement.h"
#include "solver/validity.h"

namespace spacetime {
namespace {

Scene withLegBubbles(Scene s) {
  s.transcription.legBubbles = true;
  return s;
}

const DofGroup* legGroup(const SpacetimeProblem& p) {
  for (const DofGroup& g : p.characters()[0].groups)
    if (g.legBubbles) return &g;
  return nullptr;
}

TEST(LegBubbles, OnlyOnTheLegsOfFeetTheRootDoesNotMeetAndOnlyInTheirStances) {
  std::string error;
  const Scene hop = testing::testScene("legs/planar_quadruped_hop.json");
  const auto without = SpacetimeProblem::build(hop, &error);
  ASSERT_TRUE(without) << error;
  EXPECT_FALSE(without->hasLegBubbles());  // off unless asked for

  const auto p = SpacetimeProblem::build(withLegBubbles(hop), &error);
  ASSERT_TRUE(p) << error;
  ASSERT_TRUE(p->hasLegBubbles());
  int groups = 0;
  for (const DofGroup& g : p->characters()[0].groups) groups += g.legBubbles;
  EXPECT_EQ(groups, 1);
  // The front foot (the first contact) is met by the root's three dofs, leaving one: the hind
  // foot's two rows go to the hind leg's hip and knee.
  const DofGroup& g = *legGroup(*p);
  const Model<double>& model = *p->characters()[0].model;
  EXPECT_EQ(g.dofs, (std::vector<int>{model.dofIndex("h_hip"), model.dofIndex("h_knee")}));
  const int s = hop.transcription.samplesPerSegment;
  int stance = 0, flight = 0;
  for (size_t k = 0; k + 1 < g.breaks.size(); ++k) {
    const double mid = 0.5 * (g.breaks[k] + g.breaks[k + 1]);
    if (g.breaks[k + 1] - g.breaks[k] < kTimeTolerance) continue;
    const bool onFeet = mid < 0.45 || mid > 0.8;
    EXPECT_EQ(g.bubblesIn(static_cast<int>(k)), onFeet ? s - 1 : 0) << "interval at " << mid;
    (onFeet ? stance : flight)++;
  }
  EXPECT_GT(stance, 10);
  EXPECT_GT(flight, 5);
  EXPECT_EQ(p->variables().size(), without->variables().size() + static_cast<size_t>(stance * (s - 1) * 2));

  // The planar biped's feet have two points each (three rows): the root meets the left one, the
  // right leg's hip, knee and ankle get the right one's.
  const auto biped = SpacetimeProblem::build(withLegBubbles(testing::shippedScene("biped_jump.json")), &error);
  ASSERT_TRUE(biped) << error;
  const Model<double>& bm = *biped->characters()[0].model;
  ASSERT_TRUE(legGroup(*biped));
  EXPECT_EQ(legGroup(*biped)->dofs,
            (std::vector<int>{bm.dofIndex("r_hip"), bm.dofIndex("r_knee"), bm.dofIndex("r_ankle")}));
  // Lamps stand on their root: nothing to add.
  EXPECT_FALSE(SpacetimeProblem::build(withLegBubbles(testing::shippedScene("luxo_jump.json")), &error)->hasLegBubbles());
}

TEST(LegBubbles, KeepTheJointsC2AndVanishAtTheBreakpoints) {
  std::string error;
  const auto p = SpacetimeProblem::build(withLegBubbles(testing::testScene("legs/planar_quadruped_hop.json")), &error);
  ASSERT_TRUE(p) << error;
  const DofGroup& g = *legGroup(*p);
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.1);
  for (double& x : p->variables()) x += noise(rng);
  // The leg bubbles' own contribution: the motion minus the same motion without them.
  std::vector<double> bubbles(p->variables().begin() + g.offset, p->variables().begin() + g.offset + g.variableCount());
  auto legState = [&](double t, int order, bool with) {
    std::copy(bubbles.begin(), bubbles.end(), p->variables().begin() + g.offset);
    if (!with) std::fill_n(p->variables().begin() + g.offset, g.variableCount(), 0.0);
    const Eigen::VectorXd q = p->jointState(0, t, order);
    return Eigen::Vector2d(q[g.dofs[0]], q[g.dofs[1]]);
  };
  double largest = 0;
  const double eps = 1e-6;
  for (size_t k = 1; k + 1 < g.breaks.size(); ++k) {
    const double t = g.breaks[k];
    for (int order = 0; order <= 2; ++order) {
      // Zero with two derivatives at the breakpoint...
      EXPECT_LT((legState(t, order, true) - legState(t, order, false)).norm(), 1e-9) << t << " order " << order;
      // ... so the joint is continuous there up to its second derivative: the difference across
      // the breakpoint, extrapolated to a zero gap (Richardson: the smooth part is a e + b e^2 in
      // the gap e, with b large for the bubbles' high degree - about 1e9 at order 2 - so both are
      // eliminated; a jump would not shrink).
      // Returns a vector, not Eigen's expression of the difference: that would refer to the two
      // states after they are gone (ASan: stack-use-after-scope).
      auto across = [&](double e) -> Eigen::Vector2d { return legState(t + e, order, true) - legState(t - e, order, true); };
      const Eigen::Vector2d jump = (8 * across(eps) - 6 * across(2 * eps) + across(4 * eps)) / 3;
      EXPECT_LT(jump.norm(), 1e-4) << t << " order " << order;
    }
    largest = std::max(largest, (legState(0.5 * (t + g.breaks[k + 1]), 0, true) -
                                 legState(0.5 * (t + g.breaks[k + 1]), 0, false)).norm());
  }
  EXPECT_GT(largest, 0.05);  // and they do move the legs between the breakpoints
}

TEST(LegBubbles, AQuadrupedSquatOnBothFeetStallsWithoutThemAndIsValidWithThem) {
  const Scene scene = testing::testScene("legs/planar_quadruped_squat.json");
  std::string error;
  auto problem = SpacetimeProblem::build(scene, &error);
  ASSERT_TRUE(problem) << error;
  SolverOptions options = solverOptionsFor(scene.solver);
  options.threads = 2;
  options.interiorPointAfterStall = false;
  // Twice the scene's budget: the stall and the solve with leg bubbles took 23 + 67 s on a quiet
  // day, but one CI run on a loaded machine ran out of 300 s on the second.
  options.maxSeconds = 2 * scene.solver.maxSeconds;
  RefinementOptions refinement;
  refinement.maxRefinements = 1;
  const RefinedSolve r = solveRefined(std::move(problem), options, refinement);
  ASSERT_EQ(r.attempts.size(), 2u);
  // The scene's transcription: the hind foot's rows cannot all be met.
  EXPECT_FALSE(r.attempts[0].converged);
  EXPECT_FALSE(r.attempts[0].legBubbles);
  // Then leg bubbles at the same rate: valid.
  EXPECT_TRUE(r.attempts[1].legBubbles);
  EXPECT_EQ(r.attempts[1].controlPointsPerSecond, scene.transcription.controlPointsPerSecond);
  ASSERT_TRUE(r.valid) << r.summary.reason;
  EXPECT_TRUE(r.attempts[1].kept);
  const ValidityReport& v = r.validity;
  for (const ValidityCheck& c : validityChecklist(v))
    EXPECT_TRUE(c.pass) << c.name << ": " << c.value << " " << c.unit << " (limit " << c.limit << ")";
  // The body went where the middle key says while both feet stayed put.
  const Eigen::VectorXd mid = r.problem->jointState(0, 0.6, 0);
  EXPECT_NEAR(mid[0], 0.08, 1e-6);
  EXPECT_NEAR(mid[2], 0.1, 1e-6);
  std::printf("quadruped squat: stalled at violation %.3g without leg bubbles (%.1f s); with them objective %.6g, "
              "%.1f s, dense residual %.3g of weight\n",
              r.attempts[0].maxViolation, r.attempts[0].seconds, r.attempts[1].objective, r.attempts[1].seconds,
              v.maxUnactuatedResidualDense);
}

// The same quadruped hops 0.3 m forward from its default guess, refined as the CLI refines: the
// scene's transcription stalls, leg bubbles at the same rate come close (the point feet slip
// between the nodes), and 1.5x the rate with the same s is valid.
TEST(LegBubbles, AQuadrupedHopIsValidAfterTheRefinementAddsThem) {
  const Scene scene = testing::testScene("legs/planar_quadruped_hop.json");
  std::string error;
  auto problem = SpacetimeProblem::build(scene, &error);
  ASSERT_TRUE(problem) << error;
  SolverOptions options = solverOptionsFor(scene.solver);
  options.threads = 2;
  const RefinedSolve r = solveRefined(std::move(problem), options, RefinementOptions{});
  ASSERT_TRUE(r.valid) << r.summary.reason;
  ASSERT_GE(r.attempts.size(), 2u);
  EXPECT_FALSE(r.attempts[0].converged);
  EXPECT_TRUE(r.attempts[1].legBubbles);
  const TranscriptionSpec& kept = r.problem->scene().transcription;
  EXPECT_TRUE(kept.legBubbles);
  EXPECT_EQ(kept.samplesPerSegment, scene.transcription.samplesPerSegment);
  for (const ValidityCheck& c : validityChecklist(r.validity))
    EXPECT_TRUE(c.pass) << c.name << ": " << c.value << " " << c.unit << " (limit " << c.limit << ")";
  // Both feet leave the ground and it lands 0.3 m ahead.
  EXPECT_NEAR(r.problem->jointState(0, 1.2, 0)[0], 0.3, 1e-6);
  EXPECT_GT(r.problem->jointState(0, 0.62, 0)[1], r.problem->jointState(0, 0.0, 0)[1]);
  std::printf("quadruped hop: valid at %g control points per second, s = %d, with leg bubbles; objective %.6g, "
              "%zu transcriptions, %.1f s\n",
              kept.controlPointsPerSecond, kept.samplesPerSegment, r.summary.objective, r.attempts.size(),
              r.summary.solveSeconds);
}

}  // namespace
}  // namespace spacetime
