// The symbolic RNEA compiled to a tape (see compiled_dynamics.h).
#include "dynamics/compiled_dynamics.h"

#include "core/expr/eigen_scalar.h"
#include "dynamics/algorithms.h"

namespace spacetime {

using expr::Expr;

namespace {
// tau(z) as expressions of the variables 0 .. 3n + forceDims * points - 1; *variables is how
// many that is.
std::vector<Expr> symbolicInverseDynamics(expr::Graph& g, const Model<double>& model,
                                          const std::vector<ContactPoints>& contacts, int forceDims,
                                          int* variables = nullptr) {
  const int n = model.dofCount();
  int points = 0;
  for (const ContactPoints& c : contacts) points += static_cast<int>(c.points.size());
  std::vector<Expr> z;
  for (int i = 0; i < 3 * n + forceDims * points; ++i) z.push_back(g.variable(i));
  if (variables) *variables = static_cast<int>(z.size());
  Data<Expr> data(model);
  const VecX<Expr> tau = rnea(model, data, z.data(), z.data() + n, z.data() + 2 * n,
                              contactPointForces(contacts, z.data() + 3 * n, forceDims));
  std::vector<Expr> out;
  // A generalized force that folded to a constant (a massless chain) still needs a node.
  for (int i = 0; i < n; ++i) out.push_back(tau[i].graph ? tau[i] : g.constant(tau[i].constant));
  return out;
}
}  // namespace

expr::Tape compileInverseDynamics(const Model<double>& model,
                                  const std::vector<ContactPoints>& contacts, int forceDims) {
  expr::Graph g;
  return expr::Tape::compile(g, symbolicInverseDynamics(g, model, contacts, forceDims),
                             /*reuseSlots=*/true);
}

expr::Tape compileWeightedInverseDynamics(const Model<double>& model,
                                          const std::vector<ContactPoints>& contacts, int forceDims) {
  expr::Graph g;
  int first = 0;  // the weights' variables follow z
  const std::vector<Expr> tau = symbolicInverseDynamics(g, model, contacts, forceDims, &first);
  Expr phi = g.constant(0.0);
  for (size_t d = 0; d < tau.size(); ++d) phi = phi + g.variable(first + static_cast<int>(d)) * tau[d];
  return expr::Tape::compile(g, {phi}, /*reuseSlots=*/false);
}

}  // namespace spacetime
