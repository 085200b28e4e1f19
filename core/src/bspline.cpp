// Uniform cubic B-spline basis (the standard matrix form, e.g. Foley et al. eq. 11.43) and a
// regularised least-squares fit used for initial guesses.
#include "core/bspline.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace spacetime {

UniformBSpline::UniformBSpline(double t0, double t1, int segments)
    : t0_(t0), t1_(t1), h_((t1 - t0) / segments), segments_(segments) {
  if (!(t1 > t0) || segments < 1) throw std::invalid_argument("UniformBSpline: bad interval");
}

int UniformBSpline::segmentOf(double t) const {
  const int k = static_cast<int>(std::floor((t - t0_) / h_));
  return std::clamp(k, 0, segments_ - 1);
}

BSplineBasis UniformBSpline::basis(double t) const {
  BSplineBasis b;
  const int k = segmentOf(t);
  b.first = k;
  const double u = std::clamp((t - t0_) / h_ - k, 0.0, 1.0);
  const double u2 = u * u, u3 = u2 * u, v = 1 - u;
  b.w = {v * v * v / 6, (3 * u3 - 6 * u2 + 4) / 6, (-3 * u3 + 3 * u2 + 3 * u + 1) / 6, u3 / 6};
  const double ih = 1 / h_, ih2 = ih * ih, ih3 = ih2 * ih;
  b.d1 = {-v * v / 2 * ih, (3 * u2 - 4 * u) / 2 * ih, (-3 * u2 + 2 * u + 1) / 2 * ih,
          u2 / 2 * ih};
  b.d2 = {v * ih2, (3 * u - 2) * ih2, (-3 * u + 1) * ih2, u * ih2};
  b.d3 = {-ih3, 3 * ih3, -3 * ih3, ih3};
  return b;
}

Eigen::RowVectorXd UniformBSpline::evaluate(const Eigen::MatrixXd& control, double t,
                                            int order) const {
  const BSplineBasis b = basis(t);
  const auto& w = b.derivative(order);
  Eigen::RowVectorXd out = Eigen::RowVectorXd::Zero(control.cols());
  for (int j = 0; j < 4; ++j) out += w[j] * control.row(b.first + j);
  return out;
}

Eigen::MatrixXd UniformBSpline::fit(const std::vector<double>& times,
                                    const Eigen::MatrixXd& values, double smoothing) const {
  const int n = controlPointCount();
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n, values.cols());
  for (size_t i = 0; i < times.size(); ++i) {
    const BSplineBasis b = basis(times[i]);
    for (int j = 0; j < 4; ++j) {
      rhs.row(b.first + j) += b.w[j] * values.row(i);
      for (int k = 0; k < 4; ++k) A(b.first + j, b.first + k) += b.w[j] * b.w[k];
    }
  }
  // Regularise with the integral of the squared second derivative, sampled at segment centres,
  // scaled to the data term so the fit stays close to the samples.
  const double scale = smoothing * std::max<size_t>(times.size(), 1) * std::pow(h_, 4) / n;
  for (int s = 0; s < segments_; ++s) {
    const BSplineBasis b = basis(t0_ + (s + 0.5) * h_);
    for (int j = 0; j < 4; ++j)
      for (int k = 0; k < 4; ++k) A(b.first + j, b.first + k) += scale * b.d2[j] * b.d2[k];
  }
  A.diagonal().array() += 1e-12;
  return A.ldlt().solve(rhs);
}

}  // namespace spacetime
