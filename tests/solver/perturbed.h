// Test helper: a problem's variables moved off the default guess by Gaussian noise, for tests
// that need a motion breaking the dynamics (Jacobians and Hessians away from any optimum, the
// validity report's flags). A fixed seed gives the same stream, so every run tests one motion.
#pragma once

#include <random>

#include "solver/spacetime_problem.h"

namespace spacetime::testing {

// Adds noise of standard deviation `sigma` to every variable.
inline void perturb(SpacetimeProblem& problem, unsigned seed, double sigma) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  for (double& x : problem.variables()) x += noise(rng);
}

}  // namespace spacetime::testing
