// The body meshes shared by the viewport and the glTF export: closed, wound counter-clockwise
// seen from outside, normals pointing out, and the right size - checked by the divergence
// theorem (a closed outward-wound mesh encloses the volume sum over triangles of a.(b x c)/6)
// against each solid's analytic volume, and by each geometry's extents.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <limits>

#include "core/shape_mesh.h"

namespace spacetime {
namespace {

double enclosedVolume(const TriangleMesh& m) {
  double v = 0;
  for (size_t t = 0; t < m.indices.size(); t += 3) {
    const Eigen::Vector3d a = m.positions[m.indices[t]].cast<double>();
    const Eigen::Vector3d b = m.positions[m.indices[t + 1]].cast<double>();
    const Eigen::Vector3d c = m.positions[m.indices[t + 2]].cast<double>();
    v += a.dot(b.cross(c)) / 6;
  }
  return v;
}

// Every triangle has area, and its winding's normal agrees with its vertices' normals.
void expectOutwardTriangles(const TriangleMesh& m) {
  ASSERT_EQ(m.indices.size() % 3, 0u);
  ASSERT_EQ(m.positions.size(), m.normals.size());
  for (size_t t = 0; t < m.indices.size(); t += 3) {
    const Eigen::Vector3f a = m.positions[m.indices[t]], b = m.positions[m.indices[t + 1]],
                          c = m.positions[m.indices[t + 2]];
    const Eigen::Vector3f n = (b - a).cross(c - a);
    ASSERT_GT(n.norm(), 1e-7f) << "degenerate triangle " << t / 3;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3f& vn = m.normals[m.indices[t + k]];
      EXPECT_NEAR(vn.norm(), 1.0f, 1e-5f);
      EXPECT_GT(n.normalized().dot(vn), 0.5f) << "triangle " << t / 3 << " vertex " << k;
    }
  }
}

TEST(ShapeMesh, UnitShapesAreClosedOutwardAndOfTheirVolume) {
  // Polygonal approximations of the round solids (24 slices, 14 stacks) lose a little volume.
  const struct {
    UnitShape shape;
    double volume, tolerance;
  } cases[] = {{UnitShape::Cube, 1.0, 1e-6},
               {UnitShape::Sphere, 4 * M_PI / 3, 0.04},
               {UnitShape::Cylinder, M_PI, 0.02},
               {UnitShape::Cone, M_PI / 3, 0.02}};
  for (const auto& c : cases) {
    SCOPED_TRACE(static_cast<int>(c.shape));
    const TriangleMesh m = unitShapeMesh(c.shape);
    expectOutwardTriangles(m);
    EXPECT_NEAR(enclosedVolume(m) / c.volume, 1.0, c.tolerance);
  }
}

TEST(ShapeMesh, GeometryMeshesSpanTheirShapes) {
  auto extents = [](const TriangleMesh& m) {
    Eigen::Vector3f lo = m.positions[0], hi = m.positions[0];
    for (const auto& p : m.positions) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    return std::make_pair(Eigen::Vector3d(lo.cast<double>()), Eigen::Vector3d(hi.cast<double>()));
  };
  Geometry box;
  box.kind = GeometryKind::Box;
  box.size = {0.3, 0.1, 0.2};
  box.offset = {0.05, 0.02, 0};
  auto [lo, hi] = extents(geometryMesh(box));
  EXPECT_LT((lo - (box.offset - box.size / 2)).norm(), 1e-6);
  EXPECT_LT((hi - (box.offset + box.size / 2)).norm(), 1e-6);
  expectOutwardTriangles(geometryMesh(box));
  EXPECT_NEAR(enclosedVolume(geometryMesh(box)), 0.3 * 0.1 * 0.2, 1e-8);

  // A capsule of radius 0.05 and length 0.4 along each axis reaches length/2 + radius along it
  // and the radius across it.
  for (int axis = 0; axis < 3; ++axis) {
    Geometry capsule;
    capsule.kind = GeometryKind::Capsule;
    capsule.size = {0.05, 0.4, 0};
    capsule.axis = axis;
    const TriangleMesh m = geometryMesh(capsule);
    expectOutwardTriangles(m);
    auto [clo, chi] = extents(m);
    for (int k = 0; k < 3; ++k) {
      const double reach = k == axis ? 0.25 : 0.05;
      EXPECT_NEAR(chi[k], reach, 1e-6) << "axis " << axis << " component " << k;
      EXPECT_NEAR(clo[k], -reach, 1e-6) << "axis " << axis << " component " << k;
    }
  }
  Geometry none;
  EXPECT_TRUE(geometryMesh(none).indices.empty());
}

TEST(ShapeMesh, MirroredPlacementKeepsTrianglesOutward) {
  TriangleMesh m;
  m.append(unitShapeMesh(UnitShape::Cone), Eigen::Affine3d(Eigen::Scaling(Eigen::Vector3d(1, -2, 0.5))));
  expectOutwardTriangles(m);
  EXPECT_NEAR(enclosedVolume(m) / (M_PI / 3), 1.0, 0.02);
}

// lowestHeight is exact: in the body frame it is the shape's analytic bottom, and in any pose it
// lies at or just below the lowest vertex of the shape's own mesh (the mesh is inscribed: its
// facets cut at most 2 % of a radius off a sphere or a cylinder's rim with 24 slices).
TEST(ShapeMesh, LowestHeightIsTheShapesBottomInEveryPose) {
  Geometry box{GeometryKind::Box, Eigen::Vector3d(0.3, 0.04, 0.16), 1, Eigen::Vector3d(0, 0.02, 0)};
  Geometry capsule{GeometryKind::Capsule, Eigen::Vector3d(0.015, 0.25, 0), 1, Eigen::Vector3d(0, 0.125, 0)};
  Geometry cylinder{GeometryKind::Cylinder, Eigen::Vector3d(0.06, 0.14, 0), 0, Eigen::Vector3d(0.06, 0, 0)};
  Geometry sphere{GeometryKind::Sphere, Eigen::Vector3d(0.1, 0, 0), 1, Eigen::Vector3d(0.2, -0.1, 0.3)};
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  const Eigen::Vector3d at(1, 2, 3);
  EXPECT_NEAR(lowestHeight(box, I, at), 2 + 0.02 - 0.02, 1e-15);
  EXPECT_NEAR(lowestHeight(capsule, I, at), 2 + 0.125 - 0.125 - 0.015, 1e-15);
  EXPECT_NEAR(lowestHeight(cylinder, I, at), 2 - 0.06, 1e-15);  // along x: its rim
  EXPECT_NEAR(lowestHeight(sphere, I, at), 2 - 0.1 - 0.1, 1e-15);
  EXPECT_EQ(lowestHeight(Geometry{}, I, at), std::numeric_limits<double>::infinity());
  std::srand(7);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Matrix3d R = Eigen::Quaterniond(Eigen::Vector4d::Random().normalized()).toRotationMatrix();
    const Eigen::Vector3d origin = Eigen::Vector3d::Random();
    for (const Geometry* g : {&box, &capsule, &cylinder, &sphere}) {
      double meshLowest = 1e300;
      for (const Eigen::Vector3f& p : geometryMesh(*g).positions)
        meshLowest = std::min(meshLowest, (R * p.cast<double>() + origin).y());
      const double exact = lowestHeight(*g, R, origin);
      EXPECT_LE(exact, meshLowest + 1e-6) << "trial " << trial;  // float vertices
      EXPECT_GE(exact, meshLowest - 0.02 * g->size.maxCoeff()) << "trial " << trial;
    }
  }
}

// The features the solver keeps above the ground find the same lowest point as lowestHeight's
// closed forms (an independent route: corners, end centres, rims), in random poses.
TEST(ShapeMesh, LowestPointFeaturesFindTheShapesBottom) {
  const std::vector<Geometry> shapes = {
      {GeometryKind::Box, Eigen::Vector3d(0.3, 0.04, 0.16), 1, Eigen::Vector3d(0, 0.02, 0)},
      {GeometryKind::Capsule, Eigen::Vector3d(0.015, 0.25, 0), 2, Eigen::Vector3d(0, 0.125, 0.1)},
      {GeometryKind::Cylinder, Eigen::Vector3d(0.06, 0.14, 0), 0, Eigen::Vector3d(0.06, 0, 0)},
      {GeometryKind::Sphere, Eigen::Vector3d(0.1, 0, 0), 1, Eigen::Vector3d(0.2, -0.1, 0.3)}};
  EXPECT_TRUE(lowestPointFeatures(Geometry{}).empty());
  EXPECT_EQ(lowestPointFeatures(shapes[0]).size(), 8u);
  std::srand(11);
  for (int trial = 0; trial < 500; ++trial) {
    const Eigen::Matrix3d R = Eigen::Quaterniond(Eigen::Vector4d::Random().normalized()).toRotationMatrix();
    const Eigen::Vector3d origin = Eigen::Vector3d::Random();
    for (const Geometry& g : shapes) {
      double lowest = 1e300;
      for (const LowestPointFeature& f : lowestPointFeatures(g)) lowest = std::min(lowest, f.lowestHeight(R, origin));
      EXPECT_NEAR(lowest, lowestHeight(g, R, origin), 1e-12) << "trial " << trial;
    }
  }
}

// Where the builder attaches things: a new child's joint at the parent's tip (an upright
// capsule's axis end; any other shape's highest point, checked against its mesh) and a new
// contact's points on the bottom of the body (every point at the shape's lowest height, a box's
// corners at its x (and z) extents).
TEST(ShapeMesh, TipAndBaseCornersSitOnTheShape) {
  Geometry box{GeometryKind::Box, Eigen::Vector3d(0.2, 0.1, 0.12), 1, Eigen::Vector3d(0.01, 0.05, 0)};
  Geometry capsule{GeometryKind::Capsule, Eigen::Vector3d(0.025, 0.2, 0), 1, Eigen::Vector3d(0, 0.1, 0)};
  Geometry lying{GeometryKind::Capsule, Eigen::Vector3d(0.02, 0.3, 0), 0, Eigen::Vector3d(0, 0.02, 0)};
  Geometry sphere{GeometryKind::Sphere, Eigen::Vector3d(0.1, 0, 0), 1, Eigen::Vector3d(0, 0.3, 0)};
  EXPECT_TRUE(geometryTip(capsule).isApprox(Eigen::Vector3d(0, 0.2, 0)));
  EXPECT_TRUE(geometryTip(Geometry{}).isZero());
  for (const Geometry* g : {&box, &lying, &sphere}) {
    double meshHighest = -1e300;
    for (const Eigen::Vector3f& p : geometryMesh(*g).positions) meshHighest = std::max(meshHighest, double(p.y()));
    EXPECT_GE(geometryTip(*g).y(), meshHighest - 1e-6);
    EXPECT_LE(geometryTip(*g).y(), meshHighest + 0.02 * g->size.maxCoeff());
  }
  EXPECT_NEAR(geometryTip(box).y(), 0.1, 1e-15);
  EXPECT_NEAR(geometryTip(sphere).y(), 0.4, 1e-15);

  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  const std::vector<Eigen::Vector3d> planar = geometryBaseCorners(box, true);
  ASSERT_EQ(planar.size(), 2u);
  EXPECT_TRUE(planar[0].isApprox(Eigen::Vector3d(-0.09, 0, 0)));
  EXPECT_TRUE(planar[1].isApprox(Eigen::Vector3d(0.11, 0, 0)));
  EXPECT_EQ(geometryBaseCorners(box, false).size(), 4u);
  EXPECT_EQ(geometryBaseCorners(lying, true).size(), 2u);
  EXPECT_EQ(geometryBaseCorners(sphere, true).size(), 1u);
  for (const Geometry* g : {&box, &capsule, &lying, &sphere})
    for (bool flat : {true, false})
      for (const Eigen::Vector3d& p : geometryBaseCorners(*g, flat))
        EXPECT_NEAR(p.y(), lowestHeight(*g, I, Eigen::Vector3d::Zero()), 1e-15);
}

}  // namespace
}  // namespace spacetime
