// Newton steps on a kept factorisation (see chord_steps.h).
#include "chord_steps.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "anderson_mixing.h"
#include "program_steps.h"

namespace spacetime::raw {
namespace {

// A step makes progress when the residual max(stationarity, violation) falls below this share of
// the best before it; this many steps in a row without progress end the steps. A row joining or
// leaving the held set costs a step its progress at most once.
constexpr double kProgress = 0.5;
constexpr int kStepsWithoutProgress = 2;
// Past this many steps the full Newton steps are cheaper: at a rate of 1/2 a factorisation
// (the jump's: 7 ms with its Hessian) costs about as much as three of these steps. The steps go
// on past it while the rate of the last step reaches the tolerance within kStepsToFinish more
// (at most twice as many steps): at a steady rate of 1/3 (the jump's end pose moved 10 cm: 13
// steps on the edited problem) the last steps finish where a Newton step would have.
constexpr int kMaxSteps = 12;
constexpr int kStepsToFinish = 4;
// From this step on, the back-solves are refined (chordSteps).
constexpr int kRefineFrom = 6;
// Active-set changes of one step's program (each a back-solve or none).
constexpr int kMaxChanges = 25;
// The continuation (chordSteps): a stride whose program does not settle is halved down to this
// share of the edit; a stage's point is corrected until its residual is below kTracking before
// the next stage.
constexpr double kSmallestStride = 1.0 / 16;
constexpr double kTracking = 1e-3;
// The steps mixed with the last ones (anderson_mixing.h): this many differences.
constexpr int kMixingDepth = 3;
// A row that left the held set may leave again once the residual has fallen this much since.
constexpr double kLeaveAgain = 1e-3;

// A row outside the factorised block K: an inequality the steps hold (`release` false: its
// Jacobian row b where it joined, column [b; 0]) or one of K's rows they release (column
// e_{n+p}: the bordered equation fixes its multiplier's change, the border's unknown frees the
// row's own equation). `solved` is K^-1 column, one back-solve when the border is made.
struct Border {
  int row = 0;
  bool release = false;
  std::vector<std::pair<int, double>> column;  // its nonzeros
  Vec solved;
  bool refined = false;  // `solved` refined against K
  double dot(const Vec& w) const {
    double sum = 0;
    for (const auto& [i, value] : column) sum += value * w[i];
    return sum;
  }
  Vec dense(int size) const {
    Vec c = Vec::Zero(size);
    for (const auto& [i, value] : column) c[i] = value;
    return c;
  }
};

}  // namespace

ChordResult chordSteps(const NewtonFactors& factors, RawEvaluator& evaluator, const Variables& vars,
                       const std::vector<int>& objective, const PolishOptions& options,
                       const std::atomic<bool>* cancel, RawRows* rows, std::vector<char>* held,
                       std::vector<char>* added, Vec* multipliers) {
  ChordResult result;
  const double tolerance = options.tolerance, kktTolerance = options.kktTolerance;
  const int n = factors.variables, rowCount = evaluator.rows();
  const std::vector<int>& inK = factors.constraint;
  const int m = static_cast<int>(inK.size()), size = n + m;
  const double dc = factors.constraintRegularisation;
  std::vector<int> position(static_cast<size_t>(rowCount), -1);  // each row's place among K's rows
  for (int p = 0; p < m; ++p) position[static_cast<size_t>(inK[static_cast<size_t>(p)])] = p;
  auto isInequality = [&](int row) { return evaluator.kind(row) == RowKind::Inequality; };

  // K^-1 rhs, refined once against K where `refining`: LDL^T without pivoting of an indefinite
  // K loses digits, which the steps' rate does not mind but their floor does (the jump's end pose
  // moved 4 cm: the residual stalled at 1.3e-8 after 12 steps, above the 1e-8 tolerance, and a
  // Newton step finished; with the back-solves refined from the 6th step on, the steps reach it).
  // An edit the steps finish within kRefineFrom steps (2 cm: 6) has not met the floor and does
  // not pay for the refinement (5 % of its instructions).
  const KktFactorisation& kkt = *factors.kkt;
  bool refining = false;
  auto refine = [&](const Vec& rhs, Vec* d) {
    *d += kkt.ldlt.solve(Vec(rhs - kkt.matrix.selfadjointView<Eigen::Lower>() * *d));
  };
  auto solveK = [&](const Vec& rhs) {
    Vec d = kkt.ldlt.solve(rhs);
    if (refining) refine(rhs, &d);
    return d;
  };
  std::vector<Border> borders;
  auto dropBorder = [&](int row) {
    borders.erase(std::remove_if(borders.begin(), borders.end(), [&](const Border& b) { return b.row == row; }),
                  borders.end());
  };
  auto holdRow = [&](int row) {
    const int p = position[static_cast<size_t>(row)];
    if (p >= 0) return dropBorder(row);  // back into K: its release border goes
    Border b{row, false, {}, Vec()};
    for (SpRow::InnerIterator e(rows->jacobian, row); e; ++e) b.column.emplace_back(static_cast<int>(e.col()), e.value());
    b.solved = solveK(b.dense(size));
    b.refined = refining;
    borders.push_back(std::move(b));
  };
  auto releaseRow = [&](int row) {
    const int p = position[static_cast<size_t>(row)];
    if (p < 0) return dropBorder(row);  // held by a border: the border goes
    Border b{row, true, {{n + p, 1.0}}, Vec()};
    b.solved = solveK(b.dense(size));
    b.refined = refining;
    borders.push_back(std::move(b));
  };
  for (int row = 0; row < rowCount; ++row) {
    if (evaluator.kind(row) == RowKind::Objective) continue;
    const bool inBlock = position[static_cast<size_t>(row)] >= 0;
    if ((*held)[row] && !inBlock) holdRow(row);
    if (!(*held)[row] && inBlock) releaseRow(row);
  }

  // The bordered system [K B; B^T D] [u; v] = [f; h] by the Schur complement of K,
  // S = D - B^T K^-1 B (D: -dc for held rows, 0 for released ones): u = K^-1 f - K^-1 B v.
  // h: the held borders' values negated, the released rows' multipliers negated (to zero).
  auto solveBordered = [&](const Vec& u0, Vec* v) {
    Vec u = u0;
    const int k = static_cast<int>(borders.size());
    v->resize(k);
    if (k == 0) return u;
    Eigen::MatrixXd S(k, k);
    Vec h(k);
    for (int i = 0; i < k; ++i) {
      const Border& b = borders[static_cast<size_t>(i)];
      for (int j = 0; j < k; ++j) S(i, j) = -b.dot(borders[static_cast<size_t>(j)].solved);
      if (!b.release) S(i, i) -= dc;
      h[i] = (b.release ? -(*multipliers)[b.row] : -rows->values[b.row]) - b.dot(u);
    }
    *v = S.partialPivLu().solve(h);
    for (int j = 0; j < k; ++j) u -= (*v)[j] * borders[static_cast<size_t>(j)].solved;
    return u;
  };

  // The residual where each row last left the held set (infinite: never). A row leaves again
  // only after the residual has fallen kLeaveAgain times since: a degenerate contact's cone
  // sides and normal force, whose multipliers are not unique, would otherwise leave and join in
  // turn, while a row the continuation's path releases, holds and releases again (the jump's
  // end pose moved 10 cm: two rows) would stay held, pulling, and hold the steps above the
  // tolerance.
  std::vector<double> left(static_cast<size_t>(rowCount), std::numeric_limits<double>::infinity());
  double best = std::numeric_limits<double>::infinity();
  int withoutProgress = 0;
  // The continuation: the steps follow the problems whose rows are r(x) - (1 - theta) e, with e
  // the edit's change of the rows at the kept optimum, from theta = 0 (which the kept optimum
  // solves) to theta = 1 (the edited problem). Each step aims at theta + stride; a stride whose
  // program does not settle is halved before anything is evaluated. The first stride is the
  // whole edit, so an edit the kept matrix describes takes the steps on the edited problem alone.
  const bool continued = factors.values.size() == rowCount;
  const Vec edit = continued ? Vec(rows->values - factors.values) : Vec();
  double theta = continued ? 0.0 : 1.0, stride = 1.0, shifted = 0.0;
  auto shiftRows = [&](double by) {  // rows->values hold r(x) - by e
    if (by != shifted) rows->values -= (by - shifted) * edit;
    shifted = by;
  };
  auto stop = [&](const std::string& reason) {
    shiftRows(0.0);
    result.reason = reason;
    return result;
  };
  AndersonMixing mixing(kMixingDepth);
  int stepsOnTheEdit = 0;  // steps aimed at theta = 1
  double judged = -1;      // the target whose residual `best` holds
  for (int step = 0;;) {
    // A stage's point is corrected until it tracks the path before theta moves on.
    double target = std::min(1.0, theta + stride);
    if (theta > 0 && theta < 1) {
      shiftRows(1.0 - theta);
      const HeldKkt here = heldKkt(evaluator, *rows, objective, *held, *multipliers);
      if (std::max(here.kkt, here.violation) > kTracking) target = theta;
    }
    shiftRows(1.0 - target);
    const HeldKkt point = heldKkt(evaluator, *rows, objective, *held, *multipliers);
    const std::vector<int>& constraint = point.constraint;
    const Vec &y = point.y, &gradient = point.lagrangianGradient;
    const double kkt = point.kkt, violation = point.violation, residual = std::max(kkt, violation);
    // Only the edited problem's residual is judged: that of a stage's problem says nothing of it.
    result.residual = target == 1 ? residual : std::numeric_limits<double>::infinity();
    if (step == 0 && target == 1) result.startResidual = result.residual;
    if (target != judged) {
      judged = target;
      best = std::numeric_limits<double>::infinity();
      withoutProgress = 0;
    }
    if (!(residual < 1e300)) return stop("the residual is not finite");
    if (target == 1) {
      if (kkt <= kktTolerance && violation <= tolerance) {
        // A KKT point of the held rows: those that pull are released (newton_polish.h's rule).
        bool released = false;
        for (size_t i = 0; i < constraint.size(); ++i) {
          const int row = constraint[i];
          if (isInequality(row) && y[static_cast<Eigen::Index>(i)] < point.pull) {
            (*held)[row] = 0;
            (*multipliers)[row] = 0;
            releaseRow(row);
            released = true;
          }
        }
        if (!released) {
          result.converged = true;
          result.reason = "KKT conditions met";
          return result;
        }
        // Another problem from here (the released rows' multipliers leave the gradient, evaluated
        // again above): its residual is judged afresh.
        best = std::numeric_limits<double>::infinity();
        withoutProgress = 0;
        continue;
      }
    }
    if (residual < kProgress * best) {
      withoutProgress = 0;
    } else if (++withoutProgress >= kStepsWithoutProgress) {
      return stop("the residual stopped falling");
    }
    // Past kMaxSteps on the edited problem, the steps go on while the rate of the last step
    // reaches the tolerance within kStepsToFinish more.
    bool finishing = false;
    if (target == 1 && best < std::numeric_limits<double>::infinity() && residual < best) {
      const double rate = residual / best;
      finishing = std::log(residual / kktTolerance) <= kStepsToFinish * std::log(1 / rate);
    }
    best = std::min(best, residual);
    // (The stages' steps have a bound of their own: all steps together at most 3 kMaxSteps.)
    if ((stepsOnTheEdit >= kMaxSteps && !(finishing && stepsOnTheEdit < 2 * kMaxSteps)) || step >= 3 * kMaxSteps)
      return stop("no KKT point within " + std::to_string(kMaxSteps) + " steps");
    if ((cancel && cancel->load()) || Clock::now() > options.deadline) return stop("cancelled or out of time");
    if (!refining && step >= kRefineFrom) {
      refining = true;
      for (Border& b : borders)
        if (!b.refined) refine(b.dense(size), &b.solved), b.refined = true;
    }
    // What a halved stride restores (past theta = 1 a halved stride aims there all the same).
    const bool mayHalve = continued && theta < 1 && stride > kSmallestStride;
    const std::vector<Border> bordersBefore = mayHalve ? borders : std::vector<Border>();
    const std::vector<char> heldBefore = mayHalve ? *held : std::vector<char>();
    const std::vector<char> addedBefore = mayHalve ? *added : std::vector<char>();
    const std::vector<double> leftBefore = mayHalve ? left : std::vector<double>();
    const Vec multipliersBefore = mayHalve ? *multipliers : Vec();
    // The step: the quadratic program of the kept matrix (its equalities the held rows, its
    // inequalities every other inequality linearised) solved by active-set changes on the
    // borders, a back-solve per row joining or leaving: a held inequality whose multiplier would
    // pull leaves (the most pulling first; see `left`), its multiplier leaving the gradient
    // of the Lagrangian with it; then a row the step would violate joins (the most violated
    // first).
    Vec f(size);
    f.head(n) = -gradient;
    for (int p = 0; p < m; ++p) f[n + p] = -rows->values[inK[static_cast<size_t>(p)]];
    Vec u, v, u0 = solveK(f);  // K^-1 f, again when f changes
    // The inequalities that may join: those not held, with a Jacobian row evaluated (the others'
    // linearised value is their value). Linearising only these, not every row of J at every
    // change, was half of the steps' own work on the 2 cm edit.
    std::vector<int> joinable;
    for (int row = 0; row < rowCount; ++row) {
      if (!isInequality(row) || (*held)[row]) continue;
      const double* begin = rows->jacobian.valuePtr() + rows->jacobian.outerIndexPtr()[row];
      const double* end = rows->jacobian.valuePtr() + rows->jacobian.outerIndexPtr()[row + 1];
      if (rows->values[row] > tolerance || std::any_of(begin, end, [](double x) { return x != 0; })) joinable.push_back(row);
    }
    auto mayLeave = [&](int row) { return residual < kLeaveAgain * left[static_cast<size_t>(row)]; };
    bool settled = false;
    for (int change = 0; change < kMaxChanges && !settled; ++change) {
      u = solveBordered(u0, &v);
      // The multipliers after the step: K's held rows', the held borders'.
      const double pull = -1e-6 * std::max(1.0, multipliers->lpNorm<Eigen::Infinity>());
      int leaving = -1;
      double most = pull;
      for (int p = 0; p < m; ++p) {
        const int row = inK[static_cast<size_t>(p)];
        const double y = (*multipliers)[row] + u[n + p];
        if (isInequality(row) && (*held)[row] && mayLeave(row) && y < most) leaving = row, most = y;
      }
      for (size_t j = 0; j < borders.size(); ++j) {
        const Border& b = borders[j];
        const double y = (*multipliers)[b.row] + v[static_cast<Eigen::Index>(j)];
        if (!b.release && mayLeave(b.row) && y < most) leaving = b.row, most = y;
      }
      if (leaving >= 0) {
        for (SpRow::InnerIterator e(rows->jacobian, leaving); e; ++e) f[e.col()] += (*multipliers)[leaving] * e.value();
        (*held)[leaving] = 0;
        (*multipliers)[leaving] = 0;
        left[static_cast<size_t>(leaving)] = residual;
        releaseRow(leaving);
        joinable.push_back(leaving);
        u0 = solveK(f);
        continue;
      }
      int joining = -1;
      double worst = tolerance;
      for (int row : joinable) {
        if ((*held)[row]) continue;
        double change = 0;
        for (SpRow::InnerIterator e(rows->jacobian, row); e; ++e) change += e.value() * u[e.col()];
        const double linear = rows->values[row] + change;
        if (linear > worst) joining = row, worst = linear;
      }
      if (joining < 0) {
        settled = true;
        break;
      }
      (*held)[joining] = (*added)[joining] = 1;
      (*multipliers)[joining] = 0;
      holdRow(joining);
    }
    if (!settled && mayHalve) {
      borders = bordersBefore;
      *held = heldBefore, *added = addedBefore, left = leftBefore;
      *multipliers = multipliersBefore;
      stride /= 2;
      continue;
    }
    if (!settled) return stop("the steps' program did not settle within " + std::to_string(kMaxChanges) + " changes");
    if (!u.allFinite() || !v.allFinite()) return stop("the step is not finite");
    Vec next = *multipliers;
    for (int p = 0; p < m; ++p) {
      const int row = inK[static_cast<size_t>(p)];
      next[row] = (*held)[row] ? next[row] + u[n + p] : 0.0;
    }
    for (size_t j = 0; j < borders.size(); ++j)
      if (!borders[j].release) next[borders[j].row] += v[static_cast<Eigen::Index>(j)];
    // The chord step in the variables and the held rows' multipliers, mixed with the last steps'
    // (anderson_mixing.h) on the edited problem while the held set stays: the jump's end pose
    // moved 10 cm took 15 steps instead of 17, and in a drag 2 cm at a time 8, 8, 10 and 11
    // instead of 12, 10, 11 and 12 (`sqp`'s warm 10 cm edit 11 instead of 13; a 2 cm edit from
    // the optimum, at a rate of 10-40 a step, the same 6).
    std::vector<int> heldNow;
    for (int row = 0; row < rowCount; ++row)
      if ((*held)[row]) heldNow.push_back(row);
    if (target != 1 || heldNow != constraint) mixing.reset();  // constraint: the rows held at the start
    Vec chord(n + static_cast<int>(heldNow.size()));
    chord.head(n) = u.head(n);
    for (size_t i = 0; i < heldNow.size(); ++i)
      chord[n + static_cast<Eigen::Index>(i)] = next[heldNow[i]] - (*multipliers)[heldNow[i]];
    const Vec taken = mixing.mix(chord);
    vars.plus(vars.save(), taken.head(n));
    for (int row = 0; row < rowCount; ++row)
      if (!(*held)[row]) (*multipliers)[row] = 0;
    for (size_t i = 0; i < heldNow.size(); ++i) (*multipliers)[heldNow[i]] += taken[n + static_cast<Eigen::Index>(i)];
    limitJacobiansToHeld(evaluator, *held, -kMargin);  // the programs linearise the rows near their bound
    ++result.steps, ++step;
    if (target == 1) ++stepsOnTheEdit;
    theta = target;
    shifted = 0;  // the evaluation writes r(x)
    if (!evaluator.evaluate(rows, true)) return stop("a row is not finite");
  }
}

}  // namespace spacetime::raw
