// Inverse kinematics for posing: moves a point of one body towards a world target by turning the
// joints between that body and the character's root, the root held where it is (as an IK chain
// pinned at its root in Blender); or, with planted points (feet on the ground), by moving every
// dof, root included, while the planted points stay where they are. Damped least squares (Buss,
// "Introduction to Inverse Kinematics with Jacobian Transpose, Pseudoinverse and Damped Least
// Squares Methods", 2004, eq. 11): dq = J^T (J J^T + lambda^2 I)^-1 e, each step clamped to the
// joints' position limits; planted points take priority (Siciliano & Slotine 1991: the pull acts
// in the null space of the planted points' Jacobian). A target out of reach ends at the nearest
// pose the chain can take.
#pragma once

#include <Eigen/Dense>
#include <vector>

#include "dynamics/model.h"

namespace spacetime {

// The dofs IK may turn to move `body`: its joint's and its ancestors', without the root's (the
// virtual chain of a floating root and the root body's own joint).
std::vector<int> ikChain(const Model<double>& model, int body);

// d(world position of the body point `local`)/d(q[dofs[k]]) at the pose of `d` (after
// forwardKinematics): one column per dof, from each joint's world axis and pivot; zero for a dof
// whose joint is not between the body and the root.
Eigen::Matrix3Xd pointJacobian(const Model<double>& model, const Data<double>& d, int body,
                               const Eigen::Vector3d& local, const std::vector<int>& dofs);

// The dofs a pull with planted points moves: every joint and the root's translations. The root
// keeps its orientation (a pulled pelvis moves straight, the legs fold), as a root bone dragged in
// Blender; with the root's rotations free too the smallest step tilted the pelvis 30 degrees.
std::vector<int> plantedIkDofs(const Model<double>& model);

struct IkResult {
  Eigen::VectorXd q;   // the pose reached (dofs outside the chain as given)
  double error = 0;    // |point - target| there (metres)
  int iterations = 0;
};

IkResult solvePointIk(const Model<double>& model, const Eigen::VectorXd& q0, int body, const Eigen::Vector3d& local,
                      const Eigen::Vector3d& target, int maxIterations = 100, double tolerance = 1e-7);

// A body point and where it must be (world).
struct IkPoint {
  int body = -1;
  Eigen::Vector3d local = Eigen::Vector3d::Zero();
  Eigen::Vector3d target = Eigen::Vector3d::Zero();
};

struct PlantedIkResult : IkResult {
  double plantedError = 0;  // the largest |point - target| of the planted points (metres)
};

// Pulls `pulled` towards its target by moving `dofs` (every dof of a character: its root too)
// while each planted point stays at its target; the planted points come first where both cannot
// be met. Limits are kept as in solvePointIk.
PlantedIkResult solvePlantedIk(const Model<double>& model, const Eigen::VectorXd& q0, const std::vector<int>& dofs,
                               const IkPoint& pulled, const std::vector<IkPoint>& planted,
                               int maxIterations = 100, double tolerance = 1e-7);

}  // namespace spacetime
