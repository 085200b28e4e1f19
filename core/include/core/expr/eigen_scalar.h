// Makes expr::Expr an Eigen scalar, so the templated spatial algebra and dynamics build
// symbolic graphs exactly as they compute doubles and Jets ("one implementation, three
// scalars"). Mixed products with double are allowed, as for ceres::Jet.
#pragma once

#include <Eigen/Core>

#include "core/expr/graph.h"

namespace Eigen {

template <>
struct NumTraits<spacetime::expr::Expr> : GenericNumTraits<spacetime::expr::Expr> {
  using Real = spacetime::expr::Expr;
  using NonInteger = spacetime::expr::Expr;
  using Nested = spacetime::expr::Expr;
  using Literal = spacetime::expr::Expr;
  enum {
    IsComplex = 0,
    IsInteger = 0,
    IsSigned = 1,
    RequireInitialization = 1,
    ReadCost = 1,
    AddCost = 3,
    MulCost = 3
  };
  static inline Real epsilon() { return Real(std::numeric_limits<double>::epsilon()); }
  static inline Real dummy_precision() { return Real(1e-12); }
  static inline int digits10() { return std::numeric_limits<double>::digits10; }
};

template <typename BinaryOp>
struct ScalarBinaryOpTraits<spacetime::expr::Expr, double, BinaryOp> {
  using ReturnType = spacetime::expr::Expr;
};
template <typename BinaryOp>
struct ScalarBinaryOpTraits<double, spacetime::expr::Expr, BinaryOp> {
  using ReturnType = spacetime::expr::Expr;
};

}  // namespace Eigen
