// Inverse dynamics compiled to an expression tape: the templated RNEA run once on symbolic
// scalars (core/expr), hash-consed and simplified, then flattened into a tape the solver
// evaluates per sample with doubles or Jets.
//
// Why: the symbolic graph folds what the native code computes at run time for every sample -
// multiplications by the zeros and ones of the joint axes, the tree transforms and the massless
// virtual bodies of a floating root. Measured on the Luxo lamp with 12-wide Jets (the solver's
// Jacobian), the tape takes 2.4 us against 9.2 us for the native RNEA (expr_benchmark, CPU time).
//
// Variables follow the solver's per-sample layout (formula_environment.h): q at 0..n-1, qd at
// n..2n-1, qdd at 2n..3n-1, then forceDims world components per contact point. Outputs: the n
// generalized forces, gravity included.
#pragma once

#include <vector>

#include "core/expr/tape.h"
#include "dynamics/contact_points.h"
#include "dynamics/model.h"

namespace spacetime {

expr::Tape compileInverseDynamics(const Model<double>& model,
                                  const std::vector<ContactPoints>& contacts, int forceDims);

// The weighted sum phi(z, a) = sum_d a_d tau_d(z) as one output, compiled for reverse mode
// (variables: z as above, then the n weights a). Its gradient run on Jets seeded on some inputs
// is forward-over-reverse: the Hessian columns of phi in those inputs in one pass (Griewank &
// Walther, ch. 5) - the solver's Lagrangian Hessian of the dynamics rows.
expr::Tape compileWeightedInverseDynamics(const Model<double>& model,
                                          const std::vector<ContactPoints>& contacts, int forceDims);

}  // namespace spacetime
