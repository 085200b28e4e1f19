// Lawson-Hanson NNLS (see nnls.h).
#include "core/nnls.h"

#include <Eigen/QR>
#include <vector>

namespace spacetime {

NnlsResult nnls(const Eigen::MatrixXd& A, const Eigen::VectorXd& b, int maxIterations) {
  const int n = static_cast<int>(A.cols());
  NnlsResult r;
  r.x = Eigen::VectorXd::Zero(n);
  if (maxIterations <= 0) maxIterations = 3 * n + 10;
  std::vector<bool> passive(n, false);
  // Tolerance on the gradient, relative to the problem's scale.
  const double tol = 1e-12 * std::max(1.0, A.norm() * b.norm());

  // Least squares restricted to the passive set; zero elsewhere.
  auto solvePassive = [&] {
    std::vector<int> idx;
    for (int i = 0; i < n; ++i)
      if (passive[i]) idx.push_back(i);
    if (idx.empty()) return Eigen::VectorXd::Zero(n).eval();
    Eigen::MatrixXd Ap(A.rows(), idx.size());
    for (size_t k = 0; k < idx.size(); ++k) Ap.col(k) = A.col(idx[k]);
    const Eigen::VectorXd zp = Ap.colPivHouseholderQr().solve(b);
    Eigen::VectorXd z = Eigen::VectorXd::Zero(n);
    for (size_t k = 0; k < idx.size(); ++k) z[idx[k]] = zp[k];
    return z.eval();
  };

  while (r.iterations < maxIterations) {
    const Eigen::VectorXd w = A.transpose() * (b - A * r.x);
    int best = -1;
    for (int i = 0; i < n; ++i)
      if (!passive[i] && w[i] > tol && (best < 0 || w[i] > w[best])) best = i;
    if (best < 0) break;  // KKT conditions hold
    passive[best] = true;
    // Inner loop: keep the passive solution feasible (L&H steps 6-11).
    while (true) {
      ++r.iterations;
      const Eigen::VectorXd z = solvePassive();
      bool feasible = true;
      for (int i = 0; i < n; ++i)
        if (passive[i] && z[i] <= 0) feasible = false;
      if (feasible) {
        r.x = z;
        break;
      }
      double alpha = 1;
      for (int i = 0; i < n; ++i)
        if (passive[i] && z[i] <= 0) alpha = std::min(alpha, r.x[i] / (r.x[i] - z[i]));
      r.x += alpha * (z - r.x);
      for (int i = 0; i < n; ++i)
        if (passive[i] && r.x[i] <= 1e-15) {
          passive[i] = false;
          r.x[i] = 0;
        }
      if (r.iterations >= maxIterations) break;
    }
  }
  r.converged = r.iterations < maxIterations;
  r.residualNorm = (A * r.x - b).norm();
  return r;
}

}  // namespace spacetime
