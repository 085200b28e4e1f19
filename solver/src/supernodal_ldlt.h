// A supernodal LDL^T without pivoting for the sparse symmetric systems of the quadratic programs
// (reduced_kkt_system.h): K's pattern is analysed once per family of programs and factorised at
// every interior-point iteration, so the factorisation's speed is the programs' speed.
//
// Eigen's SimplicialLDLT works column by column through index lists: on the jump's K (1116
// columns, L with 24 000 nonzeros, 0.68 Mflop) it runs about seven instructions per flop, and the
// programs spent most of their time there. Adjacent columns of L with the same row structure
// below them (a supernode: the rows of one sample's or one control point's block; relaxed, a few
// explicit zeros allowed) are kept instead as one dense column-major block, so the factorisation
// and the solves are dense products on blocks (Ng & Peyton, SIAM J. Sci. Comput. 14, 1993;
// Davis, Direct Methods for Sparse Linear Systems, 2006, ch. 4 and 9): the jump's program at its
// optimum factorises in 42 M instructions instead of 70 M (docs/design.md, Solver item 6).
//
// The factorisation is right-looking: each supernode, once its block holds its columns of K less
// every update of the supernodes before it, is factorised densely (column by column over the
// whole block: L11, D and L21 = B21 L11^-T D^-1), and its outer product L21 D L21^T is scattered
// into the supernodes its rows fall in (the scatter positions are worked out in the analysis).
// No pivoting, as in SimplicialLDLT: the programs' quasi-definite K (Vanderbei 1995) factorises
// stably in any symmetric order, and the signs of D give K's inertia (Sylvester), which the
// interior point reads.
#pragma once

#include <Eigen/SparseCore>
#include <vector>

namespace spacetime {
namespace qp {

class SupernodalLdlt {
 public:
  using SpMat = Eigen::SparseMatrix<double>;
  using Vec = Eigen::VectorXd;

  // Analyses the pattern of a symmetric matrix given by its upper triangle (column-major and
  // compressed), in the order given: elimination tree, L's structure, supernodes, where each of
  // the matrix's entries and each supernode's update land.
  void analyzePattern(const SpMat& upper);
  // Factorises a matrix with the analysed pattern (the same nonzero layout). info() says whether
  // every pivot was finite and nonzero.
  void factorize(const SpMat& upper);
  Eigen::ComputationInfo info() const { return info_; }
  // D of K = L D L^T, in the matrix's order.
  const Vec& vectorD() const { return d_; }
  // The solution of K x = b.
  Vec solve(const Vec& b) const;
  // Nonzeros of L below the diagonal as stored (dense blocks: explicit zeros included).
  Eigen::Index storedNonZeros() const;

 private:
  struct Supernode {
    int first = 0, width = 0;  // columns [first, first + width)
    int rowsBegin = 0;         // its rows below the diagonal block: rows_[rowsBegin, rowsEnd)
    int rowsEnd = 0;
    Eigen::Index offset = 0;   // its block in values_: (width + rows) x width, column-major
    int height() const { return width + rowsEnd - rowsBegin; }
  };
  // The outer product of a supernode's rows [begin, end of its rows) with its rows [begin, end)
  // (the rows that fall in the target supernode's columns), scattered into the target's block.
  struct Update {
    int target = 0, begin = 0, end = 0;
    int positionsBegin = 0;  // positions_[positionsBegin + k]: row k (from begin) in the target's block
  };

  int n_ = 0;
  std::vector<Supernode> supernodes_;
  std::vector<int> rows_;             // every supernode's rows below its diagonal block, ascending
  std::vector<Eigen::Index> slots_;   // per nonzero of the upper triangle: its place in values_
  std::vector<Update> updates_;       // grouped by source supernode: updatesBegin_[s] .. [s + 1]
  std::vector<int> updatesBegin_;
  std::vector<int> positions_;
  Vec values_, d_;
  std::vector<double> factor_, accumulator_;  // factorisation scratch: a row of L D, an update's column
  Eigen::ComputationInfo info_ = Eigen::InvalidInput;
};

}  // namespace qp
}  // namespace spacetime
