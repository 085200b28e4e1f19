// The problem's rows in raw form (before the augmented-Lagrangian transform) for the methods
// that work on them directly: the Newton polish (newton_polish.cpp), the interior-point method
// (interior_point.cpp), the restoration (restoration.cpp), the SQP (sqp.cpp) and the projected
// Newton method (witkin_kass.cpp). Variables lists the parameter blocks that move and the tangent
// column of each coordinate; RawEvaluator evaluates every row with its Jacobian in those
// columns (each term's Ceres cost function, into a pattern built once), and the weighted
// curvature sum_r w_r grad^2 row_r of the kernels.
#pragma once

#include <ceres/ceres.h>

#include <Eigen/SparseCore>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <memory>
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

// J_S^T v for the rows S = `which` of J, v one value per row of S: the product of
// selectRows(J, which) transposed and v, summed in the same order (row by row, as Eigen's sparse
// transpose-times-vector does), so to the bit, without copying the rows.
inline Vec transposeTimes(const SpRow& J, const std::vector<int>& which, const Vec& v) {
  Vec out = Vec::Zero(J.cols());
  for (size_t i = 0; i < which.size(); ++i) {
    const double vi = v[static_cast<Eigen::Index>(i)];
    for (SpRow::InnerIterator e(J, which[i]); e; ++e) out[e.col()] += e.value() * vi;
  }
  return out;
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

// The raw rows' Jacobian pattern and where each term's inputs land in it: term k's rows hold the
// sorted tangent columns its blocks move (width[k] of them); stacked input i of the term lands in
// slot slot[slotStart[k] + i] of each row (-1: a constant coordinate); a block none of whose
// coordinates moves gets no Jacobian (blockMoves, from blockStart[k]); the term's first value in
// the pattern is valueStart[k]. A function of the terms' row counts, block sizes and stacked
// tangent columns alone (`key`), so a problem rebuilt after an edit of a target (the same
// structure) has the same, and its evaluator reuses the last one's, kept with the Newton
// factorisation (NewtonFactors::layout): building it was 70 % of constructing the jump's
// evaluator (7.1 of 10.1 M instructions), which every warm polish pays.
struct RowLayout {
  std::vector<int> key;  // per term: its row count, its block count and sizes, its stacked columns
  std::vector<int> slot, slotStart, width, blockStart, valueStart;
  std::vector<char> blockMoves;
  SpRow pattern;
};

class RawEvaluator {
 public:
  // `reuse`: a layout of an earlier evaluator, taken if this problem's terms give the same key.
  RawEvaluator(SpacetimeProblem& problem, const Variables& vars, int threads,
               const std::shared_ptr<const RowLayout>& reuse = nullptr)
      : problem_(problem), threads_(std::max(1, threads)), tangent_(vars.tangent) {
    std::vector<ceres::ResidualBlockId> ids;
    problem.ceresProblem().GetResidualBlocks(&ids);
    std::vector<int> key;
    for (ceres::ResidualBlockId id : ids) {
      terms_.push_back(dynamic_cast<const TermResidual*>(problem.ceresProblem().GetCostFunctionForResidualBlock(id)));
      parameters_.emplace_back(terms_.back()->blocks().begin(), terms_.back()->blocks().end());
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
      key.push_back(terms_.back()->num_residuals());
      key.push_back(static_cast<int>(terms_.back()->parameter_block_sizes().size()));
      for (int size : terms_.back()->parameter_block_sizes()) key.push_back(size);
      key.insert(key.end(), col.begin(), col.end());
    }
    if (reuse && reuse->key == key && reuse->pattern.cols() == tangent_) {
      layout_ = reuse;
    } else {
      auto built = std::make_shared<RowLayout>();
      built->key = std::move(key);
      buildLayout(built.get());
      layout_ = std::move(built);
    }
  }
  // The row pattern and the terms' slots in it (see RowLayout), for a later evaluator.
  const std::shared_ptr<const RowLayout>& layout() const { return layout_; }
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
  // Each residual's cost function is called directly and its block Jacobians scattered into the
  // row pattern fixed at construction (every tangent column of its blocks, explicit zeros
  // included: the pattern Ceres's Problem::Evaluate gives, whose values these are bit for bit).
  // Problem::Evaluate rebuilt its program, its Jacobian's structure and two copies of it at every
  // call: 38 % of the evaluations' time in a warm SQP solve of the jump.
  bool evaluate(RawRows* out, bool jacobian) {
    AugmentedLagrangianState& al = problem_.augmentedLagrangian();
    al.raw = true;
    al.rawNeeded.swap(needed_);
    al.rawUnneededBelow = neededBelow_;
    out->values.resize(rows());
    if (jacobian && !hasPattern(out->jacobian)) out->jacobian = layout_->pattern;
    double* values = jacobian ? out->jacobian.valuePtr() : nullptr;
    const int parts = std::max(1, std::min<int>(threads_, static_cast<int>(terms_.size())));
    // The threads take runs of consecutive terms as they finish the last (the terms' costs
    // differ: the dynamics' and the clearances' alternate in time) and write their own flag
    // once. Every other term to each thread, each writing its flag (one cache line) at every
    // term, made two threads barely faster than one: the jump's evaluation (LuxoRawRows) took
    // 2.8-3.3 ms on 2 threads against 3.2-4.8 ms on 1; like this 1.6-2.3 ms.
    std::vector<char> ok(parts, 1);
    std::atomic<size_t> next{0};
    auto work = [&](int part) {
      std::vector<double> blockJacobians;
      std::vector<double*> pointers;
      const size_t T = terms_.size();
      bool good = true;
      for (size_t begin = next.fetch_add(kRun); begin < T && good; begin = next.fetch_add(kRun))
        for (size_t k = begin; k < std::min(T, begin + kRun) && good; ++k)
          good = evaluateTerm(k, out->values.data() + firstRow_[k], values, &blockJacobians, &pointers);
      ok[part] = good;
    };
    std::vector<std::thread> pool;
    for (int p = 1; p < parts; ++p) pool.emplace_back(work, p);
    work(0);
    for (std::thread& t : pool) t.join();
    al.rawNeeded.swap(needed_);
    al.raw = false;
    return std::all_of(ok.begin(), ok.end(), [](char c) { return c != 0; }) && out->values.allFinite();
  }

  // The terms a thread of evaluate() or curvature() takes at a time.
  static constexpr size_t kRun = 32;

  // Lower-triangle triplets of sum_rows w[row] grad^2 row, in the tangent columns, at the blocks'
  // current values. Residuals are split over `threads` threads.
  Triplets curvature(const Vec& w, int threads) const {
    std::vector<Triplets> parts(threads);
    auto work = [&](int part) {
      Triplets mine;  // the thread's own until it is done (see evaluate)
      for (size_t k = 0; k < terms_.size(); ++k) {
        if (static_cast<int>(k / kRun % threads) != part) continue;  // runs of terms in turn, in a fixed order
        const TermResidual* term = terms_[k];
        if (term->kernel().nonlinearInputs() == 0) continue;
        // Rows of weight zero (the polish's inequalities outside its active set: most of them)
        // add no curvature; their finite differences of Jacobians were most of its Hessian.
        const double* weights = w.data() + firstRow_[k];
        if (std::all_of(weights, weights + term->num_residuals(), [](double x) { return x == 0; })) continue;
        const std::vector<int>& col = columns_[k];
        const Eigen::MatrixXd H = term->weightedHessianNow(weights, &col);
        for (int i = 0; i < H.rows(); ++i)
          for (int j = 0; j < H.cols(); ++j)
            if (col[i] >= 0 && col[j] >= 0 && col[i] >= col[j] && H(i, j) != 0)
              mine.emplace_back(col[i], col[j], H(i, j));
      }
      parts[part] = std::move(mine);
    };
    std::vector<std::thread> pool;
    for (int p = 1; p < threads; ++p) pool.emplace_back(work, p);
    work(0);
    for (std::thread& t : pool) t.join();
    Triplets all;
    for (const Triplets& p : parts) all.insert(all.end(), p.begin(), p.end());
    return all;
  }

  // Appends the lower triangle of J_r^T J_r, the objective's Gauss-Newton Hessian, for the
  // objective rows of `rows` (evaluated with their Jacobian). A term's rows share its sorted
  // columns, so each row adds the products of its pairs of columns to slots found once, in a
  // pattern built at the first call (every pair of a term's columns, zero or not, as in the
  // product of J's pattern: the factorisations analyse K's pattern once per active set). Rows are
  // added in their order, as Eigen's sparse product J_r^T * J_r sums them, so the values are
  // that product's to the bit; its allocation and merging at every call were 13 % of a warm
  // edit's Newton steps on the jump.
  void appendGaussNewton(const RawRows& rows, Triplets* t) {
    if (gaussNewtonStart_.empty()) buildGaussNewtonPattern();
    double* g = gaussNewton_.valuePtr();
    std::fill(g, g + gaussNewton_.nonZeros(), 0.0);
    for (size_t k = 0; k < terms_.size(); ++k) {
      if (gaussNewtonStart_[k] == gaussNewtonStart_[k + 1]) continue;  // no objective row
      const int m = terms_[k]->num_residuals(), width = layout_->width[k], first = firstRow_[k];
      for (int r = 0; r < m; ++r) {
        if (kind_[first + r] != RowKind::Objective) continue;
        const double* row = rows.jacobian.valuePtr() + layout_->valueStart[k] + static_cast<size_t>(r) * width;
        const int* slot = gaussNewtonSlots_.data() + gaussNewtonStart_[k];
        for (int j = 0; j < width; ++j)
          for (int i = j; i < width; ++i) g[*slot++] += row[i] * row[j];
      }
    }
    for (int j = 0; j < gaussNewton_.outerSize(); ++j)
      for (SpMat::InnerIterator e(gaussNewton_, j); e; ++e)
        t->emplace_back(static_cast<int>(e.row()), j, e.value());
  }

 private:
  // RowLayout's arrays and pattern from the terms. Flat arrays, the pattern sized once and
  // written in place, the slots read from a table: with a row-by-row append, a copy of the result
  // and a binary search per input the jump's evaluator took 2.6 ms to construct, 2.0 ms like this.
  void buildLayout(RowLayout* L) const {
    std::vector<std::vector<int>> termColumns(terms_.size());
    std::vector<int> slotOf(static_cast<size_t>(tangent_), -1);  // a column's slot in the current term
    size_t nonzeros = 0;
    for (size_t k = 0; k < terms_.size(); ++k) {
      const std::vector<int>& stacked = columns_[k];
      std::vector<int>& cols = termColumns[k];
      for (int c : stacked)
        if (c >= 0) cols.push_back(c);
      std::sort(cols.begin(), cols.end());
      cols.erase(std::unique(cols.begin(), cols.end()), cols.end());
      L->slotStart.push_back(static_cast<int>(L->slot.size()));
      for (size_t i = 0; i < cols.size(); ++i) slotOf[static_cast<size_t>(cols[i])] = static_cast<int>(i);
      for (int c : stacked) L->slot.push_back(c < 0 ? -1 : slotOf[static_cast<size_t>(c)]);
      L->blockStart.push_back(static_cast<int>(L->blockMoves.size()));
      auto input = stacked.begin();
      for (int size : terms_[k]->parameter_block_sizes()) {
        L->blockMoves.push_back(std::any_of(input, input + size, [](int c) { return c >= 0; }));
        input += size;
      }
      L->width.push_back(static_cast<int>(cols.size()));
      L->valueStart.push_back(static_cast<int>(nonzeros));
      nonzeros += static_cast<size_t>(terms_[k]->num_residuals()) * cols.size();
    }
    SpRow& pattern = L->pattern;
    pattern.resize(rows(), tangent_);
    pattern.resizeNonZeros(static_cast<Eigen::Index>(nonzeros));
    int* outer = pattern.outerIndexPtr();
    int* inner = pattern.innerIndexPtr();
    int row = 0, at = 0;
    outer[0] = 0;
    for (size_t k = 0; k < terms_.size(); ++k) {
      const std::vector<int>& cols = termColumns[k];
      for (int r = 0; r < terms_[k]->num_residuals(); ++r) {
        inner = std::copy(cols.begin(), cols.end(), inner);
        at += static_cast<int>(cols.size());
        outer[++row] = at;
      }
    }
    std::fill(pattern.valuePtr(), pattern.valuePtr() + nonzeros, 0.0);
  }
  bool hasPattern(const SpRow& J) const {
    return J.rows() == layout_->pattern.rows() && J.cols() == layout_->pattern.cols() && J.isCompressed() &&
           J.nonZeros() == layout_->pattern.nonZeros() &&
           std::equal(J.outerIndexPtr(), J.outerIndexPtr() + J.rows() + 1, layout_->pattern.outerIndexPtr()) &&
           std::equal(J.innerIndexPtr(), J.innerIndexPtr() + J.nonZeros(), layout_->pattern.innerIndexPtr());
  }
  // Term k's rows into rows, and with `values` its Jacobian into its slots of the pattern: straight
  // from the kernel's Jacobian (TermResidual::rawRowsWithJacobian), or for a moving residual
  // through its cost function's block Jacobians.
  bool evaluateTerm(size_t k, double* rows, double* values, std::vector<double>* blockJacobians,
                    std::vector<double*>* pointers) const {
    const TermResidual& term = *terms_[k];
    const std::vector<int32_t>& sizes = term.parameter_block_sizes();
    const int m = term.num_residuals();
    if (!values) return term.Evaluate(parameters_[k].data(), rows, nullptr);
    if (!term.moving()) return term.rawRowsWithJacobian(rows, layout_->slot.data() + layout_->slotStart[k], layout_->width[k], values + layout_->valueStart[k]);
    size_t total = 0;
    for (int size : sizes) total += static_cast<size_t>(m) * size;
    blockJacobians->resize(total);
    pointers->assign(sizes.size(), nullptr);
    size_t at = 0;
    for (size_t b = 0; b < sizes.size(); ++b) {
      if (layout_->blockMoves[layout_->blockStart[k] + b]) (*pointers)[b] = blockJacobians->data() + at;
      at += static_cast<size_t>(m) * sizes[b];
    }
    if (!term.Evaluate(parameters_[k].data(), rows, pointers->data())) return false;
    const int width = layout_->width[k];
    double* row = values + layout_->valueStart[k];
    std::fill(row, row + static_cast<size_t>(m) * width, 0.0);
    const int* slot = layout_->slot.data() + layout_->slotStart[k];
    size_t input = 0;
    for (size_t b = 0; b < sizes.size(); ++b) {
      const double* J = (*pointers)[b];
      for (int a = 0; a < sizes[b]; ++a, ++input) {
        if (!J || slot[input] < 0) continue;
        for (int r = 0; r < m; ++r) row[static_cast<size_t>(r) * width + slot[input]] += J[r * sizes[b] + a];
      }
    }
    return true;
  }

  // The lower triangle of J_r^T J_r's pattern and, per term with objective rows, the slot of
  // each pair (i >= j) of its columns in it, column by column (appendGaussNewton's order).
  void buildGaussNewtonPattern() {
    Triplets pairs;
    gaussNewtonStart_.assign(terms_.size() + 1, 0);
    auto objectiveTerm = [&](size_t k) {
      for (int r = 0; r < terms_[k]->num_residuals(); ++r)
        if (kind_[firstRow_[k] + r] == RowKind::Objective) return layout_->width[k] > 0;
      return false;
    };
    auto columnsOf = [&](size_t k) { return layout_->pattern.innerIndexPtr() + layout_->valueStart[k]; };
    for (size_t k = 0; k < terms_.size(); ++k)
      if (objectiveTerm(k))
        for (int j = 0; j < layout_->width[k]; ++j)
          for (int i = j; i < layout_->width[k]; ++i) pairs.emplace_back(columnsOf(k)[i], columnsOf(k)[j], 0.0);
    gaussNewton_.resize(tangent_, tangent_);
    gaussNewton_.setFromTriplets(pairs.begin(), pairs.end());
    gaussNewton_.makeCompressed();
    for (size_t k = 0; k < terms_.size(); ++k) {
      gaussNewtonStart_[k] = static_cast<int>(gaussNewtonSlots_.size());
      if (!objectiveTerm(k)) continue;
      for (int j = 0; j < layout_->width[k]; ++j) {
        const int col = columnsOf(k)[j];
        const int* begin = gaussNewton_.innerIndexPtr() + gaussNewton_.outerIndexPtr()[col];
        const int* end = gaussNewton_.innerIndexPtr() + gaussNewton_.outerIndexPtr()[col + 1];
        for (int i = j; i < layout_->width[k]; ++i)
          gaussNewtonSlots_.push_back(static_cast<int>(std::lower_bound(begin, end, columnsOf(k)[i]) -
                                                       gaussNewton_.innerIndexPtr()));
      }
    }
    gaussNewtonStart_[terms_.size()] = static_cast<int>(gaussNewtonSlots_.size());
  }

  SpacetimeProblem& problem_;
  int threads_ = 1;
  int tangent_ = 0;
  std::vector<std::vector<const double*>> parameters_;  // each term's parameter blocks, in its order
  std::shared_ptr<const RowLayout> layout_;  // the row pattern and the terms' slots in it
  std::vector<char> needed_;  // per multiplier row (limitJacobians); empty: every row
  double neededBelow_ = 0;
  std::vector<const TermResidual*> terms_;
  std::vector<int> firstRow_;
  std::vector<std::vector<int>> columns_;  // each term's tangent column per stacked input (-1: constant)
  std::vector<RowKind> kind_;
  std::vector<int> multiplier_;
  SpMat gaussNewton_;                                   // appendGaussNewton's sum, lower triangle
  std::vector<int> gaussNewtonSlots_, gaussNewtonStart_;  // per term: its pairs' slots in it
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
