// The formula language: what users type for custom constraints, objective terms and plotted
// quantities, parsed into the expression graph.
//
//   formula  := sum
//   sum      := product (('+' | '-') product)*
//   product  := unary (('*' | '/') unary)*
//   unary    := '-' unary | power
//   power    := postfix ('^' unary)?
//   postfix  := primary ('.' name)*           -- component of a vector: .x .y .z, or a dof
//   primary  := number | '(' sum ')' | '[' sum ',' sum ',' sum ']'
//             | name '(' arguments ')' | name
//
// Math functions: sin cos tan exp log sqrt abs pow min max. Every other name comes from a
// FormulaEnvironment (the character): `q.elbow`, `qd.elbow`, `qdd.elbow`, `tau.elbow`,
// `pos(head).y`, `pos(head, [0.1, 0, 0]).x`, `vel(base).x`, `com.y`, `force(base).y`, `t`.
// Errors name the column (1-based) and what was expected there.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "core/expr/graph.h"

namespace spacetime::expr {

// A value while parsing: a scalar, or a 3-vector (pos(...), [a, b, c]).
struct FormulaValue {
  bool isVector = false;
  Expr scalar;
  std::array<Expr, 3> vector;
};

class FormulaEnvironment {
 public:
  virtual ~FormulaEnvironment() = default;
  // A plain name such as "t", "com" or a group such as "q" (followed by ".dof"). Return
  // std::nullopt and set *error to say what is known.
  virtual std::optional<FormulaValue> name(const std::string& name, std::string* error) = 0;
  // A group member: group "q", "qd", "qdd" or "tau" and a dof name.
  virtual std::optional<Expr> member(const std::string& group, const std::string& member,
                                     std::string* error) = 0;
  // Whether `name` is a group that takes a ".member".
  virtual bool isGroup(const std::string& name) const = 0;
  // A vector function of a body, with an optional body point: pos, vel, force.
  virtual std::optional<std::array<Expr, 3>> bodyFunction(const std::string& function,
                                                          const std::string& body,
                                                          const std::optional<std::array<double, 3>>& point,
                                                          std::string* error) = 0;
  virtual bool isBodyFunction(const std::string& name) const = 0;
};

struct FormulaResult {
  std::optional<Expr> value;
  int column = 0;  // 1-based column of the error
  std::string error;
};

// Parses a scalar formula into graph g. Never throws on bad input.
FormulaResult parseFormula(const std::string& text, Graph& g, FormulaEnvironment& env);

}  // namespace spacetime::expr
