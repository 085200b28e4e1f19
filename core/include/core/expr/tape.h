// A compiled expression: the reachable nodes of some outputs in topological order as a flat
// list of instructions over numbered slots, evaluated by one tight loop. Compiled with slot
// reuse (a slot is recycled after its last reader) for plain evaluation, or with one slot per
// instruction for reverse mode and for finding where a NaN or an infinity is born
// (firstNonFinite), which need every intermediate value. Evaluation is a template on the scalar, so ceres::Jet flows through it
// (forward mode: the solver's exact Jacobians of formula terms) as doubles do.
#pragma once

#include <cmath>
#include <optional>
#include <type_traits>
#include <vector>

#include "core/expr/graph.h"

namespace spacetime::expr {

struct Instruction {
  Op op;
  std::uint32_t dst, a, b;  // slots; for Const `a` indexes the tape's constants, for Var a variable
};

// Whether an instruction's `a` and `b` are slots: Const, Var and Time read other tables, unary
// operations have no `b`, and a Spline's `b` indexes the tape's splines. Sweeps over the slots
// read the operands only where they are slots (reading them always ran past the slots: ASan).
inline bool readsSlotA(Op op) { return op != Op::Const && op != Op::Var && op != Op::Time; }
inline bool readsSlotB(Op op) {
  return op == Op::Add || op == Op::Sub || op == Op::Mul || op == Op::Div || op == Op::Pow || op == Op::Min ||
         op == Op::Max;
}

// The plain value of a scalar (double, ceres::Jet): what a spline's basis is looked up at.
inline double valueOf(double x) { return x; }
template <class T>
auto valueOf(const T& x) -> decltype(x.a) {
  return x.a;
}

class Tape {
 public:
  static Tape compile(const Graph& graph, const std::vector<Expr>& outputs, bool reuseSlots = true);

  std::size_t length() const { return code_.size(); }
  std::size_t slotCount() const { return slots_; }
  std::size_t outputCount() const { return outputs_.size(); }

  // outputs[k] = value of output k. `work` is resized as needed and may be reused across calls.
  template <class T>
  void evaluate(const T* variables, const T& time, T* outputs, std::vector<T>& work) const;

  // Reverse mode: gradient of output `output` with respect to the variables (size `count`).
  // Requires a tape compiled without slot reuse. A template so that running it on Jets gives
  // forward-over-reverse second derivatives (the dynamics kernel's exact Hessian, kernels.cpp).
  template <class T>
  void gradient(const T* variables, const T& time, std::size_t output, T* gradient,
                std::size_t count, std::vector<T>& work, std::vector<T>& adjoint) const;

  // Where a NaN or an infinity is born: the operation of the first instruction whose value is
  // not finite though its operands are (nullopt if every value is finite). Needs a tape compiled
  // without slot reuse, which keeps every intermediate value.
  std::optional<Op> firstNonFinite(const double* variables, double time) const;

 private:
  std::vector<Instruction> code_;
  std::vector<double> constants_;
  std::vector<SplineTerm> splines_;
  std::vector<std::uint32_t> outputs_;  // slots
  std::size_t slots_ = 0;
  bool reuse_ = true;
  void checkKeepsEverySlot() const;  // throws for a tape compiled with slot reuse
  // Runs the instructions, leaving every slot's value in w.
  template <class T>
  void evaluateSlots(const T* variables, const T& time, std::vector<T>& w) const;
};

template <class T>
void Tape::evaluate(const T* v, const T& time, T* out, std::vector<T>& w) const {
  evaluateSlots(v, time, w);
  for (std::size_t k = 0; k < outputs_.size(); ++k) out[k] = w[outputs_[k]];
}

template <class T>
void Tape::evaluateSlots(const T* v, const T& time, std::vector<T>& w) const {
  using std::abs;
  using std::cos;
  using std::exp;
  using std::log;
  using std::max;
  using std::min;
  using std::pow;
  using std::sin;
  using std::sqrt;
  using std::tan;
  if (w.size() < slots_) w.resize(slots_);
  for (const Instruction& in : code_) {
    T& d = w[in.dst];
    switch (in.op) {
      case Op::Const: d = T(constants_[in.a]); break;
      case Op::Var: d = v[in.a]; break;
      case Op::Time: d = time; break;
      case Op::Add: d = w[in.a] + w[in.b]; break;
      case Op::Sub: d = w[in.a] - w[in.b]; break;
      case Op::Mul: d = w[in.a] * w[in.b]; break;
      case Op::Div: d = w[in.a] / w[in.b]; break;
      case Op::Neg: d = -w[in.a]; break;
      case Op::Sin: d = sin(w[in.a]); break;
      case Op::Cos: d = cos(w[in.a]); break;
      case Op::Tan: d = tan(w[in.a]); break;
      case Op::Exp: d = exp(w[in.a]); break;
      case Op::Log: d = log(w[in.a]); break;
      case Op::Sqrt: d = sqrt(w[in.a]); break;
      case Op::Abs: d = abs(w[in.a]); break;
      case Op::Pow: d = pow(w[in.a], w[in.b]); break;
      case Op::Min: d = w[in.a] < w[in.b] ? w[in.a] : w[in.b]; break;
      case Op::Max: d = w[in.a] < w[in.b] ? w[in.b] : w[in.a]; break;
      case Op::Spline: {
        // The basis is looked up at the time's value; a time carrying derivatives (Jets) adds
        // the chain rule through the next derivative order.
        const SplineTerm& st = splines_[in.b];
        const T tt = w[in.a];
        const double tv = valueOf(tt);
        T value = st.evaluate(tv, v);
        if constexpr (!std::is_same_v<T, double>) {
          SplineTerm next = st;
          ++next.order;
          if (next.order <= 3) value = value + (tt - T(tv)) * next.evaluate(tv, v);
        }
        d = value;
        break;
      }
    }
  }
}

template <class T>
void Tape::gradient(const T* v, const T& time, std::size_t output, T* grad, std::size_t count,
                    std::vector<T>& w, std::vector<T>& adj) const {
  using std::cos;
  using std::log;
  using std::pow;
  using std::sin;
  checkKeepsEverySlot();
  evaluateSlots(v, time, w);
  adj.assign(slots_, T(0.0));
  for (std::size_t i = 0; i < count; ++i) grad[i] = T(0.0);
  adj[outputs_[output]] = T(1.0);
  // Adjoints accumulated in reverse instruction order (Griewank & Walther, ch. 3).
  for (std::size_t i = code_.size(); i-- > 0;) {
    const Instruction& in = code_[i];
    const T a = adj[in.dst];
    const T& r = w[in.dst];
    const T& x = readsSlotA(in.op) ? w[in.a] : r;
    const T& y = readsSlotB(in.op) ? w[in.b] : r;
    switch (in.op) {
      case Op::Const:
      case Op::Time: break;
      case Op::Var:
        if (in.a < count) grad[in.a] += a;
        break;
      case Op::Add: adj[in.a] += a; adj[in.b] += a; break;
      case Op::Sub: adj[in.a] += a; adj[in.b] -= a; break;
      case Op::Mul: adj[in.a] += a * y; adj[in.b] += a * x; break;
      case Op::Div: adj[in.a] += a / y; adj[in.b] -= a * r / y; break;
      case Op::Neg: adj[in.a] -= a; break;
      case Op::Sin: adj[in.a] += a * cos(x); break;
      case Op::Cos: adj[in.a] -= a * sin(x); break;
      case Op::Tan: adj[in.a] += a * (T(1.0) + r * r); break;
      case Op::Exp: adj[in.a] += a * r; break;
      case Op::Log: adj[in.a] += a / x; break;
      case Op::Sqrt: adj[in.a] += a / (T(2.0) * r); break;
      case Op::Abs:
        if (x < T(0.0)) adj[in.a] -= a; else adj[in.a] += a;
        break;
      case Op::Pow:
        adj[in.a] += a * y * pow(x, y - T(1.0));
        if (T(0.0) < x) adj[in.b] += a * r * log(x);
        break;
      case Op::Min:
        if (x < y) adj[in.a] += a; else adj[in.b] += a;
        break;
      case Op::Max:
        if (x < y) adj[in.b] += a; else adj[in.a] += a;
        break;
      case Op::Spline: {
        const SplineTerm& st = splines_[in.b];
        const double tv = valueOf(x);
        const BSplineBasis b = st.spline.basis(tv);
        if (st.indicator < 0)
          for (int j = 0; j < 4; ++j) {
            const std::uint32_t var = st.controls[b.first + j];
            if (var < count) grad[var] += a * b.derivative(st.order)[j];
          }
        if (st.order < 3) {
          SplineTerm next = st;
          ++next.order;
          adj[in.a] += a * next.evaluate(tv, v);
        }
        break;
      }
    }
  }
}

}  // namespace spacetime::expr
