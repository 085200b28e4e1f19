// Formulas on the Luxo lamp against the native computations they name, at random states
// (kinematics, centre of mass, inverse dynamics with contact forces), and the parser's errors
// on a list of bad formulas: each names the column and what was expected.
#include <gtest/gtest.h>

#include <random>

#include "../shipped_scene.h"
#include "core/expr/tape.h"
#include "core/scene_io.h"
#include "dynamics/algorithms.h"
#include "dynamics/build_model.h"
#include "dynamics/formula_environment.h"
#include "random_model.h"

namespace spacetime {
namespace {

Model<double> luxo() {
  const Scene scene = testing::shippedScene("luxo_jump.json");
  return buildModel(scene.characters[0], scene.gravity);
}

TEST(Formula, ValuesMatchNativeComputations) {
  const Model<double> model = luxo();
  const int n = model.dofCount();
  const ContactPoints feet{model.bodyIndex("base"), {{-0.15, 0, 0}, {0.15, 0, 0}}};
  expr::Graph g;
  CharacterFormulaEnvironment env(model, g, {feet}, 2);
  const std::vector<std::string> formulas = {
      "pos(head).y", "pos(head, [0.1, 0, -0.02]).x", "vel(base).x", "com.y", "tau.j1",
      "tau.base_y", "q.j1 * 2 + sin(t) - qd.j2 ^ 2", "force(base).y", "qdd.j3 / (1 + q.j2^2)"};
  std::vector<expr::Expr> outputs;
  for (const auto& f : formulas) {
    const expr::FormulaResult r = expr::parseFormula(f, g, env);
    ASSERT_TRUE(r.value) << f << ": " << r.error;
    outputs.push_back(*r.value);
  }
  const expr::Tape tape = expr::Tape::compile(g, outputs, true);
  std::mt19937 rng(9);
  Data<double> data(model);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::VectorXd z = testing::randomVector(rng, env.variableCount(), 1.5);
    const double t = 0.37;
    std::vector<double> out(formulas.size()), work;
    tape.evaluate(z.data(), t, out.data(), work);
    const double* q = z.data();
    forwardKinematics(model, data, q, q + n, q + 2 * n);
    const int head = model.bodyIndex("head"), base = model.bodyIndex("base");
    const double tol = 1e-12;
    EXPECT_NEAR(out[0], pointPosition(data, head, Eigen::Vector3d::Zero().eval()).y(), tol);
    EXPECT_NEAR(out[1], pointPosition(data, head, Eigen::Vector3d(0.1, 0, -0.02)).x(), tol);
    EXPECT_NEAR(out[2], pointVelocity(data, base, Eigen::Vector3d::Zero().eval()).x(), tol);
    EXPECT_NEAR(out[3], centerOfMass(model, data).y(), tol);
    std::vector<PointForce<double>> fext;
    for (int p = 0; p < 2; ++p) {
      PointForce<double> pf;
      pf.body = base;
      pf.pointIsLocal = true;
      pf.pointWorld = feet.points[p];
      pf.forceWorld = Eigen::Vector3d(z[3 * n + 2 * p], z[3 * n + 2 * p + 1], 0);
      fext.push_back(pf);
    }
    const Eigen::VectorXd tau = rnea(model, data, q, q + n, q + 2 * n, fext);
    EXPECT_NEAR(out[4], tau[model.dofIndex("j1")], 1e-10);
    EXPECT_NEAR(out[5], tau[model.dofIndex("base_y")], 1e-10);
    const int j1 = model.dofIndex("j1"), j2 = model.dofIndex("j2"), j3 = model.dofIndex("j3");
    EXPECT_NEAR(out[6], q[j1] * 2 + std::sin(t) - std::pow(q[n + j2], 2), tol);
    EXPECT_NEAR(out[7], z[3 * n + 1] + z[3 * n + 3], tol);
    EXPECT_NEAR(out[8], q[2 * n + j3] / (1 + std::pow(q[j2], 2)), tol);
  }
}

TEST(Formula, BadFormulasNameTheColumnAndWhatWasExpected) {
  const Model<double> model = luxo();
  expr::Graph g;
  CharacterFormulaEnvironment env(model, g);
  struct Bad {
    std::string text;
    int column;
    std::string mention;
  };
  const std::vector<Bad> cases = {
      {"q.elbow", 3, "unknown degree of freedom 'elbow'"},
      {"pos(hed).y", 5, "unknown body 'hed'"},
      {"pos(head)", 1, "is a vector"},
      {"sin(q.j1", 9, "expected ')'"},
      {"1 +", 4, "formula ended"},
      {"q + 1", 3, "expected '.' after 'q'"},
      {"foo(1)", 1, "unknown function 'foo'"},
      {"3 $ 4", 3, "unexpected '$'"},
      {"com.w", 5, "unknown component 'w'"},
      {"speed * 2", 1, "unknown name 'speed'"},
      {"pos(head, [1, 2]).y", 16, "expected ','"},
      {"q.j1.x", 6, "needs a vector"},
      {"pow(q.j1)", 9, "expected ','"},
      // Non-ASCII: the whole character in the message (valid UTF-8), columns in characters.
      {"q.j1 \u00d7 2", 6, "unexpected '\u00d7'"},
      {"\u03c0 * 2", 1, "unexpected '\u03c0'"},
      {"\"\u00e9\" + \u00e9", 1, "unexpected '\"'"},
      {"q.j1 + 1 \xff", 10, "unexpected '\\xFF'"},
  };
  for (const Bad& b : cases) {
    const expr::FormulaResult r = expr::parseFormula(b.text, g, env);
    EXPECT_FALSE(r.value) << b.text;
    EXPECT_EQ(r.column, b.column) << b.text << ": " << r.error;
    EXPECT_NE(r.error.find(b.mention), std::string::npos) << b.text << ": " << r.error;
    EXPECT_EQ(r.error.rfind("column " + std::to_string(r.column) + ":", 0), 0u) << r.error;
  }
}

}  // namespace
}  // namespace spacetime
