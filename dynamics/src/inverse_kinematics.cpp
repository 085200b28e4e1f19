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

Eigen::Matrix3Xd pointJacobian(const Model<double>& model, const Data<double>& d, int body,
                               const Eigen::Vector3d& local, const std::vector<int>& dofs) {
  const Eigen::Vector3d p = pointPosition(d, body, local);
  Eigen::Matrix3Xd J(3, dofs.size());
  for (size_t k = 0; k < dofs.size(); ++k) {
    const int b = model.dofBody[dofs[k]];
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
  constexpr double kMaxStep = 0.3;  // largest joint change per iteration (rad or m)
  IkResult out{q0, 0, 0};
  const std::vector<int> dofs = ikChain(model, body);
  Data<double> d(model);
  forwardKinematics(model, d, out.q.data());
  Eigen::Vector3d e = target - pointPosition(d, body, local);
  out.error = e.norm();
  // The damping adapts as in Levenberg-Marquardt: smaller after a step that brings the point
  // closer, larger (and the step retried) after one that does not.
  double lambda = 1e-2;
  for (; out.iterations < maxIterations && out.error > tolerance && !dofs.empty() && lambda < 1e3; ++out.iterations) {
    Eigen::Matrix3Xd J = pointJacobian(model, d, body, local, dofs);
    Eigen::VectorXd step;
    // A joint at a limit that the step pushes further stays there: its column goes, and the
    // other joints take the whole step (clamping it afterwards lost the direction).
    for (int pass = 0; pass < 2; ++pass) {
      const Eigen::Matrix3d A = J * J.transpose() + lambda * lambda * Eigen::Matrix3d::Identity();
      step = J.transpose() * A.ldlt().solve(e);
      bool frozen = false;
      for (size_t k = 0; k < dofs.size(); ++k) {
        const Body<double>& link = model.bodies[model.dofBody[dofs[k]]];
        const double v = out.q[dofs[k]], dq = step[static_cast<Eigen::Index>(k)];
        if (link.hasPositionLimits && ((v <= link.lower && dq < 0) || (v >= link.upper && dq > 0)) && J.col(k).any()) {
          J.col(k).setZero();
          frozen = true;
        }
      }
      if (!frozen) break;
    }
    if (step.cwiseAbs().maxCoeff() > kMaxStep) step *= kMaxStep / step.cwiseAbs().maxCoeff();
    Eigen::VectorXd q = out.q;
    for (size_t k = 0; k < dofs.size(); ++k) {
      const Body<double>& link = model.bodies[model.dofBody[dofs[k]]];
      q[dofs[k]] += step[static_cast<Eigen::Index>(k)];
      if (link.hasPositionLimits) q[dofs[k]] = std::clamp(q[dofs[k]], link.lower, link.upper);
    }
    forwardKinematics(model, d, q.data());
    const Eigen::Vector3d eNew = target - pointPosition(d, body, local);
    if (eNew.norm() >= out.error) {  // no closer: damp more and retry from the best pose
      lambda *= 4;
      forwardKinematics(model, d, out.q.data());
      continue;
    }
    lambda = std::max(lambda / 3, 1e-6);
    out.q = q;
    e = eNew;
    out.error = e.norm();
  }
  return out;
}

}  // namespace spacetime
