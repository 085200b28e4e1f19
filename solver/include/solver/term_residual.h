// TermResidual: a kernel made into a Ceres residual block of the augmented Lagrangian.
//
// The kernel's input z is a constant linear map B of the parameter blocks it touches (spline
// basis weights of the sample's time, identity for anchors and force control points), so its
// Jacobian with respect to the parameters is exactly J_z B. Rows are transformed by kind
// (Powell-Hestenes-Rockafellar augmented Lagrangian, Nocedal & Wright eq. 17.65 for
// inequalities): objective rows pass through; an equality c becomes sqrt(rho) (c + lambda/rho);
// an inequality g <= 0 becomes sqrt(rho) max(0, g + lambda/rho). Half the sum of squares is
// then f + lambda.c + rho/2 |c|^2 up to a constant, which Ceres minimises.
//
// A residual near a free contact end (a lift-off instant the solver chooses, see
// spacetime_problem.h) has times that move with that instant T: its map B(T) is rebuilt at every
// evaluation from T, with its slope B'(T), and T is one more parameter block; the column of T
// is J_z B'(T) p (plus the change of the quadrature weight of objective rows), so the chain
// rule stays exact.
#pragma once

#include <ceres/cost_function.h>

#include <Eigen/Core>
#include <functional>
#include <memory>
#include <vector>

#include "solver/kernels.h"

namespace spacetime {

struct NewtonFactors;  // solver/src/chord_steps.h

// Penalty and multipliers shared by all residuals of one problem.
struct AugmentedLagrangianState {
  double rho = 10;
  // Feasibility projection mode: objective rows vanish, equalities are c and inequalities
  // max(0, g), so minimising the sum of squares is a Gauss-Newton solve of c(x) = 0 (the
  // constraint step of Witkin & Kass 1988), which converges quadratically near the manifold.
  bool projectOnly = false;
  // Raw mode (the Newton polish, newton_polish.h): every row passes through untouched, so the Jacobian
  // Ceres evaluates is that of the objective, equality and inequality rows themselves.
  bool raw = false;
  // Raw mode, when not empty: the rows whose Jacobian the caller needs (one per multiplier; the
  // Newton polish's objective rows, equalities and held inequalities). A block of inequalities
  // none of which is needed nor above rawUnneededBelow gets its rows and a zero Jacobian.
  std::vector<char> rawNeeded;
  double rawUnneededBelow = 0;
  std::vector<double> lambda;  // one per row of every residual (objective rows unused)
  // The Newton polish's KKT factorisation where it last ended at a KKT point with these
  // multipliers (solver/src/chord_steps.h): a warm start after an edit steps on it. Null when
  // none; it travels with the multipliers in SolutionState.
  std::shared_ptr<const NewtonFactors> newtonFactors;
};

// A sparse linear map z = B p, kept as its nonzeros: each input is a few spline basis weights
// of one degree of freedom (or a single force or anchor), so B is mostly zeros, and products
// through it as dense matrices (Eigen's GEMM on 6 x 22 times 22 x 30) cost more than the
// kernels' own arithmetic.
struct SparseMap {
  struct Entry {
    int row, col;
    double value;
  };
  int rows = 0, cols = 0;
  std::vector<Entry> entries;  // duplicates add up
  // z = B p (z has `rows` entries, p has `cols`).
  void apply(const double* p, double* z) const;
};

// Builds the input map of one residual: which parameter blocks, and B.
class InputMap {
 public:
  // Adds a parameter block (deduplicated) and returns its index.
  int block(double* data, int size);
  // z[zRow] += weight * block[b][index]; `slope` is d weight / dT for a map that moves with an
  // event time T (zero otherwise).
  void add(int zRow, int blockIndex, int index, double weight, double slope = 0);
  // Appends `count` new z rows and returns the first.
  int newRows(int count);

  int rows() const { return rows_; }
  const std::vector<double*>& blocks() const { return blocks_; }
  const std::vector<int>& sizes() const { return sizes_; }
  SparseMap matrix() const;
  SparseMap slopeMatrix() const;

  // Objective rows are scaled by this factor (and its slope in T): a moving sample's quadrature
  // weight changes with the length of its interval, and objective rows carry sqrt(weight).
  double objectiveScale = 1, objectiveScaleSlope = 0;

 private:
  struct Entry {
    int row, block, index;
    double weight, slope;
  };
  SparseMap assemble(double Entry::*field) const;  // B from one of the entries' fields
  std::vector<double*> blocks_;
  std::vector<int> sizes_;
  std::vector<Entry> entries_;
  int rows_ = 0;
};

// Rebuilds a moving residual's input map at the event time T. It must register the same
// parameter blocks in the same order at every T.
using MovingInputs = std::function<InputMap(double T)>;

class TermResidual : public ceres::CostFunction {
 public:
  TermResidual(std::shared_ptr<const Kernel> kernel, const InputMap& inputs,
               const AugmentedLagrangianState* al, int firstMultiplier);
  // A residual whose times move with the event time held in *eventTime (the last parameter
  // block, of size 1).
  TermResidual(std::shared_ptr<const Kernel> kernel, MovingInputs moving, double* eventTime,
               const AugmentedLagrangianState* al, int firstMultiplier);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

  // The kernel's raw rows at the given parameters (before the augmented-Lagrangian transform).
  void rawRows(double const* const* parameters, double* rows) const;
  // The raw rows at the parameters' current values with their Jacobian written straight into
  // `jacobian`, row-major m x width: stacked input i (the blocks' coordinates in order) into
  // column slot[i], none where slot[i] < 0. The values Evaluate gives in raw mode (its block
  // Jacobians scattered into those columns), to the bit, without the blocks: for the raw rows'
  // evaluator (solver/src/raw_rows.h), which sets AugmentedLagrangianState::raw around it. Not
  // for moving residuals. False if a row or a derivative is not finite.
  bool rawRowsWithJacobian(double* rows, const int* slot, int width, double* jacobian) const;
  // The same at the parameters' current values.
  std::vector<double> rawRowsNow() const;
  // The kernel's inputs z = B p at the parameters' current values.
  Eigen::VectorXd inputsNow() const;
  // B^T H_z B at the parameters' current values: the Hessian, in the stacked parameter blocks,
  // of sum_r w[r] raw row r (Kernel::weightedHessian). Not for moving residuals. With `columns`
  // (each stacked input's column in the caller's matrix, -1: none) only the entries (i, j) with
  // columns[i] >= columns[j] >= 0 are computed, the lower triangle the callers keep; the others
  // are left zero.
  Eigen::MatrixXd weightedHessianNow(const double* w, const std::vector<int>* columns = nullptr) const;
  // The stacked parameter columns the kernel's nonlinear inputs read, sorted: where
  // weightedHessianNow can be nonzero (rows and columns).
  std::vector<int> nonlinearColumns() const;

  const Kernel& kernel() const { return *kernel_; }
  const std::vector<double*>& blocks() const { return blocks_; }
  int firstMultiplier() const { return firstMultiplier_; }
  bool moving() const { return static_cast<bool>(moving_); }

 private:
  // The map at the given parameters: B, its slope in T, the objective rows' scale and slope.
  struct Map {
    SparseMap moved, slope;  // B(T) and B'(T) of a moving residual
    double scale = 1, scaleSlope = 0;
  };
  // B: the constant map, or a moving residual's B(T).
  const SparseMap& matrix(const Map& m) const { return moving_ ? m.moved : B_; }
  Map map(double const* const* parameters) const;
  Eigen::VectorXd inputs(const Map& m, double const* const* parameters) const;  // z = B p
  Eigen::VectorXd stacked(double const* const* parameters) const;  // p: the blocks but T
  void stackInto(double const* const* parameters, double* p) const;  // the same into p
  // The block's Jacobian is zero or not needed at z (its final rows written to rows).
  bool jacobianUnneeded(const double* z, double* rows) const;
  bool inequalityDropped(int r, double value) const;  // the transform zeroes inequality row r
  void indexColumns(const std::vector<int>& sizes);  // fills colBlock_, colIndex_
  // Scales the objective rows of raw kernel rows.
  void scaleObjective(double scale, double* rows) const;

  std::shared_ptr<const Kernel> kernel_;
  MovingInputs moving_;
  SparseMap B_;
  // Column c of B is entry colIndex_[c] of parameter block colBlock_[c].
  std::vector<int> colBlock_, colIndex_;
  std::vector<double*> blocks_;
  const AugmentedLagrangianState* al_;
  int firstMultiplier_;
};

}  // namespace spacetime
