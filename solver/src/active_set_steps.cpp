// The active-set steps from a guess of a program's active rows (see active_set_steps.h).
#include "active_set_steps.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <vector>

namespace spacetime {
namespace qp {
namespace {

// The weight of a guessed row in K~, relative to 1 + H's largest diagonal: large enough that K~
// is convex wherever the guessed rows' tangent space makes H convex (as an interior point's
// z / s weighs an active row near its end), small enough that the factorisation keeps the
// inertia it should (at 1e8 the 3D lamp's least-squares programs, H's diagonal up to 1e5, lost
// it to rounding).
constexpr double kGuessWeight = 1e5;

// The program solved by active-set steps from the guessed rows: dual steps (Goldfarb & Idnani,
// Math. Programming 27, 1983) while a row is violated, then primal steps (Nocedal & Wright,
// Algorithm 16.3) while a working row pulls. Each iterate is the minimiser of the program with
// its working rows W held as equalities. A violated row p joins as in Goldfarb and Idnani's
// method: its multiplier grows from 0, and x and the working multipliers move along the solution
// of the program with W held and that force on p, until p's bound holds (p joins W) or a pushing
// working row's multiplier reaches zero first (that row leaves and p keeps growing). Once every
// row holds, a working row that pulls leaves and x moves towards the minimiser without it, as
// far as the other rows' bounds allow (a row that blocks joins). The dual steps raise the dual
// objective and the primal ones lower the objective, so the working set does not cycle as the
// primal-dual corrections of all missed rows at once did (docs/design.md, Solver item 6).
//
// Guessed rows that pull leave before the first dual step, the most pulling first, unless H would
// not be convex on the tangent space of the rest: dropping every pulling row of the jump's
// exact-Hessian programs' guesses made them need a shift of 1 where the interior point needs
// 1e-3, and moved the steps' path; kept through the dual steps instead, a row pulling with 5e5
// dragged the hurdle's iterates across dozens of rows and the steps ran to 400 changes. Where a
// working set on the way is not convex, the steps start again from the guess with the shift
// tenfold (up to four times), as the interior point raises its shift when an iterate's K loses
// its inertia.
//
// The linear algebra is one LDL^T of K~ per attempt: K with the guessed rows B weighted rho
// (K~ is then convex where the guess's tangent space needs it, with the interior point's shift
// rule). Adding rho/2 |C_B x - d_B|^2 to the objective moves no minimiser while B's rows are
// held; the rows of B that left W (D) have it taken out again by a border row each, with 1/rho
// on the diagonal (Sherman-Morrison). With R = W and D bordered,
//     [ K~    C_R^T ] [ u ]   [ r ]
//     [ C_R   E     ] [ l ] = [ t ],   l = F^-1 (C_R K~^-1 r - t),  u = K~^-1 r - U l,
// E = 0 on W and 1/rho on D (t = d on both), U = K~^-1 C_R^T (one solve per row, kept) and the
// dense F = C_R U - E. A row joins or leaves at the cost of one solve and F's factorisation.
// The program on W is convex on W's tangent space exactly when F has |W| positive and |D|
// negative pivots (Sylvester's law of inertia on the bordered matrix, whose other block K~ has
// the inertia of a convex program). A row of D that joins again makes B = W and K~ anew.
class GuessedActiveSet {
 public:
  GuessedActiveSet(const QuadraticProgram& qp, const SpMat& H, const QpOptions& options, ReducedSystem& system,
                   double dualScale, double primalScale)
      : qp_(qp), H_(H), options_(options), system_(system), dualScale_(dualScale), primalScale_(primalScale),
        n_(static_cast<int>(qp.gradient.size())), me_(static_cast<int>(qp.equalities.rows())),
        mi_(static_cast<int>(qp.inequalities.rows())), rho_(kGuessWeight * (1 + system.largestDiagonal())),
        rowNorm_(mi_) {
    for (int i = 0; i < mi_; ++i) rowNorm_[i] = std::max(1e-300, qp.inequalities.row(i).norm());
  }

  // Attempts from the guess with the shift the guess's factorisation needs, then, where a
  // working set on the way lost convexity, with ten times the shift (as the interior point
  // raises it when an iterate's K loses its inertia).
  bool solve(QpResult* out) {
    for (int attempt = 0; attempt < kShiftAttempts; ++attempt) {
      if (attempt > 0) {
        if (!convexityLost_ || options_.convex) return false;
        system_.raiseShift(std::max(10 * system_.shift(), 1e-8 * std::max(1.0, system_.largestDiagonal())));
      }
      W_.clear(), B_.clear(), D_.clear(), columns_.clear();
      convexityLost_ = false;
      changes_ = 0;
      if (attemptFromGuess(out)) return true;
    }
    return false;
  }

 private:
  static constexpr int kShiftAttempts = 5;
  static constexpr int kMaxStartRows = 80;  // larger guesses: the interior point (a solve per row)
  // Per attempt; beyond, the interior point is cheaper. Counted over all attempts, the heavy
  // lamp's programs that needed the shift raised twice ran out of changes in the last attempt
  // (5 of its 65 guessed programs; 33 steps instead of 32, CPU 12.9-13.5 s against 7.1-11.0 s).
  static constexpr int kMaxChanges = 100;

  bool attemptFromGuess(QpResult* out) {
    const SpRow& C = qp_.inequalities;
    const double primalTolerance = options_.tolerance * primalScale_, dualTolerance = options_.tolerance * dualScale_;
    for (int i = 0; i < mi_; ++i)
      if (options_.activeGuess[static_cast<size_t>(i)]) W_.push_back(i);
    if (static_cast<int>(W_.size()) > kMaxStartRows || !factorise(true)) return stop();
    if (dropDependentRows() && !factorise(true)) return stop();
    if (!convex_) return stop();
    minimiserOnW(&u_, &lambda_);
    // Guessed rows that pull leave first, most pulling first, while the program on the rest
    // stays convex on its tangent space; the others wait for the primal steps.
    for (std::vector<int> staying;;) {
      Eigen::Index j = -1;
      for (Eigen::Index a = 0; a < lambda_.size(); ++a)
        if (lambda_[a] < -dualTolerance && (j < 0 || lambda_[a] < lambda_[j]) &&
            std::find(staying.begin(), staying.end(), W_[static_cast<size_t>(a)]) == staying.end())
          j = a;
      if (j < 0) break;
      const int row = W_[static_cast<size_t>(j)];
      W_.erase(W_.begin() + j);
      D_.push_back(row);
      factorF();
      if (!convex_) {
        D_.pop_back();
        W_.insert(W_.begin() + j, row);
        factorF();
        staying.push_back(row);
      }
      minimiserOnW(&u_, &lambda_);
    }
    for (;;) {
      const Vec excess = C * u_.head(n_) - qp_.inequalityBounds;
      const std::vector<char> held = inW();
      int p = -1;
      double worst = 0;
      for (int i = 0; i < mi_; ++i)
        if (!held[static_cast<size_t>(i)] && excess[i] > primalTolerance && excess[i] / rowNorm_[i] > worst) {
          worst = excess[i] / rowNorm_[i];
          p = i;
        }
      if (p >= 0) {
        if (!dualStep(p)) return stop();
        continue;
      }
      if (W_.empty()) break;
      Eigen::Index j;
      if (lambda_.minCoeff(&j) >= -dualTolerance) break;  // every row holds and every working row pushes
      if (!leave(static_cast<size_t>(j)) || !primalSteps()) return stop();
    }
    return refine(out);
  }

  // Gives up this attempt, noting whether a working set had lost convexity (a larger shift
  // may then carry the steps through).
  bool stop() {
    convexityLost_ = convexityLost_ || !convex_;
    return false;
  }

  // K~ with B = W and D empty, its solution u0 for the program's right-hand side, and F.
  bool factorise(bool allowShift) {
    B_ = W_;
    D_.clear();
    Vec w = Vec::Zero(mi_);
    for (int j : B_) w[j] = rho_;
    if (!system_.factorise(w, allowShift && !options_.convex)) {
      convex_ = allowShift;  // without a shift allowed, K~ on the new B has lost convexity
      return stop();
    }
    Vec rhs(n_ + me_);
    rhs.head(n_) = -qp_.gradient + qp_.inequalities.transpose() * Vec(w.cwiseProduct(qp_.inequalityBounds));
    rhs.tail(me_) = qp_.equalityTargets;
    u0_ = system_.solve(rhs);
    columns_.clear();
    factorF();
    return true;
  }

  // K~^-1 [C_j^T; 0], kept while the factorisation is.
  const Vec& column(int j) {
    auto it = columns_.find(j);
    if (it == columns_.end()) {
      Vec e = Vec::Zero(n_ + me_);
      e.head(n_) = Vec(qp_.inequalities.row(j).transpose());
      it = columns_.emplace(j, system_.solve(e)).first;
    }
    return it->second;
  }
  double rowDot(int j, const Vec& v) const { return qp_.inequalities.row(j).dot(v.head(n_)); }
  int bordered(size_t a) const { return a < W_.size() ? W_[a] : D_[a - W_.size()]; }  // R = W, then D
  size_t borderCount() const { return W_.size() + D_.size(); }

  // F over R, its factorisation and whether the program on W is convex on W's tangent space.
  void factorF() {
    const int k = static_cast<int>(borderCount());
    F_.resize(k, k);
    for (int a = 0; a < k; ++a)
      for (int b = 0; b < k; ++b) F_(a, b) = rowDot(bordered(static_cast<size_t>(a)), column(bordered(static_cast<size_t>(b))));
    F_ = (0.5 * (F_ + F_.transpose())).eval();
    for (size_t a = W_.size(); a < borderCount(); ++a) F_(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(a)) -= 1 / rho_;
    Ff_.compute(F_);
    const auto& pivots = Ff_.vectorD();
    convex_ = Ff_.info() == Eigen::Success && (pivots.array() > 0).count() == static_cast<Eigen::Index>(W_.size()) &&
              (pivots.array() < 0).count() == static_cast<Eigen::Index>(D_.size());
  }

  std::vector<char> inW() const {
    std::vector<char> held(static_cast<size_t>(mi_), 0);
    for (int j : W_) held[static_cast<size_t>(j)] = 1;
    return held;
  }

  // Working rows that depend on the ones before them (a cone's rows where its force vanishes)
  // leave: their Schur complement against the kept rows vanishes (a Cholesky factorisation of
  // F over the kept rows, grown a row at a time). True if any left.
  bool dropDependentRows() {
    const Eigen::Index k = static_cast<Eigen::Index>(W_.size());
    if (k == 0) return false;
    const double scale = F_.diagonal().cwiseAbs().maxCoeff();
    Eigen::MatrixXd L = Eigen::MatrixXd::Zero(k, k);
    std::vector<Eigen::Index> kept;
    for (Eigen::Index j = 0; j < k; ++j) {
      const Eigen::Index m = static_cast<Eigen::Index>(kept.size());
      Vec y(m);
      for (Eigen::Index a = 0; a < m; ++a) {
        double v = F_(kept[static_cast<size_t>(a)], j);
        for (Eigen::Index b = 0; b < a; ++b) v -= L(a, b) * y[b];
        y[a] = v / L(a, a);
      }
      const double pivot = F_(j, j) - y.squaredNorm();
      if (!(pivot > 1e-10 * scale)) continue;
      L.row(m).head(m) = y.transpose();
      L(m, m) = std::sqrt(pivot);
      kept.push_back(j);
    }
    if (static_cast<Eigen::Index>(kept.size()) == k) return false;
    std::vector<int> rows;
    for (Eigen::Index j : kept) rows.push_back(W_[static_cast<size_t>(j)]);
    W_ = rows;
    factorF();
    return true;
  }

  // The solution of the bordered system for K~'s right-hand side v (= K~^-1 r) and the border
  // targets t: u and the border's l (the first |W| of them W's multipliers).
  void borderedSolve(const Vec& v, const Vec& t, Vec* u, Vec* l) {
    *l = t.size() ? Vec(Ff_.solve(Vec(rowsTimes(v) - t))) : Vec();
    *u = v;
    for (size_t a = 0; a < borderCount(); ++a) *u -= (*l)[static_cast<Eigen::Index>(a)] * column(bordered(a));
  }
  Vec rowsTimes(const Vec& v) const {
    Vec out(static_cast<Eigen::Index>(borderCount()));
    for (size_t a = 0; a < borderCount(); ++a) out[static_cast<Eigen::Index>(a)] = rowDot(bordered(a), v);
    return out;
  }

  // The minimiser with W held and its working multipliers.
  void minimiserOnW(Vec* u, Vec* lambda) {
    Vec t(static_cast<Eigen::Index>(borderCount())), l;
    for (size_t a = 0; a < borderCount(); ++a) t[static_cast<Eigen::Index>(a)] = qp_.inequalityBounds[bordered(a)];
    borderedSolve(u0_, t, u, &l);
    *lambda = l.head(static_cast<Eigen::Index>(W_.size()));
  }

  // W less its row at `index` (a row of B joins D); false if the program on the rest is not
  // convex on its tangent space.
  bool leave(size_t index) {
    const int j = W_[index];
    W_.erase(W_.begin() + static_cast<std::ptrdiff_t>(index));
    if (std::find(B_.begin(), B_.end(), j) != B_.end()) D_.push_back(j);
    factorF();
    return convex_ && ++changes_ <= kMaxChanges;
  }

  // Goldfarb and Idnani's steps adding the violated row p (its multiplier t from 0).
  bool dualStep(int p) {
    if (std::find(D_.begin(), D_.end(), p) != D_.end()) {  // a row of B back: B = W again
      if (!factorise(false) || !convex_) return stop();
      minimiserOnW(&u_, &lambda_);
    }
    if (++changes_ > kMaxChanges) return stop();
    const Vec vp = column(p);
    const double gamma = rowDot(p, vp);
    for (;;) {
      const Eigen::Index k = static_cast<Eigen::Index>(W_.size());
      Vec su, a;  // d(u)/dt and the border's change; the working multipliers change by -a
      borderedSolve(-vp, Vec::Zero(static_cast<Eigen::Index>(borderCount())), &su, &a);
      a = Vec(-a.head(k));  // evaluated first: the assignment resizes a
      const double slope = rowDot(p, su);  // <= 0: the force on p lowers C_p x
      const double excess = rowDot(p, u_) - qp_.inequalityBounds[p];
      double full = std::numeric_limits<double>::infinity(), partial = full;
      Eigen::Index leaving = -1;
      if (slope < -1e-10 * std::abs(gamma)) full = std::max(0.0, excess) / -slope;
      for (Eigen::Index b = 0; b < k; ++b)
        if (lambda_[b] >= 0 && a[b] > 0 && lambda_[b] / a[b] < partial) {
          partial = lambda_[b] / a[b];
          leaving = b;
        }
      if (!std::isfinite(full) && !std::isfinite(partial)) return stop();  // no feasible point
      const double t = std::min(full, partial);
      u_ += t * su;
      lambda_ -= t * a;
      if (full <= partial) {
        W_.push_back(p);
        factorF();
        if (!convex_) return stop();
        minimiserOnW(&u_, &lambda_);
        return true;
      }
      Vec rest(k - 1);
      for (Eigen::Index b = 0, c = 0; b < k; ++b)
        if (b != leaving) rest[c++] = lambda_[b];
      lambda_ = rest;
      if (!leave(static_cast<size_t>(leaving))) return stop();
    }
  }

  // From a feasible point, towards the minimiser on W, each row that blocks the way joining.
  bool primalSteps() {
    const SpRow& C = qp_.inequalities;
    for (;;) {
      Vec target, lambda;
      minimiserOnW(&target, &lambda);
      const Vec step = target - u_;
      const Vec excess = C * u_.head(n_) - qp_.inequalityBounds, rate = C * step.head(n_);
      const std::vector<char> held = inW();
      double alpha = 1;
      int blocking = -1;
      for (int i = 0; i < mi_; ++i)
        if (!held[static_cast<size_t>(i)] && rate[i] > 0 && std::max(0.0, -excess[i]) < alpha * rate[i]) {
          alpha = std::max(0.0, -excess[i]) / rate[i];
          blocking = i;
        }
      if (blocking < 0) {
        u_ = target;
        lambda_ = lambda;
        return true;
      }
      u_ += alpha * step;
      if (std::find(D_.begin(), D_.end(), blocking) != D_.end()) {  // a row of B back: B = W again
        W_.push_back(blocking);
        if (!factorise(false) || !convex_) return stop();
      } else {
        W_.push_back(blocking);
        factorF();
      }
      if (!convex_ || ++changes_ > kMaxChanges) return stop();
    }
  }

  // Newton steps on the program's KKT conditions with W held (the start's weight and the
  // regularisation taken out), then the verdict by the interior point's measure.
  bool refine(QpResult* out) {
    const SpRow& A = qp_.equalities;
    const SpRow& C = qp_.inequalities;
    const Eigen::Index k = static_cast<Eigen::Index>(W_.size());
    Vec x, y, z, rd, re, excess;
    double error = std::numeric_limits<double>::infinity();
    for (int pass = 0;; ++pass) {
      x = u_.head(n_), y = u_.tail(me_);
      z = Vec::Zero(mi_);
      for (Eigen::Index a = 0; a < k; ++a) z[W_[static_cast<size_t>(a)]] = lambda_[a];
      rd = H_ * x + qp_.gradient + A.transpose() * y + C.transpose() * z;
      if (system_.shift() > 0) rd += system_.shift() * system_.metric().cwiseProduct(x);
      re = A * x - qp_.equalityTargets;
      excess = C * x - qp_.inequalityBounds;
      Vec t = Vec::Zero(static_cast<Eigen::Index>(borderCount()));  // D's rows: 0
      for (Eigen::Index a = 0; a < k; ++a) t[a] = -excess[W_[static_cast<size_t>(a)]];
      error = std::max(infNorm(rd) / dualScale_,
                       std::max({infNorm(re), infNorm(t), infNorm(excess.cwiseMax(0.0))}) / primalScale_);
      if (error <= 1e-2 * options_.tolerance || pass == 3) break;
      // K~ holds H + rho C_B^T C_B: on B's rows still in W its correction moves to the right.
      Vec weighted = Vec::Zero(mi_);
      for (int j : W_)
        if (std::find(B_.begin(), B_.end(), j) != B_.end()) weighted[j] = rho_ * excess[j];
      Vec r(n_ + me_);
      r.head(n_) = -rd - C.transpose() * weighted;
      r.tail(me_) = -re;
      Vec du, dl;
      borderedSolve(system_.solve(r), t, &du, &dl);
      u_ += du;
      lambda_ += dl.head(k);
    }
    if (!(error <= options_.tolerance) || (k && lambda_.minCoeff() < -options_.tolerance * dualScale_)) return stop();
    out->converged = out->fromGuess = true;
    out->x = x, out->y = y, out->z = z.cwiseMax(0.0);
    out->active = inW();
    out->dualResidual = infNorm(rd);
    out->primalResidual = std::max(infNorm(re), infNorm(excess.cwiseMax(0.0)));
    out->complementarity = 0;
    out->shift = system_.shift();
    out->activeSetChanges = changes_;
    out->reason = "KKT conditions met by active-set steps from the guessed rows";
    return true;
  }

  const QuadraticProgram& qp_;
  const SpMat& H_;
  const QpOptions& options_;
  ReducedSystem& system_;
  const double dualScale_, primalScale_;
  const int n_, me_, mi_;
  const double rho_;
  Vec rowNorm_;  // |C_i|: the most violated row is the one farthest from its bound
  std::vector<int> W_, B_, D_;  // working rows, the factorisation's weighted rows, B's rows not in W
  Vec u0_, u_, lambda_;
  std::unordered_map<int, Vec> columns_;
  Eigen::MatrixXd F_;
  Eigen::LDLT<Eigen::MatrixXd> Ff_;
  bool convex_ = false, convexityLost_ = false;
  int changes_ = 0;
};

}  // namespace

bool solveFromActiveGuess(const QuadraticProgram& qp, const SpMat& H, const QpOptions& options, ReducedSystem& system,
                          double dualScale, double primalScale, QpResult* out) {
  return GuessedActiveSet(qp, H, options, system, dualScale, primalScale).solve(out);
}

}  // namespace qp
}  // namespace spacetime
