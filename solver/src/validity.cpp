// Validity checks on a dense grid and by forward simulation (see validity.h).
#include "solver/validity.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>
#include <tuple>

#include "core/shape_mesh.h"
#include "dynamics/algorithms.h"
#include "dynamics/contact_points.h"
#include "solver/animation.h"
#include "solver/formula_series.h"
#include "solver/ground_forces.h"

namespace spacetime {
namespace {

double unactuatedResidual(const SpacetimeProblem& problem, int c, double t, const GroundForces& ground,
                          Side side = Side::Contacts) {
  const CharacterVariables& cv = problem.characters()[c];
  const Eigen::VectorXd tau = generalizedForcesAt(problem, c, t, &ground, side);
  double worst = 0;
  for (int d = 0; d < cv.dofs; ++d)
    if (!cv.model->bodies[cv.model->dofBody[d]].actuated) worst = std::max(worst, std::abs(tau[d]));
  return worst / cv.weight;
}

// Integrates q'' = ABA(q, q', tau_actuated(t)) with classical RK4 from the solution's state at
// t0 and records in `check` the largest deviation from the solution's q over [t0, t1]. An
// open-loop simulation of an inconsistent motion can blow up (to 1e104 on a 3D lamp): it stops
// at the first step that leaves the solution by more than FlightCheck::kDivergence or is not
// finite, and says when.
void simulateFlight(const SpacetimeProblem& problem, int c, double t0, double t1, FlightCheck& check,
                    const std::atomic<bool>* cancel) {
  const Model<double>& model = *problem.characters()[c].model;
  const int n = model.dofCount();
  Data<double> data(model);
  // What acts at time t: the actuated joints' torques, at a breakpoint on the given side of it.
  // The ground pushes on no side of a flight's instants (its ends read on the flight's side), so
  // the torques are the RNEA of the motion alone.
  auto loadsAt = [&](double t, Side side) {
    Eigen::VectorXd tau = generalizedForcesAt(problem, c, t, nullptr, side);
    for (int d = 0; d < n; ++d)
      if (!model.bodies[model.dofBody[d]].actuated) tau[d] = 0;
    return tau;
  };
  auto accel = [&](const Eigen::VectorXd& tau, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
    return aba(model, data, q.data(), qd.data(), tau.data(), {});
  };
  // The root's acceleration, and with it the torques, jumps at every breakpoint (its Hermite
  // intervals join with C1 only; the lift-off and the touch-down are breakpoints too), so RK4
  // integrates each interval between them on its own, reading its ends on its side. Steps across
  // them, a step's start reading the previous interval's loads, carried each jump through a
  // sixth of a step: an error proportional to the step (the jump's flight: 9.4e-5 m at 0.5 ms
  // steps, 1.9e-4 at 1 ms, 3.7e-4 at 2 ms; now 1.31e-5, 1.30e-5, 1.29e-5: the motion's own).
  // At 0.5 ms the figures agree with 0.25 ms steps' to 0.3 % (1 ms: 0.7 %).
  const double maxStep = std::min(5e-4, (t1 - t0) / 10);
  std::vector<double> ends{t0};
  for (double b : problem.transcription().breakpoints)
    if (b > t0 + kTimeTolerance && b < t1 - kTimeTolerance) ends.push_back(b);
  ends.push_back(t1);
  Eigen::VectorXd q = problem.jointState(c, t0, 0), qd = problem.jointState(c, t0, 1);
  check.maxPositionError = 0;
  for (size_t piece = 0; piece + 1 < ends.size(); ++piece) {
    const double a = ends[piece], b = ends[piece + 1];
    const int steps = static_cast<int>(std::ceil((b - a) / maxStep));
    const double h = (b - a) / steps;
    // The loads depend on time alone: RK4's two midpoint stages share theirs, and a step's end
    // is the next step's start, so each step evaluates two sets (the RNEA behind them costs more
    // than the ABA).
    Eigen::VectorXd start = loadsAt(a, Side::After);
    for (int s = 0; s < steps; ++s) {
      if (cancel && cancel->load(std::memory_order_relaxed)) return;
      const double t = a + s * h;
      const Eigen::VectorXd mid = loadsAt(t + 0.5 * h, Side::Contacts);
      const Eigen::VectorXd end = loadsAt(t + h, s + 1 == steps ? Side::Before : Side::Contacts);
      const Eigen::VectorXd k1v = qd, k1a = accel(start, q, qd);
      const Eigen::VectorXd k2v = qd + 0.5 * h * k1a, k2a = accel(mid, q + 0.5 * h * k1v, k2v);
      const Eigen::VectorXd k3v = qd + 0.5 * h * k2a, k3a = accel(mid, q + 0.5 * h * k2v, k3v);
      const Eigen::VectorXd k4v = qd + h * k3a, k4a = accel(end, q + h * k3v, k4v);
      start = end;
      q += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
      qd += h / 6 * (k1a + 2 * k2a + 2 * k3a + k4a);
      const double error = (q - problem.jointState(c, t + h, 0)).cwiseAbs().maxCoeff();
      if (!std::isfinite(error) || !qd.allFinite() || error > FlightCheck::kDivergence) {
        check.diverged = true;
        check.divergenceTime = t + h;
        return;
      }
      check.maxPositionError = std::max(check.maxPositionError, error);
    }
  }
}

ImpactCheck checkImpact(const SpacetimeProblem& problem, int j) {
  const ContactVariables& ct = problem.contacts()[j];
  const CharacterVariables& cv = problem.characters()[ct.character];
  const Model<double>& model = *cv.model;
  const int n = model.dofCount();
  ImpactCheck ic;
  ic.contact = problem.scene().terms[ct.term].id;
  ic.time = ct.start;
  const Eigen::VectorXd q = problem.jointStateBefore(ct.character, ct.start, 0);
  const Eigen::VectorXd before = problem.jointStateBefore(ct.character, ct.start, 1);
  const Eigen::VectorXd after = problem.jointState(ct.character, ct.start, 1);
  Data<double> data(model);
  const Eigen::MatrixXd M = crba(model, data, q.data());
  Eigen::VectorXd balance = M * (after - before);
  // J^T L: the generalized force of the points' impulses is the RNEA of those point forces
  // alone (no motion, no gravity), with the opposite sign.
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n);
  // Every contact touching down at the same instant shares the velocity jump.
  for (int k : problem.simultaneousImpacts(j)) {
    const ContactVariables& other = problem.contacts()[k];
    balance += rnea(model, data, q.data(), zero.data(), zero.data(),
                    contactPointForces(std::vector<ContactPoints>{other.points},
                                       problem.variables().data() + other.impulseOffset, other.forceDims),
                    false);
  }
  const std::vector<Eigen::Vector3d> impulses = problem.contactImpulses(j);
  ic.minNormalImpulse = 1e300;
  for (const Eigen::Vector3d& l : impulses) {
    ic.minNormalImpulse = std::min(ic.minNormalImpulse, l.y());
    if (l.y() > 0)
      ic.maxFrictionRatio = std::max(ic.maxFrictionRatio, std::hypot(l.x(), l.z()) / (ct.friction * l.y()));
  }
  for (int d = 0; d < n; ++d) {
    if (model.bodies[model.dofBody[d]].actuated)
      ic.maxJointImpulse = std::max(ic.maxJointImpulse, std::abs(balance[d]));
    else
      ic.maxBalanceError = std::max(ic.maxBalanceError, std::abs(balance[d]));
  }
  auto fastestPoint = [&](const Eigen::VectorXd& qd) {
    forwardKinematics(model, data, q.data(), qd.data(), static_cast<const double*>(nullptr));
    double fastest = 0;
    for (const Eigen::Vector3d& p : ct.points.points)
      fastest = std::max(fastest, pointVelocity(data, ct.points.body, p).norm());
    return fastest;
  };
  ic.speedBefore = fastestPoint(before);
  ic.maxSpeedAfter = fastestPoint(after);
  return ic;
}

// The side of its instant a sample is read on (Sample::after: the flight's).
Side sideOf(const Sample& s) { return s.after ? Side::After : Side::Contacts; }

// The unactuated residual at the samples and on the dense grid (ValidityReport's
// maxUnactuatedResidual* and segmentResidualDense), with the ground forces from groundAt (cached
// by the caller, whose contact checks read the same instants). False when stopped.
template <class GroundAt, class Stopped>
bool scanDenseResidual(const SpacetimeProblem& problem, const std::vector<double>& dense, GroundAt&& groundAt,
                       Stopped&& stopped, ValidityReport& r) {
  const Transcription& tr = problem.transcription();
  r.segmentResidualDense.assign(static_cast<size_t>(tr.motion.segmentCount()), 0.0);
  for (size_t c = 0; c < problem.characters().size(); ++c) {
    const int ci = static_cast<int>(c);
    for (const Sample& s : tr.samples)
      if (problem.physicsAt(ci, s))
        r.maxUnactuatedResidualSamples =
            std::max(r.maxUnactuatedResidualSamples,
                     unactuatedResidual(problem, ci, s.time, groundAt(ci, s.time, sideOf(s)), sideOf(s)));
    // The dense grid, ten times finer again over the grid step on each side of every contact's
    // start and end, where the root's acceleration and the ground force jump. Before the flight
    // was collocated from its first instant (Sample::after), luxo_jump's residual was 0 at the
    // lift-off, 0.0052 x weight 0.02 ms after and under 0.001 1.2 ms after, and the uniform grid
    // alone reported 0.0031 (found replaying the files in MuJoCo at 4 kHz).
    std::vector<double> times = dense;
    const double step = dense.size() > 1 ? dense[1] - dense[0] : 0;
    for (const ContactVariables& ct : problem.contacts()) {
      if (ct.character != ci || step <= 0) continue;
      for (double edge : {ct.start, ct.end})
        for (int k = -10; k <= 10; ++k) {
          const double t = edge + k * step / 10;
          if (t >= dense.front() && t <= dense.back()) times.push_back(t);
        }
    }
    for (double t : times) {
      if (stopped()) return false;
      const double v = unactuatedResidual(problem, ci, t, groundAt(ci, t));
      double& segment = r.segmentResidualDense[static_cast<size_t>(tr.motion.segmentOf(t))];
      segment = std::max(segment, v);
      if (v > r.maxUnactuatedResidualDense) {
        r.maxUnactuatedResidualDense = v;
        r.worstDenseTime = t;
      }
    }
  }
  return true;
}

}  // namespace

double sampleUnactuatedResidual(const SpacetimeProblem& problem, int c, const Sample& s) {
  return unactuatedResidual(problem, c, s.time, groundForcesAt(problem, c, s.time, sideOf(s)), sideOf(s));
}

ValidityReport checkDenseResidual(const SpacetimeProblem& problem, int denseFactor) {
  ValidityReport r;
  r.denseFactor = denseFactor;
  const auto groundAt = [&](int c, double t, Side side = Side::Contacts) { return groundForcesAt(problem, c, t, side); };
  scanDenseResidual(problem, problem.transcription().denseGrid(denseFactor), groundAt, [] { return false; }, r);
  return r;
}

ValidityReport checkValidity(const SpacetimeProblem& problem, int denseFactor, const std::atomic<bool>* cancel) {
  ValidityReport r;
  auto stopped = [&] { return r.cancelled = r.cancelled || (cancel && cancel->load(std::memory_order_relaxed)); };
  r.denseFactor = denseFactor;
  const Scene& scene = problem.scene();
  const Transcription& tr = problem.transcription();
  const std::vector<double> dense = tr.denseGrid(denseFactor);
  r.minNormalForce = problem.contacts().empty() ? 0 : 1e300;
  // Ground forces (an NNLS each) by character, time and side, solved once: the residual checks
  // and the contact checks below read the same instants.
  std::map<std::tuple<int, double, Side>, GroundForces> groundCache;
  auto groundAt = [&](int c, double t, Side side = Side::Contacts) -> const GroundForces& {
    auto [it, fresh] = groundCache.try_emplace({c, t, side});
    if (fresh) it->second = groundForcesAt(problem, c, t, side);
    return it->second;
  };
  if (!scanDenseResidual(problem, dense, groundAt, stopped, r)) return r;
  for (const TermSpec& t : scene.terms) {
    if (stopped()) return r;
    if (!t.enabled) continue;
    const int c = problem.characterIndex(t.character);
    const Model<double>& model = *problem.characters()[c].model;
    Data<double> data(model);
    auto pointAt = [&](double time, const Eigen::Vector3d& p) {
      const Eigen::VectorXd q = problem.jointState(c, time, 0);
      forwardKinematics(model, data, q.data());
      return pointPosition(data, model.bodyIndex(t.body), p);
    };
    switch (t.kind) {
      case TermKind::Pin: {
        std::vector<double> times = {t.time};
        if (t.until)
          for (double s : dense)
            if (s >= t.time && s <= *t.until) times.push_back(s);
        for (double s : times) {
          const Eigen::Vector3d p = pointAt(s, t.point);
          for (int a = 0; a < 3; ++a)
            if (t.axes[a]) r.maxPinError = std::max(r.maxPinError, std::abs(p[a] - t.position[a]));
        }
        break;
      }
      case TermKind::Rest:
        r.maxRestSpeed = std::max(r.maxRestSpeed, problem.jointState(c, t.time, 1).cwiseAbs().maxCoeff());
        break;
      case TermKind::Clearance:
        for (double s : dense) {
          if (s < t.start || s > t.end) continue;
          const Eigen::Vector3d p = pointAt(s, t.point);
          const double outside = t.box ? std::max((p - t.boxMax).maxCoeff(), (t.boxMin - p).maxCoeff())
                                       : p.y() - t.height;
          if (-outside > r.maxClearanceViolation) {
            r.maxClearanceViolation = -outside;
            r.worstClearanceTime = s;
            r.worstClearanceTerm = t.id;
          }
        }
        break;
      default: break;
    }
  }
  // Every body's geometry above the ground on the dense grid, wherever the solver's automatic
  // ground clearances hold it (SpacetimeProblem::mustClearGround; a contact's own points are
  // checked below).
  if (scene.groundEnabled)
    for (size_t c = 0; c < problem.characters().size(); ++c) {
      if (stopped()) return r;
      const CharacterSpec& spec = scene.characters[c];
      const Model<double>& model = *problem.characters()[c].model;
      Data<double> data(model);
      for (double s : dense) {
        const Eigen::VectorXd q = problem.jointState(static_cast<int>(c), s, 0);
        forwardKinematics(model, data, q.data());
        for (const BodySpec& body : spec.bodies) {
          if (body.geometry.kind == GeometryKind::None) continue;
          const int b = model.bodyIndex(body.id);
          if (b < 0 || !problem.mustClearGround(static_cast<int>(c), b, s)) continue;
          const Transform<double>& X = data.X_world[b];  // world point = E^T p + r
          const double depth =
              scene.groundHeight - lowestHeight(body.geometry, X.E.transpose(), X.r);
          if (depth > r.maxGroundPenetration) {
            r.maxGroundPenetration = depth;
            r.worstGroundPenetrationTime = s;
            r.worstGroundPenetrationBody = spec.id + "." + body.id;
          }
        }
      }
    }
  // Joint position and speed limits on the dense grid (the solver holds positions at the samples
  // and speeds on this same grid).
  for (size_t c = 0; c < problem.characters().size(); ++c) {
    if (stopped()) return r;
    const Model<double>& model = *problem.characters()[c].model;
    const std::string& character = scene.characters[c].id;
    for (const Body<double>& b : model.bodies) {
      if (b.dofIndex < 0) continue;
      r.hasPositionLimits = r.hasPositionLimits || b.hasPositionLimits;
      r.hasSpeedLimits = r.hasSpeedLimits || b.hasSpeedLimit;
    }
    for (double s : dense) {
      const Eigen::VectorXd q = problem.jointState(static_cast<int>(c), s, 0);
      const Eigen::VectorXd qd = problem.jointState(static_cast<int>(c), s, 1);
      for (const Body<double>& b : model.bodies) {
        if (b.dofIndex < 0) continue;
        const int d = b.dofIndex;
        if (b.hasPositionLimits) {
          const double excess = std::max(q[d] - b.upper, b.lower - q[d]);
          if (excess > r.maxJointLimitExcess) {
            r.maxJointLimitExcess = excess;
            r.worstJointLimitTime = s;
            r.worstJointLimit = character + "." + b.jointName;
          }
        }
        if (b.hasSpeedLimit) {
          const double excess = std::abs(qd[d]) - b.speedLimit;
          if (excess > r.maxJointSpeedExcess) {
            r.maxJointSpeedExcess = excess;
            r.worstJointSpeedTime = s;
            r.worstJointSpeed = character + "." + b.jointName;
          }
        }
      }
    }
  }
  for (size_t j = 0; j < problem.contacts().size(); ++j) {
    if (stopped()) return r;
    const ContactVariables& ct = problem.contacts()[j];
    const Model<double>& model = *problem.characters()[ct.character].model;
    Data<double> data(model);
    const std::vector<Eigen::Vector3d> anchors = [&] {
      const Eigen::VectorXd q = problem.jointState(ct.character, ct.start, 0);
      forwardKinematics(model, data, q.data());
      std::vector<Eigen::Vector3d> a;
      for (const auto& p : ct.points.points) a.push_back(pointPosition(data, ct.points.body, p));
      return a;
    }();
    // The dense grid in the contact's interval, and its samples.
    std::vector<double> times = ct.times;
    for (double s : dense)
      if (s >= ct.start && s <= ct.end) times.push_back(s);
    const double weight = problem.characters()[ct.character].weight;
    for (double s : times) {
      const Eigen::VectorXd q = problem.jointState(ct.character, s, 0);
      forwardKinematics(model, data, q.data());
      for (size_t p = 0; p < ct.points.points.size(); ++p) {
        const Eigen::Vector3d w = pointPosition(data, ct.points.body, ct.points.points[p]);
        r.maxContactSlip = std::max(r.maxContactSlip, std::hypot(w.x() - anchors[p].x(), w.z() - anchors[p].z()));
        r.maxContactPenetration = std::max(r.maxContactPenetration, scene.groundHeight - w.y());
      }
      // The recovered ground forces are cone-edge combinations, so they push and stay in the
      // cone by construction; the solver's own variables, checked at the samples, are not.
      std::vector<std::vector<Eigen::Vector3d>> forceSets = {groundAt(ct.character, s)[j]};
      if (ct.sampleIndex(s) >= 0) forceSets.push_back(problem.contactForces(static_cast<int>(j), s));
      for (const std::vector<Eigen::Vector3d>& f : forceSets)
        for (size_t p = 0; p < f.size(); ++p) {
          r.minNormalForce = std::min(r.minNormalForce, f[p].y());
          // Pulling beyond 1e-6 of the contact's own character's weight (the solver's tolerance).
          if (f[p].y() < -1e-6 * weight) r.contactsPushOnly = false;
          const double tangential = std::hypot(f[p].x(), f[p].z());
          // The exact cone: the solver imposes an inscribed pyramid, so this is conservative.
          r.maxConeViolation = std::max(r.maxConeViolation, (tangential - ct.friction * f[p].y()) / weight);
          if (f[p].y() >= 0.01 * weight)
            r.maxFrictionRatio = std::max(r.maxFrictionRatio, tangential / (ct.friction * f[p].y()));
        }
    }
  }
  for (size_t j = 0; j < problem.contacts().size(); ++j) {
    const ContactVariables& ct = problem.contacts()[j];
    if (!ct.impact()) continue;
    const CharacterVariables& cv = problem.characters()[ct.character];
    r.impacts.push_back(checkImpact(problem, static_cast<int>(j)));
    const ImpactCheck& i = r.impacts.back();
    // The impulse tolerance: the solver's, on the weight acting over one knot interval.
    const double scale = cv.weight * problem.transcription().motion.meanKnotSpacing();
    if (i.minNormalImpulse < -1e-6 * scale) r.contactsPushOnly = false;
    for (const Eigen::Vector3d& l : problem.contactImpulses(static_cast<int>(j)))
      r.maxConeViolation = std::max(r.maxConeViolation, (std::hypot(l.x(), l.z()) - ct.friction * l.y()) / scale);
  }
  r.contactsInFrictionCone = r.maxConeViolation <= 1e-6;  // fraction of weight, as above
  // Formula constraints, evaluated by the same formula language the graph widget plots with.
  for (const TermSpec& term : scene.terms) {
    if (stopped()) return r;
    if (term.kind != TermKind::Formula) continue;
    const CharacterSpec* spec = scene.character(term.character);
    if (!spec) continue;
    const int c = static_cast<int>(spec - scene.characters.data());
    std::vector<double> times;
    if (term.interval) {
      for (double t : dense)
        if (t >= term.start - 1e-12 && t <= term.end + 1e-12) times.push_back(t);
    } else {
      times.push_back(term.time);
    }
    if (times.empty()) continue;
    FormulaCheck check;
    check.term = term.id;
    const FormulaSeries series =
        evaluateFormulaSeries(scene, sampleAnimationAt(problem, times).characters[c], term.expression);
    check.error = series.error;
    for (size_t k = 0; k < series.values.size(); ++k) {
      // NaN compares false with everything: std::max(0.0, NaN) is 0, a pass. A value that is not
      // a number fails the check, named.
      if (!std::isfinite(series.values[k])) {
        if (check.error.empty()) {
          std::ostringstream why;
          why << "not a finite number at t = " << times[k] << " s";
          check.error = why.str();
          check.worstTime = times[k];
        }
        check.maxViolation = 1e300;
        continue;
      }
      const double gap = series.values[k] - term.value;
      const double violation = term.relation == '<' ? std::max(0.0, gap)
                               : term.relation == '>' ? std::max(0.0, -gap)
                                                      : std::abs(gap);
      if (violation > check.maxViolation) {
        check.maxViolation = violation;
        check.worstTime = times[k];
      }
    }
    r.maxFormulaViolation = std::max(r.maxFormulaViolation, check.maxViolation);
    r.formulas.push_back(check);
  }
  // Flight phases of every character that has contacts.
  for (size_t c = 0; c < problem.characters().size(); ++c) {
    std::vector<const ContactVariables*> mine;
    for (const ContactVariables& ct : problem.contacts())
      if (ct.character == static_cast<int>(c)) mine.push_back(&ct);
    if (mine.empty()) continue;
    const std::vector<std::pair<double, double>> flights = problem.flightPhases(static_cast<int>(c));
    const Model<double>& model = *problem.characters()[c].model;
    Data<double> data(model);
    for (const auto& [a, b] : flights) {
      FlightCheck fc;
      fc.character = model.name;
      fc.start = a;
      fc.end = b;
      simulateFlight(problem, static_cast<int>(c), a, b, fc, cancel);
      if (stopped()) return r;
      r.forwardSimulationDiverged = r.forwardSimulationDiverged || fc.diverged;
      for (double s : dense) {
        if (s < a || s > b) continue;
        const Eigen::VectorXd q = problem.jointState(static_cast<int>(c), s, 0);
        forwardKinematics(model, data, q.data());
        double lowest = 1e300;
        for (const ContactVariables* ct : mine)
          for (const auto& p : ct->points.points) lowest = std::min(lowest, pointPosition(data, ct->points.body, p).y());
        fc.maxRootLift = std::max(fc.maxRootLift, lowest - scene.groundHeight);
      }
      r.maxForwardSimulationError = std::max(r.maxForwardSimulationError, fc.maxPositionError);
      r.flights.push_back(fc);
    }
  }
  return r;
}

std::vector<ValidityCheck> validityChecklist(const ValidityReport& r) {
  std::vector<ValidityCheck> out;
  auto check = [&](std::string name, double value, double limit, std::string unit) {
    out.push_back({std::move(name), value, limit, std::move(unit), value <= limit, std::nullopt, false});
  };
  auto yes = [&](std::string name, bool ok) {
    out.push_back({std::move(name), ok ? 0.0 : 1.0, 0.0, "", ok, std::nullopt, true});
  };
  check("unactuated residual at the samples", r.maxUnactuatedResidualSamples, 1e-6, "× weight");
  check("unactuated residual on the dense grid (×" + std::to_string(r.denseFactor) + ")",
        r.maxUnactuatedResidualDense, kDenseResidualLimit, "× weight");
  out.back().time = r.worstDenseTime;
  check("pin error", r.maxPinError, 1e-4, "m");
  check("contact slip", r.maxContactSlip, 1e-4, "m");
  check("contact penetration", r.maxContactPenetration, 1e-4, "m");
  yes("contacts only push", r.contactsPushOnly);
  yes("contact forces in their friction cones", r.contactsInFrictionCone);
  check("clearance violation (dense grid)" +
            (r.worstClearanceTerm.empty() ? std::string() : " of '" + r.worstClearanceTerm + "'"),
        r.maxClearanceViolation, 1e-3, "m");
  if (!r.worstClearanceTerm.empty()) out.back().time = r.worstClearanceTime;
  check("speed at the rest terms", r.maxRestSpeed, 1e-4, "m/s or rad/s");
  // Height clearances hold at the samples; between them a smooth path dips ~1e-5 m.
  check("bodies above the ground (dense grid)" +
            (r.worstGroundPenetrationBody.empty() ? std::string() : ": '" + r.worstGroundPenetrationBody + "'"),
        r.maxGroundPenetration, 1e-3, "m");
  if (!r.worstGroundPenetrationBody.empty()) out.back().time = r.worstGroundPenetrationTime;
  // Position limits hold at the samples; between them a joint pressing on its limit overshoots
  // by a few mrad (luxo_power_formula: 3.6 mrad at j3), far below what an animator sees. 10 mrad
  // (0.57 degrees) passes that and fails a limit ignored between the samples.
  if (r.hasPositionLimits) {
    check("joint limits (dense grid)" + (r.worstJointLimit.empty() ? std::string() : ": '" + r.worstJointLimit + "'"),
          r.maxJointLimitExcess, 1e-2, "rad or m");
    if (!r.worstJointLimit.empty()) out.back().time = r.worstJointLimitTime;
  }
  if (r.hasSpeedLimits) {
    check("joint speed limits (dense grid)" + (r.worstJointSpeed.empty() ? std::string() : ": '" + r.worstJointSpeed + "'"),
          r.maxJointSpeedExcess, 1e-4, "rad/s or m/s");
    if (!r.worstJointSpeed.empty()) out.back().time = r.worstJointSpeedTime;
  }
  for (const FormulaCheck& f : r.formulas) {
    check("formula '" + f.term + "'" + (f.error.empty() ? "" : " (" + f.error + ")"),
          f.error.empty() ? f.maxViolation : 1e300, 1e-5, "");
    out.back().time = f.worstTime;
  }
  for (const FlightCheck& f : r.flights) {
    char span[64];
    std::snprintf(span, sizeof span, "%.3g-%.3g s", f.start, f.end);
    if (f.diverged) {
      char when[64];
      std::snprintf(when, sizeof when, " (diverges at %.3g s)", f.divergenceTime);
      out.push_back({"forward simulation of " + f.character + "'s flight " + span + when,
                     FlightCheck::kDivergence, 0.01, "m or rad", false, f.divergenceTime});
    } else {
      check("forward simulation of " + f.character + "'s flight " + span, f.maxPositionError, 0.01, "m or rad");
    }
  }
  for (const ImpactCheck& i : r.impacts) {
    check("impact '" + i.contact + "': impulse balance", i.maxBalanceError, 1e-6, "N s");
    check("impact '" + i.contact + "': speed after", i.maxSpeedAfter, 1e-4, "m/s");
    yes("impact '" + i.contact + "': ground only pushes", i.minNormalImpulse >= 0);
    for (size_t k = out.size() - 3; k < out.size(); ++k) out[k].time = i.time;
  }
  return out;
}

}  // namespace spacetime
