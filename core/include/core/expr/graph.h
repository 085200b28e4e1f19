// The expression graph: the seed's Expression Manager rebuilt for size and speed.
//
// Nodes live in one arena as 12-byte records (an op and two 32-bit child ids; constants sit in
// a side table and are referenced by index), hash-consed on (op, children) so an equal
// subexpression is always the same node, and simplified as they are built (constant folding,
// x+0, x*1, x*0, x-x, -(-x), gathered constants in sums and products). Simplification only ever
// returns an existing node or one new node, so it never grows the graph beyond what was asked.
// Expressions are compiled into a Tape for evaluation (see tape.h); derivatives come from
// evaluating the tape on ceres::Jet (forward mode).
#pragma once

#include <cstdint>

#include "core/bspline.h"
#include <string>
#include <unordered_map>
#include <vector>

namespace spacetime::expr {

enum class Op : std::uint8_t {
  Const, Var, Time,
  Add, Sub, Mul, Div, Neg,
  Sin, Cos, Tan, Exp, Log, Sqrt, Abs,
  Pow,  // real exponent; an integer-valued constant exponent evaluates by repeated products
  Min, Max,
  Spline,  // a: the time child; b: index of a SplineTerm (control variables, derivative order)
};

inline constexpr std::uint32_t kNone = 0xffffffffu;

struct Node {
  Op op = Op::Const;
  std::uint32_t a = kNone;  // first child, constant index (Const) or variable index (Var)
  std::uint32_t b = kNone;  // second child
};
static_assert(sizeof(Node) <= 12, "nodes must stay compact");

class Graph;

// A handle: the graph and a node id. Cheap to copy; arithmetic builds (simplified, shared)
// nodes in the handle's graph. A handle without a graph is a plain constant (what generic code
// writes as T(0) or T(1)); it joins a graph when combined with a handle that has one.
struct Expr {
  Graph* graph = nullptr;
  std::uint32_t id = kNone;
  double constant = 0;

  Expr() = default;
  Expr(double c) : constant(c) {}  // NOLINT: implicit, so generic code can write T(0)
  Expr(Graph* g, std::uint32_t i) : graph(g), id(i) {}

  Expr& operator+=(const Expr& o);
  Expr& operator-=(const Expr& o);
  Expr& operator*=(const Expr& o);
  Expr& operator/=(const Expr& o);
};

// A spline node's data: the cubic B-spline layout, the control points' variable
// indices, and which time derivative it is (the seed's B-spline expressions).
struct SplineTerm {
  CubicBSpline spline;
  std::vector<std::uint32_t> controls;  // variable index of each control point
  int order = 0;
  int indicator = -1;  // >= 0: the basis function of that control point (controls unused)
  bool operator==(const SplineTerm& o) const {
    return spline == o.spline && controls == o.controls &&
           order == o.order && indicator == o.indicator;
  }
  // Value at time t given the variables (template: the control values may be Jets).
  template <class V>
  V evaluate(double t, const V* variables) const {
    const BSplineBasis b = spline.basis(t);
    const auto& w = b.derivative(order);
    V sum = V(0.0);
    for (int j = 0; j < 4; ++j) {
      if (indicator >= 0) {
        if (b.first + j == indicator) sum = sum + V(w[j]);
      } else {
        sum = sum + variables[controls[b.first + j]] * w[j];
      }
    }
    return sum;
  }
};

class Graph {
 public:
  Graph();

  // sum_k B_k^(order)(t) x[controls[k]]: a spline of time over control-point variables.
  Expr spline(const CubicBSpline& layout, const std::vector<std::uint32_t>& controls,
              Expr time, int order = 0);
  const SplineTerm& splineTerm(std::uint32_t index) const { return splines_[index]; }
  // B_k^(order)(t): the basis function of control point k.
  Expr splineBasis(const CubicBSpline& layout, int k, Expr time, int order);

  Expr constant(double value);
  Expr variable(std::uint32_t index);
  Expr time();
  Expr make(Op op, Expr a, Expr b = {});  // simplifying, hash-consing constructor

  const Node& node(std::uint32_t id) const { return nodes_[id]; }
  double constantValue(std::uint32_t id) const { return constants_[nodes_[id].a]; }
  bool isConstant(std::uint32_t id, double value) const {
    return nodes_[id].op == Op::Const && constants_[nodes_[id].a] == value;
  }
  std::size_t size() const { return nodes_.size(); }
  std::size_t arenaBytes() const { return nodes_.capacity() * sizeof(Node); }
  std::size_t indexBytes() const;  // the hash index and the constant table, counted apart

  // Direct evaluation by recursion over a node (for tests; use a Tape for speed).
  double evaluate(Expr e, const std::vector<double>& variables, double t = 0) const;
  std::string toString(Expr e) const;

 private:
  struct Key {
    Op op;
    std::uint32_t a, b;
    bool operator==(const Key& o) const { return op == o.op && a == o.a && b == o.b; }
  };
  struct KeyHash {
    std::size_t operator()(const Key& k) const {
      std::uint64_t h = (static_cast<std::uint64_t>(k.a) << 32) ^ k.b;
      h ^= static_cast<std::uint64_t>(k.op) * 0x9e3779b97f4a7c15ull;
      h ^= h >> 29;
      h *= 0xbf58476d1ce4e5b9ull;
      return static_cast<std::size_t>(h ^ (h >> 32));
    }
  };
  std::uint32_t intern(Op op, std::uint32_t a, std::uint32_t b);
  Expr splineNode(const SplineTerm& term, Expr time);
  Expr simplify(Op op, Expr a, Expr b);

  std::vector<Node> nodes_;
  std::vector<double> constants_;
  std::vector<SplineTerm> splines_;
  std::unordered_map<Key, std::uint32_t, KeyHash> index_;
  std::unordered_map<std::uint64_t, std::uint32_t> constantIndex_;  // bit pattern -> node
};

// Arithmetic on handles (both in the same graph, or one a double).
Expr operator+(Expr a, Expr b);
Expr operator-(Expr a, Expr b);
Expr operator*(Expr a, Expr b);
Expr operator/(Expr a, Expr b);
Expr operator-(Expr a);
Expr operator+(Expr a, double b);
Expr operator+(double a, Expr b);
Expr operator-(Expr a, double b);
Expr operator-(double a, Expr b);
Expr operator*(Expr a, double b);
Expr operator*(double a, Expr b);
Expr operator/(Expr a, double b);
Expr operator/(double a, Expr b);
Expr sin(Expr a);
Expr cos(Expr a);
Expr tan(Expr a);
Expr exp(Expr a);
Expr log(Expr a);
Expr sqrt(Expr a);
Expr abs(Expr a);
Expr pow(Expr a, Expr b);
Expr pow(Expr a, double b);
Expr min(Expr a, Expr b);
Expr max(Expr a, Expr b);

}  // namespace spacetime::expr
