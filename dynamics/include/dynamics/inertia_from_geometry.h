// Mass properties of the primitive shapes (box, sphere, cylinder, capsule) about their centre,
// in shape axes, and the body inertia a BodySpec describes (given, or computed from geometry
// with a mass or a density).
#pragma once

#include "core/scene.h"
#include "dynamics/spatial.h"

namespace spacetime {

// Volume of a shape in m^3 (0 for none).
double shapeVolume(const Geometry& g);
// Rotational inertia about the shape's centre for the given mass (body axes).
Eigen::Matrix3d shapeInertia(const Geometry& g, double mass);
// The rigid-body inertia of a body about its frame origin.
Inertia<double> bodyInertia(const BodySpec& body);

}  // namespace spacetime
