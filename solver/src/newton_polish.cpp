// Newton (SQP) polish of an augmented-Lagrangian iterate (see newton_polish.h).
#include "solver/newton_polish.h"

#include <ceres/ceres.h>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>

#include "chord_steps.h"
#include "program_steps.h"
#include "raw_rows.h"
#include "solver/quadratic_program.h"

namespace spacetime {
namespace {

using raw::Clock;
using raw::RawEvaluator;
using raw::RawRows;
using raw::secondsSince;
using raw::SpMat;
using raw::SpRow;
using raw::Triplets;
using raw::Variables;
using raw::Vec;

// The quadratic program that settles the held rows (PolishOptions::settleActiveSet) where a
// Newton step on them does not fit: min 1/2 d^T W d + g^T d on the linearised equalities and the
// inequalities within kMargin of their bound or held (rows its step crosses join, and it is
// solved again), by the active-set steps from the held rows (quadratic_program.h: one
// factorisation, then a solve per change of the working set).
// Writes the program's active rows into `held` (rows it makes active into `added` too), its
// multipliers into `multipliers` and its solution, the SQP step on its active set, into `step`.
// A program those steps cannot solve from the held rows (QpOptions::guessOnly: more than 80 held
// near their bound - the 3D lamp's 700-row programs, whose interior-point solves took 0.3-0.5 s
// each and whose steps then failed - or the steps fail) changes nothing.
enum class Settled { Unchanged, Changed, Unsolved };
Settled settleActiveSet(const RawEvaluator& evaluator, const RawRows& rows, const Triplets& hessian, const Vec& grad,
                        const Vec& metric, double tolerance, std::vector<char>* held, std::vector<char>* added,
                        Vec* multipliers, Vec* step) {
  const int n = static_cast<int>(grad.size());
  const raw::RowKinds kinds(evaluator);
  const std::vector<int>&equality = kinds.equality, &inequality = kinds.inequality;
  std::vector<int> near;  // indices into `inequality`
  for (size_t i = 0; i < inequality.size(); ++i)
    if ((*held)[inequality[i]] || rows.values[inequality[i]] > -raw::kMargin) near.push_back(static_cast<int>(i));
  QuadraticProgram program;
  program.hessian.resize(n, n);
  program.hessian.setFromTriplets(hessian.begin(), hessian.end());
  program.gradient = grad;
  program.equalities = raw::selectRows(rows.jacobian, equality);
  program.equalityTargets = -raw::selectValues(rows.values, equality);
  program.shiftMetric = metric;
  const SpRow C = raw::selectRows(rows.jacobian, inequality);
  const Vec g = raw::selectValues(rows.values, inequality);
  QpWorkspace workspace;
  std::vector<int> programRows;
  for (int round = 0; round < raw::kMaxRounds; ++round) {
    programRows.clear();
    for (int i : near) programRows.push_back(inequality[static_cast<size_t>(i)]);
    program.inequalities = raw::selectRows(rows.jacobian, programRows);
    program.inequalityBounds = -raw::selectValues(rows.values, programRows);
    QpOptions programOptions;
    programOptions.guessOnly = true;
    for (int row : programRows) programOptions.activeGuess.push_back((*held)[row]);
    const QpResult qp = solveQuadraticProgram(program, programOptions, &workspace);
    if (!qp.converged) return Settled::Unsolved;
    if (raw::holdCrossedRows(g + C * qp.x, &near)) continue;
    bool changed = false;
    for (size_t i = 0; i < programRows.size(); ++i) {
      const int row = programRows[i];
      // A row the current point violates stays held, as the Newton steps hold it.
      const char active = qp.active[i] || ((*held)[row] && rows.values[row] > tolerance);
      changed = changed || active != (*held)[row];
      if (active && !(*held)[row]) (*added)[row] = 1;
      (*held)[row] = active;
      (*multipliers)[row] = active ? qp.z[static_cast<Eigen::Index>(i)] : 0.0;
    }
    for (size_t i = 0; i < equality.size(); ++i) (*multipliers)[equality[i]] = qp.y[static_cast<Eigen::Index>(i)];
    *step = qp.x;
    return changed ? Settled::Changed : Settled::Unchanged;
  }
  return Settled::Unsolved;
}

}  // namespace

PolishResult polishNewton(SpacetimeProblem& problem, const PolishOptions& options,
                          const std::atomic<bool>* cancel) {
  const Clock::time_point start = Clock::now();
  PolishResult result;
  auto finish = [&](const std::string& reason) {
    result.reason = reason;
    result.seconds = secondsSince(start);
    return result;
  };
  if (!problem.freeEnds().empty()) return finish("not run: free contact ends are bounded variables");
  const Variables vars(problem.ceresProblem());
  const int threads = std::max(1, options.threads);
  AugmentedLagrangianState& al = problem.augmentedLagrangian();
  RawEvaluator evaluator(problem, vars, threads, al.newtonFactors ? al.newtonFactors->layout : nullptr);
  if (evaluator.anyMoving()) return finish("not run: a residual moves with a free contact end");
  const int n = vars.tangent, rowCount = evaluator.rows();

  RawRows rows;
  Clock::time_point t0 = Clock::now();
  {
    // The Jacobians the steps read: the objective rows', the equalities', and the inequalities'
    // that may be held (a positive multiplier, or within kMargin of the bound, where the
    // estimate below can turn positive and the programs linearise them). The others' are never
    // read; skipping them took the jump's first evaluation from 3.9 to 3.0 ms (2 threads, one run
    // each).
    std::vector<char> needed(static_cast<size_t>(rowCount));
    for (int r = 0; r < rowCount; ++r)
      needed[static_cast<size_t>(r)] = evaluator.kind(r) != RowKind::Inequality || al.lambda[evaluator.multiplier(r)] > 0;
    evaluator.limitJacobians(needed, -raw::kMargin);
  }
  if (!evaluator.evaluate(&rows, true)) return finish("not run: a row is not finite");
  result.jacobianSeconds += secondsSince(t0);

  // Rows: objective rows (r), and the constraints held at zero: every equality and the
  // inequalities the augmented Lagrangian found active. Multiplier estimates of the first step:
  // lambda + rho * row (N&W eq. 17.39), whose sign also decides activity.
  std::vector<int> objective;
  std::vector<char> held(rowCount, 0), added(rowCount, 0);
  Vec multipliers = Vec::Zero(rowCount);  // y of each held row
  for (int r = 0; r < rowCount; ++r) {
    const RowKind kind = evaluator.kind(r);
    if (kind == RowKind::Objective) {
      objective.push_back(r);
      continue;
    }
    const double estimate = al.lambda[evaluator.multiplier(r)] + al.rho * rows.values[r];
    if (kind == RowKind::Inequality && estimate <= 0) continue;
    held[r] = 1;
    multipliers[r] = estimate;
  }

  const std::vector<double> initial = vars.save();
  std::vector<double> x = initial;
  auto giveUp = [&](const std::string& why) {
    vars.load(initial);
    return finish(why);
  };
  const std::string outOfSteps = "no KKT point within " + std::to_string(options.maxIterations) + " Newton steps";
  // The factorisation of the last Newton step, kept with the multipliers where the polish ends at
  // a KKT point (AugmentedLagrangianState::newtonFactors): the next warm polish steps on it.
  auto factorisation = std::make_shared<KktFactorisation>();
  auto& ldlt = factorisation->ldlt;
  std::vector<int> factorisedRows;  // the held rows of the last factorisation (K's constraint rows)
  bool haveFactors = false;
  bool analysed = false;  // the KKT pattern changes with the active set
  // Regularisation: dw keeps W's diagonal positive, dc makes the constraint block quasi-definite
  // so redundant held rows (degenerate contacts) still factorise; it acts on the change of y only.
  const double dw = 1e-10, dc = 1e-8;
  double lastShift = 0;
  // The line search's rows; swapped with `rows` at an accepted step, so the next trial reuses
  // the Jacobian's storage: a new one copied the pattern, and assigning it to `rows` copied it
  // again (Eigen's sparse matrices have no move assignment).
  RawRows trial;
  // Whether programs settle the active set: from the options, until one cannot be solved from
  // the held rows, after which the polish finds the set a row at a time.
  bool settling = options.settleActiveSet;
  auto heldRows = [&] {
    std::vector<int> out;
    for (int row = 0; row < rowCount; ++row)
      if (held[row]) out.push_back(row);
    return out;
  };
  // The steps need the Jacobians of the objective rows, the equalities and the held rows, and of
  // any inequality a trial point violates (it is held next): the other inequalities' blocks, most
  // of the problem's, are evaluated without their Jets in the line search. While programs settle
  // the active set, also those of the rows within kMargin of their bound, which the programs
  // linearise and each step's fit is checked against (with their Jacobians zero, the steps after
  // the first crossed rows unseen: the jump's end pose moved 10 cm, the polish failed and the
  // augmented Lagrangian took 108 iterations).
  auto limitJacobiansToHeld = [&] {
    raw::limitJacobiansToHeld(evaluator, held, settling ? -raw::kMargin : options.tolerance);
  };
  // The polish's point with its active set, to return to where steps from it do not hold.
  struct PolishPoint {
    std::vector<double> x;
    RawRows rows;
    std::vector<char> held, added;
    Vec multipliers;
  };
  auto savePoint = [&] { return PolishPoint{x, rows, held, added, multipliers}; };
  auto restorePoint = [&](const PolishPoint& p) {
    x = p.x;
    vars.load(x);
    rows = p.rows;
    held = p.held, added = p.added;
    multipliers = p.multipliers;
  };
  // Whether `values` (one per row) violate an inequality the polish does not hold.
  auto violatesUnheld = [&](const Vec& values, int row) {
    return evaluator.kind(row) == RowKind::Inequality && !held[row] && values[row] > options.tolerance;
  };
  // Steps from x along dx with the held rows' multipliers moving from yFrom to yTo (both in the
  // order of `constraint`): full steps near a KKT point, halved while the step makes the
  // violation of the held rows or the KKT residual no smaller than `reference` (the polish is
  // local: a step that keeps failing means the active set or the starting point is not good
  // enough, and the augmented Lagrangian carries on). Only the held rows judge the step: an
  // inequality it violates is held at the next step. An accepted point becomes x, its rows
  // `rows` and its multipliers the held rows'; a rejected step leaves the variables at the last
  // trial point.
  //
  // With a watchdog (N&W §15.6, after Chamberlain et al. 1982) near a KKT point (a reference
  // below kWatchBelow): a rejected full step whose merit is within kWatch times the reference is
  // taken once, and the next line search must end below the reference of that step, or the
  // polish returns to the point before it and backtracks along it. Nearly dependent held rows
  // (the quadruped's landing anchors, stance and end key, docs/design.md) make a full step raise
  // the violation before the next one lowers both: of seven cold quadruped solves on perturbed
  // paths (the LM's first radius), six failed their polishes without it, two of which converge
  // with it (the other four end unconverged at higher objectives either way).
  // Farther out it took steps that wandered: the 3D lamp's warm 10 cm edit, at references of
  // 0.16-0.23, ran out of passes where backtracking reaches the KKT point. Only Newton steps are
  // watched: a program's step that fails leaves the Newton steps to go on from x, which a
  // watched one that failed would end (the heavy lamp's witkin-kass hand-over).
  // Nor is a step that crosses an inequality the polish does not hold: held from then on, the
  // rows it crossed kept the humanoid's polish at a violation of 2.5e-6 for its last 32 passes.
  // `watchable`: whether this step may be watched.
  constexpr double kWatch = 10, kWatchBelow = 1e-2;
  struct Watched {  // the point before a watched step, and the step
    PolishPoint before;
    Vec dx, yFrom, yTo;
    std::vector<int> constraint;
    double reference = 0;
  };
  std::optional<Watched> watched;
  double trialMerit = 0;  // max(KKT residual, held rows' violation) at the last trial point
  auto tryStep = [&](double alpha, const Vec& dx, const std::vector<int>& constraint, const Vec& yFrom,
                     const Vec& yTo, double reference) {
    vars.plus(x, alpha * dx);
    t0 = Clock::now();
    const bool finite = evaluator.evaluate(&trial, true);
    result.jacobianSeconds += secondsSince(t0);
    trialMerit = std::numeric_limits<double>::infinity();
    if (!finite) return false;
    const Vec yTrial = yFrom + alpha * (yTo - yFrom);
    const Vec gt = raw::transposeTimes(trial.jacobian, objective, raw::selectValues(trial.values, objective));
    const Vec ct = raw::selectValues(trial.values, constraint);
    const double kktTrial = (gt + raw::transposeTimes(trial.jacobian, constraint, yTrial)).lpNorm<Eigen::Infinity>() /
                            std::max(1.0, gt.lpNorm<Eigen::Infinity>());
    const double violTrial = ct.size() ? ct.lpNorm<Eigen::Infinity>() : 0.0;
    trialMerit = std::max(kktTrial, violTrial);
    return trialMerit < reference;
  };
  auto acceptTrial = [&](double alpha, const std::vector<int>& constraint, const Vec& yFrom, const Vec& yTo) {
    const Vec yTrial = yFrom + alpha * (yTo - yFrom);
    for (size_t i = 0; i < constraint.size(); ++i) multipliers[constraint[i]] = yTrial[static_cast<Eigen::Index>(i)];
    x = vars.save();
    rows.values.swap(trial.values);  // O(1): Eigen's swaps exchange the storage
    rows.jacobian.swap(trial.jacobian);
  };
  auto backtrack = [&](double alpha, const Vec& dx, const std::vector<int>& constraint, const Vec& yFrom,
                       const Vec& yTo, double reference) {
    for (; alpha >= 0.125; alpha /= 2)
      if (tryStep(alpha, dx, constraint, yFrom, yTo, reference)) {
        acceptTrial(alpha, constraint, yFrom, yTo);
        return true;
      }
    return false;
  };
  // Whether the last trial point violates an inequality the polish does not hold.
  auto crossesUnheld = [&] {
    for (int row = 0; row < rowCount; ++row)
      if (violatesUnheld(trial.values, row)) return true;
    return false;
  };
  auto lineSearch = [&](const Vec& dx, const std::vector<int>& constraint, const Vec& yFrom, const Vec& yTo,
                        double reference, bool watchable) {
    const Clock::time_point phase = Clock::now();
    bool accepted = false;
    if (watched) {
      const Watched w = std::move(*watched);
      watched.reset();
      accepted = backtrack(1, dx, constraint, yFrom, yTo, std::min(reference, w.reference));
      if (!accepted) {
        // Back to the point before, with its active set (the rows held since, were they crossed
        // by the watched step or by the next, would stay held there).
        restorePoint(w.before);
        limitJacobiansToHeld();
        analysed = false;
        accepted = backtrack(0.5, w.dx, w.constraint, w.yFrom, w.yTo, w.reference);
      }
    } else if (tryStep(1, dx, constraint, yFrom, yTo, reference)) {
      acceptTrial(1, constraint, yFrom, yTo);
      accepted = true;
    } else if (watchable && reference < kWatchBelow && trialMerit < kWatch * reference && !crossesUnheld()) {
      watched = Watched{savePoint(), dx, yFrom, yTo, constraint, reference};
      acceptTrial(1, constraint, yFrom, yTo);
      accepted = true;
    } else {
      accepted = backtrack(0.5, dx, constraint, yFrom, yTo, reference);
    }
    result.lineSearchSeconds += secondsSince(phase);
    return accepted;
  };
  // A warm start whose multipliers come with the factorisation of an earlier optimum of this
  // problem's shape first steps on it (chord_steps.h). Where they reach a KKT point, or stop
  // kChordKept of their starting residual or less, x, its rows, held rows and multipliers are the
  // steps' (the full Newton steps then have less to do: `sqp`'s warm 10 cm edit of the jump, 8
  // steps from 5.2e-4 to 2.6e-6, then 1 KKT solve instead of 3); otherwise all are restored and
  // the polish takes full Newton steps from its start.
  constexpr double kChordKept = 1e-2;
  if (const std::shared_ptr<const NewtonFactors> kept = al.newtonFactors;
      kept && kept->variables == n && kept->rows == rowCount) {
    const Clock::time_point phase = Clock::now();
    const PolishPoint before = savePoint();
    const raw::ChordResult chord =
        raw::chordSteps(*kept, evaluator, vars, objective, options, cancel, &rows, &held, &added, &multipliers);
    result.chordSteps = chord.steps;
    result.chordSeconds = secondsSince(phase);
    if (chord.converged || chord.residual < kChordKept * chord.startResidual) {
      x = vars.save();
    } else {
      restorePoint(before);
    }
  }
  for (int it = 0;; ++it) {
    const raw::HeldKkt point = raw::heldKkt(evaluator, rows, objective, held, multipliers);
    const std::vector<int>& constraint = point.constraint;
    const int m = static_cast<int>(constraint.size());
    const Vec &y = point.y, &r = point.r, &c = point.c, &grad = point.grad;
    const double kkt = point.kkt, heldViolation = point.heldViolation;
    result.kktResidual = kkt;
    result.maxViolation = point.violation;
    result.iterations = it;

    // The active set. An inequality a step violated is held from then on; one the polish added
    // is released when its multiplier pulls. Rows held from the start are released only at a KKT
    // point of the held rows: where a contact force vanishes the cone's sides and the normal
    // force reach zero together, their multipliers are not unique, and releasing them on the
    // way made the active set cycle (measured on luxo_jump).
    const double pull = point.pull;
    const bool atKkt = kkt <= options.kktTolerance && result.maxViolation <= options.tolerance;
    bool activeSetChanged = false;
    for (int row = 0; row < rowCount; ++row)
      if (violatesUnheld(rows.values, row)) {
        held[row] = added[row] = 1;
        activeSetChanged = true;
      }
    for (int i = 0; i < m; ++i) {
      const int row = constraint[i];
      if (evaluator.kind(row) == RowKind::Inequality && y[i] < pull && (added[row] || atKkt) &&
          rows.values[row] <= options.tolerance) {
        held[row] = 0;
        multipliers[row] = 0;
        activeSetChanged = true;
      }
    }
    limitJacobiansToHeld();
    if (activeSetChanged) {
      analysed = false;
      if (it >= options.maxIterations) return giveUp(outOfSteps);
      continue;
    }
    if (atKkt) {
      // Every held inequality pushes: a KKT point of the whole problem. Hand the multipliers
      // back (at c = 0 the augmented Lagrangian's lambda is y; zero for rows not held).
      for (int row = 0; row < rowCount; ++row)
        if (evaluator.kind(row) != RowKind::Objective)
          al.lambda[evaluator.multiplier(row)] =
              evaluator.kind(row) == RowKind::Equality ? multipliers[row] : std::max(0.0, multipliers[row]);
      result.converged = true;
      std::vector<std::vector<double>> termRows(evaluator.terms().size());
      for (size_t k = 0; k < termRows.size(); ++k) {
        const double* first = rows.values.data() + evaluator.firstRow(k);
        termRows[k].assign(first, first + evaluator.terms()[k]->num_residuals());
      }
      result.measures = measure(evaluator.terms(), termRows);
      const std::shared_ptr<const NewtonFactors>& kept = al.newtonFactors;
      if (haveFactors || (kept && kept->variables == n && kept->rows == rowCount)) {
        // This polish's last factorisation, or the one its steps stood on, with this optimum's rows.
        auto factors = haveFactors ? std::make_shared<NewtonFactors>() : std::make_shared<NewtonFactors>(*kept);
        if (haveFactors) {
          factors->variables = n;
          factors->rows = rowCount;
          factors->constraint = factorisedRows;
          factors->constraintRegularisation = dc;
          factors->kkt = factorisation;
          factors->layout = evaluator.layout();
        }
        factors->values = rows.values;
        al.newtonFactors = factors;
      }
      return finish("KKT conditions met");
    }
    if (it >= options.maxIterations) return giveUp(outOfSteps);
    if (cancel && cancel->load()) return giveUp("cancelled");
    if (Clock::now() > options.deadline) return giveUp("out of time");

    // W = J_r^T J_r + curvature of the objective rows (weights r) and of the held constraints
    // (weights y), the Hessian of the Lagrangian 1/2 |r|^2 + y.c_A.
    Clock::time_point phase = Clock::now();
    Vec w = Vec::Zero(rowCount);
    for (size_t i = 0; i < objective.size(); ++i) w[objective[i]] = r[static_cast<Eigen::Index>(i)];
    for (int i = 0; i < m; ++i) w[constraint[i]] = y[i];
    Triplets t = evaluator.curvature(w, threads);
    evaluator.appendGaussNewton(rows, &t);
    const size_t hessianEnd = t.size();  // W's entries; K's constraint rows follow
    result.hessianSeconds += secondsSince(phase);
    phase = Clock::now();
    for (int k = 0; k < m; ++k)
      for (SpRow::InnerIterator e(rows.jacobian, constraint[k]); e; ++e) t.emplace_back(n + k, static_cast<int>(e.col()), e.value());
    for (int i = 0; i < m; ++i) t.emplace_back(n + i, n + i, -dc);
    // Inertia correction: the step minimises the local quadratic model on the constraints'
    // tangent space only if K has exactly m negative eigenvalues, which the signs of LDL^T's D
    // count (Sylvester's law of inertia).
    const size_t base = t.size();
    SpMat& K = factorisation->matrix;  // kept with its factors: the steps on them refine their solves
    K.resize(n + m, n + m);
    double shift = 0;
    bool factorised = false;
    for (int attempt = 0; attempt < 30 && !factorised; ++attempt) {
      t.resize(base);
      for (int i = 0; i < n; ++i) t.emplace_back(i, i, dw + shift);
      K.setFromTriplets(t.begin(), t.end());
      if (!analysed) {
        ldlt.analyzePattern(K);
        analysed = true;
      }
      ldlt.factorize(K);
      factorised = ldlt.info() == Eigen::Success && (ldlt.vectorD().array() < 0).count() == m;
      if (!factorised) shift = shift == 0 ? (lastShift > 0 ? lastShift / 3 : 1e-4) : shift * 8;
    }
    if (!factorised) return giveUp("the Newton system could not be given the inertia of a minimum");
    factorisedRows = constraint;
    haveFactors = true;
    lastShift = shift;
    Vec rhs(n + m);
    rhs.head(n) = -grad;
    rhs.tail(m) = -c - dc * y;
    // LDL^T of an indefinite matrix without pivoting loses digits (measured: residual 1e-3 of
    // the right-hand side on luxo_jump); three steps of iterative refinement restore them.
    Vec d = ldlt.solve(rhs);
    for (int refine = 0; refine < 3; ++refine) d += ldlt.solve(Vec(rhs - K.selfadjointView<Eigen::Lower>() * d));
    // The step of the regularised system leaves the linearised constraints off by dc times the
    // multipliers' change (the particle: violation 2e-6 after the exact step of a quadratic
    // program). Refinement against the unregularised K, preconditioned by the regularised
    // factors, removes it where the constraints' Jacobian has full rank; where it does not (the
    // residual stops shrinking: redundant or conflicting rows) the regularised step stays.
    auto exactResidual = [&](const Vec& step) {
      Vec res(n + m);
      res.head(n) = -grad;
      res.tail(m) = -c;
      res -= K.selfadjointView<Eigen::Lower>() * step;
      res.tail(m) -= dc * step.tail(m);  // K0 = K + dc on the constraint block
      return res;
    };
    Vec residual = exactResidual(d);
    for (int refine = 0; refine < 3; ++refine) {
      const Vec next = d + ldlt.solve(residual);
      const Vec nextResidual = exactResidual(next);
      if (!next.allFinite() || !(nextResidual.norm() < 0.5 * residual.norm())) break;
      d = next;
      residual = nextResidual;
    }
    result.factorisationSeconds += secondsSince(phase);
    if (!d.allFinite()) return giveUp("the Newton step is not finite");
    ++result.solves;
    if (settling) {
      // The step on the held rows is the program's solution when it crosses no other
      // inequality and every held one pushes; otherwise the program settles the held rows.
      const Vec linear = rows.values + rows.jacobian * d.head(n);
      bool fits = true;
      for (int row = 0; row < rowCount && fits; ++row)
        fits = !violatesUnheld(linear, row);
      for (int i = 0; i < m && fits; ++i)
        fits = evaluator.kind(constraint[i]) != RowKind::Inequality || d[n + i] >= pull;
      if (!fits) {
        phase = Clock::now();
        t.resize(hessianEnd);
        const Vec before = multipliers;
        Vec programStep;
        const Settled settled = settleActiveSet(evaluator, rows, t, grad, raw::shiftMetric(problem, vars),
                                                options.tolerance, &held, &added, &multipliers, &programStep);
        result.programSeconds += secondsSince(phase);
        result.settledActiveSet = result.settledActiveSet || settled == Settled::Changed;
        settling = settled != Settled::Unsolved;
        if (settled == Settled::Changed) {
          // The program's solution is the SQP step on its active set (W's weights the held rows'
          // old multipliers, N&W eq. 18.11): taken as the step, it saves the Newton step on the
          // new rows that repeated it. Where it is not accepted the polish steps on from x with
          // the program's rows and multipliers.
          analysed = false;
          limitJacobiansToHeld();
          const std::vector<int> now = heldRows();
          if (!lineSearch(programStep, now, raw::selectValues(before, now), raw::selectValues(multipliers, now),
                          std::max(kkt, heldViolation), false))
            vars.load(x);
          continue;
        }
      }
    }
    if (!lineSearch(d.head(n), constraint, y, d.tail(m), std::max(kkt, heldViolation), true))
      return giveUp("a Newton step did not reduce the KKT residual");
  }
}

}  // namespace spacetime
