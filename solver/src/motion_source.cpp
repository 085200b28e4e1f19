// The two kinds of earlier motion a solve re-fits from (see motion_source.h).
#include "solver/motion_source.h"

#include <algorithm>
#include <map>

#include "solver/animation.h"
#include "solver/ground_forces.h"
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

// A sampled motion. A frame at an impact's instant holds the velocity after it (as
// sampleAnimation writes it) and qdBefore the left limit (a motion file written before it had
// that field: a step from the frame before).
class AnimationMotion final : public MotionSource {
 public:
  explicit AnimationMotion(const Animation& a) : a_(a) {}
  bool sampled() const override { return true; }
  double start() const override { return first(&CharacterAnimation::times, true); }
  double end() const override { return first(&CharacterAnimation::times, false); }
  int character(const std::string& id, int dofs) const override {
    for (size_t c = 0; c < a_.characters.size(); ++c) {
      const CharacterAnimation& ca = a_.characters[c];
      const bool frames = ca.times.size() >= 2 && ca.q.rows() == static_cast<Eigen::Index>(ca.times.size()) &&
                          ca.qd.rows() == ca.q.rows();
      if (ca.name == id) return ca.q.cols() == dofs && frames ? static_cast<int>(c) : -1;
    }
    return -1;
  }
  // Between frames a cubic Hermite of the values and their derivatives (q with q-dot, q-dot with
  // q-double-dot when the file has it): its error is O(h^4) where linear interpolation's is
  // h^2/8 |q''| - 3.8e-3 rad at 120 Hz on the jump's whipping joint after lift-off. At a
  // touch-down's impact q-dot jumps: an interval ending on it takes q-dot's left limit there
  // (qdBefore), and one with the impact inside it (or whose file lacks qdBefore) reads each side
  // by a Taylor step from its own frame.
  Eigen::VectorXd jointState(int c, double t, int order, bool before) const override {
    const CharacterAnimation& ca = a_.characters[static_cast<size_t>(c)];
    const std::vector<double>& T = ca.times;
    const Eigen::MatrixXd& qdLeft = ca.qdBefore.rows() == ca.qd.rows() ? ca.qdBefore : ca.qd;
    const bool hasQdd = ca.qdd.rows() == ca.q.rows();
    auto row = [&](const Eigen::MatrixXd& m, size_t k) -> Eigen::VectorXd { return m.row(static_cast<Eigen::Index>(k)).transpose(); };
    // Instants within a rounding of a frame are on it (frame times are start + k (end - start) / n).
    const double eps = 1e-9 * (T.back() - T.front());
    if (t <= T.front()) return row(order == 0 ? ca.q : ca.qd, 0);
    if (t >= T.back() - eps && !before) return row(order == 0 ? ca.q : ca.qd, T.size() - 1);
    // The interval [T[i], T[i+1]] holding t; at a frame, `before` reads the interval ending there
    // and otherwise the one starting there.
    size_t i = std::min(static_cast<size_t>(std::upper_bound(T.begin(), T.end(), t) - T.begin()), T.size() - 1) - 1;
    if (t >= T[i + 1] - eps && i + 2 < T.size()) ++i;
    if (before && t <= T[i] + eps && i > 0) --i;
    const double h = T[i + 1] - T[i];
    // A Taylor step from frame k to t (first order in q-dot without q-double-dot).
    auto from = [&](size_t k) -> Eigen::VectorXd {
      const double d = t - T[k];
      if (order == 0) {
        Eigen::VectorXd q = row(ca.q, k) + d * row(ca.qd, k);
        if (hasQdd) q += 0.5 * d * d * row(ca.qdd, k);
        return q;
      }
      if (hasQdd) return row(ca.qd, k) + d * row(ca.qdd, k);
      return row(ca.qd, k) + d * (row(ca.qd, i + 1) - row(ca.qd, i)) / h;
    };
    const bool jumpAtEnd = (row(qdLeft, i + 1) - row(ca.qd, i + 1)).squaredNorm() > 0;
    for (const ContactTrack& track : ca.contacts) {
      if (!track.impact || track.impactTime <= T[i] + eps || track.impactTime > T[i + 1] + eps) continue;
      if (track.impactTime < T[i + 1] - eps || !jumpAtEnd) return before || t < track.impactTime ? from(i) : from(i + 1);
    }
    const double s = (t - T[i]) / h, s2 = s * s, s3 = s2 * s;
    const double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s, h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
    if (order == 0)
      return h00 * row(ca.q, i) + h10 * h * row(ca.qd, i) + h01 * row(ca.q, i + 1) + h11 * h * row(qdLeft, i + 1);
    if (!hasQdd) return (1 - s) * row(ca.qd, i) + s * row(qdLeft, i + 1);
    // Ending on an impact, q-double-dot's left limit there is unknown: the quadratic with the
    // start's value and slope through the end's left limit.
    if (jumpAtEnd) {
      const double d = t - T[i];
      const Eigen::VectorXd slope = row(ca.qdd, i);
      return row(ca.qd, i) + d * slope + (d * d / (h * h)) * (row(qdLeft, i + 1) - row(ca.qd, i) - h * slope);
    }
    return h00 * row(ca.qd, i) + h10 * h * row(ca.qdd, i) + h01 * row(ca.qd, i + 1) + h11 * h * row(ca.qdd, i + 1);
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
    for (const auto& [ca, track] : tracks(term, points, forceDims)) out.push_back(interpolate(ca->times, track->force, t));
    return out;
  }
  std::vector<double> anchors(const std::string& term, int points, int forceDims) const override {
    std::vector<double> out;
    for (const auto& [ca, track] : tracks(term, points, forceDims)) {
      const Eigen::Vector3d w = interpolate(ca->times, track->position, track->start);
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
  // Linear interpolation of a track's values (one per frame time) at t, clamped to the frames.
  static Eigen::Vector3d interpolate(const std::vector<double>& times, const std::vector<Eigen::Vector3d>& v, double t) {
    if (t <= times.front()) return v.front();
    if (t >= times.back()) return v.back();
    const size_t i = static_cast<size_t>(std::upper_bound(times.begin(), times.end(), t) - times.begin()) - 1;
    const double u = (t - times[i]) / (times[i + 1] - times[i]);
    return (1 - u) * v[i] + u * v[i + 1];
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

int startFromMotion(SpacetimeProblem& problem, const Animation& animation) {
  const std::unique_ptr<MotionSource> source = motionSourceOf(animation);
  const int matched = problem.initializeFrom(*source);
  // All samples' forces first, from the fitted motion with the file's forces as the tie-break,
  // then written: each sample reads only its own instant. Characters the motion does not have
  // keep the default guess.
  // One recovery per character and instant serves every contact with a sample there (a biped's
  // two feet share their samples' times).
  std::map<std::pair<int, double>, GroundForces> recovered;
  std::vector<std::pair<std::pair<int, int>, std::vector<Eigen::Vector3d>>> balanced;
  for (size_t j = 0; j < problem.contacts().size(); ++j) {
    const ContactVariables& ct = problem.contacts()[j];
    const int c = ct.character;
    if (source->character(problem.scene().characters[c].id, problem.characters()[c].dofs) < 0) continue;
    for (size_t i = 0; i < ct.times.size(); ++i) {
      auto at = recovered.find({c, ct.times[i]});
      if (at == recovered.end()) at = recovered.emplace(std::make_pair(c, ct.times[i]), groundForcesAt(problem, c, ct.times[i])).first;
      balanced.push_back({{static_cast<int>(j), static_cast<int>(i)}, at->second[j]});
    }
  }
  for (const auto& [at, forces] : balanced) problem.setSampleForces(at.first, at.second, forces);
  return matched;
}

SolverMethod methodForMotionStart(SolverMethod method) {
  return method == SolverMethod::AugmentedLagrangian ? SolverMethod::Sqp : method;
}

bool motionStartReadsMultipliers(SolverMethod method) {
  return method == SolverMethod::AugmentedLagrangian || method == SolverMethod::WitkinKass;
}

std::optional<MultiplierEstimate> multipliersForMotionStart(SpacetimeProblem& problem, const SolverOptions& options) {
  if (!motionStartReadsMultipliers(options.method)) return std::nullopt;
  return estimateMultipliers(problem, std::min(options.maxPenalty, options.nearFeasiblePenalty),
                             std::max(1, options.threads));
}

}  // namespace spacetime
