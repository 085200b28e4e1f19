// The two kinds of earlier motion a solve re-fits from (see motion_source.h).
#include "solver/motion_source.h"

#include <algorithm>

#include "solver/animation.h"
#include "solver/spacetime_problem.h"

namespace spacetime {
namespace {

// Another problem's solution, read through its own accessors.
class ProblemMotion final : public MotionSource {
 public:
  explicit ProblemMotion(const SpacetimeProblem& p) : p_(p) {}
  double start() const override { return p_.scene().startTime; }
  double end() const override { return p_.scene().endTime; }
  int character(const std::string& id, int dofs) const override {
    const std::vector<CharacterSpec>& specs = p_.scene().characters;
    for (size_t c = 0; c < specs.size(); ++c)
      if (specs[c].id == id) return p_.characters()[c].dofs == dofs ? static_cast<int>(c) : -1;
    return -1;
  }
  Eigen::VectorXd jointState(int c, double t, int order, bool before) const override {
    return before ? p_.jointStateBefore(c, t, order) : p_.jointState(c, t, order);
  }
  std::optional<std::pair<double, double>> contactInterval(const std::string& term) const override {
    for (const ContactVariables& ct : p_.contacts())
      if (p_.scene().terms[ct.term].id == term) return std::make_pair(ct.start, ct.end);
    return std::nullopt;
  }
  std::vector<Eigen::Vector3d> contactForces(const std::string& term, int points, int forceDims,
                                             double t) const override {
    const int j = contact(term, points, forceDims);
    return j < 0 ? std::vector<Eigen::Vector3d>{} : p_.contactForces(j, t);
  }
  std::vector<double> anchors(const std::string& term, int points, int forceDims) const override {
    const int j = contact(term, points, forceDims);
    if (j < 0) return {};
    const int offset = p_.contacts()[j].anchorOffset;
    return {p_.variables().begin() + offset, p_.variables().begin() + offset + 2 * points};
  }
  std::vector<Eigen::Vector3d> impulses(const std::string& term, int points, int forceDims) const override {
    const int j = contact(term, points, forceDims);
    return j < 0 ? std::vector<Eigen::Vector3d>{} : p_.contactImpulses(j);
  }

 private:
  int contact(const std::string& term, int points, int forceDims) const {
    for (size_t j = 0; j < p_.contacts().size(); ++j) {
      const ContactVariables& ct = p_.contacts()[j];
      if (p_.scene().terms[ct.term].id == term && ct.pointForceSize() == points * forceDims)
        return static_cast<int>(j);
    }
    return -1;
  }
  const SpacetimeProblem& p_;
};

// A sampled motion: values between frames interpolated linearly. A frame at an impact's instant
// holds the velocity after it (as sampleAnimation writes it); the left limit there is
// extrapolated from the two frames before.
class AnimationMotion final : public MotionSource {
 public:
  explicit AnimationMotion(const Animation& a) : a_(a) {}
  double start() const override { return first(&CharacterAnimation::times, true); }
  double end() const override { return first(&CharacterAnimation::times, false); }
  int character(const std::string& id, int dofs) const override {
    for (size_t c = 0; c < a_.characters.size(); ++c) {
      const CharacterAnimation& ca = a_.characters[c];
      if (ca.name == id) return ca.q.cols() == dofs && !ca.times.empty() ? static_cast<int>(c) : -1;
    }
    return -1;
  }
  Eigen::VectorXd jointState(int c, double t, int order, bool before) const override {
    const CharacterAnimation& ca = a_.characters[static_cast<size_t>(c)];
    const Eigen::MatrixXd& m = order == 0 ? ca.q : ca.qd;
    return before && order > 0 ? leftLimit(ca.times, m, t) : interpolate(ca.times, m, t);
  }
  std::optional<std::pair<double, double>> contactInterval(const std::string& term) const override {
    for (const CharacterAnimation& ca : a_.characters)
      for (const ContactTrack& track : ca.contacts)
        if (track.term == term) return std::make_pair(track.start, track.end);
    return std::nullopt;
  }
  std::vector<Eigen::Vector3d> contactForces(const std::string& term, int points, int forceDims,
                                             double t) const override {
    std::vector<Eigen::Vector3d> out;
    for (const auto& [ca, track] : tracks(term, points, forceDims)) {
      Eigen::MatrixXd f(static_cast<Eigen::Index>(track->force.size()), 3);
      for (size_t k = 0; k < track->force.size(); ++k) f.row(static_cast<Eigen::Index>(k)) = track->force[k].transpose();
      out.push_back(interpolate(ca->times, f, t));
    }
    return out;
  }
  std::vector<double> anchors(const std::string& term, int points, int forceDims) const override {
    std::vector<double> out;
    for (const auto& [ca, track] : tracks(term, points, forceDims)) {
      Eigen::MatrixXd p(static_cast<Eigen::Index>(track->position.size()), 3);
      for (size_t k = 0; k < track->position.size(); ++k) p.row(static_cast<Eigen::Index>(k)) = track->position[k].transpose();
      const Eigen::VectorXd w = interpolate(ca->times, p, track->start);
      out.push_back(w.x());
      out.push_back(w.z());
    }
    return out;
  }
  std::vector<Eigen::Vector3d> impulses(const std::string& term, int points, int forceDims) const override {
    std::vector<Eigen::Vector3d> out;
    for (const auto& [ca, track] : tracks(term, points, forceDims)) {
      if (!track->impact) return {};
      out.push_back(track->impulse);
    }
    return out;
  }

 private:
  double first(std::vector<double> CharacterAnimation::*times, bool front) const {
    for (const CharacterAnimation& ca : a_.characters)
      if (!(ca.*times).empty()) return front ? (ca.*times).front() : (ca.*times).back();
    return 0;
  }
  // The tracks of a contact's points in point order, empty unless there are `points` of them
  // with a value at every frame (a planar contact's forces have z = 0: any forceDims reads them).
  std::vector<std::pair<const CharacterAnimation*, const ContactTrack*>> tracks(const std::string& term, int points,
                                                                                int /*forceDims*/) const {
    std::vector<std::pair<const CharacterAnimation*, const ContactTrack*>> out(static_cast<size_t>(points));
    int found = 0;
    for (const CharacterAnimation& ca : a_.characters)
      for (const ContactTrack& track : ca.contacts) {
        if (track.term != term) continue;
        if (track.pointIndex < 0 || track.pointIndex >= points || out[static_cast<size_t>(track.pointIndex)].second ||
            track.force.size() != ca.times.size() || track.position.size() != ca.times.size())
          return {};
        out[static_cast<size_t>(track.pointIndex)] = {&ca, &track};
        ++found;
      }
    if (found != points) return {};
    return out;
  }
  // Row-wise linear interpolation of m (one row per frame time) at t, clamped to the frames.
  static Eigen::VectorXd interpolate(const std::vector<double>& times, const Eigen::MatrixXd& m, double t) {
    if (t <= times.front()) return m.row(0).transpose();
    if (t >= times.back()) return m.row(m.rows() - 1).transpose();
    const size_t i = static_cast<size_t>(std::upper_bound(times.begin(), times.end(), t) - times.begin()) - 1;
    const double u = (t - times[i]) / (times[i + 1] - times[i]);
    return ((1 - u) * m.row(static_cast<Eigen::Index>(i)) + u * m.row(static_cast<Eigen::Index>(i + 1))).transpose();
  }
  // The left limit at t: the line through the last two frames before t, evaluated at t.
  static Eigen::VectorXd leftLimit(const std::vector<double>& times, const Eigen::MatrixXd& m, double t) {
    const size_t after = static_cast<size_t>(std::lower_bound(times.begin(), times.end(), t) - times.begin());
    if (after < 2) return interpolate(times, m, t);
    const size_t a = after - 2, b = after - 1;
    const double u = (t - times[a]) / (times[b] - times[a]);
    return ((1 - u) * m.row(static_cast<Eigen::Index>(a)) + u * m.row(static_cast<Eigen::Index>(b))).transpose();
  }
  const Animation& a_;
};

}  // namespace

std::unique_ptr<MotionSource> motionSourceOf(const SpacetimeProblem& problem) {
  return std::make_unique<ProblemMotion>(problem);
}

std::unique_ptr<MotionSource> motionSourceOf(const Animation& animation) {
  return std::make_unique<AnimationMotion>(animation);
}

}  // namespace spacetime
