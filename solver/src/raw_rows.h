// The problem's rows in raw form (before the augmented-Lagrangian transform) for the methods
// that work on them directly: the Newton polish (newton_polish.cpp), the interior-point method
// (interior_point.cpp), the restoration (restoration.cpp), the SQP (sqp.cpp) and the projected
// Newton method (witkin_kass.cpp). Variables lists the parameter blocks that move and the tangent
// column of each coordinate; RawEvaluator evaluates every row with its Jacobian in those
// columns through Ceres, and the weighted curvature sum_r w_r grad^2 row_r of the kernels.
#pragma once

#include <ceres/ceres.h>

#include <Eigen/SparseCore>
#include <algorithm>
#include <chrono>
#include <thread>
#include <unordered_map>
#include <vector>

#include "solver/spacetime_problem.h"

namespace spacetime::raw {

using Clock = std::chrono::steady_clock;
using SpMat = Eigen::SparseMatrix<double>;
using SpRow = Eigen::SparseMatrix<double, Eigen::RowMajor>;
using Vec = Eigen::VectorXd;
using Triplets = std::vector<Eigen::Triplet<double>>;

inline double secondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// The entries `which` of v, in that order.
inline Vec selectValues(const Vec& v, const std::vector<int>& which) {
  Vec out(static_cast<Eigen::Index>(which.size()));
  for (size_t i = 0; i < which.size(); ++i) out[static_cast<Eigen::Index>(i)] = v[which[i]];
  return out;
}

// The rows `which` of J, in that order, keeping J's pattern (explicit zeros included).
inline SpRow selectRows(const SpRow& J, const std::vector<int>& which) {
  Eigen::Index nonzeros = 0;
  for (int row : which) nonzeros += J.outerIndexPtr()[row + 1] - J.outerIndexPtr()[row];
  SpRow S(static_cast<Eigen::Index>(which.size()), J.cols());
  S.reserve(nonzeros);
  for (size_t i = 0; i < which.size(); ++i) {
    S.startVec(static_cast<Eigen::Index>(i));
    for (SpRow::InnerIterator e(J, which[i]); e; ++e) S.insertBack(static_cast<Eigen::Index>(i), e.col()) = e.value();
  }
  S.finalize();
  return S;
}

// The parameter blocks that may move, in the order of the Jacobian's columns (Ceres's
// Problem::Evaluate with these blocks), and the column of each of their coordinates. Held
// stances keep some coordinates constant through a SubsetManifold: those have no column.
struct Variables {
  std::vector<double*> blocks;
  std::vector<int> sizes;
  std::vector<const ceres::Manifold*> manifolds;
  std::unordered_map<const double*, std::vector<int>> columns;  // -1: constant
  int tangent = 0;

  explicit Variables(const ceres::Problem& problem) {
    std::vector<double*> all;
    problem.GetParameterBlocks(&all);
    for (double* b : all) {
      const int size = problem.ParameterBlockSize(b);
      std::vector<int>& col = columns[b];
      col.assign(size, -1);
      if (problem.IsParameterBlockConstant(b)) continue;
      blocks.push_back(b);
      sizes.push_back(size);
      const ceres::Manifold* manifold = problem.GetManifold(b);
      manifolds.push_back(manifold);
      if (!manifold) {
        for (int a = 0; a < size; ++a) col[a] = tangent + a;
        tangent += size;
        continue;
      }
      // A SubsetManifold's Plus Jacobian is a selection: one 1 per moving coordinate.
      const int ts = manifold->TangentSize();
      std::vector<double> J(size * ts);
      manifold->PlusJacobian(b, J.data());
      for (int a = 0; a < size; ++a)
        for (int t = 0; t < ts; ++t)
          if (J[a * ts + t] != 0) col[a] = tangent + t;
      tangent += ts;
    }
  }
  std::vector<double> save() const {
    std::vector<double> v;
    for (size_t i = 0; i < blocks.size(); ++i) v.insert(v.end(), blocks[i], blocks[i] + sizes[i]);
    return v;
  }
  void load(const std::vector<double>& v) const {
    size_t k = 0;
    for (size_t i = 0; i < blocks.size(); ++i) {
      std::copy(v.begin() + k, v.begin() + k + sizes[i], blocks[i]);
      k += sizes[i];
    }
  }
  // blocks = from (+) step, through each block's manifold.
  void plus(const std::vector<double>& from, const Vec& step) const {
    size_t k = 0;
    int t = 0;
    for (size_t i = 0; i < blocks.size(); ++i) {
      if (manifolds[i]) {
        manifolds[i]->Plus(from.data() + k, step.data() + t, blocks[i]);
        t += manifolds[i]->TangentSize();
      } else {
        for (int j = 0; j < sizes[i]; ++j) blocks[i][j] = from[k + j] + step[t + j];
        t += sizes[i];
      }
      k += sizes[i];
    }
  }
};

// Every row of every residual in raw form, with its Jacobian in the tangent columns.
struct RawRows {
  Vec values;
  SpRow jacobian;
};

class RawEvaluator {
 public:
  RawEvaluator(SpacetimeProblem& problem, const Variables& vars, int threads) : problem_(problem) {
    options_.parameter_blocks = vars.blocks;
    options_.num_threads = threads;
    problem.ceresProblem().GetResidualBlocks(&options_.residual_blocks);
    for (ceres::ResidualBlockId id : options_.residual_blocks) {
      terms_.push_back(dynamic_cast<const TermResidual*>(problem.ceresProblem().GetCostFunctionForResidualBlock(id)));
      firstRow_.push_back(static_cast<int>(kind_.size()));
      const auto& kinds = terms_.back()->kernel().rowKinds();
      for (size_t i = 0; i < kinds.size(); ++i) {
        kind_.push_back(kinds[i]);
        multiplier_.push_back(terms_.back()->firstMultiplier() + static_cast<int>(i));
      }
      std::vector<int>& col = columns_.emplace_back();
      for (const double* b : terms_.back()->blocks()) {
        const std::vector<int>& c = vars.columns.at(b);
        col.insert(col.end(), c.begin(), c.end());
      }
    }
  }
  int rows() const { return static_cast<int>(kind_.size()); }
  RowKind kind(int row) const { return kind_[row]; }
  int multiplier(int row) const { return multiplier_[row]; }
  // The residuals in Ceres's order, the first row of each, and each one's tangent column per
  // stacked input of its parameter blocks (-1: constant).
  const std::vector<const TermResidual*>& terms() const { return terms_; }
  int firstRow(size_t term) const { return firstRow_[term]; }
  const std::vector<int>& columns(size_t term) const { return columns_[term]; }
  bool anyMoving() const {
    return std::any_of(terms_.begin(), terms_.end(), [](const TermResidual* t) { return !t || t->moving(); });
  }

  // From now on, the Jacobian rows evaluate() must compute: those `needed` (one per row) and any
  // row above `below`; blocks of inequalities with neither get zero rows, without their Jets
  // (TermResidual::jacobianUnneeded). Until called, every row's.
  void limitJacobians(const std::vector<char>& needed, double below) {
    needed_.assign(problem_.augmentedLagrangian().lambda.size(), 1);
    for (int r = 0; r < rows(); ++r) needed_[multiplier_[r]] = needed[r];
    neededBelow_ = below;
  }

  // Rows (and their Jacobian if asked) at the blocks' current values; false if not finite.
  bool evaluate(RawRows* out, bool jacobian) {
    AugmentedLagrangianState& al = problem_.augmentedLagrangian();
    al.raw = true;
    al.rawNeeded.swap(needed_);
    al.rawUnneededBelow = neededBelow_;
    std::vector<double> values;
    double cost = 0;
    ceres::CRSMatrix J;
    const bool ok = problem_.ceresProblem().Evaluate(options_, &cost, &values, nullptr, jacobian ? &J : nullptr);
    al.rawNeeded.swap(needed_);
    al.raw = false;
    if (!ok) return false;
    out->values = Eigen::Map<const Vec>(values.data(), static_cast<Eigen::Index>(values.size()));
    if (!out->values.allFinite()) return false;
    if (jacobian) {
      // Ceres's CRS arrays are Eigen's compressed row storage; copied as they are unless a row's
      // columns are out of order (Eigen's algorithms expect them sorted).
      const Eigen::Map<const SpRow> crs(J.num_rows, J.num_cols, static_cast<Eigen::Index>(J.values.size()),
                                        J.rows.data(), J.cols.data(), J.values.data());
      bool sorted = true;
      for (int r = 0; r < J.num_rows && sorted; ++r)
        sorted = std::is_sorted(J.cols.begin() + J.rows[r], J.cols.begin() + J.rows[r + 1]);
      out->jacobian = sorted ? SpRow(crs) : SpRow(SpMat(crs));  // via column-major: sorted
    }
    return true;
  }

  // Lower-triangle triplets of sum_rows w[row] grad^2 row, in the tangent columns, at the blocks'
  // current values. Residuals are split over `threads` threads.
  Triplets curvature(const Vec& w, int threads) const {
    std::vector<Triplets> parts(threads);
    auto work = [&](int part) {
      for (size_t k = part; k < terms_.size(); k += threads) {
        const TermResidual* term = terms_[k];
        if (term->kernel().nonlinearInputs() == 0) continue;
        // Rows of weight zero (the polish's inequalities outside its active set: most of them)
        // add no curvature; their finite differences of Jacobians were most of its Hessian.
        const double* weights = w.data() + firstRow_[k];
        if (std::all_of(weights, weights + term->num_residuals(), [](double x) { return x == 0; })) continue;
        const Eigen::MatrixXd H = term->weightedHessianNow(weights);
        const std::vector<int>& col = columns_[k];
        for (int i = 0; i < H.rows(); ++i)
          for (int j = 0; j < H.cols(); ++j)
            if (col[i] >= 0 && col[j] >= 0 && col[i] >= col[j] && H(i, j) != 0)
              parts[part].emplace_back(col[i], col[j], H(i, j));
      }
    };
    std::vector<std::thread> pool;
    for (int p = 1; p < threads; ++p) pool.emplace_back(work, p);
    work(0);
    for (std::thread& t : pool) t.join();
    Triplets all;
    for (const Triplets& p : parts) all.insert(all.end(), p.begin(), p.end());
    return all;
  }

 private:
  SpacetimeProblem& problem_;
  ceres::Problem::EvaluateOptions options_;
  std::vector<char> needed_;  // per multiplier row (limitJacobians); empty: every row
  double neededBelow_ = 0;
  std::vector<const TermResidual*> terms_;
  std::vector<int> firstRow_;
  std::vector<std::vector<int>> columns_;  // each term's tangent column per stacked input (-1: constant)
  std::vector<RowKind> kind_;
  std::vector<int> multiplier_;
};

// The evaluator's rows by kind, each in Ceres's order.
struct RowKinds {
  std::vector<int> objective, equality, inequality;
  explicit RowKinds(const RawEvaluator& evaluator) {
    for (int r = 0; r < evaluator.rows(); ++r)
      (evaluator.kind(r) == RowKind::Objective ? objective : evaluator.kind(r) == RowKind::Equality ? equality : inequality)
          .push_back(r);
  }
};

}  // namespace spacetime::raw
