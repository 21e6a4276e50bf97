// Struct. 1 records, statistical pose and the full-attribute rule (paper §"Quadric Modeling").
#include "geometry/error.h"
#include "geometry/quadric_record.h"
#include "test_geometry.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace quadrix {
namespace {

using testing::random_pose;
using testing::random_rotation;

// Gaussian points with standard deviations `sigma` along the columns of `pose`.
Eigen::Matrix3Xd gaussian_points(std::mt19937_64& random, const Eigen::Isometry3d& pose, const Eigen::Vector3d& sigma,
                                 int count) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::Matrix3Xd points(3, count);
  for (int i = 0; i < count; ++i)
    points.col(i) = pose * Eigen::Vector3d(sigma[0] * normal(random), sigma[1] * normal(random), sigma[2] * normal(random));
  return points;
}

bool is_proper_rotation(const Eigen::Matrix3d& r) {
  return (r.transpose() * r - Eigen::Matrix3d::Identity()).norm() < 1e-9 && std::abs(r.determinant() - 1.0) < 1e-9;
}

TEST(QuadricRecordTest, ArrayRoundTripKeepsAllTwentyOneNumbers) {
  std::mt19937_64 random(1);
  std::uniform_real_distribution<double> uniform(-10.0, 10.0);
  for (int trial = 0; trial < 100; ++trial) {
    QuadricRecord record;
    record.label = std::uint32_t(trial * 7919);
    for (int i = 0; i < 10; ++i) record.q[i] = uniform(random);
    record.full_scale = Eigen::Vector3d(std::abs(uniform(random)), std::abs(uniform(random)), std::abs(uniform(random)));
    record.full_rotation = Eigen::Quaterniond(random_rotation(random));
    record.full_center = Eigen::Vector3d(uniform(random), uniform(random), uniform(random));
    const std::array<double, 21> values = record.to_array();
    EXPECT_EQ(values[0], double(record.label));
    EXPECT_EQ(values[14], record.full_rotation.w());
    const QuadricRecord back = QuadricRecord::from_array(values);
    EXPECT_EQ(back.label, record.label);
    EXPECT_EQ(back.q, record.q);
    EXPECT_EQ(back.full_scale, record.full_scale);
    EXPECT_LT((back.full_rotation.coeffs() - record.full_rotation.coeffs()).norm(), 1e-15);
    EXPECT_EQ(back.full_center, record.full_center);
    EXPECT_EQ(back.to_array(), values);
  }
}

TEST(QuadricRecordTest, FromArrayRejectsBadNumbersNamingTheField) {
  std::array<double, 21> good{};
  good[14] = 1.0;
  EXPECT_NO_THROW(QuadricRecord::from_array(good));
  auto expect_error_mentioning = [](std::array<double, 21> values, const std::string& field) {
    try {
      QuadricRecord::from_array(values);
      FAIL() << "expected quadrix::Error for " << field;
    } catch (const Error& error) {
      EXPECT_NE(std::string(error.what()).find(field), std::string::npos) << error.what();
    }
  };
  std::array<double, 21> values = good;
  values[5] = std::numeric_limits<double>::quiet_NaN();
  expect_error_mentioning(values, "q.E");
  values = good;
  values[20] = std::numeric_limits<double>::infinity();
  expect_error_mentioning(values, "full_center.z");
  values = good;
  values[0] = -1.0;
  expect_error_mentioning(values, "label");
  values[0] = 2.5;
  expect_error_mentioning(values, "label");
  values = good;
  values[14] = 0.0;
  expect_error_mentioning(values, "full_rotation");
}

TEST(StatisticalPoseTest, RecoversMeanPrincipalAxesAndScale) {
  std::mt19937_64 random(2);
  int within = 0;
  const int rounds = 50;
  for (int trial = 0; trial < rounds; ++trial) {
    const Eigen::Isometry3d pose = random_pose(random, 20.0);
    const Eigen::Vector3d sigma(3.0, 1.5, 0.4);
    const Eigen::Matrix3Xd points = gaussian_points(random, pose, sigma, 20000);
    const StatisticalPose statistics = statistical_pose(points);
    EXPECT_TRUE(is_proper_rotation(statistics.rotation));
    EXPECT_GE(statistics.scale[0], statistics.scale[1]);
    EXPECT_GE(statistics.scale[1], statistics.scale[2]);
    EXPECT_LT((statistics.center - points.rowwise().mean()).norm(), 1e-9);
    bool good = (statistics.center - pose.translation()).norm() < 0.1;
    for (int k = 0; k < 3; ++k) {
      good = good && std::abs(statistics.rotation.col(k).dot(pose.linear().col(k))) > 0.99;
      good = good && std::abs(statistics.scale[k] / (kStatisticalScaleFactor * sigma[k]) - 1.0) < 0.03;
    }
    within += good;
  }
  EXPECT_GE(within, rounds - 2);  // statistical acceptance: 48 of 50 rounds
  const StatisticalPose empty = statistical_pose(Eigen::Matrix3Xd(3, 0));
  EXPECT_EQ(empty.scale, Eigen::Vector3d::Zero());
  EXPECT_EQ(empty.rotation, Eigen::Matrix3d::Identity());
  const StatisticalPose single = statistical_pose(Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(single.center, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(single.scale, Eigen::Vector3d::Zero());
  EXPECT_TRUE(is_proper_rotation(single.rotation));
}

// Plane: R_f's first column is the plane normal, the others come from R_s (largest in-plane spread
// first), det +1; scale and centre are statistical (I_s = 0, I_t not all ones).
TEST(FullAttributeRuleTest, PlaneKeepsNormalAndCompletesFromStatistics) {
  std::mt19937_64 random(3);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Isometry3d pose = random_pose(random, 20.0);
    // Points on a plane patch: spreads 4 and 1.5 along the plane's b and c, thin along the normal a.
    Eigen::Isometry3d points_pose = pose;
    points_pose.linear() = pose.linear() * Eigen::AngleAxisd(0.0, Eigen::Vector3d::UnitX()).toRotationMatrix();
    const Eigen::Matrix3Xd points = gaussian_points(random, points_pose, Eigen::Vector3d(0.01, 4.0, 1.5), 2000);
    const StatisticalPose statistics = statistical_pose(points);
    const Quadric plane = Quadric::from_canonical(QuadricType::Plane, Eigen::Vector3d::Zero(), pose);
    const QuadricRecord record = make_quadric_record(7, plane, statistics);
    const Eigen::Matrix3d r = record.full_rotation.toRotationMatrix();
    EXPECT_TRUE(is_proper_rotation(r));
    EXPECT_GE(record.full_rotation.w(), 0.0);
    EXPECT_NEAR(std::abs(r.col(0).dot(pose.linear().col(0))), 1.0, 1e-9);
    EXPECT_NEAR(std::abs(r.col(1).dot(statistics.rotation.col(0))), 1.0, 1e-3);  // largest spread in the plane
    EXPECT_EQ(record.full_scale, statistics.scale);
    EXPECT_EQ(record.full_center, statistics.center);
    EXPECT_EQ(record.label, 7u);
    EXPECT_LT((record.q - plane.normalized().parameters()).norm(), 1e-12);
  }
}

// Line: c is the line direction; a, b come from R_s although R_s's first column is along the line.
TEST(FullAttributeRuleTest, LineKeepsDirectionWhateverTheOrderOfStatisticalAxes) {
  std::mt19937_64 random(4);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Isometry3d pose = random_pose(random, 20.0);
    const Eigen::Matrix3Xd points = gaussian_points(random, pose, Eigen::Vector3d(0.05, 0.02, 5.0), 1000);
    StatisticalPose statistics = statistical_pose(points);
    // Shuffle and flip R_s's columns: the rule must not depend on their order or signs.
    std::array<int, 3> permutation{{0, 1, 2}};
    std::shuffle(permutation.begin(), permutation.end(), random);
    Eigen::Matrix3d shuffled;
    for (int k = 0; k < 3; ++k) shuffled.col(k) = (trial % 2 ? -1.0 : 1.0) * statistics.rotation.col(permutation[k]);
    statistics.rotation = shuffled;
    const Quadric line = Quadric::from_canonical(QuadricType::Line, Eigen::Vector3d::Zero(), pose);
    const QuadricRecord record = make_quadric_record(1, line, statistics);
    const Eigen::Matrix3d r = record.full_rotation.toRotationMatrix();
    EXPECT_TRUE(is_proper_rotation(r));
    EXPECT_NEAR(std::abs(r.col(2).dot(pose.linear().col(2))), 1.0, 1e-9);
    // a is one of the R_s directions across the line (the first such in R_s's order).
    double best = 0.0;
    for (int k = 0; k < 3; ++k) best = std::max(best, std::abs(r.col(0).dot(statistics.rotation.col(k))));
    EXPECT_NEAR(best, 1.0, 1e-3);
    EXPECT_EQ(record.full_center, statistics.center);
  }
}

TEST(FullAttributeRuleTest, DefinedAttributesComeFromTheQuadric) {
  std::mt19937_64 random(5);
  for (int trial = 0; trial < 100; ++trial) {
    const Eigen::Isometry3d pose = random_pose(random, 20.0);
    const Eigen::Matrix3Xd points = gaussian_points(random, random_pose(random, 20.0), Eigen::Vector3d(2.0, 1.0, 0.5), 500);
    const StatisticalPose statistics = statistical_pose(points);
    // Ellipsoid: everything defined.
    const Quadric ellipsoid = Quadric::from_canonical(QuadricType::Ellipsoid, Eigen::Vector3d(0.5, 1.0, 2.0), pose);
    const QuadricDecomposition shape = ellipsoid.decompose();
    const QuadricRecord full = make_quadric_record(2, ellipsoid, statistics);
    EXPECT_LT((full.full_scale - shape.scale).norm(), 1e-9 * shape.scale.norm());  // decomposed after normalisation
    EXPECT_LT((full.full_rotation.toRotationMatrix() - shape.rotation).norm(), 1e-9);
    EXPECT_LT((full.full_center - pose.translation()).norm(), 1e-8);
    // Circular cylinder: radius from the quadric, length from statistics, axis kept, centre statistical.
    const Quadric cylinder = Quadric::from_canonical(QuadricType::CircularCylinder, Eigen::Vector3d(0.7, 0.7, 0.0), pose);
    const QuadricRecord pole = make_quadric_record(3, cylinder, statistics);
    EXPECT_NEAR(pole.full_scale[0], 0.7, 1e-9);
    EXPECT_NEAR(pole.full_scale[1], 0.7, 1e-9);
    EXPECT_EQ(pole.full_scale[2], statistics.scale[2]);
    EXPECT_NEAR(std::abs(pole.full_rotation.toRotationMatrix().col(2).dot(pose.linear().col(2))), 1.0, 1e-9);
    EXPECT_TRUE(is_proper_rotation(pole.full_rotation.toRotationMatrix()));
    EXPECT_EQ(pole.full_center, statistics.center);
    // Point (augmented points): centre from the quadric, rotation and scale statistical.
    const Quadric point = Quadric::from_canonical(QuadricType::Point, Eigen::Vector3d::Ones(), pose);
    const QuadricRecord augmented = make_quadric_record(4, point, statistics);
    EXPECT_LT((augmented.full_center - pose.translation()).norm(), 1e-8);
    EXPECT_LT((augmented.full_rotation.toRotationMatrix() - statistics.rotation).norm(), 1e-9);
    EXPECT_EQ(augmented.full_scale, statistics.scale);
  }
}

TEST(FullAttributeRuleTest, InvalidQuadricFallsBackToStatistics) {
  std::mt19937_64 random(6);
  const StatisticalPose statistics =
      statistical_pose(gaussian_points(random, random_pose(random, 20.0), Eigen::Vector3d(1.0, 0.5, 0.2), 300));
  Vector10d parameters = Vector10d::Zero();
  parameters[0] = std::numeric_limits<double>::quiet_NaN();
  const QuadricRecord record = make_quadric_record(9, Quadric::from_parameters(parameters), statistics);
  EXPECT_EQ(record.full_scale, statistics.scale);
  EXPECT_EQ(record.full_center, statistics.center);
  EXPECT_LT((record.full_rotation.toRotationMatrix() - statistics.rotation).norm(), 1e-9);
}

}  // namespace
}  // namespace quadrix
