// Closed-form inertias of solid primitives (e.g. the tables in Meriam & Kraige, Dynamics,
// Appendix D). The capsule is a cylinder plus two hemispherical caps; its caps' inertia about
// the capsule centre uses the hemisphere's centroid at 3r/8 from its flat face.
#include "dynamics/inertia_from_geometry.h"

#include <cmath>

namespace spacetime {

double shapeVolume(const Geometry& g) {
  const double r = g.size[0], L = g.size[1];
  switch (g.kind) {
    case GeometryKind::Box: return g.size.prod();
    case GeometryKind::Sphere: return 4.0 / 3.0 * M_PI * r * r * r;
    case GeometryKind::Cylinder: return M_PI * r * r * L;
    case GeometryKind::Capsule: return M_PI * r * r * L + 4.0 / 3.0 * M_PI * r * r * r;
    case GeometryKind::None: return 0;
  }
  return 0;
}

Eigen::Matrix3d shapeInertia(const Geometry& g, double mass) {
  Eigen::Vector3d d = Eigen::Vector3d::Zero();  // principal moments, axis moment in [axis]
  const double r = g.size[0], L = g.size[1];
  double axial = 0, perp = 0;
  switch (g.kind) {
    case GeometryKind::Box: {
      const Eigen::Vector3d s2 = g.size.cwiseProduct(g.size);
      d = mass / 12.0 * Eigen::Vector3d(s2.y() + s2.z(), s2.x() + s2.z(), s2.x() + s2.y());
      return d.asDiagonal();
    }
    case GeometryKind::Sphere: return Eigen::Matrix3d::Identity() * (0.4 * mass * r * r);
    case GeometryKind::Cylinder:
      axial = 0.5 * mass * r * r;
      perp = mass * (3 * r * r + L * L) / 12.0;
      break;
    case GeometryKind::Capsule: {
      const double vc = M_PI * r * r * L, vh = 4.0 / 3.0 * M_PI * r * r * r;
      const double mc = mass * vc / (vc + vh), mh = mass * vh / (vc + vh);
      axial = mc * r * r / 2 + mh * 2 * r * r / 5;
      perp = mc * (L * L / 12 + r * r / 4) + mh * (2 * r * r / 5 + L * L / 4 + 3 * L * r / 8);
      break;
    }
    case GeometryKind::None: return Eigen::Matrix3d::Zero();
  }
  d.setConstant(perp);
  d[g.axis] = axial;
  return d.asDiagonal();
}

Inertia<double> bodyInertia(const BodySpec& body) {
  const double mass = body.mass ? *body.mass : *body.density * shapeVolume(body.geometry);
  const Eigen::Vector3d com = body.com ? *body.com : body.geometry.offset;
  const Eigen::Matrix3d Ic = body.inertia ? *body.inertia : shapeInertia(body.geometry, mass);
  return Inertia<double>::fromMassCom(mass, com, Ic);
}

}  // namespace spacetime
