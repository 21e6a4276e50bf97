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

/// Taubin recovers type and parameters of noise-free full surfaces to 1e-6 relative.
class TaubinExactSurfaces : public ::testing::TestWithParam<QuadricType> {};

TEST_P(TaubinExactSurfaces, RecoversTypeScaleAxisAndCentre) {
  const QuadricType type = GetParam();
  std::mt19937_64 random(1000 + static_cast<int>(type));
  const auto fitter = make_quadric_fitter("taubin");
  const int rounds = 50;
  int passed = 0;
  for (int round = 0; round < rounds; ++round) {
    Eigen::Vector3d scale = random_scale(type, random);
    const Eigen::Isometry3d pose = random_pose(random, 20.0, TranslationDraw::Gaussian);
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

/// The same target at 10k points per surface (the size of a large real element), every curved type.
TEST_P(TaubinExactSurfaces, RecoversTypeAndScaleAtTenThousandPoints) {
  const QuadricType type = GetParam();
  std::mt19937_64 random(3000 + static_cast<int>(type));
  const auto fitter = make_quadric_fitter("taubin", FitEvaluationOptions{ResidualEvaluation::Subsample, 2000});
  for (int round = 0; round < 3; ++round) {
    const Eigen::Vector3d scale = random_scale(type, random);
    const Eigen::Isometry3d pose = random_pose(random, 20.0, TranslationDraw::Gaussian);
    const Eigen::Matrix3Xd points = sample_surface_points(type, scale, pose, 10000, random);
    const QuadricFit fit = fitter->fit(points, Eigen::Matrix3Xd(), type);
    const int defined_scales = (type == QuadricType::Sphere || type == QuadricType::Ellipsoid) ? 3 : 2;
    const Eigen::Vector3d true_scales = sorted(scale, defined_scales);
    const Eigen::Vector3d found_scales = sorted(fit.shape.scale, defined_scales);
    const double scale_error =
        ((true_scales - found_scales).head(defined_scales).cwiseQuotient(true_scales.head(defined_scales))).cwiseAbs().maxCoeff();
    EXPECT_EQ(fit.status, FitStatus::Ok) << fit.message;
    EXPECT_EQ(fit.shape.type, type) << "round " << round;
    EXPECT_LT(scale_error, 1e-6) << "round " << round;
    EXPECT_LT(fit.residual_rms, 1e-6) << "round " << round;
    EXPECT_EQ(fit.residual_points, 2000);
  }
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
    const Eigen::Isometry3d pose = random_pose(random, 20.0, TranslationDraw::Gaussian);
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
    const Eigen::Isometry3d pose = random_pose(random, 20.0, TranslationDraw::Gaussian);
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
      sample_surface_points(QuadricType::Sphere, Eigen::Vector3d::Constant(2.0), random_pose(random, 20.0, TranslationDraw::Gaussian), 300, random);
  const QuadricFit fit = fitter->fit(sphere, Eigen::Matrix3Xd(), QuadricType::CircularCylinder);
  EXPECT_EQ(fit.status, FitStatus::TypeMismatch);
  EXPECT_EQ(fit.type, QuadricType::Sphere);
  EXPECT_EQ(fitter->fit(sphere.leftCols(5), Eigen::Matrix3Xd(), std::nullopt).status, FitStatus::TooFewPoints);
}

/// Noise opens a waist or an apex gap in the algebraic fit of a cone; within cone_snap_tolerance of
/// the RMS radius it is read as its asymptotic cone, with or without a hint, at 1k and 10k points.
TEST(TaubinFitter, NoisyConesReadAsCones) {
  std::mt19937_64 random(11);
  std::normal_distribution<double> noise(0.0, 0.01);
  const auto fitter = make_quadric_fitter("taubin");
  for (const int count : {1000, 10000}) {
    int hinted = 0, unhinted = 0, snapped = 0;
    const int rounds = 10;
    for (int round = 0; round < rounds; ++round) {
      const Eigen::Vector3d scale = random_scale(QuadricType::CircularCone, random);
      Eigen::Matrix3Xd points = sample_surface_points(QuadricType::CircularCone, scale, random_pose(random, 20.0, TranslationDraw::Gaussian), count, random);
      for (Eigen::Index i = 0; i < points.cols(); ++i)
        points.col(i) += Eigen::Vector3d(noise(random), noise(random), noise(random));
      const QuadricFit with_hint = fitter->fit(points, Eigen::Matrix3Xd(), QuadricType::CircularCone);
      const QuadricFit without_hint = fitter->fit(points, Eigen::Matrix3Xd(), std::nullopt);
      const bool cone = with_hint.status == FitStatus::Ok && with_hint.type == QuadricType::CircularCone &&
                        std::abs(with_hint.shape.scale(0) / scale(0) - 1.0) < 0.05;
      hinted += cone ? 1 : 0;
      unhinted += without_hint.type == QuadricType::CircularCone ? 1 : 0;
      snapped += with_hint.message.find("asymptotic cone") != std::string::npos ? 1 : 0;
      if (!cone) {
        const Eigen::Vector3d& s = with_hint.shape.scale;
        const double gap = std::max(s(0) * s(2) / std::hypot(s(0), s(2)), s(1) * s(2) / std::hypot(s(1), s(2)));
        const double size = std::sqrt((points.colwise() - points.rowwise().mean()).colwise().squaredNorm().mean());
        ADD_FAILURE() << count << " points, round " << round << ": " << fit_status_name(with_hint.status) << " "
                      << quadric_type_name(with_hint.type) << " scale " << s.transpose() << ", true tangent " << scale(0)
                      << ", distance to the asymptotic cone " << gap << " m = " << gap / size
                      << " RMS radius (" << with_hint.message << ")";
      }
    }
    EXPECT_EQ(hinted, rounds) << count << " points";
    EXPECT_EQ(unhinted, rounds) << count << " points";
    EXPECT_GT(snapped, 0) << count << " points: no fit needed the snap, so this test does not exercise it";
  }
}

/// A genuine hyperboloid of one sheet (waist as large as its height scale) is not snapped to a cone.
TEST(TaubinFitter, KeepsAWideWaistHyperboloid) {
  std::mt19937_64 random(12);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int round = 0; round < 5; ++round) {
    const Eigen::Isometry3d pose = random_pose(random, 20.0, TranslationDraw::Gaussian);
    Eigen::Matrix3Xd points(3, 2000);
    for (Eigen::Index i = 0; i < points.cols(); ++i) {
      const double angle = 2.0 * kPi * unit(random), height = 4.0 * unit(random) - 2.0;
      const double radius = std::sqrt(1.0 + height * height);  // x^2 + y^2 - z^2 = 1
      points.col(i) = pose * Eigen::Vector3d(radius * std::cos(angle), radius * std::sin(angle), height);
    }
    const QuadricFit fit = make_quadric_fitter("taubin")->fit(points, Eigen::Matrix3Xd(), std::nullopt);
    EXPECT_EQ(fit.type, QuadricType::HyperboloidOneSheet) << "round " << round << ": " << fit.message;
    EXPECT_LT(fit.residual_rms, 1e-6);
  }
}

/// Residual statistics on every point, on a strided subsample, or skipped: same quadric, honest
/// residual_points, subsampled RMS close to the exact one, NaN when skipped.
TEST(EvaluateFit, ResidualEvaluationModes) {
  EXPECT_EQ(residual_sample(10000, {ResidualEvaluation::Subsample, 2000}).stride, 5);
  EXPECT_EQ(residual_sample(10000, {ResidualEvaluation::Subsample, 2000}).count, 2000);
  EXPECT_EQ(residual_sample(10001, {ResidualEvaluation::Subsample, 2000}).count, 1667);
  EXPECT_EQ(residual_sample(150, {ResidualEvaluation::Subsample, 2000}).count, 150);
  EXPECT_EQ(residual_sample(150, {ResidualEvaluation::Exact, 1}).count, 150);
  EXPECT_EQ(residual_sample(150, {ResidualEvaluation::Skip, 2000}).count, 0);
  EXPECT_THROW(residual_sample(150, {ResidualEvaluation::Subsample, 0}), Error);
  EXPECT_EQ(residual_evaluation_from_name("subsample"), ResidualEvaluation::Subsample);
  EXPECT_THROW(residual_evaluation_from_name("some"), Error);

  std::mt19937_64 random(13);
  std::normal_distribution<double> noise(0.0, 0.02);
  Eigen::Matrix3Xd points =
      sample_surface_points(QuadricType::CircularCylinder, {0.5, 0.5, 1.0}, random_pose(random, 20.0, TranslationDraw::Gaussian), 10000, random);
  for (Eigen::Index i = 0; i < points.cols(); ++i) points.col(i) += Eigen::Vector3d(noise(random), noise(random), noise(random));
  for (const std::string name : {"statistical", "taubin", "constrained", "learned"}) {
    const QuadricFit exact = make_quadric_fitter(name)->fit(points, Eigen::Matrix3Xd(), QuadricType::CircularCylinder);
    const QuadricFit subsampled = make_quadric_fitter(name, {ResidualEvaluation::Subsample, 2000})
                                      ->fit(points, Eigen::Matrix3Xd(), QuadricType::CircularCylinder);
    const QuadricFit skipped = make_quadric_fitter(name, {ResidualEvaluation::Skip, 2000})
                                   ->fit(points, Eigen::Matrix3Xd(), QuadricType::CircularCylinder);
    ASSERT_EQ(exact.status, FitStatus::Ok) << name << ": " << exact.message;
    EXPECT_EQ(exact.residual_evaluation, ResidualEvaluation::Exact) << name;
    EXPECT_EQ(exact.residual_points, 10000) << name;
    EXPECT_EQ(subsampled.residual_evaluation, ResidualEvaluation::Subsample) << name;
    EXPECT_EQ(subsampled.residual_points, 2000) << name;
    EXPECT_EQ(skipped.residual_points, 0) << name;
    EXPECT_EQ(skipped.status, FitStatus::Ok) << name;
    EXPECT_TRUE(std::isnan(skipped.residual_rms) && std::isnan(skipped.algebraic_distance)) << name;
    EXPECT_TRUE(exact.quadric.matrix().isApprox(skipped.quadric.matrix(), 1e-12)) << name;
    EXPECT_NEAR(subsampled.residual_rms, exact.residual_rms, 0.1 * exact.residual_rms) << name;
    EXPECT_NEAR(subsampled.algebraic_distance, exact.algebraic_distance, 0.1 * exact.algebraic_distance) << name;
    EXPECT_GT(exact.evaluation_ms, 0.0) << name;
    EXPECT_LE(exact.evaluation_ms, exact.time_ms) << name;
  }
}

/// point_statistics matches geometry's statistical_pose (the fitters' one-pass replacement of it).
TEST(PointStatistics, MatchesStatisticalPose) {
  std::mt19937_64 random(14);
  for (const QuadricType type : {QuadricType::Plane, QuadricType::Ellipsoid, QuadricType::CircularCylinder}) {
    const Eigen::Matrix3Xd points = sample_surface_points(type, random_scale(type, random), random_pose(random, 20.0, TranslationDraw::Gaussian), 1003, random);
    const StatisticalPose expected = statistical_pose(points);
    Eigen::Matrix3d covariance;
    const StatisticalPose found = point_statistics(points, kStatisticalScaleFactor, &covariance);
    EXPECT_TRUE(found.center.isApprox(expected.center, 1e-12));
    EXPECT_TRUE(found.rotation.isApprox(expected.rotation, 1e-9)) << quadric_type_name(type);
    // Variances agree to rounding (a noise-free plane's zero variance is rounding noise in both).
    const Eigen::Vector3d found_variance = found.scale.cwiseAbs2(), expected_variance = expected.scale.cwiseAbs2();
    EXPECT_NEAR((found_variance - expected_variance).norm(), 0.0, 1e-12 * expected_variance.norm());
    EXPECT_NEAR(covariance.trace(), (points.colwise() - expected.center).colwise().squaredNorm().mean(), 1e-9);
  }
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
  const Eigen::Isometry3d pose = random_pose(random, 20.0, TranslationDraw::Gaussian);
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
