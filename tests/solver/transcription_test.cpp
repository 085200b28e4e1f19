// The collocation grid: Gauss-Radau nodes against the exactness that defines them, and the
// transcription's use of them where a flight starts after a lift-off.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "../shipped_scene.h"
#include "staggered_lamps.h"
#include "solver/spacetime_problem.h"
#include "solver/transcription.h"

namespace spacetime {
namespace {

// n-point left Gauss-Radau quadrature starts at -1 and integrates x^k exactly on [-1, 1] for
// k <= 2n - 2, and not for 2n - 1 (one degree less than Gauss-Legendre: one node is fixed).
TEST(GaussRadau, StartsAtMinusOneAndIsExactToDegree2nMinus2) {
  for (int n = 1; n <= 9; ++n) {
    std::vector<double> x, w;
    gaussRadau(n, &x, &w);
    ASSERT_EQ(static_cast<int>(x.size()), n);
    EXPECT_EQ(x[0], -1.0);
    for (int i = 1; i < n; ++i) EXPECT_GT(x[i], x[i - 1]) << n;
    for (int k = 0; k <= 2 * n - 1; ++k) {
      double sum = 0;
      for (int i = 0; i < n; ++i) sum += w[i] * std::pow(x[i], k);
      const double exact = k % 2 == 0 ? 2.0 / (k + 1) : 0.0;
      if (k <= 2 * n - 2) EXPECT_NEAR(sum, exact, 1e-13) << "n " << n << " x^" << k;
      else EXPECT_GT(std::abs(sum - exact), 1e-6) << "n " << n << " x^" << k;
    }
  }
  // n = 3 in closed form: -1, (1 -+ sqrt 6) / 5; weights 2/9, (16 +- sqrt 6) / 18.
  std::vector<double> x, w;
  gaussRadau(3, &x, &w);
  EXPECT_NEAR(x[1], (1 - std::sqrt(6.0)) / 5, 1e-14);
  EXPECT_NEAR(x[2], (1 + std::sqrt(6.0)) / 5, 1e-14);
  EXPECT_NEAR(w[0], 2.0 / 9, 1e-14);
  EXPECT_NEAR(w[1], (16 + std::sqrt(6.0)) / 18, 1e-14);
  EXPECT_NEAR(w[2], (16 - std::sqrt(6.0)) / 18, 1e-14);
}

// luxo_jump lifts off at 0.4 s: the interval [0.4, 0.45] holds s + 1 Radau samples, the first
// at 0.4 read on the flight side, with weights summing to its length; every other interval
// keeps s Gauss samples; the root has one more bubble there (s - 1 instead of s - 2).
TEST(Transcription, AFlightStartGetsRadauNodesAndTheRootABubble) {
  const Scene scene = testing::shippedScene("luxo_jump.json");
  const int s = scene.transcription.samplesPerSegment;
  const Transcription tr = Transcription::fromScene(scene);
  ASSERT_EQ(tr.flightStarts.size(), 1u);
  EXPECT_NEAR(tr.flightStarts[0].time, 0.4, 1e-12);
  int inside = 0, after = 0;
  double weight = 0;
  for (const Sample& smp : tr.samples) {
    after += smp.after;
    if (smp.weight > 0 && smp.time >= 0.4 - 1e-12 && smp.time < 0.45 - 1e-12) {
      ++inside;
      weight += smp.weight;
      if (std::abs(smp.time - 0.4) < 1e-12) {
        EXPECT_TRUE(smp.after);
      }
    }
  }
  EXPECT_EQ(after, 1);
  EXPECT_EQ(inside, s + 1);
  EXPECT_NEAR(weight, 0.05, 1e-12);
  int gaussInNext = 0;
  for (const Sample& smp : tr.samples) gaussInNext += smp.weight > 0 && smp.time > 0.45 && smp.time < 0.5;
  EXPECT_EQ(gaussInNext, s);

  std::string error;
  const auto problem = SpacetimeProblem::build(scene, &error);
  ASSERT_TRUE(problem) << error;
  const DofGroup* root = nullptr;
  for (const DofGroup& g : problem->characters()[0].groups)
    if (g.hermite) root = &g;
  ASSERT_TRUE(root);
  for (size_t k = 0; k + 1 < root->breaks.size(); ++k)
    EXPECT_EQ(root->bubblesIn(static_cast<int>(k)), std::abs(root->breaks[k] - 0.4) < 1e-12 ? s - 1 : s - 2)
        << "interval from " << root->breaks[k];
}

// Two lamps lifting off at 0.4 s and 0.5 s: each flight start gets Radau nodes for the lamp
// lifting off and Gauss nodes for the other (standing at 0.4, flying at 0.5), each lamp's
// weights on every interval sum to its length, and only the lifting lamp's root gets the bubble.
TEST(Transcription, EachCharacterHasItsOwnNodesWhereAFlightStarts) {
  const Scene first = testing::shippedScene("luxo_jump.json");
  const Scene both = testing::together(first, testing::laterLamp(first));
  const int s = both.transcription.samplesPerSegment;
  const Transcription tr = Transcription::fromScene(both);
  ASSERT_EQ(tr.flightStarts.size(), 2u);
  const std::string ids[2] = {"luxo", "luxo2"};
  for (int c = 0; c < 2; ++c) {
    const double liftOff = c == 0 ? 0.4 : 0.5;
    EXPECT_NEAR(tr.flightStarts[c].time, liftOff, 1e-12);
    EXPECT_EQ(tr.flightStarts[c].characters, std::vector<std::string>{ids[c]});
    for (double start : {0.4, 0.5}) {
      int nodes = 0, after = 0;
      double weight = 0;
      for (const Sample& smp : tr.samples)
        if (smp.appliesTo(ids[c]) && smp.weight > 0 && smp.time >= start - 1e-12 && smp.time < start + 0.05 - 1e-12) {
          ++nodes;
          after += smp.after;
          weight += smp.weight;
        }
      const bool lifting = std::abs(start - liftOff) < 1e-12;
      EXPECT_EQ(nodes, lifting ? s + 1 : s) << ids[c] << " from " << start;
      EXPECT_EQ(after, lifting ? 1 : 0) << ids[c] << " from " << start;
      EXPECT_NEAR(weight, 0.05, 1e-12) << ids[c] << " from " << start;
    }
  }

  std::string error;
  const auto problem = SpacetimeProblem::build(both, &error);
  ASSERT_TRUE(problem) << error;
  for (int c = 0; c < 2; ++c) {
    const DofGroup& root = problem->characters()[c].groups[1];
    ASSERT_TRUE(root.hermite);
    for (size_t k = 0; k + 1 < root.breaks.size(); ++k)
      EXPECT_EQ(root.bubblesIn(static_cast<int>(k)), std::abs(root.breaks[k] - (c == 0 ? 0.4 : 0.5)) < 1e-12 ? s - 1 : s - 2)
          << ids[c] << ", interval from " << root.breaks[k];
  }
}

// One lamp touches down at 0.8 s as the other lifts off: the lifting lamp gets the Radau nodes,
// the landing one keeps Gauss nodes (its touch-down already has its own edge sample and impact).
TEST(Transcription, ATouchDownAtAnotherCharactersLiftOffKeepsGaussNodes) {
  const Scene first = testing::shippedScene("luxo_jump.json");
  Scene second = testing::laterLamp(first);
  for (TermSpec& t : second.terms)
    if (t.kind == TermKind::Contact && t.start < 0.1) t.end = 0.8;
  const Transcription tr = Transcription::fromScene(testing::together(first, second));
  const int s = first.transcription.samplesPerSegment;
  ASSERT_EQ(tr.flightStarts.size(), 2u);
  EXPECT_NEAR(tr.flightStarts[1].time, 0.8, 1e-12);
  EXPECT_EQ(tr.flightStarts[1].characters, std::vector<std::string>{"luxo2"});
  for (const std::string id : {"luxo", "luxo2"}) {
    int nodes = 0;
    for (const Sample& smp : tr.samples)
      nodes += smp.appliesTo(id) && smp.weight > 0 && smp.time >= 0.8 - 1e-12 && smp.time < 0.85 - 1e-12;
    EXPECT_EQ(nodes, id == "luxo2" ? s + 1 : s) << id;
  }
}

// The refinement's non-uniform knots (TranscriptionSpec::knots): luxo_jump with the two
// segments around its lift-off at 0.4 s split. The split points are breakpoints, each interval
// holds its s Gauss samples (s + 1 Radau ones from the lift-off) whose weights sum to its length,
// and the dense grid is as much finer there as the samples are. Knots equal to the uniform ones
// give the uniform problem: the same variables and the same initial guess.
TEST(Transcription, SplitSegmentsGetTheirOwnSamplesAndDenseGrid) {
  Scene scene = testing::shippedScene("luxo_jump.json");
  const int s = scene.transcription.samplesPerSegment;
  const int uniformSegments = 24;  // 1.2 s at 20 control points per second
  for (int k = 1; k < uniformSegments; ++k) {
    scene.transcription.knots.push_back(0.05 * k);
    if (k == 7 || k == 8) scene.transcription.knots.push_back(0.05 * k + 0.025);
  }
  const Transcription tr = Transcription::fromScene(scene);
  EXPECT_FALSE(tr.motion.uniform());
  EXPECT_EQ(tr.motion.segmentCount(), uniformSegments + 2);
  for (double split : {0.375, 0.425})
    EXPECT_TRUE(std::any_of(tr.breakpoints.begin(), tr.breakpoints.end(), [&](double b) { return std::abs(b - split) < 1e-12; }))
        << split;
  for (size_t k = 0; k + 1 < tr.breakpoints.size(); ++k) {
    const double a = tr.breakpoints[k], b = tr.breakpoints[k + 1];
    int nodes = 0;
    double weight = 0;
    for (const Sample& smp : tr.samples)
      if (smp.weight > 0 && smp.time >= a - 1e-12 && smp.time < b - 1e-12) {
        ++nodes;
        weight += smp.weight;
      }
    EXPECT_EQ(nodes, std::abs(a - 0.4) < 1e-12 ? s + 1 : s) << "interval from " << a;
    EXPECT_NEAR(weight, b - a, 1e-12) << "interval from " << a;
  }
  const std::vector<double> dense = tr.denseGrid(kDenseGridFactor);
  auto spacingAt = [&](double t) {
    const auto it = std::upper_bound(dense.begin(), dense.end(), t);
    return *it - *(it - 1);
  };
  EXPECT_NEAR(spacingAt(0.39), 0.025 / (s * kDenseGridFactor), 1e-12);  // a split segment
  EXPECT_NEAR(spacingAt(0.61), 0.05 / (s * kDenseGridFactor), 1e-12);   // a whole one
  EXPECT_DOUBLE_EQ(dense.front(), 0.0);
  EXPECT_DOUBLE_EQ(dense.back(), 1.2);

  Scene even = testing::shippedScene("luxo_jump.json");
  for (int k = 1; k < uniformSegments; ++k) even.transcription.knots.push_back(0.05 * k);
  std::string error;
  const auto uniform = SpacetimeProblem::build(testing::shippedScene("luxo_jump.json"), &error);
  ASSERT_TRUE(uniform) << error;
  const auto knotted = SpacetimeProblem::build(even, &error);
  ASSERT_TRUE(knotted) << error;
  EXPECT_FALSE(knotted->transcription().motion.uniform());
  ASSERT_EQ(knotted->variables().size(), uniform->variables().size());
  for (size_t i = 0; i < uniform->variables().size(); ++i)
    EXPECT_NEAR(knotted->variables()[i], uniform->variables()[i], 1e-9 * (1 + std::abs(uniform->variables()[i]))) << i;
}

}  // namespace
}  // namespace spacetime
