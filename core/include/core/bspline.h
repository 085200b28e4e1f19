// Uniform cubic B-splines over a time interval: the representation of every degree of freedom
// and every contact force (Cohen 1992; the seed report, section 5.3).
//
// A spline with N segments on [t0, t1] has N + 3 control points; segment k (knot spacing
// h = (t1 - t0) / N) is shaped by control points k..k+3. Its value and time derivatives are
// fixed linear combinations of those four points, so the solver's chain rule from a sample's
// state to the control points is exact and constant.
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

class UniformBSpline {
 public:
  UniformBSpline() = default;
  UniformBSpline(double t0, double t1, int segments);

  double start() const { return t0_; }
  double end() const { return t1_; }
  int segmentCount() const { return segments_; }
  int controlPointCount() const { return segments_ + 3; }
  double knotSpacing() const { return h_; }

  // Basis of time t (clamped into [t0, t1]; t1 belongs to the last segment).
  BSplineBasis basis(double t) const;
  // The segment holding t.
  int segmentOf(double t) const;

  // Value (or derivative of the given order) of a spline whose control points are the rows of
  // `control` (one column per channel).
  Eigen::RowVectorXd evaluate(const Eigen::MatrixXd& control, double t, int order = 0) const;

  // Least-squares control points whose spline passes near (times[i], values.row(i)), with a
  // small acceleration regulariser so that under-determined segments stay smooth.
  Eigen::MatrixXd fit(const std::vector<double>& times, const Eigen::MatrixXd& values,
                      double smoothing = 1e-6) const;

 private:
  double t0_ = 0, t1_ = 1, h_ = 1;
  int segments_ = 1;
};

}  // namespace spacetime
