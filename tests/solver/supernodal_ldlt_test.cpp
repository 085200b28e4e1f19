// The supernodal LDL^T (solver/src/supernodal_ldlt.h) against independent truths: without
// pivoting, L D L^T of a matrix in a given order is unique, so its D must be Eigen's simplicial
// factorisation's; its solutions must solve the system (dense LU's answer); the signs of D must be
// the matrix's inertia (Sylvester's law: the dense eigenvalues' signs).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <random>

#include "../../solver/src/supernodal_ldlt.h"

namespace spacetime {
namespace {

using SpMat = Eigen::SparseMatrix<double>;

// A quasi-definite matrix shaped like the programs' reduced KKT systems: a banded H (blocks of
// `block` variables coupled to the next `reach` blocks, as control points through samples) plus a
// diagonal making it positive definite, equality rows each on a few neighbouring variables, and
// -delta I below. Returned as its upper triangle, column-major, compressed.
SpMat quasiDefinite(int blocks, int block, int reach, int equalities, std::mt19937& random, Eigen::MatrixXd* dense) {
  std::normal_distribution<double> normal;
  const int n = blocks * block, size = n + equalities;
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(size, size);
  for (int a = 0; a < blocks; ++a)
    for (int b = a; b < std::min(blocks, a + reach + 1); ++b)
      for (int i = 0; i < block; ++i)
        for (int j = 0; j < block; ++j) {
          const int r = a * block + i, c = b * block + j;
          if (r == c) continue;
          if (r < c || a != b) {
            const double v = 0.3 * normal(random);
            K(r, c) = v;
            K(c, r) = v;
          }
        }
  for (int i = 0; i < n; ++i) K(i, i) = 2 * block * (reach + 1) + std::abs(normal(random));
  std::uniform_int_distribution<int> column(0, n - 4);
  for (int e = 0; e < equalities; ++e) {
    const int c = column(random);
    for (int k = 0; k < 4; ++k) {
      K(n + e, c + k) = normal(random);
      K(c + k, n + e) = K(n + e, c + k);
    }
    K(n + e, n + e) = -1e-3;
  }
  *dense = K;
  return Eigen::MatrixXd(K.triangularView<Eigen::Upper>()).sparseView();
}

// K in the fill-reducing order the programs use (AMD on the full pattern), upper triangle.
SpMat permutedByAmd(const Eigen::MatrixXd& K, Eigen::MatrixXd* permutedDense) {
  const SpMat full = K.sparseView();
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> p;
  Eigen::AMDOrdering<int>()(full, p);
  *permutedDense = p.transpose() * K * p;
  SpMat upper = Eigen::MatrixXd(permutedDense->triangularView<Eigen::Upper>()).sparseView();
  upper.makeCompressed();
  return upper;
}

TEST(SupernodalLdlt, HasTheSimplicialFactorisationsPivotsAndSolvesTheSystem) {
  std::mt19937 random(3);
  for (int trial = 0; trial < 4; ++trial) {
    Eigen::MatrixXd K, P;
    quasiDefinite(30 + 10 * trial, 6, 2, 40 + 5 * trial, random, &K);
    const SpMat upper = permutedByAmd(K, &P);
    qp::SupernodalLdlt ldlt;
    ldlt.analyzePattern(upper);
    ldlt.factorize(upper);
    ASSERT_EQ(ldlt.info(), Eigen::Success);
    Eigen::SimplicialLDLT<SpMat, Eigen::Upper, Eigen::NaturalOrdering<int>> simplicial(upper);
    ASSERT_EQ(simplicial.info(), Eigen::Success);
    const Eigen::VectorXd& d = ldlt.vectorD();
    EXPECT_LE((d - simplicial.vectorD()).cwiseAbs().maxCoeff(), 1e-10 * simplicial.vectorD().cwiseAbs().maxCoeff());
    // The wide blocks hold what the simplicial factor does, and more only where they pad.
    EXPECT_GE(ldlt.storedNonZeros(), simplicial.matrixL().nestedExpression().nonZeros());
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(P.rows(), -1, 2);
    const Eigen::VectorXd x = ldlt.solve(b);
    EXPECT_LE((P * x - b).norm(), 1e-10 * b.norm());
    EXPECT_LE((x - P.lu().solve(b)).norm(), 1e-9 * x.norm());
  }
}

TEST(SupernodalLdlt, PivotSignsAreTheInertia) {
  std::mt19937 random(11);
  Eigen::MatrixXd K, P;
  quasiDefinite(25, 5, 1, 30, random, &K);
  // Make H indefinite on a few variables: their diagonal turns negative (still nonzero pivots).
  for (int i = 0; i < 125; i += 17) K(i, i) = -K(i, i);
  const SpMat upper = permutedByAmd(K, &P);
  qp::SupernodalLdlt ldlt;
  ldlt.analyzePattern(upper);
  ldlt.factorize(upper);
  ASSERT_EQ(ldlt.info(), Eigen::Success);
  const Eigen::VectorXd eigenvalues = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(P).eigenvalues();
  EXPECT_EQ((ldlt.vectorD().array() < 0).count(), (eigenvalues.array() < 0).count());
  EXPECT_GT((eigenvalues.array() < 0).count(), 30);  // the equality rows' 30 and some of H's
}

TEST(SupernodalLdlt, RefactorisesNewValuesOnTheAnalysedPattern) {
  std::mt19937 random(5);
  Eigen::MatrixXd K, P;
  quasiDefinite(20, 4, 2, 20, random, &K);
  SpMat upper = permutedByAmd(K, &P);
  qp::SupernodalLdlt ldlt;
  ldlt.analyzePattern(upper);
  ldlt.factorize(upper);
  // The interior point's next iteration: the same pattern, the diagonal changed.
  for (int k = 0; k < upper.outerSize(); ++k)
    for (SpMat::InnerIterator e(upper, k); e; ++e)
      if (e.row() == e.col() && e.value() > 0) e.valueRef() *= 3;
  ldlt.factorize(upper);
  ASSERT_EQ(ldlt.info(), Eigen::Success);
  const Eigen::MatrixXd full = Eigen::MatrixXd(upper).selfadjointView<Eigen::Upper>();
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(full.rows());
  EXPECT_LE((full * ldlt.solve(b) - b).norm(), 1e-10 * b.norm());
}

TEST(SupernodalLdlt, AZeroPivotIsReported) {
  // [[1, 1], [1, 1]]: the second pivot is 1 - 1 = 0.
  Eigen::MatrixXd K(2, 2);
  K << 1, 1, 0, 1;
  const SpMat upper = K.sparseView();
  qp::SupernodalLdlt ldlt;
  ldlt.analyzePattern(upper);
  ldlt.factorize(upper);
  EXPECT_EQ(ldlt.info(), Eigen::NumericalIssue);
}

TEST(SupernodalLdlt, AMatrixOfAnotherPatternIsRefused) {
  Eigen::MatrixXd K(3, 3);
  K << 4, 1, 0, 0, 4, 1, 0, 0, 4;
  const SpMat upper = K.sparseView();
  qp::SupernodalLdlt ldlt;
  ldlt.analyzePattern(upper);
  ASSERT_EQ(ldlt.info(), Eigen::Success);
  Eigen::MatrixXd other = K;
  other(0, 2) = 1;  // one entry more than the analysed pattern
  ldlt.factorize(SpMat(other.sparseView()));
  EXPECT_EQ(ldlt.info(), Eigen::InvalidInput);
  SpMat notSquare(3, 2);
  ldlt.analyzePattern(notSquare);
  EXPECT_EQ(ldlt.info(), Eigen::InvalidInput);
  ldlt.factorize(upper);
  EXPECT_EQ(ldlt.info(), Eigen::InvalidInput);  // no analysis holds
}

}  // namespace
}  // namespace spacetime
