// Triangle meshes of body geometry (see shape_mesh.h).
#include "core/shape_mesh.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace spacetime {
namespace {

constexpr int kSlices = 24;  // around the sphere's and cylinder's axis
constexpr int kStacks = 14;  // pole to pole on the sphere

std::uint32_t addVertex(TriangleMesh& m, const Eigen::Vector3f& p, const Eigen::Vector3f& n) {
  m.positions.push_back(p);
  m.normals.push_back(n);
  return static_cast<std::uint32_t>(m.positions.size() - 1);
}

void addTriangle(TriangleMesh& m, std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  m.indices.insert(m.indices.end(), {a, b, c});
}

// Six faces of four vertices each (flat normals). With u x w = n, the corners
// c - u - w, c + u - w, c + u + w, c - u + w run counter-clockwise seen from outside.
TriangleMesh cube() {
  TriangleMesh m;
  for (int axis = 0; axis < 3; ++axis)
    for (float sign : {-1.0f, 1.0f}) {
      const Eigen::Vector3f n = sign * Eigen::Vector3f::Unit(axis);
      Eigen::Vector3f u = 0.5f * Eigen::Vector3f::Unit((axis + 1) % 3);
      Eigen::Vector3f w = 0.5f * Eigen::Vector3f::Unit((axis + 2) % 3);
      if (sign < 0) std::swap(u, w);
      const Eigen::Vector3f c = 0.5f * n;
      const std::uint32_t first = addVertex(m, c - u - w, n);
      addVertex(m, c + u - w, n);
      addVertex(m, c + u + w, n);
      addVertex(m, c - u + w, n);
      addTriangle(m, first, first + 1, first + 2);
      addTriangle(m, first, first + 2, first + 3);
    }
  return m;
}

// Latitude-longitude grid: angle theta from the +y pole, phi about y. d/dphi x d/dtheta points
// outwards, so (i, j), (i+1, j), (i+1, j+1) is counter-clockwise seen from outside. The
// triangles that would collapse onto a pole are left out.
TriangleMesh sphere() {
  TriangleMesh m;
  auto index = [](int i, int j) { return static_cast<std::uint32_t>(j * (kSlices + 1) + i); };
  for (int j = 0; j <= kStacks; ++j)
    for (int i = 0; i <= kSlices; ++i) {
      const double th = M_PI * j / kStacks, ph = 2 * M_PI * i / kSlices;
      const Eigen::Vector3f p(static_cast<float>(std::sin(th) * std::cos(ph)),
                              static_cast<float>(std::cos(th)),
                              static_cast<float>(std::sin(th) * std::sin(ph)));
      addVertex(m, p, p);
    }
  for (int j = 0; j < kStacks; ++j)
    for (int i = 0; i < kSlices; ++i) {
      const std::uint32_t a = index(i, j), b = index(i + 1, j), c = index(i + 1, j + 1),
                          d = index(i, j + 1);
      if (j > 0) addTriangle(m, a, b, c);
      if (j < kStacks - 1) addTriangle(m, a, c, d);
    }
  return m;
}

// Radius 1 at y = -1/2 and topRadius at y = +1/2 (a cone when 0), with flat end caps. The side
// of each slice has its own vertices, with normals tilted by the slope so a cone shades right.
TriangleMesh cylinder(float topRadius) {
  TriangleMesh m;
  const float slope = 1.0f - topRadius;
  const Eigen::Vector3f down(0, -1, 0), up(0, 1, 0), half(0, 0.5f, 0);
  const std::uint32_t bottomCentre = addVertex(m, -half, down);
  const std::uint32_t topCentre = topRadius > 0 ? addVertex(m, half, up) : 0;
  for (int i = 0; i < kSlices; ++i) {
    const double a0 = 2 * M_PI * i / kSlices, a1 = 2 * M_PI * (i + 1) / kSlices;
    const Eigen::Vector3f d0(static_cast<float>(std::cos(a0)), 0, static_cast<float>(std::sin(a0)));
    const Eigen::Vector3f d1(static_cast<float>(std::cos(a1)), 0, static_cast<float>(std::sin(a1)));
    const Eigen::Vector3f n0 = (d0 + slope * up).normalized(), n1 = (d1 + slope * up).normalized();
    // Side: up x d(phi)/dphi points outwards, so b0, t0, t1 and b0, t1, b1.
    const std::uint32_t b0 = addVertex(m, d0 - half, n0), b1 = addVertex(m, d1 - half, n1);
    const std::uint32_t t1 = addVertex(m, topRadius * d1 + half, n1);
    if (topRadius > 0) {
      const std::uint32_t t0 = addVertex(m, topRadius * d0 + half, n0);
      addTriangle(m, b0, t0, t1);
    }
    addTriangle(m, b0, t1, b1);
    // Caps: flat, their own vertices.
    const std::uint32_t cb0 = addVertex(m, d0 - half, down), cb1 = addVertex(m, d1 - half, down);
    addTriangle(m, bottomCentre, cb0, cb1);  // d0 x d1 points down (x cross z = -y)
    if (topRadius > 0) {
      const std::uint32_t ct0 = addVertex(m, topRadius * d0 + half, up);
      const std::uint32_t ct1 = addVertex(m, topRadius * d1 + half, up);
      addTriangle(m, topCentre, ct1, ct0);
    }
  }
  return m;
}

// Rotation taking the unit shapes' y axis to the geometry's axis (0 = x, 1 = y, 2 = z).
Eigen::Matrix3d axisRotation(int axis) {
  if (axis == 0) return Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  if (axis == 2) return Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
  return Eigen::Matrix3d::Identity();
}

}  // namespace

void TriangleMesh::append(const TriangleMesh& other, const Eigen::Affine3d& placement) {
  const auto offset = static_cast<std::uint32_t>(positions.size());
  const Eigen::Affine3f A = placement.cast<float>();
  const Eigen::Matrix3f normalMap = A.linear().inverse().transpose();
  for (size_t i = 0; i < other.positions.size(); ++i) {
    positions.push_back(A * other.positions[i]);
    normals.push_back((normalMap * other.normals[i]).normalized());
  }
  // A reflection would turn the triangles inside out: reverse their winding.
  const bool mirrored = A.linear().determinant() < 0;
  for (size_t t = 0; t + 2 < other.indices.size(); t += 3) {
    const std::uint32_t a = other.indices[t], b = other.indices[t + 1], c = other.indices[t + 2];
    if (mirrored)
      indices.insert(indices.end(), {offset + a, offset + c, offset + b});
    else
      indices.insert(indices.end(), {offset + a, offset + b, offset + c});
  }
}

TriangleMesh unitShapeMesh(UnitShape shape) {
  switch (shape) {
    case UnitShape::Cube: return cube();
    case UnitShape::Sphere: return sphere();
    case UnitShape::Cylinder: return cylinder(1.0f);
    case UnitShape::Cone: return cylinder(0.0f);
  }
  return {};
}

std::vector<ShapePiece> geometryPieces(const Geometry& g) {
  const Eigen::Affine3d base(Eigen::Translation3d(g.offset));
  const double r = g.size[0], length = g.size[1];
  auto placed = [](const Eigen::Affine3d& at, const Eigen::Vector3d& scale) {
    return at * Eigen::Scaling(scale);
  };
  std::vector<ShapePiece> pieces;
  switch (g.kind) {
    case GeometryKind::None: break;
    case GeometryKind::Box: pieces.push_back({UnitShape::Cube, placed(base, g.size)}); break;
    case GeometryKind::Sphere:
      pieces.push_back({UnitShape::Sphere, placed(base, Eigen::Vector3d::Constant(r))});
      break;
    case GeometryKind::Cylinder:
    case GeometryKind::Capsule: {
      const Eigen::Affine3d along = base * Eigen::Affine3d(axisRotation(g.axis));
      pieces.push_back({UnitShape::Cylinder, placed(along, Eigen::Vector3d(r, length, r))});
      if (g.kind == GeometryKind::Capsule)
        for (double end : {0.5 * length, -0.5 * length})
          pieces.push_back({UnitShape::Sphere,
                            placed(along * Eigen::Translation3d(0, end, 0), Eigen::Vector3d::Constant(r))});
      break;
    }
  }
  return pieces;
}

TriangleMesh geometryMesh(const Geometry& geometry) {
  TriangleMesh mesh;
  for (const ShapePiece& piece : geometryPieces(geometry))
    mesh.append(unitShapeMesh(piece.shape), piece.placement);
  return mesh;
}

double lowestHeight(const Geometry& geometry, const Eigen::Matrix3d& rotation, const Eigen::Vector3d& origin) {
  double lowest = std::numeric_limits<double>::infinity();
  for (const ShapePiece& piece : geometryPieces(geometry)) {
    // A unit-shape point u lands at height c + a.u: a is the world y row of the piece's linear
    // map, c the height of its centre. The minimum of a linear function over each convex unit
    // shape is closed-form: over the cube's corners, the sphere's surface (-|a|), and the
    // cylinder's or cone's end discs (radius 1 in the x-z plane of u, at u_y = -1/2 or +1/2).
    const Eigen::Vector3d a = (rotation * piece.placement.linear()).row(1).transpose();
    const double c = (rotation * piece.placement.translation() + origin).y();
    const double disc = std::hypot(a.x(), a.z());
    double low = 0;
    switch (piece.shape) {
      case UnitShape::Cube: low = c - 0.5 * a.cwiseAbs().sum(); break;
      case UnitShape::Sphere: low = c - a.norm(); break;
      case UnitShape::Cylinder: low = c - 0.5 * std::abs(a.y()) - disc; break;
      case UnitShape::Cone: low = std::min(c + 0.5 * a.y(), c - 0.5 * a.y() - disc); break;  // apex, base disc
    }
    lowest = std::min(lowest, low);
  }
  return lowest;
}

Eigen::Vector3d geometryTip(const Geometry& g) {
  if (g.kind == GeometryKind::None) return Eigen::Vector3d::Zero();
  if ((g.kind == GeometryKind::Capsule || g.kind == GeometryKind::Cylinder) && g.axis == 1)
    return Eigen::Vector3d(g.offset.x(), g.offset.y() + 0.5 * g.size[1], g.offset.z());
  // The highest point is the lowest one of the shape turned upside down (a half turn about x).
  const Eigen::Matrix3d flip = Eigen::Vector3d(1, -1, -1).asDiagonal();
  return Eigen::Vector3d(g.offset.x(), -lowestHeight(g, flip, Eigen::Vector3d::Zero()), g.offset.z());
}

std::vector<Eigen::Vector3d> geometryBaseCorners(const Geometry& g, bool planar) {
  if (g.kind == GeometryKind::None) return {Eigen::Vector3d::Zero()};
  const Eigen::Vector3d o = g.offset;
  const double low = lowestHeight(g, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
  auto at = [&](double dx, double dz) { return Eigen::Vector3d(o.x() + dx, low, o.z() + dz); };
  // Two points along x (planar) or four around the centre, dx and dz out.
  auto spread = [&](double dx, double dz) -> std::vector<Eigen::Vector3d> {
    if (planar) return {at(-dx, 0), at(dx, 0)};
    return {at(-dx, -dz), at(dx, -dz), at(dx, dz), at(-dx, dz)};
  };
  const double r = g.size[0], half = 0.5 * g.size[1];
  switch (g.kind) {
    case GeometryKind::Box: return spread(0.5 * g.size.x(), 0.5 * g.size.z());
    case GeometryKind::Sphere: return {at(0, 0)};
    case GeometryKind::Capsule:
    case GeometryKind::Cylinder:
      if (g.axis == 1) return g.kind == GeometryKind::Capsule ? std::vector<Eigen::Vector3d>{at(0, 0)} : spread(r, r);
      if (g.axis == 0) return {at(-half, 0), at(half, 0)};
      return planar ? std::vector<Eigen::Vector3d>{at(0, 0)} : std::vector<Eigen::Vector3d>{at(0, -half), at(0, half)};
    case GeometryKind::None: break;
  }
  return {at(0, 0)};
}

std::vector<LowestPointFeature> lowestPointFeatures(const Geometry& g) {
  std::vector<LowestPointFeature> features;
  const double r = g.size[0], halfLength = 0.5 * g.size[1];
  const Eigen::Vector3d axis = Eigen::Vector3d::Unit(std::clamp(g.axis, 0, 2));
  switch (g.kind) {
    case GeometryKind::None: break;
    case GeometryKind::Box:
      // A linear function's minimum over a box is at a corner.
      for (int corner = 0; corner < 8; ++corner) {
        Eigen::Vector3d p = g.offset;
        for (int k = 0; k < 3; ++k) p[k] += ((corner >> k) & 1 ? 0.5 : -0.5) * g.size[k];
        features.push_back({p, 0, Eigen::Vector3d::Zero(), 0});
      }
      break;
    case GeometryKind::Sphere: features.push_back({g.offset, r, Eigen::Vector3d::Zero(), 0}); break;
    case GeometryKind::Capsule:
      // The segment swept by a ball: lowest at one of the segment's ends, one radius down.
      for (double end : {-halfLength, halfLength})
        features.push_back({g.offset + end * axis, r, Eigen::Vector3d::Zero(), 0});
      break;
    case GeometryKind::Cylinder:
      // Lowest on the rim of one of the end discs.
      for (double end : {-halfLength, halfLength})
        features.push_back({g.offset + end * axis, 0, axis, r});
      break;
  }
  return features;
}

}  // namespace spacetime
