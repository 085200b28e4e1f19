// Feasibility restoration (see restoration.h).
#include "solver/restoration.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "raw_rows.h"
#include "solver/quadratic_program.h"

namespace spacetime {

using raw::Clock;
using raw::RawEvaluator;
using raw::RawRows;
using raw::secondsSince;
using raw::SpMat;
using raw::SpRow;
using raw::Variables;
using raw::Vec;

namespace {

// Rows this close to their bound (or past it) are elastic when the linearised inequalities
// admit no point.
constexpr double kElasticMargin = 0.05;
// Rows further than this from their bound are left out of the programs unless a step crosses
// them (see Restoration::step).
constexpr double kScreen = 0.1;
// Below this largest row the programs' own accuracy, not the constraints, may stop the steps.
constexpr double kAccuracyFloor = 1e-6;
// The second-order verdict (restoration.h): at most kSecondOrderSteps steps on the merit's exact
// second-order model, certified at the first whose model, damped by at most
// kSecondOrderDamping, is convex and falls by less than kSecondOrderStationary of the merit - an
// approximate second-order stationary point: no curvature below -1e-4, and no fall the model
// sees beyond 1e-6 of the violation. The speed-limited jump's stalls (15 rad/s on every joint)
// pass at once (one thread: fall 3e-8) or after a few steps (two threads: a curvature of about
// -1e-5 there, which the damping covers); the feasible 1.5 m rung's stalls are far from it
// (their models need inertia corrections of 0.04 and 4.4, and the merit falls 0.3-2 % a step).
constexpr int kSecondOrderSteps = 15;
constexpr double kSecondOrderDamping = 1e-4;
constexpr double kSecondOrderStationary = 1e-6;

// Levenberg-Marquardt's rule on the damping, for the Gauss-Newton and the second-order steps
// alike: it starts here, falls after a step that lowers the merit and rises after one that
// does not (which is undone).
constexpr double kInitialDamping = 1e-6;
double dampingAfterProgress(double damping) { return std::max(1e-12, damping / 3); }
double dampingAfterFailure(double damping) { return 10 * damping; }

// "N steps", or "1 step".
std::string stepCount(int steps) { return std::to_string(steps) + (steps == 1 ? " step" : " steps"); }

// The reason a positive minimum of the violation gives.
std::string positiveMinimumReason(const RestorationResult& r) {
  std::ostringstream why;
  why << "minimising the violation alone ends at a positive minimum: largest row " << r.violation
      << ", 1/2 |c|^2 = " << r.merit << " after " << stepCount(r.steps);
  return why.str();
}

// min 1/2 dx^T M dx + b.dx subject to C dx <= d.
QuadraticProgram hardProgram(const SpMat& M, const Vec& b, const SpRow& C, const Vec& d) {
  QuadraticProgram qp;
  qp.hessian = M;
  qp.gradient = b;
  qp.equalities.resize(0, M.cols());
  qp.equalityTargets.resize(0);
  qp.inequalities = C;
  qp.inequalityBounds = d;
  return qp;
}

// The same with the rows `elastic` of C relaxed: variables [dx; v], rows C_i dx - v_i <= d_i,
// and 1/2 |v|^2 in the objective.
QuadraticProgram elasticProgram(const SpMat& M, const Vec& b, const SpRow& C, const Vec& d,
                                const std::vector<int>& elastic) {
  const int n = static_cast<int>(M.cols()), k = static_cast<int>(elastic.size());
  std::vector<Eigen::Triplet<double>> t;
  for (int col = 0; col < M.outerSize(); ++col)
    for (SpMat::InnerIterator e(M, col); e; ++e) t.emplace_back(static_cast<int>(e.row()), static_cast<int>(e.col()), e.value());
  for (int j = 0; j < k; ++j) t.emplace_back(n + j, n + j, 1.0);
  QuadraticProgram qp;
  qp.hessian.resize(n + k, n + k);
  qp.hessian.setFromTriplets(t.begin(), t.end());
  qp.gradient = Vec::Zero(n + k);
  qp.gradient.head(n) = b;
  qp.equalities.resize(0, n + k);
  qp.equalityTargets.resize(0);
  t.clear();
  for (int row = 0; row < C.outerSize(); ++row)
    for (SpRow::InnerIterator e(C, row); e; ++e) t.emplace_back(row, static_cast<int>(e.col()), e.value());
  for (int j = 0; j < k; ++j) t.emplace_back(elastic[j], n + j, -1.0);
  qp.inequalities.resize(C.rows(), n + k);
  qp.inequalities.setFromTriplets(t.begin(), t.end());
  qp.inequalityBounds = d;
  return qp;
}

}  // namespace

struct Restoration::State {
  SpacetimeProblem& problem;
  Variables vars;
  RawEvaluator evaluator;
  std::string error;
  const raw::RowKinds kinds;
  QpWorkspace hard, elastic;  // the two programs' patterns, analysed once
  double effortMetric = 0;
  int threads = 1;

  State(SpacetimeProblem& p, int threadCount, double metric)
      : problem(p), vars(p.ceresProblem()), evaluator(p, vars, std::max(1, threadCount)), kinds(evaluator),
        effortMetric(metric), threads(std::max(1, threadCount)) {
    if (!p.freeEnds().empty() || evaluator.anyMoving()) error = "free contact ends are bounded variables";
  }
  // The largest row violation, and the merit 1/2 sum of the rows' squared violations.
  double violation(const Vec& values) const {
    double worst = 0;
    for (int r = 0; r < evaluator.rows(); ++r) worst = std::max(worst, rowViolation(evaluator.kind(r), values[r]));
    return worst;
  }
  double merit(const Vec& values) const {
    double m = 0;
    for (int r = 0; r < evaluator.rows(); ++r) m += std::pow(rowViolation(evaluator.kind(r), values[r]), 2);
    return 0.5 * m;
  }
};

Restoration::Restoration(SpacetimeProblem& problem, int threads, double effortMetric)
    : state_(std::make_unique<State>(problem, threads, effortMetric)) {}
Restoration::~Restoration() = default;
bool Restoration::ready() const { return state_->error.empty(); }
const std::string& Restoration::error() const { return state_->error; }

RestorationStep Restoration::step(double damping, bool secondOrder) {
  State& st = *state_;
  const Clock::time_point start = Clock::now();
  RestorationStep step;
  auto finish = [&](const std::string& reason) {
    step.reason = reason;
    step.seconds = secondsSince(start);
    return step;
  };
  if (!ready()) return finish(st.error);
  RawRows rows;
  if (!st.evaluator.evaluate(&rows, true)) return finish("a row is not finite");
  step.violationBefore = step.violationAfter = st.violation(rows.values);
  step.meritBefore = step.meritAfter = st.merit(rows.values);

  const int n = st.vars.tangent;
  const SpRow Jc = raw::selectRows(rows.jacobian, st.kinds.equality);
  const SpRow Jg = raw::selectRows(rows.jacobian, st.kinds.inequality);
  const Vec c = raw::selectValues(rows.values, st.kinds.equality), g = raw::selectValues(rows.values, st.kinds.inequality);
  // The model: 1/2 dx^T M dx + b.dx is 1/2 |c + J_c dx|^2 + damping/2 |dx|_W^2 less a constant,
  // W = I + effortMetric J_r^T J_r.
  SpMat metric(n, n);
  metric.setIdentity();
  if (st.effortMetric > 0) {
    const SpRow Jr = raw::selectRows(rows.jacobian, st.kinds.objective);
    metric += st.effortMetric * SpMat(SpMat(Jr.transpose()) * Jr);
  }
  SpMat M = SpMat(Jc.transpose()) * Jc + damping * metric;
  // The rows' own curvature, sum_r v_r grad^2 row_r with v the violations (c, and max(0, g) for
  // the inequalities): the merit's exact Hessian is J^T J plus this.
  SpMat curvature(n, n);
  if (secondOrder) {
    Vec v = Vec::Zero(st.evaluator.rows());
    for (int r : st.kinds.equality) v[r] = rows.values[r];
    for (int r : st.kinds.inequality) v[r] = std::max(0.0, rows.values[r]);
    const raw::Triplets t = st.evaluator.curvature(v, st.threads);
    curvature.setFromTriplets(t.begin(), t.end());  // its lower triangle, which the programs read
    M += curvature;
  }
  const Vec b = Jc.transpose() * c;
  // Tight: near a feasible point the step is of the size of the violation, and an inexact
  // interior point leaves rows whose multipliers are nearly zero off by mu / z.
  QpOptions options;
  options.tolerance = 1e-13;
  options.acceptableTolerance = 1e-9;
  options.convex = !secondOrder;

  // Screening: the programs hold only the rows within kScreen of their bound (a few hundred of
  // the jump's 4332). That is exact, not an approximation: a convex program's minimum over fewer
  // rows is its minimum over all of them if it meets the others, which is checked, and any it
  // crosses join and the program is solved again.
  std::vector<int> held;  // indices into st.kinds.inequality
  for (Eigen::Index i = 0; i < g.size(); ++i)
    if (g[i] > -kScreen) held.push_back(static_cast<int>(i));
  const bool violated = g.size() > 0 && g.maxCoeff() > 0;
  Vec dx;
  QpResult result;
  for (int round = 0;; ++round) {
    const SpRow C = raw::selectRows(Jg, held);
    const Vec d = -raw::selectValues(g, held);
    // The hard program (every held row as it is) is a model of the merit only where no
    // inequality is violated now (dx = 0 is then one of its points, so its minimum does not
    // raise the merit); otherwise, or if it has no point, the elastic program is: variables
    // [dx; v], rows g_i + J_i dx - v_i <= 0 for the rows within kElasticMargin, 1/2 |v|^2 in
    // the objective.
    step.elastic = false;
    const Clock::time_point t0 = Clock::now();
    if (!violated) result = solveQuadraticProgram(hardProgram(M, b, C, d), options, &st.hard);
    if (violated || !result.converged) {
      std::vector<int> elastic;  // indices into `held`
      for (size_t i = 0; i < held.size(); ++i)
        if (g[held[i]] > -kElasticMargin) elastic.push_back(static_cast<int>(i));
      result = solveQuadraticProgram(elasticProgram(M, b, C, d, elastic), options, &st.elastic);
      step.elastic = true;
    }
    step.qpSeconds += secondsSince(t0);
    step.qpIterations += result.iterations;
    if (!result.converged) return finish("the restoration program was not solved: " + result.reason);
    dx = result.x.head(n);
    // The rows left out that the step crosses (linearised) join, and the program is solved again.
    const Vec linear = g + Jg * dx;
    std::vector<char> isHeld(static_cast<size_t>(g.size()), 0);
    for (int i : held) isHeld[static_cast<size_t>(i)] = 1;
    bool added = false;
    for (Eigen::Index i = 0; i < g.size(); ++i)
      if (!isHeld[static_cast<size_t>(i)] && linear[i] > 0) {
        held.push_back(static_cast<int>(i));
        added = true;
      }
    if (!added) break;
    std::sort(held.begin(), held.end());
    if (round >= 4) return finish("the screened rows kept changing");
  }
  step.meritPredicted = 0.5 * (c + Jc * dx).squaredNorm() + 0.5 * (g + Jg * dx).cwiseMax(0.0).squaredNorm();
  if (secondOrder) {
    step.meritPredicted += 0.5 * dx.dot(curvature.selfadjointView<Eigen::Lower>() * dx);
    step.shift = result.shift;
  }

  const std::vector<double> before = st.vars.save();
  st.vars.plus(before, dx);
  RawRows after;
  if (!st.evaluator.evaluate(&after, false)) {
    st.vars.load(before);
    return finish("the step leads to rows that are not finite");
  }
  step.taken = true;
  step.violationAfter = st.violation(after.values);
  step.meritAfter = st.merit(after.values);
  return finish("");
}

RestorationResult Restoration::minimiseViolation(double tolerance, int maxSteps, Clock::time_point deadline,
                                                const std::atomic<bool>* cancel) {
  State& st = *state_;
  const Clock::time_point start = Clock::now();
  RestorationResult out;
  RawRows rows;
  if (!ready() || !st.evaluator.evaluate(&rows, false)) {
    out.reason = ready() ? "a row is not finite" : st.error;
    return out;
  }
  out.violation = st.violation(rows.values);
  out.merit = st.merit(rows.values);
  double damping = kInitialDamping;
  int sinceProgress = 0;
  // The steps stopped lowering the merit: a positive minimum, unless the violation is down at
  // the programs' own accuracy.
  auto stoppedAtMinimum = [&] {
    if (out.violation > kAccuracyFloor) out.outcome = RestorationResult::Outcome::PositiveMinimum;
    else out.reason = "at the programs' accuracy";
  };
  while (out.violation > tolerance) {
    if (out.steps >= maxSteps || Clock::now() > deadline) {
      out.reason = "out of steps or time";
      break;
    }
    if (cancel && cancel->load()) {
      out.reason = "cancelled";
      break;
    }
    const std::vector<double> before = st.vars.save();
    const RestorationStep s = step(damping);
    ++out.steps;
    // First-order certificate of a positive minimum: the convex linearised merit, nearly
    // undamped, has its minimum where the motion is (no direction lowers the violation). Not
    // claimed near the programs' accuracy (a largest row of about 1e-7: rows whose multipliers
    // are nearly zero sit mu / z off their bound), where the jump, feasible, stopped at 7.8e-8
    // when asked for 1e-8.
    if (s.taken && damping <= 1e-6 && s.meritBefore - s.meritPredicted <= 1e-9 * s.meritBefore &&
        s.violationBefore > kAccuracyFloor) {
      st.vars.load(before);
      out.outcome = RestorationResult::Outcome::PositiveMinimum;
      break;
    }
    if (s.taken && s.meritAfter < s.meritBefore) {
      const double decrease = (s.meritBefore - s.meritAfter) / s.meritBefore;
      out.violation = s.violationAfter;
      out.merit = s.meritAfter;
      damping = dampingAfterProgress(damping);
      // A positive minimum: with little damping the steps stop lowering the merit.
      sinceProgress = decrease < 1e-6 && damping <= 1e-6 ? sinceProgress + 1 : 0;
      if (sinceProgress >= 3) {
        stoppedAtMinimum();
        break;
      }
    } else {
      if (s.taken) st.vars.load(before);
      damping = dampingAfterFailure(damping);
      if (damping > 1e8) {
        // Even a step as short as the damping allows does not lower the merit.
        stoppedAtMinimum();
        break;
      }
    }
  }
  if (out.violation <= tolerance) out.outcome = RestorationResult::Outcome::Feasible;
  const std::string steps = stepCount(out.steps);
  std::ostringstream why;
  switch (out.outcome) {
    case RestorationResult::Outcome::Feasible:
      why << "minimising the violation alone met the constraints (" << out.violation << ") in " << steps;
      break;
    case RestorationResult::Outcome::PositiveMinimum:
      why << positiveMinimumReason(out);
      break;
    case RestorationResult::Outcome::Undecided:
      why << "minimising the violation alone reached a largest row of " << out.violation << " (1/2 |c|^2 = "
          << out.merit << ") after " << steps << " without settling (" << out.reason << ")";
      break;
  }
  out.reason = why.str();
  out.seconds = secondsSince(start);
  return out;
}

bool Restoration::certifySecondOrderMinimum(RestorationResult* result, Clock::time_point deadline) {
  if (result->outcome != RestorationResult::Outcome::Undecided || result->violation <= kAccuracyFloor) return false;
  State& st = *state_;
  double damping = kInitialDamping;
  bool certified = false;
  int kept = 0;
  for (int k = 0; k < kSecondOrderSteps && !certified && result->violation > kAccuracyFloor && Clock::now() <= deadline;
       ++k) {
    const std::vector<double> before = st.vars.save();
    const RestorationStep s = step(damping, true);
    certified = s.taken && damping <= kSecondOrderDamping && s.shift == 0 &&
                s.meritBefore - s.meritPredicted <= kSecondOrderStationary * s.meritBefore;
    if (certified || !(s.taken && s.meritAfter < s.meritBefore)) {
      st.vars.load(before);  // a certifying step only measures; a rejected one is undone
      damping = dampingAfterFailure(damping);
    } else {
      ++result->steps, ++kept;
      result->violation = s.violationAfter;
      result->merit = s.meritAfter;
      damping = dampingAfterProgress(damping);
    }
  }
  if (!certified) {
    if (kept) {
      std::ostringstream more;
      more << "; " << stepCount(kept) << " on the second-order model then reached " << result->violation
           << " (1/2 |c|^2 = " << result->merit << ") without a minimum";
      result->reason += more.str();
    }
    return false;
  }
  std::ostringstream why;
  why << positiveMinimumReason(*result) << ", where the merit's exact second-order model is convex and falls by less than "
      << kSecondOrderStationary << " of it";
  result->outcome = RestorationResult::Outcome::PositiveMinimum;
  result->reason = why.str();
  return true;
}

}  // namespace spacetime
