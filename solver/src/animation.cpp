// Sampling a solution into an Animation.
#include "solver/animation.h"

#include <cmath>

#include "dynamics/algorithms.h"
#include "solver/ground_forces.h"

namespace spacetime {

Eigen::VectorXd generalizedForcesAt(const SpacetimeProblem& problem, int c, double t,
                                    const GroundForces* ground, Side side) {
  const Model<double>& model = *problem.characters()[c].model;
  const Eigen::VectorXd q = problem.jointStateOnSide(c, t, 0, side), qd = problem.jointStateOnSide(c, t, 1, side),
                        qdd = problem.jointStateOnSide(c, t, 2, side);
  Data<double> data(model);
  return rnea(model, data, q.data(), qd.data(), qdd.data(), groundPointForcesAt(problem, c, t, ground, side));
}

Animation sampleAnimation(const SpacetimeProblem& problem, double rateHz) {
  const Scene& scene = problem.scene();
  const int frames =
      std::max(2, static_cast<int>(std::lround((scene.endTime - scene.startTime) * rateHz)) + 1);
  std::vector<double> times;
  for (int f = 0; f < frames; ++f) times.push_back(scene.startTime + (scene.endTime - scene.startTime) * f / (frames - 1));
  return sampleAnimationAt(problem, times);
}

std::vector<double> frameTimes(const Scene& scene, double rateHz) {
  const int last = std::max(1, static_cast<int>(std::floor((scene.endTime - scene.startTime) * rateHz + 1e-9)));
  std::vector<double> times;
  for (int f = 0; f <= last; ++f) times.push_back(std::min(scene.startTime + f / rateHz, scene.endTime));
  return times;
}

Animation sampleAnimationAt(const SpacetimeProblem& problem, const std::vector<double>& times) {
  Animation anim;
  const Scene& scene = problem.scene();
  const int frames = static_cast<int>(times.size());
  for (size_t c = 0; c < problem.characters().size(); ++c) {
    const int ci = static_cast<int>(c);
    const Model<double>& model = *problem.characters()[c].model;
    CharacterAnimation ca;
    ca.name = model.name;
    ca.gravity = scene.gravity;
    ca.dofs = model.dofNames();
    ca.actuated = model.actuatedDofs();
    const int n = model.dofCount();
    ca.q.resize(frames, n);
    ca.qd.resize(frames, n);
    ca.qdBefore.resize(frames, n);
    ca.qdd.resize(frames, n);
    ca.tau.resize(frames, n);
    for (size_t j = 0; j < problem.contacts().size(); ++j) {
      const ContactVariables& ct = problem.contacts()[j];
      if (ct.character != ci) continue;
      for (size_t p = 0; p < ct.points.points.size(); ++p) {
        ContactTrack track;
        track.term = scene.terms[ct.term].id;
        track.link = model.bodies[ct.points.body].name;
        track.pointIndex = static_cast<int>(p);
        track.start = ct.start;
        track.end = ct.end;
        track.freeEnd = ct.freeEnd >= 0;
        if (ct.impact()) {
          track.impact = true;
          track.impactTime = ct.start;
          track.impulse = problem.contactImpulses(static_cast<int>(j))[p];
        }
        ca.contacts.push_back(track);
      }
    }
    Data<double> data(model);
    for (int f = 0; f < frames; ++f) {
      const double t = times[f];
      ca.times.push_back(t);
      ca.q.row(f) = problem.jointState(ci, t, 0).transpose();
      ca.qd.row(f) = problem.jointState(ci, t, 1).transpose();
      ca.qdBefore.row(f) = ca.qd.row(f);
      if (t > scene.startTime) ca.qdBefore.row(f) = problem.jointStateOnSide(ci, t, 1, Side::Before).transpose();
      ca.qdd.row(f) = problem.jointState(ci, t, 2).transpose();
      const GroundForces ground = groundForcesAt(problem, ci, t);
      ca.tau.row(f) = generalizedForcesAt(problem, ci, t, &ground).transpose();
      forwardKinematics(model, data, ca.q.row(f).transpose().eval().data());
      size_t k = 0;
      for (size_t j = 0; j < problem.contacts().size(); ++j) {
        const ContactVariables& ct = problem.contacts()[j];
        if (ct.character != ci) continue;
        const std::vector<Eigen::Vector3d>& forces = ground[j];
        for (size_t p = 0; p < ct.points.points.size(); ++p, ++k) {
          ca.contacts[k].position.push_back(pointPosition(data, ct.points.body, ct.points.points[p]));
          ca.contacts[k].force.push_back(forces[p]);
        }
      }
    }
    anim.characters.push_back(std::move(ca));
  }
  return anim;
}

}  // namespace spacetime
