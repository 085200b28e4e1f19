// The interior-point method (`--method ipopt`): the spacetime problem handed whole to IPOPT
// (Waechter & Biegler, "On the implementation of an interior-point filter line-search
// algorithm for large-scale nonlinear programming", Math. Prog. 106, 2006) as
//     min 1/2 |r(x)|^2  subject to  c(x) = 0, g(x) <= 0,
// the raw rows the augmented Lagrangian penalises: objective rows r, equalities c, inequalities
// g. Ceres evaluates the rows and their exact Jacobians (raw_rows.h); the Hessian of the
// Lagrangian sigma (J_r^T J_r + sum r_k grad^2 r_k) + sum lambda_i grad^2 c_i is assembled from
// the kernels' weighted Hessians (Kernel::weightedHessian), the same curvature the Newton polish
// uses, into a pattern fixed once. IPOPT brings what the hand-made interior point lacked: its
// feasibility restoration phase (so "infeasible" means a positive minimum of the violation),
// multiplier initialisation and MUMPS's inertia-revealing factorisation.
//
// Built when Debian's coinor-libipopt-dev is installed (SPACETIME_HAVE_IPOPT); without it the
// method reports that it is missing. Free contact ends (moving residuals) are not handed over.
// IPOPT's own options file is read only when SPACETIME_IPOPT_OPTIONS names one (experiments:
// print_level 5, print_timing_statistics yes), never ./ipopt.opt.
#pragma once

#include <atomic>

#include "solver/augmented_lagrangian.h"

namespace spacetime {

// True if this build has IPOPT.
bool interiorPointAvailable();

// Solves the problem from its current variables; same contract as solveSpacetime (which calls
// it for SolverMethod::InteriorPoint): never throws, keeps a finite iterate, says why it stopped.
SolverSummary solveInteriorPoint(SpacetimeProblem& problem, const SolverOptions& options,
                                 const ProgressCallback& callback, const std::atomic<bool>* cancel);

}  // namespace spacetime
