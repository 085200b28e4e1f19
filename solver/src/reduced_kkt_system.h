// The linear algebra the quadratic program solvers share (quadratic_program.h): K's pattern for
// a family of programs, kept in a QpWorkspace between them, and the reduced KKT system
//     [ H + C^T W C + shift M + dx I    A^T  ]
//     [ A                              -dy I ]
// for inequality weights W (an interior point's z / s, or the active-set steps' weight on their
// start rows) with its LDL^T and solves.
#pragma once

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <unordered_map>
#include <vector>

#include "solver/quadratic_program.h"
#include "supernodal_ldlt.h"

namespace spacetime {
namespace qp {

using SpMat = Eigen::SparseMatrix<double>;
using SpRow = Eigen::SparseMatrix<double, Eigen::RowMajor>;
using Vec = Eigen::VectorXd;

inline double infNorm(const Vec& v) { return v.size() ? v.lpNorm<Eigen::Infinity>() : 0.0; }

}  // namespace qp

// K in a pattern fixed for a family of programs, already permuted by a fill-reducing ordering
// (so each factorisation reads K as stored instead of permuting a copy),
// the slot in K's values of every entry the current program's matrices scatter into, and the
// LDL^T's symbolic analysis. The SQP-type methods solve many programs on one problem whose
// inequality rows come and go (the rows held near activity, the rows a step crosses); their
// entries mostly fall inside a pattern already built, so a new program only looks up its slots,
// and a program that needs new entries rebuilds the pattern with the old ones kept, so the
// pattern grows to cover the family after a few rebuilds (a pattern per row set would be
// rebuilt for 40 of the jump's 75 sqp programs).
struct QpWorkspace::Pattern {
  using SpMat = qp::SpMat;
  using SpRow = qp::SpRow;
  using Vec = qp::Vec;

  std::vector<int> signature;  // patternOf the last program whose slots are assigned
  int n = 0, me = 0;
  Eigen::VectorXi position;  // position[i]: where K's row and column i sit in the permuted K
  SpMat K;                   // the upper triangle of the permuted K, column-major
  std::vector<int> hessianSlots, equalitySlots, diagonal, dualDiagonal;
  // C^T (Z/S) C by runs of consecutive inequality rows on the same columns (a sample's rows):
  // a run's pairs of columns are summed densely over its rows, then added to K once. Columns
  // that only one row touches (an elastic program's slack of a violated row) are left out of
  // the run's columns; their pairs are added row by row.
  struct Run {
    int rowBegin, rowEnd, width, slotsBegin;  // rows [rowBegin, rowEnd); `width` shared columns
  };
  std::vector<Run> runs;
  std::vector<int> runSlots;                   // each run's width (width + 1) / 2 pair slots
  std::vector<char> privateColumn;             // per column of C: touched by one row only
  std::vector<int> privateSlots, rowPrivate;   // per row: the slots of its pairs with such a column
  // The layouts (outer and inner indices) hessianSlots and equalitySlots were looked up for, and
  // the pair slots of each run's shared columns.
  std::vector<int> hessianLayout, equalityLayout;
  struct ColumnsHash {
    size_t operator()(const std::vector<int>& v) const {
      size_t h = 1469598103934665603ull;  // FNV-1a over the indices
      for (int i : v) h = (h ^ static_cast<size_t>(static_cast<unsigned>(i))) * 1099511628211ull;
      return h;
    }
  };
  std::unordered_map<std::vector<int>, std::vector<int>, ColumnsHash> rowSlots;
  qp::SupernodalLdlt ldlt;

  // A pattern holding every entry `qp` scatters into and every entry of `previous`.
  Pattern(const QuadraticProgram& qp, const Pattern* previous) {
    n = static_cast<int>(qp.gradient.size());
    me = static_cast<int>(qp.equalities.rows());
    std::vector<Eigen::Triplet<double>> entries;  // lower triangle, unpermuted
    forEachEntry(qp, [&](int row, int col) { entries.emplace_back(row, col, 1.0); });
    if (previous)
      for (int k = 0; k < previous->K.outerSize(); ++k)
        for (SpMat::InnerIterator e(previous->K, k); e; ++e) {
          const int a = previous->original[e.row()], b = previous->original[e.col()];
          entries.emplace_back(std::max(a, b), std::min(a, b), 1.0);
        }
    const int size = n + me;
    SpMat lower(size, size);
    lower.setFromTriplets(entries.begin(), entries.end());
    // The ordering of the full symmetric pattern (AMD, as SimplicialLDLT would choose).
    const SpMat full = lower.selfadjointView<Eigen::Lower>();
    Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> inverse;
    Eigen::AMDOrdering<int>()(full, inverse);
    original = inverse.indices();  // original[p]: K's index at permuted position p
    position.resize(size);
    for (int p = 0; p < size; ++p) position[original[p]] = p;
    std::vector<Eigen::Triplet<double>> permuted;
    permuted.reserve(lower.nonZeros());
    for (int k = 0; k < lower.outerSize(); ++k)
      for (SpMat::InnerIterator e(lower, k); e; ++e) {
        const int a = position[static_cast<int>(e.row())], b = position[static_cast<int>(e.col())];
        permuted.emplace_back(std::min(a, b), std::max(a, b), 0.0);
      }
    K.resize(size, size);
    K.setFromTriplets(permuted.begin(), permuted.end());
    K.makeCompressed();
    ldlt.analyzePattern(K);
  }

  // Looks up the slot of every entry `qp` scatters into; false if one is not in the pattern.
  // H's and A's slots are kept while their patterns repeat (an SQP's programs of one kind share
  // them), and a run's pairs depend only on its shared columns, which recur between programs:
  // they are looked up once per column list. Looking up every entry took 4 ms of
  // each of the jump's programs (docs/design.md, Solver item 6).
  bool assignSlots(const QuadraticProgram& qp) {
    if (static_cast<int>(qp.gradient.size()) != n || static_cast<int>(qp.equalities.rows()) != me) return false;
    if (diagonal.empty())
      for (int i = 0; i < n + me; ++i) (i < n ? diagonal : dualDiagonal).push_back(slot(i, i));
    if (!sameLayout(qp.hessian, &hessianLayout)) {
      hessianSlots.clear();
      for (int k = 0; k < qp.hessian.outerSize(); ++k)
        for (SpMat::InnerIterator e(qp.hessian, k); e; ++e)
          if (e.row() >= e.col()) hessianSlots.push_back(slot(static_cast<int>(e.row()), static_cast<int>(e.col())));
    }
    if (!sameLayout(qp.equalities, &equalityLayout)) {
      equalitySlots.clear();
      for (int k = 0; k < qp.equalities.outerSize(); ++k)
        for (SpRow::InnerIterator e(qp.equalities, k); e; ++e) equalitySlots.push_back(slot(n + k, static_cast<int>(e.col())));
    }
    const SpRow& C = qp.inequalities;
    privateColumn.assign(static_cast<size_t>(n), 0);
    {
      std::vector<int> rowsOf(static_cast<size_t>(n), 0);
      for (int k = 0; k < C.nonZeros(); ++k) ++rowsOf[static_cast<size_t>(C.innerIndexPtr()[k])];
      for (int c = 0; c < n; ++c) privateColumn[static_cast<size_t>(c)] = rowsOf[static_cast<size_t>(c)] == 1;
    }
    runs.clear(), runSlots.clear(), privateSlots.clear(), rowPrivate.assign(1, 0);
    std::vector<int> columns, shared, runColumns;  // runColumns: the shared columns of the last run
    for (int i = 0; i < C.outerSize(); ++i) {
      columns.assign(C.innerIndexPtr() + C.outerIndexPtr()[i], C.innerIndexPtr() + C.outerIndexPtr()[i + 1]);
      shared.clear();
      for (int c : columns)
        if (!privateColumn[static_cast<size_t>(c)]) shared.push_back(c);
      if (runs.empty() || !std::equal(shared.begin(), shared.end(), runColumns.begin(), runColumns.end())) {
        auto cached = rowSlots.find(shared);
        if (cached == rowSlots.end()) {
          std::vector<int> slots;
          for (size_t a = 0; a < shared.size(); ++a)
            for (size_t b = 0; b <= a; ++b) slots.push_back(slot(shared[a], shared[b]));
          cached = rowSlots.emplace(shared, std::move(slots)).first;
        }
        runs.push_back({i, i, static_cast<int>(shared.size()), static_cast<int>(runSlots.size())});
        runSlots.insert(runSlots.end(), cached->second.begin(), cached->second.end());
        runColumns = shared;
      }
      runs.back().rowEnd = i + 1;
      for (size_t a = 0; a < columns.size(); ++a)
        for (size_t b = 0; b <= a; ++b)
          if (privateColumn[static_cast<size_t>(columns[a])] || privateColumn[static_cast<size_t>(columns[b])])
            privateSlots.push_back(slot(columns[a], columns[b]));
      rowPrivate.push_back(static_cast<int>(privateSlots.size()));
    }
    for (const auto* slots : {&hessianSlots, &equalitySlots, &diagonal, &dualDiagonal, &runSlots, &privateSlots})
      if (std::find(slots->begin(), slots->end(), -1) != slots->end()) {
        hessianLayout.clear(), equalityLayout.clear();  // looked up again on the next program
        return false;
      }
    return true;
  }

  // Whether m's outer and inner indices are those in `layout`; if not, `layout` takes them.
  template <typename Matrix>
  static bool sameLayout(const Matrix& m, std::vector<int>* layout) {
    const int outer = static_cast<int>(m.outerSize()), nonZeros = static_cast<int>(m.nonZeros());
    const size_t size = static_cast<size_t>(outer) + 1 + static_cast<size_t>(nonZeros) + 2;
    if (m.isCompressed() && layout->size() == size && (*layout)[0] == outer && (*layout)[1] == nonZeros &&
        std::equal(m.outerIndexPtr(), m.outerIndexPtr() + outer + 1, layout->begin() + 2) &&
        std::equal(m.innerIndexPtr(), m.innerIndexPtr() + nonZeros, layout->begin() + 3 + outer))
      return true;
    layout->clear();
    if (!m.isCompressed()) return false;
    layout->push_back(outer);
    layout->push_back(nonZeros);
    layout->insert(layout->end(), m.outerIndexPtr(), m.outerIndexPtr() + outer + 1);
    layout->insert(layout->end(), m.innerIndexPtr(), m.innerIndexPtr() + nonZeros);
    return false;
  }

  // Permutes a vector of K's rows into the factorisation's order and back.
  Vec permute(const Vec& v) const {
    Vec out(v.size());
    for (Eigen::Index i = 0; i < v.size(); ++i) out[position[i]] = v[i];
    return out;
  }
  Vec unpermute(const Vec& v) const {
    Vec out(v.size());
    for (Eigen::Index i = 0; i < v.size(); ++i) out[i] = v[position[i]];
    return out;
  }

 private:
  Eigen::VectorXi original;

  // Every entry of K's lower triangle (unpermuted) the program scatters into: H's lower
  // triangle, A below H, the pairs of columns each inequality row touches, the diagonal.
  template <typename Visit>
  void forEachEntry(const QuadraticProgram& qp, Visit visit) const {
    for (int k = 0; k < qp.hessian.outerSize(); ++k)
      for (SpMat::InnerIterator e(qp.hessian, k); e; ++e)
        if (e.row() >= e.col()) visit(static_cast<int>(e.row()), static_cast<int>(e.col()));
    for (int k = 0; k < qp.equalities.outerSize(); ++k)
      for (SpRow::InnerIterator e(qp.equalities, k); e; ++e) visit(n + k, static_cast<int>(e.col()));
    const SpRow& C = qp.inequalities;
    for (int i = 0; i < C.outerSize(); ++i)
      for (SpRow::InnerIterator a(C, i); a; ++a)
        for (SpRow::InnerIterator b(C, i); b && b.col() <= a.col(); ++b)
          visit(static_cast<int>(a.col()), static_cast<int>(b.col()));
    for (int i = 0; i < n + me; ++i) visit(i, i);
  }

  // Index into K's values of the entry (row, col) of the unpermuted K, or -1 if it is not in
  // the pattern.
  int slot(int row, int col) const {
    int a = position[row], b = position[col];
    if (a > b) std::swap(a, b);  // the upper triangle: column b, row a
    const int* begin = K.innerIndexPtr() + K.outerIndexPtr()[b];
    const int* end = K.innerIndexPtr() + K.outerIndexPtr()[b + 1];
    const int* at = std::lower_bound(begin, end, a);
    return at != end && *at == a ? static_cast<int>(at - K.innerIndexPtr()) : -1;
  }
};

namespace qp {

// The reduced KKT system of one iteration on a workspace's pattern: values, LDL^T factors and
// solves. C^T (Z/S) C is a scatter of w_i C_ia C_ib into the precomputed slots, row by row: the
// sparse product it replaces took three quarters of a solve (the jump's restoration program:
// 7 ms of each 9 ms iteration), and building the pattern another 50 ms per program.
class ReducedSystem {
 public:
  ReducedSystem(const QuadraticProgram& qp, const QpOptions& options, QpWorkspace::Pattern& pattern)
      : qp_(qp), p_(pattern), base_(Vec::Zero(pattern.K.nonZeros())),
        metric_(qp.shiftMetric.size() ? qp.shiftMetric : Vec(Vec::Ones(qp.gradient.size()))) {
    int i = 0;
    for (int k = 0; k < qp.hessian.outerSize(); ++k)
      for (SpMat::InnerIterator e(qp.hessian, k); e; ++e)
        if (e.row() >= e.col()) base_[p_.hessianSlots[i++]] += e.value();
    i = 0;
    for (int k = 0; k < qp.equalities.outerSize(); ++k)
      for (SpRow::InnerIterator e(qp.equalities, k); e; ++e) base_[p_.equalitySlots[i++]] += e.value();
    for (int slot : p_.diagonal) {
      base_[slot] += options.primalRegularisation;
      maxDiagonal_ = std::max(maxDiagonal_, base_[slot]);
    }
    for (int slot : p_.dualDiagonal) base_[slot] -= options.dualRegularisation;
    // Each run's rows on its shared columns, densely (row-major), and each row's products of
    // the pairs with a private column, in the order of the pattern's slots.
    const SpRow& C = qp.inequalities;
    const double* v = C.valuePtr();
    const int* columns = C.innerIndexPtr();
    for (const auto& run : p_.runs)
      for (int r = run.rowBegin; r < run.rowEnd; ++r)
        for (int k = C.outerIndexPtr()[r]; k < C.outerIndexPtr()[r + 1]; ++k)
          if (!p_.privateColumn[static_cast<size_t>(columns[k])]) runValues_.push_back(v[k]);
    privateProducts_.reserve(p_.privateSlots.size());
    for (int r = 0; r < C.outerSize(); ++r) {
      if (p_.rowPrivate[static_cast<size_t>(r)] == p_.rowPrivate[static_cast<size_t>(r) + 1]) continue;  // none
      const int begin = C.outerIndexPtr()[r], end = C.outerIndexPtr()[r + 1];
      for (int a = begin; a < end; ++a)
        for (int b = begin; b <= a; ++b)
          if (p_.privateColumn[static_cast<size_t>(columns[a])] || p_.privateColumn[static_cast<size_t>(columns[b])])
            privateProducts_.push_back(v[a] * v[b]);
    }
  }
  double shift() const { return shift_; }
  double largestDiagonal() const { return maxDiagonal_; }
  void resetShift() { shift_ = 0; }
  void raiseShift(double shift) { shift_ = std::max(shift_, shift); }
  // The shift's metric: the program's, or the identity.
  const Vec& metric() const { return metric_; }

  // Factorises K for the inequality weights w = z / s; with allowShift, raising the shift on H
  // until K has the inertia of a convex program (n positive and m_e negative pivots). False if
  // it does not have that inertia.
  bool factorise(const Vec& w, bool allowShift) {
    const int me = static_cast<int>(qp_.equalities.rows());
    Eigen::Map<Vec> values(p_.K.valuePtr(), p_.K.nonZeros());
    for (int attempt = 0; attempt < 40; ++attempt) {
      values = base_;
      addInequalities(w, values);
      if (shift_ > 0)
        for (size_t i = 0; i < p_.diagonal.size(); ++i) values[p_.diagonal[i]] += shift_ * metric_[static_cast<Eigen::Index>(i)];
      p_.ldlt.factorize(p_.K);
      const auto& D = p_.ldlt.vectorD();
      if (p_.ldlt.info() == Eigen::Success && (D.array() < 0).count() == me && (D.array() != 0).all()) return true;
      if (!allowShift) return false;
      shift_ = shift_ == 0 ? 1e-8 * std::max(1.0, maxDiagonal_) : 10 * shift_;
    }
    return false;
  }

  // The solution of K [dx; dy] = rhs, refined twice against K (pivots of both signs without
  // pivoting lose digits).
  Vec solve(const Vec& rhs) const {
    const Vec b = p_.permute(rhs);
    Vec d = p_.ldlt.solve(b);
    for (int refine = 0; refine < 2; ++refine) d += p_.ldlt.solve(Vec(b - p_.K.selfadjointView<Eigen::Upper>() * d));
    return p_.unpermute(d);
  }

 private:
  // Adds C^T diag(w) C to K's values: per run, its pairs' entries of K are gathered into a
  // dense lower triangle, w_r (C_ra C_rb) added over its rows, and the triangle put back. Each
  // entry gets the same additions in the same order as row by row, so K is the same to the bit
  // (the steps' paths follow the last digits, docs/design.md, Solver item 6); rows of weight
  // zero (the guessed programs' inactive rows) add nothing and are skipped. Added to K row by
  // row through each pair's slot, these products took as long as the factorisation: the jump's
  // `sqp` programs have ~300 000 of them but ~80 runs with ~27 000 pairs in all. A private
  // column's pairs have one row each, so their order does not matter.
  void addInequalities(const Vec& w, Eigen::Map<Vec>& values) {
    const double* row = runValues_.data();
    for (const auto& run : p_.runs) {
      const int width = run.width, pairs = width * (width + 1) / 2;
      const int* slots = p_.runSlots.data() + run.slotsBegin;
      sum_.resize(static_cast<size_t>(pairs));
      for (int k = 0; k < pairs; ++k) sum_[static_cast<size_t>(k)] = values[slots[k]];
      for (int r = run.rowBegin; r < run.rowEnd; ++r, row += width) {
        const double wr = w[r];
        if (wr == 0) continue;
        double* out = sum_.data();
        for (int a = 0; a < width; ++a) {
          const double va = row[a];
          for (int b = 0; b <= a; ++b) out[b] += wr * (va * row[b]);
          out += a + 1;
        }
      }
      for (int k = 0; k < pairs; ++k) values[slots[k]] = sum_[static_cast<size_t>(k)];
    }
    const int* slots = p_.privateSlots.data();
    const double* products = privateProducts_.data();
    for (Eigen::Index i = 0; i < w.size(); ++i) {
      const double wi = w[i];
      for (int p = p_.rowPrivate[static_cast<size_t>(i)], end = p_.rowPrivate[static_cast<size_t>(i) + 1]; p < end; ++p)
        values[slots[p]] += wi * products[p];
    }
  }

  const QuadraticProgram& qp_;
  QpWorkspace::Pattern& p_;
  Vec base_, metric_;
  std::vector<double> runValues_, privateProducts_, sum_;
  double maxDiagonal_ = 0, shift_ = 0;
};

}  // namespace qp
}  // namespace spacetime
