// The airborne preset's pieces below the command line: the ground taken from a LAS classification
// (ExtractionOptions::ground_class) or, without one, from geometry; and a model scaled from metres
// into a file's length unit (scaled).
#include "fitting/extraction.h"
#include "fitting/scene_model.h"

#include "geometry/error.h"
#include "geometry/quadric.h"
#include "geometry/quadric_record.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace quadrix {
namespace {

// A nadir scan in metres of flat ground at height 0 (class 2) with a 20 m x 20 m flat roof 6 m up
// (class 6) and a 10 m x 10 m raised lawn 0.5 m up classified as ground too (class 2), 1 point/m^2,
// heights with 0.03 m noise.
PointCloud roof_on_ground(unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<float> coordinate(-60.0f, 60.0f);
  std::normal_distribution<float> noise(0.0f, 0.03f);
  const int count = 120 * 120;
  PointCloud cloud;
  cloud.positions.resize(3, count);
  cloud.labels.resize(count);
  for (int i = 0; i < count; ++i) {
    const float x = coordinate(random), y = coordinate(random);
    float z = 0.0f;
    std::uint32_t label = 2;
    if (std::abs(x - 20.0f) < 10.0f && std::abs(y) < 10.0f) {
      z = 6.0f;
      label = 6;
    } else if (std::abs(x + 30.0f) < 5.0f && std::abs(y - 30.0f) < 5.0f) {
      z = 0.5f;
    }
    cloud.positions.col(i) = Eigen::Vector3f(x, y, z + noise(random));
    cloud.labels[static_cast<std::size_t>(i)] = label;
  }
  return cloud;
}

// With the classification, the ground element is exactly the class-2 points (the raised lawn
// included, which no plane through the ground holds) and the roof is a plane among the rest.
TEST(AirborneExtraction, GroundIsTheClassifiedGroundWhereTheFileHasIt) {
  const PointCloud cloud = roof_on_ground(11);
  const ExtractionOptions options = extraction_preset("airborne");
  ASSERT_EQ(options.ground_class, 2);
  const ExtractionResult result = extract_elements(cloud, options);
  ASSERT_EQ(result.status, ExtractionStatus::Ok) << result.message;
  EXPECT_EQ(result.ground_source, "classification");
  ASSERT_FALSE(result.elements.empty());
  const Element& ground = result.elements.front();
  ASSERT_EQ(ground.element_class, ElementClass::Ground);
  std::size_t classified = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) classified += cloud.labels[i] == 2 ? 1 : 0;
  EXPECT_EQ(ground.point_indices.size(), classified - result.isolated_points);
  for (const std::uint32_t index : ground.point_indices) EXPECT_EQ(cloud.labels[index], 2u);
  EXPECT_GT(result.ground_normal.z(), std::cos(1.0 * M_PI / 180.0));
  int roofs = 0;
  for (std::size_t e = 1; e < result.elements.size(); ++e) {
    const Element& element = result.elements[e];
    EXPECT_EQ(element.element_class, ElementClass::Plane);
    std::size_t on_roof = 0;
    for (const std::uint32_t index : element.point_indices) on_roof += cloud.labels[index] == 6 ? 1 : 0;
    roofs += on_roof * 10 >= element.point_indices.size() * 9 ? 1 : 0;
  }
  EXPECT_EQ(roofs, 1) << "the roof is one plane of its own points";
}

// Without labels (or with ground_class -1) the ground is the lowest large horizontal plane: at
// height 0, without the roof's points.
TEST(AirborneExtraction, GroundFallsBackToGeometryWithoutAClassification) {
  PointCloud cloud = roof_on_ground(12);
  cloud.labels.clear();
  const ExtractionResult result = extract_elements(cloud, extraction_preset("airborne"));
  ASSERT_EQ(result.status, ExtractionStatus::Ok) << result.message;
  EXPECT_EQ(result.ground_source, "geometry");
  ASSERT_EQ(result.elements.front().element_class, ElementClass::Ground);
  for (const std::uint32_t index : result.elements.front().point_indices)
    EXPECT_LT(cloud.positions(2, index), 1.0f) << "ground point at " << cloud.positions.col(index).transpose();
  EXPECT_GT(result.ground_normal.z(), std::cos(1.0 * M_PI / 180.0));
  EXPECT_NEAR(result.ground_offset, 0.0, 0.02);
}

// scaled: a sphere, a plane and the ground put into feet keep their shapes, with every length
// multiplied; and scaling commutes with translating by the scaled offset.
TEST(ScaledModel, LengthsAreMultipliedAndShapesKept) {
  const double to_feet = 1.0 / 0.3048;
  SceneModel model;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(1.0, 2.0, 3.0);
  const Quadric sphere = Quadric::from_canonical(QuadricType::Sphere, Eigen::Vector3d::Constant(2.0), pose);
  Eigen::Matrix3Xd sphere_points(3, 4);
  sphere_points << 3, -1, 1, 1, 2, 2, 4, 0, 3, 3, 3, 3;
  model.records.push_back(make_quadric_record(static_cast<std::uint32_t>(ElementClass::Sphere), sphere, statistical_pose(sphere_points)));
  model.types.push_back(QuadricType::Sphere);
  model.element_point_counts.push_back(4);
  model.augmented_begin = 1;
  model.has_ground = true;
  model.ground_normal = Eigen::Vector3d(0.0, 0.6, 0.8);
  model.ground_offset = -5.0;
  const SceneModel feet = scaled(model, to_feet);
  validate_scene_model(feet);
  const QuadricDecomposition shape = feet.records[0].quadric().decompose();
  ASSERT_EQ(shape.type, QuadricType::Sphere);
  EXPECT_NEAR(shape.scale.x(), 2.0 * to_feet, 1e-9);
  EXPECT_LT((shape.center - Eigen::Vector3d(1.0, 2.0, 3.0) * to_feet).norm(), 1e-9);
  EXPECT_LT((feet.records[0].full_center - model.records[0].full_center * to_feet).norm(), 1e-12);
  EXPECT_LT((feet.records[0].full_scale - model.records[0].full_scale * to_feet).norm(), 1e-12);
  EXPECT_NEAR(feet.ground_offset, -5.0 * to_feet, 1e-12);
  // A point on the ground plane in metres lies on it in feet.
  const Eigen::Vector3d on_ground = Eigen::Vector3d(0.0, 0.6, 0.8) * 5.0;
  EXPECT_NEAR(feet.ground_normal.dot(on_ground * to_feet) + feet.ground_offset, 0.0, 1e-9);
  const Eigen::Vector3d offset(1e5, 2e5, 10.0);
  const SceneModel a = translated(scaled(model, to_feet), offset);
  const SceneModel b = scaled(translated(model, offset / to_feet), to_feet);
  EXPECT_LT((a.records[0].full_center - b.records[0].full_center).norm(), 1e-6);
  EXPECT_THROW(scaled(model, 0.0), Error);
  EXPECT_THROW(scaled(model, std::nan("")), Error);
}

}  // namespace
}  // namespace quadrix
