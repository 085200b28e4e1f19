// Every term's Jacobian (Jets through the dynamics, chained through the spline basis and the
// augmented-Lagrangian transform) against central finite differences, at a perturbed point
// of each shipped scene with non-zero multipliers, so every kernel kind is exercised (and of the
// Luxo jump landing on two contact terms at once, for the shared impact; of the biped with leg
// bubbles; of the humanoid on four-point soles, whose anchors and still rows keep a subset of the
// points' rows). And every term's equality rows independent of each other, so the constraint Jacobian
// has no redundant rows by construction (what a KKT system needs).
#include <gtest/gtest.h>

#include <Eigen/QR>

#include <algorithm>
#include <map>
#include <random>
#include <set>

#include "../shipped_scene.h"
#include "split_landing.h"
#include "core/scene_io.h"
#include "solver/kernels.h"
#include "solver/spacetime_problem.h"

namespace spacetime {
namespace {

// One term's rows and Jacobian at the variables' current values: one row-major block per
// parameter block.
struct TermJacobian {
  bool evaluated = false;
  std::vector<double> rows;
  std::vector<std::vector<double>> blocks;
};

TermJacobian termJacobian(const TermResidual& res) {
  const int m = res.num_residuals();
  const auto& sizes = res.parameter_block_sizes();
  std::vector<const double*> params(res.blocks().begin(), res.blocks().end());
  TermJacobian t;
  t.rows.resize(m);
  t.blocks.resize(sizes.size());
  std::vector<double*> pointers;
  for (size_t b = 0; b < sizes.size(); ++b) {
    t.blocks[b].resize(m * sizes[b]);
    pointers.push_back(t.blocks[b].data());
  }
  t.evaluated = res.Evaluate(params.data(), t.rows.data(), pointers.data());
  return t;
}

class TermJacobians : public ::testing::TestWithParam<const char*> {};

TEST_P(TermJacobians, MatchFiniteDifferences) {
  std::string error;
  // "NAME:split" is the shipped scene with its landing split into one contact per point;
  // "NAME:free" the same with a free take-off end (the lift-off instant a variable) and three
  // samples per interval (root curves with a bubble).
  const std::string param = GetParam();
  const std::string name = param.substr(0, param.find(':'));
  const std::string variant = param.size() > name.size() ? param.substr(name.size() + 1) : "";
  Scene scene = testing::shippedScene(name);
  if (variant == "split") scene = testing::withSplitLanding(scene);
  if (variant == "legs") scene.transcription.legBubbles = true;  // the right leg's (leg_bubbles.cpp)
  if (variant == "free") {
    scene.transcription.samplesPerSegment = 3;
    for (TermSpec& t : scene.terms)
      if (t.kind == TermKind::Contact && t.start == scene.startTime) t.freeEnd = true;
  }
  auto problem = SpacetimeProblem::build(scene, &error);
  ASSERT_TRUE(problem) << error;
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.05);
  for (double& x : problem->variables()) x += noise(rng);
  // A lift-off instant moves within its window, away from where the problem was built.
  for (const FreeEnd& e : problem->freeEnds())
    problem->variables()[e.offset] = e.current + 0.6 * (e.upper - e.current);
  EXPECT_EQ(problem->freeEnds().size(), variant == "free" ? 1u : 0u);
  AugmentedLagrangianState& al = problem->augmentedLagrangian();
  al.rho = 7.0;
  for (double& l : al.lambda) l = noise(rng) * 10;
  int checked = 0, movingChecked = 0;
  std::set<std::string> kinds;
  for (const TermResidual* res : problem->residuals()) {
    const int m = res->num_residuals();
    const auto& sizes = res->parameter_block_sizes();
    std::vector<const double*> params(res->blocks().begin(), res->blocks().end());
    const TermJacobian at = termJacobian(*res);
    ASSERT_TRUE(at.evaluated);
    const std::vector<std::vector<double>>& jac = at.blocks;
    std::vector<double> rp(m), rm(m);
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
          EXPECT_NEAR(an, fd, 1e-5 * (1 + std::abs(fd))) << res->kernel().label() << " row " << row
                                                          << " block " << b;
          ++checked;
          if (res->moving() && b + 1 == sizes.size() && an != 0) ++movingChecked;
        }
      }
    }
    kinds.insert(res->kernel().label().substr(0, res->kernel().label().find(' ')));
  }
  // Luxo: dynamics, smoothness, joint limits, keyframe, rest, contact, clearance.
  const bool luxo = std::string(GetParam()).rfind("luxo", 0) == 0;
  EXPECT_GT(checked, luxo ? 5000 : 500);
  EXPECT_GE(kinds.size(), luxo ? 7u : 2u);
  // The lift-off instant's column: every kind of term in the window depends on it.
  if (variant == "free") {
    EXPECT_GT(movingChecked, 50);
  }
}

INSTANTIATE_TEST_SUITE_P(Scenes, TermJacobians,
                         ::testing::Values("luxo_jump.json", "luxo_3d.json", "particle_gravity.json",
                                           "luxo_jump.json:split", "luxo_jump.json:free",
                                           "luxo_3d.json:free", "biped_jump.json:legs", "humanoid_jump.json"));

// Within each term the equality rows' Jacobian (with respect to the variables it touches, at a
// perturbed default guess) has full row rank. A contact's points move rigidly, so rows per point
// are dependent: two points in the plane have velocities of rank 3, a flat sole of four points
// heights of rank 3 and velocities of rank 6. Such rows stalled the humanoid and leave the Newton
// polish's and IPOPT's KKT systems singular.
class TermRows : public ::testing::TestWithParam<const char*> {};

TEST_P(TermRows, EqualityRowsOfEachTermAreIndependent) {
  std::string error;
  auto problem = SpacetimeProblem::build(testing::shippedScene(GetParam()), &error);
  ASSERT_TRUE(problem) << error;
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.05);
  for (double& x : problem->variables()) x += noise(rng);
  problem->augmentedLagrangian().raw = true;  // the rows themselves
  int checkedRows = 0;
  std::set<std::string> contactKinds;
  for (const TermResidual* res : problem->residuals()) {
    const std::vector<RowKind>& kinds = res->kernel().rowKinds();
    std::vector<int> equalities;
    for (size_t r = 0; r < kinds.size(); ++r)
      if (kinds[r] == RowKind::Equality) equalities.push_back(static_cast<int>(r));
    // Two feet landing together can repeat each other: the humanoid's legs turn only about z, so
    // both say the pelvis does not roll or yaw. That dependence is the character's, not a term's.
    if (equalities.empty() || res->kernel().label().find("' and '") != std::string::npos) continue;
    const auto& sizes = res->parameter_block_sizes();
    const TermJacobian at = termJacobian(*res);
    ASSERT_TRUE(at.evaluated);
    const std::vector<std::vector<double>>& jac = at.blocks;
    int columns = 0;
    for (int size : sizes) columns += size;
    Eigen::MatrixXd J(equalities.size(), columns);
    for (size_t i = 0; i < equalities.size(); ++i)
      for (size_t b = 0, c = 0; b < sizes.size(); c += sizes[b], ++b)
        for (int k = 0; k < sizes[b]; ++k) J(i, c + k) = jac[b][equalities[i] * sizes[b] + k];
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(J.transpose());
    qr.setThreshold(1e-10);
    EXPECT_EQ(qr.rank(), J.rows()) << res->kernel().label() << ": " << J.rows() << " equality rows";
    checkedRows += static_cast<int>(J.rows());
    const std::string& label = res->kernel().label();
    for (const char* kind : {"anchor", "still", "at rest", "impact"})
      if (label.find(kind) != std::string::npos) contactKinds.insert(kind);
  }
  EXPECT_GT(checkedRows, 100);
  EXPECT_TRUE(contactKinds.count("anchor") && (contactKinds.count("impact") || contactKinds.count("still"))) << GetParam();
}

// The lamps' two-point base (planar and 3D: rest and landing in a held stance), the biped's feet
// kept still by their motion, the humanoid's four-point soles.
INSTANTIATE_TEST_SUITE_P(Scenes, TermRows,
                         ::testing::Values("luxo_jump.json", "luxo_3d.json", "biped_jump.json",
                                           "humanoid_jump.json"));

// The Newton polish asks for the Jacobians it needs (AugmentedLagrangianState::rawNeeded): a
// block of inequalities none of which is needed and none above the threshold keeps its raw rows
// and gets a zero Jacobian; every other block is evaluated in full, as if nothing were marked.
// At the perturbed default guess of the jump some clearance rows lie above the threshold and
// some below, so both cases are met.
TEST(TermJacobianLimits, OnlyUnneededInequalityBlocksBelowTheThresholdAreSkipped) {
  std::string error;
  auto problem = SpacetimeProblem::build(testing::shippedScene("luxo_jump.json"), &error);
  ASSERT_TRUE(problem) << error;
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.05);
  for (double& x : problem->variables()) x += noise(rng);
  AugmentedLagrangianState& al = problem->augmentedLagrangian();
  al.raw = true;
  const double below = 1e-3;
  int skipped = 0, kept = 0;
  for (const TermResidual* res : problem->residuals()) {
    al.rawNeeded.clear();
    const TermJacobian full = termJacobian(*res);
    al.rawNeeded.assign(al.lambda.size(), 1);
    for (int r = 0; r < res->num_residuals(); ++r) al.rawNeeded[res->firstMultiplier() + r] = 0;
    al.rawUnneededBelow = below;
    const TermJacobian limited = termJacobian(*res);
    ASSERT_TRUE(full.evaluated && limited.evaluated);
    EXPECT_EQ(limited.rows, full.rows) << res->kernel().label();
    const bool skippable = res->kernel().allInequalities() && !res->moving() &&
                           std::all_of(full.rows.begin(), full.rows.end(), [&](double v) { return v <= below; });
    for (size_t b = 0; b < full.blocks.size(); ++b)
      for (size_t k = 0; k < full.blocks[b].size(); ++k)
        EXPECT_EQ(limited.blocks[b][k], skippable ? 0.0 : full.blocks[b][k]) << res->kernel().label();
    (skippable ? skipped : kept) += res->kernel().allInequalities() ? 1 : 0;
  }
  al.rawNeeded.clear();
  EXPECT_GT(skipped, 100);
  EXPECT_GT(kept, 0);  // inequality blocks above the threshold: evaluated in full
}

// The kinematic kernels' Jacobians through the body's spatial Jacobian (bodyPoseAndJacobian:
// ground clearances, point clearances, pins, contact anchors) are the Jets' along the chain to
// rounding, at perturbed poses of the planar and the 3D lamp (its head a cylinder: disc rows,
// tilted), the hurdle (a box to clear) and the humanoid (boxes and capsules, a deep tree, soles
// of four points).
TEST(KinematicJacobians, EqualTheJetsAlongTheChain) {
  std::string error;
  std::map<std::string, int> checked;
  for (const char* name : {"luxo_jump.json", "luxo_3d.json", "luxo_hurdle.json", "humanoid_jump.json"}) {
    Scene scene = testing::shippedScene(name);
    if (std::string(name) == "luxo_3d.json") {  // and a pin on the 3D lamp's head, held a while
      TermSpec pin;
      pin.kind = TermKind::Pin;
      pin.id = "head pin";
      pin.character = "luxo";
      pin.body = "head";
      pin.time = 0.5;
      pin.until = 0.6;
      pin.point = Eigen::Vector3d(0.05, 0.1, -0.03);
      pin.position = Eigen::Vector3d(0.3, 0.6, 0.1);
      scene.terms.push_back(pin);
    }
    auto problem = SpacetimeProblem::build(scene, &error);
    ASSERT_TRUE(problem) << error;
    std::mt19937 rng(11);
    std::normal_distribution<double> noise(0.0, 0.3);
    for (double& x : problem->variables()) x += noise(rng);
    for (const TermResidual* res : problem->residuals()) {
      const Kernel& kernel = res->kernel();
      const char* kind = dynamic_cast<const GroundClearanceKernel*>(&kernel) ? "ground clearance"
                         : dynamic_cast<const ClearanceKernel*>(&kernel)     ? "clearance"
                         : dynamic_cast<const PinKernel*>(&kernel)           ? "pin"
                         : dynamic_cast<const ContactAnchorKernel*>(&kernel) ? "contact anchor"
                                                                             : nullptr;
      if (!kind) continue;
      const Eigen::VectorXd z = res->inputsNow();
      const int m = kernel.rowCount(), n = kernel.inputSize();
      std::vector<double> rows(m), jets(m), J(m * n), Jjets(m * n);
      kernel.rawJacobian(z.data(), rows.data(), J.data());
      kernel.evaluateWithJacobian(z.data(), jets.data(), Jjets.data());
      double scale = 1;
      for (double v : Jjets) scale = std::max(scale, std::abs(v));
      for (int r = 0; r < m; ++r) EXPECT_NEAR(rows[r], jets[r], 1e-14 * scale) << name << " " << kernel.label();
      for (int k = 0; k < m * n; ++k) EXPECT_NEAR(J[k], Jjets[k], 1e-12 * scale) << name << " " << kernel.label() << " entry " << k;
      ++checked[std::string(name) + ": " + kind];
    }
  }
  for (const char* kind : {"luxo_jump.json: ground clearance", "luxo_3d.json: ground clearance",
                           "humanoid_jump.json: ground clearance", "luxo_hurdle.json: clearance",
                           "luxo_jump.json: contact anchor", "humanoid_jump.json: contact anchor", "luxo_3d.json: pin"})
    EXPECT_GT(checked[kind], 0) << kind;
}

}  // namespace
}  // namespace spacetime
