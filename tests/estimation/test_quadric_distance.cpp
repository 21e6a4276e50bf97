// Quadric distance (Eq. (quadrics distance)), its Jacobian (Eq. (Jacobian of quadrics distance))
// against numeric differentiation for every type, the masks, f_pp, Augment(), the ground factor and
// the robust kernels.
#include "estimation/quadric_distance.h"
#include "estimation/synthetic_scene.h"
#include "geometry/constants.h"
#include "geometry/error.h"

#include <gtest/gtest.h>

#include <limits>
#include <random>

namespace quadrix {
namespace {

using testing::estimation_types;
using testing::make_scene;
using testing::SceneSpec;

Matrix12x6d numeric_jacobian(const QuadricFactor& factor, const Eigen::Isometry3d& pose) {
  constexpr double step = 1e-6;
  Matrix12x6d jacobian;
  for (int k = 0; k < 6; ++k) {
    Vector6d delta = Vector6d::Zero();
    delta[k] = step;
    jacobian.col(k) = (quadric_distance(factor, apply_increment(pose, delta)) -
                       quadric_distance(factor, apply_increment(pose, -delta))) / (2.0 * step);
  }
  return jacobian;
}

SceneSpec single_type(QuadricType type) {
  SceneSpec spec;
  spec.types = {type};
  spec.copies_per_type = 1;
  return spec;
}

TEST(QuadricDistance, ZeroAtTheTrueTransformForEveryType) {
  std::mt19937 rng(11);
  for (const QuadricType type : estimation_types()) {
    for (int trial = 0; trial < 20; ++trial) {
      const auto scene = make_scene(rng, single_type(type));
      const QuadricDecomposition source_shape = scene.source[0].quadric().decompose();
      const QuadricDecomposition target_shape = scene.target[0].quadric().decompose();
      ASSERT_EQ(source_shape.type, type) << quadric_type_name(type);
      ASSERT_EQ(target_shape.type, type) << quadric_type_name(type);
      const QuadricFactor factor = make_quadric_factor(scene.source[0], source_shape, scene.target[0], target_shape);
      EXPECT_EQ(factor.rotation_mask, degeneracy_indicators(type).rotation) << quadric_type_name(type);
      EXPECT_EQ(factor.translation_mask, degeneracy_indicators(type).translation) << quadric_type_name(type);
      EXPECT_LT(quadric_distance(factor, scene.truth).norm(), 1e-7) << quadric_type_name(type) << " trial " << trial;
      // Away from the truth the distance is non-zero for every type (each constrains something).
      const Eigen::Isometry3d wrong = scene.truth * testing::perturbation(rng, 1.0, 0.3);
      EXPECT_GT(quadric_distance(factor, wrong).norm(), 1e-3) << quadric_type_name(type);
    }
  }
}

TEST(QuadricDistance, AnalyticJacobianMatchesNumericDifferentiationForEveryType) {
  std::mt19937 rng(12);
  for (const QuadricType type : estimation_types()) {
    int checked = 0;
    for (int trial = 0; trial < 30; ++trial) {
      const auto scene = make_scene(rng, single_type(type));
      QuadricFactor factor = make_quadric_factor(scene.source[0], scene.target[0]);
      const Eigen::Isometry3d pose = testing::random_pose(rng, 30.0);
      Vector12d residual;
      Matrix12x6d analytic;
      quadric_distance_with_jacobian(factor, pose, &residual, &analytic);
      EXPECT_LT((residual - quadric_distance(factor, pose)).norm(), 1e-12);
      const Matrix12x6d numeric = numeric_jacobian(factor, pose);
      const double scale = std::max(1.0, numeric.cwiseAbs().maxCoeff());
      EXPECT_LT((analytic - numeric).cwiseAbs().maxCoeff(), 1e-6 * scale)
          << quadric_type_name(type) << " trial " << trial << "\nanalytic\n" << analytic << "\nnumeric\n" << numeric;
      // The same with every mask opened: all 12 rows are exercised, not only the non-degenerate ones.
      factor.rotation_mask.setOnes();
      factor.translation_mask.setOnes();
      quadric_distance_with_jacobian(factor, pose, &residual, &analytic);
      EXPECT_LT((analytic - numeric_jacobian(factor, pose)).cwiseAbs().maxCoeff(), 1e-6 * scale);
      ++checked;
    }
    EXPECT_EQ(checked, 30);
  }
}

TEST(QuadricDistance, DegenerateDirectionsDoNotCountAndAxisSignsDoNotMatter) {
  std::mt19937 rng(13);
  // Plane: sliding the source inside the plane and rotating about the normal are free; moving along
  // the normal by h gives |e_t| = h (point-to-plane).
  const auto planes = make_scene(rng, single_type(QuadricType::Plane));
  const QuadricFactor plane = make_quadric_factor(planes.source[0], planes.target[0]);
  const Eigen::Vector3d normal = plane.target_axes.col(0);
  const Eigen::Vector3d in_plane = plane.target_axes.col(1);
  Eigen::Isometry3d slid = planes.truth;
  slid.pretranslate(2.5 * in_plane);
  EXPECT_LT(quadric_distance(plane, slid).norm(), 1e-7);
  Eigen::Isometry3d spun = Eigen::Isometry3d::Identity();
  spun.linear() = Eigen::AngleAxisd(0.7, normal).toRotationMatrix();
  spun.translation() = planes.target[0].full_center - spun.linear() * planes.target[0].full_center;
  EXPECT_LT(quadric_distance(plane, spun * planes.truth).norm(), 1e-7);
  Eigen::Isometry3d lifted = planes.truth;
  lifted.pretranslate(0.3 * normal);
  EXPECT_NEAR(quadric_distance(plane, lifted).norm(), 0.3, 1e-9);

  // Line: rotation about its own axis and sliding along it are free.
  const auto lines = make_scene(rng, single_type(QuadricType::Line));
  const QuadricFactor line = make_quadric_factor(lines.source[0], lines.target[0]);
  const Eigen::Vector3d direction = line.target_axes.col(2);
  Eigen::Isometry3d about_axis = Eigen::Isometry3d::Identity();
  about_axis.linear() = Eigen::AngleAxisd(1.1, direction).toRotationMatrix();
  about_axis.translation() = lines.target[0].full_center - about_axis.linear() * lines.target[0].full_center;
  about_axis.pretranslate(4.0 * direction);
  EXPECT_LT(quadric_distance(line, about_axis * lines.truth).norm(), 1e-7);

  // Flipping eigenvector signs (the paper's +/- ambiguity) leaves e unchanged.
  const auto ellipsoids = make_scene(rng, single_type(QuadricType::Ellipsoid));
  QuadricFactor ellipsoid = make_quadric_factor(ellipsoids.source[0], ellipsoids.target[0]);
  const Eigen::Isometry3d pose = ellipsoids.truth * testing::perturbation(rng, 0.5, 0.2);
  const Vector12d before = quadric_distance(ellipsoid, pose);
  ellipsoid.source_axes.col(0) *= -1.0;
  ellipsoid.source_axes.col(1) *= -1.0;
  ellipsoid.target_axes.col(2) *= -1.0;
  ellipsoid.target_axes.col(1) *= -1.0;
  const Vector12d after = quadric_distance(ellipsoid, pose);
  EXPECT_LT((before.head<9>().cwiseAbs() - after.head<9>().cwiseAbs()).norm(), 1e-12);
  EXPECT_NEAR(before.norm(), after.norm(), 1e-12);
}

TEST(QuadricDistance, GroundFactorAlignsNormalsAndOffsets) {
  const GroundPlane source{Eigen::Vector3d(0.0, 0.0, 2.0), 3.4};  // z = -1.7, unnormalised
  const GroundPlane target{Eigen::Vector3d(0.0, 1.0, 0.0), 1.0};  // y = -1
  const QuadricFactor factor = make_ground_factor(source, target, 2.0);
  EXPECT_EQ(factor.kind, FactorKind::Ground);
  EXPECT_EQ(factor.weight, 2.0);
  // A rotation taking z to y plus a shift mapping z = -1.7 onto y = -1 zeroes the factor.
  Eigen::Isometry3d aligned = Eigen::Isometry3d::Identity();
  aligned.linear() = Eigen::AngleAxisd(-kPi / 2.0, Eigen::Vector3d::UnitX()).toRotationMatrix();
  aligned.translation() = Eigen::Vector3d(5.0, -1.0 + 1.7, 9.0);  // any in-plane shift is free
  ASSERT_LT((aligned.linear() * Eigen::Vector3d::UnitZ() - Eigen::Vector3d::UnitY()).norm(), 1e-12);
  EXPECT_LT(quadric_distance(factor, aligned).norm(), 1e-12);
  Eigen::Isometry3d raised = aligned;
  raised.translation().y() += 0.25;
  EXPECT_NEAR(quadric_distance(factor, raised).norm(), 0.25, 1e-12);
  EXPECT_THROW(make_ground_factor({Eigen::Vector3d::Zero(), 0.0}, target), Error);
  EXPECT_THROW(make_ground_factor(source, target, -1.0), Error);
}

// The lever arm turns the ground factor's tilt residual into metres: a tilt θ of level grounds
// costs L sin θ, what lifting a ground point L metres out costs; the offset residual keeps its metres.
TEST(QuadricDistance, GroundFactorWeighsTiltByItsLeverArm) {
  const GroundPlane level{Eigen::Vector3d::UnitZ(), 1.7};
  const double lever_arm = 40.0, tilt = 2.0 * kPi / 180.0;
  Eigen::Isometry3d tilted = Eigen::Isometry3d::Identity();
  tilted.linear() = Eigen::AngleAxisd(tilt, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Vector12d unscaled = quadric_distance(make_ground_factor(level, level), tilted);
  const Vector12d scaled = quadric_distance(make_ground_factor(level, level, 1.0, lever_arm), tilted);
  EXPECT_NEAR(unscaled.head<3>().norm(), std::sin(tilt), 1e-12);
  EXPECT_NEAR(scaled.head<3>().norm(), lever_arm * std::sin(tilt), 1e-9);
  EXPECT_LT((scaled.tail<3>() - unscaled.tail<3>()).norm(), 1e-12);  // the offset is not scaled
  Eigen::Isometry3d raised = Eigen::Isometry3d::Identity();
  raised.translation().z() = 0.25;
  EXPECT_NEAR(quadric_distance(make_ground_factor(level, level, 1.0, lever_arm), raised).norm(), 0.25, 1e-12);
  for (const double bad : {0.0, -3.0, std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN()})
    EXPECT_THROW(make_ground_factor(level, level, 1.0, bad), Error) << bad;
}

TEST(QuadricDistance, ManhattanFilterUsesTheGivenGroundNormal) {
  const Eigen::Vector3d tilted_ground = Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitX()) * Eigen::Vector3d::UnitZ();
  const auto plane_with_normal = [](const Eigen::Vector3d& normal) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitX(), normal).toRotationMatrix();
    return Quadric::from_canonical(QuadricType::Plane, Eigen::Vector3d::Ones(), pose).decompose();
  };
  const Eigen::AngleAxisd three_degrees(3.0 * kPi / 180.0, Eigen::Vector3d::UnitX());
  const Eigen::AngleAxisd thirty_degrees(30.0 * kPi / 180.0, Eigen::Vector3d::UnitX());
  // Parallel (ground-like), antiparallel and perpendicular (wall) to the tilted ground are kept...
  EXPECT_TRUE(is_manhattan_aligned(plane_with_normal(three_degrees * tilted_ground), tilted_ground, 5.0));
  EXPECT_TRUE(is_manhattan_aligned(plane_with_normal(-tilted_ground), tilted_ground, 5.0));
  const Eigen::Vector3d wall = tilted_ground.cross(Eigen::Vector3d::UnitX()).normalized();
  EXPECT_TRUE(is_manhattan_aligned(plane_with_normal(wall), tilted_ground, 5.0));
  // ...a 30-degree slope is not, and 3 degrees fails a 2-degree tolerance.
  EXPECT_FALSE(is_manhattan_aligned(plane_with_normal(thirty_degrees * tilted_ground), tilted_ground, 5.0));
  EXPECT_FALSE(is_manhattan_aligned(plane_with_normal(three_degrees * tilted_ground), tilted_ground, 2.0));
  // Against the z axis instead (the released code's pitfall) the truly level plane looks tilted.
  EXPECT_FALSE(is_manhattan_aligned(plane_with_normal(tilted_ground), Eigen::Vector3d::UnitZ(), 5.0));
  // A sphere has no defined axis: always kept.
  const auto sphere = Quadric::from_canonical(QuadricType::Sphere, Eigen::Vector3d::Ones(), Eigen::Isometry3d::Identity());
  EXPECT_TRUE(is_manhattan_aligned(sphere.decompose(), tilted_ground, 0.0));
  EXPECT_THROW(is_manhattan_aligned(sphere.decompose(), Eigen::Vector3d::Zero(), 5.0), Error);
}

TEST(QuadricDistance, BuildFactorsAugmentsFiltersAndAddsTheGround) {
  std::mt19937 rng(14);
  SceneSpec spec;
  spec.copies_per_type = 1;
  spec.types = {QuadricType::Point, QuadricType::Line, QuadricType::Plane, QuadricType::Sphere,
                QuadricType::CircularCylinder, QuadricType::CircularCone};
  const auto scene = make_scene(rng, spec);
  const auto source_shapes = decompose_records(scene.source);
  const auto target_shapes = decompose_records(scene.target);
  const FactorSet plain = build_quadric_factors(scene.source, source_shapes, scene.target, target_shapes,
                                                scene.correspondences, {});
  EXPECT_EQ(plain.correspondence_count, 6u);
  EXPECT_EQ(plain.filtered_count, 0u);
  EXPECT_EQ(plain.augmented_count, 2u + 4u + 2u);  // line: 2, plane: 4, cylinder: 2
  EXPECT_EQ(plain.factors.size(), 6u + 8u);
  for (const QuadricFactor& factor : plain.factors) {
    EXPECT_LT(quadric_distance(factor, scene.truth).norm(), 1e-7);  // samples lie on the centre line/plane
    if (factor.kind == FactorKind::Augmented) {
      EXPECT_EQ(factor.rotation_mask, Eigen::Vector3d::Zero());
    }
  }
  // Each augmented sample sits at the mean full scale from the full centre.
  for (const QuadricFactor& factor : plain.factors) {
    if (factor.kind != FactorKind::Augmented) continue;
    const QuadricRecord& record = scene.source[factor.source_index];
    EXPECT_NEAR((factor.source_center - record.full_center).norm(), record.full_scale.mean(), 1e-9);
  }

  FactorBuildOptions options;
  options.augment_non_central = false;
  options.source_ground = GroundPlane{Eigen::Vector3d::UnitZ(), 0.0};
  options.target_ground = GroundPlane{scene.truth.linear() * Eigen::Vector3d::UnitZ(),
                                      -(scene.truth.linear() * Eigen::Vector3d::UnitZ()).dot(scene.truth.translation())};
  const FactorSet with_ground = build_quadric_factors(scene.source, source_shapes, scene.target, target_shapes,
                                                      scene.correspondences, options);
  EXPECT_EQ(with_ground.factors.size(), 7u);
  EXPECT_EQ(with_ground.factors.back().kind, FactorKind::Ground);
  EXPECT_LT(quadric_distance(with_ground.factors.back(), scene.truth).norm(), 1e-9);

  // f_pp with a ground normal no random structure is aligned to within 0.01 degrees removes the
  // line, plane and cylinder (the structures) and keeps point, sphere and cone.
  options.source_ground_normal = testing::random_unit_vector(rng);
  options.target_ground_normal = scene.truth.linear() * *options.source_ground_normal;
  options.manhattan_tolerance_degrees = 0.01;
  options.source_ground.reset();
  const FactorSet filtered = build_quadric_factors(scene.source, source_shapes, scene.target, target_shapes,
                                                   scene.correspondences, options);
  EXPECT_EQ(filtered.filtered_count, 3u);
  EXPECT_EQ(filtered.factors.size(), 3u);

  std::vector<RecordCorrespondence> bad = {{0, 99}};
  EXPECT_THROW(build_quadric_factors(scene.source, source_shapes, scene.target, target_shapes, bad, {}), Error);
  EXPECT_THROW(build_quadric_factors(scene.source, {}, scene.target, target_shapes, scene.correspondences, {}), Error);
}

TEST(QuadricDistance, RobustKernelsAreContinuousWithMatchingDerivatives) {
  for (const RobustLoss loss : {RobustLoss::None, RobustLoss::Huber, RobustLoss::Cauchy, RobustLoss::Dcs}) {
    EXPECT_EQ(robust_loss_from_name(robust_loss_name(loss)), loss);
    for (const double s : {0.01, 0.2, 0.49, 0.51, 1.3, 7.0, 120.0}) {
      const double h = 1e-6 * std::max(1.0, s);
      const LossValue value = evaluate_robust_loss(loss, 0.5, s);
      const LossValue plus = evaluate_robust_loss(loss, 0.5, s + h);
      const LossValue minus = evaluate_robust_loss(loss, 0.5, s - h);
      EXPECT_NEAR(value.derivative, (plus.rho - minus.rho) / (2.0 * h), 1e-6) << robust_loss_name(loss) << " s=" << s;
      EXPECT_NEAR(value.second, (plus.derivative - minus.derivative) / (2.0 * h), 1e-5) << robust_loss_name(loss) << " s=" << s;
      EXPECT_LE(value.rho, s + 1e-15);  // every kernel is below the quadratic
    }
  }
  // DCS: rho = s inside Phi, bounded by 3 Phi, weight = square of the DCS scale 2 Phi / (Phi + s).
  EXPECT_DOUBLE_EQ(evaluate_robust_loss(RobustLoss::Dcs, 0.5, 0.4).rho, 0.4);
  EXPECT_NEAR(evaluate_robust_loss(RobustLoss::Dcs, 0.5, 0.5 + 1e-12).rho, 0.5, 1e-11);
  EXPECT_LT(evaluate_robust_loss(RobustLoss::Dcs, 0.5, 1e9).rho, 1.5);
  EXPECT_NEAR(evaluate_robust_loss(RobustLoss::Dcs, 0.5, 4.5).derivative, std::pow(2.0 * 0.5 / 5.0, 2), 1e-15);
  EXPECT_THROW(evaluate_robust_loss(RobustLoss::Huber, 0.0, 1.0), Error);
  EXPECT_THROW(robust_loss_from_name("tukey"), Error);
}

TEST(QuadricDistance, ConstraintAnalysisFindsTheFreeDirectionsOfParallelPlanes) {
  std::mt19937 rng(15);
  const Eigen::Vector3d normal = testing::random_unit_vector(rng);
  std::vector<QuadricFactor> factors;
  for (int k = 0; k < 6; ++k) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitX(), normal).toRotationMatrix();
    pose.translation() = 3.0 * k * normal + testing::random_pose(rng, 10.0).translation().cross(normal);
    const Quadric plane = Quadric::from_canonical(QuadricType::Plane, Eigen::Vector3d::Ones(), pose);
    StatisticalPose statistics;
    statistics.center = pose.translation();
    statistics.scale = Eigen::Vector3d(4.0, 3.0, 0.1);
    statistics.rotation = pose.linear();
    const QuadricRecord record = make_quadric_record(0, plane, statistics);
    factors.push_back(make_quadric_factor(record, record));
  }
  const ConstraintAnalysis analysis = analyse_constraints(factors, Eigen::Isometry3d::Identity());
  EXPECT_EQ(analysis.rank, 3);
  ASSERT_EQ(analysis.weak_directions.size(), 3u);
  // The free directions are: rotation about the normal, translations orthogonal to it.
  for (const Vector6d& direction : analysis.weak_directions) {
    const Eigen::Vector3d phi = direction.head<3>();
    const Eigen::Vector3d rho = direction.tail<3>();
    EXPECT_LT((phi - phi.dot(normal) * normal).norm(), 1e-6);
    EXPECT_LT(std::abs(rho.dot(normal)), 1e-6);
  }
  // A sphere and two lines in general position make it fully constrained.
  auto scene = make_scene(rng, SceneSpec{});
  std::vector<QuadricFactor> mixed;
  for (const auto& pair : scene.correspondences)
    mixed.push_back(make_quadric_factor(scene.source[pair.source_index], scene.target[pair.target_index]));
  EXPECT_EQ(analyse_constraints(mixed, scene.truth).rank, 6);
}

}  // namespace
}  // namespace quadrix
