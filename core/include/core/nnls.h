// Non-negative least squares: min |A x - b|^2 subject to x >= 0.
//
// Lawson & Hanson, "Solving Least Squares Problems" (1974), chapter 23, algorithm NNLS: an
// active-set method that moves one variable at a time into the passive (free) set and, when
// the unconstrained solution on that set leaves the feasible region, steps back to its
// boundary. It terminates in finitely many steps with the KKT point: x >= 0, the gradient
// w = A^T (b - A x) is <= 0 on the active set and x_i > 0 only where w_i = 0.
//
// Used for the ground forces: a contact force is a non-negative combination of the friction
// cone's edges, so "the admissible force that best explains the motion" is an NNLS problem.
#pragma once

#include <Eigen/Core>

namespace spacetime {

struct NnlsResult {
  Eigen::VectorXd x;
  double residualNorm = 0;  // |A x - b|
  int iterations = 0;
  bool converged = true;  // false only if the iteration limit was reached
};

NnlsResult nnls(const Eigen::MatrixXd& A, const Eigen::VectorXd& b, int maxIterations = 0);

}  // namespace spacetime
