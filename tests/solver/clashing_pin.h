// A task whose constraints truly conflict: the particle scene with a second pin, "clash", at the
// instant of its pin p1 but in another place (5, 5, 5). Both methods must stop and name the pins.
#pragma once

#include <gtest/gtest.h>

#include <cmath>

#include "core/scene.h"
#include "solver/augmented_lagrangian.h"

namespace spacetime::testing {

// Adds the clashing pin to `scene` (a copy of particle.json) and returns it.
inline TermSpec addClashingPin(Scene& scene) {
  TermSpec clash = scene.terms[1];
  clash.id = "clash";
  clash.position = Eigen::Vector3d(5, 5, 5);  // same time as p1, another place
  scene.terms.push_back(clash);
  return clash;
}

// A solve of the clashing task stopped as it must: stalled, saying the constraints conflict and
// `handOver` (how the method came to the augmented Lagrangian), with finite variables and only
// the two pins named.
inline void expectTheClashNamed(const SolverSummary& s, const SpacetimeProblem& problem, const Scene& scene,
                                const std::string& handOver) {
  EXPECT_FALSE(s.converged);
  EXPECT_EQ(s.status, SolveStatus::Stalled) << s.reason;
  EXPECT_NE(s.reason.find("conflict"), std::string::npos) << s.reason;
  EXPECT_NE(s.reason.find(handOver), std::string::npos) << s.reason;
  for (double x : problem.variables()) ASSERT_TRUE(std::isfinite(x));
  ASSERT_FALSE(s.violated.empty()) << s.reason;
  for (const ViolatedConstraint& v : s.violated)
    EXPECT_TRUE(v.label.find("'clash'") != std::string::npos || v.label.find("'" + scene.terms[1].id + "'") != std::string::npos)
        << v.label;
}

}  // namespace spacetime::testing
