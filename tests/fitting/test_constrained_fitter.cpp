// The constrained fitter against synthetic ground truth: exact full surfaces (1e-6 relative
// target), half-visible noisy cylinders (radius error <= 5%, statistical acceptance), the automatic
// type choice, and honest statuses. Surfaces are sampled here in their canonical frame (independent
// of geometry/mesh.cpp) under random poses with fixed seeds.
#include "fitting/constrained_fitter.h"
#include "fitting/quadric_fitter.h"
#include "geometry/error.h"
#include "fitting/canonical_surfaces.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <map>
#include <random>
#include <vector>

namespace quadrix {
namespace {

using namespace ::quadrix::testing;


/// Errors of a fitted shape against the truth (scale: max relative error of the defined scales;
/// centre: central types distance, axis types distance of the centre from the true axis, plane offset
/// along the normal; axis: 1 - |cos| of the defining axis).
struct ShapeErrors {
  double scale = 0.0, centre = 0.0, axis = 0.0;
};

ShapeErrors shape_errors(QuadricType type, const Eigen::Vector3d& scale, const Eigen::Isometry3d& pose,
                         const QuadricDecomposition& shape) {
  ShapeErrors errors;
  const bool central = type == QuadricType::Sphere || type == QuadricType::Ellipsoid ||
                       type == QuadricType::CircularCone || type == QuadricType::EllipticCone;
  int defined = 2;
  if (type == QuadricType::Sphere || type == QuadricType::Ellipsoid) defined = 3;
  if (type == QuadricType::Plane || type == QuadricType::Line) defined = 0;
  if (defined > 0) {
    const Eigen::Vector3d truth = sorted(scale, defined);
    const Eigen::Vector3d found = sorted(shape.scale, defined);
    errors.scale = (truth - found).head(defined).cwiseQuotient(truth.head(defined)).cwiseAbs().maxCoeff();
  }
  const Eigen::Vector3d offset = shape.center - pose.translation();
  if (central) {
    errors.centre = offset.norm();
  } else if (type == QuadricType::Plane) {
    errors.centre = std::abs(offset.dot(pose.linear().col(0)));
  } else {
    const Eigen::Vector3d axis = pose.linear().col(2);
    errors.centre = (offset - offset.dot(axis) * axis).norm();
  }
  if (type == QuadricType::Plane) errors.axis = 1.0 - std::abs(shape.rotation.col(0).dot(pose.linear().col(0)));
  else if (type != QuadricType::Sphere && type != QuadricType::Ellipsoid)
    errors.axis = 1.0 - std::abs(shape.rotation.col(2).dot(pose.linear().col(2)));
  return errors;
}

/// Target: on noise-free full surfaces the constrained fitter recovers type and parameters
/// to 1e-6 relative.
class ConstrainedExactSurfaces : public ::testing::TestWithParam<QuadricType> {};

/// Fits `rounds` noise-free random surfaces of `type` with `count` points each and counts those whose
/// type and parameters are recovered to 1e-6 relative (each miss is reported with its errors).
int exact_recoveries(const QuadricFitter& fitter, QuadricType type, int count, int rounds, std::mt19937_64& random) {
  int passed = 0;
  for (int round = 0; round < rounds; ++round) {
    const Eigen::Vector3d scale = random_scale(type, random);
    const Eigen::Isometry3d pose = random_pose(random, 20.0, TranslationDraw::Gaussian);
    const Eigen::Matrix3Xd points = sample_surface_points(type, scale, pose, count, random);
    const QuadricFit fit = fitter.fit(points, Eigen::Matrix3Xd(), type);
    const QuadricDecomposition shape = fit.quadric.decompose();
    const ShapeErrors errors = shape_errors(type, scale, pose, shape);
    const bool ok = fit.status == FitStatus::Ok && fit.type == type && shape.type == type && errors.scale < 1e-6 &&
                    errors.centre < 1e-6 * (1.0 + pose.translation().norm()) && errors.axis < 1e-9 &&
                    fit.residual_rms < 1e-6;
    passed += ok ? 1 : 0;
    if (!ok)
      ADD_FAILURE() << quadric_type_name(type) << " (" << count << " points) round " << round << ": status "
                    << fit_status_name(fit.status) << " (" << fit.message << ") type " << quadric_type_name(shape.type)
                    << " scale error " << errors.scale << " centre error " << errors.centre << " axis error "
                    << errors.axis << " rms " << fit.residual_rms;
  }
  return passed;
}

TEST_P(ConstrainedExactSurfaces, RecoversTypeScaleAxisAndCentre) {
  std::mt19937_64 random(2000 + static_cast<int>(GetParam()));
  EXPECT_EQ(exact_recoveries(*make_quadric_fitter("constrained"), GetParam(), 500, 20, random), 20);
}

/// The same target at 10k points: the initial values are screened on a 1,500-point subsample and the
/// best is polished on every point (residuals read on 2,000 of them).
TEST_P(ConstrainedExactSurfaces, RecoversTypeScaleAxisAndCentreAtTenThousandPoints) {
  std::mt19937_64 random(2500 + static_cast<int>(GetParam()));
  const auto fitter = make_quadric_fitter("constrained", FitEvaluationOptions{ResidualEvaluation::Subsample, 2000});
  EXPECT_EQ(exact_recoveries(*fitter, GetParam(), 10000, 1, random), 1);
}

INSTANTIATE_TEST_SUITE_P(EverySupportedSurface, ConstrainedExactSurfaces,
                         ::testing::Values(QuadricType::Plane, QuadricType::Line, QuadricType::Sphere,
                                           QuadricType::Ellipsoid, QuadricType::CircularCylinder,
                                           QuadricType::EllipticCylinder, QuadricType::CircularCone,
                                           QuadricType::EllipticCone),
                         [](const auto& info) { return quadric_type_name(info.param); });

/// Target: half-visible cylinders with 2 cm Gaussian noise. Every registered fitter's radius
/// error is reported; the constrained fitter must stay within 5% in at least 45 of 50 trials.
TEST(ConstrainedFitter, HalfVisibleNoisyCylinderRadiusWithinFivePercent) {
  std::mt19937_64 random(31);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::uniform_real_distribution<double> radius_distribution(0.3, 1.5);
  std::map<std::string, std::vector<double>> errors;
  const int trials = 50;
  for (int trial = 0; trial < trials; ++trial) {
    const double radius = radius_distribution(random);
    const Eigen::Isometry3d pose = random_pose(random, 20.0, TranslationDraw::Gaussian);
    Eigen::Matrix3Xd points =
        sample_surface_points(QuadricType::CircularCylinder, {radius, radius, 1.0}, pose, 500, random, kPi);
    for (Eigen::Index i = 0; i < points.cols(); ++i)
      points.col(i) += Eigen::Vector3d(noise(random), noise(random), noise(random));
    for (const std::string& name : quadric_fitter_names()) {
      const QuadricFit fit = make_quadric_fitter(name)->fit(points, Eigen::Matrix3Xd(), QuadricType::CircularCylinder);
      const bool cylinder = fit.type == QuadricType::CircularCylinder || fit.type == QuadricType::EllipticCylinder;
      const double error = cylinder ? std::abs(fit.shape.scale.head<2>().mean() - radius) / radius
                                    : std::numeric_limits<double>::infinity();
      errors[name].push_back(error);
    }
  }
  for (auto& [name, values] : errors) {
    std::sort(values.begin(), values.end());
    const auto within = std::count_if(values.begin(), values.end(), [](double e) { return e <= 0.05; });
    std::cout << "half-visible cylinder, 2 cm noise: " << name << " median radius error "
              << 100.0 * values[values.size() / 2] << "%, 90th percentile " << 100.0 * values[values.size() * 9 / 10]
              << "%, within 5%: " << within << "/" << values.size() << std::endl;
    ::testing::Test::RecordProperty(name + "_median_radius_error_percent",
                                    std::to_string(100.0 * values[values.size() / 2]));
  }
  const auto& constrained = errors.at("constrained");
  const auto within = std::count_if(constrained.begin(), constrained.end(), [](double e) { return e <= 0.05; });
  EXPECT_GE(within, 45);
  EXPECT_LE(constrained[constrained.size() / 2], 0.02);
}

/// Without a hint, the lowest BIC picks the generating type of slightly noisy surfaces.
TEST(ConstrainedFitter, AutomaticTypeChoiceFindsTheGeneratingType) {
  std::mt19937_64 random(41);
  std::normal_distribution<double> noise(0.0, 0.002);
  const auto fitter = make_quadric_fitter("constrained");
  const std::vector<QuadricType> types = {QuadricType::Plane, QuadricType::Sphere, QuadricType::CircularCylinder,
                                          QuadricType::CircularCone, QuadricType::Ellipsoid};
  for (const QuadricType type : types) {
    int correct = 0;
    const int rounds = 8;
    for (int round = 0; round < rounds; ++round) {
      Eigen::Vector3d scale = random_scale(type, random);
      if (type == QuadricType::Plane) scale.setOnes();
      Eigen::Matrix3Xd points = sample_surface_points(type, scale, random_pose(random, 20.0, TranslationDraw::Gaussian), 400, random);
      for (Eigen::Index i = 0; i < points.cols(); ++i)
        points.col(i) += Eigen::Vector3d(noise(random), noise(random), noise(random));
      const QuadricFit fit = fitter->fit(points, Eigen::Matrix3Xd(), std::nullopt);
      correct += (fit.status == FitStatus::Ok && fit.type == type) ? 1 : 0;
    }
    EXPECT_GE(correct, rounds - 1) << quadric_type_name(type);
  }
}

TEST(ConstrainedFitter, ReportsDegenerateTooFewUnsupportedAndBadInput) {
  const auto fitter = make_quadric_fitter("constrained");
  EXPECT_EQ(fitter->name(), "constrained");
  Eigen::Matrix3Xd collinear(3, 20);
  for (int i = 0; i < 20; ++i) collinear.col(i) = Eigen::Vector3d(1.0, 2.0, 3.0) * i;
  const QuadricFit line_as_cylinder = fitter->fit(collinear, Eigen::Matrix3Xd(), QuadricType::CircularCylinder);
  EXPECT_EQ(line_as_cylinder.status, FitStatus::Degenerate);
  EXPECT_THAT(line_as_cylinder.message, ::testing::HasSubstr("collinear"));

  // A flat patch has no finite best cylinder: the radius diverges and is reported, not returned.
  std::mt19937_64 random(5);
  const Eigen::Matrix3Xd flat = sample_surface_points(QuadricType::Plane, Eigen::Vector3d::Ones(), random_pose(random, 20.0, TranslationDraw::Gaussian), 200, random);
  const QuadricFit flat_cylinder = fitter->fit(flat, Eigen::Matrix3Xd(), QuadricType::CircularCylinder);
  EXPECT_EQ(flat_cylinder.status, FitStatus::Degenerate) << flat_cylinder.message;
  EXPECT_EQ(fitter->fit(flat, Eigen::Matrix3Xd(), QuadricType::Sphere).status, FitStatus::Degenerate);

  EXPECT_EQ(fitter->fit(collinear.leftCols(5), Eigen::Matrix3Xd(), QuadricType::Ellipsoid).status, FitStatus::TooFewPoints);
  const QuadricFit unsupported = fitter->fit(flat, Eigen::Matrix3Xd(), QuadricType::HyperboloidOneSheet);
  EXPECT_EQ(unsupported.status, FitStatus::Failed);
  EXPECT_THAT(unsupported.message, ::testing::HasSubstr("hyperboloid"));

  Eigen::Matrix3Xd with_nan = flat;
  with_nan(1, 7) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(fitter->fit(with_nan, Eigen::Matrix3Xd(), QuadricType::Sphere), Error);
}

/// The optional Cauchy loss keeps a sphere's radius under 20% gross outliers; plain least squares
/// is pulled away (documents why the option exists).
TEST(ConstrainedFitter, RobustLossResistsOutliers) {
  std::mt19937_64 random(77);
  std::uniform_real_distribution<double> box(-3.0, 3.0);
  ConstrainedFitterOptions robust_options;
  robust_options.robust_loss_scale = 0.02;
  const auto robust = make_constrained_fitter(robust_options);
  const auto plain = make_constrained_fitter();
  int robust_better = 0;
  const int rounds = 10;
  for (int round = 0; round < rounds; ++round) {
    Eigen::Isometry3d pose = random_pose(random, 20.0, TranslationDraw::Gaussian);
    Eigen::Matrix3Xd points = sample_surface_points(QuadricType::Sphere, Eigen::Vector3d::Constant(1.5), pose, 400, random);
    for (Eigen::Index i = 0; i < 80; ++i) points.col(i) = pose * Eigen::Vector3d(box(random), box(random), box(random));
    const QuadricFit robust_fit = robust->fit(points, Eigen::Matrix3Xd(), QuadricType::Sphere);
    const QuadricFit plain_fit = plain->fit(points, Eigen::Matrix3Xd(), QuadricType::Sphere);
    ASSERT_NE(robust_fit.status, FitStatus::Failed);
    const double robust_error = std::abs(robust_fit.shape.scale(0) - 1.5);
    const double plain_error = std::abs(plain_fit.shape.scale(0) - 1.5);
    EXPECT_LT(robust_error, 0.03) << "round " << round;
    robust_better += robust_error < plain_error ? 1 : 0;
  }
  EXPECT_GE(robust_better, rounds - 1);
}

TEST(ConstrainedFitter, SupportedTypesAndDegreesOfFreedom) {
  const auto types = constrained_fitter_types();
  EXPECT_THAT(types, ::testing::Contains(QuadricType::EllipticCone));
  EXPECT_EQ(constrained_type_degrees_of_freedom(QuadricType::Plane), 3);
  EXPECT_EQ(constrained_type_degrees_of_freedom(QuadricType::CircularCylinder), 5);
  EXPECT_EQ(constrained_type_degrees_of_freedom(QuadricType::Ellipsoid), 9);
}

}  // namespace
}  // namespace quadrix
