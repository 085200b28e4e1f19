// The expression system against independent truths: random programs run on doubles and on the
// graph (simplification never changes a value), the compiled tape against direct evaluation,
// and derivatives in forward mode (Jets through the tape, as the solver differentiates formula
// terms) and reverse mode (the dynamics kernel's Hessian runs it on Jets) against central finite
// differences, on hundreds of random expressions.
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <Eigen/Core>

#include <cmath>
#include <random>
#include <set>

#include "core/expr/graph.h"
#include "core/expr/tape.h"

namespace spacetime::expr {
namespace {

constexpr int kVars = 4;

// A random program over kVars inputs whose every step is defined for any real input.
template <class T>
T randomProgram(unsigned seed, const std::vector<T>& x, int steps) {
  std::mt19937 rng(seed);
  std::vector<T> pool(x.begin(), x.end());
  std::uniform_int_distribution<int> op(0, 13);
  std::uniform_real_distribution<double> c(-2, 2);
  for (int s = 0; s < steps; ++s) {
    const T a = pool[std::uniform_int_distribution<size_t>(0, pool.size() - 1)(rng)];
    const T b = pool[std::uniform_int_distribution<size_t>(0, pool.size() - 1)(rng)];
    const double k = c(rng);
    using std::cos;
    using std::exp;
    using std::log;
    using std::sin;
    using std::sqrt;
    T r;
    switch (op(rng)) {
      case 0: r = a + b; break;
      case 1: r = a - b; break;
      case 2: r = a * b; break;
      case 3: r = a / (b * b + 1.0); break;
      case 4: r = -a; break;
      case 5: r = sin(a); break;
      case 6: r = cos(a) * k; break;
      case 7: r = exp(a * 0.3 - 1.0); break;
      case 8: r = log(a * a + 1.0); break;
      case 9: r = sqrt(a * a + 0.5); break;
      case 10: r = a + k; break;
      case 11: r = a * k; break;
      case 12: r = (a + 0.0) * 1.0 - (b - b); break;  // exercises x+0, x*1, x-x
      default: r = -(-(a * b)); break;
    }
    pool.push_back(r);
  }
  return pool.back();
}

std::vector<double> randomPoint(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  std::vector<double> x(kVars);
  for (double& v : x) v = u(rng);
  return x;
}

std::vector<Expr> variables(Graph& g) {
  std::vector<Expr> vars;
  for (int i = 0; i < kVars; ++i) vars.push_back(g.variable(i));
  return vars;
}

double finiteDifference(Graph& g, Expr e, std::vector<double> x, int k) {
  const double h = 1e-6;
  x[k] += h;
  const double p = g.evaluate(e, x);
  x[k] -= 2 * h;
  return (p - g.evaluate(e, x)) / (2 * h);
}

TEST(Expr, SimplificationNeverChangesAValue) {
  std::mt19937 rng(1);
  for (unsigned seed = 0; seed < 300; ++seed) {
    Graph g;
    const std::vector<Expr> vars = variables(g);
    const Expr e = randomProgram(seed, vars, 25);
    const std::vector<double> x = randomPoint(rng);
    const double direct = randomProgram(seed, x, 25);
    EXPECT_NEAR(g.evaluate(e, x), direct, 1e-12 * (1 + std::abs(direct))) << g.toString(e);
  }
}

TEST(Expr, BuildingTheSameExpressionTwiceAddsNoNodes) {
  Graph g;
  const std::vector<Expr> vars = variables(g);
  for (unsigned seed = 0; seed < 50; ++seed) {
    const Expr first = randomProgram(seed, vars, 30);
    const size_t nodes = g.size();
    const Expr second = randomProgram(seed, vars, 30);
    EXPECT_EQ(g.size(), nodes);
    EXPECT_EQ(first.id, second.id);
  }
}

TEST(Expr, SimplificationRules) {
  Graph g;
  const Expr x = g.variable(0), y = g.variable(1);
  EXPECT_EQ((x + 0.0).id, x.id);
  EXPECT_EQ((x * 1.0).id, x.id);
  EXPECT_TRUE(g.isConstant((x * 0.0).id, 0));
  EXPECT_TRUE(g.isConstant((x - x).id, 0));
  EXPECT_EQ((-(-x)).id, x.id);
  EXPECT_EQ((x + y).id, (y + x).id);
  EXPECT_EQ((x * y).id, (y * x).id);
  const Expr gathered = (x + 2.0) + 3.0;
  EXPECT_EQ(gathered.id, (x + 5.0).id);
  EXPECT_EQ(((x * 2.0) * 3.0).id, (x * 6.0).id);
  EXPECT_TRUE(g.isConstant((g.constant(2) * g.constant(3) + 1.0).id, 7));
  EXPECT_LE(sizeof(Node), 16u);
}

TEST(Expr, TapeMatchesDirectEvaluationWithAndWithoutSlotReuse) {
  std::mt19937 rng(2);
  for (unsigned seed = 0; seed < 200; ++seed) {
    Graph g;
    const std::vector<Expr> vars = variables(g);
    const Expr e1 = randomProgram(seed, vars, 30), e2 = randomProgram(seed + 1000, vars, 20);
    const std::vector<double> x = randomPoint(rng);
    for (bool reuse : {true, false}) {
      const Tape tape = Tape::compile(g, {e1, e2}, reuse);
      std::vector<double> work, out(2);
      tape.evaluate(x.data(), 0.0, out.data(), work);
      EXPECT_NEAR(out[0], g.evaluate(e1, x), 1e-12 * (1 + std::abs(out[0])));
      EXPECT_NEAR(out[1], g.evaluate(e2, x), 1e-12 * (1 + std::abs(out[1])));
      if (reuse) {
        EXPECT_LE(tape.slotCount(), tape.length());
      }
    }
  }
}

TEST(Expr, ForwardAndReverseDerivativesMatchFiniteDifferences) {
  std::mt19937 rng(3);
  using Jet = ceres::Jet<double, kVars>;
  int checked = 0;
  for (unsigned seed = 0; seed < 300; ++seed) {
    Graph g;
    const std::vector<Expr> vars = variables(g);
    const Expr e = randomProgram(seed, vars, 20);
    const std::vector<double> x = randomPoint(rng);
    // Forward mode: Jets through the compiled tape.
    const Tape tape = Tape::compile(g, {e}, true);
    std::vector<Jet> xj(kVars), work;
    for (int i = 0; i < kVars; ++i) xj[i] = Jet(x[i], i);
    Jet out;
    tape.evaluate(xj.data(), Jet(0.0), &out, work);
    const Tape full = Tape::compile(g, {e}, false);
    std::vector<double> grad(kVars), w, adj;
    full.gradient(x.data(), 0.0, 0, grad.data(), kVars, w, adj);
    for (int k = 0; k < kVars; ++k) {
      const double fd = finiteDifference(g, e, x, k);
      EXPECT_NEAR(out.v[k], fd, 1e-5 * (1 + std::abs(fd))) << "forward " << g.toString(e);
      EXPECT_NEAR(grad[k], fd, 1e-5 * (1 + std::abs(fd))) << "reverse " << g.toString(e);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 300 * kVars);
}

// Spline nodes: values and time derivatives against CubicBSpline; derivatives with respect to
// control points and (through a variable-dependent time) the chain rule, in forward and reverse
// mode, against finite differences.
TEST(Expr, SplineNodes) {
  const CubicBSpline layout(0.0, 1.0, 5);
  const int m = layout.controlPointCount();  // 8 control variables, then x8 shifts time
  Graph g;
  std::vector<std::uint32_t> controls;
  for (int k = 0; k < m; ++k) controls.push_back(k);
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> x(m + 1);
  for (double& v : x) v = u(rng);
  Eigen::MatrixXd C(m, 1);
  for (int k = 0; k < m; ++k) C(k, 0) = x[k];
  for (double t : {0.05, 0.33, 0.5, 0.91}) {
    for (int order = 0; order <= 3; ++order) {
      const Expr s = g.spline(layout, controls, g.constant(t), order);
      EXPECT_NEAR(g.evaluate(s, x), layout.evaluate(C, t, order)(0), 1e-9);
    }
    // f = spline(t + 0.1 x8) * spline'(t) : controls and time both depend on variables.
    const Expr time = g.constant(t) + 0.1 * g.variable(m);
    const Expr f = g.spline(layout, controls, time, 0) * g.spline(layout, controls, g.constant(t), 1);
    const Tape full = Tape::compile(g, {f}, false), reused = Tape::compile(g, {f}, true);
    std::vector<double> grad(m + 1), w, adj;
    full.gradient(x.data(), 0.0, 0, grad.data(), m + 1, w, adj);
    using Jet = ceres::Jet<double, 9>;
    std::vector<Jet> xj(m + 1), wj;
    for (int k = 0; k <= m; ++k) xj[k] = Jet(x[k], k);
    Jet out;
    reused.evaluate(xj.data(), Jet(0.0), &out, wj);
    for (int k = 0; k <= m; ++k) {
      const double fd = finiteDifference(g, f, x, k);
      EXPECT_NEAR(out.v[k], fd, 1e-6) << "forward t=" << t << " k=" << k;
      EXPECT_NEAR(grad[k], fd, 1e-6) << "reverse t=" << t << " k=" << k;
    }
  }
}

TEST(Expr, NonSmoothOperationsAwayFromTheirKinks) {
  Graph g;
  const Expr x = g.variable(0), y = g.variable(1);
  const Expr f = min(x * x, y) + max(abs(x), y * 2.0) + pow(x * x + 1.0, y);
  const std::vector<double> p = {0.7, 0.3};
  const Tape tape = Tape::compile(g, {f}, true);
  using Jet = ceres::Jet<double, 2>;
  const std::vector<Jet> pj = {Jet(p[0], 0), Jet(p[1], 1)};
  std::vector<Jet> work;
  Jet out;
  tape.evaluate(pj.data(), Jet(0.0), &out, work);
  for (int k = 0; k < 2; ++k) EXPECT_NEAR(out.v[k], finiteDifference(g, f, p, k), 1e-6);
}

}  // namespace
}  // namespace spacetime::expr
