// Symbolic dynamics: the templated RNEA instantiated with the expression scalar builds the
// inverse dynamics of a character as a graph; compiled to a tape it must equal the native
// double RNEA, and building it a second time must add no node (hash-consing).
#include <gtest/gtest.h>

#include <random>

#include "../shipped_scene.h"
#include "core/expr/eigen_scalar.h"
#include "core/expr/tape.h"
#include "core/scene_io.h"
#include "dynamics/algorithms.h"
#include "dynamics/build_model.h"
#include "dynamics/compiled_dynamics.h"
#include "random_model.h"

namespace spacetime {
namespace {

using expr::Expr;

// tau(q, qd, qdd) as expressions of variables 0..3n-1 (q, then qd, then qdd).
std::vector<Expr> symbolicRnea(expr::Graph& g, const Model<double>& model) {
  const int n = model.dofCount();
  std::vector<Expr> z;
  for (int i = 0; i < 3 * n; ++i) z.push_back(g.variable(i));
  Data<Expr> data(model);
  const VecX<Expr> tau = rnea(model, data, z.data(), z.data() + n, z.data() + 2 * n);
  std::vector<Expr> out;
  for (int i = 0; i < n; ++i) out.push_back(tau[i].graph ? tau[i] : g.constant(tau[i].constant));
  return out;
}

class SymbolicRnea : public ::testing::TestWithParam<const char*> {};

TEST_P(SymbolicRnea, CompiledTapeEqualsNativeAndRebuildAddsNoNodes) {
  const Scene scene = testing::shippedScene(GetParam());
  const Model<double> model = buildModel(scene.characters[0], scene.gravity);
  const int n = model.dofCount();
  expr::Graph g;
  const std::vector<Expr> tau = symbolicRnea(g, model);
  const size_t nodes = g.size();
  const std::vector<Expr> again = symbolicRnea(g, model);
  EXPECT_EQ(g.size(), nodes);
  for (int i = 0; i < n; ++i) EXPECT_EQ(tau[i].id, again[i].id);

  const expr::Tape tape = expr::Tape::compile(g, tau, true);
  std::mt19937 rng(5);
  Data<double> data(model);
  std::vector<double> work, out(n);
  for (int trial = 0; trial < 100; ++trial) {
    const Eigen::VectorXd z = testing::randomVector(rng, 3 * n, 2.0);
    tape.evaluate(z.data(), 0.0, out.data(), work);
    const Eigen::VectorXd native = rnea(model, data, z.data(), z.data() + n, z.data() + 2 * n);
    for (int i = 0; i < n; ++i) EXPECT_NEAR(out[i], native[i], 1e-12 * (1 + native.cwiseAbs().maxCoeff()));
  }
}

// The solver's compiled inverse dynamics (contact forces as variables) equals the native RNEA
// with the same point forces, planar (2 force components) and 3D (3).
TEST_P(SymbolicRnea, CompiledInverseDynamicsWithContactsEqualsNative) {
  const Scene scene = testing::shippedScene(GetParam());
  const Model<double> model = buildModel(scene.characters[0], scene.gravity);
  const int n = model.dofCount();
  std::mt19937 rng(11);
  for (int forceDims : {2, 3}) {
    std::vector<ContactPoints> contacts = {{model.bodyCount() - 1, {testing::randomVec(rng), testing::randomVec(rng)}},
                                           {model.bodyCount() / 2, {testing::randomVec(rng)}}};
    const expr::Tape tape = compileInverseDynamics(model, contacts, forceDims);
    Data<double> data(model);
    std::vector<double> work, out(n);
    for (int trial = 0; trial < 50; ++trial) {
      const Eigen::VectorXd z = testing::randomVector(rng, 3 * n + 3 * forceDims, 2.0);
      tape.evaluate(z.data(), 0.0, out.data(), work);
      const Eigen::VectorXd native = rnea(model, data, z.data(), z.data() + n, z.data() + 2 * n,
                                          contactPointForces(contacts, z.data() + 3 * n, forceDims));
      for (int i = 0; i < n; ++i)
        EXPECT_NEAR(out[i], native[i], 1e-12 * (1 + native.cwiseAbs().maxCoeff())) << "dof " << i;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Characters, SymbolicRnea, ::testing::Values("luxo_jump.json", "luxo_3d.json"));

}  // namespace
}  // namespace spacetime
