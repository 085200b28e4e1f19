// Contact points of a body and the flat layout of their forces that the solver's per-sample
// inputs and the formula variables share: forceDims components (x, y[, z], world axes) per
// point, contacts in order.
#pragma once

#include <vector>

#include "dynamics/model.h"

namespace spacetime {

struct ContactPoints {
  int body = -1;
  std::vector<Eigen::Vector3d> points;  // body frame
};

// The body's rotations that move some of the points: unit axes in the body frame spanning the
// row space of the stacked [p_i - p_0]x (in the plane, z once two points differ in x or y). The points'
// rigid motion has rank forceDims + their count: the first point's motion and these turns.
std::vector<Eigen::Vector3d> contactTurns(const ContactPoints& contact, bool planar);
// The largest distance of a point from the first.
double contactReach(const ContactPoints& contact);
// The points whose heights decide every point's height: the first, then each point whose offset
// from the first is independent of the offsets already taken (in the plane, of their x and y).
// Heights are y_0 + (R d_i)_y, linear in d_i, so if these are on the ground every point is; a
// flat sole of four points needs three (its fourth height row is redundant).
std::vector<int> heightPoints(const ContactPoints& contact, bool planar);

// The point forces given by `forces` (laid out as above), applied at the body points.
template <class T>
std::vector<PointForce<T>> contactPointForces(const std::vector<ContactPoints>& contacts,
                                              const T* forces, int forceDims) {
  std::vector<PointForce<T>> out;
  int k = 0;
  for (const ContactPoints& c : contacts)
    for (const Eigen::Vector3d& p : c.points) {
      PointForce<T> pf;
      pf.body = c.body;
      pf.pointIsLocal = true;
      pf.pointWorld = p.cast<T>();
      pf.forceWorld = Vec3<T>(forces[k], forces[k + 1], forceDims == 3 ? forces[k + 2] : T(0.0));
      k += forceDims;
      out.push_back(pf);
    }
  return out;
}

}  // namespace spacetime
