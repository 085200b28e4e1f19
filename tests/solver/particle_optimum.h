// The seed's particle (Figure 7): its analytic optimum, which particle_test.cpp derives.
//
// Minimising the integral of |F|^2 = m^2 |x'' - g|^2 over a path through p0, p1, p2 at
// t = 0, 1/2, 1: x - g t^2 / 2 is the natural cubic spline through the shifted points, whose
// middle moment is M1 = 6 (y0 - 2 y1 + y2) / (4 h^2) (h = 1/2), and the integral of its squared
// second derivative is 2 h M1^2 / 3 per axis.
#pragma once

#include <Eigen/Core>

#include "core/scene.h"

namespace spacetime::testing {

inline double analyticParticleMinimum(const Scene& scene) {
  const double h = 0.5, m = 1.0;
  const Eigen::Vector3d p[3] = {{0, 0, 0}, {2, 1, 1}, {-2, 2, 1}};
  double total = 0;
  for (int axis = 0; axis < 3; ++axis) {
    double y[3];
    for (int i = 0; i < 3; ++i) {
      const double t = i * h;
      y[i] = p[i][axis] - scene.gravity[axis] * t * t / 2;
    }
    const double M1 = 6 * (y[0] - 2 * y[1] + y[2]) / (4 * h * h);
    total += m * m * 2 * h * M1 * M1 / 3;
  }
  return total;
}

}  // namespace spacetime::testing
