// The second-order check of a solved motion: is it a strict local minimum, and how firmly.
//
// A KKT point can be a minimum, a saddle or a maximum of the objective on the constraints. It is a
// strict local minimum when the Hessian of the Lagrangian W = J_r^T J_r + sum r_k grad^2 r_k +
// sum y_i grad^2 c_i is positive definite on the null space of the active constraints' Jacobian A
// (the equalities and the inequalities held at their bound with a positive multiplier: the
// second-order sufficient conditions, Nocedal & Wright, Numerical Optimization, 2nd ed.,
// Theorem 12.6). Z, an orthonormal basis of null(A), comes from a sparse QR factorisation of A^T
// (its last n - rank columns of Q; Nocedal & Wright section 15.3), and the reduced Hessian
// Z^T W Z is small (the jump: 56 free directions of 588) and dense: its eigenvalues say it.
// Orthogonal factors keep it exact to rounding where a test of W - s I + rho A^T A by Cholesky,
// or of the inertia of [W - s I, A^T; A, 0] by LDL^T, is not: W's diagonal spans nine decades on
// the jump (1e5 on the forces, 7e-5 the smallest reduced curvature), the penalty that makes the
// first decide needs more digits than a double has, and the second, without pivoting, breaks
// down on the variables W has no curvature for (the anchors).
//
// Two methods that end at different objectives on one scene each reach a KKT point; the check
// says whether both are strict local minima (two basins of one problem, docs/design.md) or
// one of them is not a minimum at all.
#pragma once

#include <string>
#include <vector>

namespace spacetime {

class SpacetimeProblem;

struct SecondOrderCheck {
  bool checked = false;        // false: not run (reason says why)
  bool strictMinimum = false;  // the reduced Hessian is positive definite at the point (beyond rounding)
  // The reduced Hessian's extreme eigenvalues, in the solver's variables (infinite smallest when the
  // active constraints leave no free direction).
  double smallestEigenvalue = 0, largestEigenvalue = 0;
  // Eigenvalues within this of zero are zero to rounding: strict needs smallestEigenvalue above it;
  // below minus it the reduced Hessian is indefinite (a saddle when `dependent` and `weaklyActive`
  // are zero).
  double roundingFloor = 0;
  int nullity = 0;  // free directions: n - rank(A)
  // Not strict, but every flat direction moves contact forces only (a sample's force split
  // between points or feet that no term decides): the motion itself is then a strict local
  // minimum, curved by at least motionEigenvalue along any direction that moves it.
  bool strictMotion = false;
  int freeForceDirections = 0;
  double motionEigenvalue = 0;
  // Not strict: the variables the direction of least curvature moves most (variable_labels.h).
  std::vector<std::string> direction;
  double stationarity = 0;  // |grad f + J^T y|_inf / max(1, |grad f|_inf) at the multipliers used
  int constraints = 0;      // rows of A: equalities and strongly active inequalities
  int weaklyActive = 0;     // inequalities at their bound with a zero multiplier (not in A)
  // Rows of A dependent on the others (rows - rank). With none, and no weakly active row, the
  // multipliers are unique and a negative eigenvalue makes the point a saddle (the second-order
  // necessary conditions, N&W Theorem 12.5, fail); with some, other multipliers could curve that
  // direction upwards, or a weakly active row forbid it.
  int dependent = 0;
  double seconds = 0;
  std::string reason;
};

// Checks the problem's current motion with its solver's multipliers or its least-squares ones
// (multiplier_estimate.h), whichever meet stationarity better.
// Meaningful at a KKT point (a converged solve); it changes nothing in the problem.
SecondOrderCheck checkSecondOrder(SpacetimeProblem& problem, int threads);

}  // namespace spacetime
