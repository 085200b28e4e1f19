// Inverse kinematics for posing (see inverse_kinematics.h).
#include "dynamics/inverse_kinematics.h"

#include <algorithm>

#include "dynamics/algorithms.h"

namespace spacetime {

std::vector<int> ikChain(const Model<double>& model, int body) {
  std::vector<int> dofs;
  for (int b = body; b >= 0; b = model.bodies[b].parent) {
    const Body<double>& link = model.bodies[b];
    const bool root = link.isVirtual || link.parent < 0 || model.bodies[link.parent].isVirtual;
    if (root) break;
    if (link.dofIndex >= 0) dofs.push_back(link.dofIndex);
  }
  return dofs;
}

std::vector<int> plantedIkDofs(const Model<double>& model) {
  std::vector<int> dofs;
  for (int dof = 0; dof < model.dofCount(); ++dof) {
    const Body<double>& link = model.bodies[model.dofBody[dof]];
    const bool root = link.isVirtual || link.parent < 0 || model.bodies[link.parent].isVirtual;
    if (!(root && link.joint.type == JointType::Revolute)) dofs.push_back(dof);
  }
  return dofs;
}

Eigen::Matrix3Xd pointJacobian(const Model<double>& model, const Data<double>& d, int body,
                               const Eigen::Vector3d& local, const std::vector<int>& dofs) {
  const Eigen::Vector3d p = pointPosition(d, body, local);
  Eigen::Matrix3Xd J = Eigen::Matrix3Xd::Zero(3, dofs.size());
  std::vector<char> moves(model.bodies.size(), 0);  // the body and its ancestors carry the point
  for (int b = body; b >= 0; b = model.bodies[b].parent) moves[b] = 1;
  for (size_t k = 0; k < dofs.size(); ++k) {
    const int b = model.dofBody[dofs[k]];
    if (!moves[b]) continue;  // a joint elsewhere in the tree does not move this point
    const Joint<double>& joint = model.bodies[b].joint;
    // The joint's axis and pivot in world: the child frame turns or slides about its own axis.
    const Eigen::Vector3d axis = d.X_world[b].E.transpose() * joint.axis, pivot = d.X_world[b].r;
    switch (joint.type) {
      case JointType::Revolute: J.col(k) = axis.cross(p - pivot); break;
      case JointType::Prismatic: J.col(k) = axis; break;
      case JointType::Helical: J.col(k) = axis.cross(p - pivot) + joint.pitch * axis; break;
      case JointType::Fixed: J.col(k).setZero(); break;
    }
  }
  return J;
}

IkResult solvePointIk(const Model<double>& model, const Eigen::VectorXd& q0, int body, const Eigen::Vector3d& local,
                      const Eigen::Vector3d& target, int maxIterations, double tolerance) {
  return solvePlantedIk(model, q0, ikChain(model, body), {body, local, target}, {}, maxIterations, tolerance);
}

PlantedIkResult solvePlantedIk(const Model<double>& model, const Eigen::VectorXd& q0, const std::vector<int>& dofs,
                               const IkPoint& pulled, const std::vector<IkPoint>& planted, int maxIterations,
                               double tolerance) {
  constexpr double kMaxStep = 0.3;        // largest change of a dof per iteration (rad or m)
  // A step is accepted when it lowers |pull error| + |planted error|. The planted points' drift
  // after a step is second order (the pull acts in their null space) and the next step's
  // correction removes it; weighting it more (100) rejected every step of a 6 cm crouch.
  const int n = static_cast<int>(dofs.size()), k = static_cast<int>(planted.size());
  PlantedIkResult out;
  out.q = q0;
  Data<double> d(model);
  // The errors (targets minus points) at the pose of d: the pull's, and the planted points' stacked.
  auto errors = [&](Eigen::Vector3d* pull, Eigen::VectorXd* held) {
    *pull = pulled.target - pointPosition(d, pulled.body, pulled.local);
    held->resize(3 * k);
    for (int i = 0; i < k; ++i)
      held->segment<3>(3 * i) = planted[i].target - pointPosition(d, planted[i].body, planted[i].local);
  };
  auto merit = [&](const Eigen::Vector3d& pull, const Eigen::VectorXd& held) {
    return pull.norm() + (k ? held.norm() : 0.0);
  };
  forwardKinematics(model, d, out.q.data());
  Eigen::Vector3d e;
  Eigen::VectorXd eh;
  errors(&e, &eh);
  out.error = e.norm();
  out.plantedError = k ? eh.lpNorm<Eigen::Infinity>() : 0.0;
  auto done = [&] { return out.error <= tolerance && out.plantedError <= tolerance; };
  // The damping adapts as in Levenberg-Marquardt: smaller after a step that improves the merit,
  // larger (and the step retried) after one that does not.
  double lambda = 1e-2;
  for (; out.iterations < maxIterations && !done() && n > 0 && lambda < 1e3; ++out.iterations) {
    Eigen::Matrix3Xd J = pointJacobian(model, d, pulled.body, pulled.local, dofs);
    Eigen::MatrixXd Jh(3 * k, n);
    for (int i = 0; i < k; ++i) Jh.middleRows<3>(3 * i) = pointJacobian(model, d, planted[i].body, planted[i].local, dofs);
    Eigen::VectorXd step;
    // A joint at a limit that the step pushes further stays there: its column goes, and the
    // other joints take the whole step (clamping it afterwards lost the direction).
    for (int pass = 0; pass < 2; ++pass) {
      // The planted points' correction first (nearly undamped: they are met where they can be),
      // then the pull within what leaves them unchanged to first order.
      Eigen::VectorXd base = Eigen::VectorXd::Zero(n);
      Eigen::MatrixXd N = Eigen::MatrixXd::Identity(n, n);
      if (k) {
        // J_h^+ = J_h^T (J_h J_h^T + 1e-12 I)^-1, the transpose of a solve with the symmetric matrix.
        const Eigen::MatrixXd pinv =
            (Jh * Jh.transpose() + 1e-12 * Eigen::MatrixXd::Identity(3 * k, 3 * k)).ldlt().solve(Jh).transpose();
        base = pinv * eh;
        N -= pinv * Jh;
      }
      const Eigen::Matrix3Xd JN = J * N;
      const Eigen::Matrix3d A = JN * JN.transpose() + lambda * lambda * Eigen::Matrix3d::Identity();
      step = base + N * (JN.transpose() * A.ldlt().solve(e - J * base));
      bool frozen = false;
      for (int c = 0; c < n; ++c) {
        const Body<double>& link = model.bodies[model.dofBody[dofs[c]]];
        const double v = out.q[dofs[c]], dq = step[c];
        if (link.hasPositionLimits && ((v <= link.lower && dq < 0) || (v >= link.upper && dq > 0)) &&
            (J.col(c).any() || (k && Jh.col(c).any()))) {
          J.col(c).setZero();
          if (k) Jh.col(c).setZero();
          frozen = true;
        }
      }
      if (!frozen) break;
    }
    if (step.cwiseAbs().maxCoeff() > kMaxStep) step *= kMaxStep / step.cwiseAbs().maxCoeff();
    Eigen::VectorXd q = out.q;
    for (int c = 0; c < n; ++c) {
      const Body<double>& link = model.bodies[model.dofBody[dofs[c]]];
      q[dofs[c]] += step[c];
      if (link.hasPositionLimits) q[dofs[c]] = std::clamp(q[dofs[c]], link.lower, link.upper);
    }
    forwardKinematics(model, d, q.data());
    Eigen::Vector3d eNew;
    Eigen::VectorXd ehNew;
    errors(&eNew, &ehNew);
    if (merit(eNew, ehNew) >= merit(e, eh)) {  // no better: damp more and retry from the best pose
      lambda *= 4;
      forwardKinematics(model, d, out.q.data());
      continue;
    }
    lambda = std::max(lambda / 3, 1e-6);
    out.q = q;
    e = eNew;
    eh = ehNew;
    out.error = e.norm();
    out.plantedError = k ? eh.lpNorm<Eigen::Infinity>() : 0.0;
  }
  return out;
}

}  // namespace spacetime
