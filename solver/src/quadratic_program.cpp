// The interior-point quadratic program solver (see quadratic_program.h).
#include "solver/quadratic_program.h"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

namespace spacetime {
namespace {

using SpMat = Eigen::SparseMatrix<double>;
using SpRow = Eigen::SparseMatrix<double, Eigen::RowMajor>;
using Vec = Eigen::VectorXd;

// Largest step in [0, 1] keeping v + alpha dv >= (1 - tau) v (the fraction to the boundary).
double stepToBoundary(const Vec& v, const Vec& dv, double tau) {
  double alpha = 1;
  for (Eigen::Index i = 0; i < v.size(); ++i)
    if (dv[i] < 0) alpha = std::min(alpha, -tau * v[i] / dv[i]);
  return alpha;
}

double infNorm(const Vec& v) { return v.size() ? v.lpNorm<Eigen::Infinity>() : 0.0; }

// The reduced KKT system of one iteration: its lower triangle, LDL^T factors and solves.
class ReducedSystem {
 public:
  ReducedSystem(const QuadraticProgram& qp, const QpOptions& options)
      : qp_(qp), options_(options), n_(static_cast<int>(qp.gradient.size())),
        me_(static_cast<int>(qp.equalities.rows())), Ct_(qp.inequalities.transpose()) {
    for (int k = 0; k < qp.hessian.outerSize(); ++k)
      for (SpMat::InnerIterator e(qp.hessian, k); e; ++e)
        if (e.row() >= e.col()) hessian_.emplace_back(static_cast<int>(e.row()), static_cast<int>(e.col()), e.value());
    for (int k = 0; k < qp.equalities.outerSize(); ++k)
      for (SpRow::InnerIterator e(qp.equalities, k); e; ++e)
        equalities_.emplace_back(n_ + static_cast<int>(e.row()), static_cast<int>(e.col()), e.value());
  }
  double shift() const { return shift_; }

  // Factorises K for the inequality weights w = z / s, raising the shift on H until K has the
  // inertia of a convex program (n positive and m_e negative pivots); false if it cannot.
  bool factorise(const Vec& w) {
    const SpMat CtWC = Ct_ * w.asDiagonal() * qp_.inequalities;
    std::vector<Eigen::Triplet<double>> t = hessian_;
    t.insert(t.end(), equalities_.begin(), equalities_.end());
    for (int k = 0; k < CtWC.outerSize(); ++k)
      for (SpMat::InnerIterator e(CtWC, k); e; ++e)
        if (e.row() >= e.col()) t.emplace_back(static_cast<int>(e.row()), static_cast<int>(e.col()), e.value());
    for (int i = 0; i < me_; ++i) t.emplace_back(n_ + i, n_ + i, -options_.dualRegularisation);
    const size_t base = t.size();
    for (int attempt = 0; attempt < 40; ++attempt) {
      t.resize(base);
      for (int i = 0; i < n_; ++i) t.emplace_back(i, i, options_.primalRegularisation + shift_);
      K_.resize(n_ + me_, n_ + me_);
      K_.setFromTriplets(t.begin(), t.end());
      if (K_.nonZeros() != analysedNonZeros_) {
        ldlt_.analyzePattern(K_);
        analysedNonZeros_ = K_.nonZeros();
      }
      ldlt_.factorize(K_);
      if (ldlt_.info() == Eigen::Success && (ldlt_.vectorD().array() < 0).count() == me_ &&
          (ldlt_.vectorD().array() != 0).all())
        return true;
      shift_ = shift_ == 0 ? 1e-8 * std::max(1.0, maxDiagonal()) : 10 * shift_;
    }
    return false;
  }

  // The solution of K [dx; dy] = rhs, refined twice against K (pivots of both signs without
  // pivoting lose digits).
  Vec solve(const Vec& rhs) const {
    Vec d = ldlt_.solve(rhs);
    for (int refine = 0; refine < 2; ++refine) d += ldlt_.solve(Vec(rhs - K_.selfadjointView<Eigen::Lower>() * d));
    return d;
  }

 private:
  double maxDiagonal() const {
    double m = 0;
    for (const auto& e : hessian_)
      if (e.row() == e.col()) m = std::max(m, std::abs(e.value()));
    return m;
  }
  const QuadraticProgram& qp_;
  const QpOptions& options_;
  const int n_, me_;
  const SpMat Ct_;
  std::vector<Eigen::Triplet<double>> hessian_, equalities_;
  SpMat K_;
  Eigen::SimplicialLDLT<SpMat, Eigen::Lower, Eigen::AMDOrdering<int>> ldlt_;
  Eigen::Index analysedNonZeros_ = -1;
  double shift_ = 0;
};

}  // namespace

QpResult solveQuadraticProgram(const QuadraticProgram& qp, const QpOptions& options) {
  QpResult result;
  const int n = static_cast<int>(qp.gradient.size());
  const int me = static_cast<int>(qp.equalities.rows()), mi = static_cast<int>(qp.inequalities.rows());
  if (qp.hessian.rows() != n || qp.hessian.cols() != n || qp.equalities.cols() != n || qp.inequalities.cols() != n ||
      qp.equalityTargets.size() != me || qp.inequalityBounds.size() != mi) {
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

  ReducedSystem system(qp, options);
  Vec x = Vec::Zero(n), y = Vec::Zero(me), z = Vec::Ones(mi), s = Vec::Ones(mi);

  // One Newton step of the perturbed KKT conditions with complementarity target rc (s o z - rc
  // is driven to zero), on the factorised system: dx, dy, ds, dz.
  struct Step {
    Vec dx, dy, ds, dz;
  };
  Vec rd, re, ri;
  auto residuals = [&] {
    // H as factorised: with the inertia correction's shift the convexified program is solved.
    rd = H * x + system.shift() * x + g + A.transpose() * y + C.transpose() * z;
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
  if (!system.factorise(z.cwiseQuotient(s))) {
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

  // The last finite iterate is what a failed solve returns.
  Vec lastX = x, lastY = y, lastZ = z;
  for (int it = 0;; ++it) {
    residuals();
    const double mu = mi ? s.dot(z) / mi : 0.0;
    result.iterations = it;
    result.dualResidual = infNorm(rd);
    result.primalResidual = std::max(infNorm(re), infNorm(ri));
    result.complementarity = mu;
    // An iterate that runs off to infinity: no feasible point, or no bounded minimum.
    if (!(std::max({infNorm(x), infNorm(y), infNorm(z), infNorm(s)}) < 1e30) || !rd.allFinite() || !ri.allFinite()) {
      x = lastX, y = lastY, z = lastZ;
      result.reason = "the iterates diverge: the program has no feasible point or no bounded minimum";
      break;
    }
    lastX = x, lastY = y, lastZ = z;
    if (result.dualResidual <= options.tolerance * dualScale && result.primalResidual <= options.tolerance * primalScale &&
        mu <= options.tolerance) {
      result.converged = true;
      result.reason = "KKT conditions met";
      break;
    }
    if (it >= options.maxIterations) {
      std::ostringstream why;
      why << "no KKT point within " << options.maxIterations << " iterations (primal residual " << result.primalResidual
          << ", dual " << result.dualResidual << ", complementarity " << mu << ")";
      result.reason = why.str();
      break;
    }
    if (!system.factorise(z.cwiseQuotient(s))) {
      result.reason = "the reduced KKT system could not be factorised";
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
  result.x = x;
  result.y = y;
  result.z = z;
  result.shift = system.shift();
  return result;
}

}  // namespace spacetime
