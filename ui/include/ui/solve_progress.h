// How far a running solve has come, for the status bar's progress bar. Both methods end when the
// largest constraint violation falls to the tolerance, and the violation falls by orders of
// magnitude (0.1 to 1e-7 on the jump), so progress is its decrease on a log scale: 0 at the
// first iterate's violation, 1 at the tolerance. It can go back when an iterate gets worse:
// it is an estimate, not a promise.
#pragma once

#include <algorithm>
#include <cmath>

namespace spacetime::ui {

class SolveProgress {
 public:
  explicit SolveProgress(double tolerance) : tolerance_(std::max(tolerance, 1e-300)) {}

  // The fraction done at an iterate of largest violation `violation`, in [0, 1].
  double update(double violation) {
    if (!(violation >= 0)) return last_;  // NaN: keep the last estimate
    if (first_ < 0) first_ = std::max(violation, 10 * tolerance_);
    const double span = std::log(first_ / tolerance_);
    last_ = std::clamp(std::log(first_ / std::max(violation, tolerance_)) / span, 0.0, 1.0);
    return last_;
  }

 private:
  double tolerance_;
  double first_ = -1;  // the first iterate's violation (at least ten times the tolerance)
  double last_ = 0;
};

}  // namespace spacetime::ui
