// Leg bubbles: the unknowns that let a character stand on the feet of several legs.
//
// A contact that does not hold the floating root keeps its points still by zero acceleration at
// every collocation node of its interval (SpacetimeProblem::assemble): r rows per node, r the
// rank of the points' rigid motion (a planar point 2, a planar foot of two points 3; in 3D a
// point 3, two points 5, three or more 6). Only the motion meets these rows - forces do not enter
// them - and per interval the motion has the root's s coefficients per dof (Hermite data and
// bubbles) and about one B-spline coefficient per joint. One foot is met by the root; every
// further foot on another leg needs that leg's joints to follow it between the knots, which a
// cubic B-spline at one coefficient per interval cannot do unless all legs move alike (four feet
// of a planar quadruped: 8s rows per interval against 3s + 8 unknowns, design.md). Here each
// such foot gets s - 1 bubbles per interval on each joint of its own leg, so the leg has s
// unknowns per interval and joint, as many as its foot has rows when the leg has r joints -
// the same count that makes the root's collocation square (de Boor & Swartz 1973). The bubbles
// 64 u^3 (1-u)^3 (2u-1)^j vanish with their first two derivatives at the interval's ends: the
// joint stays C2, so a lift-off still lets go without a jump in the joints' accelerations.
//
// Which feet: in each interval, the active contacts kept still by acceleration, in scene order;
// the root meets them while its dofs last (rows subtracted from its dof count), every later
// contact gets bubbles on the joints between its body and the root not already used by an
// earlier contact of the interval, if there are at least as many as its rows. Characters with a
// free contact end get none (their breakpoints move; the moving time map has no bubbles).
#include <algorithm>
#include <map>

#include "solver/spacetime_problem.h"

namespace spacetime {
namespace {

// The rank of a contact's points' rigid motion: how many independent still-rows per node (the
// rows ContactPointMotionKernel writes).
int pointsRank(const ContactPoints& points, bool planar) {
  return (planar ? 2 : 3) + static_cast<int>(contactTurns(points, planar).size());
}

// The actuated dofs between a body and the root, sorted (every joint has one dof).
std::vector<int> legDofs(const Model<double>& model, int body) {
  std::vector<int> dofs;
  for (int b = body; b >= 0; b = model.bodies[b].parent)
    if (model.bodies[b].actuated && model.bodies[b].dofIndex >= 0) dofs.push_back(model.bodies[b].dofIndex);
  std::sort(dofs.begin(), dofs.end());
  return dofs;
}

}  // namespace

bool SpacetimeProblem::hasLegBubbles() const {
  return std::any_of(characters_.begin(), characters_.end(), [](const CharacterVariables& cv) {
    return std::any_of(cv.groups.begin(), cv.groups.end(), [](const DofGroup& g) { return g.legBubbles; });
  });
}

bool SpacetimeProblem::legBubblesWouldApply() const {
  for (size_t c = 0; c < characters_.size(); ++c)
    if (!legBubbleCounts(static_cast<int>(c)).empty()) return true;
  return false;
}

std::map<std::vector<int>, std::vector<int>> SpacetimeProblem::legBubbleCounts(int c) const {
  std::map<std::vector<int>, std::vector<int>> counts;  // a leg's dofs -> bubbles per interval
  const int bubbles = scene_.transcription.samplesPerSegment - 1;
  const CharacterVariables& cv = characters_[c];
  const DofGroup* root = rootGroup(c);
  const bool freeEnd = std::any_of(contacts_.begin(), contacts_.end(), [&](const ContactVariables& ct) {
    return ct.character == c && ct.freeEnd >= 0;
  });
  if (bubbles < 1 || !root || freeEnd) return counts;
  const std::vector<double>& breaks = root->breaks;
  const int intervals = static_cast<int>(breaks.size()) - 1;
  for (int k = 0; k < intervals; ++k) {
    if (breaks[k + 1] - breaks[k] < kTimeTolerance) continue;  // an impact's repeated breakpoint
    int capacity = static_cast<int>(root->dofs.size());
    std::vector<int> used;
    for (int j : activeContacts(c, 0.5 * (breaks[k] + breaks[k + 1]))) {
      const ContactVariables& ct = contacts_[j];
      if (ct.holdsRoot || ct.freeEnd >= 0) continue;
      const int rows = pointsRank(ct.points, cv.forceDims == 2);
      std::vector<int> leg = legDofs(*cv.model, ct.points.body);
      if (rows <= capacity) {  // the root meets this contact
        capacity -= rows;
        used.insert(used.end(), leg.begin(), leg.end());
        continue;
      }
      std::erase_if(leg, [&](int d) { return std::find(used.begin(), used.end(), d) != used.end(); });
      if (static_cast<int>(leg.size()) < rows) continue;  // no leg of its own: rows stay as they are
      used.insert(used.end(), leg.begin(), leg.end());
      std::vector<int>& perInterval = counts[leg];
      perInterval.resize(intervals, 0);
      perInterval[k] = bubbles;
    }
  }
  return counts;
}

void SpacetimeProblem::layoutLegBubbles(int* size) {
  if (!scene_.transcription.legBubbles) return;
  for (size_t c = 0; c < characters_.size(); ++c) {
    const std::map<std::vector<int>, std::vector<int>> counts = legBubbleCounts(static_cast<int>(c));
    if (counts.empty()) continue;
    const std::vector<double> breaks = rootGroup(static_cast<int>(c))->breaks;  // before groups grow
    for (const auto& [dofs, perInterval] : counts) {
      DofGroup g;
      g.legBubbles = true;
      g.dofs = dofs;
      g.breaks = breaks;
      g.extraBubble = perInterval;
      g.offset = g.bubbleOffset = *size;
      g.layoutBubbles();
      *size += g.variableCount();
      characters_[c].groups.push_back(g);
    }
  }
}

}  // namespace spacetime
