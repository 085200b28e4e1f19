// Held stances (solver/src/held_stances.cpp): a contact whose points fix the floating root holds
// the root still by construction. Checked on arbitrary (random) variables, not on a solve, so
// the property is the transcription's and not the optimum's: over every held contact the root's
// pose is one value and its velocity and acceleration are exactly zero at every instant, the
// first flight interval starts from that pose at rest, the flight itself is free, and contacts
// that cannot fix the root (one point, a body other than the root) leave it free.
#include <gtest/gtest.h>


#include "../shipped_scene.h"
#include "perturbed.h"
#include "split_landing.h"
#include "solver/spacetime_problem.h"

namespace spacetime {
namespace {

std::unique_ptr<SpacetimeProblem> randomised(const Scene& scene) {
  std::string error;
  auto problem = SpacetimeProblem::build(scene, &error);
  EXPECT_TRUE(problem) << error;
  if (!problem) return problem;
  testing::perturb(*problem, 11, 0.3);
  return problem;
}

// The root coordinates' part of a joint vector.
Eigen::VectorXd root(const SpacetimeProblem& p, const Eigen::VectorXd& q) {
  const std::vector<int>& dofs = p.characters()[0].groups[1].dofs;
  Eigen::VectorXd r(dofs.size());
  for (size_t k = 0; k < dofs.size(); ++k) r[k] = q[dofs[k]];
  return r;
}

// Stance samples (the knots inside a contact): physics there for a character whose root the
// contact holds, and the contact's force is a variable there; nowhere else. Returns how many.
int stanceSamples(const SpacetimeProblem& p) {
  int count = 0;
  for (const Sample& s : p.transcription().samples) {
    if (!s.stance) continue;
    EXPECT_EQ(s.weight, 0.0);
    bool held = false;
    for (const ContactVariables& ct : p.contacts()) {
      const bool inside = s.time > ct.start && s.time < ct.end;
      EXPECT_EQ(ct.sampleIndex(s.time) >= 0, inside && ct.holdsRoot) << "t=" << s.time;
      held = held || (inside && ct.holdsRoot);
    }
    EXPECT_EQ(p.physicsAt(0, s), held) << "t=" << s.time;
    count += held;
  }
  return count;
}

// Over each contact that holds the root: one pose, zero velocity and acceleration, on a grid of
// 200 instants per contact (the touch-down instant on its contact side). Returns how many
// contacts were checked.
int expectStill(const SpacetimeProblem& p) {
  int held = 0;
  for (const ContactVariables& ct : p.contacts()) {
    if (!ct.holdsRoot) continue;
    ++held;
    const Eigen::VectorXd pose = root(p, p.jointState(0, ct.start, 0));
    for (int i = 0; i <= 200; ++i) {
      const double t = ct.start + (ct.end - ct.start) * i / 200.0;
      EXPECT_LT((root(p, p.jointState(0, t, 0)) - pose).cwiseAbs().maxCoeff(), 1e-12) << "t=" << t;
      EXPECT_LT(root(p, p.jointState(0, t, 1)).cwiseAbs().maxCoeff(), 1e-12) << "t=" << t;
      EXPECT_LT(root(p, p.jointState(0, t, 2)).cwiseAbs().maxCoeff(), 1e-9) << "t=" << t;
    }
  }
  return held;
}

TEST(HeldStance, TheLampsBaseStandsStillOverEachContactAndMovesInFlight) {
  for (const char* name : {"luxo_jump.json", "luxo_3d.json"}) {
    SCOPED_TRACE(name);
    for (int samples : {2, 4}) {
      Scene scene = testing::shippedScene(name);
      scene.transcription.samplesPerSegment = samples;
      const auto p = randomised(scene);
      ASSERT_TRUE(p);
      EXPECT_EQ(expectStill(*p), 2);  // take-off and landing
      // 20 knots per second: 0.05-0.35 s inside the take-off, 0.85-1.15 s inside the landing.
      EXPECT_EQ(stanceSamples(*p), 14);
      const ContactVariables& takeoff = p->contacts()[0];
      const ContactVariables& landing = p->contacts()[1];
      // The flight starts from the held pose at rest and is free: it moves, and it arrives at the
      // landing with a velocity the impact takes away.
      const double T = takeoff.end, mid = 0.5 * (T + landing.start);
      const double after = T + 1e-7;  // on the flight's side of the lift-off breakpoint
      const double accel = root(*p, p->jointState(0, after, 2)).norm();
      EXPECT_LT((root(*p, p->jointState(0, after, 0)) - root(*p, p->jointState(0, T, 0))).norm(), 1e-9);
      EXPECT_LT(root(*p, p->jointState(0, after, 1)).norm(), 2e-7 * (1 + accel));
      EXPECT_GT(accel, 1e-3);
      EXPECT_GT(root(*p, p->jointState(0, mid, 1)).norm(), 1e-3);
      EXPECT_GT(root(*p, p->jointStateBefore(0, landing.start, 1)).norm(), 1e-3);
      EXPECT_LT(root(*p, p->jointState(0, landing.start, 1)).norm(), 1e-12);
    }
  }
}

TEST(HeldStance, ContactsThatCannotFixTheRootLeaveItFree) {
  // One point per contact term (heel and toe landing separately): each fixes two of the three
  // planar root coordinates, so neither holds the root, and the landing's root moves.
  {
    const auto p = randomised(testing::withSplitLanding(testing::shippedScene("luxo_jump.json")));
    ASSERT_TRUE(p);
    EXPECT_EQ(expectStill(*p), 1);  // the take-off only
    const ContactVariables& heel = p->contacts()[1];
    ASSERT_FALSE(heel.holdsRoot);
    EXPECT_EQ(stanceSamples(*p), 7);  // the take-off's only
    EXPECT_GT(root(*p, p->jointState(0, 0.5 * (heel.start + heel.end), 1)).norm(), 1e-3);
  }
  // Two points on a body other than the root: the joints move that body, so the root is free.
  {
    Scene scene = testing::shippedScene("luxo_jump.json");
    for (TermSpec& t : scene.terms)
      if (t.id == "landing") t.body = "head";
    const auto p = randomised(scene);
    ASSERT_TRUE(p);
    EXPECT_EQ(expectStill(*p), 1);
    EXPECT_FALSE(p->contacts()[1].holdsRoot);
  }
}

// A state reads the same as restoring it: its held copies of a stance's pose are the pose, at
// rest, whatever moved the pose block since the last restore (noise here, a solve's steps in
// the editor, which saves the state and compares it with the reopened scene's).
TEST(HeldStance, AStateIsSettledLikeItsRestoredSelf) {
  const auto p = randomised(testing::shippedScene("luxo_jump.json"));
  ASSERT_TRUE(p);
  const SolutionState s = p->state();
  const std::vector<double> raw = p->variables();  // before restore overwrites them
  int moved = 0;
  for (size_t i = 0; i < raw.size(); ++i) moved += raw[i] != s.variables[i];
  EXPECT_GT(moved, 0);  // the noise moved the held copies away from their pose
  ASSERT_TRUE(p->restore(s));
  EXPECT_EQ(p->variables(), s.variables);
  EXPECT_EQ(p->state().variables, s.variables);
  EXPECT_EQ(expectStill(*p), 2);
}

}  // namespace
}  // namespace spacetime
