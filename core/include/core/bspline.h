// Cubic B-splines over a time interval: the representation of every degree of freedom and every
// contact force (Cohen 1992; the seed report, section 5.3).
//
// A spline with N segments between the breakpoints t0 = τ_0 < τ_1 < … < τ_N = t1 has N + 3
// control points; segment k, [τ_k, τ_k+1], is shaped by control points k..k+3. Its value and
// time derivatives are fixed linear combinations of those four points, so the solver's chain
// rule from a sample's state to the control points is exact and constant. The breakpoints are
// uniform (the scene's control points per second) or, after the automatic refinement has split
// the segments where the motion needed more freedom, non-uniform (de Boor, "A Practical Guide to
// Splines", ch. IX): the knot vector then continues three knots past each end with the end
// segments' lengths, so that equal breakpoints give exactly the uniform spline.
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

namespace spacetime {

// The four basis weights of one time and the first control point they apply to.
struct BSplineBasis {
  int first = 0;                 // index of the first of the four active control points
  std::array<double, 4> w{};     // value weights
  std::array<double, 4> d1{};    // first time derivative
  std::array<double, 4> d2{};    // second time derivative
  std::array<double, 4> d3{};    // third time derivative (piecewise constant)
  const std::array<double, 4>& derivative(int order) const {
    return order == 0 ? w : order == 1 ? d1 : order == 2 ? d2 : d3;
  }
};

class CubicBSpline {
 public:
  CubicBSpline() = default;
  // Uniform: `segments` equal segments on [t0, t1].
  CubicBSpline(double t0, double t1, int segments);
  // On the given breakpoints (strictly increasing, at least two).
  explicit CubicBSpline(const std::vector<double>& breakpoints);

  double start() const { return t0_; }
  double end() const { return t1_; }
  int segmentCount() const { return segments_; }
  int controlPointCount() const { return segments_ + 3; }
  bool uniform() const { return breaks_.empty(); }
  // Breakpoint k (0..segmentCount()): t0 + k h on a uniform spline.
  double knot(int k) const { return uniform() ? t0_ + k * h_ : breaks_[static_cast<size_t>(k)]; }
  double segmentLength(int k) const { return uniform() ? h_ : breaks_[k + 1] - breaks_[k]; }
  // (t1 - t0) / segments: the knot spacing of a uniform spline.
  double meanKnotSpacing() const { return h_; }
  // perSegment + 1 times per segment, its ends shared: evenly over [t0, t1] on a uniform spline
  // (segments x perSegment + 1 in all), each segment's own on a non-uniform one.
  std::vector<double> sampleTimes(int perSegment) const;

  // Basis of time t (clamped into [t0, t1]; t1 belongs to the last segment).
  BSplineBasis basis(double t) const;
  // The segment holding t.
  int segmentOf(double t) const;

  // Value (or derivative of the given order) of a spline whose control points are the rows of
  // `control` (one column per channel).
  Eigen::RowVectorXd evaluate(const Eigen::MatrixXd& control, double t, int order = 0) const;

  // Least-squares control points whose spline passes near (times[i], values.row(i)), with a
  // small acceleration regulariser so that under-determined segments stay smooth.
  static constexpr double kDefaultSmoothing = 1e-6;
  Eigen::MatrixXd fit(const std::vector<double>& times, const Eigen::MatrixXd& values,
                      double smoothing = kDefaultSmoothing) const;

  bool operator==(const CubicBSpline& o) const {
    return t0_ == o.t0_ && t1_ == o.t1_ && segments_ == o.segments_ && breaks_ == o.breaks_;
  }

 private:
  double t0_ = 0, t1_ = 1, h_ = 1;
  int segments_ = 1;
  // Non-uniform splines only: the breakpoints, and per segment the power-basis coefficients of
  // its four basis functions in u = (t - τ_k) / (τ_k+1 - τ_k): B_j(u) = Σ_p poly[k][j][p] u^p.
  std::vector<double> breaks_;
  std::vector<std::array<std::array<double, 4>, 4>> poly_;
};

}  // namespace spacetime
