// First-order multiplier estimate (see multiplier_estimate.h): the regularised least-squares
// solution of J_A^T y = -grad f by the normal equations' sparse LDL^T, with the inequalities whose
// multiplier comes out negative leaving A one round at a time; and the choice between those and
// the augmented-Lagrangian state's own (kkt_multipliers.h).
#include "solver/multiplier_estimate.h"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <vector>

#include "kkt_multipliers.h"
#include "program_steps.h"

namespace spacetime {

using raw::RawEvaluator;
using raw::RawRows;
using raw::SpMat;
using raw::SpRow;
using raw::Vec;

namespace {

constexpr int kMaxRounds = 20;
// On the scaled normal equations' unit diagonal.
constexpr double kRegularisation = 1e-12;

// The objective's gradient J_r^T r.
Vec objectiveGradient(const raw::RowKinds& kinds, const RawRows& rows) {
  return raw::selectRows(rows.jacobian, kinds.objective).transpose() * raw::selectValues(rows.values, kinds.objective);
}

// |grad f + J^T y|_inf / max(1, |grad f|_inf): how far multipliers y are from stationarity.
double stationarityOf(const Vec& grad, const RawRows& rows, const Vec& y) {
  return (grad + SpMat(rows.jacobian.transpose()) * y).lpNorm<Eigen::Infinity>() /
         std::max(1.0, grad.lpNorm<Eigen::Infinity>());
}

}  // namespace

Vec leastSquaresMultipliers(const RawEvaluator& evaluator, const RawRows& rows, MultiplierEstimate* out) {
  const raw::RowKinds kinds(evaluator);
  const Vec grad = objectiveGradient(kinds, rows);
  std::vector<int> held = kinds.equality;
  for (int r : kinds.inequality)
    if (rows.values[r] > -raw::kAtBound) held.push_back(r);
  if (held.empty()) return Vec();
  std::sort(held.begin(), held.end());

  Vec y = Vec::Zero(evaluator.rows());
  for (int round = 0; round < kMaxRounds; ++round) {
    // Tikhonov-regularised least squares, min |J_A^T y + grad f|^2 + delta |y|^2 over rows scaled
    // to unit norm (metres, radians and fractions of the weight differ by orders of magnitude):
    // at a bound the rows are dependent, so the multipliers are not unique, and the regularised
    // ones stay moderate. An exact sparse QR's basic solution reached a stationarity of 5e-12 at
    // the jump's optimum but put multipliers in the thousands on dependent rows, and from their
    // motion files the 3D lamp and the biped then ran away under the augmented Lagrangian
    // (objectives 5e4 and 1e6) where with these they converge.
    SpRow JA = raw::selectRows(rows.jacobian, held);
    Vec scale(JA.rows());
    for (Eigen::Index i = 0; i < JA.rows(); ++i) {
      const double norm = JA.row(i).norm();
      scale[i] = norm > 0 ? 1 / norm : 1;
    }
    JA = scale.asDiagonal() * JA;
    SpMat N = SpMat(JA * SpRow(JA.transpose()));
    for (int i = 0; i < N.outerSize(); ++i) N.coeffRef(i, i) += kRegularisation;
    Eigen::SimplicialLDLT<SpMat> ldlt(N);
    if (ldlt.info() != Eigen::Success) return Vec();
    const Vec yA = scale.cwiseProduct(ldlt.solve(-(JA * grad)));
    y.setZero();
    std::vector<int> keep;
    for (size_t i = 0; i < held.size(); ++i) {
      const int r = held[i];
      y[r] = yA[static_cast<Eigen::Index>(i)];
      if (evaluator.kind(r) == RowKind::Inequality && y[r] < 0) {
        ++out->dropped;
        y[r] = 0;
      } else {
        keep.push_back(r);
      }
    }
    if (keep.size() == held.size()) break;
    held = keep;
  }
  out->active = 0;
  for (int r : kinds.inequality) out->active += y[r] > 0;
  out->stationarity = stationarityOf(grad, rows, y);
  out->ok = true;
  return y;
}

Vec stationaryMultipliers(SpacetimeProblem& problem, const RawEvaluator& evaluator, const RawRows& rows,
                          MultiplierEstimate* out) {
  Vec y = leastSquaresMultipliers(evaluator, rows, out);
  if (!out->ok) return y;
  const raw::RowKinds kinds(evaluator);
  const AugmentedLagrangianState& al = problem.augmentedLagrangian();
  Vec state = Vec::Zero(evaluator.rows());
  for (int r = 0; r < evaluator.rows(); ++r)
    if (evaluator.kind(r) != RowKind::Objective) state[r] = al.lambda[evaluator.multiplier(r)];
  const double stationarity = stationarityOf(objectiveGradient(kinds, rows), rows, state);
  if (!(stationarity < out->stationarity)) return y;
  out->stationarity = stationarity;
  out->active = 0;
  for (int r : kinds.inequality) out->active += state[r] > 0;
  return state;
}

MultiplierEstimate estimateMultipliers(SpacetimeProblem& problem, double rho, int threads) {
  MultiplierEstimate out;
  const raw::Variables vars(problem.ceresProblem());
  RawEvaluator evaluator(problem, vars, threads);
  RawRows rows;
  if (!evaluator.evaluate(&rows, true)) return out;
  const Vec y = leastSquaresMultipliers(evaluator, rows, &out);
  if (!out.ok) return out;
  raw::handOverMultipliers(evaluator, y, rows.values, rho, &problem.augmentedLagrangian());
  return out;
}

}  // namespace spacetime
