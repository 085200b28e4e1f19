// Tape compilation (iterative post-order, so deep graphs cannot overflow the stack), slot
// allocation by last use, and the reverse sweep (Griewank & Walther, "Evaluating Derivatives",
// ch. 3: adjoints accumulated in reverse instruction order).
#include "core/expr/tape.h"

#include <algorithm>
#include <iterator>

#include "core/expr/dual.h"
#include <stdexcept>
#include <unordered_map>

namespace spacetime::expr {

namespace {
// The second child of a node, or kNone (a spline's b is a table index, not a child).
std::uint32_t secondChild(const Node& n) { return n.op == Op::Spline ? kNone : n.b; }
}  // namespace

Tape Tape::compile(const Graph& g, const std::vector<Expr>& outputs, bool reuseSlots) {
  Tape tape;
  std::unordered_map<std::uint32_t, std::uint32_t> splineIndex;  // graph -> tape
  tape.reuse_ = reuseSlots;
  // Topological order of the reachable nodes.
  std::vector<std::uint32_t> order;
  std::unordered_map<std::uint32_t, std::uint32_t> position;  // node -> index in order
  std::vector<std::pair<std::uint32_t, bool>> stack;
  for (const Expr& e : outputs) stack.push_back({e.id, false});
  while (!stack.empty()) {
    auto [id, expanded] = stack.back();
    stack.pop_back();
    if (position.count(id)) continue;
    const Node& n = g.node(id);
    const bool leaf = n.op == Op::Const || n.op == Op::Var || n.op == Op::Time;
    if (expanded || leaf) {
      position.emplace(id, static_cast<std::uint32_t>(order.size()));
      order.push_back(id);
      continue;
    }
    stack.push_back({id, true});
    if (secondChild(n) != kNone && !position.count(n.b)) stack.push_back({n.b, false});
    if (!position.count(n.a)) stack.push_back({n.a, false});
  }
  // Last reader of every value (outputs live to the end).
  std::vector<std::size_t> lastUse(order.size(), 0);
  for (std::size_t i = 0; i < order.size(); ++i) {
    const Node& n = g.node(order[i]);
    if (n.op == Op::Const || n.op == Op::Var || n.op == Op::Time) continue;
    lastUse[position[n.a]] = i;
    if (secondChild(n) != kNone) lastUse[position[n.b]] = i;
  }
  for (const Expr& e : outputs) lastUse[position[e.id]] = order.size();
  // Slots.
  std::vector<std::uint32_t> slotOf(order.size());
  std::vector<std::uint32_t> freeSlots;
  std::vector<std::vector<std::uint32_t>> releaseAt(order.size() + 1);
  std::uint32_t nextSlot = 0;
  for (std::size_t i = 0; i < order.size(); ++i) {
    const Node& n = g.node(order[i]);
    Instruction in{n.op, 0, 0, 0};
    if (n.op == Op::Const) {
      in.a = static_cast<std::uint32_t>(tape.constants_.size());
      tape.constants_.push_back(g.constantValue(order[i]));
    } else if (n.op == Op::Var) {
      in.a = n.a;
    } else if (n.op == Op::Spline) {
      in.a = slotOf[position[n.a]];
      auto [it, fresh] = splineIndex.emplace(n.b, static_cast<std::uint32_t>(tape.splines_.size()));
      if (fresh) tape.splines_.push_back(g.splineTerm(n.b));
      in.b = it->second;
    } else if (n.op != Op::Time) {
      in.a = slotOf[position[n.a]];
      in.b = n.b != kNone ? slotOf[position[n.b]] : 0;
    }
    // Operands whose last use is this instruction free their slots before the result is
    // placed, so the result may overwrite an operand (each op reads before it writes).
    if (reuseSlots)
      for (std::uint32_t s : releaseAt[i]) freeSlots.push_back(s);
    if (reuseSlots && !freeSlots.empty()) {
      in.dst = freeSlots.back();
      freeSlots.pop_back();
    } else {
      in.dst = nextSlot++;
    }
    slotOf[i] = in.dst;
    if (reuseSlots && lastUse[i] < order.size() && lastUse[i] > i) releaseAt[lastUse[i]].push_back(in.dst);
    if (reuseSlots && lastUse[i] == 0 && i + 1 < order.size()) releaseAt[i + 1].push_back(in.dst);  // unused
    tape.code_.push_back(in);
  }
  for (const Expr& e : outputs) tape.outputs_.push_back(slotOf[position[e.id]]);
  tape.slots_ = nextSlot;
  return tape;
}

std::optional<Op> Tape::firstNonFinite(const double* v, double time) const {
  checkReverse();
  std::vector<double> w;
  evaluateSlots(v, time, w);
  for (const Instruction& in : code_) {
    if (std::isfinite(w[in.dst])) continue;
    const bool finiteA = !readsSlotA(in.op) || std::isfinite(w[in.a]);
    const bool finiteB = !readsSlotB(in.op) || std::isfinite(w[in.b]);
    if (finiteA && finiteB) return in.op;
  }
  return std::nullopt;
}

void Tape::checkReverse() const {
  if (reuse_) throw std::logic_error("expr::Tape: reverse mode needs a tape compiled without slot reuse");
}

void Tape::gradient(const double* v, double time, std::size_t output, double* grad,
                    std::size_t count, std::vector<double>& w, std::vector<double>& adj) const {
  checkReverse();
  if (!splines_.empty()) return gradient<double>(v, time, output, grad, count, w, adj);
  if (w.size() < slots_ + 2 * code_.size()) w.resize(slots_ + 2 * code_.size());
  double* p = w.data() + slots_;  // two local partials per instruction
  for (std::size_t i = 0; i < code_.size(); ++i) {
    const Instruction& in = code_[i];
    double& d = w[in.dst];
    double& pa = p[2 * i];
    double& pb = p[2 * i + 1];
    const double x = readsSlotA(in.op) ? w[in.a] : 0.0, y = readsSlotB(in.op) ? w[in.b] : 0.0;
    switch (in.op) {
      case Op::Const: d = constants_[in.a]; break;
      case Op::Var: d = v[in.a]; break;
      case Op::Time: d = time; break;
      case Op::Add: d = x + y; pa = 1; pb = 1; break;
      case Op::Sub: d = x - y; pa = 1; pb = -1; break;
      case Op::Mul: d = x * y; pa = y; pb = x; break;
      case Op::Div: d = x / y; pa = 1 / y; pb = -d / y; break;
      case Op::Neg: d = -x; pa = -1; break;
      case Op::Sin: d = std::sin(x); pa = std::cos(x); break;
      case Op::Cos: d = std::cos(x); pa = -std::sin(x); break;
      case Op::Tan: d = std::tan(x); pa = 1 + d * d; break;
      case Op::Exp: d = std::exp(x); pa = d; break;
      case Op::Log: d = std::log(x); pa = 1 / x; break;
      case Op::Sqrt: d = std::sqrt(x); pa = 1 / (2 * d); break;
      case Op::Abs: d = std::abs(x); pa = x >= 0 ? 1 : -1; break;
      case Op::Pow:
        d = std::pow(x, y);
        pa = y * std::pow(x, y - 1);
        pb = x > 0 ? d * std::log(x) : 0;
        break;
      case Op::Min: d = x < y ? x : y; pa = x < y; pb = !(x < y); break;
      case Op::Max: d = x < y ? y : x; pa = !(x < y); pb = x < y; break;
      case Op::Spline: break;  // excluded above
    }
  }
  adj.assign(slots_, 0.0);
  std::fill(grad, grad + count, 0.0);
  adj[outputs_[output]] = 1.0;
  for (std::size_t i = code_.size(); i-- > 0;) {
    const Instruction& in = code_[i];
    const double a = adj[in.dst];
    if (a == 0.0) continue;
    switch (in.op) {
      case Op::Const:
      case Op::Time: break;
      case Op::Var:
        if (in.a < count) grad[in.a] += a;
        break;
      case Op::Add: case Op::Sub: case Op::Mul: case Op::Div: case Op::Pow: case Op::Min:
      case Op::Max:
        adj[in.a] += a * p[2 * i];
        adj[in.b] += a * p[2 * i + 1];
        break;
      default: adj[in.a] += a * p[2 * i]; break;
    }
  }
}

void Tape::hessianVectorProduct(const double* x, double time, std::size_t output,
                                const double* direction, double* product, std::size_t count) const {
  std::vector<Dual> xd(count), grad(count), work, adjoint;
  for (std::size_t i = 0; i < count; ++i) xd[i] = Dual(x[i], direction[i]);
  gradient(xd.data(), Dual(time), output, grad.data(), count, work, adjoint);
  for (std::size_t i = 0; i < count; ++i) product[i] = grad[i].d;
}

std::vector<std::vector<std::uint32_t>> Tape::sparsity() const {
  std::vector<std::vector<std::uint32_t>> deps(slots_);
  for (const Instruction& in : code_) {
    std::vector<std::uint32_t> d;
    switch (in.op) {
      case Op::Const:
      case Op::Time: break;
      case Op::Var: d = {in.a}; break;
      case Op::Spline: {
        const SplineTerm& st = splines_[in.b];
        std::vector<std::uint32_t> controls = st.controls;
        std::sort(controls.begin(), controls.end());
        controls.erase(std::unique(controls.begin(), controls.end()), controls.end());
        std::set_union(controls.begin(), controls.end(), deps[in.a].begin(), deps[in.a].end(),
                       std::back_inserter(d));
        break;
      }
      default: {
        const bool binary = in.op == Op::Add || in.op == Op::Sub || in.op == Op::Mul ||
                            in.op == Op::Div || in.op == Op::Pow || in.op == Op::Min ||
                            in.op == Op::Max;
        d = deps[in.a];
        if (binary) {
          std::vector<std::uint32_t> merged;
          std::set_union(d.begin(), d.end(), deps[in.b].begin(), deps[in.b].end(),
                         std::back_inserter(merged));
          d = std::move(merged);
        }
      }
    }
    deps[in.dst] = std::move(d);
  }
  std::vector<std::vector<std::uint32_t>> out;
  for (std::uint32_t s : outputs_) out.push_back(deps[s]);
  return out;
}

}  // namespace spacetime::expr
