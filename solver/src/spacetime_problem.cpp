// Assembly of the spacetime problem from a Scene (see spacetime_problem.h).
#include "solver/spacetime_problem.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <charconv>
#include <initializer_list>
#include <cmath>
#include <sstream>
#include <vector>

#include "dynamics/algorithms.h"
#include "dynamics/build_model.h"
#include "dynamics/formula_environment.h"
#include "solver/motion_source.h"

namespace spacetime {
namespace {

// The time as a stream writes it by default (printf's %g: six significant digits), by
// std::to_chars: a stream per label was a fifth of a problem's build (the jump's: 10.9 of 51.0 M
// instructions), and every edit builds one.
std::string at(const std::string& what, double t) {
  char digits[32];
  const std::to_chars_result end = std::to_chars(digits, digits + sizeof digits, t, std::chars_format::general, 6);
  std::string label;
  label.reserve(what.size() + 3 + static_cast<size_t>(end.ptr - digits));
  label.append(what).append(" t=").append(digits, end.ptr);
  return label;
}

// A contact that begins after the clip's start and asks for an impact (the default).
bool touchesDownWithImpact(const TermSpec& t, const Scene& scene) {
  return t.enabled && t.kind == TermKind::Contact && t.impact &&
         t.start > scene.startTime + kTimeTolerance && t.start < scene.endTime - kTimeTolerance;
}

// Times where a character's interval term is imposed: that character's samples inside it and its
// two ends; stance samples (Sample::stance) only when asked for.
std::vector<double> intervalTimes(const Transcription& tr, const std::string& character, double a, double b,
                                  bool stance = false) {
  std::vector<double> times = {a, b};
  for (const Sample& s : tr.samplesIn(a, b, &character))
    if (std::abs(s.time - a) > kTimeTolerance && std::abs(s.time - b) > kTimeTolerance && (stance || !s.stance))
      times.push_back(s.time);
  std::sort(times.begin(), times.end());
  return times;
}

constexpr int kBoxClearanceDensity = 10;  // instants per sample gap where a box clearance holds

// `times` with factor - 1 evenly spaced instants added between each consecutive pair.
std::vector<double> densified(const std::vector<double>& times, int factor) {
  std::vector<double> out;
  for (size_t i = 0; i < times.size(); ++i) {
    out.push_back(times[i]);
    if (i + 1 < times.size())
      for (int k = 1; k < factor; ++k) out.push_back(times[i] + (times[i + 1] - times[i]) * k / factor);
  }
  return out;
}

// True when every body only ever turns about the world z axis (a planar character): then a body
// point's height does not depend on its z coordinate.
bool turnsAboutZOnly(const Model<double>& model) {
  for (const Body<double>& b : model.bodies) {
    if (std::abs(b.X_tree.E(2, 2) - 1) > 1e-12) return false;
    const bool turns = b.joint.type == JointType::Revolute || b.joint.type == JointType::Helical;
    if (turns && std::abs(std::abs(b.joint.axis.z()) - 1) > 1e-12) return false;
  }
  return true;
}

// A planar character's lowest-point features, fewer and exact: points lose their z (a box's
// eight corners become four), a disc facing z is its centre with the radius as margin, and a
// disc whose normal lies in the plane is the two ends of its diameter in the plane (the lamp's
// head: the four corners of its side view). Duplicates go: two identical active rows would
// make the constraints' Jacobian rank-deficient.
std::vector<LowestPointFeature> inPlane(const std::vector<LowestPointFeature>& features) {
  std::vector<LowestPointFeature> out;
  auto add = [&](Eigen::Vector3d p, double margin) {
    p.z() = 0;
    for (const LowestPointFeature& f : out)
      if (!f.isDisc() && (f.point - p).norm() < 1e-12 && f.margin == margin) return;
    out.push_back({p, margin, Eigen::Vector3d::Zero(), 0});
  };
  for (const LowestPointFeature& f : features) {
    const double nz = std::abs(f.discNormal.z());
    if (!f.isDisc()) {
      add(f.point, f.margin);
    } else if (nz > 1 - 1e-12) {
      add(f.point, f.discRadius);
    } else if (nz < 1e-12) {
      const Eigen::Vector3d across = f.discRadius * Eigen::Vector3d::UnitZ().cross(f.discNormal).normalized();
      add(f.point + across, 0);
      add(f.point - across, 0);
    } else {
      out.push_back(f);
    }
  }
  return out;
}

// The ascending coefficients of the order-th derivative in u of base(u) (2u-1)^j, base given by
// its ascending coefficients; `size` of them (the derivatives' top ones zero).
constexpr int kLongestBase = 7;  // the leg bubbles' base
using ShapeCoefficients = std::array<double, kLongestBase + GroupBasis::kCapacity + 1>;
ShapeCoefficients shapeCoefficients(const std::vector<double>& base, int j, int order, size_t* size) {
  ShapeCoefficients c{};
  assert(static_cast<int>(base.size()) <= kLongestBase && j <= GroupBasis::kCapacity);
  std::copy(base.begin(), base.end(), c.begin());
  *size = base.size();
  for (int i = 0; i < j; ++i) {  // times (2u - 1), in place from the top: c_k <- 2 c_(k-1) - c_k
    c[*size] = 2 * c[*size - 1];
    for (size_t k = *size - 1; k > 0; --k) c[k] = 2 * c[k - 1] - c[k];
    c[0] = -c[0];
    ++*size;
  }
  for (int d = 0; d < order; ++d) {
    for (size_t k = 1; k < *size; ++k) c[k - 1] = k * c[k];
    c[*size - 1] = 0;
  }
  return c;
}

// base(u) (2u-1)^j and its derivatives, the polynomials made once per (j, order) and evaluated
// by Horner's rule. Every spline evaluation of a root with bubbles comes here (the validity
// report's dense grid, the outputs' frames); building the polynomial at each call (on the heap
// at first, then on the stack) was 12 %, then 3 %, of a warm solve's run.
class BubbleShapes {
 public:
  explicit BubbleShapes(std::initializer_list<double> base) : base_(base) {
    for (int j = 0; j <= GroupBasis::kCapacity; ++j)
      for (int order = 0; order < kOrders; ++order) {
        size_t size = 0;
        coefficients_.push_back(shapeCoefficients(base_, j, order, &size));
        sizes_.push_back(size);
      }
  }
  double operator()(int j, double u, int order) const {
    size_t size = 0;
    ShapeCoefficients other;
    const ShapeCoefficients* c = &other;
    if (j >= 0 && j <= GroupBasis::kCapacity && order >= 0 && order < kOrders) {
      c = &coefficients_[j * kOrders + order];
      size = sizes_[j * kOrders + order];
    } else {
      other = shapeCoefficients(base_, j, order, &size);
    }
    double v = 0;
    for (size_t k = size; k-- > 0;) v = v * u + (*c)[k];
    return v;
  }

 private:
  static constexpr int kOrders = 5;  // positions to the slope of a third derivative
  std::vector<double> base_;
  std::vector<ShapeCoefficients> coefficients_;
  std::vector<size_t> sizes_;
};

// The order-th derivative in u of the root's bubble j, 16 u^2 (1-u)^2 (2u-1)^j (1 at the
// middle for j = 0; zero with its slope at both ends).
double bubble(int j, double u, int order) {
  static const BubbleShapes shapes({0, 0, 16, -32, 16});
  return shapes(j, u, order);
}

// A leg bubble (DofGroup::legBubbles), 64 u^3 (1-u)^3 (2u-1)^j: zero with its first two
// derivatives at both ends, so the joint it adds to stays C2.
double legBubble(int j, double u, int order) {
  static const BubbleShapes shapes({0, 0, 0, 64, -192, 192, -64});
  return shapes(j, u, order);
}

// A B-spline group's four control points at basis b, with the given weights.
GroupBasis splineBasis(const DofGroup& g, const BSplineBasis& b, const std::array<double, 4>& w) {
  GroupBasis gb;
  const int n = static_cast<int>(g.dofs.size());
  gb.count = 4;
  for (int i = 0; i < 4; ++i) {
    gb.start[i] = g.offset + (b.first + i) * n;
    gb.size[i] = n;
    gb.index[i] = 0;
    gb.weight[i] = w[i];
  }
  return gb;
}

}  // namespace

SpacetimeProblem::SpacetimeProblem(const Scene& scene) : scene_(scene) {}

std::unique_ptr<SpacetimeProblem> SpacetimeProblem::build(const Scene& scene, std::string* error,
                                                          ContactLayout layout) {
  std::unique_ptr<SpacetimeProblem> p(new SpacetimeProblem(scene));
  p->contactLayout_ = layout;
  if (!p->assemble(error)) return nullptr;
  return p;
}

int SpacetimeProblem::characterIndex(const std::string& id) const {
  for (size_t c = 0; c < scene_.characters.size(); ++c)
    if (scene_.characters[c].id == id) return static_cast<int>(c);
  return 0;
}

// Joint speed limits (JointSpec::speedLimit), held at every instant of the validity report's
// dense grid. A joint's speed is piecewise quadratic (the cubic spline's derivative) and peaks
// between the grid's instants: on a grid as dense as the samples, the arm swing of
// tests/solver/speed_limit_test.cpp passed its 3 rad/s by 0.053 rad/s on the dense grid; on the
// dense grid itself it passes it by 1.4e-6 between the grid's instants. The rows are linear in the
// control points. Bounding the derivative's B-spline coefficients instead (the convex hull
// property) would hold everywhere but caps a sharp peak at 75 % of the limit.
void SpacetimeProblem::addJointSpeedLimits() {
  for (size_t c = 0; c < characters_.size(); ++c) {
    const CharacterVariables& cv = characters_[c];
    if (std::none_of(cv.model->bodies.begin(), cv.model->bodies.end(),
                     [](const Body<double>& b) { return b.hasSpeedLimit && b.dofIndex >= 0; }))
      continue;
    const int ci = static_cast<int>(c);
    const std::string label = "joint speed limits " + scene_.characters[c].id;
    for (double time : transcription_.denseGrid(kDenseGridFactor)) {
      const TimeRef r = timeRef(ci, time);
      addResidualAt(std::make_shared<JointSpeedLimitKernel>(cv.model, at(label, time)), r.event,
                    [this, ci, r](InputMap& in, double T) { addMotionInputs(in, ci, r, T, 1); });
    }
  }
}

// Automatic ground clearances (SolverSpec::bodiesAboveGround): each body with geometry keeps its
// lowest-point features above the ground at every sample of its character where it must
// (mustClearGround), except where a clearance term of the scene already holds the same point at
// least as high. Held at the samples and halfway between them: at the samples alone the lamp's head corner dipped
// 2.6 mm between two of them when it chose its own lift-off; halfway too, ~1e-5 m (luxo_jump
// 0.94 s instead of 0.66 s). The validity report checks every body on the dense grid.
void SpacetimeProblem::addGroundClearances() {
  for (size_t c = 0; c < characters_.size(); ++c) {
    const CharacterVariables& cv = characters_[c];
    const CharacterSpec& spec = scene_.characters[c];
    const bool planar = turnsAboutZOnly(*cv.model);
    const std::vector<double> times =
        densified(intervalTimes(transcription_, spec.id, scene_.startTime, scene_.endTime), 2);
    for (const BodySpec& bs : spec.bodies) {
      std::vector<LowestPointFeature> features = lowestPointFeatures(bs.geometry);
      if (planar) features = inPlane(features);
      const int body = cv.model->bodyIndex(bs.id);
      if (features.empty() || body < 0) continue;
      const std::string label = "'" + spec.id + "." + bs.id + "' above the ground";
      for (double time : times) {
        if (!mustClearGround(static_cast<int>(c), body, time)) continue;
        std::vector<LowestPointFeature> held;
        for (const LowestPointFeature& f : features) {
          const bool covered = std::any_of(scene_.terms.begin(), scene_.terms.end(), [&](const TermSpec& t) {
            if (!t.enabled || t.kind != TermKind::Clearance || t.box || t.character != spec.id || t.body != bs.id ||
                time < t.start - kTimeTolerance || time > t.end + kTimeTolerance || t.height < scene_.groundHeight + f.margin)
              return false;
            Eigen::Vector3d d = t.point - f.point;
            if (planar) d.z() = 0;
            return !f.isDisc() && d.norm() < 1e-12;
          });
          if (!covered) held.push_back(f);
        }
        if (held.empty()) continue;
        const TimeRef r = timeRef(static_cast<int>(c), time);
        const int ci = static_cast<int>(c);
        addResidualAt(std::make_shared<GroundClearanceKernel>(cv.model, body, std::move(held), scene_.groundHeight,
                                                              at(label, time)),
                      r.event, [this, ci, r](InputMap& in, double T) { addMotionInputs(in, ci, r, T, 0); });
      }
    }
  }
}

bool SpacetimeProblem::mustClearGround(int c, int body, double t) const {
  if (!scene_.groundEnabled || scene_.characters[c].root == RootKind::Fixed) return false;
  const std::vector<int> touching = activeContacts(c, t);
  return std::none_of(touching.begin(), touching.end(), [&](int j) { return contacts_[j].points.body == body; });
}

std::vector<int> SpacetimeProblem::activeContacts(int c, double t, bool afterEnds) const {
  std::vector<int> active;
  for (size_t j = 0; j < contacts_.size(); ++j)
    if (contacts_[j].character == c && t >= contacts_[j].start - kTimeTolerance &&
        t <= contacts_[j].end + (afterEnds ? -kTimeTolerance : kTimeTolerance))
      active.push_back(static_cast<int>(j));
  return active;
}

std::vector<std::pair<double, double>> SpacetimeProblem::flightPhases(int c) const {
  std::vector<std::pair<double, double>> holds, flights;
  for (const ContactVariables& ct : contacts_)
    if (ct.character == c) holds.emplace_back(ct.start, ct.end);
  std::sort(holds.begin(), holds.end());
  double cursor = scene_.startTime;
  for (const auto& [a, b] : holds) {
    if (a > cursor + kTimeTolerance) flights.emplace_back(cursor, a);
    cursor = std::max(cursor, b);
  }
  if (scene_.endTime > cursor + kTimeTolerance) flights.emplace_back(cursor, scene_.endTime);
  return flights;
}

GroupBasis SpacetimeProblem::groupBasis(int c, const DofGroup& g, double t, int order,
                                        Side side) const {
  if (g.legBubbles) return legBubbleBasis(g, hermiteInterval(c, g, t, side), t, order);
  if (!g.hermite) {
    const BSplineBasis b = g.spline.basis(t);
    return splineBasis(g, b, b.derivative(order));
  }
  const int k = hermiteInterval(c, g, t, side);
  return hermiteBasis(g, k, g.breaks[k], g.breaks[k + 1], t, order, 0, 0, 0, nullptr);
}

GroupBasis SpacetimeProblem::legBubbleBasis(const DofGroup& g, int k, double t, int order) const {
  GroupBasis gb;
  const double a = g.breaks[k], h = g.breaks[k + 1] - a;
  if (h < kTimeTolerance) return gb;
  const double u = std::clamp((t - a) / h, 0.0, 1.0);
  for (int j = 0; j < g.bubblesIn(k); ++j) {
    gb.start[gb.count] = g.bubbleStart(k);
    gb.size[gb.count] = g.bubbleBlockSize(k);
    gb.index[gb.count] = j * static_cast<int>(g.dofs.size());
    gb.weight[gb.count] = legBubble(j, u, order) * std::pow(h, -order);
    ++gb.count;
  }
  return gb;
}

int SpacetimeProblem::hermiteInterval(int c, const DofGroup& g, double t, Side side) const {
  const auto& br = g.breaks;
  int k = static_cast<int>(std::upper_bound(br.begin(), br.end(), t) - br.begin()) - 1;
  k = std::clamp(k, 0, static_cast<int>(br.size()) - 2);
  if (side == Side::Before)  // the interval that ends at t: the last one starting before t
    k = std::clamp(static_cast<int>(std::lower_bound(br.begin(), br.end(), t - kTimeTolerance) -
                                    br.begin()) - 1,
                   0, static_cast<int>(br.size()) - 2);
  // At an interior breakpoint, take the interval on the side that has t's contacts. (An impact
  // repeats its breakpoint; upper_bound already lands after the repeat, on the contact side.)
  else if (side == Side::Contacts && k > 0 && std::abs(t - br[k]) < kTimeTolerance &&
      activeContacts(c, 0.5 * (br[k - 1] + br[k])) == activeContacts(c, t) &&
      activeContacts(c, 0.5 * (br[k] + br[k + 1])) != activeContacts(c, t))
    --k;
  return k;
}

namespace {

// The cubic Hermite basis (h00, h10, h01, h11) and its derivatives in u.
std::array<double, 4> hermite(double u, int order) {
  const double u2 = u * u, u3 = u2 * u;
  switch (order) {
    case 0: return {2 * u3 - 3 * u2 + 1, u3 - 2 * u2 + u, -2 * u3 + 3 * u2, u3 - u2};
    case 1: return {6 * u2 - 6 * u, 3 * u2 - 4 * u + 1, -6 * u2 + 6 * u, 3 * u2 - 2 * u};
    case 2: return {12 * u - 6, 6 * u - 4, -12 * u + 6, 6 * u - 2};
    case 3: return {12, 6, -12, 6};
    default: return {0, 0, 0, 0};
  }
}

}  // namespace

GroupBasis SpacetimeProblem::hermiteBasis(const DofGroup& g, int k, double a, double b, double t,
                                          int order, double rate, double da, double db,
                                          GroupBasis* slope) const {
  GroupBasis gb;
  const double h = b - a;
  const double u = std::clamp((t - a) / h, 0.0, 1.0);
  const std::array<double, 4> w = hermite(u, order);
  const int n = static_cast<int>(g.dofs.size()), size = g.blockSize();
  gb.count = 4;  // index[0] = index[2] = 0: positions; index[1] = index[3] = n: velocities
  gb.start[0] = gb.start[1] = g.offset + k * size;
  gb.start[2] = gb.start[3] = g.offset + (k + 1) * size;
  for (int i = 0; i < 4; ++i) gb.size[i] = size;
  gb.index[1] = gb.index[3] = n;
  // Weight i is c_i(u) h^(e_i): e = -order for positions and bubbles, 1 - order for velocities.
  std::array<double, GroupBasis::kCapacity> power{}, shape{};
  for (int i = 0; i < 4; ++i) {
    power[i] = (i % 2 == 1 ? 1 : 0) - order;
    shape[i] = w[i];
  }
  for (int j = 0; j < g.bubblesIn(k); ++j) {
    gb.start[gb.count] = g.bubbleStart(k);
    gb.size[gb.count] = g.bubbleBlockSize(k);
    gb.index[gb.count] = j * n;
    power[gb.count] = -order;
    shape[gb.count] = bubble(j, u, order);
    ++gb.count;
  }
  // h^e for the few exponents used (-order - 1 ... 1 - order), each std::pow'd once: a call per
  // weight was a third of this function's time in the validity report's dense grid.
  std::array<double, 3> hPower{};
  std::array<bool, 3> known{};
  auto hPow = [&](double e) {
    const int slot = static_cast<int>(e) + order + 1;
    if (!known[slot]) {
      hPower[slot] = std::pow(h, e);
      known[slot] = true;
    }
    return hPower[slot];
  };
  for (int i = 0; i < gb.count; ++i) gb.weight[i] = shape[i] * hPow(power[i]);
  if (slope) {
    // d/dT of c(u) h^e with u = (t - a) / h: u' = (t' - a' - u h') / h, h' = b' - a'.
    *slope = gb;
    const double dh = db - da, du = (rate - da - u * dh) / h;
    const std::array<double, 4> w1 = hermite(u, order + 1);
    for (int i = 0; i < gb.count; ++i) {
      const double next = i < 4 ? w1[i] : bubble(i - 4, u, order + 1);
      slope->weight[i] = next * du * hPow(power[i]) + power[i] * shape[i] * hPow(power[i] - 1) * dh;
    }
  }
  applyHeldStances(g, k, &gb, slope);
  return gb;
}

const DofGroup* SpacetimeProblem::rootGroup(int c) const {
  for (const DofGroup& g : characters_[c].groups)
    if (g.hermite) return &g;
  return nullptr;
}

GroupBasis SpacetimeProblem::groupBasisAt(int c, const DofGroup& g, const TimeRef& r, double T,
                                          int order, GroupBasis* slope) const {
  const double t = r.at(T);
  if (g.legBubbles) {  // only on characters without free ends (leg_bubbles.cpp): never moving
    *slope = GroupBasis{};
    return groupBasis(c, g, t, order, r.rootSide);
  }
  if (!g.hermite) {
    const BSplineBasis b = g.spline.basis(t);
    std::array<double, 4> next{};  // cubic: the fourth derivative vanishes
    if (order + 1 <= 3)
      for (int i = 0; i < 4; ++i) next[i] = b.derivative(order + 1)[i] * r.rate;
    *slope = splineBasis(g, b, next);
    return splineBasis(g, b, b.derivative(order));
  }
  const FreeEnd& e = freeEnds_[r.event];
  return hermiteBasis(g, r.interval, e.map(r.intervalStart, r.eventTime, T),
                      e.map(r.intervalEnd, r.eventTime, T), t, order, r.rate,
                      e.rate(r.intervalStart, r.eventTime), e.rate(r.intervalEnd, r.eventTime), slope);
}

void SpacetimeProblem::addMotionInputs(InputMap& in, int c, double t, int order, Side side) {
  const CharacterVariables& cv = characters_[c];
  const int row0 = in.newRows(cv.dofs);
  for (const DofGroup& g : cv.groups) {
    const int n = static_cast<int>(g.dofs.size());
    if (n == 0) continue;  // Ceres has no zero-size parameter blocks
    const GroupBasis gb = groupBasis(c, g, t, order, side);
    for (int i = 0; i < gb.count; ++i) {
      const int blk = in.block(x_.data() + gb.start[i], gb.size[i]);
      for (int k = 0; k < n; ++k) in.add(row0 + g.dofs[k], blk, gb.index[i] + k, gb.weight[i]);
    }
  }
}

void SpacetimeProblem::addMotionInputs(InputMap& in, int c, const TimeRef& r, double T, int order) {
  if (r.event < 0) {
    addMotionInputs(in, c, r.time, order, r.rootSide);
    return;
  }
  const CharacterVariables& cv = characters_[c];
  const FreeEnd& e = freeEnds_[r.event];
  const int row0 = in.newRows(cv.dofs);
  for (const DofGroup& g : cv.groups) {
    const int n = static_cast<int>(g.dofs.size());
    if (n == 0) continue;
    GroupBasis slope;
    const GroupBasis gb = groupBasisAt(c, g, r, T, order, &slope);
    if (!g.hasBubbles()) {
      // The parameter blocks must not change with T: register every control point the moving
      // time can reach, in order, before the ones in use.
      const int lo = g.spline.basis(r.at(e.lower)).first, hi = g.spline.basis(r.at(e.upper)).first;
      for (int k = lo; k <= hi + 3; ++k) in.block(x_.data() + g.offset + k * n, n);
    }
    for (int i = 0; i < gb.count; ++i) {
      const int blk = in.block(x_.data() + gb.start[i], gb.size[i]);
      for (int k = 0; k < n; ++k)
        in.add(row0 + g.dofs[k], blk, gb.index[i] + k, gb.weight[i], slope.weight[i]);
    }
  }
}

void SpacetimeProblem::setQuadratureScale(InputMap& in, const TimeRef& r, double T) const {
  if (r.event < 0 || r.side == 0) return;
  const FreeEnd& e = freeEnds_[r.event];
  const double h0 = r.side < 0 ? r.eventTime - e.left : e.right - r.eventTime;
  const double h = r.side < 0 ? T - e.left : e.right - T;
  in.objectiveScale = std::sqrt(h / h0);
  in.objectiveScaleSlope = in.objectiveScale * (r.side < 0 ? 1.0 : -1.0) / (2 * h);
}

int ContactVariables::sampleIndex(double t) const {
  for (size_t i = 0; i < times.size(); ++i)
    if (std::abs(times[i] - t) < kTimeTolerance) return static_cast<int>(i);
  return -1;
}

std::pair<int, double> ContactVariables::interpolation(double t) const {
  if (times.size() < 2) return {0, 0.0};
  if (const int exact = sampleIndex(t); exact >= 0) return {exact, 0.0};
  const int i = std::clamp(static_cast<int>(std::upper_bound(times.begin(), times.end(), t) - times.begin()) - 1,
                           0, static_cast<int>(times.size()) - 2);
  return {i, std::clamp((t - times[i]) / (times[i + 1] - times[i]), 0.0, 1.0)};
}

Eigen::MatrixXd ContactVariables::split() const {
  if (!resultant) return Eigen::MatrixXd::Identity(pointForceSize(), pointForceSize());
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(4, 3);
  S(0, 0) = S(2, 0) = 0.5;  // the points' x: half of Fx each
  S(1, 1) = S(3, 1) = 0.5;  // their y: half of Fy each,
  S(1, 2) = -1;             // less and plus D
  S(3, 2) = 1;
  return S;
}

Eigen::MatrixXd ContactVariables::gather() const {
  if (!resultant) return Eigen::MatrixXd::Identity(pointForceSize(), pointForceSize());
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(3, 4);
  G(0, 0) = G(0, 2) = 1;       // Fx
  G(1, 1) = G(1, 3) = 1;       // Fy
  G(2, 1) = -0.5, G(2, 3) = 0.5;  // D
  return G;
}

void SpacetimeProblem::addForceInputs(InputMap& in, int j, double t, double scale) {
  // Forces are linear between the contact's samples; terms imposed between samples (a formula
  // constraint at any instant of a contact) read the two neighbours.
  addForceInputs(in, j, contacts_[j].interpolation(t), scale);
}

void SpacetimeProblem::addForceInputs(InputMap& in, int j, std::pair<int, double> at, double scale) {
  // z = the points' forces, split() times the sample's variables.
  const ContactVariables& cv = contacts_[j];
  const int size = cv.blockSize();
  const Eigen::MatrixXd S = cv.split();
  const int row0 = in.newRows(cv.pointForceSize());
  const auto [i, a] = at;
  auto addSample = [&](int sample, double w) {
    const int blk = in.block(x_.data() + cv.sampleOffset(sample), size);
    for (int r = 0; r < S.rows(); ++r)
      for (int d = 0; d < size; ++d)
        if (S(r, d) != 0) in.add(row0 + r, blk, d, scale * w * S(r, d));
  };
  addSample(i, 1 - a);
  if (a != 0) addSample(i + 1, a);
}

void SpacetimeProblem::setSampleForces(int j, int sample, const std::vector<Eigen::Vector3d>& forces) {
  const ContactVariables& ct = contacts_[j];
  Eigen::VectorXd f(ct.pointForceSize());
  for (int p = 0; p < static_cast<int>(ct.points.points.size()); ++p)
    for (int k = 0; k < ct.forceDims; ++k) f[p * ct.forceDims + k] = forces[static_cast<size_t>(p)][k];
  const Eigen::VectorXd u = ct.gather() * f;
  for (int d = 0; d < ct.blockSize(); ++d) x_[ct.sampleOffset(sample) + d] = u[d];
}

void SpacetimeProblem::addBlockInputs(InputMap& in, int offset, int size, double scale) {
  const int row0 = in.newRows(size);
  const int blk = in.block(x_.data() + offset, size);
  for (int d = 0; d < size; ++d) in.add(row0 + d, blk, d, scale);
}

void SpacetimeProblem::addAnchorInputs(InputMap& in, int j) {
  addBlockInputs(in, contacts_[j].anchorOffset, 2 * static_cast<int>(contacts_[j].points.points.size()));
}

void SpacetimeProblem::addResidual(std::shared_ptr<const Kernel> kernel, const InputMap& inputs) {
  if (kernel->rowCount() == 0) return;
  const int first = static_cast<int>(al_.lambda.size());
  al_.lambda.resize(first + kernel->rowCount(), 0.0);
  auto* residual = new TermResidual(std::move(kernel), inputs, &al_, first);
  problem_->AddResidualBlock(residual, nullptr, inputs.blocks());
  residuals_.push_back(residual);
}

void SpacetimeProblem::addResidualAt(std::shared_ptr<const Kernel> kernel, int event, const Fill& fill) {
  if (event < 0) {
    InputMap in;
    fill(in, 0.0);
    addResidual(std::move(kernel), in);
    return;
  }
  if (kernel->rowCount() == 0) return;
  const int first = static_cast<int>(al_.lambda.size());
  al_.lambda.resize(first + kernel->rowCount(), 0.0);
  MovingInputs moving = [fill](double T) {
    InputMap in;
    fill(in, T);
    return in;
  };
  auto* residual = new TermResidual(std::move(kernel), std::move(moving),
                                    x_.data() + freeEnds_[event].offset, &al_, first);
  problem_->AddResidualBlock(residual, nullptr, residual->blocks());
  residuals_.push_back(residual);
}

SpacetimeProblem::SampleInputs SpacetimeProblem::sampleInputs(int c, double t, bool after) const {
  SampleInputs s;
  s.character = c;
  // The first instant of a flight (Sample::after): the interval that starts at t, without the
  // contacts that end at t.
  s.ref = timeRef(c, t, after ? Side::After : Side::Contacts);
  s.active = activeContacts(c, t, after);
  for (int j : s.active) s.forces.push_back(contacts_[j].interpolation(t));
  return s;
}

void SpacetimeProblem::addSampleInputs(InputMap& in, const SampleInputs& s, double T) {
  for (int order = 0; order < 3; ++order) addMotionInputs(in, s.character, s.ref, T, order);
  for (size_t i = 0; i < s.active.size(); ++i) addForceInputs(in, s.active[i], s.forces[i]);
}

bool SpacetimeProblem::assemble(std::string* error) {
  transcription_ = Transcription::fromScene(scene_);
  const double gravity = scene_.gravity.norm();

  // Variables: layout first (pointers into x_ must stay valid), then values.
  int size = 0;
  for (const CharacterSpec& spec : scene_.characters) {
    CharacterVariables cv;
    cv.model = std::make_shared<const Model<double>>(buildModel(spec, scene_.gravity));
    cv.dofs = cv.model->dofCount();
    cv.weight = cv.model->totalMass() * (gravity > 0 ? gravity : 1.0);
    cv.forceDims = spec.root == RootKind::Planar ? 2 : 3;
    if (cv.dofs == 0) {
      *error = "character '" + spec.id + "' has no degrees of freedom: nothing to solve";
      return false;
    }
    DofGroup actuated, unactuated;
    for (int d = 0; d < cv.dofs; ++d)
      (cv.model->bodies[cv.model->dofBody[d]].actuated ? actuated : unactuated).dofs.push_back(d);
    actuated.spline = transcription_.motion;
    cv.groups.push_back(actuated);
    if (!unactuated.dofs.empty()) {
      unactuated.hermite = true;
      unactuated.breaks = transcription_.breakpoints;
      unactuated.bubbles = std::max(0, scene_.transcription.samplesPerSegment - 2);
      // An impact repeats its breakpoint: one velocity before, one after (positions are made
      // equal by the impact term).
      for (const TermSpec& t : scene_.terms)
        if (touchesDownWithImpact(t, scene_) && t.character == spec.id &&
            std::count_if(unactuated.breaks.begin(), unactuated.breaks.end(),
                          [&](double b) { return std::abs(b - t.start) < kTimeTolerance; }) == 1)
          unactuated.breaks.insert(
              std::lower_bound(unactuated.breaks.begin(), unactuated.breaks.end(), t.start - kTimeTolerance),
              t.start);
      unactuated.extraBubble.assign(unactuated.breaks.size() - 1, 0);
      for (size_t k = 0; k + 1 < unactuated.breaks.size(); ++k)
        if (unactuated.breaks[k + 1] - unactuated.breaks[k] > kTimeTolerance)
          if (transcription_.flightStartsAt(spec.id, unactuated.breaks[k])) unactuated.extraBubble[k] = 1;
      cv.groups.push_back(unactuated);
    }
    for (DofGroup& g : cv.groups) {
      g.offset = size;
      g.bubbleOffset = size + g.blockSize() * g.blockCount();
      if (g.hermite) g.layoutBubbles();
      size += g.variableCount();
    }
    characters_.push_back(cv);
  }
  for (size_t ti = 0; ti < scene_.terms.size(); ++ti) {
    const TermSpec& t = scene_.terms[ti];
    if (!t.enabled || t.kind != TermKind::Contact) continue;
    if (!scene_.groundEnabled) {
      *error = "term '" + t.id + "': a contact needs the ground (ground.enabled is false)";
      return false;
    }
    ContactVariables cv;
    cv.term = static_cast<int>(ti);
    cv.character = characterIndex(t.character);
    const CharacterVariables& ch = characters_[cv.character];
    cv.points.body = ch.model->bodyIndex(t.body);
    cv.points.points = t.points;
    cv.start = t.start;
    cv.end = t.end;
    cv.friction = t.friction;
    cv.forceDims = ch.forceDims;
    cv.holdsRoot = fixesRoot(cv.character, cv.points);
    cv.resultant = contactLayout_ == ContactLayout::Resultants && cv.forceDims == 2 && t.points.size() == 2;
    cv.times = intervalTimes(transcription_, t.character, t.start, t.end, cv.holdsRoot);
    cv.forceOffset = size;
    size += cv.blockSize() * static_cast<int>(cv.times.size());
    cv.anchorOffset = size;
    size += 2 * static_cast<int>(t.points.size());
    if (touchesDownWithImpact(t, scene_) && ch.groups.size() > 1) {
      cv.impulseOffset = size;
      size += cv.pointForceSize();
    }
    contacts_.push_back(cv);
  }
  if (!addFreeEnds(error, &size)) return false;
  layoutLegBubbles(&size);
  layoutHeldStances();
  x_.assign(size, 0.0);
  initialGuess();
  settleHeldStances(&x_);
  for (const FreeEnd& e : freeEnds_) x_[e.offset] = e.current;

  ceres::Problem::Options options;
  options.enable_fast_removal = false;
  problem_ = std::make_unique<ceres::Problem>(options);

  const ObjectiveSpec& obj = scene_.objective;
  for (size_t c = 0; c < characters_.size(); ++c) {
    const CharacterVariables& cv = characters_[c];
    const int ci = static_cast<int>(c);
    const std::string& name = scene_.characters[c].id;
    const bool anyLimits = std::any_of(cv.model->bodies.begin(), cv.model->bodies.end(),
                                       [](const Body<double>& b) { return b.hasPositionLimits; });
    for (const Sample& s : transcription_.samples) {
      if (!physicsAt(ci, s)) continue;
      DynamicsKernel::Options o;
      o.effortWeight = obj.effort * s.weight;
      o.powerWeight = obj.power * s.weight;
      o.weightScale = 1.0 / cv.weight;
      const SampleInputs si = sampleInputs(ci, s.time, s.after);
      const TimeRef r = si.ref;
      std::vector<ContactPoints> cps;
      for (int j : si.active) cps.push_back(contacts_[j].points);
      addResidualAt(std::make_shared<DynamicsKernel>(cv.model, cps, cv.forceDims, o,
                                                     at("dynamics " + name, s.time)),
                    r.event, [this, si](InputMap& in, double T) {
                      addSampleInputs(in, si, T);
                      setQuadratureScale(in, si.ref, T);
                    });
      if (obj.smoothness > 0 && s.weight > 0) {
        const int order = obj.smoothnessOrder;
        addResidualAt(std::make_shared<WeightedValueKernel>(cv.dofs, obj.smoothness * s.weight,
                                                            at("smoothness " + name, s.time)),
                      r.event, [this, ci, r, order](InputMap& in, double T) {
                        addMotionInputs(in, ci, r, T, order);
                        setQuadratureScale(in, r, T);
                      });
      }
      if (anyLimits)
        addResidualAt(std::make_shared<JointLimitKernel>(cv.model, at("joint limits " + name, s.time)),
                      r.event, [this, ci, r](InputMap& in, double T) { addMotionInputs(in, ci, r, T, 0); });
    }
  }

  for (const TermSpec& t : scene_.terms) {
    if (!t.enabled) continue;
    const int ci = characterIndex(t.character);
    const CharacterVariables& cv = characters_[ci];
    const std::string label = toString(t.kind) + " '" + t.id + "'";
    // A kernel at one time of this term, its inputs q^(order) for each listed order.
    auto addAt = [&](std::shared_ptr<const Kernel> kernel, double time, std::vector<int> orders) {
      const TimeRef r = timeRef(ci, time);
      addResidualAt(std::move(kernel), r.event, [this, ci, r, orders](InputMap& in, double T) {
        for (int order : orders) addMotionInputs(in, ci, r, T, order);
      });
    };
    switch (t.kind) {
      case TermKind::Keyframe: {
        if (!checkOutsideWindows(t.time, label, error)) return false;
        std::vector<std::pair<int, double>> targets;
        for (const auto& [dof, value] : t.values) targets.emplace_back(cv.model->dofIndex(dof), value);
        addAt(std::make_shared<TargetKernel>(cv.dofs, targets, at(label, t.time)), t.time, {0});
        break;
      }
      case TermKind::Rest: {
        if (!checkOutsideWindows(t.time, label, error)) return false;
        if (t.body.empty()) {
          // A held stance keeps the root at rest already.
          std::vector<int> held;
          if (const DofGroup* root = rootGroup(ci); root && rootHeldAt(ci, t.time)) held = root->dofs;
          std::vector<std::pair<int, double>> targets;
          for (int d = 0; d < cv.dofs; ++d)
            if (std::find(held.begin(), held.end(), d) == held.end()) targets.emplace_back(d, 0.0);
          addAt(std::make_shared<TargetKernel>(cv.dofs, targets, at(label, t.time)), t.time, {1});
        } else {
          addAt(std::make_shared<BodyRestKernel>(cv.model, cv.model->bodyIndex(t.body), at(label, t.time)),
                t.time, {0, 1});
        }
        break;
      }
      case TermKind::Pin: {
        if (!checkOutsideWindows(t.time, label, error) ||
            (t.until && !checkOutsideWindows(*t.until, label, error)))
          return false;
        const std::vector<double> times =
            t.until ? intervalTimes(transcription_, t.character, t.time, *t.until) : std::vector<double>{t.time};
        for (double time : times)
          addAt(std::make_shared<PinKernel>(cv.model, cv.model->bodyIndex(t.body), t.point, t.position,
                                            t.axes, at(label, time)),
                time, {0});
        break;
      }
      case TermKind::Clearance:
        if (!checkOutsideWindows(t.start, label, error) || !checkOutsideWindows(t.end, label, error))
          return false;
        // Outside-a-box is not convex: held at the samples only, a path cut the box's corner by
        // 8 mm between them (ParticleClearance.PassesOverABox, 40 control points per second).
        // Box clearances are therefore also imposed at kBoxClearanceDensity - 1 instants between
        // consecutive samples (0.4 mm). Height clearances stay at the samples: a smooth path over a
        // flat bound dips 3e-5 m between them (luxo_hurdle), and the extra rows slowed every Luxo
        // scene (luxo_jump: 600 instead of 360 iterations with the ground clearances densified).
        for (double time : densified(intervalTimes(transcription_, t.character, t.start, t.end), t.box ? kBoxClearanceDensity : 1)) {
          const int body = cv.model->bodyIndex(t.body);
          addAt(t.box ? std::make_shared<ClearanceKernel>(cv.model, body, t.point, t.boxMin, t.boxMax,
                                                          at(label, time))
                      : std::make_shared<ClearanceKernel>(cv.model, body, t.point, t.height, at(label, time)),
                time, {0});
        }
        break;
      case TermKind::Contact: break;  // below, per contact variable set
      case TermKind::Formula: break;  // addFormulaTerms
    }
  }

  if (scene_.groundEnabled && scene_.solver.bodiesAboveGround) addGroundClearances();
  addJointSpeedLimits();

  for (size_t j = 0; j < contacts_.size(); ++j) {
    const ContactVariables& ct = contacts_[j];
    const int jj = static_cast<int>(j);
    const CharacterVariables& cv = characters_[ct.character];
    const std::string label = "contact '" + scene_.terms[ct.term].id + "'";
    const std::string& owner = scene_.characters[ct.character].id;
    if (!checkOutsideWindows(ct.start, label, error) ||
        !checkOutsideWindows(ct.end, label, error))
      return false;
    // A contact that does not hold the root (its points on another body, or too few to fix the
    // root) keeps its points still by their motion: anchored at the contact's first instant, at
    // rest there (a touch-down's impact already says so), and without acceleration at every
    // collocation sample - the same collocation that makes the flight obey the dynamics, with as
    // many conditions as the root polynomial has free coefficients. Anchors at every sample
    // instead fix positions only, and a 1e-5 m anchor violation buys a large root acceleration
    // at a sample: the lamp rooted at its head (contacts on its base, a leaf) stopped after 100
    // multiplier updates at objective 66; now it converges to the
    // base-rooted jump. Free lift-offs keep the anchors (their samples move with the end).
    const bool stillByAcceleration = !ct.holdsRoot && ct.freeEnd < 0;
    if (stillByAcceleration) {
      // The points' velocity (order 1) or acceleration (order 2) is zero at `time`.
      auto addPointMotion = [&](int order, double time, const std::string& what) {
        const int c = ct.character;
        const TimeRef r = timeRef(c, time);
        addResidualAt(std::make_shared<ContactPointMotionKernel>(cv.model, ct.points, ct.forceDims, order,
                                                                 at(label + " " + what, time)),
                      r.event, [this, c, r, order](InputMap& in, double T) {
                        for (int o = 0; o <= order; ++o) addMotionInputs(in, c, r, T, o);
                      });
      };
      if (!ct.impact()) addPointMotion(1, ct.times.front(), "at rest");
      for (const Sample& smp : transcription_.samplesIn(ct.start, ct.end, &owner))
        if (smp.weight > 0 && !smp.after && !smp.stance) addPointMotion(2, smp.time, "still");  // collocation nodes
    }
    // A held stance's anchor rows are the same at every sample, and a contact kept still by its
    // motion is anchored at its start: once is enough.
    for (double time : ct.holdsRoot || stillByAcceleration ? std::vector<double>{ct.times.front()} : ct.times) {
      const TimeRef r = timeRef(ct.character, time);
      const int c = ct.character;
      addResidualAt(std::make_shared<ContactAnchorKernel>(cv.model, ct.points, ct.forceDims, scene_.groundHeight,
                                                          at(label + " anchor", time)),
                    r.event, [this, c, r, jj](InputMap& in, double T) {
                      addMotionInputs(in, c, r, T, 0);
                      addAnchorInputs(in, jj);
                    });
    }
    const int points = static_cast<int>(ct.points.points.size());
    // Several contact points on one rigid body make their forces statically indeterminate
    // (a planar base: 4 unknowns for 3 equations per sample; the 3D base: 12 for 6). A small
    // minimum-norm term picks evenly shared loads and removes that null space, which otherwise
    // leaves the Levenberg-Marquardt system singular (CHOLMOD rejected it on the 3D lamp). At
    // weight 1e-3 the effect on solve time varies with the local optimum reached: Luxo jump
    // with 2 threads 3292 -> 1907 iterations; single-threaded jump 15.2 -> 15.4 s, heavy
    // 14.4 -> 11.4 s, hurdle 12.9 -> 25.0 s.
    for (const Sample& smp : transcription_.samplesIn(ct.start, ct.end, &owner)) {
      if (obj.contactForce <= 0 || smp.weight <= 0 || smp.after) continue;
      const TimeRef r = timeRef(ct.character, smp.time);
      const std::pair<int, double> force = ct.interpolation(smp.time);
      const double scale = 1.0 / cv.weight;  // as fractions of the weight
      addResidualAt(std::make_shared<WeightedValueKernel>(ct.pointForceSize(), obj.contactForce * smp.weight,
                                                          at(label + " load sharing", smp.time)),
                    r.event, [this, r, jj, force, scale](InputMap& in, double T) {
                      addForceInputs(in, jj, force, scale);
                      setQuadratureScale(in, r, T);
                    });
    }
    // A contact that ends before the clip does lets go at its end: its force there is zero.
    // The joints are C2, so their accelerations do not jump at lift-off; a force still pushing
    // at that instant would, once removed, accelerate the points into the ground (the root's
    // acceleration jumps by -M_rr^-1 J^T f). With the clearance or the cone at the next samples
    // that leaves a feasible set {f >= 0, M^-1 f <= 0} = {0} on which no multiplier exists.
    const bool releases = letsGo(jj);
    for (double time : ct.times) {
      InputMap in;
      if (releases && time == ct.times.back()) {
        std::vector<std::pair<int, double>> zero;
        for (int d = 0; d < ct.blockSize(); ++d) zero.emplace_back(d, 0.0);
        // On the sample's own variables: the split's rows would repeat Fx = 0.
        addBlockInputs(in, ct.sampleOffset(static_cast<int>(ct.times.size()) - 1), ct.blockSize(), 1.0 / cv.weight);
        addResidual(std::make_shared<TargetKernel>(ct.blockSize(), zero, at(label + " lift-off", time)), in);
        continue;
      }
      addForceInputs(in, jj, time);
      if (ct.resultant)
        addResidual(std::make_shared<ContactWrenchConeKernel>(ct.friction, 1.0 / cv.weight, at(label + " cone", time)),
                    in);
      else
        addResidual(std::make_shared<FrictionConeKernel>(points, ct.forceDims, ct.friction, 1.0 / cv.weight,
                                                         at(label + " cone", time)),
                    in);
    }
    if (ct.impact()) addImpactTerms(jj);
  }
  if (!addFormulaTerms(error)) return false;
  fixHeldVelocities();
  if (!checkFormulasFinite(error)) return false;
  for (const FreeEnd& e : freeEnds_) {
    double* T = x_.data() + e.offset;
    if (!problem_->HasParameterBlock(T)) continue;
    problem_->SetParameterLowerBound(T, 0, e.lower);
    problem_->SetParameterUpperBound(T, 0, e.upper);
  }
  return true;
}

bool SpacetimeProblem::letsGo(int j) const {
  const ContactVariables& ct = contacts_[j];
  if (ct.end >= scene_.endTime - kTimeTolerance) return false;
  // Another contact that carries the same points on past the end (a change of friction, say)
  // keeps them on the ground.
  for (size_t k = 0; k < contacts_.size(); ++k) {
    const ContactVariables& other = contacts_[k];
    if (static_cast<int>(k) == j || other.character != ct.character || other.points.body != ct.points.body ||
        other.start > ct.end + kTimeTolerance || other.end < ct.end + kTimeTolerance)
      continue;
    for (const Eigen::Vector3d& p : ct.points.points)
      for (const Eigen::Vector3d& o : other.points.points)
        if ((p - o).norm() < 1e-9) return false;
  }
  return true;
}

std::vector<int> SpacetimeProblem::simultaneousImpacts(int j) const {
  std::vector<int> group;
  const ContactVariables& ct = contacts_[j];
  for (size_t k = 0; k < contacts_.size(); ++k) {
    const ContactVariables& other = contacts_[k];
    if (other.impact() && other.character == ct.character && std::abs(other.start - ct.start) < kTimeTolerance)
      group.push_back(static_cast<int>(k));
  }
  return group;
}

void SpacetimeProblem::addImpactTerms(int j) {
  const ContactVariables& ct = contacts_[j];
  const CharacterVariables& cv = characters_[ct.character];
  const std::string label = "contact '" + scene_.terms[ct.term].id + "'";
  const double t = ct.start;
  const std::vector<int> group = simultaneousImpacts(j);
  // Impulses are measured as the weight acting over one knot interval, and an impulsive joint
  // torque costs what the same torque impulse spread over one knot interval would cost in the
  // effort integral (tau^2 h = (impulse / h)^2 h); on a refined, non-uniform transcription the
  // mean interval.
  const double h = transcription_.motion.meanKnotSpacing();
  const double impulseScale = 1.0 / (cv.weight * h);
  // One velocity jump for every contact touching down now: the first of them adds it.
  if (group.front() == j) {
    InputMap in;
    addMotionInputs(in, ct.character, t, 0, Side::Before);
    addMotionInputs(in, ct.character, t, 0);
    addMotionInputs(in, ct.character, t, 1, Side::Before);
    addMotionInputs(in, ct.character, t, 1);
    std::vector<ContactPoints> points;
    std::vector<char> held;
    std::string names = label;
    for (int k : group) {
      addBlockInputs(in, contacts_[k].impulseOffset, contacts_[k].pointForceSize());
      points.push_back(contacts_[k].points);
      held.push_back(contacts_[k].holdsRoot);
      if (k != j) names += " and '" + scene_.terms[contacts_[k].term].id + "'";
    }
    addResidual(std::make_shared<ImpactKernel>(cv.model, points, held, ct.forceDims, impulseScale,
                                               scene_.objective.effort / h, at(names + " impact", t)),
                in);
  }
  InputMap imp;
  addBlockInputs(imp, ct.impulseOffset, ct.pointForceSize());
  const int points = static_cast<int>(ct.points.points.size());
  addResidual(std::make_shared<FrictionConeKernel>(points, ct.forceDims, ct.friction, impulseScale,
                                                   at(label + " impulse cone", t)),
              imp);
  // As for the forces: several points on one body share an impulse indeterminately; a small
  // minimum-norm term picks the even split.
  if (scene_.objective.contactForce > 0) {
    InputMap share;
    addBlockInputs(share, ct.impulseOffset, ct.pointForceSize(), impulseScale);
    addResidual(std::make_shared<WeightedValueKernel>(ct.pointForceSize(), scene_.objective.contactForce * h,
                                                      at(label + " impulse sharing", t)),
                share);
  }
}

std::shared_ptr<const expr::Tape> SpacetimeProblem::formulaTape(int c, const std::vector<int>& active,
                                                                const std::string& expression,
                                                                std::string* error) {
  std::string key = std::to_string(c) + "|";
  for (int j : active) key += std::to_string(j) + ",";
  key += "|" + expression;
  if (auto it = formulaTapes_.find(key); it != formulaTapes_.end()) return it->second;
  std::vector<ContactPoints> points;
  for (int j : active) points.push_back(contacts_[j].points);
  expr::Graph g;
  CharacterFormulaEnvironment env(*characters_[c].model, g, points, characters_[c].forceDims);
  std::vector<int> touched;
  for (const ContactVariables& ct : contacts_)
    if (ct.character == c) touched.push_back(ct.points.body);
  env.setContactBodies(std::move(touched));
  const expr::FormulaResult r = expr::parseFormula(expression, g, env);
  if (!r.value) {
    *error = r.error;
    return nullptr;
  }
  // One slot per instruction: a formula that is not finite is traced to the operation where
  // its NaN or infinity is born (checkFormulasFinite). Formulas are short; the slots cost nothing.
  auto tape = std::make_shared<const expr::Tape>(expr::Tape::compile(g, {*r.value}, false));
  formulaTapes_.emplace(key, tape);
  return tape;
}

bool SpacetimeProblem::addFormulaTerms(std::string* error) {
  // A formula at a sample reads the sample's inputs: q, qd, qdd and the active contacts' forces.
  auto addFormula = [&](int c, double time, const std::string& expression, RowKind kind, double scale,
                        double value, const std::string& label, const std::string& source, std::string* why) {
    const SampleInputs si = sampleInputs(c, time);
    auto tape = formulaTape(c, si.active, expression, why);
    if (!tape) return false;
    int inputs = 3 * characters_[c].dofs;
    for (int j : si.active) inputs += contacts_[j].pointForceSize();
    addResidualAt(std::make_shared<FormulaKernel>(tape, inputs, time, kind, scale, value, label, source),
                  si.ref.event, [this, si, kind](InputMap& in, double T) {
                    addSampleInputs(in, si, T);
                    if (kind == RowKind::Objective) setQuadratureScale(in, si.ref, T);
                  });
    return true;
  };
  for (const TermSpec& t : scene_.terms) {
    if (!t.enabled || t.kind != TermKind::Formula) continue;
    const int c = characterIndex(t.character);
    const std::string label = "formula '" + t.id + "'";
    for (double e : t.interval ? std::vector<double>{t.start, t.end} : std::vector<double>{t.time})
      if (!checkOutsideWindows(e, label, error)) return false;
    // An interval formula is imposed where the validity report checks it: at the samples and on
    // the report's dense grid (kDenseGridFactor). At the samples alone, a converged solve could
    // fail its own check between them (q.j2 <= 0.3 over the jump's flight: met at the samples,
    // off by 1.4 mrad between them, exit 4).
    std::vector<double> times =
        t.interval ? intervalTimes(transcription_, t.character, t.start, t.end) : std::vector<double>{t.time};
    if (t.interval) {
      for (double d : transcription_.denseGrid(kDenseGridFactor))
        if (d > t.start + kTimeTolerance && d < t.end - kTimeTolerance) times.push_back(d);
      std::sort(times.begin(), times.end());
      times.erase(std::unique(times.begin(), times.end(), [](double a, double b) { return b - a <= kTimeTolerance; }),
                  times.end());
    }
    const RowKind kind = t.relation == '=' ? RowKind::Equality : RowKind::Inequality;
    const double scale = t.relation == '>' ? -1.0 : 1.0;
    const std::string source = "term '" + t.id + "': formula \"" + t.expression + "\"";
    for (double time : times) {
      std::string why;
      if (!addFormula(c, time, t.expression, kind, scale, t.value, at(label, time), source, &why)) {
        *error = source + ": " + why;
        return false;
      }
    }
  }
  for (const FormulaObjective& f : scene_.objective.formulas) {
    const int c = characterIndex(f.character);
    const std::string source = "objective formula \"" + f.expression + "\"";
    for (const Sample& s : transcription_.samples) {
      if (s.weight <= 0 || f.weight <= 0 || !s.appliesTo(f.character)) continue;
      std::string why;
      if (!addFormula(c, s.time, f.expression, RowKind::Objective, std::sqrt(f.weight * s.weight), 0.0,
                      at("objective formula", s.time), source, &why)) {
        *error = source + ": " + why;
        return false;
      }
    }
  }
  return true;
}

namespace {
// Why an operation's value is not finite though its operands are.
std::string notFiniteBecause(expr::Op op) {
  switch (op) {
    case expr::Op::Div: return "a division by zero";
    case expr::Op::Log: return "the logarithm of a number that is not positive";
    case expr::Op::Sqrt: return "the square root of a negative number";
    case expr::Op::Pow: return "a power with no real value (a negative base, or zero to a negative power)";
    case expr::Op::Tan: return "the tangent of an odd multiple of pi/2";
    case expr::Op::Exp: return "an exponential that overflows";
    case expr::Op::Var: return "an input that is not finite";
    default: return "a value that overflows";
  }
}
}  // namespace

// A formula that evaluates to NaN or infinity (x/0, log(-1)) would reach the solver as Ceres's
// "evaluation failed", naming nothing: it is bad input, named with its term, its time and the
// operation where the NaN or infinity is born, on the motion the solve starts from.
bool SpacetimeProblem::checkFormulasFinite(std::string* error) const {
  for (const TermResidual* r : residuals_) {
    const auto* f = dynamic_cast<const FormulaKernel*>(&r->kernel());
    if (!f) continue;
    const Eigen::VectorXd z = r->inputsNow();
    const std::optional<expr::Op> op = f->tape().firstNonFinite(z.data(), f->time());
    if (!op) continue;
    std::ostringstream why;
    why << f->source() << " is not a finite number at t = " << f->time() << " s of the starting motion: "
        << notFiniteBecause(*op);
    *error = why.str();
    return false;
  }
  return true;
}

void SpacetimeProblem::initialGuess() {
  // Joint trajectories: piecewise-linear through the keyframes of each dof (held outside them),
  // fitted by the spline; dofs without keyframes stay at zero, as the seed started. The root's
  // dofs are interpolated in "flight time", which stands still while a contact holds the
  // character, and the root's vertical translation follows the ballistic arc of each flight
  // phase: a guess that already respects the contact schedule and gravity.
  const CubicBSpline& spline = transcription_.motion;
  const double g = scene_.gravity.norm();
  for (size_t c = 0; c < characters_.size(); ++c) {
    const CharacterVariables& cv = characters_[c];
    const std::string& id = scene_.characters[c].id;
    const std::vector<std::pair<double, double>> flights = flightPhases(static_cast<int>(c));
    const bool hasContacts = std::any_of(contacts_.begin(), contacts_.end(), [&](const ContactVariables& ct) {
      return ct.character == static_cast<int>(c);
    });
    auto flightTime = [&](double t) {  // time spent in flight phases up to t
      double flown = 0;
      for (const auto& [a, b] : flights) flown += std::max(0.0, std::min(t, b) - a);
      return flown;
    };
    std::vector<std::vector<std::pair<double, double>>> keys(cv.dofs);
    for (const TermSpec& t : scene_.terms)
      if (t.enabled && t.kind == TermKind::Keyframe && t.character == id)
        for (const auto& [dof, v] : t.values) keys[cv.model->dofIndex(dof)].emplace_back(t.time, v);
    const std::vector<double> times = spline.sampleTimes(20);
    Eigen::MatrixXd values = Eigen::MatrixXd::Zero(times.size(), cv.dofs);
    for (int d = 0; d < cv.dofs; ++d) {
      const Body<double>& body = cv.model->bodies[cv.model->dofBody[d]];
      const bool rootDof = body.isVirtual || body.parent < 0 ||
                           cv.model->bodies[body.parent].isVirtual;
      const bool useFlightTime = rootDof && hasContacts;
      auto& k = keys[d];
      for (auto& [time, v] : k) time = useFlightTime ? flightTime(time) : time;
      std::sort(k.begin(), k.end());
      const bool vertical = rootDof && body.joint.type == JointType::Prismatic && g > 0 &&
                            std::abs(body.joint.axis.dot(scene_.gravity) / g) > 0.999;
      for (size_t i = 0; i < times.size(); ++i) {
        const double t = useFlightTime ? flightTime(times[i]) : times[i];
        double v = 0;
        if (k.empty()) v = 0;
        else if (t <= k.front().first) v = k.front().second;
        else if (t >= k.back().first) v = k.back().second;
        else
          for (size_t s = 0; s + 1 < k.size(); ++s)
            if (t >= k[s].first && t <= k[s + 1].first) {
              const double a = (t - k[s].first) / std::max(1e-12, k[s + 1].first - k[s].first);
              v = (1 - a) * k[s].second + a * k[s + 1].second;
              break;
            }
        if (vertical)  // ballistic height g (t - a)(b - t) / 2 over each flight phase [a, b]
          for (const auto& [a, b] : flights)
            if (times[i] > a && times[i] < b)
              v += body.joint.axis.dot(-scene_.gravity) * (times[i] - a) * (b - times[i]) / 2;
        values(i, d) = v;
      }
    }
    for (const DofGroup& grp : cv.groups) {
      const int size = static_cast<int>(grp.dofs.size());
      if (size == 0 || grp.legBubbles) continue;  // leg bubbles start at zero
      Eigen::MatrixXd groupValues(values.rows(), size);
      for (int k = 0; k < size; ++k) groupValues.col(k) = values.col(grp.dofs[k]);
      // Fit the B-spline through the target, then read the Hermite data off that fit.
      const Eigen::MatrixXd ctrl = spline.fit(times, groupValues);
      if (!grp.hermite) {
        for (int k = 0; k < spline.controlPointCount(); ++k)
          for (int d = 0; d < size; ++d) x_[grp.offset + k * size + d] = ctrl(k, d);
        continue;
      }
      for (size_t k = 0; k < grp.breaks.size(); ++k) {
        const Eigen::RowVectorXd p = spline.evaluate(ctrl, grp.breaks[k], 0);
        const Eigen::RowVectorXd v = spline.evaluate(ctrl, grp.breaks[k], 1);
        for (int d = 0; d < size; ++d) {
          x_[grp.offset + k * 2 * size + d] = p[d];
          x_[grp.offset + k * 2 * size + size + d] = v[d];
        }
      }
    }
  }
  // Contact forces: the weight shared among the contact's points; anchors under the points.
  for (size_t j = 0; j < contacts_.size(); ++j) {
    const ContactVariables& ct = contacts_[j];
    const CharacterVariables& cv = characters_[ct.character];
    const int points = static_cast<int>(ct.points.points.size());
    const std::vector<Eigen::Vector3d> shared(static_cast<size_t>(points), Eigen::Vector3d(0, cv.weight / points, 0));
    for (size_t k = 0; k < ct.times.size(); ++k) setSampleForces(static_cast<int>(j), static_cast<int>(k), shared);
    const Eigen::VectorXd q = jointState(ct.character, ct.start, 0);
    Data<double> data(*cv.model);
    forwardKinematics(*cv.model, data, q.data());
    for (int p = 0; p < points; ++p) {
      const Eigen::Vector3d w = pointPosition(data, ct.points.body, ct.points.points[p]);
      x_[ct.anchorOffset + 2 * p] = w.x();
      x_[ct.anchorOffset + 2 * p + 1] = w.z();
    }
  }
}

Eigen::VectorXd SpacetimeProblem::jointState(int c, double t, int order) const {
  return jointStateOnSide(c, t, order, Side::Contacts);
}

Eigen::VectorXd SpacetimeProblem::jointStateOnSide(int c, double t, int order, Side side) const {
  const CharacterVariables& cv = characters_[c];
  Eigen::VectorXd out = Eigen::VectorXd::Zero(cv.dofs);
  for (const DofGroup& g : cv.groups) {
    const int n = static_cast<int>(g.dofs.size());
    const GroupBasis gb = groupBasis(c, g, t, order, side);
    for (int i = 0; i < gb.count; ++i)
      for (int k = 0; k < n; ++k)
        out[g.dofs[k]] += gb.weight[i] * x_[gb.start[i] + gb.index[i] + k];
  }
  return out;
}

void SpacetimeProblem::fitBubbles(int c, const DofGroup& g,
                                  const std::function<Eigen::VectorXd(double)>& target) {
  const int n = static_cast<int>(g.dofs.size());
  std::fill(x_.begin() + g.bubbleOffset, x_.begin() + g.offset + g.variableCount(), 0.0);
  for (size_t k = 0; k + 1 < g.breaks.size(); ++k) {
    const double a = g.breaks[k], h = g.breaks[k + 1] - a;
    const int m = g.bubblesIn(static_cast<int>(k));
    if (h < kTimeTolerance || m == 0) continue;  // an impact's repeated breakpoint
    // Interpolate the target at m interior points: the bubbles vanish at the ends, so the
    // Hermite part keeps the breakpoint data.
    Eigen::MatrixXd B(m, m), R(m, n);
    for (int i = 0; i < m; ++i) {
      const double u = (i + 1.0) / (m + 1), t = a + u * h;
      for (int j = 0; j < m; ++j) B(i, j) = bubble(j, u, 0);
      const Eigen::VectorXd want = target(t), have = jointState(c, t, 0);
      for (int d = 0; d < n; ++d) R(i, d) = want[g.dofs[d]] - have[g.dofs[d]];
    }
    const Eigen::MatrixXd coefficients = B.partialPivLu().solve(R);
    for (int j = 0; j < m; ++j)
      for (int d = 0; d < n; ++d) x_[g.bubbleStart(static_cast<int>(k)) + j * n + d] = coefficients(j, d);
  }
}

Eigen::VectorXd SpacetimeProblem::jointStateBefore(int c, double t, int order) const {
  return jointStateOnSide(c, t, order, Side::Before);
}

std::vector<Eigen::Vector3d> SpacetimeProblem::contactImpulses(int j) const {
  const ContactVariables& ct = contacts_[j];
  std::vector<Eigen::Vector3d> out;
  if (!ct.impact()) return out;
  for (size_t p = 0; p < ct.points.points.size(); ++p) {
    Eigen::Vector3d v = Eigen::Vector3d::Zero();
    for (int k = 0; k < ct.forceDims; ++k) v[k] = x_[ct.impulseOffset + p * ct.forceDims + k];
    out.push_back(v);
  }
  return out;
}

std::vector<Eigen::Vector3d> SpacetimeProblem::contactForces(int j, double t) const {
  const ContactVariables& ct = contacts_[j];
  const int points = static_cast<int>(ct.points.points.size());
  std::vector<Eigen::Vector3d> out(points, Eigen::Vector3d::Zero());
  if (ct.times.empty() || t < ct.times.front() - kTimeTolerance || t > ct.times.back() + kTimeTolerance)
    return out;
  // Linear interpolation between the samples around t.
  const auto [i, a] = ct.interpolation(t);
  const size_t i1 = std::min<size_t>(i + 1, ct.times.size() - 1);
  const int size = ct.blockSize();
  const Eigen::VectorXd u = (1 - a) * Eigen::Map<const Eigen::VectorXd>(x_.data() + ct.sampleOffset(i), size) +
                            a * Eigen::Map<const Eigen::VectorXd>(x_.data() + ct.sampleOffset(static_cast<int>(i1)), size);
  const Eigen::VectorXd f = ct.split() * u;
  for (int p = 0; p < points; ++p)
    for (int k = 0; k < ct.forceDims; ++k) out[p][k] = f[p * ct.forceDims + k];
  // A resultant's horizontal force is reported shared in proportion to the points' normal
  // forces: then each point's force is in its own cone exactly when the resultant is in the
  // contact wrench cone (the split the dynamics reads has the same wrench).
  if (ct.resultant && u[1] > 0)
    for (int p = 0; p < points; ++p) out[p].x() = u[0] * out[p].y() / u[1];
  return out;
}

int SpacetimeProblem::initializeFrom(const SpacetimeProblem& previous) {
  const int matched = initializeFrom(*motionSourceOf(previous));
  // The penalty transfers with the motion: it keeps the next solve near the transferred motion
  // instead of first relaxing the constraints.
  if (matched > 0) al_.rho = std::max(al_.rho, previous.al_.rho);
  return matched;
}

int SpacetimeProblem::initializeFrom(const MotionSource& previous) {
  // Each character's counterpart (-1: none, or another body tree); a contact transfers only with
  // its character.
  std::vector<int> counterpart;
  for (size_t c = 0; c < characters_.size(); ++c)
    counterpart.push_back(previous.character(scene_.characters[c].id, characters_[c].dofs));
  int matched = 0;
  // Free lift-off instants first: the root's breakpoints and the contacts' samples follow them.
  for (const FreeEnd& e : freeEnds_) {
    const ContactVariables& ct = contacts_[e.contact];
    if (counterpart[static_cast<size_t>(ct.character)] < 0) continue;
    if (const auto old = previous.contactInterval(scene_.terms[ct.term].id))
      x_[e.offset] = std::clamp(old->second, e.lower, e.upper);
  }
  syncFreeEnds();
  const CubicBSpline& spline = transcription_.motion;
  const double t0 = std::max(spline.start(), previous.start());
  const double t1 = std::min(spline.end(), previous.end());
  auto clampTime = [&](double t) { return std::clamp(t, t0, t1); };
  // A sampled motion's frames are fitted without smoothing (eight samples per segment determine
  // the fit; with the fit's default the joints started 4.6e-6 rad off a 1 kHz file's motion,
  // 9.4e-10 without). Another problem's splines keep the smoothing: unsmoothed, a finer
  // transcription whose knots contain the old ones starts exactly where the last one ended (the
  // 1.2 m rung 61 -> 50 s), but after a stall that only changes the path, and the planar
  // quadruped's hop then ended at its 100 multiplier updates instead of valid (docs/design.md).
  const double fitSmoothing = previous.sampled() ? 0.0 : CubicBSpline::kDefaultSmoothing;
  for (size_t c = 0; c < characters_.size(); ++c) {
    const CharacterVariables& cv = characters_[c];
    const int pc = counterpart[c];
    if (pc < 0) continue;
    ++matched;
    for (const DofGroup& g : cv.groups) {
      const int n = static_cast<int>(g.dofs.size());
      // Leg bubbles start at zero: the joints' B-splines are fitted to the whole previous motion.
      if (n == 0 || g.legBubbles) continue;
      if (!g.hermite) {
        const std::vector<double> times = spline.sampleTimes(8);
        Eigen::MatrixXd values(times.size(), n);
        for (size_t i = 0; i < times.size(); ++i) {
          const Eigen::VectorXd q = previous.jointState(pc, clampTime(times[i]), 0);
          for (int k = 0; k < n; ++k) values(i, k) = q[g.dofs[k]];
        }
        const Eigen::MatrixXd ctrl = spline.fit(times, values, fitSmoothing);
        for (int k = 0; k < ctrl.rows(); ++k)
          for (int d = 0; d < n; ++d) x_[g.offset + k * n + d] = ctrl(k, d);
        continue;
      }
      for (size_t k = 0; k < g.breaks.size(); ++k) {
        // The first of a repeated breakpoint is the state before an impact.
        const bool before = g.beforeImpact(k);
        const double t = clampTime(g.breaks[k]);
        const Eigen::VectorXd q = previous.jointState(pc, t, 0, before);
        const Eigen::VectorXd v = previous.jointState(pc, t, 1, before);
        for (int d = 0; d < n; ++d) {
          x_[g.offset + k * 2 * n + d] = q[g.dofs[d]];
          x_[g.offset + k * 2 * n + n + d] = v[g.dofs[d]];
        }
      }
      fitBubbles(static_cast<int>(c), g, [&](double t) { return previous.jointState(pc, clampTime(t), 0); });
    }
  }
  for (ContactVariables& ct : contacts_) {
    if (counterpart[static_cast<size_t>(ct.character)] < 0) continue;
    const std::string& id = scene_.terms[ct.term].id;
    const int points = static_cast<int>(ct.points.points.size());
    const auto old = previous.contactInterval(id);
    if (!old || previous.contactForces(id, points, ct.forceDims, old->first).empty()) continue;
    for (size_t i = 0; i < ct.times.size(); ++i) {
      // Forces at the old interval's matching instant (the interval may have moved).
      const double u = (ct.times[i] - ct.start) / (ct.end - ct.start);
      setSampleForces(static_cast<int>(&ct - contacts_.data()), static_cast<int>(i),
                      previous.contactForces(id, points, ct.forceDims, old->first + u * (old->second - old->first)));
    }
    const std::vector<double> anchors = previous.anchors(id, points, ct.forceDims);
    for (size_t a = 0; a < anchors.size(); ++a) x_[ct.anchorOffset + static_cast<int>(a)] = anchors[a];
    if (ct.impact()) {
      const std::vector<Eigen::Vector3d> impulses = previous.impulses(id, points, ct.forceDims);
      for (size_t p = 0; p < impulses.size(); ++p)
        for (int k = 0; k < ct.forceDims; ++k) x_[ct.impulseOffset + static_cast<int>(p) * ct.forceDims + k] = impulses[p][k];
    }
  }
  // Multipliers do not transfer (their rows differ), nor their KKT factorisation.
  settleHeldStances(&x_);
  std::fill(al_.lambda.begin(), al_.lambda.end(), 0.0);
  al_.newtonFactors.reset();
  return matched;
}

SpacetimeProblem::WarmStart SpacetimeProblem::warmStartFrom(const Scene& source, const SolutionState& state) {
  if (restore(state)) return WarmStart::Exact;
  for (ContactLayout layout : {ContactLayout::Resultants, ContactLayout::PointForces}) {
    std::string ignored;
    const std::unique_ptr<SpacetimeProblem> previous = build(source, &ignored, layout);
    if (previous && previous->restore(state)) return initializeFrom(*previous) > 0 ? WarmStart::Refitted : WarmStart::None;
  }
  return WarmStart::None;
}

SolutionState SpacetimeProblem::state() const {
  SolutionState s{x_, al_.lambda, al_.rho, al_.newtonFactors};
  settleHeldStances(&s.variables);
  return s;
}

bool SpacetimeProblem::restore(const SolutionState& s) {
  if (s.variables.size() != x_.size() || s.multipliers.size() != al_.lambda.size()) return false;
  std::copy(s.variables.begin(), s.variables.end(), x_.begin());  // parameter blocks point into x_
  syncFreeEnds();
  settleHeldStances(&x_);
  al_.lambda = s.multipliers;
  if (s.rho > 0) al_.rho = s.rho;
  al_.newtonFactors = s.newtonFactors;
  return true;
}

}  // namespace spacetime
