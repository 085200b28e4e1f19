// Tape compilation (iterative post-order, so deep graphs cannot overflow the stack), slot
// allocation by last use, and the reverse sweep (Griewank & Walther, "Evaluating Derivatives",
// ch. 3: adjoints accumulated in reverse instruction order).
#include "core/expr/tape.h"

#include <algorithm>
#include <iterator>

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
  checkKeepsEverySlot();
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

void Tape::checkKeepsEverySlot() const {
  if (reuse_) throw std::logic_error("expr::Tape: reverse mode and firstNonFinite need a tape compiled without slot reuse");
}

}  // namespace spacetime::expr
