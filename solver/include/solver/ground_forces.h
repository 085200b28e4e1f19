// The ground forces acting on a character at any instant of a solution.
//
// The solver's contact forces are variables at the collocation samples, where they balance the
// unactuated dynamics exactly; between samples they are interpolated linearly, and a fast
// motion outruns that interpolation (measured on luxo_jump's push-off: up to 0.65 x weight
// unexplained, Euclidean norm of the root rows, with the samples exact; 0.041 with the forces
// below, left where no admissible force exists). The ground is rigid:
// at every instant it supplies whatever force inside the friction cone the motion asks of it,
// and between two points of one body that force is statically indeterminate. So the forces reported and
// checked at any time t are the admissible ones that best balance the unactuated rows of the
// dynamics, tie-broken towards the interpolated variables:
//
//   min_a  |tau_u(q, qd, qdd) - (J^T G a)_u|^2 / (m g)^2 + eps |G a - f_interp|^2 / (m g)^2,
//   a >= 0,
//
// where the columns of G are the friction cone's edges at each point (planar: (+-mu, 1); 3D:
// an octagonal pyramid inscribed in the cone, which contains the solver's square pyramid), so
// every such force pushes and stays in the cone by construction. It is an NNLS problem
// (core/nnls.h). At the samples the interpolated forces already balance the motion and lie in
// the cone, so they are returned unchanged; what stays unexplained elsewhere is a real defect
// of the motion, not of the interpolation.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "dynamics/model.h"
#include "solver/spacetime_problem.h"

namespace spacetime {

// [contact][point]: world force of each point of each contact of the problem.
using GroundForces = std::vector<std::vector<Eigen::Vector3d>>;

// Forces of every point of every contact of the problem (indexed like problem.contacts()) on
// character c at time t: zero for contacts of other characters or not active at t.
// Side::After: the flight side of a lift-off at t (Sample::after) - the motion of the interval
// that starts at t, without the contacts that end there; Side::Before: the flight side of a
// touch-down at t - the interval that ends at t, without the contacts that begin there.
GroundForces groundForcesAt(const SpacetimeProblem& problem, int c, double t, Side side = Side::Contacts);

// The same as point forces for RNEA; `forces` is groundForcesAt(problem, c, t) if given.
std::vector<PointForce<double>> groundPointForcesAt(const SpacetimeProblem& problem, int c,
                                                    double t, const GroundForces* forces = nullptr,
                                                    Side side = Side::Contacts);

}  // namespace spacetime
