#include "ui/solved_motion.h"

#include <algorithm>

namespace spacetime::ui {

std::shared_ptr<SolvedMotion> sampleMotion(const SpacetimeProblem& problem) {
  auto m = std::make_shared<SolvedMotion>();
  m->animation = sampleAnimation(problem, kDisplayRateHz);
  m->state = problem.state();
  m->scene = std::make_shared<const Scene>(problem.scene());
  return m;
}

Eigen::VectorXd poseAt(const CharacterAnimation& a, double t, int order) {
  const Eigen::MatrixXd& m = order == 0 ? a.q : a.qd;
  if (a.times.empty()) return Eigen::VectorXd::Zero(m.cols());
  if (t <= a.times.front()) return m.row(0).transpose();
  if (t >= a.times.back()) return m.row(m.rows() - 1).transpose();
  const auto it = std::upper_bound(a.times.begin(), a.times.end(), t);
  const Eigen::Index i = static_cast<Eigen::Index>(it - a.times.begin());
  const double t0 = a.times[i - 1], t1 = a.times[i];
  const double s = t1 > t0 ? (t - t0) / (t1 - t0) : 0.0;
  return ((1 - s) * m.row(i - 1) + s * m.row(i)).transpose();
}

bool motionFitsScene(const SolvedMotion& motion, const Scene& scene) {
  if (motion.animation.characters.size() != scene.characters.size()) return false;
  for (size_t c = 0; c < scene.characters.size(); ++c)
    if (motion.animation.characters[c].name != scene.characters[c].id ||
        motion.animation.characters[c].dofs != scene.characters[c].dofNames())
      return false;
  return true;
}

}  // namespace spacetime::ui
