// The interior-point quadratic program solver (see quadratic_program.h).
#include "solver/quadratic_program.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>
#include <vector>

#include "active_set_steps.h"
#include "reduced_kkt_system.h"

namespace spacetime {

using qp::infNorm;
using qp::ReducedSystem;
using qp::SpMat;
using qp::SpRow;
using qp::Vec;

namespace {

// Largest step in [0, 1] keeping v + alpha dv >= (1 - tau) v (the fraction to the boundary).
double stepToBoundary(const Vec& v, const Vec& dv, double tau) {
  double alpha = 1;
  for (Eigen::Index i = 0; i < v.size(); ++i)
    if (dv[i] < 0) alpha = std::min(alpha, -tau * v[i] / dv[i]);
  return alpha;
}

// Every nonzero of the program's matrices that enters K, in iteration order: H's lower
// triangle, A, C. Two programs with the same list share K's pattern.
std::vector<int> patternOf(const QuadraticProgram& qp) {
  std::vector<int> p{static_cast<int>(qp.gradient.size()), static_cast<int>(qp.equalities.rows()),
                     static_cast<int>(qp.inequalities.rows())};
  for (int k = 0; k < qp.hessian.outerSize(); ++k)
    for (SpMat::InnerIterator e(qp.hessian, k); e; ++e)
      if (e.row() >= e.col()) p.insert(p.end(), {static_cast<int>(e.row()), static_cast<int>(e.col())});
  p.push_back(-1);
  for (int k = 0; k < qp.equalities.outerSize(); ++k)
    for (SpRow::InnerIterator e(qp.equalities, k); e; ++e) p.insert(p.end(), {k, static_cast<int>(e.col())});
  p.push_back(-1);
  for (int k = 0; k < qp.inequalities.outerSize(); ++k)
    for (SpRow::InnerIterator e(qp.inequalities, k); e; ++e) p.insert(p.end(), {k, static_cast<int>(e.col())});
  return p;
}

}  // namespace

QpWorkspace::QpWorkspace() = default;
QpWorkspace::~QpWorkspace() = default;

QpResult solveQuadraticProgram(const QuadraticProgram& qp, const QpOptions& options, QpWorkspace* workspace) {
  QpResult result;
  const int n = static_cast<int>(qp.gradient.size());
  const int me = static_cast<int>(qp.equalities.rows()), mi = static_cast<int>(qp.inequalities.rows());
  if (qp.hessian.rows() != n || qp.hessian.cols() != n || qp.equalities.cols() != n || qp.inequalities.cols() != n ||
      qp.equalityTargets.size() != me || qp.inequalityBounds.size() != mi ||
      (qp.shiftMetric.size() && qp.shiftMetric.size() != n)) {
    result.reason = "the program's matrices and vectors do not agree in size";
    return result;
  }
  const SpMat H = qp.hessian.selfadjointView<Eigen::Lower>();
  const SpRow& A = qp.equalities;
  const SpRow& C = qp.inequalities;
  const Vec& g = qp.gradient;
  const Vec& b = qp.equalityTargets;
  const Vec& d = qp.inequalityBounds;
  const double dualScale = 1 + infNorm(g), primalScale = 1 + std::max(infNorm(b), infNorm(d));

  QpWorkspace scratch;
  QpWorkspace& ws = workspace ? *workspace : scratch;
  std::vector<int> signature = patternOf(qp);
  if (!ws.pattern_ || ws.pattern_->signature != signature) {
    if (!ws.pattern_ || !ws.pattern_->assignSlots(qp)) {
      const bool grow = ws.pattern_ && ws.pattern_->n == n && ws.pattern_->me == me;
      ws.pattern_ = std::make_unique<QpWorkspace::Pattern>(qp, grow ? ws.pattern_.get() : nullptr);
      ws.pattern_->assignSlots(qp);
    }
    ws.pattern_->signature = std::move(signature);
  }
  ReducedSystem system(qp, options, *ws.pattern_);
  const bool guessed = options.activeGuess.size() == static_cast<size_t>(mi);
  if (guessed && qp::solveFromActiveGuess(qp, H, options, system, dualScale, primalScale, &result)) return result;
  if (guessed && options.guessOnly) {
    result = QpResult();
    result.reason = "the active-set steps from the guess could not finish";
    return result;
  }
  system.resetShift();  // the interior point finds its own
  Vec x = Vec::Zero(n), y = Vec::Zero(me), z = Vec::Ones(mi), s = Vec::Ones(mi);

  // One Newton step of the perturbed KKT conditions with complementarity target rc (s o z - rc
  // is driven to zero), on the factorised system: dx, dy, ds, dz.
  struct Step {
    Vec dx, dy, ds, dz;
  };
  Vec rd, re, ri;
  auto residuals = [&] {
    // H as factorised: with the inertia correction's shift the convexified program is solved.
    rd = H * x + g + A.transpose() * y + C.transpose() * z;
    if (system.shift() > 0) rd += system.shift() * system.metric().cwiseProduct(x);
    re = A * x - b;
    ri = C * x + s - d;
  };
  auto newtonStep = [&](const Vec& rc) {
    Vec rhs(n + me);
    rhs.head(n) = -rd - C.transpose() * Vec((z.cwiseProduct(ri) - rc).cwiseQuotient(s));
    rhs.tail(me) = -re;
    const Vec sol = system.solve(rhs);
    Step st;
    st.dx = sol.head(n);
    st.dy = sol.tail(me);
    st.ds = -ri - C * st.dx;
    st.dz = (-rc - z.cwiseProduct(st.ds)).cwiseQuotient(s);
    return st;
  };

  // Starting point (Nocedal & Wright, section 16.6): the affine step from x = 0, s = z = 1,
  // then slacks and multipliers moved away from zero.
  residuals();
  if (!system.factorise(z.cwiseQuotient(s), !options.convex)) {
    result.reason = "the reduced KKT system could not be factorised";
    return result;
  }
  {
    const Step affine = newtonStep(s.cwiseProduct(z));
    x += affine.dx;
    y += affine.dy;
    s = (s + affine.ds).cwiseAbs().cwiseMax(1.0);
    z = (z + affine.dz).cwiseAbs().cwiseMax(1.0);
  }

  // The best iterate so far (by the largest scaled residual) is what the solve returns: near the
  // solution z / s grows without bound for active rows, and in double precision the last
  // iterations can lose what the earlier ones reached (the pivots then no longer show the
  // inertia they should, and a shift would change the program).
  double bestError = std::numeric_limits<double>::infinity();
  Vec bestX = x, bestY = y, bestZ = z, bestS = s;
  QpResult best;
  std::string stop;
  for (int it = 0;; ++it) {
    residuals();
    const double mu = mi ? s.dot(z) / mi : 0.0;
    result.iterations = it;
    result.dualResidual = infNorm(rd);
    result.primalResidual = std::max(infNorm(re), infNorm(ri));
    result.complementarity = mu;
    const double error = std::max({result.dualResidual / dualScale, result.primalResidual / primalScale, mu});
    // An iterate that runs off to infinity: no feasible point, or no bounded minimum.
    if (!(std::max({infNorm(x), infNorm(y), infNorm(z), infNorm(s)}) < 1e30) || !(error < 1e300)) {
      stop = "the iterates diverge: the program has no feasible point or no bounded minimum";
      break;
    }
    if (error < bestError) {
      bestError = error;
      bestX = x, bestY = y, bestZ = z, bestS = s;
      best = result;
    }
    if (error <= options.tolerance) break;
    if (it >= options.maxIterations) {
      stop = "no KKT point within " + std::to_string(options.maxIterations) + " iterations";
      break;
    }
    if (!system.factorise(z.cwiseQuotient(s), !options.convex && bestError > options.acceptableTolerance)) {
      stop = "the reduced KKT system lost its inertia";
      break;
    }
    // Predictor (sigma = 0), then the corrector aimed at sigma mu with Mehrotra's second-order
    // term ds_aff o dz_aff; one step length for primal and dual (H couples them).
    const Step affine = newtonStep(s.cwiseProduct(z));
    const double alphaAffine = std::min(stepToBoundary(s, affine.ds, 1.0), stepToBoundary(z, affine.dz, 1.0));
    const double muAffine = mi ? (s + alphaAffine * affine.ds).dot(z + alphaAffine * affine.dz) / mi : 0.0;
    const double sigma = mu > 0 ? std::pow(muAffine / mu, 3) : 0.0;
    const Step step = newtonStep(s.cwiseProduct(z) + affine.ds.cwiseProduct(affine.dz) - Vec::Constant(mi, sigma * mu));
    const double tau = std::max(0.9, 1 - mu);  // towards 1 as the iterates converge
    const double alpha = std::min(stepToBoundary(s, step.ds, tau), stepToBoundary(z, step.dz, tau));
    x += alpha * step.dx;
    y += alpha * step.dy;
    s += alpha * step.ds;
    z += alpha * step.dz;
  }
  const int iterations = result.iterations;
  result = best;
  result.iterations = iterations;
  x = bestX, y = bestY, z = bestZ;
  result.converged = bestError <= options.acceptableTolerance;
  std::ostringstream why;
  if (bestError <= options.tolerance) {
    why << "KKT conditions met";
  } else {
    why << (result.converged ? "KKT conditions met to " : "stopped at a KKT error of ") << bestError;
    if (!stop.empty()) why << ": " << stop;
  }
  result.reason = why.str();
  result.x = x;
  result.y = y;
  result.z = z;
  result.active.resize(static_cast<size_t>(mi));
  for (int i = 0; i < mi; ++i) result.active[static_cast<size_t>(i)] = z[i] > bestS[i];
  result.shift = system.shift();
  return result;
}

}  // namespace spacetime
