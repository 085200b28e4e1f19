// The `sqp` method (see sqp.h): elastic SQP steps with an l1-merit line search, finished by the
// Newton polish, with the augmented Lagrangian as the fallback.
#include "solver/sqp.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "program_steps.h"
#include "solver/quadratic_program.h"

namespace spacetime {
namespace {

using raw::appendTriplets;
using raw::Clock;
using raw::kAtBound;
using raw::kMargin;
using raw::kMaxRounds;
using raw::RawEvaluator;
using raw::RawRows;
using raw::secondsSince;
using raw::SpRow;
using raw::Triplets;
using raw::Variables;
using raw::Vec;

// The exact Hessian of the Lagrangian is indefinite far from feasibility (docs/design.md,
// "Newton steps on the augmented Lagrangian's inner problem"); above this violation the
// programs use the Gauss-Newton one, J_r^T J_r, convex by construction - until the line search
// cuts a step to kCreepingStep or less: that model then leaves out curvature the constraints
// have over the step (of the biped's rejected full steps' merit above the linear model, 96-100 %
// was in its contact points' motion rows), and the exact Hessian is used from there on. The
// hurdle, the heavy lamp, the ladder's 0.3 and 0.9 m rungs and the doubled hurdle then take 15,
// 20, 13, 22 and 14 steps instead of 20, 35, 24, 30 and 27, to the same optima; the jump and
// the 3D lamp are never cut that far (docs/design.md, SQP).
constexpr double kGaussNewtonAbove = 1e-3;
constexpr double kCreepingStep = 1.0 / 16;
// Steps cut to kCreepingStep or less this many times in a row do not follow the constraints'
// curvature in either model (the biped's: 1/128-1/512 for 50 steps, lowering the violation 0.4 %
// each): they hand over to the augmented Lagrangian, whose damped least-squares steps do. Of the
// scenes whose steps converge none had two such steps in a row (the hurdle, the heavy lamp, the
// ladder's 0.3 and 0.9 m rungs, the doubled hurdle: one each; the jump, the 3D lamp: none); those
// that hand over crept in runs of ten (the biped from its sixth step, the 1.2 m rung from its
// 14th, the two-hop scene from its 13th).
constexpr int kMaxCreepingSteps = 3;
// Steps whose programs keep at least this share of the l1 violation in their elastic slacks,
// this many in a row, hand over too: the linearised constraints cannot be met near the iterate
// (a local infeasible point of the violation, which no step rule gets past). On the scenes whose
// steps converge no program kept more than 2 % (one program of the power-formula scene, whose
// steps hand over by creeping, kept 0.92, once); where the steps hand over later the share stays
// at 0.96-0.99 for ten steps and more (the 1.2 m rung from its 17th step, the quadruped from its
// 13th), the steps creeping meanwhile.
constexpr double kTrappedShare = 0.9;
constexpr int kMaxTrappedSteps = 3;
// Warm steps whose programs each needed the inertia correction's shift at kLargeShift or more
// (the shift metric's units), SolverOptions::sqpShiftedStepsLimit in a row, stop: such a program's
// step is a damped gradient step, and they converge linearly. The shipped jump at s = 3, split
// after its converged solve: 17 full steps each at a shift of 0.81, ½|r|² 13.90 -> 12.34 where
// its optimum is 11.69; where such steps converged their shift fell below 0.07 by the second
// step (the 1.2 m rung's split transcription 0.66, then 0.0066) or a cut step's proximal
// damping took its place.
constexpr double kLargeShift = 0.1;
// Steps within the tolerance that stop approaching a KKT point hand over: this many in a row
// whose stationarity fell by less than this factor. The power-formula scene's exact-Hessian
// programs need a shift of ~190 (its objective is not convex) and its feasible steps then lowered
// the objective 0.012 a step while the stationarity rose from 1.0e-5 to 1.9e-5, for 40 steps,
// before the step limit handed it over (docs/design.md, SQP).
constexpr int kStagnantSteps = 10;
constexpr double kStagnantFall = 0.9;
// The l1 penalty: exact once above the multipliers (N&W Theorem 17.3); raised tenfold while the
// elastic programs keep more than half the violation (steering), up to the cap.
constexpr double kInitialPenalty = 100, kMaxPenalty = 1e8;
// A hard program's multipliers up to this raise the penalty at any distance (the particle's
// quadratic program: one step); above it, far from feasibility, they are the linearisation's
// artefact (3e7 at the jump's default guess) and the elastic program is solved instead.
constexpr double kHardMultiplierCap = 1e4;
constexpr double kElasticCurvature = 1e-6;  // keeps the slacks' block of the program definite
constexpr double kArmijo = 1e-4;
// Second-order corrections of a rejected full step, each from the last corrected point while it
// lowers the l1 violation by this factor (IPOPT's max_soc and kappa_soc). Near the solution the
// jump's full steps move the forces far along flat directions and their violation is second
// order (1.8e-4 -> 2.4e-2 at the full step, 1.9e-3, 2.5e-4, 3.1e-5 after one, two, three
// corrections); far from it (Gauss-Newton programs) one correction, as more changed the path
// of the 0.9 m rung and the doubled hurdle, which then handed over.
constexpr int kMaxCorrections = 4;
constexpr double kCorrectionContraction = 0.99;
// Proximal damping of the steps from the augmented Lagrangian's near-feasible point
// (sqpStepsNearFeasible): delta times the shift metric added to the exact Hessian, raised to
// max(kProximalStart, 10 delta) after a step the line search cut to kCreepingStep or less and
// divided by 3 after a full one (to 0 below kProximalFloor), as Levenberg and Marquardt damp a
// Newton step. There the undamped programs' steps run along directions of nearly no curvature
// (|d|inf 5-7 on the 0.9 m rung, against 0.07-0.09 damped) that the merit accepts only at
// 1/2048: 40 such steps moved its objective 69.50 -> 69.37, while damped ones reach its optimum,
// 65.649, in 13.
constexpr double kProximalStart = 0.1, kProximalGrowth = 10, kProximalShrink = 3, kProximalFloor = 1e-8;
// Stationarity: |grad f + J^T y|_inf relative to max(1, |grad f|_inf), IPOPT's acceptable level.
// Where the polish finishes it reaches 1e-8; steps whose programs need the inertia correction
// can converge linearly (the jump's did, when its shift damped the forces as the angles: 35
// steps to this level, 1e-8 would have taken hundreds).
constexpr double kStationary = 1e-6;

std::string toShortString(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2g", v);
  return text;
}

// Where the steps stop with the last program elastic: the terms whose rows hold its slacks
// (`slacks`: problem row, slack), most first, at most three, as "; its last program left 0.0546
// of the violation unmet, on LABEL (0.0187), ...": the rows the linearised constraints could not
// meet there (two contradictory pins: the pin the program gives up; the ladder's long rungs'
// creeping steps: the start and end keys' base x and the landing impact's horizontal row,
// docs/design.md, SQP).
std::string describeSlacks(const RawEvaluator& evaluator, const std::vector<std::pair<int, double>>& slacks,
                           double tolerance) {
  double total = 0;
  std::map<size_t, double> byTerm;  // term index -> its rows' slacks
  std::vector<int> first;
  for (size_t t = 0; t < evaluator.terms().size(); ++t) first.push_back(evaluator.firstRow(t));
  for (const auto& [row, slack] : slacks) {
    total += slack;
    const size_t term = static_cast<size_t>(std::upper_bound(first.begin(), first.end(), row) - first.begin()) - 1;
    byTerm[term] += slack;
  }
  if (!(total > tolerance)) return "";
  std::vector<std::pair<double, size_t>> order;
  for (const auto& [term, slack] : byTerm) order.emplace_back(slack, term);
  std::stable_sort(order.begin(), order.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  std::string out = "; its last program left " + toShortString(total) + " of the violation unmet, on ";
  for (size_t i = 0; i < order.size() && i < 3 && order[i].first > std::max(tolerance, 0.01 * total); ++i) {
    const TermResidual* term = evaluator.terms()[order[i].second];
    out += (i ? ", " : "") + (term ? term->kernel().label() : std::string("a row")) + " (" + toShortString(order[i].first) + ")";
  }
  return out;
}

struct Merit {
  double f = 0;          // 1/2 |r|^2
  double violation = 0;  // largest row: |c|, max(0, g)
  double l1 = 0;         // |c|_1 + |max(0, g)|_1
};

// The steps of solveSqp; `nearFeasible`: those of sqpStepsNearFeasible (warm, proximally damped,
// the start restored where they fail, with no hand-over).
SolverSummary runSqp(SpacetimeProblem& problem, const SolverOptions& options, const ProgressCallback& callback,
                     const std::atomic<bool>* cancel, bool nearFeasible) {
  const Clock::time_point start = Clock::now();
  SolverOptions al = options;
  al.method = SolverMethod::AugmentedLagrangian;
  // A warm start (an edit of a solved scene) steps from the earlier solve's multipliers.
  const bool warm = (options.warmStart || nearFeasible) && problem.augmentedLagrangian().rho > 0;
  if (!options.validate().empty() || !problem.freeEnds().empty()) {
    if (nearFeasible) {
      SolverSummary s;
      s.method = SolverMethod::Sqp;
      s.reason = "not run: free contact ends or invalid options";
      return s;
    }
    SolverSummary s = solveSpacetime(problem, al, callback, cancel);
    s.method = SolverMethod::Sqp;
    return s;
  }
  const Clock::time_point deadline = options.deadlineFrom(start);
  // Steps that have not converged within a third of the budget hand over to the augmented
  // Lagrangian while it has time to finish: the humanoid's programs take ~4 s, its 60 steps
  // spent 250 s of 300, and the hand-over stopped unconverged at the time limit.
  const Clock::time_point handOverBy = start + (deadline - start) / 3;
  const SolutionState initial = problem.state();
  const Variables vars(problem.ceresProblem());
  const int threads = std::max(1, options.threads);
  RawEvaluator evaluator(problem, vars, threads);
  const int n = vars.tangent, rowCount = evaluator.rows();
  const raw::RowKinds kinds(evaluator);
  const std::vector<int>&objective = kinds.objective, &equality = kinds.equality, &inequality = kinds.inequality;
  const int me = static_cast<int>(equality.size());
  const Vec metric = raw::shiftMetric(problem, vars);
  auto meritOf = [&](const Vec& v) {
    Merit m;
    m.f = 0.5 * raw::selectValues(v, objective).squaredNorm();
    for (int r : equality) {
      m.l1 += std::abs(v[r]);
      m.violation = std::max(m.violation, std::abs(v[r]));
    }
    for (int r : inequality) {
      m.l1 += std::max(0.0, v[r]);
      m.violation = std::max(m.violation, v[r]);
    }
    return m;
  };

  SolverSummary summary;
  summary.method = SolverMethod::Sqp;
  AugmentedLagrangianState& state = problem.augmentedLagrangian();
  Vec y = Vec::Zero(rowCount);  // multipliers per row: equalities free, inequalities >= 0
  double nu = kInitialPenalty, lastViolation = 1e300, lastPolishViolation = 1e300;
  double lastReport = 0;
  QpWorkspace hardWorkspace, elasticWorkspace;  // the two programs' patterns differ
  std::string why;
  std::vector<std::pair<int, double>> lastSlacks;  // the last elastic program's: problem row, slack
  bool done = false;
  auto handOverMultipliers = [&](double rho, const Vec& values) {
    raw::handOverMultipliers(evaluator, y, values, rho, &state);
  };
  auto polish = [&] { return raw::polishInto(problem, options, threads, deadline, cancel, &summary); };

  // The rows active in the last program solved (per row of the problem): the next exact-Hessian
  // program's guess (QpOptions::activeGuess). Near the constraints the active set changes by a
  // few rows between programs, and the active-set steps from the guess solve a program on one
  // factorisation and a solve per change instead of ~15 interior-point iterations; its inactive
  // rows' multipliers are then exactly zero (an interior point leaves each ~mu/s), so fewer rows
  // stay held by their multiplier. The far programs (Gauss-Newton) get no guess: between them
  // the active set changes by hundreds of rows (the 3D lamp), and a guess only costs its solves.
  std::vector<char> wasActive;
  std::vector<double> feasibleKkt;  // the stationarity of the feasible steps in a row
  bool exactHessian = false;  // from the first step cut to kCreepingStep or less on
  if (warm) {
    // Next to the earlier optimum the exact Hessian's programs with its multipliers and active
    // set (the first program's guess) take Newton's steps.
    exactHessian = true;
    wasActive.assign(static_cast<size_t>(rowCount), 0);
    for (int r = 0; r < rowCount; ++r) {
      if (evaluator.kind(r) == RowKind::Objective) continue;
      const double lambda = state.lambda[evaluator.multiplier(r)];
      y[r] = evaluator.kind(r) == RowKind::Equality ? lambda : std::max(0.0, lambda);
      wasActive[static_cast<size_t>(r)] = evaluator.kind(r) == RowKind::Inequality && lambda > 0;
    }
  }
  int creepingSteps = 0;      // in a row
  double proximal = 0;        // the damping delta (kProximalStart), near feasibility only
  int trappedSteps = 0;       // in a row
  int shiftedSteps = 0;       // in a row: programs that needed a shift of kLargeShift or more
  RawRows rows;
  if (!evaluator.evaluate(&rows, true)) why = "the rows at the starting point are not finite";
  for (int step = 0; why.empty() && !done; ++step) {
    const Merit merit = meritOf(rows.values);
    const SpRow A = raw::selectRows(rows.jacobian, equality);
    const Vec r = raw::selectValues(rows.values, objective), c = raw::selectValues(rows.values, equality);
    const Vec g = raw::selectValues(rows.values, inequality);
    const Vec grad = raw::transposeTimes(rows.jacobian, objective, r);  // J_r^T r, J_r not copied
    const double kkt = (grad + rows.jacobian.transpose() * y).lpNorm<Eigen::Infinity>() /
                       std::max(1.0, grad.lpNorm<Eigen::Infinity>());
    summary.sqpSteps = step;
    if (callback && secondsSince(start) - lastReport >= 0.1) {
      lastReport = secondsSince(start);
      IterationReport report;
      report.iterations = step;
      report.objective = 2 * merit.f;  // the problem's objective is |r|^2
      report.maxViolation = merit.violation;
      report.rho = nu;
      if (!callback(report)) {
        why = "cancelled";
        break;
      }
    }
    if (merit.violation <= options.tolerance && kkt <= kStationary) {
      handOverMultipliers(std::min(options.maxPenalty, options.nearFeasiblePenalty), rows.values);
      summary.reason = "constraints within tolerance and the KKT conditions met after " + std::to_string(step) + " SQP steps";
      done = true;
      // From here the polish, with the active set a warm start would take (lambda + rho c > 0),
      // finishes what the linearly converging tail left: the jump 28.1005 -> 28.0987.
      const PolishResult polished = polish();
      if (polished.converged) {
        summary.polished = true;
        summary.reason += " and " + std::to_string(polished.iterations) + " Newton steps with the exact Hessian";
      }
      break;
    }
    // Near feasibility the polish's Newton steps on the active rows finish quadratically, where
    // the programs' inertia correction (a multiple of the identity wherever the Hessian is not
    // convex on the margin's directions) would leave a linearly converging tail: the jump took
    // 23 more programs from a violation of 3e-5 to converge.
    if (options.newtonPolish && merit.violation <= options.polishBelow && merit.violation <= 0.1 * lastPolishViolation) {
      lastPolishViolation = merit.violation;
      const std::vector<double> saved = state.lambda;
      handOverMultipliers(0, rows.values);
      const PolishResult polished = polish();
      if (polished.converged) {
        state.rho = std::min(options.maxPenalty, options.nearFeasiblePenalty);
        summary.polished = true;
        summary.reason = "constraints within tolerance and the KKT conditions met after " + std::to_string(step) +
                         " SQP steps and " + std::to_string(polished.iterations) + " Newton steps with the exact Hessian";
        done = true;
        break;
      }
      state.lambda = saved;
    }
    if (merit.violation <= options.tolerance) {
      feasibleKkt.push_back(kkt);
      const size_t k = feasibleKkt.size();
      if (k > kStagnantSteps && kkt > kStagnantFall * feasibleKkt[k - 1 - kStagnantSteps]) {
        why = std::to_string(kStagnantSteps) + " steps within the tolerance stopped approaching a KKT point (stationarity " +
              toShortString(kkt) + ")";
        break;
      }
    } else {
      feasibleKkt.clear();
    }
    if (step >= options.sqpMaxSteps) {
      why = "no KKT point within " + std::to_string(options.sqpMaxSteps) + " steps";
      break;
    }
    if (cancel && cancel->load()) {
      why = "cancelled";
      break;
    }
    if (Clock::now() > deadline) {
      why = "out of time";
      break;
    }
    if (Clock::now() > handOverBy) {
      why = "a third of the time budget spent";
      break;
    }

    // The Hessian of the Lagrangian 1/2 |r|^2 + y.c (Gauss-Newton far from feasibility).
    Clock::time_point phase = Clock::now();
    const bool gaussNewton = !exactHessian && merit.violation > kGaussNewtonAbove;
    Triplets ht;
    if (gaussNewton) {
      for (int i = 0; i < n; ++i) ht.emplace_back(i, i, kElasticCurvature);
    } else {
      Vec w = y;
      for (int row : objective) w[row] = rows.values[row];
      ht = evaluator.curvature(w, threads);
    }
    evaluator.appendGaussNewton(rows, &ht);
    if (!gaussNewton && proximal > 0)
      for (int i = 0; i < n; ++i) ht.emplace_back(i, i, proximal * metric[i]);
    summary.hessianSeconds += secondsSince(phase);

    std::vector<int> held;  // indices into `inequality`
    for (size_t i = 0; i < inequality.size(); ++i)
      if (g[static_cast<Eigen::Index>(i)] > -kMargin || y[inequality[i]] > 0) held.push_back(static_cast<int>(i));
    const SpRow Cfull = raw::selectRows(rows.jacobian, inequality);
    // The program: near feasibility hard rows first; elastic when that has no point or needs
    // multipliers above the penalty (far away they reach 3e7, which would drown the objective).
    bool hard = true;
    QpOptions programOptions;
    programOptions.maxIterations = 100;
    programOptions.convex = gaussNewton;
    QpResult qp;
    QuadraticProgram program;
    std::vector<int> heldRows;
    SpRow C;  // the held rows' Jacobian, of the last round's program
    double elasticSum = 0;
    phase = Clock::now();
    bool solved = false;
    for (int round = 0; round < kMaxRounds && !solved; ++round) {
      heldRows.clear();
      for (int i : held) heldRows.push_back(inequality[i]);
      C = raw::selectRows(rows.jacobian, heldRows);
      const Vec gh = raw::selectValues(rows.values, heldRows);
      std::vector<int> elastic;  // indices into held: the violated rows
      if (!hard)
        for (size_t i = 0; i < held.size(); ++i)
          if (gh[static_cast<Eigen::Index>(i)] > 0) elastic.push_back(static_cast<int>(i));
      // Variables: the step, then (elastic) p and q >= 0 per equality (c + A d = p - q) and t >= 0
      // per violated inequality (g + C d <= t), each weighted nu in the objective.
      const int pe = hard ? 0 : me, ke = static_cast<int>(elastic.size()), mh = static_cast<int>(held.size());
      const int N = n + 2 * pe + ke;
      Triplets t = ht;
      for (int i = n; i < N; ++i) t.emplace_back(i, i, kElasticCurvature);
      program.hessian.resize(N, N);
      program.hessian.setFromTriplets(t.begin(), t.end());
      program.gradient = Vec::Constant(N, nu);
      program.gradient.head(n) = grad;
      Triplets ta;
      appendTriplets(A, 0, 0, &ta);
      for (int i = 0; i < pe; ++i) {
        ta.emplace_back(i, n + i, -1.0);
        ta.emplace_back(i, n + pe + i, 1.0);
      }
      program.equalities.resize(me, N);
      program.equalities.setFromTriplets(ta.begin(), ta.end());
      program.equalityTargets = -c;
      Triplets tc;
      appendTriplets(C, 0, 0, &tc);
      for (int j = 0; j < ke; ++j) tc.emplace_back(elastic[j], n + 2 * pe + j, -1.0);
      for (int j = 0; j < 2 * pe + ke; ++j) tc.emplace_back(mh + j, n + j, -1.0);  // slacks >= 0
      program.inequalities.resize(mh + 2 * pe + ke, N);
      program.inequalities.setFromTriplets(tc.begin(), tc.end());
      program.inequalityBounds = Vec::Zero(mh + 2 * pe + ke);
      program.inequalityBounds.head(mh) = -gh;
      program.shiftMetric = Vec::Ones(N);
      program.shiftMetric.head(n) = metric;
      programOptions.activeGuess.clear();
      if (!gaussNewton && !wasActive.empty()) {
        for (int row : heldRows) programOptions.activeGuess.push_back(wasActive[static_cast<size_t>(row)]);
        programOptions.activeGuess.resize(static_cast<size_t>(mh + 2 * pe + ke), 1);  // the slacks at zero
      }
      qp = solveQuadraticProgram(program, programOptions, hard ? &hardWorkspace : &elasticWorkspace);
      wasActive.assign(static_cast<size_t>(rowCount), 0);
      for (size_t i = 0; i < heldRows.size() && i < qp.active.size(); ++i) wasActive[static_cast<size_t>(heldRows[i])] = qp.active[i];
      if (hard) {
        const double largest = std::max(qp.y.lpNorm<Eigen::Infinity>(), qp.z.size() ? qp.z.lpNorm<Eigen::Infinity>() : 0.0);
        if (qp.converged && largest > nu && (merit.violation < kGaussNewtonAbove || largest <= kHardMultiplierCap))
          nu = 1.1 * largest;
        if (!qp.converged || largest > nu) {
          hard = false;
          --round;
          continue;
        }
      }
      elasticSum = hard ? 0.0 : qp.x.tail(2 * pe + ke).sum();
      lastSlacks.clear();
      for (int i = 0; i < pe; ++i) lastSlacks.emplace_back(equality[i], qp.x[n + i] + qp.x[n + pe + i]);
      for (int j = 0; j < ke; ++j) lastSlacks.emplace_back(heldRows[elastic[j]], qp.x[n + 2 * pe + j]);
      // Rows outside the program the step crosses join it, and it is solved again.
      const Vec linear = g + Cfull * qp.x.head(n);
      if (raw::holdCrossedRows(linear, &held)) {
        for (int i : held)  // a crossed row is guessed active in the next round
          if (linear[i] > raw::kCrossed) wasActive[static_cast<size_t>(inequality[static_cast<size_t>(i)])] = 1;
        continue;
      }
      // Steering: the elastic program keeps most of the violation (the penalty is too low for
      // the constraints to win against the objective): raise the penalty and solve again.
      const bool stalled = merit.violation > options.tolerance && merit.violation > 0.99 * lastViolation &&
                           elasticSum > 0.5 * merit.l1;
      if (stalled && nu < kMaxPenalty) {
        nu *= 10;
        --round;
        continue;
      }
      solved = true;
    }
    summary.qpSeconds += secondsSince(phase);
    if (!solved) {
      why = "a step's quadratic program kept gaining rows";
      break;
    }
    if (merit.l1 > options.tolerance && elasticSum >= kTrappedShare * merit.l1) {
      if (++trappedSteps == kMaxTrappedSteps) {
        why = std::to_string(kMaxTrappedSteps) + " programs in a row kept " + std::to_string(static_cast<int>(100 * kTrappedShare)) +
              " % of the violation or more in their elastic slacks";
        break;
      }
    } else {
      trappedSteps = 0;
    }
    if (options.sqpShiftedStepsLimit > 0 && qp.shift >= kLargeShift && proximal == 0) {
      if (++shiftedSteps == options.sqpShiftedStepsLimit) {
        why = std::to_string(shiftedSteps) + " programs in a row needed the Hessian shifted by " + toShortString(kLargeShift) +
              " or more";
        break;
      }
    } else {
      shiftedSteps = 0;
    }
    const Vec d = qp.x.head(n);
    Vec yNew = Vec::Zero(rowCount);
    for (int i = 0; i < me; ++i) yNew[equality[i]] = qp.y[i];
    for (size_t i = 0; i < heldRows.size(); ++i) yNew[heldRows[i]] = qp.z[static_cast<Eigen::Index>(i)];

    // Line search on the l1 merit; its directional derivative along d is grad.d - nu (l1 - the
    // slacks' sum) (N&W eq. 18.29). A full step the merit rejects first tries second-order
    // corrections: the same program with the rows' values at the trial point less their linear
    // change (N&W 18.3), repeated from each corrected point (kMaxCorrections). Trial points are
    // evaluated without Jacobians (0.6 ms instead of 4.5 on the jump), the accepted one with them.
    phase = Clock::now();
    const double phi0 = merit.f + nu * merit.l1;
    const double slope = std::min(0.0, grad.dot(d) - nu * (merit.l1 - elasticSum));
    const std::vector<double> x0 = vars.save();
    RawRows trial;
    bool accepted = false;
    double alpha = 1;
    for (int ls = 0; ls < 30 && !accepted; ++ls, alpha *= 0.5) {
      vars.plus(x0, alpha * d);
      if (!evaluator.evaluate(&trial, false)) continue;
      Merit m = meritOf(trial.values);
      if (m.f + nu * m.l1 <= phi0 + kArmijo * alpha * slope) {
        accepted = true;
        break;
      }
      if (ls > 0) continue;
      Vec corrected = d;
      RawRows at = std::move(trial);
      QuadraticProgram correction = program;  // only its targets change between corrections
      QpOptions correctionOptions = programOptions;
      correctionOptions.activeGuess = qp.active;
      for (int k = 0; k < (gaussNewton ? 1 : kMaxCorrections) && !accepted; ++k) {
        correction.equalityTargets = -(raw::selectValues(at.values, equality) - A * corrected);
        correction.inequalityBounds.head(static_cast<Eigen::Index>(heldRows.size())) =
            -(raw::selectValues(at.values, heldRows) - C * corrected);
        const Clock::time_point q0 = Clock::now();
        const QpResult soc = solveQuadraticProgram(correction, correctionOptions, hard ? &hardWorkspace : &elasticWorkspace);
        summary.qpSeconds += secondsSince(q0);
        if (!soc.converged) break;
        correctionOptions.activeGuess = soc.active;
        corrected = soc.x.head(n);
        RawRows correctedRows;
        vars.plus(x0, corrected);
        if (!evaluator.evaluate(&correctedRows, false)) break;
        const Merit mc = meritOf(correctedRows.values);
        if (mc.f + nu * mc.l1 <= phi0 + kArmijo * slope) {
          trial = std::move(correctedRows);
          accepted = true;
        } else if (mc.l1 > kCorrectionContraction * m.l1) {
          break;
        } else {
          m = mc;
          at = std::move(correctedRows);
        }
      }
      if (accepted) break;
    }
    if (accepted) accepted = evaluator.evaluate(&trial, true);  // at the accepted point
    summary.lineSearchSeconds += secondsSince(phase);
    if (!accepted) {
      vars.load(x0);
      why = "no step lowered the l1 merit";
      break;
    }
    if (nearFeasible && !gaussNewton) {
      if (alpha <= kCreepingStep) proximal = std::max(kProximalStart, kProximalGrowth * proximal);
      else if (alpha >= 1) proximal = proximal > kProximalFloor ? proximal / kProximalShrink : 0.0;
    }
    y += alpha * (yNew - y);
    lastViolation = merit.violation;
    rows.values.swap(trial.values);  // O(1); Eigen's sparse matrices have no move assignment
    rows.jacobian.swap(trial.jacobian);
    if (alpha > kCreepingStep) {
      creepingSteps = 0;
    } else {
      exactHessian = true;
      if (++creepingSteps == kMaxCreepingSteps) {
        why = "the line search cut " + std::to_string(kMaxCreepingSteps) + " steps in a row to 1/" +
              std::to_string(static_cast<int>(1 / kCreepingStep)) + " or less";
        break;
      }
    }
  }
  summary.sqpSeconds = secondsSince(start);

  auto finish = [&](SolveStatus status) { return raw::finishedAs(status, problem, start, summary); };
  if (done) {
    problem.syncFreeEnds();
    return finish(SolveStatus::Converged);
  }
  // The steps failed: the augmented Lagrangian solves from the starting point instead.
  problem.restore(initial);
  if (why == "cancelled") {
    summary.reason = "cancelled by the user; the starting motion is kept";
    return finish(SolveStatus::Cancelled);
  }
  if (nearFeasible) {
    summary.reason = "the SQP stopped after " + std::to_string(summary.sqpSteps) + " steps (" + why + ")";
    return finish(SolveStatus::IterationLimit);
  }
  al.spentSeconds += budgetSecondsSince(start);
  SolverSummary fallback = solveSpacetime(problem, al, callback, cancel);
  fallback.method = SolverMethod::Sqp;
  raw::addPhaseTo(summary, &fallback);
  fallback.reason = "the SQP stopped after " + std::to_string(summary.sqpSteps) + " steps (" + why +
                    describeSlacks(evaluator, lastSlacks, options.tolerance) +
                    "); the augmented Lagrangian from the starting motion: " + fallback.reason;
  fallback.solveSeconds = secondsSince(start);
  return fallback;
}

}  // namespace

SolverSummary solveSqp(SpacetimeProblem& problem, const SolverOptions& options, const ProgressCallback& callback,
                       const std::atomic<bool>* cancel) {
  return runSqp(problem, options, callback, cancel, false);
}

SolverSummary sqpStepsNearFeasible(SpacetimeProblem& problem, const SolverOptions& options,
                                   const std::atomic<bool>* cancel) {
  return runSqp(problem, options, nullptr, cancel, true);
}

}  // namespace spacetime
