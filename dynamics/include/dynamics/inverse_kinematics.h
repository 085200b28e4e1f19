// Inverse kinematics for posing: moves a point of one body towards a world target by turning the
// joints between that body and the character's root, the root held where it is (as an IK chain
// pinned at its root in Blender). Damped least squares (Buss, "Introduction to Inverse Kinematics
// with Jacobian Transpose, Pseudoinverse and Damped Least Squares Methods", 2004, eq. 11):
// dq = J^T (J J^T + lambda^2 I)^-1 e, each step clamped to the joints' position limits; a target
// out of reach ends at the nearest pose the chain can take.
#pragma once

#include <Eigen/Dense>
#include <vector>

#include "dynamics/model.h"

namespace spacetime {

// The dofs IK may turn to move `body`: its joint's and its ancestors', without the root's (the
// virtual chain of a floating root and the root body's own joint).
std::vector<int> ikChain(const Model<double>& model, int body);

// d(world position of the body point `local`)/d(q[dofs[k]]) at the pose of `d` (after
// forwardKinematics): one column per dof, from each joint's world axis and pivot.
Eigen::Matrix3Xd pointJacobian(const Model<double>& model, const Data<double>& d, int body,
                               const Eigen::Vector3d& local, const std::vector<int>& dofs);

struct IkResult {
  Eigen::VectorXd q;   // the pose reached (dofs outside the chain as given)
  double error = 0;    // |point - target| there (metres)
  int iterations = 0;
};

IkResult solvePointIk(const Model<double>& model, const Eigen::VectorXd& q0, int body, const Eigen::Vector3d& local,
                      const Eigen::Vector3d& target, int maxIterations = 100, double tolerance = 1e-7);

}  // namespace spacetime
