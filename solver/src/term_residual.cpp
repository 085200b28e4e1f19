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

void InputMap::add(int zRow, int blockIndex, int index, double weight, double slope) {
  entries_.push_back({zRow, blockIndex, index, weight, slope});
}

int InputMap::newRows(int count) {
  rows_ += count;
  return rows_ - count;
}

Eigen::MatrixXd InputMap::matrix() const { return assemble(&Entry::weight); }

Eigen::MatrixXd InputMap::slopeMatrix() const { return assemble(&Entry::slope); }

Eigen::MatrixXd InputMap::assemble(double Entry::*field) const {
  std::vector<int> offset(sizes_.size() + 1, 0);
  for (size_t i = 0; i < sizes_.size(); ++i) offset[i + 1] = offset[i] + sizes_[i];
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(rows_, offset.back());
  for (const Entry& e : entries_) B(e.row, offset[e.block] + e.index) += e.*field;
  return B;
}

TermResidual::TermResidual(std::shared_ptr<const Kernel> kernel, const InputMap& inputs,
                           const AugmentedLagrangianState* al, int firstMultiplier)
    : kernel_(std::move(kernel)), B_(inputs.matrix()), blocks_(inputs.blocks()), al_(al),
      firstMultiplier_(firstMultiplier) {
  set_num_residuals(kernel_->rowCount());
  for (int s : inputs.sizes()) mutable_parameter_block_sizes()->push_back(s);
}

TermResidual::TermResidual(std::shared_ptr<const Kernel> kernel, MovingInputs moving,
                           double* eventTime, const AugmentedLagrangianState* al,
                           int firstMultiplier)
    : kernel_(std::move(kernel)), moving_(std::move(moving)), al_(al),
      firstMultiplier_(firstMultiplier) {
  const InputMap inputs = moving_(*eventTime);
  B_ = inputs.matrix();
  blocks_ = inputs.blocks();
  blocks_.push_back(eventTime);
  set_num_residuals(kernel_->rowCount());
  for (int s : inputs.sizes()) mutable_parameter_block_sizes()->push_back(s);
  mutable_parameter_block_sizes()->push_back(1);
}

TermResidual::Map TermResidual::map(double const* const* parameters) const {
  Map m;
  if (!moving_) return m;
  const InputMap inputs = moving_(parameters[parameter_block_sizes().size() - 1][0]);
  m.moved = inputs.matrix();
  m.slope = inputs.slopeMatrix();
  m.scale = inputs.objectiveScale;
  m.scaleSlope = inputs.objectiveScaleSlope;
  return m;
}

Eigen::VectorXd TermResidual::stacked(double const* const* parameters) const {
  Eigen::VectorXd p(B_.cols());
  int k = 0;
  const auto& sizes = parameter_block_sizes();
  const size_t count = sizes.size() - (moving_ ? 1 : 0);
  for (size_t b = 0; b < count; ++b)
    for (int i = 0; i < sizes[b]; ++i) p[k++] = parameters[b][i];
  return p;
}

void TermResidual::scaleObjective(double scale, double* rows) const {
  if (scale == 1) return;
  const auto& kinds = kernel_->rowKinds();
  for (int r = 0; r < kernel_->rowCount(); ++r)
    if (kinds[r] == RowKind::Objective) rows[r] *= scale;
}

void TermResidual::rawRows(double const* const* parameters, double* rows) const {
  const Map m = map(parameters);
  const Eigen::VectorXd z = matrix(m) * stacked(parameters);
  kernel_->evaluate(z.data(), rows);
  scaleObjective(m.scale, rows);
}

std::vector<double> TermResidual::rawRowsNow() const {
  std::vector<double> rows(kernel_->rowCount());
  rawRows(blocks_.data(), rows.data());
  return rows;
}

Eigen::MatrixXd TermResidual::weightedHessianNow(const double* w) const {
  const Eigen::VectorXd z = B_ * stacked(blocks_.data());
  const int nz = kernel_->inputSize();
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> Hz(nz, nz);
  kernel_->weightedHessian(z.data(), w, Hz.data());
  return B_.transpose() * Hz * B_;
}

bool TermResidual::Evaluate(double const* const* parameters, double* residuals,
                            double** jacobians) const {
  const Map mp = map(parameters);
  const Eigen::VectorXd p = stacked(parameters);
  const Eigen::VectorXd z = matrix(mp) * p;
  const int m = kernel_->rowCount(), nz = kernel_->inputSize();
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> Jz(m, nz);
  if (jacobians)
    kernel_->evaluateWithJacobian(z.data(), residuals, Jz.data());
  else
    kernel_->evaluate(z.data(), residuals);

  // A moving sample's objective rows: sqrt of the quadrature weight, which changes with T.
  const auto& kinds = kernel_->rowKinds();
  Eigen::VectorXd scaleTerm = Eigen::VectorXd::Zero(m);  // d(scale)/dT * raw objective row
  if (moving_) {
    for (int r = 0; r < m; ++r)
      if (kinds[r] == RowKind::Objective) {
        scaleTerm[r] = mp.scaleSlope * residuals[r];
        residuals[r] *= mp.scale;
        if (jacobians) Jz.row(r) *= mp.scale;
      }
  }

  // Augmented-Lagrangian transform of each row: scale and (for inactive inequalities) zero.
  const double sr = std::sqrt(al_->rho);
  Eigen::VectorXd rowScale = Eigen::VectorXd::Ones(m);
  for (int r = 0; r < m; ++r) {
    if (!std::isfinite(residuals[r])) return false;  // Ceres rejects the step
    if (al_->raw) continue;
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
  const Eigen::MatrixXd Jp = rowScale.asDiagonal() * (Jz * matrix(mp));
  int col = 0;
  const auto& sizes = parameter_block_sizes();
  const size_t count = sizes.size() - (moving_ ? 1 : 0);
  if (moving_ && jacobians[count]) {  // the event time's column
    const Eigen::VectorXd dz = mp.slope * p;
    Eigen::Map<Eigen::VectorXd>(jacobians[count], m) = rowScale.asDiagonal() * (Jz * dz + scaleTerm);
  }
  for (size_t b = 0; b < count; ++b) {
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
