// Animation: a solved motion sampled on a uniform time grid - joint positions, velocities,
// accelerations, the generalized forces the dynamics give (unactuated entries are the physics
// residual) and every contact point's world position and force. A plain value the exporters,
// plots and viewport read.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "solver/ground_forces.h"
#include "solver/spacetime_problem.h"

namespace spacetime {

struct ContactTrack {
  std::string term;   // the contact term's id
  std::string link;   // body id
  int pointIndex = 0;
  // The interval as solved: with a free end (freeEnd) `end` is where the solver let go.
  double start = 0, end = 0;
  bool freeEnd = false;
  std::vector<Eigen::Vector3d> position, force;  // world, one per frame
  // A contact that touches down with an impact: the instant and the point's world impulse (N s).
  bool impact = false;
  double impactTime = 0;
  Eigen::Vector3d impulse = Eigen::Vector3d::Zero();
};

struct CharacterAnimation {
  std::string name;
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();
  std::vector<std::string> dofs;
  std::vector<bool> actuated;
  std::vector<double> times;
  Eigen::MatrixXd q, qd, qdd, tau;  // frames x dofs
  // q-dot just before each frame: qd's left limit, which differs from qd only at a touch-down's
  // impact (the glTF export's incoming tangents). Empty for an animation without velocities.
  Eigen::MatrixXd qdBefore;
  std::vector<ContactTrack> contacts;
};

struct Animation {
  std::vector<CharacterAnimation> characters;
};

// Samples the problem's current solution at `rateHz` frames per second (both ends included).
Animation sampleAnimation(const SpacetimeProblem& problem, double rateHz);
// Frames exactly 1/rateHz apart from the clip's start, the last at or before its end: a frame
// grid an importer that assumes a fixed frame time plays in real time (BVH). Where the clip is
// not a whole number of frames the last one falls short of the end by less than a frame.
std::vector<double> frameTimes(const Scene& scene, double rateHz);
// The same at the given times (the validity report's checks at chosen instants).
Animation sampleAnimationAt(const SpacetimeProblem& problem, const std::vector<double>& times);

// The generalized forces of character c at time t from the solution's motion and contact
// forces (RNEA with the contacts as external point forces); `ground` is groundForcesAt(problem,
// c, t, side) if the caller has it already. Side::After: the flight side of a lift-off at t.
Eigen::VectorXd generalizedForcesAt(const SpacetimeProblem& problem, int c, double t,
                                    const GroundForces* ground = nullptr, Side side = Side::Contacts);

}  // namespace spacetime
