// Anderson mixing (type II: Walker and Ni, "Anderson acceleration for fixed-point iterations",
// SIAM J. Numer. Anal. 49(4), 2011, eq. 2.1-2.2) of a fixed-point iteration's steps.
//
// The steps on a kept factorisation (chord_steps.h) are the iteration z <- z + f(z), with
// f(z) = -M^-1 F(z) for a fixed matrix M: a linear rate set by how far M is from the Jacobian
// at the point. Where that rate is slow and steady (an edit far from the factorisation's point:
// about 1/3 a step), the last few steps' differences span the directions M gets wrong, and the
// mixed step
//     s_k = f_k - (dZ + dF) gamma,   gamma = argmin |f_k - dF gamma|,
// with dZ and dF the differences of the last `depth` + 1 points and steps, removes them; on a
// linear iteration, with a memory of the dimension, it is GMRES's step (Walker and Ni, section 4),
// exact after dimension + 1 steps.
// The points are kept as the sum of the steps taken, in the tangent space where the first was.
#pragma once

#include <Eigen/Dense>
#include <vector>

namespace spacetime::raw {

class AndersonMixing {
 public:
  explicit AndersonMixing(int depth) : depth_(depth) {}

  // Forgets the history: the iteration's map changed (the held set, the problem).
  void reset() {
    points_.clear();
    steps_.clear();
  }

  // The step to take from the current point, given the iteration's step f there.
  Eigen::VectorXd mix(const Eigen::VectorXd& f) {
    if (points_.empty()) here_ = Eigen::VectorXd::Zero(f.size());
    points_.push_back(here_);
    steps_.push_back(f);
    if (static_cast<int>(points_.size()) > depth_ + 1) {
      points_.erase(points_.begin());
      steps_.erase(steps_.begin());
    }
    Eigen::VectorXd s = f;
    const int k = static_cast<int>(points_.size()) - 1;
    if (k >= 1) {
      Eigen::MatrixXd dF(f.size(), k), dZ(f.size(), k);
      for (int i = 0; i < k; ++i) {
        dF.col(i) = steps_[static_cast<size_t>(i) + 1] - steps_[static_cast<size_t>(i)];
        dZ.col(i) = points_[static_cast<size_t>(i) + 1] - points_[static_cast<size_t>(i)];
      }
      const Eigen::VectorXd gamma = dF.colPivHouseholderQr().solve(f);
      s -= (dZ + dF) * gamma;
    }
    here_ += s;
    return s;
  }

 private:
  int depth_;
  std::vector<Eigen::VectorXd> points_, steps_;
  Eigen::VectorXd here_;
};

}  // namespace spacetime::raw
