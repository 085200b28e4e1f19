// A quadratic program solved from a guess of its active rows (the previous program's, in an SQP
// near its solution) by active-set steps: Goldfarb and Idnani's dual steps while a row is
// violated, primal steps while a working row pulls, each change one solve on one factorisation
// of the reduced KKT system (reduced_kkt_system.h) with the guessed rows weighted.
#pragma once

#include "reduced_kkt_system.h"

namespace spacetime {
namespace qp {

// True, with `out` filled in (converged, fromGuess, the working rows as `active`), if the steps
// reach a KKT point of the program to the options' tolerance by the interior point's measure;
// false where they cannot (a guess of more than 80 rows, a working set on which H is not convex
// even with the shift raised four times tenfold, more than 100 changes in an attempt, no
// feasible point): the interior point then solves the program from scratch.
bool solveFromActiveGuess(const QuadraticProgram& qp, const SpMat& H, const QpOptions& options, ReducedSystem& system,
                          double dualScale, double primalScale, QpResult* out);

}  // namespace qp
}  // namespace spacetime
