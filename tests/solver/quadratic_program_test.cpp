// The interior-point quadratic program solver against independent truths: the Euclidean
// projection onto the probability simplex (the sort-and-threshold algorithm of Duchi et al.,
// ICML 2008) and, for small random programs, the minimum over every choice of active
// inequalities of the equality-constrained program's solution (a dense KKT solve each),
// keeping the feasible ones whose multipliers push; the same minimiser from a guess of the
// active rows, right or wrong, by active-set steps without the interior point. Also: a concave H
// gets the inertia correction (and none where a guessed row's tangent space makes it convex),
// redundant equality rows still solve, and a program with no feasible point ends not converged
// with a reason rather than a wrong answer.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <functional>
#include <limits>
#include <random>

#include "solver/quadratic_program.h"

namespace spacetime {
namespace {

using Vec = Eigen::VectorXd;
using Mat = Eigen::MatrixXd;
using SpRow = Eigen::SparseMatrix<double, Eigen::RowMajor>;
using Vec2 = Eigen::Vector2d;

QuadraticProgram program(const Mat& H, const Vec& g, const Mat& A, const Vec& b, const Mat& C, const Vec& d) {
  QuadraticProgram qp;
  qp.hessian = H.sparseView();
  qp.gradient = g;
  qp.equalities = SpRow(A.sparseView());
  qp.equalityTargets = b;
  qp.inequalities = SpRow(C.sparseView());
  qp.inequalityBounds = d;
  return qp;
}

// Duchi et al. 2008, Figure 1: the projection of p onto {x >= 0, sum x = 1}.
Vec simplexProjection(const Vec& p) {
  std::vector<double> u(p.data(), p.data() + p.size());
  std::sort(u.rbegin(), u.rend());
  double sum = 0, theta = 0;
  for (size_t j = 0; j < u.size(); ++j) {
    sum += u[j];
    const double t = (sum - 1) / static_cast<double>(j + 1);
    if (u[j] - t > 0) theta = t;
  }
  return (p.array() - theta).cwiseMax(0.0);
}

// A point of n normally distributed coordinates (standard deviation 0.3), and the program of its
// projection onto the simplex: min 1/2 |x - p|^2 = 1/2 x.x - p.x + const, sum x = 1, -x <= 0.
Vec randomPoint(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0, 1);
  Vec p(n);
  for (int i = 0; i < n; ++i) p[i] = 0.3 * normal(rng);
  return p;
}
QuadraticProgram simplexProjectionProgram(const Vec& p) {
  const Eigen::Index n = p.size();
  return program(Mat::Identity(n, n), -p, Mat::Ones(1, n), Vec::Ones(1), -Mat::Identity(n, n), Vec::Zero(n));
}

TEST(QuadraticProgram, ProjectsOntoTheSimplexAsTheSortingAlgorithmDoes) {
  const Vec p = randomPoint(60, 7);
  const QuadraticProgram qp = simplexProjectionProgram(p);
  // A bound whose multiplier is nearly zero sits at x = mu / z: at the default tolerance (mean
  // complementarity 1e-9) one coordinate was 1.3e-6 off; at 1e-12, 1e-13.
  QpOptions options;
  options.tolerance = 1e-12;
  const QpResult r = solveQuadraticProgram(qp, options);
  ASSERT_TRUE(r.converged) << r.reason;
  const Vec truth = simplexProjection(p);
  EXPECT_LT((r.x - truth).lpNorm<Eigen::Infinity>(), 1e-10);
  EXPECT_GT((truth.array() == 0).count(), 10);  // many bounds active: a real test of the inequalities
  EXPECT_EQ(r.shift, 0.0);
  EXPECT_LT(r.iterations, 30);
}

// A guess the active-set steps cannot start from (more than their 80 rows: every one of the
// simplex's 100 bounds) goes to the interior point, which finds the projection; with guessOnly
// the solve stops unsolved instead and says why (the warm Newton polish then finds the active
// set its own way, cheaper than a solve from scratch).
TEST(QuadraticProgram, AGuessOnlySolveStopsWhereTheStepsCannotStart) {
  const int n = 100;
  const Vec p = randomPoint(n, 11);
  const QuadraticProgram qp = simplexProjectionProgram(p);
  QpOptions options;
  options.activeGuess.assign(n, 1);
  options.guessOnly = true;
  const QpResult stopped = solveQuadraticProgram(qp, options);
  EXPECT_FALSE(stopped.converged);
  EXPECT_FALSE(stopped.reason.empty());
  options.guessOnly = false;
  options.tolerance = 1e-12;
  const QpResult r = solveQuadraticProgram(qp, options);
  ASSERT_TRUE(r.converged) << r.reason;
  EXPECT_FALSE(r.fromGuess);
  EXPECT_LT((r.x - simplexProjection(p)).lpNorm<Eigen::Infinity>(), 1e-10);
}

// The minimiser by enumeration: for every subset of inequalities held as equalities, the KKT
// point of the equality-constrained program; the feasible one with pushing multipliers and the
// lowest objective.
Vec enumeratedMinimiser(const Mat& H, const Vec& g, const Mat& A, const Vec& b, const Mat& C, const Vec& d) {
  const int n = static_cast<int>(g.size()), me = static_cast<int>(A.rows()), mi = static_cast<int>(C.rows());
  double best = std::numeric_limits<double>::infinity();
  Vec bestX;
  for (int mask = 0; mask < (1 << mi); ++mask) {
    std::vector<int> active;
    for (int i = 0; i < mi; ++i)
      if (mask & (1 << i)) active.push_back(i);
    const int m = me + static_cast<int>(active.size());
    if (m > n) continue;
    Mat K = Mat::Zero(n + m, n + m);
    Vec rhs(n + m);
    K.topLeftCorner(n, n) = H;
    rhs.head(n) = -g;
    for (int i = 0; i < me; ++i) {
      K.block(n + i, 0, 1, n) = A.row(i);
      rhs[n + i] = b[i];
    }
    for (size_t k = 0; k < active.size(); ++k) {
      K.block(n + me + k, 0, 1, n) = C.row(active[k]);
      rhs[n + me + k] = d[active[k]];
    }
    K.topRightCorner(n, m) = K.bottomLeftCorner(m, n).transpose();
    Eigen::FullPivLU<Mat> lu(K);
    if (lu.rank() < n + m) continue;
    const Vec sol = lu.solve(rhs);
    const Vec x = sol.head(n);
    if (((C * x - d).array() > 1e-9).any()) continue;
    // The solve gives H x + A^T y + C_A^T z = -g: the Lagrange multipliers of
    // f + y.(A x - b) + z.(C x - d), so an active inequality pushes when its z >= 0.
    bool pushes = true;
    for (size_t k = 0; k < active.size(); ++k) pushes = pushes && sol[n + me + static_cast<int>(k)] >= -1e-9;
    if (!pushes) continue;
    const double f = 0.5 * x.dot(H * x) + g.dot(x);
    if (f < best) {
      best = f;
      bestX = x;
    }
  }
  return bestX;
}

// A random convex program with a feasible point strictly inside every inequality.
struct DenseProgram {
  Mat H, A, C;
  Vec g, b, d;
};
DenseProgram randomProgram(std::mt19937& rng, int n, int me, int mi) {
  std::normal_distribution<double> normal(0, 1);
  std::uniform_real_distribution<double> uniform(0, 1);
  auto random = [&](int r, int c) { return Mat(Mat::NullaryExpr(r, c, [&] { return normal(rng); })); };
  DenseProgram p;
  const Mat M = random(n, n);
  p.H = M.transpose() * M + 0.05 * Mat::Identity(n, n);
  p.g = 3 * random(n, 1);
  p.A = random(me, n);
  p.C = random(mi, n);
  const Vec feasible = random(n, 1);
  p.b = p.A * feasible;
  p.d = p.C * feasible;
  for (int i = 0; i < mi; ++i) p.d[i] += uniform(rng);
  return p;
}

TEST(QuadraticProgram, MatchesEnumerationOfActiveSetsOnRandomPrograms) {
  std::mt19937 rng(11);
  int withActiveRows = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const int n = 5, mi = 8;
    const auto [H, A, C, g, b, d] = randomProgram(rng, n, trial % 3, mi);
    const Vec truth = enumeratedMinimiser(H, g, A, b, C, d);
    ASSERT_EQ(truth.size(), n) << "trial " << trial;
    const QpResult r = solveQuadraticProgram(program(H, g, A, b, C, d));
    ASSERT_TRUE(r.converged) << "trial " << trial << ": " << r.reason;
    EXPECT_LT((r.x - truth).lpNorm<Eigen::Infinity>(), 1e-6) << "trial " << trial;
    EXPECT_GE(r.z.minCoeff(), 0.0);
    if (((C * truth - d).array() > -1e-9).any()) ++withActiveRows;
  }
  EXPECT_GT(withActiveRows, 20);
}

TEST(QuadraticProgram, RowsSharingColumnsAndPrivateColumnsGiveTheEnumeratedMinimiser) {
  // The spacetime programs' inequality rows come in runs on one sample's columns, and an
  // elastic program's violated rows each have a slack column no other row touches; K sums the
  // runs densely and the private columns' pairs row by row. Rows 0-2 share columns 0-3, row 3
  // shares them and has private column 5, rows 4-5 share columns 2-4, row 6 has column 4 and
  // private column 6. Each program is solved from scratch and from its active rows as the
  // guess; both must be the enumerated minimiser, the interior point in as few iterations as a
  // dense program's (a wrong K still converges, slowly, from its exact residuals).
  std::mt19937 rng(31);
  std::normal_distribution<double> normal(0, 1);
  std::uniform_real_distribution<double> uniform(0, 1);
  const std::vector<std::vector<int>> rows{{0, 1, 2, 3}, {0, 1, 2, 3}, {0, 1, 2, 3}, {0, 1, 2, 3, 5},
                                           {2, 3, 4},    {2, 3, 4},    {4, 6}};
  const int n = 7, mi = static_cast<int>(rows.size());
  int withActiveRows = 0;
  for (int trial = 0; trial < 30; ++trial) {
    const Mat M = Mat::NullaryExpr(n, n, [&] { return normal(rng); });
    const Mat H = M.transpose() * M + 0.05 * Mat::Identity(n, n);
    const Vec g = 3 * Vec::NullaryExpr(n, [&] { return normal(rng); });
    Mat C = Mat::Zero(mi, n);
    for (int i = 0; i < mi; ++i)
      for (int c : rows[static_cast<size_t>(i)]) C(i, c) = normal(rng);
    const Vec feasible = Vec::NullaryExpr(n, [&] { return normal(rng); });
    const Vec d = C * feasible + Vec::NullaryExpr(mi, [&] { return uniform(rng); });
    const Mat A = Mat::Zero(0, n);
    const Vec b = Vec::Zero(0);
    const Vec truth = enumeratedMinimiser(H, g, A, b, C, d);
    ASSERT_EQ(truth.size(), n) << "trial " << trial;
    const QuadraticProgram qp = program(H, g, A, b, C, d);
    const QpResult scratch = solveQuadraticProgram(qp);
    ASSERT_TRUE(scratch.converged) << "trial " << trial << ": " << scratch.reason;
    EXPECT_LT((scratch.x - truth).lpNorm<Eigen::Infinity>(), 1e-5 * (1 + truth.lpNorm<Eigen::Infinity>()))
        << "trial " << trial;
    EXPECT_LE(scratch.iterations, 25) << "trial " << trial;
    QpOptions options;
    options.activeGuess.assign(static_cast<size_t>(mi), 0);
    for (int i = 0; i < mi; ++i) options.activeGuess[static_cast<size_t>(i)] = C.row(i).dot(truth) - d[i] > -1e-9;
    withActiveRows += std::count(options.activeGuess.begin(), options.activeGuess.end(), 1) > 0;
    const QpResult guessed = solveQuadraticProgram(qp, options);
    ASSERT_TRUE(guessed.converged) << "trial " << trial << ": " << guessed.reason;
    EXPECT_TRUE(guessed.fromGuess) << "trial " << trial << ": " << guessed.reason;
    EXPECT_LT((guessed.x - truth).lpNorm<Eigen::Infinity>(), 1e-7) << "trial " << trial;
  }
  EXPECT_GT(withActiveRows, 15);
}

TEST(QuadraticProgram, AGuessOfTheActiveRowsRightOrWrongIsSolvedByActiveSetStepsToTheMinimiser) {
  // Random convex programs with active rows, each solved with the active rows of the enumerated
  // minimiser as the guess (one factorisation, no change of the working set, no interior-point
  // iteration) and with guesses wrong in every way - an inactive row held, an active row left
  // out, both, several at random, none held at all - which the dual and primal steps correct to
  // the same minimiser, still without the interior point.
  std::mt19937 rng(23);
  std::bernoulli_distribution coin(0.3);
  int corrected = 0, fromScratch = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const int n = 6, mi = 9;
    const auto [H, A, C, g, b, d] = randomProgram(rng, n, trial % 3, mi);
    const Vec truth = enumeratedMinimiser(H, g, A, b, C, d);
    ASSERT_EQ(truth.size(), n) << "trial " << trial;
    const QuadraticProgram qp = program(H, g, A, b, C, d);
    std::vector<char> right(mi, 0);
    int inactiveRow = -1;
    for (int i = 0; i < mi; ++i)
      if (C.row(i).dot(truth) - d[i] > -1e-9) {
        right[static_cast<size_t>(i)] = 1;
      } else {
        inactiveRow = i;
      }
    QpOptions options;
    options.activeGuess = right;
    const QpResult r = solveQuadraticProgram(qp, options);
    ASSERT_TRUE(r.converged) << "trial " << trial << ": " << r.reason;
    EXPECT_TRUE(r.fromGuess) << "trial " << trial << ": " << r.reason;
    EXPECT_EQ(r.iterations, 0);
    EXPECT_EQ(r.activeSetChanges, 0) << "trial " << trial;
    EXPECT_LT((r.x - truth).lpNorm<Eigen::Infinity>(), 1e-7) << "trial " << trial;
    EXPECT_LE((C * r.x - d).maxCoeff(), 1e-8);
    EXPECT_GE(r.z.minCoeff(), 0.0);
    std::vector<std::vector<char>> wrong;
    if (inactiveRow >= 0) {
      wrong.push_back(right);
      wrong.back()[static_cast<size_t>(inactiveRow)] = 1;  // an inactive row held: it would pull
    }
    for (int i = 0; i < mi; ++i)
      if (right[static_cast<size_t>(i)]) {
        wrong.push_back(right);
        wrong.back()[static_cast<size_t>(i)] = 0;  // an active row left out: its bound crossed
        if (inactiveRow >= 0) {
          wrong.push_back(wrong.back());
          wrong.back()[static_cast<size_t>(inactiveRow)] = 1;
        }
        break;
      }
    wrong.emplace_back(mi, 0);
    std::vector<char> random(mi);
    for (auto& held : random) held = coin(rng);
    wrong.push_back(random);
    for (const auto& guess : wrong) {
      if (guess == right) continue;
      options.activeGuess = guess;
      const QpResult w = solveQuadraticProgram(qp, options);
      ASSERT_TRUE(w.converged) << "trial " << trial << ": " << w.reason;
      EXPECT_LT((w.x - truth).lpNorm<Eigen::Infinity>(), 1e-7) << "trial " << trial;
      EXPECT_LE((C * w.x - d).maxCoeff(), 1e-8);
      EXPECT_GE(w.z.minCoeff(), 0.0);
      EXPECT_EQ(w.active, right) << "trial " << trial;
      corrected += w.fromGuess && w.activeSetChanges > 0;
      fromScratch += !w.fromGuess;
    }
  }
  EXPECT_GT(corrected, 100);
  EXPECT_EQ(fromScratch, 0);
}

TEST(QuadraticProgram, AGuessKeepsAHessianConvexOnlyOnItsRowsTangentSpaceUnshifted) {
  // min 1/2 (y^2 - x^2) + 0.1 x subject to x <= 1, -x <= 1, x + 2y <= 3: H is concave in x, so an
  // interior point shifts it; on the tangent space of the row x <= 1 it is convex (y alone),
  // and that row guessed active gives the program's local minimiser x = 1, y = 0 unshifted,
  // with the multiplier 1 - 0.1 = 0.9 from stationarity. A guess of no rows cannot be solved
  // without a shift: H is then concave on the whole space.
  const Mat H = Vec(Vec2(-1.0, 1.0)).asDiagonal();
  const Vec g = Vec2(0.1, 0.0);
  const Mat C = (Mat(3, 2) << 1, 0, -1, 0, 1, 2).finished();
  const Vec d = Eigen::Vector3d(1, 1, 3);
  const QuadraticProgram qp = program(H, g, Mat::Zero(0, 2), Vec::Zero(0), C, d);
  QpOptions options;
  options.activeGuess = {1, 0, 0};
  const QpResult r = solveQuadraticProgram(qp, options);
  ASSERT_TRUE(r.converged) << r.reason;
  EXPECT_TRUE(r.fromGuess) << r.reason;
  EXPECT_EQ(r.shift, 0.0);
  EXPECT_NEAR(r.x[0], 1.0, 1e-9);
  EXPECT_NEAR(r.x[1], 0.0, 1e-9);
  EXPECT_NEAR(r.z[0], 0.9, 1e-8);
  options.activeGuess = {0, 0, 0};
  const QpResult none = solveQuadraticProgram(qp, options);
  ASSERT_TRUE(none.converged) << none.reason;
  EXPECT_GT(none.shift, 0.0);
}

TEST(QuadraticProgram, AWorkspaceSharedByProgramsWithChangingRowsGivesEachItsOwnSolution) {
  // The SQP-type methods solve many programs of one problem on one workspace while inequality
  // rows come and go; a program whose entries lie outside the pattern built so far makes it
  // grow. Each program must get the solution a fresh workspace gives it, and the first again
  // at the end (on the grown pattern).
  std::mt19937 rng(5);
  std::normal_distribution<double> normal(0, 1);
  std::uniform_int_distribution<int> column(0, 29);
  const int n = 30, me = 4;
  Mat H = Mat::Zero(n, n);  // banded and convex
  for (int i = 0; i < n; ++i) {
    H(i, i) = 4;
    if (i + 1 < n) H(i, i + 1) = H(i + 1, i) = -1;
  }
  Mat A = Mat::Zero(me, n);
  for (int i = 0; i < me; ++i)
    for (int j = 5 * i; j < 5 * i + 3; ++j) A(i, j) = normal(rng);
  const Vec g = 5 * Vec::NullaryExpr(n, [&] { return normal(rng); });
  const Vec b = Vec::Zero(me);
  auto randomRows = [&](int rows) {
    Mat C = Mat::Zero(rows, n);
    for (int i = 0; i < rows; ++i)
      for (int k = 0; k < 3; ++k) C(i, column(rng)) = normal(rng);
    return C;
  };
  QpWorkspace shared;
  std::vector<QuadraticProgram> programs;
  for (int trial = 0; trial < 12; ++trial) {
    const Mat C = randomRows(6 + trial);
    programs.push_back(program(H, g, A, b, C, Vec::Constant(C.rows(), 0.5)));
  }
  programs.push_back(programs.front());
  for (size_t k = 0; k < programs.size(); ++k) {
    const QpResult fresh = solveQuadraticProgram(programs[k]);
    const QpResult reused = solveQuadraticProgram(programs[k], {}, &shared);
    ASSERT_TRUE(fresh.converged) << "program " << k << ": " << fresh.reason;
    ASSERT_TRUE(reused.converged) << "program " << k << ": " << reused.reason;
    EXPECT_LT((fresh.x - reused.x).lpNorm<Eigen::Infinity>(), 1e-7) << "program " << k;
    EXPECT_LT((fresh.z - reused.z).lpNorm<Eigen::Infinity>(), 1e-6) << "program " << k;
    EXPECT_LE((Mat(programs[k].inequalities) * reused.x - programs[k].inequalityBounds).maxCoeff(), 1e-8);
  }
}

TEST(QuadraticProgram, ConcaveHessianGetsTheInertiaCorrection) {
  // min -1/2 |x|^2 on the box |x_i| <= 1: H is not convex; the solver adds a shift until the
  // system has the inertia of a convex program and solves that program.
  const int n = 3;
  const Mat C = (Mat(2 * n, n) << Mat::Identity(n, n), -Mat::Identity(n, n)).finished();
  const QpResult r = solveQuadraticProgram(
      program(-Mat::Identity(n, n), Vec::Constant(n, 0.1), Mat::Zero(0, n), Vec::Zero(0), C, Vec::Ones(2 * n)));
  EXPECT_GE(r.shift, 1.0);
  ASSERT_TRUE(r.converged) << r.reason;
  EXPECT_LE((C * r.x).maxCoeff(), 1 + 1e-8);
}

TEST(QuadraticProgram, TheInertiaShiftActsThroughTheProgramsMetric) {
  // min 1/2 x^T diag(-4, -0.04) x + g^T x on the box |x_i| <= 1 with the shift metric
  // (1, 0.01): the second variable is in units a hundred times larger, and its curvature is
  // shifted in its own scale. The first factorisation (each box row weighted 1) already lacks
  // the inertia, so the shift holds from the start; the shifted program's minimiser, inside the
  // box, is x_i = -g_i / (H_ii + shift m_i); with the identity metric the second component
  // would be ~100 times smaller.
  const Mat H = Vec(Vec2(-4.0, -0.04)).asDiagonal();
  const Vec g = Vec2(0.5, 0.005), metric = Vec2(1.0, 0.01);
  const Mat C = (Mat(4, 2) << Mat::Identity(2, 2), -Mat::Identity(2, 2)).finished();
  QuadraticProgram qp = program(H, g, Mat::Zero(0, 2), Vec::Zero(0), C, Vec::Ones(4));
  qp.shiftMetric = metric;
  const QpResult r = solveQuadraticProgram(qp);
  ASSERT_TRUE(r.converged) << r.reason;
  ASSERT_GT(r.shift, 2.0);
  for (int i = 0; i < 2; ++i) {
    const double expected = -g[i] / (H(i, i) + r.shift * metric[i]);
    ASSERT_LT(std::abs(expected), 1.0);
    EXPECT_NEAR(r.x[i], expected, 1e-9 * (1 + std::abs(expected))) << i;
  }
  qp.shiftMetric.resize(0);
  const QpResult identity = solveQuadraticProgram(qp);
  ASSERT_TRUE(identity.converged) << identity.reason;
  EXPECT_NEAR(identity.x[1], -g[1] / (H(1, 1) + identity.shift), 1e-9);
  EXPECT_GT(std::abs(r.x[1]), 50 * std::abs(identity.x[1]));
}

TEST(QuadraticProgram, RedundantEqualityRowsStillSolve) {
  // The same row twice (as two contacts' rows can repeat each other): min |x|^2/2, x0 + x1 = 2.
  const Mat A = (Mat(2, 2) << 1, 1, 1, 1).finished();
  const QpResult r = solveQuadraticProgram(
      program(Mat::Identity(2, 2), Vec::Zero(2), A, Vec::Constant(2, 2.0), Mat::Zero(0, 2), Vec::Zero(0)));
  ASSERT_TRUE(r.converged) << r.reason;
  EXPECT_NEAR(r.x[0], 1.0, 1e-7);
  EXPECT_NEAR(r.x[1], 1.0, 1e-7);
}

TEST(QuadraticProgram, InfeasibleProgramEndsNotConvergedWithAReason) {
  // x <= -1 and -x <= -1 (x >= 1).
  const Mat C = (Mat(2, 1) << 1, -1).finished();
  const QpResult r = solveQuadraticProgram(
      program(Mat::Identity(1, 1), Vec::Zero(1), Mat::Zero(0, 1), Vec::Zero(0), C, Vec::Constant(2, -1.0)));
  EXPECT_FALSE(r.converged);
  EXPECT_FALSE(r.reason.empty());
  EXPECT_TRUE(r.x.allFinite());
}

}  // namespace
}  // namespace spacetime
