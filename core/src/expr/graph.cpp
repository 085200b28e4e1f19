// Expression graph: hash-consing, simplification and symbolic differentiation (see graph.h).
#include "core/expr/graph.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <sstream>
#include <stdexcept>

namespace spacetime::expr {
namespace {

bool commutative(Op op) { return op == Op::Add || op == Op::Mul || op == Op::Min || op == Op::Max; }

double apply(Op op, double x, double y) {
  switch (op) {
    case Op::Add: return x + y;
    case Op::Sub: return x - y;
    case Op::Mul: return x * y;
    case Op::Div: return x / y;
    case Op::Neg: return -x;
    case Op::Sin: return std::sin(x);
    case Op::Cos: return std::cos(x);
    case Op::Tan: return std::tan(x);
    case Op::Exp: return std::exp(x);
    case Op::Log: return std::log(x);
    case Op::Sqrt: return std::sqrt(x);
    case Op::Abs: return std::abs(x);
    case Op::Pow: return std::pow(x, y);
    case Op::Min: return std::min(x, y);
    case Op::Max: return std::max(x, y);
    default: break;
  }
  throw std::logic_error("expr: not an operation");
}

bool unary(Op op) {
  return op == Op::Neg || op == Op::Sin || op == Op::Cos || op == Op::Tan || op == Op::Exp ||
         op == Op::Log || op == Op::Sqrt || op == Op::Abs;
}

}  // namespace

Graph::Graph() {
  nodes_.reserve(1024);
  constant(0.0);
  constant(1.0);
}

std::size_t Graph::indexBytes() const {
  return index_.size() * (sizeof(Key) + sizeof(std::uint32_t) + 2 * sizeof(void*)) +
         index_.bucket_count() * sizeof(void*) + constants_.capacity() * sizeof(double) +
         constantIndex_.size() * (sizeof(std::uint64_t) + sizeof(std::uint32_t) + 2 * sizeof(void*));
}

Expr Graph::constant(double value) {
  if (value == 0.0) value = 0.0;  // one zero, whatever its sign
  std::uint64_t bits;
  std::memcpy(&bits, &value, sizeof bits);
  const auto it = constantIndex_.find(bits);
  if (it != constantIndex_.end()) return {this, it->second};
  constants_.push_back(value);
  nodes_.push_back({Op::Const, static_cast<std::uint32_t>(constants_.size() - 1), kNone});
  const auto id = static_cast<std::uint32_t>(nodes_.size() - 1);
  constantIndex_.emplace(bits, id);
  return {this, id};
}

std::uint32_t Graph::intern(Op op, std::uint32_t a, std::uint32_t b) {
  const Key key{op, a, b};
  const auto it = index_.find(key);
  if (it != index_.end()) return it->second;
  nodes_.push_back({op, a, b});
  const auto id = static_cast<std::uint32_t>(nodes_.size() - 1);
  index_.emplace(key, id);
  return id;
}

Expr Graph::variable(std::uint32_t index) { return {this, intern(Op::Var, index, kNone)}; }
Expr Graph::time() { return {this, intern(Op::Time, kNone, kNone)}; }

Expr Graph::make(Op op, Expr a, Expr b) { return simplify(op, a, b); }

Expr Graph::spline(const CubicBSpline& layout, const std::vector<std::uint32_t>& controls,
                   Expr time, int order) {
  if (static_cast<int>(controls.size()) != layout.controlPointCount())
    throw std::invalid_argument("expr: spline needs one variable per control point");
  return splineNode({layout, controls, order, -1}, time);
}

Expr Graph::splineBasis(const CubicBSpline& layout, int k, Expr time, int order) {
  return splineNode({layout, {}, order, k}, time);
}

Expr Graph::splineNode(const SplineTerm& term, Expr time) {
  if (term.order > 3) return constant(0);  // a cubic's fourth derivative
  std::uint32_t index = 0;
  while (index < splines_.size() && !(splines_[index] == term)) ++index;
  if (index == splines_.size()) splines_.push_back(term);
  return {this, intern(Op::Spline, time.graph ? time.id : constant(time.constant).id, index)};
}

Expr Graph::simplify(Op op, Expr a, Expr b) {
  const bool aConst = nodes_[a.id].op == Op::Const;
  const bool bConst = b.id != kNone && nodes_[b.id].op == Op::Const;
  // Constant folding.
  if (unary(op) && aConst) return constant(apply(op, constantValue(a.id), 0));
  if (!unary(op) && aConst && bConst) return constant(apply(op, constantValue(a.id), constantValue(b.id)));
  auto is = [&](Expr e, double v) { return isConstant(e.id, v); };
  const Node& na = nodes_[a.id];
  switch (op) {
    case Op::Neg:
      if (na.op == Op::Neg) return {this, na.a};  // -(-x) = x
      break;
    case Op::Add:
      if (is(a, 0)) return b;
      if (is(b, 0)) return a;
      if (aConst) std::swap(a, b);  // constant on the right
      if (nodes_[b.id].op == Op::Const && nodes_[a.id].op == Op::Add &&
          nodes_[nodes_[a.id].b].op == Op::Const)  // (x + c1) + c2 = x + (c1 + c2)
        return simplify(Op::Add, {this, nodes_[a.id].a},
                        constant(constantValue(nodes_[a.id].b) + constantValue(b.id)));
      break;
    case Op::Sub:
      if (a.id == b.id) return constant(0);
      if (is(b, 0)) return a;
      if (is(a, 0)) return simplify(Op::Neg, b, {});
      if (bConst) return simplify(Op::Add, a, constant(-constantValue(b.id)));
      break;
    case Op::Mul:
      if (is(a, 0) || is(b, 0)) return constant(0);
      if (is(a, 1)) return b;
      if (is(b, 1)) return a;
      if (is(a, -1)) return simplify(Op::Neg, b, {});
      if (is(b, -1)) return simplify(Op::Neg, a, {});
      if (aConst) std::swap(a, b);
      if (nodes_[b.id].op == Op::Const && nodes_[a.id].op == Op::Mul &&
          nodes_[nodes_[a.id].b].op == Op::Const)  // (x c1) c2 = x (c1 c2)
        return simplify(Op::Mul, {this, nodes_[a.id].a},
                        constant(constantValue(nodes_[a.id].b) * constantValue(b.id)));
      break;
    case Op::Div:
      if (is(a, 0)) return constant(0);
      if (is(b, 1)) return a;
      if (a.id == b.id) return constant(1);
      if (bConst) return simplify(Op::Mul, a, constant(1.0 / constantValue(b.id)));
      break;
    case Op::Pow:
      if (is(b, 0)) return constant(1);
      if (is(b, 1)) return a;
      break;
    case Op::Min:
    case Op::Max:
      if (a.id == b.id) return a;
      break;
    default: break;
  }
  if (commutative(op) && b.id != kNone && b.id < a.id && nodes_[b.id].op != Op::Const)
    std::swap(a, b);  // canonical order, so a+b and b+a are one node
  return {this, intern(op, a.id, b.id)};
}

double Graph::evaluate(Expr e, const std::vector<double>& variables, double t) const {
  const Node& n = nodes_[e.id];
  switch (n.op) {
    case Op::Const: return constants_[n.a];
    case Op::Var: return variables.at(n.a);
    case Op::Time: return t;
    case Op::Spline:
      return splines_[n.b].evaluate(evaluate({const_cast<Graph*>(this), n.a}, variables, t),
                                    variables.data());
    default: break;
  }
  const double x = evaluate({const_cast<Graph*>(this), n.a}, variables, t);
  const double y = n.b == kNone ? 0.0 : evaluate({const_cast<Graph*>(this), n.b}, variables, t);
  return apply(n.op, x, y);
}

std::string Graph::toString(Expr e) const {
  static const char* names[] = {"c",   "v",    "t",   "+",   "-",   "*",   "/",
                                "neg", "sin",  "cos", "tan", "exp", "log", "sqrt",
                                "abs", "pow",  "min", "max", "spline"};
  const Node& n = nodes_[e.id];
  std::ostringstream s;
  switch (n.op) {
    case Op::Const: s << constants_[n.a]; return s.str();
    case Op::Var: s << "x" << n.a; return s.str();
    case Op::Time: return "t";
    default: break;
  }
  Graph* self = const_cast<Graph*>(this);
  s << names[static_cast<int>(n.op)] << "(" << toString({self, n.a});
  if (n.b != kNone) s << ", " << toString({self, n.b});
  s << ")";
  return s.str();
}

namespace {
Graph* graphOf(Expr a, Expr b) {
  if (a.graph && b.graph && a.graph != b.graph) throw std::logic_error("expr: two graphs");
  return a.graph ? a.graph : b.graph;
}
Expr bind(Graph* g, Expr e) { return e.graph ? e : g->constant(e.constant); }
Expr binary(Op op, Expr a, Expr b) {
  Graph* g = graphOf(a, b);
  if (!g) return Expr(apply(op, a.constant, b.constant));
  return g->make(op, bind(g, a), bind(g, b));
}
Expr unaryOp(Op op, Expr a) {
  if (!a.graph) return Expr(apply(op, a.constant, 0));
  return a.graph->make(op, a);
}
}  // namespace

Expr& Expr::operator+=(const Expr& o) { return *this = *this + o; }
Expr& Expr::operator-=(const Expr& o) { return *this = *this - o; }
Expr& Expr::operator*=(const Expr& o) { return *this = *this * o; }
Expr& Expr::operator/=(const Expr& o) { return *this = *this / o; }

Expr operator+(Expr a, Expr b) { return binary(Op::Add, a, b); }
Expr operator-(Expr a, Expr b) { return binary(Op::Sub, a, b); }
Expr operator*(Expr a, Expr b) { return binary(Op::Mul, a, b); }
Expr operator/(Expr a, Expr b) { return binary(Op::Div, a, b); }
Expr operator-(Expr a) { return unaryOp(Op::Neg, a); }
Expr operator+(Expr a, double b) { return a + Expr(b); }
Expr operator+(double a, Expr b) { return Expr(a) + b; }
Expr operator-(Expr a, double b) { return a - Expr(b); }
Expr operator-(double a, Expr b) { return Expr(a) - b; }
Expr operator*(Expr a, double b) { return a * Expr(b); }
Expr operator*(double a, Expr b) { return Expr(a) * b; }
Expr operator/(Expr a, double b) { return a / Expr(b); }
Expr operator/(double a, Expr b) { return Expr(a) / b; }
Expr sin(Expr a) { return unaryOp(Op::Sin, a); }
Expr cos(Expr a) { return unaryOp(Op::Cos, a); }
Expr tan(Expr a) { return unaryOp(Op::Tan, a); }
Expr exp(Expr a) { return unaryOp(Op::Exp, a); }
Expr log(Expr a) { return unaryOp(Op::Log, a); }
Expr sqrt(Expr a) { return unaryOp(Op::Sqrt, a); }
Expr abs(Expr a) { return unaryOp(Op::Abs, a); }
Expr pow(Expr a, Expr b) { return binary(Op::Pow, a, b); }
Expr pow(Expr a, double b) { return binary(Op::Pow, a, Expr(b)); }
Expr min(Expr a, Expr b) { return binary(Op::Min, a, b); }
Expr max(Expr a, Expr b) { return binary(Op::Max, a, b); }

}  // namespace spacetime::expr
