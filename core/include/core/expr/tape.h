// A compiled expression: the reachable nodes of some outputs in topological order as a flat
// list of instructions over numbered slots, evaluated by one tight loop. Compiled with slot
// reuse (a slot is recycled after its last reader) for plain evaluation, or with one slot per
// instruction for reverse mode, which needs every intermediate value. Evaluation is a template
// on the scalar, so ceres::Jet flows through it (forward mode) as doubles do.
#pragma once

#include <cmath>
#include <vector>

#include "core/expr/graph.h"

namespace spacetime::expr {

struct Instruction {
  Op op;
  std::uint32_t dst, a, b;  // slots; for Const `a` indexes the tape's constants, for Var a variable
};

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
  // Requires a tape compiled without slot reuse.
  void gradient(const double* variables, double time, std::size_t output, double* gradient,
                std::size_t count, std::vector<double>& work, std::vector<double>& adjoint) const;

 private:
  std::vector<Instruction> code_;
  std::vector<double> constants_;
  std::vector<std::uint32_t> outputs_;  // slots
  std::size_t slots_ = 0;
  bool reuse_ = true;
};

template <class T>
void Tape::evaluate(const T* v, const T& time, T* out, std::vector<T>& w) const {
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
    }
  }
  for (std::size_t k = 0; k < outputs_.size(); ++k) out[k] = w[outputs_[k]];
}

}  // namespace spacetime::expr
