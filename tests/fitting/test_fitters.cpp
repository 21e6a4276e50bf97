// Fitters against synthetic ground truth: exact surfaces sampled in their canonical frame
// (sampled here independently of geometry/mesh.cpp) under random poses, fixed seeds.
#include "fitting/quadric_fitter.h"
#include "fitting/statistical_fitter.h"
#include "fitting/taubin_fitter.h"
#include "geometry/error.h"
#include "fitting/canonical_surfaces.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace quadrix {
namespace {

using namespace ::quadrix::testing;

/// Taubin recovers type and parameters of noise-free full surfaces to 1e-6 relative (issue 5 figure).
class TaubinExactSurfaces : public ::testing::TestWithParam<QuadricType> {};

TEST_P(TaubinExactSurfaces, RecoversTypeScaleAxisAndCentre) {
  const QuadricType type = GetParam();
  std::mt19937_64 random(1000 + static_cast<int>(type));
  const auto fitter = make_quadric_fitter("taubin");
  const int rounds = 50;
  int passed = 0;
  for (int round = 0; round < rounds; ++round) {
    Eigen::Vector3d scale = random_scale(type, random);
    const Eigen::Isometry3d pose = random_pose(random);
    const Eigen::Matrix3Xd points = sample_surface_points(type, scale, pose, 600, random);
    const QuadricFit fit = fitter->fit(points, Eigen::Matrix3Xd(), type);
    const QuadricDecomposition shape = fit.quadric.decompose();
    const bool central = type == QuadricType::Sphere || type == QuadricType::Ellipsoid ||
                         type == QuadricType::CircularCone || type == QuadricType::EllipticCone;
    const int defined_scales = (type == QuadricType::Sphere || type == QuadricType::Ellipsoid) ? 3 : 2;
    const Eigen::Vector3d true_scales = sorted(scale, defined_scales);
    const Eigen::Vector3d found_scales = sorted(shape.scale, defined_scales);
    const double scale_error =
        ((true_scales - found_scales).head(defined_scales).cwiseQuotient(true_scales.head(defined_scales))).cwiseAbs().maxCoeff();
    double centre_error = 0.0;
    if (central) {
      centre_error = (shape.center - pose.translation()).norm();
    } else {  // distance of the recovered centre from the true axis line
      const Eigen::Vector3d axis = pose.linear().col(2);
      const Eigen::Vector3d offset = shape.center - pose.translation();
      centre_error = (offset - offset.dot(axis) * axis).norm();
    }
    double axis_error = 0.0;
    if (!central || type == QuadricType::CircularCone || type == QuadricType::EllipticCone)
      axis_error = 1.0 - std::abs(shape.rotation.col(2).dot(pose.linear().col(2)));
    const bool ok = fit.status == FitStatus::Ok && shape.type == type && scale_error < 1e-6 &&
                    centre_error < 1e-6 * (1.0 + pose.translation().norm()) && axis_error < 1e-9 &&
                    fit.residual_rms < 1e-6;
    passed += ok ? 1 : 0;
    if (!ok)
      ADD_FAILURE() << quadric_type_name(type) << " round " << round << ": status " << fit_status_name(fit.status)
                    << " type " << quadric_type_name(shape.type) << " scale error " << scale_error << " centre error "
                    << centre_error << " axis error " << axis_error << " rms " << fit.residual_rms;
  }
  EXPECT_EQ(passed, rounds);
}

INSTANTIATE_TEST_SUITE_P(AllCurvedTypes, TaubinExactSurfaces,
                         ::testing::Values(QuadricType::Sphere, QuadricType::Ellipsoid, QuadricType::CircularCylinder,
                                           QuadricType::EllipticCylinder, QuadricType::CircularCone,
                                           QuadricType::EllipticCone),
                         [](const auto& info) { return quadric_type_name(info.param); });

TEST(StatisticalFitter, PlaneRecoversNormalAndCentreExactly) {
  std::mt19937_64 random(7);
  const auto fitter = make_quadric_fitter("statistical");
  for (int round = 0; round < 100; ++round) {
    const Eigen::Isometry3d pose = random_pose(random);
    const Eigen::Matrix3Xd points = sample_surface_points(QuadricType::Plane, Eigen::Vector3d::Ones(), pose, 200, random);
    const QuadricFit fit = fitter->fit(points, Eigen::Matrix3Xd(), QuadricType::Plane);
    ASSERT_EQ(fit.status, FitStatus::Ok);
    ASSERT_EQ(fit.type, QuadricType::Plane);
    EXPECT_NEAR(std::abs(fit.shape.rotation.col(0).dot(pose.linear().col(0))), 1.0, 1e-9);
    EXPECT_NEAR((fit.shape.center - pose.translation()).dot(pose.linear().col(0)), 0.0, 1e-7);
    EXPECT_LT(fit.residual_rms, 1e-7);
    // The statistical pose: in-plane extents 10 m x 4 m give sigma ~ 10/sqrt(12), 4/sqrt(12).
    EXPECT_GT(fit.statistics.scale(0), fit.statistics.scale(1));
    EXPECT_NEAR(fit.statistics.scale(2), 0.0, 1e-6);
  }
}

TEST(StatisticalFitter, LineAndCylinderAxisFollowLargestVariance) {
  std::mt19937_64 random(8);
  const auto fitter = make_quadric_fitter("statistical");
  for (int round = 0; round < 100; ++round) {
    const Eigen::Isometry3d pose = random_pose(random);
    const Eigen::Matrix3Xd line = sample_surface_points(QuadricType::Line, Eigen::Vector3d::Ones(), pose, 50, random);
    const QuadricFit line_fit = fitter->fit(line, Eigen::Matrix3Xd(), QuadricType::Line);
    ASSERT_EQ(line_fit.status, FitStatus::Ok);
    ASSERT_EQ(line_fit.type, QuadricType::Line);
    EXPECT_NEAR(std::abs(line_fit.shape.rotation.col(2).dot(pose.linear().col(2))), 1.0, 1e-9);
    EXPECT_LT(line_fit.residual_rms, 1e-7);

    const Eigen::Matrix3Xd cylinder = sample_surface_points(QuadricType::CircularCylinder, {0.3, 0.3, 1.0}, pose, 2000, random);
    const QuadricFit cylinder_fit = fitter->fit(cylinder, Eigen::Matrix3Xd(), QuadricType::CircularCylinder);
    ASSERT_EQ(cylinder_fit.status, FitStatus::Ok);
    ASSERT_EQ(cylinder_fit.type, QuadricType::CircularCylinder);
    EXPECT_GT(std::abs(cylinder_fit.shape.rotation.col(2).dot(pose.linear().col(2))), std::cos(2.0 * kPi / 180.0));
  }
}

TEST(StatisticalFitter, ReportsTooFewPointsAndDegenerateInput) {
  const auto fitter = make_quadric_fitter("statistical");
  Eigen::Matrix3Xd two(3, 2);
  two << 0, 1, 0, 0, 0, 0;
  EXPECT_EQ(fitter->fit(two, Eigen::Matrix3Xd(), QuadricType::Plane).status, FitStatus::TooFewPoints);
  Eigen::Matrix3Xd collinear(3, 5);
  collinear << 0, 1, 2, 3, 4, 0, 1, 2, 3, 4, 0, 1, 2, 3, 4;
  const QuadricFit fit = fitter->fit(collinear, Eigen::Matrix3Xd(), QuadricType::Plane);
  EXPECT_EQ(fit.status, FitStatus::Degenerate);
  EXPECT_THAT(fit.message, ::testing::HasSubstr("collinear"));
}

TEST(TaubinFitter, ReportsTypeMismatchAndTooFewPoints) {
  std::mt19937_64 random(9);
  const auto fitter = make_quadric_fitter("taubin");
  const Eigen::Matrix3Xd sphere =
      sample_surface_points(QuadricType::Sphere, Eigen::Vector3d::Constant(2.0), random_pose(random), 300, random);
  const QuadricFit fit = fitter->fit(sphere, Eigen::Matrix3Xd(), QuadricType::CircularCylinder);
  EXPECT_EQ(fit.status, FitStatus::TypeMismatch);
  EXPECT_EQ(fit.type, QuadricType::Sphere);
  EXPECT_EQ(fitter->fit(sphere.leftCols(5), Eigen::Matrix3Xd(), std::nullopt).status, FitStatus::TooFewPoints);
}

TEST(FitterRegistry, NamesAndErrors) {
  const auto names = quadric_fitter_names();
  EXPECT_THAT(names, ::testing::Contains("statistical"));
  EXPECT_THAT(names, ::testing::Contains("taubin"));
  for (const auto& name : names) EXPECT_EQ(make_quadric_fitter(name)->name(), name);
  try {
    make_quadric_fitter("magic");
    FAIL() << "expected quadrix::Error";
  } catch (const Error& error) {
    EXPECT_THAT(error.what(), ::testing::HasSubstr("magic"));
    EXPECT_THAT(error.what(), ::testing::HasSubstr("statistical"));
  }
  EXPECT_FALSE(fit_type_hint_from_name("auto").has_value());
  EXPECT_EQ(*fit_type_hint_from_name("cylinder"), QuadricType::CircularCylinder);
  EXPECT_THROW(fit_type_hint_from_name("blob"), Error);
}

TEST(UnitSpaceAlgebraicDistance, ZeroOnTheSurfaceAndScaleInvariant) {
  std::mt19937_64 random(10);
  const Eigen::Isometry3d pose = random_pose(random);
  const Eigen::Vector3d scale(1.0, 2.0, 3.0);
  const Eigen::Matrix3Xd points = sample_surface_points(QuadricType::Ellipsoid, scale, pose, 200, random);
  const Quadric quadric = Quadric::from_canonical(QuadricType::Ellipsoid, scale, pose);
  EXPECT_LT(unit_space_algebraic_distance(points, quadric), 1e-9);
  // Moving the points off the surface by a fixed fraction of the size gives the same value at any size.
  const Eigen::Matrix3Xd inflated = ((points.colwise() - pose.translation()) * 1.05).colwise() + pose.translation();
  const double small = unit_space_algebraic_distance(inflated, quadric);
  Eigen::Isometry3d scaled_pose = pose;
  scaled_pose.translation() *= 10.0;
  const Quadric large_quadric = Quadric::from_canonical(QuadricType::Ellipsoid, scale * 10.0, scaled_pose);
  const Eigen::Matrix3Xd large_points = (((points.colwise() - pose.translation()) * 1.05) * 10.0).colwise() + scaled_pose.translation();
  EXPECT_GT(small, 1e-3);
  EXPECT_NEAR(unit_space_algebraic_distance(large_points, large_quadric), small, 1e-9 * (1.0 + small));
}

}  // namespace
}  // namespace quadrix
