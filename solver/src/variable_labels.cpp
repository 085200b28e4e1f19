// What a variable of the problem is, in words (solver/variable_labels.h): the layout the problem
// gives its characters' groups, its contacts and its free contact ends (spacetime_problem.h).
#include "solver/variable_labels.h"

#include <iomanip>
#include <sstream>

#include "solver/spacetime_problem.h"

namespace spacetime {

namespace {

std::string at(double t) {
  std::ostringstream s;
  s << "t=" << std::fixed << std::setprecision(4) << t;
  return s.str();
}

const char* axisName(int k, int dims) { return dims == 3 ? (k == 0 ? "x" : k == 1 ? "y" : "z") : (k == 0 ? "x" : "y"); }

}  // namespace

std::string describeVariable(const SpacetimeProblem& problem, int index) {
  const Scene& scene = problem.scene();
  for (size_t c = 0; c < problem.characters().size(); ++c) {
    const CharacterVariables& cv = problem.characters()[c];
    const std::string& who = scene.characters[c].id;
    const std::vector<std::string> names = scene.characters[c].dofNames();
    for (const DofGroup& g : cv.groups) {
      const int n = static_cast<int>(g.dofs.size());
      if (n == 0) continue;
      auto dof = [&](int d) { return names[static_cast<size_t>(g.dofs[static_cast<size_t>(d)])]; };
      const int blocks = g.blockSize() * g.blockCount();
      if (index >= g.offset && index < g.offset + blocks) {
        const int k = (index - g.offset) / g.blockSize(), within = (index - g.offset) % g.blockSize();
        if (!g.hermite) return who + " " + dof(within) + ", spline control point " + std::to_string(k);
        return who + " " + dof(within % n) + (within < n ? ", position" : ", velocity") + " at breakpoint " +
               at(g.breaks[static_cast<size_t>(k)]);
      }
      if (g.hasBubbles() && index >= g.bubbleOffset && index < g.bubbleOffset + g.bubbleValues)
        for (int k = 0; k + 1 < g.blockCount(); ++k) {
          const int start = g.bubbleStart(k), size = g.bubbleBlockSize(k);
          if (index < start || index >= start + size) continue;
          return who + " " + dof((index - start) % n) + ", bubble " + std::to_string((index - start) / n) +
                 " of the interval " + at(g.breaks[static_cast<size_t>(k)]) + " to " + at(g.breaks[static_cast<size_t>(k + 1)]);
        }
    }
  }
  for (const ContactVariables& ct : problem.contacts()) {
    const std::string what = "contact '" + scene.terms[static_cast<size_t>(ct.term)].id + "'";
    const int forces = ct.blockSize() * static_cast<int>(ct.times.size());
    if (index >= ct.forceOffset && index < ct.forceOffset + forces) {
      const int sample = (index - ct.forceOffset) / ct.blockSize(), within = (index - ct.forceOffset) % ct.blockSize();
      const std::string component =
          ct.resultant ? std::string(within == 0 ? "resultant x" : within == 1 ? "resultant y" : "resultant moment")
                       : "point " + std::to_string(within / ct.forceDims) + " force " + axisName(within % ct.forceDims, ct.forceDims);
      return what + " " + component + " at " + at(ct.times[static_cast<size_t>(sample)]);
    }
    const int points = static_cast<int>(ct.points.points.size());
    if (index >= ct.anchorOffset && index < ct.anchorOffset + 2 * points)
      return what + " point " + std::to_string((index - ct.anchorOffset) / 2) + " anchor " +
             ((index - ct.anchorOffset) % 2 ? "z" : "x");
    if (ct.impact() && index >= ct.impulseOffset && index < ct.impulseOffset + ct.pointForceSize())
      return what + " touch-down impulse, point " + std::to_string((index - ct.impulseOffset) / ct.forceDims) + " " +
             axisName((index - ct.impulseOffset) % ct.forceDims, ct.forceDims);
  }
  for (const FreeEnd& e : problem.freeEnds())
    if (index == e.offset) return "contact '" + scene.terms[static_cast<size_t>(problem.contacts()[static_cast<size_t>(e.contact)].term)].id + "' lift-off instant";
  return "variable " + std::to_string(index);
}

bool isContactForce(const SpacetimeProblem& problem, int index) {
  for (const ContactVariables& ct : problem.contacts()) {
    if (index >= ct.forceOffset && index < ct.forceOffset + ct.blockSize() * static_cast<int>(ct.times.size())) return true;
    if (ct.impact() && index >= ct.impulseOffset && index < ct.impulseOffset + ct.pointForceSize()) return true;
  }
  return false;
}

}  // namespace spacetime
