// Quadric algebra and decomposition (paper §"Quadrics"): randomised shapes under random poses,
// fixed seeds, every table type plus the other real types, distances against brute force.
#include "geometry/constants.h"
#include "geometry/error.h"
#include "geometry/mesh.h"
#include "geometry/quadric.h"
#include "test_geometry.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace quadrix {
namespace {

using testing::random_pose;

double log_uniform(std::mt19937_64& random, double low, double high) {
  std::uniform_real_distribution<double> uniform(std::log(low), std::log(high));
  return std::exp(uniform(random));
}

// Random k != 0 of either sign, over several orders of magnitude (scale ambiguity of Eq. (quadrics equation)).
double random_multiplier(std::mt19937_64& random) {
  std::bernoulli_distribution negative(0.5);
  return (negative(random) ? -1.0 : 1.0) * log_uniform(random, 1e-3, 1e3);
}

// Ascending scales at least 10% apart (so that the elliptic axes are well conditioned).
Eigen::Vector3d distinct_ascending_scales(std::mt19937_64& random, double low, double high) {
  for (;;) {
    Eigen::Vector3d s(log_uniform(random, low, high), log_uniform(random, low, high), log_uniform(random, low, high));
    std::sort(s.data(), s.data() + 3);
    if (s[1] > 1.1 * s[0] && s[2] > 1.1 * s[1]) return s;
  }
}

// The scales a table type is built from, in the canonical order decompose() reports.
Eigen::Vector3d scales_for(QuadricType type, std::mt19937_64& random) {
  const Eigen::Vector3d s = distinct_ascending_scales(random, 0.2, 5.0);
  switch (type) {
    case QuadricType::Sphere: return Eigen::Vector3d::Constant(s[1]);
    case QuadricType::CircularCylinder: return Eigen::Vector3d(s[1], s[1], 0.0);
    case QuadricType::EllipticCylinder: return Eigen::Vector3d(s[0], s[2], 0.0);
    case QuadricType::CircularCone: {
      const double tangent = log_uniform(random, 0.2, 3.0);
      return Eigen::Vector3d(tangent, tangent, 0.0);
    }
    case QuadricType::EllipticCone: {
      const Eigen::Vector3d t = distinct_ascending_scales(random, 0.2, 3.0);
      return Eigen::Vector3d(t[0], t[2], 0.0);
    }
    case QuadricType::Point:
    case QuadricType::Line:
    case QuadricType::Plane: return Eigen::Vector3d::Zero();
    default: return s;
  }
}

bool is_central(QuadricType type) {
  return type == QuadricType::Point || type == QuadricType::Sphere || type == QuadricType::Ellipsoid ||
         type == QuadricType::CircularCone || type == QuadricType::EllipticCone;
}

const std::vector<QuadricType> kTableTypes = {
    QuadricType::Point, QuadricType::Line, QuadricType::Plane, QuadricType::Sphere, QuadricType::Ellipsoid,
    QuadricType::CircularCylinder, QuadricType::EllipticCylinder, QuadricType::CircularCone, QuadricType::EllipticCone};

const std::vector<QuadricType> kOtherRealTypes = {
    QuadricType::HyperboloidOneSheet, QuadricType::HyperboloidTwoSheets, QuadricType::EllipticParaboloid,
    QuadricType::HyperbolicParaboloid, QuadricType::ParabolicCylinder, QuadricType::HyperbolicCylinder,
    QuadricType::IntersectingPlanes, QuadricType::ParallelPlanes};

class TableTypeTest : public ::testing::TestWithParam<QuadricType> {};

// Build Q from (type, scale, pose), multiply by a random k, decompose: type, scales (1e-9
// relative), defined axes up to sign, centre (on the true centre line/plane for non-central).
TEST_P(TableTypeTest, DecompositionRecoversTypeScaleAxesAndCentre) {
  const QuadricType type = GetParam();
  std::mt19937_64 random(1000 + int(type));
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3d scale = scales_for(type, random);
    const Eigen::Isometry3d pose = random_pose(random, 20.0);
    const Quadric quadric(random_multiplier(random) * Quadric::from_canonical(type, scale, pose).matrix());
    const QuadricDecomposition shape = quadric.decompose();
    SCOPED_TRACE("trial " + std::to_string(trial) + " type " + quadric_type_name(type));
    ASSERT_EQ(shape.type, type);
    EXPECT_NEAR(shape.rotation.determinant(), 1.0, 1e-12);
    EXPECT_LT((shape.rotation.transpose() * shape.rotation - Eigen::Matrix3d::Identity()).norm(), 1e-12);
    const DegeneracyIndicators expected = degeneracy_indicators(type);
    EXPECT_EQ(shape.indicators.scale, expected.scale);
    EXPECT_EQ(shape.indicators.rotation, expected.rotation);
    EXPECT_EQ(shape.indicators.translation, expected.translation);
    for (int k = 0; k < 3; ++k) {
      if (expected.scale[k] > 0.5) {
        EXPECT_NEAR(shape.scale[k], scale[k], 1e-9 * scale[k]) << "axis " << k;
      } else {
        EXPECT_EQ(shape.scale[k], 0.0);
      }
      if (expected.rotation[k] > 0.5) {
        EXPECT_NEAR(std::abs(shape.rotation.col(k).dot(pose.linear().col(k))), 1.0, 1e-9) << "axis " << k;
      }
    }
    const Eigen::Vector3d true_center = pose.translation();
    const Eigen::Vector3d offset = shape.center - true_center;
    switch (type) {
      case QuadricType::Line:
      case QuadricType::CircularCylinder:
      case QuadricType::EllipticCylinder: {
        const Eigen::Vector3d axis = pose.linear().col(2);
        EXPECT_LT((offset - offset.dot(axis) * axis).norm(), 1e-8);   // on the true axis line
        EXPECT_LT(std::abs(shape.center.dot(axis)), 1e-8);             // its minimum-norm point
        EXPECT_EQ(shape.center_kind, CenterKind::LinearCenter);
        break;
      }
      case QuadricType::Plane: {
        const Eigen::Vector3d normal = pose.linear().col(0);
        EXPECT_LT(std::abs(offset.dot(normal)), 1e-8);                                  // on the plane
        EXPECT_LT((shape.center - shape.center.dot(normal) * normal).norm(), 1e-8);     // minimum norm
        EXPECT_EQ(shape.center_kind, CenterKind::PlanarCenter);
        break;
      }
      default:
        EXPECT_LT(offset.norm(), 1e-8);
        EXPECT_EQ(shape.center_kind, CenterKind::Central);
    }
  }
}

// Q and k Q decompose identically (normalisation with its deterministic sign rule).
TEST_P(TableTypeTest, NormalisationMakesDecompositionScaleInvariant) {
  const QuadricType type = GetParam();
  std::mt19937_64 random(2000 + int(type));
  for (int trial = 0; trial < 200; ++trial) {
    const Quadric quadric = Quadric::from_canonical(type, scales_for(type, random), random_pose(random, 20.0));
    const Quadric scaled(random_multiplier(random) * quadric.matrix());
    const QuadricDecomposition a = quadric.decompose();
    const QuadricDecomposition b = scaled.decompose();
    ASSERT_EQ(a.type, b.type);
    EXPECT_LT((a.scale - b.scale).norm(), 1e-9 * (1.0 + a.scale.norm()));
    EXPECT_LT((a.center - b.center).norm(), 1e-8);
    EXPECT_LT((a.eigenvalues - b.eigenvalues).norm(), 1e-9 * a.eigenvalues.cwiseAbs().maxCoeff());
    for (int k = 0; k < 3; ++k) {
      if (a.indicators.rotation[k] > 0.5) {
        EXPECT_LT((a.rotation.col(k) - b.rotation.col(k)).norm(), 1e-8);
      }
    }
    const Eigen::Matrix4d na = quadric.normalized().matrix();
    const Eigen::Matrix4d nb = scaled.normalized().matrix();
    EXPECT_LT((na - nb).norm(), 1e-9 * na.norm());
  }
}

// Transforming Q and its surface points together keeps the points on the surface.
TEST_P(TableTypeTest, TransformKeepsSampledPointsOnSurface) {
  const QuadricType type = GetParam();
  std::mt19937_64 random(3000 + int(type));
  LocalExtent extent;
  extent.minimum = Eigen::Vector3d::Constant(-3.0);
  extent.maximum = Eigen::Vector3d::Constant(3.0);
  for (int trial = 0; trial < 50; ++trial) {
    const Quadric quadric = Quadric::from_canonical(type, scales_for(type, random), random_pose(random, 20.0));
    const QuadricDecomposition shape = quadric.decompose();
    const Eigen::Matrix3Xd points = sample_surface(shape, extent, 0.3);
    ASSERT_GT(points.cols(), 0);
    const Eigen::Isometry3d motion = random_pose(random, 20.0);
    const Quadric moved = quadric.transformed(motion);
    const QuadricDecomposition moved_shape = moved.decompose();
    ASSERT_EQ(moved_shape.type, type);
    for (Eigen::Index i = 0; i < points.cols(); ++i) {
      const Eigen::Vector3d p = motion * Eigen::Vector3d(points.col(i));
      EXPECT_LT(orthogonal_distance(moved_shape, p), 1e-7);
      if (type != QuadricType::Point && type != QuadricType::Line && type != QuadricType::Plane &&
          !((type == QuadricType::CircularCone || type == QuadricType::EllipticCone) &&
            (Eigen::Vector3d(points.col(i)) - shape.center).norm() < 1e-6)) {  // the apex is singular
        EXPECT_LT(moved.sampson_distance(p), 1e-7);
      }
    }
    if (is_central(type)) {
      EXPECT_LT((moved_shape.center - motion * shape.center).norm(), 1e-7);
    }
  }
}

// Exact orthogonal distance and closest point against dense brute-force sampling: brute force can
// never beat the exact distance, and is within one sampling step of it.
TEST_P(TableTypeTest, OrthogonalDistanceMatchesBruteForce) {
  const QuadricType type = GetParam();
  std::mt19937_64 random(4000 + int(type));
  const double spacing = 0.02;
  std::uniform_real_distribution<double> query(-2.5, 2.5);
  for (int trial = 0; trial < 6; ++trial) {
    // Bounded sizes (ratios kept) so the nearest surface point lies inside the sampled region.
    Eigen::Vector3d scale = scales_for(type, random);
    const double limit = (type == QuadricType::CircularCone || type == QuadricType::EllipticCone) ? 1.5 : 2.0;
    if (scale.maxCoeff() > limit) scale *= limit / scale.maxCoeff();
    const Eigen::Isometry3d pose = random_pose(random, 5.0);
    const QuadricDecomposition shape = Quadric::from_canonical(type, scale, pose).decompose();
    ASSERT_EQ(shape.type, type);
    LocalExtent extent;
    extent.minimum = Eigen::Vector3d::Constant(-8.0);
    extent.maximum = Eigen::Vector3d::Constant(8.0);
    const Eigen::Matrix3Xd surface = sample_surface(shape, extent, spacing);
    ASSERT_GT(surface.cols(), 0);
    for (int q = 0; q < 15; ++q) {
      const Eigen::Vector3d x = shape.pose() * Eigen::Vector3d(query(random), query(random), query(random));
      const double exact = orthogonal_distance(shape, x);
      const double brute = (surface.colwise() - x).colwise().norm().minCoeff();
      EXPECT_GE(brute, exact - 1e-9) << "query " << q;
      EXPECT_LE(brute, exact + spacing) << "query " << q;
      const Eigen::Vector3d foot = closest_surface_point(shape, x);
      EXPECT_NEAR((foot - x).norm(), exact, 1e-9 * (1.0 + exact));
      EXPECT_LT(orthogonal_distance(shape, foot), 1e-8);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(AllTableTypes, TableTypeTest, ::testing::ValuesIn(kTableTypes),
                         [](const ::testing::TestParamInfo<QuadricType>& info) { return quadric_type_name(info.param); });

class OtherRealTypeTest : public ::testing::TestWithParam<QuadricType> {};

// The other real types of the 17: classified from their canonical forms under random poses, and
// the decomposition rebuilds the same surface (same normalised Q).
TEST_P(OtherRealTypeTest, ClassifiedAndRebuiltUnderRandomPoses) {
  const QuadricType type = GetParam();
  std::mt19937_64 random(5000 + int(type));
  LocalExtent extent;
  extent.minimum = Eigen::Vector3d::Constant(-3.0);
  extent.maximum = Eigen::Vector3d::Constant(3.0);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3d scale = distinct_ascending_scales(random, 0.3, 3.0);
    const Quadric quadric(random_multiplier(random) * Quadric::from_canonical(type, scale, random_pose(random, 20.0)).matrix());
    const QuadricDecomposition shape = quadric.decompose();
    ASSERT_EQ(shape.type, type) << "trial " << trial;
    EXPECT_NEAR(shape.rotation.determinant(), 1.0, 1e-12);
    const Quadric rebuilt = quadric_from_decomposition(shape);
    const Eigen::Matrix4d a = quadric.normalized().matrix();
    const Eigen::Matrix4d b = rebuilt.normalized().matrix();
    EXPECT_LT((a - b).norm(), 1e-7 * a.norm()) << "trial " << trial;
    if (trial < 20) {
      const Eigen::Matrix3Xd points = sample_surface(shape, extent, 0.25);
      ASSERT_GT(points.cols(), 0);
      for (Eigen::Index i = 0; i < points.cols(); ++i) {
        const Eigen::Vector3d p = points.col(i);
        const double gradient = quadric.gradient(p).norm();
        if (gradient > 1e-6 * quadric.matrix().norm()) {  // away from singular points (e.g. plane-pair line)
          EXPECT_LT(quadric.sampson_distance(p), 1e-7);
        }
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(OtherRealTypes, OtherRealTypeTest, ::testing::ValuesIn(kOtherRealTypes),
                         [](const ::testing::TestParamInfo<QuadricType>& info) { return quadric_type_name(info.param); });

TEST(QuadricTest, RebuildingFromDecompositionRoundTripsForTableTypes) {
  std::mt19937_64 random(6000);
  for (QuadricType type : kTableTypes) {
    for (int trial = 0; trial < 50; ++trial) {
      const Quadric quadric = Quadric::from_canonical(type, scales_for(type, random), random_pose(random, 20.0));
      const Quadric rebuilt = quadric_from_decomposition(quadric.decompose());
      // Point, line and plane: the weights of degenerate axes are not part of the surface; compare surfaces.
      if (type == QuadricType::Point || type == QuadricType::Line || type == QuadricType::Plane) {
        EXPECT_EQ(rebuilt.decompose().type, type);
        EXPECT_LT((rebuilt.decompose().center - quadric.decompose().center).norm(), 1e-8);
      } else {
        EXPECT_LT((quadric.normalized().matrix() - rebuilt.normalized().matrix()).norm(),
                  1e-7 * quadric.normalized().matrix().norm())
            << quadric_type_name(type) << " trial " << trial;
      }
    }
  }
}

TEST(QuadricTest, ParametersMatchPaperLayout) {
  Vector10d q;
  q << 1, 2, 3, 4, 5, 6, 7, 8, 9, 10;
  const Quadric quadric = Quadric::from_parameters(q);
  EXPECT_EQ(quadric.parameters(), q);
  EXPECT_EQ(quadric.matrix()(0, 1), 4.0);
  EXPECT_EQ(quadric.matrix()(1, 2), 6.0);
  EXPECT_EQ(quadric.matrix()(2, 3), 9.0);
  // f(x) = Ax^2 + By^2 + Cz^2 + 2Dxy + 2Exz + 2Fyz + 2Gx + 2Hy + 2Iz + J at a random point.
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> uniform(-3.0, 3.0);
  for (int trial = 0; trial < 100; ++trial) {
    const Eigen::Vector3d p(uniform(random), uniform(random), uniform(random));
    const double x = p[0], y = p[1], z = p[2];
    const double expected = 1 * x * x + 2 * y * y + 3 * z * z + 2 * 4 * x * y + 2 * 5 * x * z + 2 * 6 * y * z +
                            2 * 7 * x + 2 * 8 * y + 2 * 9 * z + 10;
    EXPECT_NEAR(quadric.evaluate(p), expected, 1e-9 * (1.0 + std::abs(expected)));
    // Gradient against central differences.
    const double h = 1e-6;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d step = h * Eigen::Vector3d::Unit(k);
      const double numeric = (quadric.evaluate(p + step) - quadric.evaluate(p - step)) / (2 * h);
      EXPECT_NEAR(quadric.gradient(p)[k], numeric, 1e-5 * (1.0 + std::abs(numeric)));
    }
  }
}

TEST(QuadricTest, NormalisationFollowsPaperRuleAndSignConvention) {
  std::mt19937_64 random(8);
  for (int trial = 0; trial < 100; ++trial) {
    const Eigen::Vector3d scale = distinct_ascending_scales(random, 0.2, 5.0);
    const Quadric ellipsoid(random_multiplier(random) *
                            Quadric::from_canonical(QuadricType::Ellipsoid, scale, random_pose(random, 20.0)).matrix());
    const Eigen::Matrix4d n = ellipsoid.normalized().matrix();
    // Paper: Q * |prod l(Q33) / prod l(Q)| when c44 != 0, i.e. |det Q33 / det Q| for rank 3.
    const double paper = std::abs(ellipsoid.matrix().topLeftCorner<3, 3>().determinant() / ellipsoid.matrix().determinant());
    EXPECT_LT((n.cwiseAbs() - paper * ellipsoid.matrix().cwiseAbs()).norm(), 1e-8 * n.norm());
    const QuadricDecomposition shape = ellipsoid.decompose();
    EXPECT_NEAR(shape.constant, -1.0, 1e-9);
    EXPECT_GT(shape.eigenvalues.minCoeff(), 0.0);
    EXPECT_GE(shape.eigenvalues[0], shape.eigenvalues[1]);
    EXPECT_GE(shape.eigenvalues[1], shape.eigenvalues[2]);
    // c44 = 0: Frobenius normalisation.
    const Quadric cone(random_multiplier(random) *
                       Quadric::from_canonical(QuadricType::EllipticCone, Eigen::Vector3d(0.5, 1.0, 0.0), random_pose(random, 20.0)).matrix());
    EXPECT_NEAR(cone.normalized().matrix().norm(), 1.0, 1e-12);
    EXPECT_EQ((cone.normalized().decompose().eigenvalues.array() > 0).count(), 2);
  }
}

TEST(QuadricTest, SymmetryAwareIndicators) {
  std::mt19937_64 random(9);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Isometry3d pose = random_pose(random, 20.0);
    // Oblate spheroid (two small equal lambdas? here two equal large scales): unique axis is c or a.
    const QuadricDecomposition prolate =
        Quadric::from_canonical(QuadricType::Ellipsoid, Eigen::Vector3d(1.0, 1.0, 3.0), pose).decompose();
    ASSERT_EQ(prolate.type, QuadricType::Ellipsoid);
    EXPECT_EQ(prolate.indicators.rotation, Eigen::Vector3d(0, 0, 1));
    EXPECT_NEAR(std::abs(prolate.rotation.col(2).dot(pose.linear().col(2))), 1.0, 1e-9);
    const QuadricDecomposition oblate =
        Quadric::from_canonical(QuadricType::Ellipsoid, Eigen::Vector3d(0.5, 2.0, 2.0), pose).decompose();
    ASSERT_EQ(oblate.type, QuadricType::Ellipsoid);
    EXPECT_EQ(oblate.indicators.rotation, Eigen::Vector3d(1, 0, 0));
    EXPECT_NEAR(std::abs(oblate.rotation.col(0).dot(pose.linear().col(0))), 1.0, 1e-9);
    const QuadricDecomposition sphere =
        Quadric::from_canonical(QuadricType::Ellipsoid, Eigen::Vector3d(1.5, 1.5, 1.5), pose).decompose();
    EXPECT_EQ(sphere.type, QuadricType::Sphere);
    EXPECT_EQ(sphere.indicators.rotation, Eigen::Vector3d::Zero());
    EXPECT_EQ(sphere.rotation, Eigen::Matrix3d::Identity());  // deterministic: no axis is defined
    const QuadricDecomposition round =
        Quadric::from_canonical(QuadricType::EllipticCylinder, Eigen::Vector3d(2.0, 2.0, 0.0), pose).decompose();
    EXPECT_EQ(round.type, QuadricType::CircularCylinder);
    EXPECT_EQ(round.indicators.rotation, Eigen::Vector3d(0, 0, 1));
    const QuadricDecomposition hyperboloid =
        Quadric::from_canonical(QuadricType::HyperboloidOneSheet, Eigen::Vector3d(1.0, 1.0, 2.0), pose).decompose();
    EXPECT_EQ(hyperboloid.indicators.rotation, Eigen::Vector3d(0, 0, 1));
  }
}

TEST(QuadricTest, ImaginaryAndInvalidQuadrics) {
  std::mt19937_64 random(10);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Isometry3d pose = random_pose(random, 20.0);
    for (const Eigen::Vector4d& diagonal :
         {Eigen::Vector4d(1, 2, 3, 1), Eigen::Vector4d(1, 2, 0, 1), Eigen::Vector4d(2, 0, 0, 1)}) {
      Eigen::Matrix4d c = diagonal.asDiagonal();
      const Eigen::Matrix4d inverse = pose.inverse().matrix();
      const Quadric imaginary(random_multiplier(random) * inverse.transpose() * c * inverse);
      const QuadricDecomposition shape = imaginary.decompose();
      EXPECT_EQ(shape.type, QuadricType::Imaginary);
      EXPECT_EQ(shape.indicators.scale, Eigen::Vector3d::Zero());
      EXPECT_TRUE(std::isinf(orthogonal_distance(shape, Eigen::Vector3d::Zero())));
    }
  }
  EXPECT_EQ(Quadric().decompose().type, QuadricType::Invalid);
  Vector10d nan_parameters = Vector10d::Ones();
  nan_parameters[4] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(Quadric::from_parameters(nan_parameters).decompose().type, QuadricType::Invalid);
  Vector10d infinite = Vector10d::Ones();
  infinite[9] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(Quadric::from_parameters(infinite).decompose().type, QuadricType::Invalid);
  Vector10d linear_only = Vector10d::Zero();
  linear_only[6] = 1.0;  // 2x + 0 = 0: quadratic part all zero, excluded by Eq. (quadrics equation)
  EXPECT_EQ(Quadric::from_parameters(linear_only).decompose().type, QuadricType::Invalid);
  const QuadricDecomposition invalid = Quadric().decompose();
  EXPECT_TRUE(std::isinf(orthogonal_distance(invalid, Eigen::Vector3d::Ones())));
  EXPECT_EQ(closest_surface_point(invalid, Eigen::Vector3d::Ones()), Eigen::Vector3d::Ones());
  EXPECT_EQ(Quadric().normalized().matrix(), Eigen::Matrix4d::Zero());
}

TEST(QuadricTest, FromCanonicalRejectsBadInput) {
  const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
  EXPECT_THROW(Quadric::from_canonical(QuadricType::Sphere, Eigen::Vector3d(-1, 1, 1), identity), Error);
  EXPECT_THROW(Quadric::from_canonical(QuadricType::EllipticCylinder, Eigen::Vector3d(1, 0, 0), identity), Error);
  EXPECT_THROW(Quadric::from_canonical(QuadricType::Imaginary, Eigen::Vector3d(1, 1, 1), identity), Error);
  EXPECT_THROW(Quadric::from_canonical(QuadricType::Invalid, Eigen::Vector3d(1, 1, 1), identity), Error);
  EXPECT_THROW(Quadric::from_canonical(QuadricType::Ellipsoid,
                                       Eigen::Vector3d(1, std::numeric_limits<double>::quiet_NaN(), 1), identity),
               Error);
  Eigen::Isometry3d skewed = identity;
  skewed.linear()(0, 1) = 0.5;
  EXPECT_THROW(Quadric::from_canonical(QuadricType::Sphere, Eigen::Vector3d(1, 1, 1), skewed), Error);
  try {
    Quadric::from_canonical(QuadricType::Ellipsoid, Eigen::Vector3d(1, 0, 1), identity);
    FAIL() << "expected quadrix::Error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("axis b"), std::string::npos) << error.what();
  }
  // Degenerate scales of point, line and plane are weights only: zero is accepted.
  EXPECT_EQ(Quadric::from_canonical(QuadricType::Line, Eigen::Vector3d::Zero(), identity).decompose().type,
            QuadricType::Line);
}

TEST(QuadricTest, TypeNamesRoundTrip) {
  for (int value = 0; value <= int(QuadricType::Invalid); ++value) {
    const QuadricType type = QuadricType(value);
    EXPECT_EQ(quadric_type_from_name(quadric_type_name(type)), type);
  }
  EXPECT_EQ(quadric_type_from_name("cylinder"), QuadricType::CircularCylinder);
  EXPECT_EQ(quadric_type_from_name("cone"), QuadricType::CircularCone);
  EXPECT_THROW(quadric_type_from_name("torus"), Error);
}

TEST(QuadricTest, SampsonDistanceIsFirstOrderDistance) {
  // Sphere radius 2 at the origin: f = |x|^2 - 4, Sampson = ||x|^2 - 4| / (2|x|).
  const Quadric sphere = Quadric::from_canonical(QuadricType::Sphere, Eigen::Vector3d::Constant(2.0), Eigen::Isometry3d::Identity());
  std::mt19937_64 random(11);
  std::uniform_real_distribution<double> uniform(-5.0, 5.0);
  for (int trial = 0; trial < 100; ++trial) {
    const Eigen::Vector3d x(uniform(random), uniform(random), uniform(random));
    const double r = x.norm();
    EXPECT_NEAR(sphere.sampson_distance(x), std::abs(r * r - 4.0) / (2.0 * r), 1e-12 * (1.0 + r * r));
  }
  const Quadric point = Quadric::from_canonical(QuadricType::Point, Eigen::Vector3d::Ones(), Eigen::Isometry3d::Identity());
  EXPECT_EQ(point.sampson_distance(Eigen::Vector3d::Zero()), 0.0);
}

TEST(QuadricTest, ConeDistanceHandlesAxisApexAndBothNappes) {
  const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
  const QuadricDecomposition circular =
      Quadric::from_canonical(QuadricType::CircularCone, Eigen::Vector3d(1.0, 1.0, 0.0), identity).decompose();
  const QuadricDecomposition elliptic =
      Quadric::from_canonical(QuadricType::EllipticCone, Eigen::Vector3d(1.0, 1.0 + 1e-3, 0.0), identity).decompose();
  ASSERT_EQ(circular.type, QuadricType::CircularCone);
  ASSERT_EQ(elliptic.type, QuadricType::EllipticCone);
  for (const QuadricDecomposition& cone : {circular, elliptic}) {
    // 45 degree half-angle: a point on the axis at height h is h / sqrt(2) away (both nappes).
    EXPECT_NEAR(orthogonal_distance(cone, Eigen::Vector3d(0, 0, 2)), 2.0 / std::sqrt(2.0), 2e-3);
    EXPECT_NEAR(orthogonal_distance(cone, Eigen::Vector3d(0, 0, -3)), 3.0 / std::sqrt(2.0), 3e-3);
    EXPECT_NEAR(orthogonal_distance(cone, Eigen::Vector3d(0, 0, 0)), 0.0, 1e-12);
    // In the plane z = 0 both nappes are r / sqrt(2) away (45 degree generatrices).
    EXPECT_NEAR(orthogonal_distance(cone, Eigen::Vector3d(2, 0, 0)), 2.0 / std::sqrt(2.0), 2e-3);
  }
}

// Queries with exact zero coordinates (centre, axes, coordinate planes) are the degenerate cases of
// the Lagrange/bisection solver (the minimum sits on a pole); check them against brute force.
TEST(QuadricTest, DistanceOnAxesAndCentreMatchesBruteForce) {
  const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
  LocalExtent extent;
  extent.minimum = Eigen::Vector3d::Constant(-6.0);
  extent.maximum = Eigen::Vector3d::Constant(6.0);
  const double spacing = 0.01;
  const std::vector<std::pair<QuadricType, Eigen::Vector3d>> shapes = {
      {QuadricType::Ellipsoid, Eigen::Vector3d(0.7, 1.2, 2.0)},
      {QuadricType::EllipticCylinder, Eigen::Vector3d(0.7, 1.6, 0.0)},
      {QuadricType::EllipticCone, Eigen::Vector3d(0.4, 1.1, 0.0)}};
  std::vector<Eigen::Vector3d> queries = {Eigen::Vector3d::Zero()};
  for (int k = 0; k < 3; ++k)
    for (double value : {-2.5, -0.3, 0.2, 1.0, 3.0}) queries.push_back(value * Eigen::Vector3d::Unit(k));
  queries.push_back(Eigen::Vector3d(0.0, 0.4, 0.5));
  queries.push_back(Eigen::Vector3d(0.3, 0.0, -0.4));
  queries.push_back(Eigen::Vector3d(0.2, 0.3, 0.0));
  for (const auto& [type, scale] : shapes) {
    const QuadricDecomposition shape = Quadric::from_canonical(type, scale, identity).decompose();
    ASSERT_EQ(shape.type, type);
    const Eigen::Matrix3Xd surface = sample_surface(shape, extent, spacing);
    for (const Eigen::Vector3d& x : queries) {
      const double exact = orthogonal_distance(shape, x);
      const double brute = (surface.colwise() - x).colwise().norm().minCoeff();
      EXPECT_GE(brute, exact - 1e-9) << quadric_type_name(type) << " at " << x.transpose();
      EXPECT_LE(brute, exact + spacing) << quadric_type_name(type) << " at " << x.transpose();
      EXPECT_LT(orthogonal_distance(shape, closest_surface_point(shape, x)), 1e-9);
    }
  }
}

}  // namespace
}  // namespace quadrix
