// Admissible ground forces by NNLS over the friction cone's edges (see ground_forces.h).
#include "solver/ground_forces.h"

#include <cmath>
#include <numbers>
#include <vector>

#include "core/nnls.h"
#include "dynamics/algorithms.h"
#include "dynamics/inverse_kinematics.h"

namespace spacetime {
namespace {

// Tie-break weight towards the interpolated forces: small enough that the balance dominates
// (a residual of eps * |delta f| is left at most), large enough to make the answer unique.
constexpr double kTieBreak = 1e-6;

std::vector<Eigen::Vector3d> coneEdges(double mu, int forceDims) {
  std::vector<Eigen::Vector3d> edges;
  if (forceDims == 2) {
    edges = {Eigen::Vector3d(mu, 1, 0), Eigen::Vector3d(-mu, 1, 0)};
  } else {
    for (int k = 0; k < 8; ++k) {
      const double a = std::numbers::pi / 4 * (k + 0.5);  // includes the square's corners
      edges.emplace_back(mu * std::cos(a), 1, mu * std::sin(a));
    }
  }
  return edges;
}

PointForce<double> pointForce(const ContactVariables& ct, size_t p, const Eigen::Vector3d& f) {
  PointForce<double> pf;
  pf.body = ct.points.body;
  pf.pointIsLocal = true;
  pf.pointWorld = ct.points.points[p];
  pf.forceWorld = f;
  return pf;
}

// The contacts acting on character c at t on the given side of it: After leaves out those that
// end at t (the flight after a lift-off), Before those that begin at t (the flight before a
// touch-down).
std::vector<int> activeOnSide(const SpacetimeProblem& problem, int c, double t, Side side) {
  std::vector<int> active = problem.activeContacts(c, t, side == Side::After);
  if (side == Side::Before)
    std::erase_if(active, [&](int j) { return problem.contacts()[j].start > t - kTimeTolerance; });
  return active;
}

}  // namespace

GroundForces groundForcesAt(const SpacetimeProblem& problem, int c, double t, Side side) {
  GroundForces out(problem.contacts().size());
  for (size_t j = 0; j < out.size(); ++j)
    out[j].assign(problem.contacts()[j].points.points.size(), Eigen::Vector3d::Zero());
  const std::vector<int> active = activeOnSide(problem, c, t, side);
  if (active.empty()) return out;

  const CharacterVariables& cv = problem.characters()[c];
  const Model<double>& model = *cv.model;
  const int n = model.dofCount();
  std::vector<int> unactuated;
  for (int d = 0; d < n; ++d)
    if (!model.bodies[model.dofBody[d]].actuated) unactuated.push_back(d);
  const int u = static_cast<int>(unactuated.size());

  // Columns: one per (contact, point, edge); rows: the unactuated balance, then the tie-break.
  struct Column {
    int contact;
    size_t point;
    Eigen::Vector3d edge;
  };
  std::vector<Column> columns;
  GroundForces interpolated;
  int pointCount = 0;
  for (int j : active) {
    const ContactVariables& ct = problem.contacts()[j];
    interpolated.push_back(problem.contactForces(j, t));
    for (size_t p = 0; p < ct.points.points.size(); ++p, ++pointCount)
      for (const Eigen::Vector3d& e : coneEdges(ct.friction, ct.forceDims)) columns.push_back({j, p, e});
  }
  const Eigen::VectorXd q = problem.jointStateOnSide(c, t, 0, side), qd = problem.jointStateOnSide(c, t, 1, side),
                        qdd = problem.jointStateOnSide(c, t, 2, side);
  Data<double> data(model);
  const Eigen::VectorXd tau = rnea(model, data, q.data(), qd.data(), qdd.data(), {});
  const double sqrtEps = std::sqrt(kTieBreak);

  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(u + 3 * pointCount, columns.size());
  Eigen::VectorXd b = Eigen::VectorXd::Zero(A.rows());
  for (int k = 0; k < u; ++k) b[k] = -tau[unactuated[k]] / cv.weight;
  {
    int row = u;
    for (size_t a = 0; a < active.size(); ++a)
      for (const Eigen::Vector3d& f : interpolated[a]) {
        b.segment<3>(row) = sqrtEps * f / cv.weight;
        row += 3;
      }
  }
  // An edge force e at a point enters the unactuated balance as -J^T e (what the RNEA of that
  // force alone, without motion or gravity, gives): J, the point's Jacobian in the unactuated
  // dofs, once per point (virtual work: a force f at the point does J^T f), instead of an
  // RNEA per edge - two per point in the plane, eight in 3D.
  forwardKinematics(model, data, q.data());
  int pointRow = 0;
  Eigen::Matrix3Xd J;
  for (size_t col = 0; col < columns.size(); ++col) {
    const Column& cl = columns[col];
    const ContactVariables& ct = problem.contacts()[cl.contact];
    const bool newPoint = col == 0 || columns[col - 1].contact != cl.contact || columns[col - 1].point != cl.point;
    if (col > 0 && newPoint) ++pointRow;
    if (newPoint) J = pointJacobian(model, data, ct.points.body, ct.points.points[cl.point], unactuated);
    for (int k = 0; k < u; ++k) A(k, col) = -J.col(k).dot(cl.edge) / cv.weight;
    A.block<3, 1>(u + 3 * pointRow, col) = sqrtEps * cl.edge / cv.weight;
  }
  const NnlsResult r = nnls(A, b);
  for (size_t col = 0; col < columns.size(); ++col)
    out[columns[col].contact][columns[col].point] += r.x[col] * columns[col].edge;
  return out;
}

std::vector<PointForce<double>> groundPointForcesAt(const SpacetimeProblem& problem, int c,
                                                    double t, const GroundForces* forces, Side side) {
  GroundForces computed;
  const GroundForces& f = forces ? *forces : (computed = groundForcesAt(problem, c, t, side));
  std::vector<PointForce<double>> out;
  for (int j : activeOnSide(problem, c, t, side))
    for (size_t p = 0; p < f[j].size(); ++p) out.push_back(pointForce(problem.contacts()[j], p, f[j][p]));
  return out;
}

}  // namespace spacetime
