// The second-order check (see second_order.h): W and A at the point, a null-space basis of A from
// a sparse QR factorisation of A^T, and the eigenvalues of the reduced Hessian.
#include "solver/second_order.h"

#include <Eigen/Eigenvalues>
#include <Eigen/SparseQR>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

#include "kkt_multipliers.h"
#include "program_steps.h"
#include "solver/variable_labels.h"

namespace spacetime {

using raw::RawEvaluator;
using raw::RawRows;
using raw::SpMat;
using raw::SpRow;
using raw::Triplets;
using raw::Vec;

namespace {

// An inequality's multiplier below this fraction of the largest multiplier counts as zero: the
// row is weakly active and is left out of A (the critical cone then only grows, so the check
// stays sufficient).
constexpr double kZeroMultiplier = 1e-9;
// Eigenvalues of the reduced Hessian within this fraction of its largest are zero to the accuracy
// of W even where the products' rounding bound is smaller: the kinematic rows' curvature is a
// forward difference of their exact Jacobians at a step of 1e-7 (Kernel::weightedHessian). A
// particle kept on a circle of equally good motions: -1.2e-9 against a largest of 5.3e3; the
// lamps' smallest, 6.6e-5 to 1.4e-4, against largest ones of 4.5 to 470.
constexpr double kRoundingFloor = 1e-8;
// A direction that is not curved upwards is named by its largest components: at most this many,
// each at least this share of the largest.
constexpr size_t kNamedVariables = 6;
constexpr double kNamedShare = 0.2;
// A flat direction moves "contact forces only" when its largest component on any other variable
// is below this share of its largest component: the 3D lamp's 612 flat directions move the
// motion by 1e-12 of that, the quadruped's 3 by 3e-7; the biped's 20 smallest curvatures, all
// under its floor, by up to 1.1e-3 (not forces only: it stays "not shown").
constexpr double kMotionShare = 1e-5;

}  // namespace

SecondOrderCheck checkSecondOrder(SpacetimeProblem& problem, int threads) {
  SecondOrderCheck out;
  const auto t0 = std::chrono::steady_clock::now();
  auto finish = [&](const std::string& why) {
    out.reason = why;
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return out;
  };
  if (!problem.freeEnds().empty()) return finish("not run: free contact ends are bounded variables");
  const raw::Variables vars(problem.ceresProblem());
  RawEvaluator evaluator(problem, vars, threads);
  if (evaluator.anyMoving()) return finish("not run: a residual moves with a free contact end");
  RawRows rows;
  if (!evaluator.evaluate(&rows, true)) return finish("not run: a row is not finite");
  MultiplierEstimate estimate;
  const Vec y = stationaryMultipliers(problem, evaluator, rows, &estimate);
  if (!estimate.ok) return finish("not run: no constraint row, or the multipliers could not be estimated");
  out.stationarity = estimate.stationarity;

  // A: the equalities and the inequalities at their bound that push; W weighs each row's curvature
  // by its residual (objective rows) or its multiplier (rows of A).
  const int n = vars.tangent;
  const double largest = std::max(1.0, y.lpNorm<Eigen::Infinity>());
  std::vector<int> active;
  Vec w = Vec::Zero(evaluator.rows());
  for (int r = 0; r < evaluator.rows(); ++r) {
    const RowKind kind = evaluator.kind(r);
    if (kind == RowKind::Objective) {
      w[r] = rows.values[r];
      continue;
    }
    if (kind == RowKind::Inequality) {
      if (rows.values[r] <= -raw::kAtBound) continue;
      if (y[r] <= kZeroMultiplier * largest) {
        ++out.weaklyActive;
        continue;
      }
    }
    active.push_back(r);
    w[r] = y[r];
  }
  const int m = static_cast<int>(active.size());
  out.constraints = m;
  Triplets t = evaluator.curvature(w, threads);
  evaluator.appendGaussNewton(rows, &t);
  SpMat W(n, n);
  W.setFromTriplets(t.begin(), t.end());  // lower triangle
  W = SpMat(W.selfadjointView<Eigen::Lower>());

  // Z: the last n - rank columns of Q in A^T P = Q R (rows of A scaled to unit norm, so that the
  // rank decision weighs metres, radians and fractions of the weight alike).
  SpRow A = raw::selectRows(rows.jacobian, active);
  for (Eigen::Index k = 0; k < A.rows(); ++k) {
    const double norm = A.row(k).norm();
    if (norm > 0) A.row(k) /= norm;
  }
  const SpMat At = SpMat(A.transpose());
  Eigen::SparseQR<SpMat, Eigen::COLAMDOrdering<int>> qr;
  qr.compute(At);
  if (qr.info() != Eigen::Success) return finish("not run: the active constraints' QR factorisation failed");
  const int rank = static_cast<int>(qr.rank());
  out.nullity = n - rank;
  out.dependent = m - rank;
  out.checked = true;
  if (out.nullity == 0) {
    out.strictMinimum = true;
    out.smallestEigenvalue = std::numeric_limits<double>::infinity();
    return finish("a strict local minimum: the active constraints fix the point (no free direction)");
  }
  Eigen::MatrixXd E = Eigen::MatrixXd::Zero(n, out.nullity);
  for (int k = 0; k < out.nullity; ++k) E(rank + k, k) = 1;
  const Eigen::MatrixXd Z = qr.matrixQ() * E;
  const Eigen::MatrixXd reduced = Z.transpose() * (W * Z);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(0.5 * (reduced + reduced.transpose()), Eigen::EigenvaluesOnly);
  out.smallestEigenvalue = eigen.eigenvalues()[0];
  out.largestEigenvalue = eigen.eigenvalues()[out.nullity - 1];
  // Rounding: each entry of fl(Z^T (W Z)) is within gamma |Z|^T |W| |Z| of the exact one
  // (Higham, Accuracy and Stability of Numerical Algorithms, section 3.5), gamma = 2 n u for the
  // two products; the eigenvalues move by at most the 2-norm of that error, bounded here by its
  // Frobenius norm.
  const SpMat absW = W.cwiseAbs();
  const Eigen::MatrixXd absZ = Z.cwiseAbs();
  const Eigen::MatrixXd bound = absZ.transpose() * (absW * absZ);
  const double gamma = 2.0 * n * std::numeric_limits<double>::epsilon();
  out.roundingFloor = std::max(kRoundingFloor * std::abs(out.largestEigenvalue), gamma * bound.norm());
  out.strictMinimum = out.smallestEigenvalue > out.roundingFloor;
  if (!out.strictMinimum) {
    // The direction of least curvature, by the variables it moves most (its vectors only now: the
    // humanoid's 2005 free directions take seconds more with them).
    eigen.compute(0.5 * (reduced + reduced.transpose()), Eigen::ComputeEigenvectors);
    const Vec direction = Z * eigen.eigenvectors().col(0);
    std::vector<int> variable(static_cast<size_t>(n), -1);  // tangent column -> index into the variables
    for (double* block : vars.blocks) {
      const std::vector<int>& columns = vars.columns.at(block);
      for (size_t a = 0; a < columns.size(); ++a)
        if (columns[a] >= 0) variable[static_cast<size_t>(columns[a])] = static_cast<int>(block - problem.variables().data() + a);
    }
    // Flat directions that move contact forces only (a split of a sample's force no term decides)
    // leave the motion itself strictly optimal: any direction that moves the motion has a part
    // outside their span, curved by at least the next eigenvalue.
    if (out.smallestEigenvalue >= -out.roundingFloor) {
      int flat = 0;
      while (flat < out.nullity && eigen.eigenvalues()[flat] <= out.roundingFloor) ++flat;
      bool forcesOnly = flat < out.nullity;
      std::vector<char> force(static_cast<size_t>(n), 0);  // per tangent column: a contact force
      for (int c = 0; c < n; ++c)
        force[static_cast<size_t>(c)] = variable[static_cast<size_t>(c)] >= 0 && isContactForce(problem, variable[static_cast<size_t>(c)]);
      // The flat directions in the variables, in one product: one column at a time read Z from
      // memory once per direction (the humanoid's check, resumed at its optimum: 20.5 s, against
      // 17.2 s in one product).
      const Eigen::MatrixXd flats = Z * eigen.eigenvectors().leftCols(flat);
      for (int k = 0; k < flat && forcesOnly; ++k) {
        const Vec d = flats.col(k);
        double motion = 0;
        for (int c = 0; c < n; ++c)
          if (!force[static_cast<size_t>(c)]) motion = std::max(motion, std::abs(d[c]));
        forcesOnly = motion <= kMotionShare * d.lpNorm<Eigen::Infinity>();
      }
      if (forcesOnly) {
        out.freeForceDirections = flat;
        out.strictMotion = true;
        out.motionEigenvalue = eigen.eigenvalues()[flat];
      }
    }
    std::vector<int> order(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) order[static_cast<size_t>(i)] = i;
    std::sort(order.begin(), order.end(), [&](int a, int b) { return std::abs(direction[a]) > std::abs(direction[b]); });
    for (size_t k = 0; k < kNamedVariables && k < order.size(); ++k) {
      const int column = order[k];
      if (std::abs(direction[column]) < kNamedShare * std::abs(direction[order[0]])) break;
      out.direction.push_back(variable[static_cast<size_t>(column)] >= 0
                                  ? describeVariable(problem, variable[static_cast<size_t>(column)])
                                  : "column " + std::to_string(column));
    }
  }
  std::ostringstream why;
  if (out.strictMinimum)
    why << "a strict local minimum: the reduced Hessian's smallest eigenvalue is " << out.smallestEigenvalue;
  else if (out.strictMotion)
    why << "the motion is a strict local minimum (its smallest curvature " << out.motionEigenvalue << "), but "
        << out.freeForceDirections << " directions of the reduced Hessian are flat to rounding (" << out.roundingFloor
        << ") and move contact forces only: forces no term decides";
  else if (out.smallestEigenvalue >= -out.roundingFloor)
    why << "not shown to be a strict local minimum: the reduced Hessian's smallest eigenvalue, "
        << out.smallestEigenvalue << ", is zero to rounding (" << out.roundingFloor
        << "): the objective is flat along a direction the constraints allow";
  else if (out.dependent == 0 && out.weaklyActive == 0)
    why << "not a local minimum: the reduced Hessian's smallest eigenvalue is " << out.smallestEigenvalue
        << ", so the objective falls along a direction the constraints allow (a saddle)";
  else
    why << "not shown to be a local minimum: the reduced Hessian's smallest eigenvalue is " << out.smallestEigenvalue
        << " with these multipliers, but " << out.dependent << " of the " << m << " active constraints are dependent"
        << " (other multipliers could curve that direction otherwise) and " << out.weaklyActive
        << " inequalities are at their bound without a multiplier (they may forbid it)";
  if (!out.direction.empty()) {
    why << "; along it move most: ";
    for (size_t k = 0; k < out.direction.size(); ++k) why << (k ? "; " : "") << out.direction[k];
  }
  return finish(why.str());
}

}  // namespace spacetime
