// Surface sampling and meshing inside extents (geometry/mesh.h) for every real type.
#include "geometry/constants.h"
#include "geometry/error.h"
#include "geometry/mesh.h"
#include "test_geometry.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>

namespace quadrix {
namespace {

using testing::random_pose;

Eigen::Vector3d scales_for(QuadricType type, std::mt19937_64& random) {
  std::uniform_real_distribution<double> uniform(0.4, 1.6);
  const double a = uniform(random), b = a * 1.5, c = a * 2.2;
  switch (type) {
    case QuadricType::Sphere: return Eigen::Vector3d::Constant(a);
    case QuadricType::CircularCylinder: return Eigen::Vector3d(a, a, 0.0);
    case QuadricType::CircularCone: return Eigen::Vector3d(a, a, 0.0);
    case QuadricType::EllipticCylinder:
    case QuadricType::EllipticCone: return Eigen::Vector3d(a, b, 0.0);
    case QuadricType::HyperboloidTwoSheets: return Eigen::Vector3d(a, b, a);  // both vertices inside the extent
    default: return Eigen::Vector3d(a, b, c);
  }
}

const std::vector<QuadricType> kSurfaceTypes = {
    QuadricType::Plane, QuadricType::Sphere, QuadricType::Ellipsoid, QuadricType::CircularCylinder,
    QuadricType::EllipticCylinder, QuadricType::CircularCone, QuadricType::EllipticCone,
    QuadricType::HyperboloidOneSheet, QuadricType::HyperboloidTwoSheets, QuadricType::EllipticParaboloid,
    QuadricType::HyperbolicParaboloid, QuadricType::ParabolicCylinder, QuadricType::HyperbolicCylinder,
    QuadricType::IntersectingPlanes, QuadricType::ParallelPlanes};

bool inside_extent(const QuadricDecomposition& shape, const LocalExtent& extent, const Eigen::Vector3d& world) {
  const Eigen::Vector3d local = shape.pose().inverse() * world;
  return (local.array() >= extent.minimum.array() - 1e-9).all() && (local.array() <= extent.maximum.array() + 1e-9).all();
}

// Distance of a world point to the surface: exact where available, else Sampson distance.
double surface_distance(const QuadricDecomposition& shape, const Quadric& quadric, const Eigen::Vector3d& p) {
  const double exact = orthogonal_distance(shape, p);
  if (quadric.gradient(p).norm() < 1e-6 * quadric.matrix().norm()) return 0.0;  // singular point (apex, plane-pair line)
  return exact;
}

class SurfaceTypeTest : public ::testing::TestWithParam<QuadricType> {};

TEST_P(SurfaceTypeTest, SamplesAndMeshVerticesLieOnTheSurfaceInsideTheExtent) {
  const QuadricType type = GetParam();
  std::mt19937_64 random(100 + int(type));
  LocalExtent extent;
  extent.minimum = Eigen::Vector3d(-2.5, -3.0, -2.0);
  extent.maximum = Eigen::Vector3d(3.0, 2.0, 2.5);
  for (int trial = 0; trial < 20; ++trial) {
    const Quadric quadric = Quadric::from_canonical(type, scales_for(type, random), random_pose(random, 10.0));
    const QuadricDecomposition shape = quadric.decompose();
    ASSERT_EQ(shape.type, type);
    const Eigen::Matrix3Xd samples = sample_surface(shape, extent, 0.2);
    ASSERT_GT(samples.cols(), 10);
    for (Eigen::Index i = 0; i < samples.cols(); ++i) {
      const Eigen::Vector3d p = samples.col(i);
      EXPECT_LT(surface_distance(shape, quadric, p), 1e-8);
      EXPECT_TRUE(inside_extent(shape, extent, p));
    }
    const TriangleMesh mesh = mesh_surface(shape, extent, 24);
    ASSERT_GT(mesh.triangles.size(), 0u);
    EXPECT_TRUE(mesh.colors.empty());
    for (Eigen::Index i = 0; i < mesh.vertices.cols(); ++i) {
      const Eigen::Vector3d p = mesh.vertices.col(i);
      EXPECT_LT(surface_distance(shape, quadric, p), 1e-8);
      EXPECT_TRUE(inside_extent(shape, extent, p));
    }
    for (const Eigen::Vector3i& t : mesh.triangles) {
      EXPECT_TRUE((t.array() >= 0).all() && (t.array() < mesh.vertices.cols()).all());
      // Counter-clockwise seen from outside: the face normal agrees with the gradient side.
      const Eigen::Vector3d p0 = mesh.vertices.col(t[0]), p1 = mesh.vertices.col(t[1]), p2 = mesh.vertices.col(t[2]);
      const Eigen::Vector3d normal = (p1 - p0).cross(p2 - p0);
      const Eigen::Vector3d gradient = quadric.normalized().gradient((p0 + p1 + p2) / 3.0);
      if (type != QuadricType::Plane && gradient.norm() > 1e-3) {
        EXPECT_GE(normal.dot(gradient), -1e-12 * normal.norm() * gradient.norm());  // sliver triangles at poles
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(AllRealSurfaces, SurfaceTypeTest, ::testing::ValuesIn(kSurfaceTypes),
                         [](const ::testing::TestParamInfo<QuadricType>& info) { return quadric_type_name(info.param); });

// Every point of the surface inside the extent has a sample within about the spacing.
TEST(SampleSurfaceTest, SpacingBoundsTheGapsOnSpheresAndCylinders) {
  std::mt19937_64 random(7);
  LocalExtent extent;
  extent.minimum = Eigen::Vector3d::Constant(-3.0);
  extent.maximum = Eigen::Vector3d::Constant(3.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(-3.0, 3.0);
  for (QuadricType type : {QuadricType::Sphere, QuadricType::EllipticCylinder}) {
    const Eigen::Isometry3d pose = random_pose(random, 10.0);
    const Eigen::Vector3d scale = type == QuadricType::Sphere ? Eigen::Vector3d::Constant(1.3) : Eigen::Vector3d(0.8, 1.7, 0.0);
    const QuadricDecomposition shape = Quadric::from_canonical(type, scale, pose).decompose();
    const double spacing = 0.1;
    const Eigen::Matrix3Xd samples = sample_surface(shape, extent, spacing);
    int within = 0;
    const int probes = 300;
    for (int k = 0; k < probes; ++k) {
      // A random surface point: the closest surface point to a random query.
      // Canonical frame of the decomposition (for a cylinder its centre is the minimum-norm axis point).
      const Eigen::Vector3d query = shape.pose() * Eigen::Vector3d(normal(random), normal(random), uniform(random) * 0.8);
      const Eigen::Vector3d foot = closest_surface_point(shape, query);
      const double gap = (samples.colwise() - foot).colwise().norm().minCoeff();
      within += gap <= spacing;
    }
    EXPECT_EQ(within, probes) << quadric_type_name(type) << " samples " << samples.cols();
  }
}

TEST(SampleSurfaceTest, PointsLinesAndDegenerateInput) {
  std::mt19937_64 random(8);
  const Eigen::Isometry3d pose = random_pose(random, 10.0);
  LocalExtent extent;
  const QuadricDecomposition point = Quadric::from_canonical(QuadricType::Point, Eigen::Vector3d::Ones(), pose).decompose();
  const Eigen::Matrix3Xd one = sample_surface(point, extent, 0.1);
  ASSERT_EQ(one.cols(), 1);
  EXPECT_LT((Eigen::Vector3d(one.col(0)) - pose.translation()).norm(), 1e-8);
  const TriangleMesh octahedron = mesh_surface(point, extent);
  EXPECT_EQ(octahedron.vertices.cols(), 6);
  EXPECT_EQ(octahedron.triangles.size(), 8u);
  for (Eigen::Index i = 0; i < 6; ++i)
    EXPECT_NEAR((octahedron.vertices.col(i) - pose.translation()).norm(), 0.02, 1e-9);  // 1% of a 2 m extent

  const QuadricDecomposition line = Quadric::from_canonical(QuadricType::Line, Eigen::Vector3d::Ones(), pose).decompose();
  const Eigen::Matrix3Xd along = sample_surface(line, extent, 0.1);
  EXPECT_EQ(along.cols(), 21);
  for (Eigen::Index i = 0; i < along.cols(); ++i) EXPECT_LT(orthogonal_distance(line, along.col(i)), 1e-9);
  const TriangleMesh tube = mesh_surface(line, extent, 8);
  ASSERT_GT(tube.triangles.size(), 0u);
  for (Eigen::Index i = 0; i < tube.vertices.cols(); ++i)
    EXPECT_NEAR(orthogonal_distance(line, tube.vertices.col(i)), 0.01, 1e-9);

  EXPECT_THROW(sample_surface(line, extent, 0.0), Error);
  EXPECT_THROW(sample_surface(line, extent, -1.0), Error);
  EXPECT_THROW(sample_surface(line, extent, 1e-9), Error);  // far too many points
  EXPECT_THROW(mesh_surface(line, extent, 1), Error);
  LocalExtent inverted;
  inverted.minimum = Eigen::Vector3d::Constant(1.0);
  inverted.maximum = Eigen::Vector3d::Constant(-1.0);
  EXPECT_THROW(sample_surface(line, inverted, 0.1), Error);
  EXPECT_EQ(sample_surface(Quadric().decompose(), extent, 0.1).cols(), 0);
  EXPECT_EQ(mesh_surface(Quadric().decompose(), extent).triangles.size(), 0u);
}

TEST(MeshTest, ClosedEllipsoidIsOrientedOutwards) {
  std::mt19937_64 random(9);
  LocalExtent extent;
  extent.minimum = Eigen::Vector3d::Constant(-10.0);
  extent.maximum = Eigen::Vector3d::Constant(10.0);
  const Eigen::Vector3d scale(0.5, 1.0, 2.0);
  const Eigen::Isometry3d pose = random_pose(random, 10.0);
  const QuadricDecomposition shape = Quadric::from_canonical(QuadricType::Ellipsoid, scale, pose).decompose();
  const TriangleMesh mesh = mesh_surface(shape, extent, 96);
  // Divergence theorem: signed volume of an outward-oriented closed mesh is the enclosed volume.
  double volume = 0.0;
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3d p0 = mesh.vertices.col(t[0]) - pose.translation();
    const Eigen::Vector3d p1 = mesh.vertices.col(t[1]) - pose.translation();
    const Eigen::Vector3d p2 = mesh.vertices.col(t[2]) - pose.translation();
    volume += p0.dot(p1.cross(p2)) / 6.0;
  }
  const double exact = 4.0 / 3.0 * kPi * scale.prod();
  EXPECT_GT(volume, 0.98 * exact);
  EXPECT_LT(volume, exact);
}

TEST(MeshTest, AppendShiftsIndicesAndColours) {
  std::mt19937_64 random(10);
  LocalExtent extent;
  const QuadricDecomposition sphere =
      Quadric::from_canonical(QuadricType::Sphere, Eigen::Vector3d::Constant(0.5), random_pose(random, 10.0)).decompose();
  const QuadricDecomposition plane =
      Quadric::from_canonical(QuadricType::Plane, Eigen::Vector3d::Zero(), random_pose(random, 10.0)).decompose();
  const TriangleMesh a = mesh_surface(sphere, extent, 12);
  const TriangleMesh b = mesh_surface(plane, extent, 12);
  TriangleMesh scene;
  append_mesh(scene, a, quadric_type_color(QuadricType::Sphere));
  append_mesh(scene, b, quadric_type_color(QuadricType::Plane));
  ASSERT_EQ(scene.vertices.cols(), a.vertices.cols() + b.vertices.cols());
  ASSERT_EQ(scene.triangles.size(), a.triangles.size() + b.triangles.size());
  ASSERT_EQ(scene.colors.size(), std::size_t(scene.vertices.cols()));
  EXPECT_EQ(scene.triangles[a.triangles.size()], b.triangles[0] + Eigen::Vector3i::Constant(int(a.vertices.cols())));
  EXPECT_EQ(scene.colors.front(), quadric_type_color(QuadricType::Sphere));
  EXPECT_EQ(scene.colors.back(), quadric_type_color(QuadricType::Plane));
  EXPECT_EQ(Eigen::Vector3d(scene.vertices.col(a.vertices.cols())), Eigen::Vector3d(b.vertices.col(0)));
  // Table types get distinct colours.
  std::set<std::array<std::uint8_t, 3>> colours;
  for (QuadricType type : {QuadricType::Point, QuadricType::Line, QuadricType::Plane, QuadricType::Sphere,
                           QuadricType::Ellipsoid, QuadricType::CircularCylinder, QuadricType::EllipticCylinder,
                           QuadricType::CircularCone, QuadricType::EllipticCone})
    colours.insert(quadric_type_color(type));
  EXPECT_EQ(colours.size(), 9u);
}

}  // namespace
}  // namespace quadrix
