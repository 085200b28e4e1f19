// The interior-point method through IPOPT (see interior_point.h).
#include "solver/interior_point.h"

#ifdef SPACETIME_HAVE_IPOPT

#include <coin/IpIpoptApplication.hpp>
#include <coin/IpTNLP.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <unordered_map>

#include "raw_rows.h"

namespace spacetime {
namespace {

using raw::Clock;
using raw::RawEvaluator;
using raw::RawRows;
using raw::secondsSince;
using raw::selectRows;
using raw::SpMat;
using raw::SpRow;
using raw::Variables;
using raw::Vec;
using Ipopt::Index;
using Ipopt::Number;

// The lower triangle of the Lagrangian's Hessian in a pattern fixed at the start: every pair of
// tangent columns a kernel's nonlinear inputs read, and the pattern of J_r^T J_r. Each term's
// dense weighted Hessian and each entry of J_r^T J_r know their slot, so assembly is a scatter.
class HessianPattern {
 public:
  HessianPattern(const RawEvaluator& evaluator, const SpMat& gaussNewton) {
    for (size_t k = 0; k < evaluator.terms().size(); ++k) {
      const TermResidual* term = evaluator.terms()[k];
      std::vector<Scatter>& scatter = terms_.emplace_back();
      if (term->kernel().nonlinearInputs() == 0) continue;
      const std::vector<int>& col = evaluator.columns(k);
      const std::vector<int> inputs = term->nonlinearColumns();
      for (int a : inputs)
        for (int b : inputs)
          if (col[a] >= 0 && col[b] >= 0 && col[a] >= col[b]) scatter.push_back({a, b, slot(col[a], col[b])});
    }
    for (int k = 0; k < gaussNewton.outerSize(); ++k)
      for (SpMat::InnerIterator e(gaussNewton, k); e; ++e)
        if (e.row() >= e.col()) gaussNewtonSlots_.push_back(slot(static_cast<int>(e.row()), static_cast<int>(e.col())));
    gaussNewtonNonZeros_ = gaussNewton.nonZeros();
  }
  int size() const { return static_cast<int>(rows_.size()); }
  const std::vector<int>& rows() const { return rows_; }
  const std::vector<int>& cols() const { return cols_; }

  // values = sigma J_r^T J_r + sum_k (term k's Hessian weighted by w).
  void assemble(const RawEvaluator& evaluator, const SpMat& gaussNewton, double sigma, const Vec& w,
                double* values) const {
    std::fill(values, values + size(), 0.0);
    if (sigma != 0) {
      if (gaussNewton.nonZeros() == gaussNewtonNonZeros_) {
        size_t i = 0;
        for (int k = 0; k < gaussNewton.outerSize(); ++k)
          for (SpMat::InnerIterator e(gaussNewton, k); e; ++e)
            if (e.row() >= e.col()) values[gaussNewtonSlots_[i++]] += sigma * e.value();
      } else {  // the product's pattern changed (it should not): look each entry up
        for (int k = 0; k < gaussNewton.outerSize(); ++k)
          for (SpMat::InnerIterator e(gaussNewton, k); e; ++e)
            if (e.row() >= e.col())
              if (auto it = slots_.find(key(static_cast<int>(e.row()), static_cast<int>(e.col()))); it != slots_.end())
                values[it->second] += sigma * e.value();
      }
    }
    for (size_t k = 0; k < terms_.size(); ++k) {
      if (terms_[k].empty()) continue;
      const Eigen::MatrixXd H = evaluator.terms()[k]->weightedHessianNow(w.data() + evaluator.firstRow(k), &evaluator.columns(k));
      for (const Scatter& s : terms_[k]) values[s.slot] += H(s.a, s.b);
    }
  }

 private:
  struct Scatter {
    int a, b, slot;  // H(a, b) of the term's stacked inputs goes to values[slot]
  };
  static long long key(int row, int col) { return (static_cast<long long>(row) << 32) | static_cast<unsigned>(col); }
  int slot(int row, int col) {
    const auto [it, added] = slots_.try_emplace(key(row, col), size());
    if (added) {
      rows_.push_back(row);
      cols_.push_back(col);
    }
    return it->second;
  }
  std::unordered_map<long long, int> slots_;
  std::vector<int> rows_, cols_;
  std::vector<std::vector<Scatter>> terms_;
  std::vector<int> gaussNewtonSlots_;
  Eigen::Index gaussNewtonNonZeros_ = 0;
};

class SpacetimeNlp : public Ipopt::TNLP {
 public:
  SpacetimeNlp(SpacetimeProblem& problem, const SolverOptions& options, const ProgressCallback& callback,
               const std::atomic<bool>* cancel, Clock::time_point deadline)
      : problem_(problem), vars_(problem.ceresProblem()), evaluator_(problem, vars_, std::max(1, options.threads)),
        options_(options), callback_(callback), cancel_(cancel), deadline_(deadline), start_(vars_.save()) {
    for (int r = 0; r < evaluator_.rows(); ++r)
      (evaluator_.kind(r) == RowKind::Objective ? objective_ : constraint_).push_back(r);
    current_ = Vec::Zero(vars_.tangent);
    ok_ = evaluateAt(current_, true);
    if (ok_) {
      jacobianPattern_ = constraintJacobian_;
      hessian_ = std::make_unique<HessianPattern>(evaluator_, gaussNewton());
    }
  }
  bool ok() const { return ok_; }
  int iterations() const { return iterations_; }
  double evaluationSeconds() const { return evaluationSeconds_; }
  double hessianSeconds() const { return hessianSeconds_; }
  bool cancelled() const { return cancelled_; }
  bool timedOut() const { return timedOut_; }

  bool get_nlp_info(Index& n, Index& m, Index& nnzJacobian, Index& nnzHessian, IndexStyleEnum& style) override {
    n = vars_.tangent;
    m = static_cast<Index>(constraint_.size());
    nnzJacobian = static_cast<Index>(jacobianPattern_.nonZeros());
    nnzHessian = hessian_->size();
    style = C_STYLE;
    return true;
  }
  bool get_bounds_info(Index n, Number* xl, Number* xu, Index m, Number* gl, Number* gu) override {
    std::fill(xl, xl + n, -kInfinity);
    std::fill(xu, xu + n, kInfinity);
    for (Index i = 0; i < m; ++i) {
      const bool equality = evaluator_.kind(constraint_[i]) == RowKind::Equality;
      gl[i] = equality ? 0.0 : -kInfinity;  // inequality rows are g <= 0
      gu[i] = 0.0;
    }
    return true;
  }
  bool get_starting_point(Index n, bool initX, Number* x, bool, Number*, Number*, Index, bool, Number*) override {
    if (initX) std::fill(x, x + n, 0.0);  // x is the step from the starting variables
    return true;
  }
  bool eval_f(Index n, const Number* x, bool, Number& f) override {
    if (!evaluateAt(Eigen::Map<const Vec>(x, n), false)) return false;
    f = 0;
    for (int r : objective_) f += 0.5 * rows_.values[r] * rows_.values[r];
    return true;
  }
  bool eval_grad_f(Index n, const Number* x, bool, Number* grad) override {
    if (!evaluateAt(Eigen::Map<const Vec>(x, n), true)) return false;
    Eigen::Map<Vec>(grad, n) = objectiveJacobian_.transpose() * objectiveValues();
    return true;
  }
  bool eval_g(Index n, const Number* x, bool, Index m, Number* g) override {
    if (!evaluateAt(Eigen::Map<const Vec>(x, n), false)) return false;
    for (Index i = 0; i < m; ++i) g[i] = rows_.values[constraint_[i]];
    return true;
  }
  bool eval_jac_g(Index n, const Number* x, bool, Index, Index nnz, Index* iRow, Index* jCol, Number* values) override {
    if (!values) {
      Index k = 0;
      for (int r = 0; r < jacobianPattern_.outerSize(); ++r)
        for (SpRow::InnerIterator e(jacobianPattern_, r); e; ++e, ++k) {
          iRow[k] = r;
          jCol[k] = static_cast<Index>(e.col());
        }
      return true;
    }
    if (!evaluateAt(Eigen::Map<const Vec>(x, n), true)) return false;
    if (constraintJacobian_.nonZeros() != nnz) return false;  // Ceres's pattern is fixed
    std::copy(constraintJacobian_.valuePtr(), constraintJacobian_.valuePtr() + nnz, values);
    return true;
  }
  bool eval_h(Index n, const Number* x, bool, Number sigma, Index m, const Number* lambda, bool, Index nnz,
              Index* iRow, Index* jCol, Number* values) override {
    if (!values) {
      std::copy(hessian_->rows().begin(), hessian_->rows().end(), iRow);
      std::copy(hessian_->cols().begin(), hessian_->cols().end(), jCol);
      return true;
    }
    if (!evaluateAt(Eigen::Map<const Vec>(x, n), true)) return false;
    const Clock::time_point t0 = Clock::now();
    Vec w = Vec::Zero(evaluator_.rows());
    for (int r : objective_) w[r] = sigma * rows_.values[r];
    for (Index i = 0; i < m; ++i) w[constraint_[i]] = lambda[i];
    hessian_->assemble(evaluator_, gaussNewton(), sigma, w, values);
    hessianSeconds_ += secondsSince(t0);
    return std::all_of(values, values + nnz, [](double v) { return std::isfinite(v); });
  }
  void finalize_solution(Ipopt::SolverReturn, Index n, const Number* x, const Number*, const Number*, Index m,
                         const Number*, const Number* lambda, Number, const Ipopt::IpoptData*,
                         Ipopt::IpoptCalculatedQuantities*) override {
    // The last iterate if it is finite, else the starting variables: never a NaN motion.
    const Eigen::Map<const Vec> step(x, n);
    if (step.allFinite()) {
      vars_.plus(start_, step);
      // Multipliers back to the augmented-Lagrangian state, so a warm start or a polish can use
      // them (for an inequality g <= 0, IPOPT's lambda >= 0 pushes as the AL's does).
      AugmentedLagrangianState& al = problem_.augmentedLagrangian();
      for (Index i = 0; i < m; ++i) {
        const int row = constraint_[i];
        al.lambda[evaluator_.multiplier(row)] =
            evaluator_.kind(row) == RowKind::Equality ? lambda[i] : std::max(0.0, lambda[i]);
      }
      if (al.rho < options_.warmRestartPenalty) al.rho = options_.warmRestartPenalty;
    } else {
      vars_.load(start_);
    }
  }
  bool intermediate_callback(Ipopt::AlgorithmMode, Index iter, Number objective, Number primal, Number, Number,
                             Number, Number, Number, Number, Index, const Ipopt::IpoptData*,
                             Ipopt::IpoptCalculatedQuantities*) override {
    iterations_ = iter;
    if (cancel_ && cancel_->load()) {
      cancelled_ = true;
      return false;
    }
    if (Clock::now() > deadline_) {
      timedOut_ = true;
      return false;
    }
    if (callback_ && secondsSince(lastReport_) >= 0.1) {
      lastReport_ = Clock::now();
      IterationReport report;
      report.iterations = iter;
      report.objective = 2 * objective;  // the user's objective is |r|^2
      report.maxViolation = primal;
      if (!callback_(report)) {
        cancelled_ = true;
        return false;
      }
    }
    return true;
  }

 private:
  static constexpr double kInfinity = 1e20;  // beyond IPOPT's nlp_*_bound_inf: no bound

  // Brings the rows (and the Jacobians if asked) to the step x from the starting variables.
  bool evaluateAt(const Eigen::Ref<const Vec>& x, bool jacobian) {
    const bool moved = !haveValues_ || x != current_;
    if (!moved && (haveJacobian_ || !jacobian)) return valuesFinite_;
    const Clock::time_point t0 = Clock::now();
    current_ = x;
    vars_.plus(start_, current_);
    valuesFinite_ = evaluator_.evaluate(&rows_, jacobian);
    haveValues_ = true;
    haveJacobian_ = jacobian && valuesFinite_;
    if (haveJacobian_) {
      objectiveJacobian_ = selectRows(rows_.jacobian, objective_);
      constraintJacobian_ = selectRows(rows_.jacobian, constraint_);
      gaussNewtonValid_ = false;
    }
    evaluationSeconds_ += secondsSince(t0);
    return valuesFinite_;
  }
  Vec objectiveValues() const { return raw::selectValues(rows_.values, objective_); }
  const SpMat& gaussNewton() {
    if (!gaussNewtonValid_) {
      gaussNewton_ = SpMat(objectiveJacobian_.transpose()) * objectiveJacobian_;
      gaussNewtonValid_ = true;
    }
    return gaussNewton_;
  }

  SpacetimeProblem& problem_;
  Variables vars_;
  RawEvaluator evaluator_;
  const SolverOptions& options_;
  const ProgressCallback& callback_;
  const std::atomic<bool>* cancel_;
  Clock::time_point deadline_;
  Clock::time_point lastReport_ = Clock::now();
  const std::vector<double> start_;
  std::vector<int> objective_, constraint_;  // rows of 1/2 |r|^2; rows held as constraints
  bool ok_ = false;

  Vec current_;
  bool haveValues_ = false, haveJacobian_ = false, valuesFinite_ = false, gaussNewtonValid_ = false;
  RawRows rows_;
  SpRow objectiveJacobian_, constraintJacobian_, jacobianPattern_;
  SpMat gaussNewton_;
  std::unique_ptr<HessianPattern> hessian_;

  int iterations_ = 0;
  bool cancelled_ = false, timedOut_ = false;
  double evaluationSeconds_ = 0, hessianSeconds_ = 0;
};

// IPOPT's options for our problems; false if IPOPT cannot start.
bool configure(Ipopt::IpoptApplication& app, const SolverOptions& options) {
  app.Options()->SetIntegerValue("print_level", 0);
  app.Options()->SetStringValue("sb", "yes");  // no banner
  app.Options()->SetStringValue("hessian_approximation", "exact");
  app.Options()->SetStringValue("mu_strategy", "adaptive");
  app.Options()->SetNumericValue("tol", 1e-8);
  app.Options()->SetNumericValue("constr_viol_tol", options.tolerance);
  app.Options()->SetNumericValue("acceptable_constr_viol_tol", options.tolerance);
  app.Options()->SetIntegerValue("max_iter", options.interiorPointMaxIterations);
  // MUMPS with approximate minimum degree: the shipped jump 9.4 -> 6.6 s against its automatic
  // choice (METIS 9.4 s); the adaptive barrier update takes 88 iterations, the monotone one 170.
  app.Options()->SetIntegerValue("mumps_pivot_order", 0);
  // IPOPT reads ./ipopt.opt by default, so a file in the working directory would change the
  // solve unseen; only SPACETIME_IPOPT_OPTIONS names an options file (print_level 5, ...).
  if (const char* file = std::getenv("SPACETIME_IPOPT_OPTIONS")) return app.Initialize(std::string(file)) == Ipopt::Solve_Succeeded;
  std::istringstream none;
  return app.Initialize(none) == Ipopt::Solve_Succeeded;
}

}  // namespace

bool interiorPointAvailable() { return true; }

SolverSummary solveInteriorPoint(SpacetimeProblem& problem, const SolverOptions& options,
                                 const ProgressCallback& callback, const std::atomic<bool>* cancel) {
  const Clock::time_point start = Clock::now();
  SolverSummary summary;
  summary.method = SolverMethod::InteriorPoint;
  auto finish = [&](SolveStatus status, const std::string& reason) {
    problem.syncFreeEnds();
    const ProblemMeasures m = measure(problem);
    summary.status = status;
    summary.converged = status == SolveStatus::Converged;
    summary.reason = reason;
    summary.objective = m.objective;
    summary.maxViolation = m.maxViolation;
    summary.worstConstraint = m.worstConstraint;
    if (!summary.converged) {
      summary.violated = unmetConstraints(problem, options.tolerance, m.maxViolation);
      summary.reason += describeViolated(summary.violated);
    }
    summary.solveSeconds = secondsSince(start);
    return summary;
  };
  if (!problem.freeEnds().empty())
    return finish(SolveStatus::InvalidOptions,
                  "the interior-point method does not handle free contact ends (freeEnd); use the augmented Lagrangian");
  Ipopt::SmartPtr<SpacetimeNlp> nlp = new SpacetimeNlp(problem, options, callback, cancel, options.deadlineFrom(start));
  if (!nlp->ok()) return finish(SolveStatus::NumericalFailure, "a row is not finite at the starting motion");

  Ipopt::SmartPtr<Ipopt::IpoptApplication> app = IpoptApplicationFactory();
  if (!configure(*app, options))
    return finish(SolveStatus::InvalidOptions, "IPOPT could not be initialised");
  const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(Ipopt::SmartPtr<Ipopt::TNLP>(GetRawPtr(nlp)));
  summary.iterations = nlp->iterations();  // counted once: there is no polish (newtonSteps stays 0)
  summary.jacobianSeconds = nlp->evaluationSeconds();
  summary.hessianSeconds = nlp->hessianSeconds();

  const ProblemMeasures m = measure(problem);
  std::ostringstream steps;
  steps << nlp->iterations() << " interior-point iterations";
  if (nlp->cancelled()) return finish(SolveStatus::Cancelled, "cancelled by the user; the last iterate is kept");
  if (nlp->timedOut()) {
    std::ostringstream limit;
    limit << "stopped after the time limit of " << options.maxSeconds << " s; the last iterate is kept";
    return finish(SolveStatus::TimeLimit, limit.str());
  }
  switch (status) {
    case Ipopt::Solve_Succeeded:
    case Ipopt::Solved_To_Acceptable_Level:
      if (m.maxViolation <= options.tolerance)
        return finish(SolveStatus::Converged, "constraints within tolerance and the KKT conditions met after " + steps.str());
      return finish(SolveStatus::NumericalFailure, "IPOPT stopped as optimal but the constraints are not within tolerance");
    case Ipopt::Infeasible_Problem_Detected:
      return finish(SolveStatus::Stalled, "the constraints conflict: the restoration phase ended at a positive minimum "
                                          "of the violation after " + steps.str());
    case Ipopt::Maximum_Iterations_Exceeded:
      return finish(SolveStatus::IterationLimit,
                    "reached the limit of " + std::to_string(options.interiorPointMaxIterations) +
                        " interior-point iterations");
    case Ipopt::Restoration_Failed:
      return finish(SolveStatus::Stalled, "the restoration phase could not reduce the violation after " + steps.str());
    default: {
      std::ostringstream why;
      why << "IPOPT stopped (status " << static_cast<int>(status) << ") after " << steps.str();
      return finish(SolveStatus::NumericalFailure, why.str());
    }
  }
}

}  // namespace spacetime

#else  // no IPOPT in this build

namespace spacetime {

bool interiorPointAvailable() { return false; }

SolverSummary solveInteriorPoint(SpacetimeProblem&, const SolverOptions&, const ProgressCallback&,
                                 const std::atomic<bool>*) {
  SolverSummary summary;
  summary.method = SolverMethod::InteriorPoint;
  summary.status = SolveStatus::InvalidOptions;
  summary.reason = "this build has no IPOPT (install coinor-libipopt-dev and rebuild) for the interior-point method";
  return summary;
}

}  // namespace spacetime

#endif
