// TermResidual: the chain rule through the linear input map and the augmented-Lagrangian rows.
#include "solver/term_residual.h"

#include <cmath>

namespace spacetime {

int InputMap::block(double* data, int size) {
  for (size_t i = 0; i < blocks_.size(); ++i)
    if (blocks_[i] == data) return static_cast<int>(i);
  blocks_.push_back(data);
  sizes_.push_back(size);
  return static_cast<int>(blocks_.size()) - 1;
}

void InputMap::add(int zRow, int blockIndex, int index, double weight) {
  entries_.push_back({zRow, blockIndex, index, weight});
}

int InputMap::newRows(int count) {
  rows_ += count;
  return rows_ - count;
}

Eigen::MatrixXd InputMap::matrix() const {
  std::vector<int> offset(sizes_.size() + 1, 0);
  for (size_t i = 0; i < sizes_.size(); ++i) offset[i + 1] = offset[i] + sizes_[i];
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(rows_, offset.back());
  for (const Entry& e : entries_) B(e.row, offset[e.block] + e.index) += e.weight;
  return B;
}

TermResidual::TermResidual(std::shared_ptr<const Kernel> kernel, const InputMap& inputs,
                           const AugmentedLagrangianState* al, int firstMultiplier)
    : kernel_(std::move(kernel)), B_(inputs.matrix()), blocks_(inputs.blocks()), al_(al),
      firstMultiplier_(firstMultiplier) {
  set_num_residuals(kernel_->rowCount());
  for (int s : inputs.sizes()) mutable_parameter_block_sizes()->push_back(s);
}

Eigen::VectorXd TermResidual::inputs(double const* const* parameters) const {
  Eigen::VectorXd p(B_.cols());
  int k = 0;
  const auto& sizes = parameter_block_sizes();
  for (size_t b = 0; b < sizes.size(); ++b)
    for (int i = 0; i < sizes[b]; ++i) p[k++] = parameters[b][i];
  return B_ * p;
}

void TermResidual::rawRows(double const* const* parameters, double* rows) const {
  const Eigen::VectorXd z = inputs(parameters);
  kernel_->evaluate(z.data(), rows);
}

std::vector<double> TermResidual::rawRowsNow() const {
  std::vector<double> rows(kernel_->rowCount());
  rawRows(blocks_.data(), rows.data());
  return rows;
}

bool TermResidual::Evaluate(double const* const* parameters, double* residuals,
                            double** jacobians) const {
  const Eigen::VectorXd z = inputs(parameters);
  const int m = kernel_->rowCount(), nz = kernel_->inputSize();
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> Jz(m, nz);
  if (jacobians)
    kernel_->evaluateWithJacobian(z.data(), residuals, Jz.data());
  else
    kernel_->evaluate(z.data(), residuals);

  // Augmented-Lagrangian transform of each row: scale and (for inactive inequalities) zero.
  const double sr = std::sqrt(al_->rho);
  Eigen::VectorXd rowScale = Eigen::VectorXd::Ones(m);
  const auto& kinds = kernel_->rowKinds();
  for (int r = 0; r < m; ++r) {
    if (!std::isfinite(residuals[r])) return false;  // Ceres rejects the step
    if (al_->projectOnly) {
      const bool zero = kinds[r] == RowKind::Objective ||
                        (kinds[r] == RowKind::Inequality && residuals[r] <= 0);
      if (zero) residuals[r] = 0;
      rowScale[r] = zero ? 0 : 1;
      continue;
    }
    if (kinds[r] == RowKind::Objective) continue;
    const double shift = al_->lambda[firstMultiplier_ + r] / al_->rho;
    const double s = residuals[r] + shift;
    if (kinds[r] == RowKind::Inequality && s <= 0) {
      residuals[r] = 0;
      rowScale[r] = 0;
    } else {
      residuals[r] = sr * s;
      rowScale[r] = sr;
    }
  }
  if (!jacobians) return true;
  const Eigen::MatrixXd Jp = rowScale.asDiagonal() * (Jz * B_);
  int col = 0;
  const auto& sizes = parameter_block_sizes();
  for (size_t b = 0; b < sizes.size(); ++b) {
    if (jacobians[b]) {
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> J(
          jacobians[b], m, sizes[b]);
      J = Jp.middleCols(col, sizes[b]);
    }
    col += sizes[b];
  }
  return Jz.allFinite() || !jacobians;
}

}  // namespace spacetime
