// Triangle meshes of the scene's body geometry, shared by the viewport and the glTF export so
// that what an animator sees in the editor is what a downstream package imports.
//
// Four unit shapes (cube of side 1, sphere of radius 1, cylinder of radius 1 and height 1 along
// y, cone likewise) and the placement of each piece of a body's Geometry on them, in the body
// frame: a capsule is a cylinder and two spheres. Triangles wind counter-clockwise seen from
// outside (the glTF convention for front faces), and every vertex carries its outward normal.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/scene.h"

namespace spacetime {

enum class UnitShape { Cube, Sphere, Cylinder, Cone };

struct TriangleMesh {
  std::vector<Eigen::Vector3f> positions, normals;
  std::vector<std::uint32_t> indices;  // three per triangle

  // Appends `other` moved by `placement` (any affine map; normals follow its inverse transpose).
  void append(const TriangleMesh& other, const Eigen::Affine3d& placement);
};

TriangleMesh unitShapeMesh(UnitShape shape);

// One unit shape placed in the body frame (the placement includes the scale).
struct ShapePiece {
  UnitShape shape = UnitShape::Cube;
  Eigen::Affine3d placement = Eigen::Affine3d::Identity();
};

// The pieces of a geometry; none for GeometryKind::None.
std::vector<ShapePiece> geometryPieces(const Geometry& geometry);

// The geometry as one mesh in the body frame (empty for GeometryKind::None).
TriangleMesh geometryMesh(const Geometry& geometry);

// The world height (y) of the lowest point of a body's geometry when the body frame is at
// `origin` with orientation `rotation` (body to world): exact for the shapes themselves, not
// their meshes (a sphere's lowest point lies between the mesh's vertices). +infinity for
// GeometryKind::None.
double lowestHeight(const Geometry& geometry, const Eigen::Matrix3d& rotation, const Eigen::Vector3d& origin);

// The far end of a body's geometry along its +y axis, in the body frame: where the builder puts
// a new child's joint and a new pin's body point. A capsule or cylinder along y: the end of its
// axis (a child capsule's round end then overlaps it, as a limb's joint does); any other shape:
// its highest point. 0 for GeometryKind::None.
Eigen::Vector3d geometryTip(const Geometry& geometry);

// The points a contact under a body holds by default, in the body frame, at the bottom of its
// geometry: a box's bottom corners (two, front and back along x, for a planar character; four
// otherwise), a horizontal capsule's or cylinder's two ends, an upright cylinder's base rim
// (two or four points), a sphere's or an upright capsule's lowest point. A planar root needs two
// points apart along x to stand: one point is a pivot.
std::vector<Eigen::Vector3d> geometryBaseCorners(const Geometry& geometry, bool planar);

// A place where a shape's lowest point can be, in the body frame: a point, a sphere of radius
// `margin` around it, or a disc of radius `discRadius` around it, normal to the unit vector
// `discNormal`. Its lowest world height with the body at (rotation, origin) is
//   (R p + o)_y - margin - discRadius sqrt(1 - (R n)_y^2 + smoothing^2)
// (exact for smoothing = 0). The solver keeps each one above the ground (smooth rows, unlike
// lowestHeight's minimum), with the scalar a Jet and a small smoothing that keeps a disc's row
// differentiable where it lies flat.
struct LowestPointFeature {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  double margin = 0;
  Eigen::Vector3d discNormal = Eigen::Vector3d::Zero();  // zero: not a disc
  double discRadius = 0;

  bool isDisc() const { return discRadius > 0; }
  template <class T>
  T lowestHeight(const Eigen::Matrix<T, 3, 3>& rotation, const Eigen::Matrix<T, 3, 1>& origin,
                 double smoothing = 0) const {
    using std::sqrt;
    T height = (rotation * point.cast<T>() + origin).y() - T(margin);
    if (isDisc()) {
      const T ny = (rotation * discNormal.cast<T>()).y();
      T across = T(1) - ny * ny;
      if (across < T(0)) across = T(0);
      height -= discRadius * sqrt(across + T(smoothing * smoothing));
    }
    return height;
  }
};

// The features whose lowest is the geometry's lowest point in every pose: a box's eight corners,
// a sphere's centre (margin: the radius), a capsule's two end centres (margin: the radius), a
// cylinder's two end discs. None for GeometryKind::None.
std::vector<LowestPointFeature> lowestPointFeatures(const Geometry& geometry);

}  // namespace spacetime
