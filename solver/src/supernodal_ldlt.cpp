// The supernodal LDL^T (see supernodal_ldlt.h).
#include "supernodal_ldlt.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <utility>

namespace spacetime {
namespace qp {
namespace {

// Wider supernodes than this are split: a block's dense factorisation costs height x width^2,
// and past a few dozen columns the split costs nothing measurable while capping the scratch.
constexpr int kMaxWidth = 128;

using Block = Eigen::Map<Eigen::MatrixXd>;

// y[r] (+)= sum_k L[k * ld + r] f[k] for r < m, k < w (`assign`: y is overwritten): a
// column-major matrix-vector product, four columns at a time so that y is loaded and stored once
// per four (the blocks are too small for a general product's set-up to pay, and one column at a
// time spent most instructions on y).
void addProduct(double* y, int m, const double* L, Eigen::Index ld, const double* f, int w, bool assign) {
  int k = 0;
  for (; k + 4 <= w; k += 4, assign = false) {
    const double *l0 = L + k * ld, *l1 = l0 + ld, *l2 = l1 + ld, *l3 = l2 + ld;
    const double f0 = f[k], f1 = f[k + 1], f2 = f[k + 2], f3 = f[k + 3];
    if (assign)
      for (int r = 0; r < m; ++r) y[r] = l0[r] * f0 + l1[r] * f1 + l2[r] * f2 + l3[r] * f3;
    else
      for (int r = 0; r < m; ++r) y[r] += l0[r] * f0 + l1[r] * f1 + l2[r] * f2 + l3[r] * f3;
  }
  for (; k < w; ++k, assign = false) {
    const double* l = L + k * ld;
    const double fk = f[k];
    if (assign)
      for (int r = 0; r < m; ++r) y[r] = l[r] * fk;
    else
      for (int r = 0; r < m; ++r) y[r] += l[r] * fk;
  }
  if (assign) std::fill(y, y + m, 0.0);  // w = 0
}

}  // namespace

void SupernodalLdlt::analyzePattern(const SpMat& upper) {
  info_ = Eigen::InvalidInput;
  slots_.clear();  // until the analysis ends, factorize() refuses every matrix
  n_ = static_cast<int>(upper.cols());
  if (upper.rows() != upper.cols() || !upper.isCompressed()) return;
  const int* outer = upper.outerIndexPtr();
  const int* inner = upper.innerIndexPtr();

  // Elimination tree (Liu 1986; Davis 2006, section 4.1), with path compression.
  std::vector<int> parent(static_cast<size_t>(n_), -1), ancestor(static_cast<size_t>(n_), -1);
  for (int j = 0; j < n_; ++j)
    for (int p = outer[j]; p < outer[j + 1]; ++p)
      for (int r = inner[p]; r != -1 && r < j;) {
        const int next = ancestor[static_cast<size_t>(r)];
        ancestor[static_cast<size_t>(r)] = j;
        if (next == -1) parent[static_cast<size_t>(r)] = j;
        r = next;
      }

  // L's columns: row j of L is the union of the tree paths from each i < j with K_ij != 0 up to
  // j (the row subtree, Davis 2006, section 4.2); rows come in ascending order.
  std::vector<std::vector<int>> columns(static_cast<size_t>(n_));
  std::vector<int> mark(static_cast<size_t>(n_), -1);
  for (int j = 0; j < n_; ++j) {
    mark[static_cast<size_t>(j)] = j;
    for (int p = outer[j]; p < outer[j + 1]; ++p)
      for (int k = inner[p]; k < j && mark[static_cast<size_t>(k)] != j; k = parent[static_cast<size_t>(k)]) {
        columns[static_cast<size_t>(k)].push_back(j);
        mark[static_cast<size_t>(k)] = j;
      }
  }

  // Supernodes: column j joins the supernode of columns [f, j) when it is j - 1's parent (then
  // every column k of them has its structure within {k + 1, .., j} and j's) and the zeros the
  // block then stores are few: always (fundamental supernodes, j - 1's structure is j's and j),
  // or within the relaxed amalgamation's limits (Ashcraft & Grimes 1989; CHOLMOD's defaults:
  // any zeros up to 4 columns, 80 % up to 16, 10 % up to 48, 5 % beyond). Without relaxing, the
  // jump's K had 302 supernodes, 168 of one column, and the small blocks' overhead ate the gain.
  supernodes_.clear();
  rows_.clear();
  std::vector<int> supernodeOf(static_cast<size_t>(n_));
  double countSum = 0;  // sum over the current supernode's columns of their structures' sizes
  for (int j = 0; j < n_; ++j) {
    const double count = static_cast<double>(columns[static_cast<size_t>(j)].size());
    bool joins = j > 0 && parent[static_cast<size_t>(j - 1)] == j && supernodes_.back().width < kMaxWidth;
    if (joins) {
      const double w = supernodes_.back().width + 1;  // its width with j
      const double stored = w * (w - 1) / 2 + w * count, zeros = stored - countSum - count;
      const double fraction = stored > 0 ? zeros / stored : 0;
      joins = zeros == 0 || w <= 4 || (w <= 16 && fraction < 0.8) || (w <= 48 && fraction < 0.1) || fraction < 0.05;
    }
    if (joins) {
      ++supernodes_.back().width;
      countSum += count;
    } else {
      countSum = count;
      Supernode s;
      s.first = j;
      s.width = 1;
      supernodes_.push_back(s);
    }
    supernodeOf[static_cast<size_t>(j)] = static_cast<int>(supernodes_.size()) - 1;
  }
  Eigen::Index offset = 0;
  for (Supernode& s : supernodes_) {
    const auto& below = columns[static_cast<size_t>(s.first + s.width - 1)];
    s.rowsBegin = static_cast<int>(rows_.size());
    rows_.insert(rows_.end(), below.begin(), below.end());
    s.rowsEnd = static_cast<int>(rows_.size());
    s.offset = offset;
    offset += static_cast<Eigen::Index>(s.height()) * s.width;
  }
  values_.resize(offset);
  d_.resize(n_);

  // Where row `row` of L sits in supernode s's block (its columns first, then its rows below);
  // -1 if the block has no such row, which the elimination tree's fill rules out (L_rj != 0 and
  // L_ij != 0 for i < r imply L_ri != 0), so that would be a bug in this analysis.
  auto position = [&](const Supernode& s, int row) {
    if (row < s.first + s.width) return row - s.first;
    const auto begin = rows_.begin() + s.rowsBegin, end = rows_.begin() + s.rowsEnd;
    const auto at = std::lower_bound(begin, end, row);
    return at != end && *at == row ? s.width + static_cast<int>(at - begin) : -1;
  };
  bool found = true;
  std::vector<Eigen::Index> slots(static_cast<size_t>(upper.nonZeros()), 0);
  for (int j = 0; j < n_; ++j)
    for (int p = outer[j]; p < outer[j + 1]; ++p) {
      const int i = inner[p];  // K_ij, i <= j: L's entry (j, i)
      const Supernode& s = supernodes_[static_cast<size_t>(supernodeOf[static_cast<size_t>(i)])];
      const int at = position(s, j);
      found = found && at >= 0;
      slots[static_cast<size_t>(p)] = s.offset + static_cast<Eigen::Index>(i - s.first) * s.height() + at;
    }

  // Each supernode's updates: its rows grouped by the supernode whose columns they are.
  updates_.clear();
  positions_.clear();
  updatesBegin_.assign(1, 0);
  for (const Supernode& s : supernodes_) {
    for (int k = s.rowsBegin; k < s.rowsEnd;) {
      Update u;
      u.target = supernodeOf[static_cast<size_t>(rows_[static_cast<size_t>(k)])];
      u.begin = k - s.rowsBegin;
      int end = k;
      while (end < s.rowsEnd && supernodeOf[static_cast<size_t>(rows_[static_cast<size_t>(end)])] == u.target) ++end;
      u.end = end - s.rowsBegin;
      u.positionsBegin = static_cast<int>(positions_.size());
      const Supernode& t = supernodes_[static_cast<size_t>(u.target)];
      for (int r = k; r < s.rowsEnd; ++r) {
        positions_.push_back(position(t, rows_[static_cast<size_t>(r)]));
        found = found && positions_.back() >= 0;
      }
      updates_.push_back(u);
      k = end;
    }
    updatesBegin_.push_back(static_cast<int>(updates_.size()));
  }
  if (!found) return;
  slots_ = std::move(slots);
  info_ = Eigen::Success;
}

void SupernodalLdlt::factorize(const SpMat& upper) {
  if (static_cast<size_t>(upper.nonZeros()) != slots_.size() || upper.cols() != n_) {
    info_ = Eigen::InvalidInput;
    return;
  }
  values_.setZero();
  const double* k = upper.valuePtr();
  for (size_t p = 0; p < slots_.size(); ++p) values_[slots_[p]] += k[p];
  for (size_t si = 0; si < supernodes_.size(); ++si) {
    const Supernode& s = supernodes_[si];
    const int w = s.width, h = s.height(), below = h - w;
    Block B(values_.data() + s.offset, h, w);
    // Dense LDL^T of the block's columns, left-looking (Golub & Van Loan, Algorithm 4.1.2):
    // column j less its products with the columns before it, then divided by its pivot.
    factor_.resize(static_cast<size_t>(w));
    for (int j = 0; j < w; ++j) {
      for (int k = 0; k < j; ++k) factor_[static_cast<size_t>(k)] = -B(j, k) * d_[s.first + k];
      addProduct(B.data() + static_cast<Eigen::Index>(j) * h + j, h - j, B.data() + j, h, factor_.data(), j, false);
      const double dj = B(j, j);
      if (!(dj != 0) || !std::isfinite(dj)) {
        info_ = Eigen::NumericalIssue;
        return;
      }
      d_[s.first + j] = dj;
      B.col(j).tail(h - j - 1) /= dj;
    }
    if (below == 0) continue;
    // Each target's block less L21[rows from begin] D L21[rows begin..end)^T, a column at a time.
    accumulator_.resize(static_cast<size_t>(below));
    const double* L21 = B.data() + w;
    for (int u = updatesBegin_[si]; u < updatesBegin_[si + 1]; ++u) {
      const Update& up = updates_[static_cast<size_t>(u)];
      const Supernode& t = supernodes_[static_cast<size_t>(up.target)];
      double* target = values_.data() + t.offset;
      const int th = t.height();
      const int* pos = positions_.data() + up.positionsBegin;
      for (int c = up.begin; c < up.end; ++c) {
        const int m = below - c;  // rows c.. of L21: those on or below the target's diagonal
        for (int k = 0; k < w; ++k) factor_[static_cast<size_t>(k)] = L21[static_cast<Eigen::Index>(k) * h + c] * d_[s.first + k];
        double* acc = accumulator_.data();
        addProduct(acc, m, L21 + c, h, factor_.data(), w, true);
        double* column = target + static_cast<Eigen::Index>(rows_[static_cast<size_t>(s.rowsBegin + c)] - t.first) * th;
        const int* p = pos + (c - up.begin);
        for (int r = 0; r < m; ++r) column[p[r]] -= acc[r];
      }
    }
  }
  info_ = Eigen::Success;
}

SupernodalLdlt::Vec SupernodalLdlt::solve(const Vec& b) const {
  Vec x = b;
  std::vector<double> gathered;
  for (const Supernode& s : supernodes_) {  // L y = b
    const int w = s.width, h = s.height(), below = h - w;
    const double* B = values_.data() + s.offset;
    double* xs = x.data() + s.first;
    for (int j = 0; j < w; ++j)
      for (int i = j + 1; i < w; ++i) xs[i] -= B[static_cast<Eigen::Index>(j) * h + i] * xs[j];
    if (below == 0) continue;
    gathered.assign(static_cast<size_t>(below), 0.0);
    for (int k = 0; k < w; ++k) {
      const double* l = B + static_cast<Eigen::Index>(k) * h + w;
      const double xk = xs[k];
      for (int r = 0; r < below; ++r) gathered[static_cast<size_t>(r)] += l[r] * xk;
    }
    const int* rows = rows_.data() + s.rowsBegin;
    for (int r = 0; r < below; ++r) x[rows[r]] -= gathered[static_cast<size_t>(r)];
  }
  x.array() /= d_.array();  // D z = y
  for (auto s = supernodes_.rbegin(); s != supernodes_.rend(); ++s) {  // L^T x = z
    const int w = s->width, h = s->height(), below = h - w;
    const double* B = values_.data() + s->offset;
    double* xs = x.data() + s->first;
    if (below > 0) {
      const int* rows = rows_.data() + s->rowsBegin;
      gathered.resize(static_cast<size_t>(below));
      for (int r = 0; r < below; ++r) gathered[static_cast<size_t>(r)] = x[rows[r]];
      for (int k = 0; k < w; ++k) {
        const double* l = B + static_cast<Eigen::Index>(k) * h + w;
        double sum = 0;
        for (int r = 0; r < below; ++r) sum += l[r] * gathered[static_cast<size_t>(r)];
        xs[k] -= sum;
      }
    }
    for (int j = w - 1; j >= 0; --j)
      for (int i = j + 1; i < w; ++i) xs[j] -= B[static_cast<Eigen::Index>(j) * h + i] * xs[i];
  }
  return x;
}

Eigen::Index SupernodalLdlt::storedNonZeros() const {
  Eigen::Index count = 0;
  for (const Supernode& s : supernodes_)
    count += static_cast<Eigen::Index>(s.width) * (s.width - 1) / 2 + static_cast<Eigen::Index>(s.width) * (s.rowsEnd - s.rowsBegin);
  return count;
}

}  // namespace qp
}  // namespace spacetime
