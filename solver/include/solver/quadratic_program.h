// A sparse convex quadratic program solved by a primal-dual interior point:
//     min 1/2 x^T H x + g^T x   subject to   A x = b,   C x <= d.
//
// This is the subproblem of the SQP-type methods the solver issue asks for: a step of Cohen's
// SQP and both halves of Witkin & Kass's projected Newton method (the restoration onto the
// constraints and the tangent step) are such programs, with the spacetime problem's linearised
// rows as A and C. The inequalities (contact pushes and cones, clearances, limits: thousands of
// rows of which a few dozen are active) are handled as inequalities, which the damped
// least-squares restoration measured in docs/design.md could not do.
//
// Method: Mehrotra's predictor-corrector (Nocedal & Wright, Numerical Optimization, 2nd ed.,
// Algorithm 16.4, with equality rows), slacks s = d - C x >= 0 and multipliers z >= 0. Each
// iteration eliminates the slacks and the inequality multipliers and solves the quasi-definite
// system (Vanderbei 1995)
//     [ H + C^T (Z/S) C + dx I    A^T  ] [ dx ]   [ -r_d - C^T S^-1 (Z r_i - r_c) ]
//     [ A                        -dy I ] [ dy ] = [ -r_e                          ]
// by a supernodal sparse LDL^T (solver/src/supernodal_ldlt.h) whose pattern is analysed once
// (the band of H, C^T C and A^T A). H only
// needs to be convex on the feasible directions; where the factorisation shows it is not (more
// than |A| negative pivots, Sylvester's law of inertia) a multiple of a diagonal metric (the
// identity unless the program gives one) is added to H for the rest of the solve and reported,
// as the inertia correction of Waechter & Biegler (2006, section 3.1) does for a Newton step.
//
// A guess of the active rows (the previous program's, in an SQP near its solution) is tried
// first, by active-set steps on one factorisation of the same system with the guessed rows
// weighted heavily (solver/src/active_set_steps.h): Goldfarb and Idnani's dual steps add the
// rows the point violates, primal steps drop the rows that pull, one row and one solve per
// change. A convex program has one minimiser, which both paths return; where H needs the
// inertia shift, the steps' shift is the one that makes H convex on the tangent spaces of the
// working rows they pass through, which can be smaller than the interior point's. Where the
// steps cannot finish (a large guess, many changes, no feasible point) the interior point
// solves from scratch.
#pragma once

#include <Eigen/SparseCore>
#include <memory>
#include <string>
#include <vector>

namespace spacetime {

struct QuadraticProgram {
  Eigen::SparseMatrix<double> hessian;  // H (n x n): the lower triangle is read
  Eigen::VectorXd gradient;             // g
  Eigen::SparseMatrix<double, Eigen::RowMajor> equalities;    // A (m_e x n)
  Eigen::VectorXd equalityTargets;                            // b
  Eigen::SparseMatrix<double, Eigen::RowMajor> inequalities;  // C (m_i x n)
  Eigen::VectorXd inequalityBounds;                           // d
  // The inertia correction's metric: a shift adds shift * shiftMetric_i to H_ii (empty: the
  // identity). Variables in other units than the rest - contact forces in newtons beside joint
  // angles - are then damped in their own scale (see SQP in docs/design.md).
  Eigen::VectorXd shiftMetric;
};

struct QpOptions {
  double tolerance = 1e-9;  // residuals relative to 1 + the data's size, and the mean complementarity
  // Where rounding stops the iterations short of `tolerance`, the best iterate counts as a
  // solution if its error is within this (as IPOPT's "solved to an acceptable level").
  double acceptableTolerance = 1e-6;
  int maxIterations = 80;
  // H is known to be convex (a least-squares program): no inertia correction, and a
  // factorisation without the expected inertia ends the solve at its best iterate.
  bool convex = false;
  // Regularisation of the two diagonal blocks: keeps the system quasi-definite with redundant
  // equality rows (contacts whose rows repeat each other) and a singular H.
  double primalRegularisation = 1e-10, dualRegularisation = 1e-9;
  // Rows guessed active (one entry per inequality row, nonzero = active); empty: no guess.
  std::vector<char> activeGuess;
  // With a guess: where its active-set steps cannot finish, stop unsolved instead of solving by
  // the interior point (a caller that has a cheaper way on than a solve from scratch).
  bool guessOnly = false;
};

struct QpResult {
  bool converged = false;
  Eigen::VectorXd x, y, z;  // the point, the equalities' and the inequalities' (z >= 0) multipliers
  int iterations = 0;
  double shift = 0;  // multiple of the shift metric added to H (0 when H was convex enough)
  double primalResidual = 0, dualResidual = 0, complementarity = 0;  // at x, unscaled, inf-norms
  std::vector<char> active;  // per inequality row: at its bound (its multiplier above its slack)
  bool fromGuess = false;    // solved by active-set steps from the guess: no interior-point iterations
  int activeSetChanges = 0;  // rows those steps added or dropped
  std::string reason;
};

// The symbolic part of a solve - K's pattern, where each matrix entry goes in it, the LDL^T's
// ordering - kept between the solves of one problem (the steps of a restoration or an SQP). A
// program whose entries all fall inside the pattern only looks up its slots; one that needs new
// entries rebuilds it with the old entries kept, so the pattern grows to cover the inequality
// rows that come and go between steps (an analysis is 50 ms of the jump's 90 ms program).
class QpWorkspace {
 public:
  QpWorkspace();
  ~QpWorkspace();
  QpWorkspace(const QpWorkspace&) = delete;
  QpWorkspace& operator=(const QpWorkspace&) = delete;
  struct Pattern;

 private:
  friend QpResult solveQuadraticProgram(const QuadraticProgram&, const QpOptions&, QpWorkspace*);
  std::unique_ptr<Pattern> pattern_;
};

// Never throws; returns the best iterate found (by its largest scaled KKT residual). A program
// with no feasible point or no bounded minimum ends not converged, with the reason.
QpResult solveQuadraticProgram(const QuadraticProgram& qp, const QpOptions& options = {},
                               QpWorkspace* workspace = nullptr);

}  // namespace spacetime
