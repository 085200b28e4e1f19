// TermResidual: the chain rule through the linear input map and the augmented-Lagrangian rows.
#include "solver/term_residual.h"

#include <algorithm>
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

void SparseMap::apply(const double* p, double* z) const {
  std::fill(z, z + rows, 0.0);
  for (const Entry& e : entries) z[e.row] += e.value * p[e.col];
}

SparseMap InputMap::matrix() const { return assemble(&Entry::weight); }

SparseMap InputMap::slopeMatrix() const { return assemble(&Entry::slope); }

SparseMap InputMap::assemble(double Entry::*field) const {
  std::vector<int> offset(sizes_.size() + 1, 0);
  for (size_t i = 0; i < sizes_.size(); ++i) offset[i + 1] = offset[i] + sizes_[i];
  SparseMap B;
  B.rows = rows_;
  B.cols = offset.back();
  for (const Entry& e : entries_)
    if (e.*field != 0) B.entries.push_back({e.row, offset[e.block] + e.index, e.*field});
  return B;
}

TermResidual::TermResidual(std::shared_ptr<const Kernel> kernel, const InputMap& inputs,
                           const AugmentedLagrangianState* al, int firstMultiplier)
    : kernel_(std::move(kernel)), B_(inputs.matrix()), blocks_(inputs.blocks()), al_(al),
      firstMultiplier_(firstMultiplier) {
  set_num_residuals(kernel_->rowCount());
  for (int s : inputs.sizes()) mutable_parameter_block_sizes()->push_back(s);
  indexColumns(inputs.sizes());
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
  indexColumns(inputs.sizes());
}

void TermResidual::indexColumns(const std::vector<int>& sizes) {
  size_t total = 0;
  for (int size : sizes) total += static_cast<size_t>(size);
  colBlock_.reserve(total);
  colIndex_.reserve(total);
  for (size_t b = 0; b < sizes.size(); ++b)
    for (int i = 0; i < sizes[b]; ++i) {
      colBlock_.push_back(static_cast<int>(b));
      colIndex_.push_back(i);
    }
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

void TermResidual::stackInto(double const* const* parameters, double* p) const {
  int k = 0;
  const auto& sizes = parameter_block_sizes();
  const size_t count = sizes.size() - (moving_ ? 1 : 0);
  for (size_t b = 0; b < count; ++b)
    for (int i = 0; i < sizes[b]; ++i) p[k++] = parameters[b][i];
}

Eigen::VectorXd TermResidual::stacked(double const* const* parameters) const {
  Eigen::VectorXd p(B_.cols);
  stackInto(parameters, p.data());
  return p;
}

void TermResidual::scaleObjective(double scale, double* rows) const {
  if (scale == 1) return;
  const auto& kinds = kernel_->rowKinds();
  for (int r = 0; r < kernel_->rowCount(); ++r)
    if (kinds[r] == RowKind::Objective) rows[r] *= scale;
}

Eigen::VectorXd TermResidual::inputs(const Map& m, double const* const* parameters) const {
  Eigen::VectorXd z(kernel_->inputSize());
  matrix(m).apply(stacked(parameters).data(), z.data());
  return z;
}

void TermResidual::rawRows(double const* const* parameters, double* rows) const {
  const Map m = map(parameters);
  kernel_->evaluate(inputs(m, parameters).data(), rows);
  scaleObjective(m.scale, rows);
}

Eigen::VectorXd TermResidual::inputsNow() const { return inputs(map(blocks_.data()), blocks_.data()); }

std::vector<double> TermResidual::rawRowsNow() const {
  std::vector<double> rows(kernel_->rowCount());
  rawRows(blocks_.data(), rows.data());
  return rows;
}

Eigen::MatrixXd TermResidual::weightedHessianNow(const double* w, const std::vector<int>* columns) const {
  const int nz = kernel_->inputSize();
  Eigen::VectorXd z(nz);
  B_.apply(stacked(blocks_.data()).data(), z.data());
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> Hz(nz, nz);
  kernel_->weightedHessian(z.data(), w, Hz.data());
  // B^T Hz B one pair of B's nonzeros at a time, in the pairs' order, skipping the pairs whose
  // Hz entry is zero: each z row's list of B's entries under a nonzero of Hz (in entry order) is
  // made once per call, so a pair that adds nothing is not visited (the flight's dynamics: 108^2
  // pairs, Hz nonzero in about 140 of its 324 entries). Visiting every pair was most of the
  // curvature's time in a warm edit's Newton steps; the sums, in the same order, are the same to
  // the bit.
  thread_local std::vector<int> under, start;
  const int nEntries = static_cast<int>(B_.entries.size());
  under.clear();
  start.assign(nz + 1, 0);
  for (int i = 0; i < nz; ++i) {
    start[i] = static_cast<int>(under.size());
    for (int e = 0; e < nEntries; ++e)
      if (Hz(i, B_.entries[e].row) != 0) under.push_back(e);
  }
  start[nz] = static_cast<int>(under.size());
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(B_.cols, B_.cols);
  for (const SparseMap::Entry& e1 : B_.entries) {
    const int c1 = columns ? (*columns)[e1.col] : 0;
    if (c1 < 0) continue;
    for (int u = start[e1.row]; u < start[e1.row + 1]; ++u) {
      const SparseMap::Entry& e2 = B_.entries[under[u]];
      // The caller's upper triangle is not read: half the pairs skipped, the rest summed as before.
      if (columns && !((*columns)[e2.col] >= 0 && c1 >= (*columns)[e2.col])) continue;
      H(e1.col, e2.col) += e1.value * Hz(e1.row, e2.row) * e2.value;
    }
  }
  return H;
}

std::vector<int> TermResidual::nonlinearColumns() const {
  std::vector<int> cols;
  for (const SparseMap::Entry& e : B_.entries)
    if (e.row < kernel_->nonlinearInputs()) cols.push_back(e.col);
  std::sort(cols.begin(), cols.end());
  cols.erase(std::unique(cols.begin(), cols.end()), cols.end());
  return cols;
}

// The augmented-Lagrangian transform's rule for inequality row r of value g: it is dropped (row
// and Jacobian zero) where g <= 0 when projecting onto the constraints, else where the shifted
// g + lambda/rho <= 0 (N&W eq. 17.65).
bool TermResidual::inequalityDropped(int r, double value) const {
  return (al_->projectOnly ? value : value + al_->lambda[firstMultiplier_ + r] / al_->rho) <= 0;
}

// True if the block's Jacobian is not needed at z, with its rows' final values written to
// `rows`: every row is an inequality, and either the augmented-Lagrangian transform drops each
// (inequalityDropped) or, in raw mode, the caller marked none of them as needed (AugmentedLagrangianState::
// rawNeeded: the Newton polish's inequalities outside its active set) and none exceeds
// rawUnneededBelow (so none joins the active set at this point). Most of a problem's inequality
// blocks are inactive at any iterate (the jump: 22 of 4332 rows active at the optimum), and the
// Jets of their kinematic kernels (every body's ground clearance at every sample and halfway)
// were the largest share of a Jacobian evaluation. The values cost a double evaluation.
bool TermResidual::jacobianUnneeded(const double* z, double* rows) const {
  if (!kernel_->allInequalities()) return false;
  const int m = kernel_->rowCount();
  if (al_->raw) {
    if (al_->rawNeeded.empty()) return false;
    for (int r = 0; r < m; ++r)
      if (al_->rawNeeded[firstMultiplier_ + r]) return false;
  }
  kernel_->evaluate(z, rows);
  for (int r = 0; r < m; ++r) {
    if (!std::isfinite(rows[r])) return false;
    if (al_->raw ? rows[r] > al_->rawUnneededBelow : !inequalityDropped(r, rows[r])) return false;
  }
  if (!al_->raw) std::fill(rows, rows + m, 0.0);
  return true;
}

bool TermResidual::Evaluate(double const* const* parameters, double* residuals,
                            double** jacobians) const {
  // Ceres calls this for every residual block of every iteration from its worker threads: the
  // work vectors are per thread and reused rather than allocated per call.
  thread_local std::vector<double> p, z, Jz, rowScale, scaleTerm;
  const Map mp = map(parameters);
  const int m = kernel_->rowCount(), nz = kernel_->inputSize();
  const SparseMap& B = matrix(mp);
  p.resize(B.cols);
  stackInto(parameters, p.data());
  z.resize(nz);
  B.apply(p.data(), z.data());
  if (jacobians && !moving_ && jacobianUnneeded(z.data(), residuals)) {
    const auto& sizes = parameter_block_sizes();
    for (size_t b = 0; b < sizes.size(); ++b)
      if (jacobians[b]) std::fill(jacobians[b], jacobians[b] + m * sizes[b], 0.0);
    return true;
  }
  Jz.resize(static_cast<size_t>(m) * nz);  // row-major m x nz
  if (jacobians)
    kernel_->evaluateWithJacobian(z.data(), residuals, Jz.data());
  else
    kernel_->evaluate(z.data(), residuals);

  // A moving sample's objective rows: sqrt of the quadrature weight, which changes with T.
  const auto& kinds = kernel_->rowKinds();
  scaleTerm.assign(m, 0.0);  // d(scale)/dT * raw objective row
  if (moving_) {
    for (int r = 0; r < m; ++r)
      if (kinds[r] == RowKind::Objective) {
        scaleTerm[r] = mp.scaleSlope * residuals[r];
        residuals[r] *= mp.scale;
        if (jacobians)
          for (int k = 0; k < nz; ++k) Jz[r * nz + k] *= mp.scale;
      }
  }

  // Augmented-Lagrangian transform of each row: scale and (for inactive inequalities) zero.
  const double sr = std::sqrt(al_->rho);
  rowScale.assign(m, 1.0);
  for (int r = 0; r < m; ++r) {
    if (!std::isfinite(residuals[r])) return false;  // Ceres rejects the step
    if (al_->raw) continue;
    if (al_->projectOnly) {
      const bool zero = kinds[r] == RowKind::Objective ||
                        (kinds[r] == RowKind::Inequality && inequalityDropped(r, residuals[r]));
      if (zero) residuals[r] = 0;
      rowScale[r] = zero ? 0 : 1;
      continue;
    }
    if (kinds[r] == RowKind::Objective) continue;
    const double shift = al_->lambda[firstMultiplier_ + r] / al_->rho;
    const double s = residuals[r] + shift;
    if (kinds[r] == RowKind::Inequality && inequalityDropped(r, residuals[r])) {
      residuals[r] = 0;
      rowScale[r] = 0;
    } else {
      residuals[r] = sr * s;
      rowScale[r] = sr;
    }
  }
  if (!jacobians) return true;
  for (double v : Jz)
    if (!std::isfinite(v)) return false;
  const auto& sizes = parameter_block_sizes();
  const size_t count = sizes.size() - (moving_ ? 1 : 0);
  if (moving_ && jacobians[count]) {  // the event time's column
    Eigen::VectorXd dz(nz);
    mp.slope.apply(p.data(), dz.data());
    for (int r = 0; r < m; ++r) {
      double d = scaleTerm[r];
      for (int k = 0; k < nz; ++k) d += Jz[r * nz + k] * dz[k];
      jacobians[count][r] = rowScale[r] * d;
    }
  }
  // diag(rowScale) Jz B into the blocks, one nonzero of B at a time (rows scaled first).
  for (int r = 0; r < m; ++r)
    if (rowScale[r] != 1)
      for (int k = 0; k < nz; ++k) Jz[r * nz + k] *= rowScale[r];
  for (size_t b = 0; b < count; ++b)
    if (jacobians[b]) std::fill(jacobians[b], jacobians[b] + m * sizes[b], 0.0);
  for (const SparseMap::Entry& e : B.entries) {
    const int b = colBlock_[e.col], width = sizes[b];
    if (!jacobians[b]) continue;
    double* column = jacobians[b] + colIndex_[e.col];
    const double* zc = Jz.data() + e.row;
    for (int r = 0; r < m; ++r) column[r * width] += e.value * zc[r * nz];
  }
  return true;
}

// Evaluate's raw-mode path (rowScale 1) with the chain rule Jz B summed straight into the
// caller's columns, entry by entry in B's order as Evaluate sums each block entry: the block
// Jacobians (every coordinate of every block, most of them zero) were zeroed, filled and copied
// into these columns at every call.
bool TermResidual::rawRowsWithJacobian(double* rows, const int* slot, int width, double* jacobian) const {
  thread_local std::vector<double> p, z, Jz;
  const int m = kernel_->rowCount(), nz = kernel_->inputSize();
  p.resize(B_.cols);
  stackInto(blocks_.data(), p.data());
  z.resize(nz);
  B_.apply(p.data(), z.data());
  std::fill(jacobian, jacobian + static_cast<size_t>(m) * width, 0.0);
  if (jacobianUnneeded(z.data(), rows)) return true;
  Jz.resize(static_cast<size_t>(m) * nz);
  kernel_->rawJacobian(z.data(), rows, Jz.data());
  for (int r = 0; r < m; ++r)
    if (!std::isfinite(rows[r])) return false;
  for (double v : Jz)
    if (!std::isfinite(v)) return false;
  for (const SparseMap::Entry& e : B_.entries) {
    const int s = slot[e.col];
    if (s < 0) continue;
    double* column = jacobian + s;
    const double* zc = Jz.data() + e.row;
    for (int r = 0; r < m; ++r) column[static_cast<size_t>(r) * width] += e.value * zc[static_cast<size_t>(r) * nz];
  }
  return true;
}

}  // namespace spacetime
