// Cubic B-spline basis - the standard matrix form on uniform knots (e.g. Foley et al.
// eq. 11.43), Cox-de Boor's recurrence on non-uniform ones (The NURBS Book, Algorithm A2.2) -
// and a regularised least-squares fit used for initial guesses.
#include "core/bspline.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace spacetime {
namespace {

// The four cubic basis functions that are non-zero on knots[span], knots[span + 1] at t
// (The NURBS Book, Algorithm A2.2, p = 3): the piece of that span, also outside it.
std::array<double, 4> coxDeBoor(const std::vector<double>& knots, int span, double t) {
  std::array<double, 4> n{1, 0, 0, 0};
  std::array<double, 4> left{}, right{};
  for (int j = 1; j <= 3; ++j) {
    left[j] = t - knots[span + 1 - j];
    right[j] = knots[span + j] - t;
    double saved = 0;
    for (int r = 0; r < j; ++r) {
      const double temp = n[r] / (right[r + 1] + left[j - r]);
      n[r] = saved + right[r + 1] * temp;
      saved = left[j - r] * temp;
    }
    n[j] = saved;
  }
  return n;
}

}  // namespace

CubicBSpline::CubicBSpline(double t0, double t1, int segments)
    : t0_(t0), t1_(t1), h_((t1 - t0) / segments), segments_(segments) {
  if (!(t1 > t0) || segments < 1) throw std::invalid_argument("CubicBSpline: bad interval");
}

CubicBSpline::CubicBSpline(const std::vector<double>& breakpoints) : breaks_(breakpoints) {
  if (breaks_.size() < 2) throw std::invalid_argument("CubicBSpline: fewer than two breakpoints");
  for (size_t k = 0; k + 1 < breaks_.size(); ++k)
    if (!(breaks_[k + 1] > breaks_[k])) throw std::invalid_argument("CubicBSpline: breakpoints not increasing");
  t0_ = breaks_.front();
  t1_ = breaks_.back();
  segments_ = static_cast<int>(breaks_.size()) - 1;
  h_ = (t1_ - t0_) / segments_;
  // The knot vector: three more knots past each end, spaced as the end segments.
  const double first = breaks_[1] - breaks_[0], last = breaks_[segments_] - breaks_[segments_ - 1];
  std::vector<double> knots;
  for (int i = 3; i >= 1; --i) knots.push_back(t0_ - i * first);
  knots.insert(knots.end(), breaks_.begin(), breaks_.end());
  for (int i = 1; i <= 3; ++i) knots.push_back(t1_ + i * last);
  // Each segment's basis functions are cubics: interpolate them at four points of the segment.
  Eigen::Matrix4d vandermonde;
  for (int m = 0; m < 4; ++m)
    for (int p = 0; p < 4; ++p) vandermonde(m, p) = std::pow(m / 3.0, p);
  const Eigen::Matrix4d inverse = vandermonde.inverse();
  poly_.resize(static_cast<size_t>(segments_));
  for (int k = 0; k < segments_; ++k) {
    Eigen::Matrix4d values;  // (point, basis function)
    for (int m = 0; m < 4; ++m) {
      const std::array<double, 4> n = coxDeBoor(knots, k + 3, breaks_[k] + m / 3.0 * segmentLength(k));
      for (int j = 0; j < 4; ++j) values(m, j) = n[j];
    }
    const Eigen::Matrix4d coefficients = inverse * values;  // (power, basis function)
    for (int j = 0; j < 4; ++j)
      for (int p = 0; p < 4; ++p) poly_[k][j][p] = coefficients(p, j);
  }
}

int CubicBSpline::segmentOf(double t) const {
  if (uniform()) {
    const int k = static_cast<int>(std::floor((t - t0_) / h_));
    return std::clamp(k, 0, segments_ - 1);
  }
  const int k = static_cast<int>(std::upper_bound(breaks_.begin(), breaks_.end(), t) - breaks_.begin()) - 1;
  return std::clamp(k, 0, segments_ - 1);
}

BSplineBasis CubicBSpline::basis(double t) const {
  BSplineBasis b;
  const int k = segmentOf(t);
  b.first = k;
  if (!uniform()) {
    const double h = segmentLength(k);
    const double u = std::clamp((t - breaks_[k]) / h, 0.0, 1.0);
    const double ih = 1 / h, ih2 = ih * ih, ih3 = ih2 * ih;
    for (int j = 0; j < 4; ++j) {
      const std::array<double, 4>& c = poly_[k][j];
      b.w[j] = c[0] + u * (c[1] + u * (c[2] + u * c[3]));
      b.d1[j] = (c[1] + u * (2 * c[2] + u * 3 * c[3])) * ih;
      b.d2[j] = (2 * c[2] + 6 * c[3] * u) * ih2;
      b.d3[j] = 6 * c[3] * ih3;
    }
    return b;
  }
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

std::vector<double> CubicBSpline::sampleTimes(int perSegment) const {
  std::vector<double> times;
  if (uniform()) {
    const int n = perSegment * segments_;
    for (int i = 0; i <= n; ++i) times.push_back(t0_ + (t1_ - t0_) * i / n);
    return times;
  }
  for (int k = 0; k < segments_; ++k)
    for (int i = 0; i < perSegment; ++i) times.push_back(breaks_[k] + segmentLength(k) * i / perSegment);
  times.push_back(t1_);
  return times;
}

Eigen::RowVectorXd CubicBSpline::evaluate(const Eigen::MatrixXd& control, double t,
                                          int order) const {
  const BSplineBasis b = basis(t);
  const auto& w = b.derivative(order);
  Eigen::RowVectorXd out = Eigen::RowVectorXd::Zero(control.cols());
  for (int j = 0; j < 4; ++j) out += w[j] * control.row(b.first + j);
  return out;
}

Eigen::MatrixXd CubicBSpline::fit(const std::vector<double>& times,
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
    const double centre = uniform() ? t0_ + (s + 0.5) * h_ : breaks_[s] + 0.5 * segmentLength(s);
    const BSplineBasis b = basis(centre);
    for (int j = 0; j < 4; ++j)
      for (int k = 0; k < 4; ++k) A(b.first + j, b.first + k) += scale * b.d2[j] * b.d2[k];
  }
  A.diagonal().array() += 1e-12;
  return A.ldlt().solve(rhs);
}

}  // namespace spacetime
