// Triangle meshes of the scene's body geometry, shared by the viewport and the glTF export so
// that what an animator sees in the editor is what a downstream package imports.
//
// Four unit shapes (cube of side 1, sphere of radius 1, cylinder of radius 1 and height 1 along
// y, cone likewise) and the placement of each piece of a body's Geometry on them, in the body
// frame: a capsule is a cylinder and two spheres. Triangles wind counter-clockwise seen from
// outside (the glTF convention for front faces), and every vertex carries its outward normal.
#pragma once

#include <Eigen/Geometry>
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

}  // namespace spacetime
