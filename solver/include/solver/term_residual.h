// TermResidual: a kernel made into a Ceres residual block of the augmented Lagrangian.
//
// The kernel's input z is a constant linear map B of the parameter blocks it touches (spline
// basis weights of the sample's time, identity for anchors and force control points), so its
// Jacobian with respect to the parameters is exactly J_z B. Rows are transformed by kind
// (Powell-Hestenes-Rockafellar augmented Lagrangian, Nocedal & Wright eq. 17.65 for
// inequalities): objective rows pass through; an equality c becomes sqrt(rho) (c + lambda/rho);
// an inequality g <= 0 becomes sqrt(rho) max(0, g + lambda/rho). Half the sum of squares is
// then f + lambda.c + rho/2 |c|^2 up to a constant, which Ceres minimises.
#pragma once

#include <ceres/cost_function.h>

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "solver/kernels.h"

namespace spacetime {

// Penalty and multipliers shared by all residuals of one problem.
struct AugmentedLagrangianState {
  double rho = 10;
  // Feasibility projection mode: objective rows vanish, equalities are c and inequalities
  // max(0, g), so minimising the sum of squares is a Gauss-Newton solve of c(x) = 0 (the
  // constraint step of Witkin & Kass 1988), which converges quadratically near the manifold.
  bool projectOnly = false;
  std::vector<double> lambda;  // one per row of every residual (objective rows unused)
};

// Builds the input map of one residual: which parameter blocks, and B.
class InputMap {
 public:
  // Adds a parameter block (deduplicated) and returns its index.
  int block(double* data, int size);
  // z[zRow] += weight * block[b][index]
  void add(int zRow, int blockIndex, int index, double weight);
  // Appends `count` new z rows and returns the first.
  int newRows(int count);

  int rows() const { return rows_; }
  const std::vector<double*>& blocks() const { return blocks_; }
  const std::vector<int>& sizes() const { return sizes_; }
  Eigen::MatrixXd matrix() const;

 private:
  struct Entry {
    int row, block, index;
    double weight;
  };
  std::vector<double*> blocks_;
  std::vector<int> sizes_;
  std::vector<Entry> entries_;
  int rows_ = 0;
};

class TermResidual : public ceres::CostFunction {
 public:
  TermResidual(std::shared_ptr<const Kernel> kernel, const InputMap& inputs,
               const AugmentedLagrangianState* al, int firstMultiplier);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

  // The kernel's raw rows at the given parameters (before the augmented-Lagrangian transform).
  void rawRows(double const* const* parameters, double* rows) const;
  // The same at the parameters' current values.
  std::vector<double> rawRowsNow() const;

  const Kernel& kernel() const { return *kernel_; }
  const std::vector<double*>& blocks() const { return blocks_; }
  int firstMultiplier() const { return firstMultiplier_; }

 private:
  Eigen::VectorXd inputs(double const* const* parameters) const;

  std::shared_ptr<const Kernel> kernel_;
  Eigen::MatrixXd B_;
  std::vector<double*> blocks_;
  const AugmentedLagrangianState* al_;
  int firstMultiplier_;
};

}  // namespace spacetime
