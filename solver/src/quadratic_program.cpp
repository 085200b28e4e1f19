// The interior-point quadratic program solver (see quadratic_program.h).
#include "solver/quadratic_program.h"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>
#include <unordered_map>
#include <vector>

namespace spacetime {
namespace {

using SpMat = Eigen::SparseMatrix<double>;
using SpRow = Eigen::SparseMatrix<double, Eigen::RowMajor>;
using Vec = Eigen::VectorXd;

// Largest step in [0, 1] keeping v + alpha dv >= (1 - tau) v (the fraction to the boundary).
double stepToBoundary(const Vec& v, const Vec& dv, double tau) {
  double alpha = 1;
  for (Eigen::Index i = 0; i < v.size(); ++i)
    if (dv[i] < 0) alpha = std::min(alpha, -tau * v[i] / dv[i]);
  return alpha;
}

double infNorm(const Vec& v) { return v.size() ? v.lpNorm<Eigen::Infinity>() : 0.0; }

// Every nonzero of the program's matrices that enters K, in iteration order: H's lower
// triangle, A, C. Two programs with the same list share K's pattern.
std::vector<int> patternOf(const QuadraticProgram& qp) {
  std::vector<int> p{static_cast<int>(qp.gradient.size()), static_cast<int>(qp.equalities.rows()),
                     static_cast<int>(qp.inequalities.rows())};
  for (int k = 0; k < qp.hessian.outerSize(); ++k)
    for (SpMat::InnerIterator e(qp.hessian, k); e; ++e)
      if (e.row() >= e.col()) p.insert(p.end(), {static_cast<int>(e.row()), static_cast<int>(e.col())});
  p.push_back(-1);
  for (int k = 0; k < qp.equalities.outerSize(); ++k)
    for (SpRow::InnerIterator e(qp.equalities, k); e; ++e) p.insert(p.end(), {k, static_cast<int>(e.col())});
  p.push_back(-1);
  for (int k = 0; k < qp.inequalities.outerSize(); ++k)
    for (SpRow::InnerIterator e(qp.inequalities, k); e; ++e) p.insert(p.end(), {k, static_cast<int>(e.col())});
  return p;
}

}  // namespace

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
  Eigen::SimplicialLDLT<SpMat, Eigen::Upper, Eigen::NaturalOrdering<int>> ldlt;

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

QpWorkspace::QpWorkspace() = default;
QpWorkspace::~QpWorkspace() = default;

namespace {

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

// The weight of a guessed active row, relative to 1 + H's largest diagonal: large enough that
// each Newton step below shrinks the held rows' residual by about 1e-5, small enough that the
// factorisation keeps the inertia it should (at 1e8 the 3D lamp's least-squares programs, H's
// diagonal up to 1e5, lost it to rounding).
constexpr double kGuessWeight = 1e5;
// Newton steps on one factorisation: the first solves the program with the held rows as
// weighted penalties, the next remove what the weight and the rounding leave.
constexpr int kGuessSolves = 6;
// Factorisations: a guess that misses is corrected as a primal-dual active set method corrects
// its sets (Hintermueller, Ito & Kunisch 2002): held rows that pull are released, rows the point
// crosses are held. Where a contact force vanishes its cone's rows are all active and their
// multipliers not unique, and the first split of them can pull on one row (the jump's last
// programs: -29 on one of 11 held rows); releasing it gives the solution on the next try. The
// jump's 2 cm warm edit's first program takes all three (one row missed, then one other).
constexpr int kGuessAttempts = 3;
// A guess that needs more changes than this, or more than the last correction made, is far
// from the solution's active set: the corrections then swing (on the 3D lamp's steps, hundreds
// of rows each way), and the interior point is cheaper than more factorisations. As many
// changes as the last correction go on (the 2 cm edit: 53.7 ms instead of 81 when they stopped).
constexpr int kGuessMaxChanges = 8;

// The program with the guessed rows held as equalities (see the header): Newton steps on its
// KKT conditions H x + g + A^T y + C_a^T z = 0, A x = b, C_a x = d_a, each from the residuals
// at the current point, with the held rows' multipliers eliminated as an interior point's are
// (dz = w (C_a dx + C_a x - d_a), with a large weight w, as an active row's z / s near its end).
// K is then the interior point's, with the held rows weighted w and the others 0. True, with
// the result filled in, if the point is a KKT point of the whole program to the tolerance, by
// the interior point's measure.
bool solveOnGuess(const QuadraticProgram& qp, const SpMat& H, const QpOptions& options, ReducedSystem& system,
                  double dualScale, double primalScale, QpResult* out) {
  const SpRow& A = qp.equalities;
  const SpRow& C = qp.inequalities;
  const int n = static_cast<int>(qp.gradient.size()), me = static_cast<int>(A.rows()), mi = static_cast<int>(C.rows());
  const double weight = kGuessWeight * (1 + system.largestDiagonal());
  std::vector<char> guess = options.activeGuess;
  int lastChanges = std::numeric_limits<int>::max();
  for (int attempt = 0; attempt < kGuessAttempts; ++attempt) {
    Vec held = Vec::Zero(mi);
    for (int i = 0; i < mi; ++i) held[i] = guess[static_cast<size_t>(i)] ? 1.0 : 0.0;
    const Vec w = weight * held;
    // H is made convex on the held rows' tangent space as the interior point makes it on its
    // iterates' (the same shift rule; the jump's exact-Hessian programs need one near its optimum).
    if (!system.factorise(w, !options.convex)) return false;
    Vec x = Vec::Zero(n), y = Vec::Zero(me), z = Vec::Zero(mi), rhs(n + me), rd, excess;
    // A held row that pulls or another row the point crosses, by `margin` times the tolerance.
    auto missed = [&](int i, double margin) {
      return held[i] != 0 ? z[i] < -margin * options.tolerance * dualScale
                          : excess[i] > margin * options.tolerance * primalScale;
    };
    auto misses = [&](double margin) {
      int count = 0;
      for (int i = 0; i < mi; ++i) count += missed(i, margin);
      return count;
    };
    double error = std::numeric_limits<double>::infinity(), primal = 0, mu = 0, heldError = 0;
    for (int k = 0;; ++k) {
      rd = H * x + qp.gradient + A.transpose() * y + C.transpose() * z;
      if (system.shift() > 0) rd += system.shift() * system.metric().cwiseProduct(x);
      const Vec re = A * x - qp.equalityTargets;
      excess = C * x - qp.inequalityBounds;
      const Vec gap = held.cwiseProduct(excess);
      primal = std::max(infNorm(re), infNorm(excess.cwiseMax(0.0)));
      mu = mi ? (-excess).cwiseMax(0.0).dot(z) / mi : 0.0;
      // The program with the held rows as equalities, and over all rows: the held rows at their
      // bound (|gap|), the others inside it (excess <= 0).
      heldError = std::max({infNorm(rd) / dualScale, std::max(infNorm(re), infNorm(gap)) / primalScale});
      error = std::max({heldError, primal / primalScale, mu});
      if (heldError <= 1e-2 * options.tolerance || k == kGuessSolves || !std::isfinite(error)) break;
      // The first solve is accurate to about 1 / weight: a guess it already shows far off is
      // not refined.
      if (k == 1 && misses(1e3) > kGuessMaxChanges) return false;
      rhs.head(n) = -rd - C.transpose() * Vec(w.cwiseProduct(gap));
      rhs.tail(me) = -re;
      const Vec step = system.solve(rhs);
      x += step.head(n);
      y += step.tail(me);
      z += w.cwiseProduct(C * step.head(n) + gap);
    }
    if (!(heldError <= options.tolerance)) return false;  // the held rows' program itself not solved
    const int changes = misses(1);
    if (error <= options.tolerance && changes == 0) {
      out->converged = out->fromGuess = true;
      out->x = x, out->y = y, out->z = z.cwiseMax(0.0);
      out->active = guess;
      out->dualResidual = infNorm(rd);
      out->primalResidual = primal;
      out->complementarity = mu;
      out->shift = system.shift();
      out->reason = "KKT conditions met on the guessed active rows";
      return true;
    }
    if (changes > kGuessMaxChanges || changes > lastChanges) return false;
    for (int i = 0; i < mi; ++i)
      if (missed(i, 1)) guess[static_cast<size_t>(i)] = !guess[static_cast<size_t>(i)];
    lastChanges = changes;
  }
  return false;
}

}  // namespace

QpResult solveQuadraticProgram(const QuadraticProgram& qp, const QpOptions& options, QpWorkspace* workspace) {
  QpResult result;
  const int n = static_cast<int>(qp.gradient.size());
  const int me = static_cast<int>(qp.equalities.rows()), mi = static_cast<int>(qp.inequalities.rows());
  if (qp.hessian.rows() != n || qp.hessian.cols() != n || qp.equalities.cols() != n || qp.inequalities.cols() != n ||
      qp.equalityTargets.size() != me || qp.inequalityBounds.size() != mi ||
      (qp.shiftMetric.size() && qp.shiftMetric.size() != n)) {
    result.reason = "the program's matrices and vectors do not agree in size";
    return result;
  }
  const SpMat H = qp.hessian.selfadjointView<Eigen::Lower>();
  const SpRow& A = qp.equalities;
  const SpRow& C = qp.inequalities;
  const Vec& g = qp.gradient;
  const Vec& b = qp.equalityTargets;
  const Vec& d = qp.inequalityBounds;
  const double dualScale = 1 + infNorm(g), primalScale = 1 + std::max(infNorm(b), infNorm(d));

  QpWorkspace scratch;
  QpWorkspace& ws = workspace ? *workspace : scratch;
  std::vector<int> signature = patternOf(qp);
  if (!ws.pattern_ || ws.pattern_->signature != signature) {
    if (!ws.pattern_ || !ws.pattern_->assignSlots(qp)) {
      const bool grow = ws.pattern_ && ws.pattern_->n == n && ws.pattern_->me == me;
      ws.pattern_ = std::make_unique<QpWorkspace::Pattern>(qp, grow ? ws.pattern_.get() : nullptr);
      ws.pattern_->assignSlots(qp);
    }
    ws.pattern_->signature = std::move(signature);
  }
  ReducedSystem system(qp, options, *ws.pattern_);
  if (options.activeGuess.size() == static_cast<size_t>(mi) &&
      solveOnGuess(qp, H, options, system, dualScale, primalScale, &result))
    return result;
  system.resetShift();  // the interior point finds its own
  Vec x = Vec::Zero(n), y = Vec::Zero(me), z = Vec::Ones(mi), s = Vec::Ones(mi);

  // One Newton step of the perturbed KKT conditions with complementarity target rc (s o z - rc
  // is driven to zero), on the factorised system: dx, dy, ds, dz.
  struct Step {
    Vec dx, dy, ds, dz;
  };
  Vec rd, re, ri;
  auto residuals = [&] {
    // H as factorised: with the inertia correction's shift the convexified program is solved.
    rd = H * x + g + A.transpose() * y + C.transpose() * z;
    if (system.shift() > 0) rd += system.shift() * system.metric().cwiseProduct(x);
    re = A * x - b;
    ri = C * x + s - d;
  };
  auto newtonStep = [&](const Vec& rc) {
    Vec rhs(n + me);
    rhs.head(n) = -rd - C.transpose() * Vec((z.cwiseProduct(ri) - rc).cwiseQuotient(s));
    rhs.tail(me) = -re;
    const Vec sol = system.solve(rhs);
    Step st;
    st.dx = sol.head(n);
    st.dy = sol.tail(me);
    st.ds = -ri - C * st.dx;
    st.dz = (-rc - z.cwiseProduct(st.ds)).cwiseQuotient(s);
    return st;
  };

  // Starting point (Nocedal & Wright, section 16.6): the affine step from x = 0, s = z = 1,
  // then slacks and multipliers moved away from zero.
  residuals();
  if (!system.factorise(z.cwiseQuotient(s), !options.convex)) {
    result.reason = "the reduced KKT system could not be factorised";
    return result;
  }
  {
    const Step affine = newtonStep(s.cwiseProduct(z));
    x += affine.dx;
    y += affine.dy;
    s = (s + affine.ds).cwiseAbs().cwiseMax(1.0);
    z = (z + affine.dz).cwiseAbs().cwiseMax(1.0);
  }

  // The best iterate so far (by the largest scaled residual) is what the solve returns: near the
  // solution z / s grows without bound for active rows, and in double precision the last
  // iterations can lose what the earlier ones reached (the pivots then no longer show the
  // inertia they should, and a shift would change the program).
  double bestError = std::numeric_limits<double>::infinity();
  Vec bestX = x, bestY = y, bestZ = z, bestS = s;
  QpResult best;
  std::string stop;
  for (int it = 0;; ++it) {
    residuals();
    const double mu = mi ? s.dot(z) / mi : 0.0;
    result.iterations = it;
    result.dualResidual = infNorm(rd);
    result.primalResidual = std::max(infNorm(re), infNorm(ri));
    result.complementarity = mu;
    const double error = std::max({result.dualResidual / dualScale, result.primalResidual / primalScale, mu});
    // An iterate that runs off to infinity: no feasible point, or no bounded minimum.
    if (!(std::max({infNorm(x), infNorm(y), infNorm(z), infNorm(s)}) < 1e30) || !(error < 1e300)) {
      stop = "the iterates diverge: the program has no feasible point or no bounded minimum";
      break;
    }
    if (error < bestError) {
      bestError = error;
      bestX = x, bestY = y, bestZ = z, bestS = s;
      best = result;
    }
    if (error <= options.tolerance) break;
    if (it >= options.maxIterations) {
      stop = "no KKT point within " + std::to_string(options.maxIterations) + " iterations";
      break;
    }
    if (!system.factorise(z.cwiseQuotient(s), !options.convex && bestError > options.acceptableTolerance)) {
      stop = "the reduced KKT system lost its inertia";
      break;
    }
    // Predictor (sigma = 0), then the corrector aimed at sigma mu with Mehrotra's second-order
    // term ds_aff o dz_aff; one step length for primal and dual (H couples them).
    const Step affine = newtonStep(s.cwiseProduct(z));
    const double alphaAffine = std::min(stepToBoundary(s, affine.ds, 1.0), stepToBoundary(z, affine.dz, 1.0));
    const double muAffine = mi ? (s + alphaAffine * affine.ds).dot(z + alphaAffine * affine.dz) / mi : 0.0;
    const double sigma = mu > 0 ? std::pow(muAffine / mu, 3) : 0.0;
    const Step step = newtonStep(s.cwiseProduct(z) + affine.ds.cwiseProduct(affine.dz) - Vec::Constant(mi, sigma * mu));
    const double tau = std::max(0.9, 1 - mu);  // towards 1 as the iterates converge
    const double alpha = std::min(stepToBoundary(s, step.ds, tau), stepToBoundary(z, step.dz, tau));
    x += alpha * step.dx;
    y += alpha * step.dy;
    s += alpha * step.ds;
    z += alpha * step.dz;
  }
  const int iterations = result.iterations;
  result = best;
  result.iterations = iterations;
  x = bestX, y = bestY, z = bestZ;
  result.converged = bestError <= options.acceptableTolerance;
  std::ostringstream why;
  if (bestError <= options.tolerance) {
    why << "KKT conditions met";
  } else {
    why << (result.converged ? "KKT conditions met to " : "stopped at a KKT error of ") << bestError;
    if (!stop.empty()) why << ": " << stop;
  }
  result.reason = why.str();
  result.x = x;
  result.y = y;
  result.z = z;
  result.active.resize(static_cast<size_t>(mi));
  for (int i = 0; i < mi; ++i) result.active[static_cast<size_t>(i)] = z[i] > bestS[i];
  result.shift = system.shift();
  return result;
}

}  // namespace spacetime
