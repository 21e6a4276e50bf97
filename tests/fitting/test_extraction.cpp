// Element extraction (paper §"Quadric Extraction") on synthetic scenes built here with known
// ground truth: a sloped ground, walls, poles, boxes and ellipsoid bushes sampled LiDAR-like with
// noise; and a monument-like static scan for CGAL Efficient RANSAC.
#include "fitting/extraction.h"

#include "geometry/constants.h"
#include "geometry/error.h"
#include "geometry/io.h"
#include "geometry/voxel_cells.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <iostream>
#include <map>
#include <random>
#include <set>

namespace quadrix {
namespace {


// Ground of the street scene: z = -1.73 + slope * x (the sensor is 1.73 m above it, KITTI-like).
constexpr double kSlope = 0.06;  // 3.4 degrees
double ground_height(double x) { return -1.73 + kSlope * x; }

struct SyntheticStreet {
  PointCloud cloud;
  std::vector<int> truth;  // per point: 0 ground, 1.. wall id, 10.. pole id, 20.. box id, 30.. bush id
};

void add_point(SyntheticStreet& scene, std::vector<Eigen::Vector3f>& points, const Eigen::Vector3d& p, int id) {
  points.push_back(p.cast<float>());
  scene.truth.push_back(id);
}

// Sloped ground sampled uniformly in range (density ~ 1/r like a spinning LiDAR), two long walls,
// three poles (sensor-facing half), two boxes (cars) and two ellipsoid bushes; Gaussian noise.
SyntheticStreet make_street(std::uint64_t seed, double noise = 0.02) {
  std::mt19937_64 engine(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, noise);
  const auto jitter = [&]() { return Eigen::Vector3d(gauss(engine), gauss(engine), gauss(engine)); };
  SyntheticStreet scene;
  std::vector<Eigen::Vector3f> points;
  for (int i = 0; i < 40000; ++i) {
    const double r = 2.5 + 47.5 * unit(engine), angle = 2.0 * kPi * unit(engine);
    const double x = r * std::cos(angle), y = r * std::sin(angle);
    if (std::abs(y) > 11.8) continue;  // the walls close the street
    add_point(scene, points, Eigen::Vector3d(x, y, ground_height(x)) + jitter(), 0);
  }
  const double wall_y[2] = {12.0, -12.0};
  for (int wall = 0; wall < 2; ++wall)
    for (int i = 0; i < 6000; ++i) {
      const double x = -20.0 + 45.0 * unit(engine), h = 7.0 * unit(engine);
      add_point(scene, points, Eigen::Vector3d(x, wall_y[wall], ground_height(x) + h) + jitter(), 1 + wall);
    }
  const Eigen::Vector2d poles[3] = {{6.0, 7.0}, {18.0, -8.0}, {-9.0, -7.0}};
  for (int pole = 0; pole < 3; ++pole)
    for (int i = 0; i < 300; ++i) {
      const Eigen::Vector2d toward_sensor = -poles[pole].normalized();
      const double phi = (unit(engine) - 0.5) * kPi, h = 5.0 * unit(engine);
      const double base = std::atan2(toward_sensor.y(), toward_sensor.x());
      // 0.08 m, a lamp post's radius: a stem of 0.11 m or more whose top is out of view is a trunk.
      const Eigen::Vector2d xy = poles[pole] + 0.08 * Eigen::Vector2d(std::cos(base + phi), std::sin(base + phi));
      add_point(scene, points, Eigen::Vector3d(xy.x(), xy.y(), ground_height(xy.x()) + h) + 0.5 * jitter(), 10 + pole);
    }
  const Eigen::Vector2d boxes[2] = {{10.0, -4.0}, {-6.0, 4.5}};
  for (int box = 0; box < 2; ++box)
    for (int i = 0; i < 1500; ++i) {
      // Surface of a 4 x 1.8 x 1.5 m box standing 0.3 m above the ground (a car body).
      const Eigen::Vector3d size(4.0, 1.8, 1.5);
      const int face = static_cast<int>(unit(engine) * 5.0);  // no bottom face
      Eigen::Vector3d local(unit(engine) * size.x(), unit(engine) * size.y(), unit(engine) * size.z());
      if (face == 0) local.x() = 0.0;
      if (face == 1) local.x() = size.x();
      if (face == 2) local.y() = 0.0;
      if (face == 3) local.y() = size.y();
      if (face == 4) local.z() = size.z();
      const Eigen::Vector3d corner(boxes[box].x() - 2.0, boxes[box].y() - 0.9, ground_height(boxes[box].x()) + 0.3);
      add_point(scene, points, corner + local + jitter(), 20 + box);
    }
  const Eigen::Vector2d bushes[2] = {{-15.0, 9.0}, {25.0, 8.0}};
  for (int bush = 0; bush < 2; ++bush)
    for (int i = 0; i < 1200; ++i) {
      Eigen::Vector3d direction(gauss(engine), gauss(engine), gauss(engine));
      direction.normalize();
      const Eigen::Vector3d radii(1.5, 1.0, 1.0);
      const Eigen::Vector3d centre(bushes[bush].x(), bushes[bush].y(), ground_height(bushes[bush].x()) + 1.3);
      add_point(scene, points, centre + radii.cwiseProduct(direction) + jitter(), 30 + bush);
    }
  scene.cloud.positions.resize(3, static_cast<Eigen::Index>(points.size()));
  for (std::size_t i = 0; i < points.size(); ++i) scene.cloud.positions.col(static_cast<Eigen::Index>(i)) = points[i];
  return scene;
}

int count_class(const ExtractionResult& result, ElementClass element_class) {
  return static_cast<int>(std::count_if(result.elements.begin(), result.elements.end(),
                                        [&](const Element& e) { return e.element_class == element_class; }));
}

// Majority ground-truth id of an element and the fraction of its points carrying it.
std::pair<int, double> majority_truth(const Element& element, const std::vector<int>& truth) {
  std::map<int, int> votes;
  for (const std::uint32_t index : element.point_indices) ++votes[truth[index]];
  const auto best = std::max_element(votes.begin(), votes.end(), [](auto a, auto b) { return a.second < b.second; });
  return {best->first, static_cast<double>(best->second) / static_cast<double>(element.point_indices.size())};
}

TEST(Extraction, PresetsFollowTheReferenceTable) {
  const ExtractionOptions hdl = extraction_preset("vlp64");
  EXPECT_DOUBLE_EQ(hdl.minimum_range, 2.0);
  EXPECT_DOUBLE_EQ(hdl.maximum_range, 80.0);
  EXPECT_DOUBLE_EQ(hdl.planes.voxel_size, 1.0);
  EXPECT_DOUBLE_EQ(hdl.planes.merge_distance, 0.20);
  EXPECT_DOUBLE_EQ(hdl.planes.normal_cosine, 0.95);
  EXPECT_DOUBLE_EQ(hdl.planes.eigenvalue_ratio, 30.0);
  EXPECT_EQ(hdl.clusters.minimum_points, 20);
  EXPECT_DOUBLE_EQ(extraction_preset("vlp16").planes.voxel_size, 1.4);
  EXPECT_DOUBLE_EQ(extraction_preset("vlp16").planes.eigenvalue_ratio, 16.0);
  EXPECT_DOUBLE_EQ(extraction_preset("mid360").planes.merge_distance, 0.25);
  EXPECT_DOUBLE_EQ(extraction_preset("avia").planes.eigenvalue_ratio, 20.0);
  EXPECT_TRUE(extraction_preset("monument").static_scan);
  EXPECT_THROW(extraction_preset("hdl128"), Error);
}

TEST(Extraction, SemanticKittiLabelMapping) {
  ElementClass element_class;
  ASSERT_TRUE(element_class_for_semantic_kitti_label(10, element_class));
  EXPECT_EQ(element_class, ElementClass::Vehicle);
  ASSERT_TRUE(element_class_for_semantic_kitti_label((7u << 16) | 18u, element_class));  // instance bits ignored
  EXPECT_EQ(element_class, ElementClass::Vehicle);
  ASSERT_TRUE(element_class_for_semantic_kitti_label(71, element_class));
  EXPECT_EQ(element_class, ElementClass::Trunk);
  ASSERT_TRUE(element_class_for_semantic_kitti_label(70, element_class));
  EXPECT_EQ(element_class, ElementClass::Vegetation);
  ASSERT_TRUE(element_class_for_semantic_kitti_label(51, element_class));
  EXPECT_EQ(element_class, ElementClass::Plane);
  ASSERT_TRUE(element_class_for_semantic_kitti_label(81, element_class));
  EXPECT_EQ(element_class, ElementClass::Line);
  ASSERT_TRUE(element_class_for_semantic_kitti_label(72, element_class));
  EXPECT_EQ(element_class, ElementClass::Ground);
  EXPECT_FALSE(element_class_for_semantic_kitti_label(0, element_class));   // unlabelled
  EXPECT_FALSE(element_class_for_semantic_kitti_label(30, element_class));  // person
}

TEST(Extraction, SyntheticStreetFindsGroundWallsPolesAndObjects) {
  for (const std::uint64_t seed : {1u, 2u, 3u}) {
    SCOPED_TRACE(seed);
    const SyntheticStreet scene = make_street(seed);
    const ExtractionResult result = extract_elements(scene.cloud, extraction_preset("vlp64"));
    ASSERT_EQ(result.status, ExtractionStatus::Ok) << result.message;
    ASSERT_TRUE(result.has_ground);
    const Eigen::Vector3d true_normal = Eigen::Vector3d(-kSlope, 0.0, 1.0).normalized();
    EXPECT_LT(std::acos(std::min(1.0, result.ground_normal.dot(true_normal))) * 180.0 / kPi, 2.0);
    EXPECT_EQ(count_class(result, ElementClass::Ground), 1);
    EXPECT_EQ(count_class(result, ElementClass::Plane), 2);
    EXPECT_EQ(count_class(result, ElementClass::Line), 3);
    EXPECT_EQ(count_class(result, ElementClass::Object), 4);
    // Every element is pure (>= 90% one truth id) and of the right kind.
    std::set<int> found;
    for (const Element& element : result.elements) {
      const auto [id, purity] = majority_truth(element, scene.truth);
      EXPECT_GE(purity, 0.9) << element_class_name(element.element_class) << " element of truth " << id;
      found.insert(id);
      switch (element.element_class) {
        case ElementClass::Ground: EXPECT_EQ(id, 0); break;
        case ElementClass::Plane: EXPECT_TRUE(id == 1 || id == 2) << id; break;
        case ElementClass::Line: EXPECT_TRUE(id >= 10 && id < 13) << id; break;
        case ElementClass::Object: EXPECT_TRUE(id >= 20 && id < 32) << id; break;
        default: break;
      }
    }
    EXPECT_EQ(found.size(), 10u);  // ground, 2 walls, 3 poles, 2 boxes, 2 bushes: each found once
    // Ground recall: most of the ground points in range are labelled ground.
    std::size_t ground_truth_points = 0;
    for (std::size_t i = 0; i < scene.truth.size(); ++i) ground_truth_points += scene.truth[i] == 0;
    EXPECT_GE(static_cast<double>(result.elements.front().point_indices.size()), 0.9 * ground_truth_points);
  }
}

TEST(Extraction, CgalRegionGrowingPlanesAgreeWithVoxelPlanes) {
  const SyntheticStreet scene = make_street(4);
  ExtractionOptions options = extraction_preset("vlp64");
  options.planes.method = PlaneMethod::CgalRegionGrowing;
  const ExtractionResult result = extract_elements(scene.cloud, options);
  ASSERT_TRUE(result.has_ground);
  EXPECT_EQ(count_class(result, ElementClass::Plane), 2);
  for (const Element& element : result.elements)
    if (element.element_class == ElementClass::Plane) {
      const auto [id, purity] = majority_truth(element, scene.truth);
      EXPECT_TRUE(id == 1 || id == 2) << id;
      EXPECT_GE(purity, 0.95);
      EXPECT_GE(element.point_indices.size(), 4000u);  // of 6000 wall points
    }
}

TEST(Extraction, GridAndPclClusteringGiveTheSamePartition) {
  const SyntheticStreet scene = make_street(5);
  const Eigen::Matrix3Xd points = scene.cloud.positions.cast<double>();
  std::vector<std::uint32_t> candidates;
  for (std::uint32_t i = 0; i < scene.truth.size(); ++i)
    if (scene.truth[i] >= 10) candidates.push_back(i);
  ClusterOptions grid_options;
  ClusterOptions pcl_options;
  pcl_options.method = ClusterMethod::Pcl;
  const auto grid = euclidean_clusters(points, candidates, grid_options);
  const auto pcl = euclidean_clusters(points, candidates, pcl_options);
  EXPECT_EQ(grid.size(), 7u);  // 3 poles, 2 boxes, 2 bushes
  EXPECT_EQ(grid, pcl);
}

TEST(Extraction, RansacLineRejectsBlobsAndAcceptsPoles) {
  std::mt19937_64 engine(11);
  std::normal_distribution<double> gauss(0.0, 1.0);
  Eigen::Matrix3Xd points(3, 400);
  for (int i = 0; i < 200; ++i) points.col(i) = Eigen::Vector3d(0.05 * gauss(engine), 0.05 * gauss(engine), 0.02 * i);
  for (int i = 200; i < 400; ++i) points.col(i) = Eigen::Vector3d(5.0 + gauss(engine), gauss(engine), gauss(engine));
  std::vector<std::uint32_t> pole(200), blob(200), remaining;
  for (std::uint32_t i = 0; i < 200; ++i) {
    pole[i] = i;
    blob[i] = 200 + i;
  }
  const LineOptions options;
  const auto lines = extract_lines(points, pole, options, Eigen::Vector3d::UnitZ(), remaining);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_GE(lines[0].point_indices.size(), 190u);
  EXPECT_TRUE(extract_lines(points, blob, options, Eigen::Vector3d::UnitZ(), remaining).empty());
  EXPECT_EQ(remaining.size(), 200u);
}

// Points on the sensor-facing half of an upright cylinder (sensor at the origin), bottom to top.
void add_stem(std::vector<Eigen::Vector3d>& points, std::vector<int>& truth, int id, const Eigen::Vector2d& axis,
              double radius, double bottom, double top, int count, std::mt19937_64& engine) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double facing = std::atan2(-axis.y(), -axis.x());
  for (int i = 0; i < count; ++i) {
    const double phi = facing + (unit(engine) - 0.5) * kPi;
    points.emplace_back(axis.x() + radius * std::cos(phi), axis.y() + radius * std::sin(phi),
                        bottom + (top - bottom) * unit(engine));
    truth.push_back(id);
  }
}

std::vector<std::uint32_t> all_indices(std::size_t count) {
  std::vector<std::uint32_t> indices(count);
  for (std::uint32_t i = 0; i < count; ++i) indices[i] = i;
  return indices;
}

Eigen::Matrix3Xd to_matrix(const std::vector<Eigen::Vector3d>& points) {
  Eigen::Matrix3Xd matrix(3, static_cast<Eigen::Index>(points.size()));
  for (std::size_t i = 0; i < points.size(); ++i) matrix.col(static_cast<Eigen::Index>(i)) = points[i];
  return matrix;
}

// How many of `indices` belong to the primitive `id` of `truth`.
std::size_t count_truth(const std::vector<std::uint32_t>& indices, const std::vector<int>& truth, int id) {
  return static_cast<std::size_t>(std::count_if(indices.begin(), indices.end(), [&](std::uint32_t i) { return truth[i] == id; }));
}

TEST(Extraction, StemsStandingInAHedgeAreFoundButHedgesCarsAndPeopleAreNot) {
  std::mt19937_64 engine(33);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  // A 4 x 2 x 1 m hedge 9 m away with a 0.15 m trunk standing in it up to 3 m, and a 0.06 m pole in
  // its other end up to 4.5 m: the hedge hides their feet, so neither the trunk rule nor a line sees them.
  std::vector<Eigen::Vector3d> points;
  std::vector<int> truth;
  for (int i = 0; i < 1500; ++i) {
    points.emplace_back(9.0 + 2.0 * unit(engine), -2.0 + 4.0 * unit(engine), 1.0 * unit(engine));
    truth.push_back(0);
  }
  add_stem(points, truth, 1, {9.5, -1.0}, 0.15, 0.0, 3.0, 240, engine);
  add_stem(points, truth, 2, {9.5, 1.5}, 0.06, 0.0, 4.5, 200, engine);
  StemOptions options;
  options.enabled = true;
  const std::vector<std::vector<std::uint32_t>> stems =
      find_stems(to_matrix(points), all_indices(points.size()), options, Eigen::Vector3d::UnitZ());
  ASSERT_EQ(stems.size(), 2u);
  for (const std::vector<std::uint32_t>& stem : stems) {
    const std::size_t trunk = count_truth(stem, truth, 1), pole = count_truth(stem, truth, 2);
    // Most of the part above the hedge (two thirds of the trunk, three quarters of the pole) and no hedge.
    EXPECT_TRUE(trunk >= 140u || pole >= 130u) << "trunk " << trunk << ", pole " << pole;
    EXPECT_LE(count_truth(stem, truth, 0), 5u);
    EXPECT_TRUE(std::is_sorted(stem.begin(), stem.end()));
  }
  // The hedge alone, a car-sized box and a person 1.8 m tall: no stem.
  const auto box = [&](const Eigen::Vector3d& low, const Eigen::Vector3d& size, int count) {
    std::vector<Eigen::Vector3d> solid;
    for (int i = 0; i < count; ++i)
      solid.push_back(low + size.cwiseProduct(Eigen::Vector3d(unit(engine), unit(engine), unit(engine))));
    return find_stems(to_matrix(solid), all_indices(solid.size()), options, Eigen::Vector3d::UnitZ());
  };
  EXPECT_TRUE(box({9.0, -2.0, 0.0}, {2.0, 4.0, 1.0}, 1500).empty());
  EXPECT_TRUE(box({6.0, 3.0, 0.3}, {4.2, 1.8, 1.2}, 2000).empty());
  EXPECT_TRUE(box({5.0, 0.0, 0.0}, {0.4, 0.3, 1.8}, 300).empty());
  // Switched off (the default), nothing.
  const StemOptions off;
  EXPECT_TRUE(find_stems(to_matrix(points), all_indices(points.size()), off, Eigen::Vector3d::UnitZ()).empty());
}

TEST(Extraction, TreeGivesItsTrunkAndCrownButPostsKeepTheirLine) {
  std::mt19937_64 engine(21);
  std::normal_distribution<double> gauss(0.0, 1.0);
  // Tree 8 m away: a 0.2 m trunk up to 2.8 m under the visible shell of a 1.6 x 1.4 x 1.8 m crown.
  std::vector<Eigen::Vector3d> tree;
  std::vector<int> tree_truth;
  add_stem(tree, tree_truth, 0, {8.0, 0.0}, 0.2, 0.0, 2.8, 300, engine);
  for (int i = 0; i < 800; ++i) {
    Eigen::Vector3d direction(gauss(engine), gauss(engine), gauss(engine));
    direction.normalize();
    if (direction.x() > 0.3) direction.x() = -direction.x();  // the far side is hidden
    tree.push_back(Eigen::Vector3d(8.0, 0.0, 4.4) + Eigen::Vector3d(1.6, 1.4, 1.8).cwiseProduct(direction));
    tree_truth.push_back(1);
  }
  std::vector<std::uint32_t> trunk, crown;
  const TrunkOptions options;
  ASSERT_TRUE(separate_trunk(to_matrix(tree), all_indices(tree.size()), options, Eigen::Vector3d::UnitZ(), trunk, crown));
  EXPECT_GE(count_truth(trunk, tree_truth, 0), 250u);          // most of the 300 trunk points (its top is among the crown's)
  EXPECT_LE(trunk.size() - count_truth(trunk, tree_truth, 0), 20u);  // and little of the crown
  EXPECT_GE(count_truth(crown, tree_truth, 1), 780u);          // nearly all of the 800 crown points
  EXPECT_EQ(trunk.size() + crown.size(), tree.size());

  // A lamp post with a horizontal arm and a sign post with a flat sign: no crown, no trunk.
  std::vector<Eigen::Vector3d> lamp;
  std::vector<int> lamp_truth;
  add_stem(lamp, lamp_truth, 0, {6.0, 3.0}, 0.08, 0.0, 6.0, 300, engine);
  for (int i = 0; i < 80; ++i) {
    lamp.emplace_back(6.0, 3.0 - 1.8 * (i / 80.0), 5.8 + 0.03 * gauss(engine));
    lamp_truth.push_back(1);
  }
  EXPECT_FALSE(separate_trunk(to_matrix(lamp), all_indices(lamp.size()), options, Eigen::Vector3d::UnitZ(), trunk, crown));
  EXPECT_TRUE(trunk.empty() && crown.empty());
  std::vector<Eigen::Vector3d> sign;
  std::vector<int> sign_truth;
  add_stem(sign, sign_truth, 0, {-5.0, 4.0}, 0.05, 0.0, 2.2, 150, engine);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < 150; ++i) {  // a 1.2 x 0.9 m sign facing the street, 2.2-3.1 m up
    sign.emplace_back(-5.0 + 0.01 * gauss(engine), 4.0 - 0.6 + 1.2 * unit(engine), 2.2 + 0.9 * unit(engine));
    sign_truth.push_back(1);
  }
  EXPECT_FALSE(separate_trunk(to_matrix(sign), all_indices(sign.size()), options, Eigen::Vector3d::UnitZ(), trunk, crown));
}

// An upright cylinder standing on the ground, for ring_scan.
struct UprightCylinder {
  Eigen::Vector2d axis;  // where it stands, m
  double radius;         // m
  double top;            // height of its top, m (the ground is at -1.73)
};

// A spinning scanner at the origin, 1.73 m above flat ground, with the HDL-64E's top beam (+2 deg),
// beams every 0.4 deg below it and 0.2 deg azimuth steps, seeing upright cylinders and a wall
// x = wall_x up to 8 m high (behind the sensor); range noise 1 cm. truth: cylinder index, -1
// ground, -2 wall.
PointCloud ring_scan(const std::vector<UprightCylinder>& cylinders, double wall_x, std::vector<int>& truth) {
  std::mt19937_64 engine(17);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<Eigen::Vector3f> points;
  truth.clear();
  for (int beam = 0; beam <= 64; ++beam) {
    const double slope = std::tan((2.0 - 0.4 * beam) * kPi / 180.0);  // height gained per metre of horizontal range
    for (int step = 0; step < 1800; ++step) {
      const double azimuth = step * 0.2 * kPi / 180.0;
      const Eigen::Vector2d along(std::cos(azimuth), std::sin(azimuth));
      double nearest = 1e300;  // horizontal distance of the first hit
      int hit = -3;
      for (std::size_t c = 0; c < cylinders.size(); ++c) {
        const double middle = along.dot(cylinders[c].axis);
        const double squared = cylinders[c].radius * cylinders[c].radius - (cylinders[c].axis - middle * along).squaredNorm();
        if (squared < 0.0 || middle <= 0.0) continue;
        const double distance = middle - std::sqrt(squared);
        const double height = distance * slope;
        if (height >= -1.73 && height <= cylinders[c].top && distance < nearest) {
          nearest = distance;
          hit = static_cast<int>(c);
        }
      }
      if (along.x() < -1e-9 && wall_x / along.x() * slope <= 8.0 && wall_x / along.x() < nearest) {
        nearest = wall_x / along.x();
        hit = -2;
      }
      if (slope < 0.0 && -1.73 / slope < std::min(nearest, 60.0)) {
        nearest = -1.73 / slope;
        hit = -1;
      }
      if (hit == -3) continue;
      const double range = nearest * std::sqrt(1.0 + slope * slope) + noise(engine);
      const Eigen::Vector3d direction = Eigen::Vector3d(along.x(), along.y(), slope).normalized();
      points.push_back((range * direction).cast<float>());
      truth.push_back(hit);
    }
  }
  PointCloud cloud;
  cloud.positions.resize(3, static_cast<Eigen::Index>(points.size()));
  for (std::size_t i = 0; i < points.size(); ++i) cloud.positions.col(static_cast<Eigen::Index>(i)) = points[i];
  return cloud;
}

TEST(Extraction, ThickStemRunningOutOfViewIsATrunkButPolesAndPillarsStayLines) {
  // A 0.2 m trunk whose crown is above the top beam, a 0.07 m lamp post, a 0.2 m pillar 1.7 m tall
  // in front of a wall (the beams above it hit the wall) and a 0.2 m trunk 46 m away (too sparse).
  const std::vector<UprightCylinder> cylinders = {
      {{8.0, 0.0}, 0.2, 6.0}, {{6.0, 4.0}, 0.07, 6.0}, {{-8.0, 2.0}, 0.2, 0.0}, {{45.0, 10.0}, 0.2, 6.0}};
  std::vector<int> truth;
  const PointCloud cloud = ring_scan(cylinders, -14.0, truth);
  const Eigen::Matrix3Xd points = cloud.positions.cast<double>();
  std::vector<std::vector<std::uint32_t>> of_cylinder(cylinders.size());
  std::vector<std::uint32_t> everything;
  for (std::uint32_t i = 0; i < truth.size(); ++i) {
    everything.push_back(i);
    if (truth[i] >= 0) of_cylinder[static_cast<std::size_t>(truth[i])].push_back(i);
  }
  const TrunkOptions options;
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ(), sensor = Eigen::Vector3d::Zero();
  EXPECT_NEAR(stem_radius_across_view(points, of_cylinder[0], options, sensor), 0.2, 0.03);
  EXPECT_NEAR(stem_radius_across_view(points, of_cylinder[1], options, sensor), 0.07, 0.03);
  EXPECT_NEAR(stem_radius_across_view(points, of_cylinder[2], options, sensor), 0.2, 0.03);
  EXPECT_LT(stem_radius_across_view(points, of_cylinder[3], options, sensor), 0.0);  // not measured
  EXPECT_TRUE(stem_reaches_top_of_view(points, of_cylinder[0], everything, options, up, sensor));
  EXPECT_TRUE(stem_reaches_top_of_view(points, of_cylinder[1], everything, options, up, sensor));
  EXPECT_FALSE(stem_reaches_top_of_view(points, of_cylinder[2], everything, options, up, sensor));

  // The whole pipeline: the element holding most of each cylinder has the expected class.
  const auto class_of = [&](const ExtractionResult& result, int cylinder) {
    std::size_t best = 0;
    ElementClass element_class = ElementClass::Ground;
    for (const Element& element : result.elements) {
      const auto held = static_cast<std::size_t>(std::count_if(element.point_indices.begin(), element.point_indices.end(),
                                                               [&](std::uint32_t i) { return truth[i] == cylinder; }));
      if (held > best) {
        best = held;
        element_class = element.element_class;
      }
    }
    return element_class;
  };
  ExtractionOptions extraction = extraction_preset("vlp64");
  const ExtractionResult result = extract_elements(cloud, extraction);
  ASSERT_TRUE(result.has_ground);
  EXPECT_EQ(class_of(result, 0), ElementClass::Trunk);
  EXPECT_EQ(class_of(result, 1), ElementClass::Line);
  EXPECT_EQ(class_of(result, 2), ElementClass::Line);
  EXPECT_NE(class_of(result, 3), ElementClass::Trunk);
  // Switched off (the mid360/avia presets), the trunk is a line again.
  extraction.trunks.crownless_minimum_radius = 0.0;
  EXPECT_EQ(class_of(extract_elements(cloud, extraction), 0), ElementClass::Line);
  EXPECT_EQ(class_of(extract_elements(cloud, extraction_preset("avia")), 0), ElementClass::Line);
}

TEST(Extraction, ClusterOfWallsIsSplitIntoItsPlanesButABlobIsNot) {
  // A recessed entrance seen from the street (sensor at the origin, facade at y = 10): the back
  // wall 3 m wide at y = 11.5, two 1.5 m jambs and a facade piece beside it, 2 m of each visible.
  std::mt19937_64 engine(8);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::vector<Eigen::Vector3d> points;
  std::vector<int> truth;
  const auto add = [&](int id, int count, const std::function<Eigen::Vector3d(double, double)>& at) {
    for (int i = 0; i < count; ++i) {
      points.push_back(at(unit(engine), unit(engine)) + Eigen::Vector3d(noise(engine), noise(engine), noise(engine)));
      truth.push_back(id);
    }
  };
  add(0, 900, [](double a, double b) { return Eigen::Vector3d(-1.5 + 3.0 * a, 11.5, 2.0 * b); });
  add(1, 300, [](double a, double b) { return Eigen::Vector3d(-1.5, 10.0 + 1.5 * a, 2.0 * b); });
  add(2, 300, [](double a, double b) { return Eigen::Vector3d(1.5, 10.0 + 1.5 * a, 2.0 * b); });
  add(3, 500, [](double a, double b) { return Eigen::Vector3d(1.5 + 2.5 * a, 10.0, 2.0 * b); });
  const Eigen::Matrix3Xd matrix = to_matrix(points);
  const PlaneOptions options;
  const auto planes = cluster_planes(matrix, all_indices(points.size()), options, Eigen::Vector3d::UnitZ());
  ASSERT_GE(planes.size(), 3u);
  std::set<int> walls;
  std::size_t covered = 0;
  for (const auto& plane : planes) {
    std::map<int, std::size_t> votes;
    for (const std::uint32_t index : plane) ++votes[truth[index]];
    const auto best = std::max_element(votes.begin(), votes.end(), [](auto a, auto b) { return a.second < b.second; });
    // Each plane also holds the other walls' points within 0.1 m of it (their edges: ~7% here).
    EXPECT_GE(static_cast<double>(best->second), 0.85 * static_cast<double>(plane.size())) << "plane of wall " << best->first;
    walls.insert(best->first);
    covered += plane.size();
  }
  EXPECT_GE(walls.size(), 3u);  // back wall, facade piece and at least one jamb, each its own plane
  EXPECT_GE(static_cast<double>(covered), 0.8 * static_cast<double>(points.size()));
  for (std::size_t p = 1; p < planes.size(); ++p) EXPECT_LE(planes[p].size(), planes[p - 1].size());  // largest first

  // An ellipsoid blob (a car, a bush) holds no wall.
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<Eigen::Vector3d> blob;
  for (int i = 0; i < 2000; ++i) {
    Eigen::Vector3d direction(gauss(engine), gauss(engine), gauss(engine));
    blob.push_back(Eigen::Vector3d(2.2, 0.9, 0.75).cwiseProduct(direction.normalized()) + Eigen::Vector3d(8.0, 3.0, 0.0));
  }
  EXPECT_TRUE(cluster_planes(to_matrix(blob), all_indices(blob.size()), options, Eigen::Vector3d::UnitZ()).empty());
}

// Uniform strays (dust, rain, multipath echoes) in the street's volume: the extraction leaves the
// isolated points out before the ground and the clusters (ExtractionOptions::isolation_cell). No
// element holds one of them, they are counted, and the street is modelled as without strays. (What
// it is worth to registration is measured on real scans: FaultInjectionRealData.)
TEST(Extraction, IsolatedStraysAreLeftOutBeforeModelling) {
  constexpr int kStrayId = -1;
  for (const std::uint64_t seed : {1u, 2u}) {
    SCOPED_TRACE(seed);
    SyntheticStreet scene = make_street(seed);
    const Eigen::Index street_points = scene.cloud.positions.cols();
    const int strays = 4000;  // 8% of the scan, one per 4 m^3 of the street's volume
    std::mt19937_64 engine(seed + 100);
    std::uniform_real_distribution<double> along(-40.0, 40.0), across(-11.5, 11.5), up(0.0, 8.0);
    scene.cloud.positions.conservativeResize(3, street_points + strays);
    for (int i = 0; i < strays; ++i) {
      const double x = along(engine);
      scene.cloud.positions.col(street_points + i) = Eigen::Vector3d(x, across(engine), ground_height(x) + up(engine)).cast<float>();
      scene.truth.push_back(kStrayId);
    }
    const ExtractionOptions options = extraction_preset("vlp64");
    ExtractionOptions keep_all = options;
    keep_all.isolation_cell = 0.0;
    const ExtractionResult filtered = extract_elements(scene.cloud, options), unfiltered = extract_elements(scene.cloud, keep_all);
    ASSERT_EQ(filtered.status, ExtractionStatus::Ok) << filtered.message;
    EXPECT_EQ(unfiltered.isolated_points, 0u);
    EXPECT_EQ(filtered.points_in_range, unfiltered.points_in_range);
    // The rule on the points in range, applied here on its own: no element holds a point it leaves out.
    const Eigen::Matrix3Xd points = scene.cloud.positions.cast<double>();
    std::vector<std::uint32_t> in_range;
    for (std::uint32_t i = 0; i < points.cols(); ++i)
      if (within_range(points.col(i), options)) in_range.push_back(i);
    const std::vector<std::uint32_t> accompanied = accompanied_points(points, in_range, options.isolation_cell);
    EXPECT_EQ(filtered.isolated_points, in_range.size() - accompanied.size());
    const std::set<std::uint32_t> kept(accompanied.begin(), accompanied.end());
    bool unfiltered_holds_isolated = false;
    for (const Element& element : filtered.elements)
      for (const std::uint32_t index : element.point_indices) ASSERT_EQ(kept.count(index), 1u) << "isolated point " << index;
    for (const Element& element : unfiltered.elements)
      for (const std::uint32_t index : element.point_indices) unfiltered_holds_isolated = unfiltered_holds_isolated || kept.count(index) == 0;
    EXPECT_TRUE(unfiltered_holds_isolated);  // the premise: left in, some isolated points join elements
    // Most strays are isolated, and hardly any street point is: the isolated count is at least
    // 80% of the strays in range and at most all of them plus 1% of the street (the synthetic
    // ground is sampled at random, sparser than a scan line far from the sensor).
    std::size_t strays_in_range = 0;
    for (Eigen::Index i = street_points; i < scene.cloud.positions.cols(); ++i)
      strays_in_range += within_range(points.col(i), options);
    EXPECT_GE(filtered.isolated_points, static_cast<std::size_t>(0.8 * strays_in_range));
    EXPECT_LE(filtered.isolated_points, strays_in_range + static_cast<std::size_t>(0.01 * street_points));
    // The street is still modelled as without strays: ground, both walls, the three poles.
    EXPECT_TRUE(filtered.has_ground);
    EXPECT_EQ(count_class(filtered, ElementClass::Plane), 2);
    EXPECT_EQ(count_class(filtered, ElementClass::Line), 3);
  }
  // Every point in range isolated: a status naming why, not an empty success.
  PointCloud scattered;
  scattered.positions.resize(3, 50);
  for (int i = 0; i < 50; ++i) scattered.positions.col(i) = Eigen::Vector3f(5.0f + 2.0f * static_cast<float>(i), 0.0f, 0.0f);
  const ExtractionResult alone = extract_elements(scattered, extraction_preset("vlp64"));
  EXPECT_EQ(alone.status, ExtractionStatus::EmptyCloud);
  EXPECT_EQ(alone.isolated_points, alone.points_in_range);
  EXPECT_NE(alone.message.find("isolated"), std::string::npos) << alone.message;
  ExtractionOptions negative = extraction_preset("vlp64");
  negative.isolation_cell = -0.3;
  EXPECT_THROW(extract_elements(scattered, negative), Error);
  ExtractionOptions no_neighbours = extraction_preset("vlp64");
  no_neighbours.isolation_neighbours = 0;
  EXPECT_THROW(extract_elements(scattered, no_neighbours), Error);
}

TEST(Extraction, UpAxisIsConfigurable) {
  // The same street with y up (x, y, z) -> (x, z, -y): the ground must still be found.
  SyntheticStreet scene = make_street(6);
  Eigen::Matrix3f rotate;
  rotate << 1, 0, 0, 0, 0, 1, 0, -1, 0;
  scene.cloud.positions = rotate * scene.cloud.positions;
  ExtractionOptions options = extraction_preset("vlp64");
  options.up = Eigen::Vector3d::UnitY();
  const ExtractionResult result = extract_elements(scene.cloud, options);
  ASSERT_TRUE(result.has_ground);
  const Eigen::Vector3d true_normal = (rotate.cast<double>() * Eigen::Vector3d(-kSlope, 0.0, 1.0)).normalized();
  EXPECT_LT(std::acos(std::min(1.0, result.ground_normal.dot(true_normal))) * 180.0 / kPi, 2.0);
  EXPECT_EQ(count_class(result, ElementClass::Plane), 2);
  EXPECT_EQ(count_class(result, ElementClass::Line), 3);
}

TEST(Extraction, GroundIsTheLargestContinuousRegionNotTheRegionOfTheDensestPatch) {
  // A flat ground 1.73 m below the sensor, 6 points per m^2 out to 40 m, and one dense bank tilted
  // 20 deg (below the 25 deg a patch may slope) filling one sector of the 4-8 m ring: its patch holds
  // the most inliers, but no neighbour continues its slope. The ground is the flat region.
  std::mt19937_64 engine(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Eigen::Vector3d> points;
  const double bank_first = 1.0 * kPi / 180.0, bank_last = 10.0 * kPi / 180.0;
  std::size_t flat = 0;
  for (int i = 0; i < 30000; ++i) {
    const double radius = std::sqrt(4.0 + unit(engine) * (1600.0 - 4.0)), azimuth = 2.0 * kPi * unit(engine);
    if (radius >= 4.0 && radius <= 8.0 && azimuth >= bank_first - 0.2 && azimuth <= bank_last + 0.2) continue;
    points.emplace_back(radius * std::cos(azimuth), radius * std::sin(azimuth), -1.73);
    ++flat;
  }
  for (int i = 0; i < 3000; ++i) {
    const double radius = 4.5 + 3.0 * unit(engine), azimuth = bank_first + (bank_last - bank_first) * unit(engine);
    points.emplace_back(radius * std::cos(azimuth), radius * std::sin(azimuth), -1.73 + std::tan(20.0 * kPi / 180.0) * (radius - 4.5));
  }
  const GroundSegmentation ground = segment_ground(to_matrix(points), all_indices(points.size()), GroundOptions(),
                                                   Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ());
  ASSERT_TRUE(ground.found);
  EXPECT_LT(std::acos(std::min(1.0, ground.normal.z())) * 180.0 / kPi, 1.0);
  EXPECT_NEAR(ground.offset, 1.73, 0.02);
  EXPECT_GE(ground.ground_indices.size(), flat * 9 / 10);
  EXPECT_GT(ground.patches_accepted, 100);
}

TEST(Extraction, GroundOfARealScanDoesNotDependOnItsHeading) {
  // One KITTI sweep turned about the up axis: the sectors fall elsewhere on the street, and the
  // ground plane found must turn with the sweep and keep its height.
  const std::string path = testing::shared_data_path("kitti00/velodyne/000088.bin");
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared data absent: " << path;
  const PointCloud cloud = read_point_cloud(path);
  const ExtractionOptions options = extraction_preset("vlp64");
  const ExtractionResult unturned = extract_elements(cloud, options);
  ASSERT_TRUE(unturned.has_ground);
  for (const double yaw : {45.0, 90.0, 135.0, -135.8, 180.0, -60.0}) {
    SCOPED_TRACE("yaw " + std::to_string(yaw));
    const Eigen::Matrix3f turn = Eigen::AngleAxisf(static_cast<float>(yaw * kPi / 180.0), Eigen::Vector3f::UnitZ()).toRotationMatrix();
    PointCloud turned = cloud;
    turned.positions = turn * cloud.positions;
    const ExtractionResult result = extract_elements(turned, options);
    ASSERT_TRUE(result.has_ground);
    const Eigen::Vector3d expected = turn.cast<double>() * unturned.ground_normal;
    EXPECT_LT(std::acos(std::min(1.0, result.ground_normal.dot(expected))) * 180.0 / kPi, 1.0);
    EXPECT_NEAR(result.ground_offset, unturned.ground_offset, 0.05);
  }
}

TEST(Extraction, DegenerateCloudsGiveAStatusNotACrash) {
  PointCloud empty;
  EXPECT_EQ(extract_elements(empty, extraction_preset("vlp64")).status, ExtractionStatus::EmptyCloud);

  // All ground: one element, the ground.
  PointCloud flat;
  flat.positions.resize(3, 5000);
  std::mt19937_64 engine(3);
  std::uniform_real_distribution<float> unit(-30.0f, 30.0f);
  for (int i = 0; i < 5000; ++i) flat.positions.col(i) = Eigen::Vector3f(unit(engine), unit(engine), -1.73f);

  // The same ground placed 500 m from the origin (a map's frame): nothing in range, and the message
  // says how far the points lie from the sensor the range limits assume.
  PointCloud placed = flat;
  placed.positions.row(0).array() += 500.0f;
  const ExtractionResult out_of_range = extract_elements(placed, extraction_preset("vlp64"));
  EXPECT_EQ(out_of_range.status, ExtractionStatus::EmptyCloud);
  EXPECT_NE(out_of_range.message.find("no point within the range limits (2 to 80 m"), std::string::npos) << out_of_range.message;
  EXPECT_NE(out_of_range.message.find("the points lie 4"), std::string::npos) << out_of_range.message;
  EXPECT_NE(out_of_range.message.find("in its sensor's frame"), std::string::npos) << out_of_range.message;

  const ExtractionResult ground_only = extract_elements(flat, extraction_preset("vlp64"));
  EXPECT_EQ(ground_only.status, ExtractionStatus::Ok);
  ASSERT_EQ(ground_only.elements.size(), 1u);
  EXPECT_EQ(ground_only.elements[0].element_class, ElementClass::Ground);

  // A single wall and nothing else: no ground, one plane.
  PointCloud wall;
  wall.positions.resize(3, 4000);
  std::uniform_real_distribution<float> height(0.0f, 6.0f);
  for (int i = 0; i < 4000; ++i) wall.positions.col(i) = Eigen::Vector3f(unit(engine), 8.0f, height(engine));
  const ExtractionResult wall_only = extract_elements(wall, extraction_preset("vlp64"));
  EXPECT_EQ(wall_only.status, ExtractionStatus::NoGround) << wall_only.message;
  EXPECT_FALSE(wall_only.message.empty());
  EXPECT_EQ(count_class(wall_only, ElementClass::Plane), 1);

  // Labels mode with the wrong number of labels is bad input.
  ExtractionOptions labelled = extraction_preset("vlp64");
  labelled.semantic_mode = SemanticMode::Labels;
  EXPECT_THROW(extract_elements(wall, labelled, std::vector<std::uint32_t>(3, 50)), Error);
}

// SemanticKITTI labels of the synthetic street's primitives: road, building, pole, car, vegetation.
std::vector<std::uint32_t> semantic_kitti_labels_of(const SyntheticStreet& scene) {
  std::vector<std::uint32_t> labels(scene.truth.size());
  for (std::size_t i = 0; i < labels.size(); ++i) {
    const int id = scene.truth[i];
    labels[i] = id == 0 ? 40u : id < 10 ? 50u : id < 20 ? 80u : id < 30 ? 10u : 70u;
  }
  return labels;
}

TEST(Extraction, LabelsModeUsesTheMapping) {
  const SyntheticStreet scene = make_street(7);
  const std::vector<std::uint32_t> labels = semantic_kitti_labels_of(scene);
  ExtractionOptions options = extraction_preset("vlp64");
  options.semantic_mode = SemanticMode::Labels;
  const ExtractionResult result = extract_elements(scene.cloud, options, labels);
  ASSERT_TRUE(result.has_ground);
  EXPECT_EQ(count_class(result, ElementClass::Ground), 1);
  EXPECT_EQ(count_class(result, ElementClass::Plane), 2);
  EXPECT_EQ(count_class(result, ElementClass::Line), 3);
  EXPECT_EQ(count_class(result, ElementClass::Vehicle), 2);
  EXPECT_EQ(count_class(result, ElementClass::Vegetation), 2);
}

TEST(Extraction, SomeClassesFromLabelsTheRestFromGeometry) {
  const SyntheticStreet scene = make_street(7);
  const std::vector<std::uint32_t> labels = semantic_kitti_labels_of(scene);
  ExtractionOptions options = extraction_preset("vlp64");
  options.semantic_mode = SemanticMode::Labels;
  options.label_classes = parse_label_classes("vehicle");
  const ExtractionResult result = extract_elements(scene.cloud, options, labels);
  // The cars come from the labels; the ground, the walls and the poles from geometry, as without labels.
  const ExtractionResult geometric = extract_elements(scene.cloud, extraction_preset("vlp64"));
  ASSERT_TRUE(result.has_ground);
  EXPECT_EQ(count_class(result, ElementClass::Vehicle), 2);
  EXPECT_EQ(count_class(result, ElementClass::Plane), count_class(geometric, ElementClass::Plane));
  EXPECT_EQ(count_class(result, ElementClass::Line), count_class(geometric, ElementClass::Line));
  for (const Element& element : result.elements)
    for (const std::uint32_t index : element.point_indices)
      EXPECT_EQ(labels[index] == 10u, element.element_class == ElementClass::Vehicle) << "point " << index;
  // Classes the labels cannot give alone, and names that are no class, are errors that name them.
  options.label_classes = {ElementClass::Plane};
  EXPECT_THROW(extract_elements(scene.cloud, options, labels), Error);
  EXPECT_EQ(parse_label_classes("trunk,line,trunk").size(), 2u);
  try {
    parse_label_classes("vehicle,tree");
    FAIL() << "an unknown class was accepted";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("'tree'"), std::string::npos) << error.what();
  }
  EXPECT_THROW(parse_label_classes("ground"), Error);
}

// Monument-like static scan: 3 columns, a floor and a wall, a sphere and a cone, with normals.
PointCloud make_monument(std::uint64_t seed, int expected_counts[4]) {
  std::mt19937_64 engine(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 0.004);
  std::vector<Eigen::Vector3d> points, normals;
  const auto add = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& n) {
    points.push_back(p + Eigen::Vector3d(gauss(engine), gauss(engine), gauss(engine)));
    normals.push_back(n.normalized());
  };
  const auto dense = [](double area) { return static_cast<int>(area * 150.0); };
  // Floor 14 x 14 m (z = 0) and a back wall (x = -7, 14 x 6 m).
  for (int i = 0; i < dense(196.0); ++i) add({-7.0 + 14.0 * unit(engine), -7.0 + 14.0 * unit(engine), 0.0}, {0, 0, 1});
  for (int i = 0; i < dense(84.0); ++i) add({-7.0, -7.0 + 14.0 * unit(engine), 6.0 * unit(engine)}, {1, 0, 0});
  // Three columns, radius 0.4 m, 5 m high.
  const Eigen::Vector2d columns[3] = {{-4.0, -4.0}, {-4.0, 0.0}, {-4.0, 4.0}};
  for (const auto& column : columns)
    for (int i = 0; i < dense(2.0 * kPi * 0.4 * 5.0); ++i) {
      const double angle = 2.0 * kPi * unit(engine);
      const Eigen::Vector3d radial(std::cos(angle), std::sin(angle), 0.0);
      add(Eigen::Vector3d(column.x(), column.y(), 5.0 * unit(engine)) + 0.4 * radial, radial);
    }
  // A sphere of radius 1.5 m resting on the floor (upper 80% visible).
  for (int i = 0; i < dense(4.0 * kPi * 2.25); ++i) {
    Eigen::Vector3d d(gauss(engine), gauss(engine), gauss(engine));
    d.normalize();
    if (d.z() < -0.6) continue;
    add(Eigen::Vector3d(3.0, -3.0, 1.5) + 1.5 * d, d);
  }
  // A cone: apex at (3, 3, 3), axis down, half-angle 30 degrees, 2.5 m high.
  const double tangent = std::tan(30.0 * kPi / 180.0), height = 2.5;
  for (int i = 0; i < dense(kPi * height * tangent * height / std::cos(30.0 * kPi / 180.0)); ++i) {
    const double t = height * std::sqrt(unit(engine)), angle = 2.0 * kPi * unit(engine);
    const Eigen::Vector3d radial(std::cos(angle), std::sin(angle), 0.0), axis(0, 0, -1);
    add(Eigen::Vector3d(3.0, 3.0, 3.0) + t * axis + t * tangent * radial, radial - tangent * axis);
  }
  expected_counts[0] = 2;  // planes (one becomes the ground)
  expected_counts[1] = 3;  // cylinders
  expected_counts[2] = 1;  // spheres
  expected_counts[3] = 1;  // cones
  PointCloud cloud;
  cloud.positions.resize(3, static_cast<Eigen::Index>(points.size()));
  std::vector<float> nx, ny, nz;
  for (std::size_t i = 0; i < points.size(); ++i) {
    cloud.positions.col(static_cast<Eigen::Index>(i)) = points[i].cast<float>();
    nx.push_back(static_cast<float>(normals[i].x()));
    ny.push_back(static_cast<float>(normals[i].y()));
    nz.push_back(static_cast<float>(normals[i].z()));
  }
  cloud.extra_fields["nx"] = nx;
  cloud.extra_fields["ny"] = ny;
  cloud.extra_fields["nz"] = nz;
  return cloud;
}

int count_type(const ExtractionResult& result, QuadricType type) {
  return static_cast<int>(std::count_if(result.elements.begin(), result.elements.end(),
                                        [&](const Element& e) { return e.detected_type == type; }));
}

TEST(Extraction, MonumentPresetFindsEachShapeTypeWithCgalEfficientRansac) {
  int expected[4];
  const PointCloud cloud = make_monument(21, expected);
  // Statistical acceptance: Efficient RANSAC is randomised; k of n seeds must give exact counts.
  int exact_runs = 0;
  for (const std::uint32_t seed : {1u, 2u, 3u}) {
    ExtractionOptions options = extraction_preset("monument");
    options.shapes.seed = seed;
    const ExtractionResult result = extract_elements(cloud, options);
    EXPECT_TRUE(result.has_ground);
    EXPECT_EQ(result.elements.front().element_class, ElementClass::Ground);
    const int planes = count_type(result, QuadricType::Plane), cylinders = count_type(result, QuadricType::CircularCylinder);
    const int spheres = count_type(result, QuadricType::Sphere), cones = count_type(result, QuadricType::CircularCone);
    std::cout << "seed " << seed << ": planes " << planes << ", cylinders " << cylinders << ", spheres " << spheres
              << ", cones " << cones << "\n";
    exact_runs += planes == expected[0] && cylinders == expected[1] && spheres == expected[2] && cones == expected[3];
  }
  EXPECT_GE(exact_runs, 2);
}

TEST(Extraction, MonumentWithoutNormalsUsesJetNormals) {
  int expected[4];
  PointCloud cloud = make_monument(22, expected);
  cloud.extra_fields.clear();
  ExtractionOptions options = extraction_preset("monument");
  // The preset is scaled for a 160 m monument (0.2 m simplification); this 14 m scene with 0.4 m
  // columns needs ShapeDetectionOptions' small-scene defaults for jet normals to resolve the columns.
  options.shapes = ShapeDetectionOptions();
  options.sensor_origin = Eigen::Vector3d(0.0, 0.0, 1.7);  // one station inside the scene
  const ExtractionResult result = extract_elements(cloud, options);
  EXPECT_EQ(count_type(result, QuadricType::CircularCylinder), expected[1]);
  EXPECT_EQ(count_type(result, QuadricType::Sphere), expected[2]);
  EXPECT_EQ(count_type(result, QuadricType::CircularCone), expected[3]);
  EXPECT_GE(count_type(result, QuadricType::Plane), expected[0]);
}

}  // namespace
}  // namespace quadrix
