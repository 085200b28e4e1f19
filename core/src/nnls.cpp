// Lawson-Hanson NNLS (see nnls.h).
#include "core/nnls.h"

#include <Eigen/QR>
#include <algorithm>

namespace spacetime {
namespace {

// The ground's problems (a few unactuated dofs and three tie-break rows per contact point, by
// two or eight cone edges per point) fit these bounds, and their matrices then live on the
// stack: the validity report solves one per instant of its dense grid, and the heap allocations
// were about 40 % of a small solve's time.
constexpr int kMaxRows = 48, kMaxCols = 64;

// The algorithm on storage of at most MaxRows x MaxCols (Eigen::Dynamic: unbounded, on the
// heap); the arithmetic is the same either way.
template <int MaxRows, int MaxCols>
NnlsResult solve(const Eigen::MatrixXd& Ain, const Eigen::VectorXd& bin, int maxIterations) {
  using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, MaxRows, MaxCols>;
  using PerRow = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, MaxRows, 1>;
  using PerColumn = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, MaxCols, 1>;
  using Flags = Eigen::Array<bool, Eigen::Dynamic, 1, 0, MaxCols, 1>;  // passive columns
  const Matrix A = Ain;
  const PerRow b = bin;
  const int n = static_cast<int>(A.cols());
  NnlsResult r;
  PerColumn x = PerColumn::Zero(n), w(n), z(n);
  PerRow residual(A.rows());
  Flags passive = Flags::Constant(n, false);
  if (maxIterations <= 0) maxIterations = 3 * n + 10;
  // Tolerance on the gradient, relative to the problem's scale.
  const double tol = 1e-12 * std::max(1.0, A.norm() * b.norm());

  // Least squares restricted to the passive set; zero elsewhere.
  Matrix Ap(A.rows(), n);
  Eigen::ColPivHouseholderQR<Matrix> qr(A.rows(), n);
  auto solvePassive = [&] {
    z.setZero();
    int k = 0;
    for (int i = 0; i < n; ++i)
      if (passive[i]) Ap.col(k++) = A.col(i);
    if (k == 0) return;
    qr.compute(Ap.leftCols(k));
    const PerColumn zp = qr.solve(b);
    k = 0;
    for (int i = 0; i < n; ++i)
      if (passive[i]) z[i] = zp[k++];
  };

  while (r.iterations < maxIterations) {
    residual = b - A * x;
    w.noalias() = A.transpose() * residual;
    int best = -1;
    for (int i = 0; i < n; ++i)
      if (!passive[i] && w[i] > tol && (best < 0 || w[i] > w[best])) best = i;
    if (best < 0) break;  // KKT conditions hold
    passive[best] = true;
    // Inner loop: keep the passive solution feasible (L&H steps 6-11).
    while (true) {
      ++r.iterations;
      solvePassive();
      bool feasible = true;
      for (int i = 0; i < n; ++i)
        if (passive[i] && z[i] <= 0) feasible = false;
      if (feasible) {
        x = z;
        break;
      }
      double alpha = 1;
      for (int i = 0; i < n; ++i)
        if (passive[i] && z[i] <= 0) alpha = std::min(alpha, x[i] / (x[i] - z[i]));
      x += alpha * (z - x);
      for (int i = 0; i < n; ++i)
        if (passive[i] && x[i] <= 1e-15) {
          passive[i] = false;
          x[i] = 0;
        }
      if (r.iterations >= maxIterations) break;
    }
  }
  r.converged = r.iterations < maxIterations;
  r.residualNorm = (A * x - b).norm();
  r.x = x;
  return r;
}

}  // namespace

NnlsResult nnls(const Eigen::MatrixXd& A, const Eigen::VectorXd& b, int maxIterations) {
  if (A.rows() <= kMaxRows && A.cols() <= kMaxCols) return solve<kMaxRows, kMaxCols>(A, b, maxIterations);
  return solve<Eigen::Dynamic, Eigen::Dynamic>(A, b, maxIterations);
}

}  // namespace spacetime
