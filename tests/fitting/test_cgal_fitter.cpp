// The CGAL shape-detection fitter against synthetic ground truth (fixed seeds, statistical
// acceptance): each supported primitive restricted by the hint, the automatic choice, caller
// normals, reproducibility, and honest statuses for what CGAL cannot detect.
#include "fitting/cgal_fitter.h"
#include "fitting/quadric_fitter.h"
#include "geometry/constants.h"
#include "geometry/error.h"
#include "test_geometry.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>

namespace quadrix {
namespace {

using testing::random_pose;
using testing::TranslationDraw;

/// Points (and exact normals) on a canonical surface under `pose`.
std::pair<Eigen::Matrix3Xd, Eigen::Matrix3Xd> sample(QuadricType type, const Eigen::Vector3d& scale,
                                                      const Eigen::Isometry3d& pose, int count, std::mt19937_64& random) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::Matrix3Xd points(3, count), normals(3, count);
  for (int i = 0; i < count; ++i) {
    const double angle = 2.0 * kPi * unit(random);
    Eigen::Vector3d local, local_normal;
    switch (type) {
      case QuadricType::Sphere: {
        local_normal = Eigen::Vector3d(normal(random), normal(random), normal(random)).normalized();
        local = local_normal * scale(0);
        break;
      }
      case QuadricType::CircularCylinder:
        local << scale(0) * std::cos(angle), scale(0) * std::sin(angle), (unit(random) - 0.5) * 3.0;
        local_normal << std::cos(angle), std::sin(angle), 0.0;
        break;
      case QuadricType::CircularCone: {
        const double height = 0.5 + 2.0 * unit(random);
        local << height * scale(0) * std::cos(angle), height * scale(0) * std::sin(angle), height;
        local_normal = Eigen::Vector3d(std::cos(angle), std::sin(angle), -scale(0)).normalized();
        break;
      }
      case QuadricType::Plane:
        local << 0.0, (unit(random) - 0.5) * 4.0, (unit(random) - 0.5) * 3.0;
        local_normal = Eigen::Vector3d::UnitX();
        break;
      default:
        local << 0.0, 0.0, (unit(random) - 0.5) * 6.0;
        local_normal = Eigen::Vector3d::UnitX();
    }
    points.col(i) = pose * local;
    normals.col(i) = pose.linear() * local_normal;
  }
  return {points, normals};
}

struct Case {
  QuadricType type;
  Eigen::Vector3d scale;
};

/// Each primitive, detected with the type as the hint on noise-free points with estimated normals:
/// the type is exact and the radius / tangent within 1% (RANSAC estimates from minimal samples with
/// jet-fitted normals, so not to machine precision), in at least 18 of 20 rounds.
class CgalDetectsPrimitive : public ::testing::TestWithParam<QuadricType> {};

TEST_P(CgalDetectsPrimitive, TypeAndScaleFromEstimatedNormals) {
  const QuadricType type = GetParam();
  std::mt19937_64 random(500 + static_cast<int>(type));
  std::uniform_real_distribution<double> size(0.4, 2.0), tangent(0.3, 1.0);
  const auto fitter = make_quadric_fitter("cgal");
  const int rounds = 20;
  int passed = 0;
  for (int round = 0; round < rounds; ++round) {
    Eigen::Vector3d scale = Eigen::Vector3d::Ones();
    if (type == QuadricType::Sphere) scale.setConstant(size(random));
    if (type == QuadricType::CircularCylinder) { const double r = size(random); scale << r, r, 1.0; }
    if (type == QuadricType::CircularCone) { const double t = tangent(random); scale << t, t, 1.0; }
    const Eigen::Isometry3d pose = random_pose(random, 10.0, TranslationDraw::Gaussian);
    const auto [points, normals] = sample(type, scale, pose, 1500, random);
    const QuadricFit fit = fitter->fit(points, Eigen::Matrix3Xd(), type);
    bool ok = fit.status == FitStatus::Ok && fit.type == type;
    double scale_error = 0.0, axis_error = 0.0;
    if (ok && type != QuadricType::Plane) scale_error = std::abs(fit.shape.scale(0) - scale(0)) / scale(0);
    if (ok && type == QuadricType::Plane) axis_error = 1.0 - std::abs(fit.shape.rotation.col(0).dot(pose.linear().col(0)));
    if (ok && (type == QuadricType::CircularCylinder || type == QuadricType::CircularCone))
      axis_error = 1.0 - std::abs(fit.shape.rotation.col(2).dot(pose.linear().col(2)));
    ok = ok && scale_error < 0.01 && axis_error < 1e-3 && fit.residual_rms < 0.01 * scale.maxCoeff();
    passed += ok ? 1 : 0;
    if (!ok)
      std::cout << quadric_type_name(type) << " round " << round << ": " << fit_status_name(fit.status) << " ("
                << fit.message << ") type " << quadric_type_name(fit.type) << " scale error " << scale_error
                << " axis error " << axis_error << " rms " << fit.residual_rms << std::endl;
  }
  EXPECT_GE(passed, rounds - 2);
}

INSTANTIATE_TEST_SUITE_P(Primitives, CgalDetectsPrimitive,
                         ::testing::Values(QuadricType::Plane, QuadricType::Sphere, QuadricType::CircularCylinder,
                                           QuadricType::CircularCone),
                         [](const auto& info) { return quadric_type_name(info.param); });

TEST(CgalFitter, AutomaticChoiceKeepsTheShapeCoveringMostPoints) {
  std::mt19937_64 random(61);
  const auto fitter = make_quadric_fitter("cgal");
  int correct = 0, total = 0;
  for (const QuadricType type : {QuadricType::Plane, QuadricType::Sphere, QuadricType::CircularCylinder}) {
    for (int round = 0; round < 6; ++round) {
      const Eigen::Vector3d scale = type == QuadricType::Plane ? Eigen::Vector3d::Ones() : Eigen::Vector3d(1.0, 1.0, 1.0);
      const auto [points, normals] = sample(type, scale, random_pose(random, 10.0, TranslationDraw::Gaussian), 1200, random);
      const QuadricFit fit = fitter->fit(points, normals, std::nullopt);
      correct += (fit.status == FitStatus::Ok && fit.type == type) ? 1 : 0;
      ++total;
    }
  }
  EXPECT_GE(correct, total - 2);
}

TEST(CgalFitter, CallerNormalsAreUsedAndFitsAreReproducible) {
  std::mt19937_64 random(62);
  const auto fitter = make_quadric_fitter("cgal");
  const auto [points, normals] = sample(QuadricType::CircularCylinder, {0.5, 0.5, 1.0}, random_pose(random, 10.0, TranslationDraw::Gaussian), 1500, random);
  const QuadricFit with_normals = fitter->fit(points, normals, QuadricType::CircularCylinder);
  ASSERT_EQ(with_normals.status, FitStatus::Ok) << with_normals.message;
  // Exact normals: the radius from RANSAC's minimal sample is exact up to rounding.
  EXPECT_NEAR(with_normals.shape.scale(0), 0.5, 1e-6);
  const QuadricFit again = fitter->fit(points, normals, QuadricType::CircularCylinder);
  EXPECT_TRUE(again.quadric.matrix() == with_normals.quadric.matrix());  // the seed is reset at every fit
  EXPECT_THROW(fitter->fit(points, normals.leftCols(10), QuadricType::CircularCylinder), Error);
}

TEST(CgalFitter, LineAndPointUseLeastSquares) {
  std::mt19937_64 random(63);
  const auto fitter = make_quadric_fitter("cgal");
  const Eigen::Isometry3d pose = random_pose(random, 10.0, TranslationDraw::Gaussian);
  const auto [points, normals] = sample(QuadricType::Line, Eigen::Vector3d::Ones(), pose, 100, random);
  const QuadricFit line = fitter->fit(points, Eigen::Matrix3Xd(), QuadricType::Line);
  ASSERT_EQ(line.status, FitStatus::Ok);
  EXPECT_EQ(line.type, QuadricType::Line);
  EXPECT_NEAR(std::abs(line.shape.rotation.col(2).dot(pose.linear().col(2))), 1.0, 1e-9);
  EXPECT_LT(line.residual_rms, 1e-7);
  const QuadricFit point = fitter->fit(points, Eigen::Matrix3Xd(), QuadricType::Point);
  ASSERT_EQ(point.status, FitStatus::Ok);
  EXPECT_LT((point.shape.center - Eigen::Vector3d(points.rowwise().mean())).norm(), 1e-9);
}

TEST(CgalFitter, ReportsWhatCgalCannotDetect) {
  std::mt19937_64 random(64);
  const auto fitter = make_quadric_fitter("cgal");
  EXPECT_EQ(fitter->name(), "cgal");
  const auto [points, normals] = sample(QuadricType::Sphere, Eigen::Vector3d::Constant(1.0), random_pose(random, 10.0, TranslationDraw::Gaussian), 500, random);
  const QuadricFit ellipsoid = fitter->fit(points, Eigen::Matrix3Xd(), QuadricType::Ellipsoid);
  EXPECT_EQ(ellipsoid.status, FitStatus::Failed);
  EXPECT_THAT(ellipsoid.message, ::testing::HasSubstr("ellipsoid"));
  EXPECT_EQ(fitter->fit(points.leftCols(2), Eigen::Matrix3Xd(), QuadricType::Plane).status, FitStatus::TooFewPoints);
  // Uniform noise in a cube holds no sphere covering half of the points.
  std::uniform_real_distribution<double> box(-1.0, 1.0);
  Eigen::Matrix3Xd cloud(3, 600);
  for (Eigen::Index i = 0; i < cloud.cols(); ++i) cloud.col(i) = Eigen::Vector3d(box(random), box(random), box(random));
  const QuadricFit nothing = fitter->fit(cloud, Eigen::Matrix3Xd(), QuadricType::Sphere);
  EXPECT_EQ(nothing.status, FitStatus::Degenerate);
  EXPECT_THAT(nothing.message, ::testing::HasSubstr("found no sphere"));
  CgalFitterOptions bad;
  bad.minimum_coverage = 0.0;
  EXPECT_THROW(make_cgal_fitter(bad), Error);
}

}  // namespace
}  // namespace quadrix
