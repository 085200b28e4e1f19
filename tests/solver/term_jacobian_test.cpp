// Every term's Jacobian (Jets through the dynamics, chained through the spline basis and the
// augmented-Lagrangian transform) against central finite differences, at a perturbed point
// of each shipped scene with non-zero multipliers, so every kernel kind is exercised (and of the
// Luxo jump landing on two contact terms at once, for the shared impact).
#include <gtest/gtest.h>

#include <random>
#include <set>

#include "../shipped_scene.h"
#include "split_landing.h"
#include "core/scene_io.h"
#include "solver/spacetime_problem.h"

namespace spacetime {
namespace {

class TermJacobians : public ::testing::TestWithParam<const char*> {};

TEST_P(TermJacobians, MatchFiniteDifferences) {
  std::string error;
  // "NAME:split" is the shipped scene with its landing split into one contact per point.
  const std::string name = GetParam();
  const bool split = name.size() > 6 && name.substr(name.size() - 6) == ":split";
  const Scene shipped = testing::shippedScene(split ? name.substr(0, name.size() - 6) : name);
  auto problem = SpacetimeProblem::build(split ? testing::withSplitLanding(shipped) : shipped, &error);
  ASSERT_TRUE(problem) << error;
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.05);
  for (double& x : problem->variables()) x += noise(rng);
  AugmentedLagrangianState& al = problem->augmentedLagrangian();
  al.rho = 7.0;
  for (double& l : al.lambda) l = noise(rng) * 10;
  int checked = 0;
  std::set<std::string> kinds;
  for (const TermResidual* res : problem->residuals()) {
    const int m = res->num_residuals();
    const auto& sizes = res->parameter_block_sizes();
    std::vector<const double*> params(res->blocks().begin(), res->blocks().end());
    std::vector<std::vector<double>> jac(sizes.size());
    std::vector<double*> jacPtr;
    for (size_t b = 0; b < sizes.size(); ++b) {
      jac[b].resize(m * sizes[b]);
      jacPtr.push_back(jac[b].data());
    }
    std::vector<double> r0(m), rp(m), rm(m);
    ASSERT_TRUE(res->Evaluate(params.data(), r0.data(), jacPtr.data()));
    // Skip rows at an inequality's kink, where the derivative is one-sided.
    std::vector<bool> smooth(m, true);
    for (size_t b = 0; b < sizes.size(); ++b) {
      for (int i = 0; i < sizes[b]; ++i) {
        double* x = res->blocks()[b] + i;
        const double saved = *x, h = 1e-6 * std::max(1.0, std::abs(saved));
        *x = saved + h;
        res->Evaluate(params.data(), rp.data(), nullptr);
        *x = saved - h;
        res->Evaluate(params.data(), rm.data(), nullptr);
        *x = saved;
        for (int row = 0; row < m; ++row) {
          if ((rp[row] == 0) != (rm[row] == 0)) smooth[row] = false;
          if (!smooth[row]) continue;
          const double fd = (rp[row] - rm[row]) / (2 * h);
          const double an = jac[b][row * sizes[b] + i];
          EXPECT_NEAR(an, fd, 1e-5 * (1 + std::abs(fd))) << res->kernel().label() << " row " << row;
          ++checked;
        }
      }
    }
    kinds.insert(res->kernel().label().substr(0, res->kernel().label().find(' ')));
  }
  // Luxo: dynamics, smoothness, joint limits, keyframe, rest, contact, clearance.
  const bool luxo = std::string(GetParam()).rfind("luxo", 0) == 0;
  EXPECT_GT(checked, luxo ? 5000 : 500);
  EXPECT_GE(kinds.size(), luxo ? 7u : 2u);
}

INSTANTIATE_TEST_SUITE_P(Scenes, TermJacobians,
                         ::testing::Values("luxo_jump.json", "luxo_3d.json", "particle_gravity.json",
                                           "luxo_jump.json:split"));

}  // namespace
}  // namespace spacetime
