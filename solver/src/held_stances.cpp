// Held stances: while a contact's points fix the floating root's pose (the points lie on the
// root body and are not collinear, so their positions determine every root coordinate), the
// root does not move, and the transcription says so by construction instead of by anchor rows at
// the samples. The root's Hermite breakpoints inside the contact share one pose - the positions
// of the stance's first breakpoint - and have zero velocity; the bubbles of the intervals between
// them vanish. The root's acceleration is then exactly zero at every instant of the stance, the
// contact forces alone balance the root rows of the dynamics, and the first flight interval
// starts from the held pose at rest, its acceleration free to jump at lift-off (as the ground
// force does). See spacetime_problem.h, "Held stances", for why anchors alone stall.
#include <ceres/manifold.h>

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <numeric>

#include "dynamics/algorithms.h"
#include "solver/spacetime_problem.h"

namespace spacetime {

namespace {

// Whether the points of a contact on body `body` fix the root group's coordinates: the root
// chain ends at that body, and the Jacobian of the points' world positions with respect to the
// root coordinates (central differences at the zero pose) has full column rank.
bool pointsFixRoot(const Model<double>& model, const DofGroup& root, const ContactPoints& points) {
  const int rootBody = model.dofBody[root.dofs.back()];
  if (points.body != rootBody) return false;
  for (int d : root.dofs) {
    const Body<double>& b = model.bodies[model.dofBody[d]];
    if (!b.isVirtual && model.dofBody[d] != rootBody) return false;  // a passive joint elsewhere
  }
  const int n = static_cast<int>(root.dofs.size()), m = static_cast<int>(points.points.size());
  Eigen::MatrixXd J(3 * m, n);
  Data<double> data(model);
  const double step = 1e-6;
  for (int i = 0; i < n; ++i) {
    Eigen::VectorXd q = Eigen::VectorXd::Zero(model.dofCount());
    Eigen::VectorXd plus(3 * m), minus(3 * m);
    for (double sign : {1.0, -1.0}) {
      q[root.dofs[i]] = sign * step;
      forwardKinematics(model, data, q.data());
      for (int p = 0; p < m; ++p)
        (sign > 0 ? plus : minus).segment<3>(3 * p) = pointPosition(data, points.body, points.points[p]);
    }
    J.col(i) = (plus - minus) / (2 * step);
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(J);
  const Eigen::VectorXd sv = svd.singularValues();
  return sv.size() == n && sv[n - 1] > 1e-6 * std::max(1.0, sv[0]);
}

// Whether a contact that holds the root holds it at t: from its start to its end, both included.
bool holdsRootAt(const ContactVariables& ct, double t) {
  return ct.holdsRoot && t >= ct.start - kTimeTolerance && t <= ct.end + kTimeTolerance;
}

}  // namespace

bool SpacetimeProblem::fixesRoot(int character, const ContactPoints& points) const {
  const DofGroup* g = rootGroup(character);
  return g && pointsFixRoot(*characters_[character].model, *g, points);
}

bool SpacetimeProblem::physicsAt(int character, const Sample& s) const {
  if (!s.appliesTo(scene_.characters[character].id)) return false;  // another character's nodes
  if (s.stance)
    return std::any_of(contacts_.begin(), contacts_.end(), [&](const ContactVariables& ct) {
      return ct.holdsRoot && ct.character == character && ct.sampleIndex(s.time) >= 0;
    });
  if (s.weight > 0) return true;  // a collocation node
  // A zero-weight sample is at the clip's start or end or at a contact's edge
  // (Transcription::fromScene); an edge is imposed only on the character whose contact begins or
  // ends there. On another character in flight the instant is a root breakpoint whose intervals
  // already meet physics at their own nodes, and one more row over-determines the root there:
  // two lamps lifting off 0.1 s apart stalled at violation 3e-7 after 100 multiplier updates,
  // the worst row the second lamp's physics next to the first one's touch-down. The problem's
  // contacts, not the scene's: a free end moves its contact's edge and the edge's sample together
  // (syncFreeEnds), and the validity report asks after the solve.
  if (std::abs(s.time - scene_.startTime) < kTimeTolerance || std::abs(s.time - scene_.endTime) < kTimeTolerance)
    return true;
  return std::any_of(contacts_.begin(), contacts_.end(), [&](const ContactVariables& ct) {
    return ct.character == character &&
           (std::abs(ct.start - s.time) < kTimeTolerance || std::abs(ct.end - s.time) < kTimeTolerance);
  });
}

bool SpacetimeProblem::rootHeldAt(int character, double t) const {
  return std::any_of(contacts_.begin(), contacts_.end(), [&](const ContactVariables& ct) {
    return ct.character == character && holdsRootAt(ct, t);
  });
}

void SpacetimeProblem::layoutHeldStances() {
  for (size_t c = 0; c < characters_.size(); ++c)
    for (DofGroup& g : characters_[c].groups) {
      if (!g.hermite) continue;
      const int breaks = static_cast<int>(g.breaks.size());
      std::vector<char> held(breaks, 0);
      g.heldInterval.assign(std::max(0, breaks - 1), 0);
      for (const ContactVariables& ct : contacts_) {
        if (!ct.holdsRoot || ct.character != static_cast<int>(c)) continue;
        // The first of an impact's repeated breakpoints is the state before touch-down.
        auto inside = [&](int k) { return holdsRootAt(ct, g.breaks[k]) && !g.beforeImpact(k); };
        for (int k = 0; k < breaks; ++k) held[k] |= inside(k);
        for (int k = 0; k + 1 < breaks; ++k)
          if (inside(k) && inside(k + 1) && g.breaks[k + 1] - g.breaks[k] > kTimeTolerance) g.heldInterval[k] = 1;
      }
      g.poseOf.assign(breaks, -1);
      for (int k = 0; k < breaks; ++k)
        if (held[k]) g.poseOf[k] = k > 0 && g.heldInterval[k - 1] ? g.poseOf[k - 1] : k;
    }
}

void SpacetimeProblem::applyHeldStances(const DofGroup& g, int k, GroupBasis* gb, GroupBasis* slope) const {
  if (g.poseOf.empty()) return;
  const int size = g.blockSize();
  // The same redirection for the basis and its slope in T.
  auto redirect = [&](GroupBasis* b) {
    // Entries 0-3 are the Hermite data of breakpoints k and k + 1 (position, velocity each).
    for (int i = 0; i < 4; ++i) {
      const int end = i < 2 ? k : k + 1;
      if (!g.heldAt(end)) continue;
      b->start[i] = g.offset + g.poseOf[end] * size;
      if (i % 2 == 1) b->weight[i] = 0;  // a held breakpoint is at rest
    }
    if (!g.heldInterval[k]) return;
    // A held interval's bubbles vanish: point their entries at the pose block with zero weight,
    // so the unused bubble block never enters the problem.
    for (int i = 4; i < b->count; ++i) {
      b->start[i] = g.offset + g.poseOf[k] * size;
      b->size[i] = size;
      b->index[i] = 0;
      b->weight[i] = 0;
    }
  };
  redirect(gb);
  if (slope) redirect(slope);
}

void SpacetimeProblem::settleHeldStances(std::vector<double>* x) const {
  for (const CharacterVariables& cv : characters_)
    for (const DofGroup& g : cv.groups) {
      if (g.poseOf.empty()) continue;
      const int n = static_cast<int>(g.dofs.size()), size = g.blockSize();
      for (size_t k = 0; k < g.poseOf.size(); ++k) {
        if (g.poseOf[k] < 0) continue;
        double* data = x->data() + g.offset + k * size;
        const double* pose = x->data() + g.offset + g.poseOf[k] * size;
        std::copy(pose, pose + n, data);
        std::fill(data + n, data + size, 0.0);
      }
      for (size_t k = 0; k < g.heldInterval.size(); ++k)
        if (g.heldInterval[k])
          std::fill_n(x->begin() + g.bubbleStart(static_cast<int>(k)), g.bubbleBlockSize(static_cast<int>(k)), 0.0);
    }
}

void SpacetimeProblem::fixHeldVelocities() {
  for (const CharacterVariables& cv : characters_)
    for (const DofGroup& g : cv.groups) {
      const int n = static_cast<int>(g.dofs.size()), size = g.blockSize();
      std::vector<int> velocities(n);
      std::iota(velocities.begin(), velocities.end(), n);
      for (size_t k = 0; k < g.poseOf.size(); ++k) {
        double* block = x_.data() + g.offset + k * size;
        if (g.poseOf[k] != static_cast<int>(k) || !problem_->HasParameterBlock(block)) continue;
        problem_->SetManifold(block, new ceres::SubsetManifold(size, velocities));
      }
    }
}

}  // namespace spacetime
