// Synthetic scenes: label table, layouts per seed, the monument's primitive counts, ground truth
// consistency with the geometry library, pose specifications and the portable random numbers.
#include "experiments/synthetic/synthetic_output.h"
#include "experiments/synthetic/synthetic_scene.h"
#include "geometry/constants.h"
#include "geometry/error.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

namespace quadrix {
namespace {

std::map<std::string, int> type_counts(const Scene& scene) {
  std::map<std::string, int> counts;
  for (const auto& [type, count] : count_model_types(scene)) counts[type] = count;
  return counts;
}

std::map<SemanticLabel, int> label_counts(const Scene& scene) {
  std::map<SemanticLabel, int> counts;
  for (const auto& primitive : scene.primitives) ++counts[primitive.label];
  return counts;
}

TEST(SemanticLabels, NamesAreUniqueAndRoundTrip) {
  std::set<std::string> names;
  std::set<std::uint32_t> ids;
  for (const auto& row : semantic_label_table()) {
    EXPECT_TRUE(names.insert(row.name).second) << row.name;
    EXPECT_TRUE(ids.insert(static_cast<std::uint32_t>(row.label)).second) << row.name;
    EXPECT_EQ(semantic_label_from_name(row.name), row.label);
    EXPECT_EQ(semantic_label_name(row.label), row.name);
    EXPECT_FALSE(row.description.empty());
  }
  EXPECT_THROW(semantic_label_from_name("lamppost"), Error);
  EXPECT_THROW(semantic_label_name(static_cast<SemanticLabel>(9999)), Error);
  // SemanticKITTI ids are reused where the class exists.
  EXPECT_EQ(static_cast<std::uint32_t>(SemanticLabel::Car), 10u);
  EXPECT_EQ(static_cast<std::uint32_t>(SemanticLabel::Pole), 80u);
}

TEST(Scenes, UnknownNameIsAnErrorNamingTheChoices) {
  try {
    make_scene("forest", 1);
    FAIL() << "expected quadrix::Error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("street"), std::string::npos);
  }
  EXPECT_THROW(scene_description("forest"), Error);
}

TEST(Monument, CountsMatchThePapersModel) {
  const Scene scene = make_monument_scene(1);
  const auto counts = type_counts(scene);
  EXPECT_EQ(counts.at("circular_cylinder"), 33);
  EXPECT_EQ(counts.at("plane"), 25);
  EXPECT_EQ(counts.at("sphere"), 3);
  EXPECT_EQ(counts.at("circular_cone"), 1);
  EXPECT_EQ(scene.primitives.size(), 62u);
  EXPECT_EQ(scene.default_tls_stations.size(), 7u);
  EXPECT_EQ(scene.default_lidar_poses.size(), 2u);
  // The layout does not depend on the seed (only the default LiDAR yaw does).
  const auto layout = [](std::uint64_t seed) {
    return nlohmann::json::parse(primitives_json(make_monument_scene(seed), 200)).at("primitives");
  };
  EXPECT_TRUE(layout(1) == layout(2));
}

TEST(Street, SameSeedIsIdenticalAndOtherSeedsDiffer) {
  const std::string first = primitives_json(make_street_scene(7), 300);
  EXPECT_TRUE(first == primitives_json(make_street_scene(7), 300));
  std::set<std::string> layouts{first};
  for (std::uint64_t seed = 8; seed < 13; ++seed) layouts.insert(primitives_json(make_street_scene(seed), 300));
  EXPECT_EQ(layouts.size(), 6u) << "every seed must give its own layout";
}

// Porous foliage changes the vegetation only: the solid layout, primitive for primitive, with porous
// crowns, plus porous hedges 0.8-2 m tall standing on the sidewalks along the facades.
TEST(Street, PorousFoliageKeepsTheLayoutAndAddsHedges) {
  StreetOptions porous;
  porous.foliage = Foliage::Porous;
  for (std::uint64_t seed = 1; seed < 6; ++seed) {
    const Scene solid = make_street_scene(seed);
    const Scene leafy = make_street_scene(seed, porous);
    ASSERT_GT(leafy.primitives.size(), solid.primitives.size());
    int crowns = 0, hedges = 0;
    for (std::size_t i = 0; i < leafy.primitives.size(); ++i) {
      const ScenePrimitive& primitive = leafy.primitives[i];
      if (i < solid.primitives.size()) {
        EXPECT_EQ(primitive.name, solid.primitives[i].name);
        EXPECT_TRUE(primitive.pose.isApprox(solid.primitives[i].pose));
        EXPECT_EQ(primitive.mean_free_path > 0.0, primitive.label == SemanticLabel::Vegetation) << primitive.name;
        EXPECT_EQ(solid.primitives[i].mean_free_path, 0.0);
        crowns += primitive.label == SemanticLabel::Vegetation;
        continue;
      }
      ++hedges;
      EXPECT_EQ(primitive.name.rfind("hedge_", 0), 0u) << primitive.name;
      EXPECT_EQ(primitive.label, SemanticLabel::Vegetation);
      EXPECT_GT(primitive.mean_free_path, 0.0);
      // Top 0.8-2 m above the sidewalk (its centre stands at a tenth of its height), the cut below it.
      const double top = primitive.pose.translation().z() + primitive.extent.maximum.z();
      const double bottom = primitive.pose.translation().z() + primitive.extent.minimum.z();
      const double sidewalk = primitive.pose.translation().z() - 0.1 * primitive.extent.maximum.z() / 0.9;
      EXPECT_GE(top - sidewalk, 0.8 - 0.05);
      EXPECT_LE(top - sidewalk, 2.0 + 0.05);
      EXPECT_LT(bottom, sidewalk);
    }
    EXPECT_GT(crowns, 0);
    EXPECT_GE(hedges, 10) << "seed " << seed;
  }
  EXPECT_THROW(make_scene("corridor", 1, porous), Error);
  EXPECT_THROW(foliage_from_name("leafy", "--foliage"), Error);
}

TEST(Street, EverySeedHasEveryStreetClass) {
  for (std::uint64_t seed = 0; seed < 20; ++seed) {
    const Scene scene = make_street_scene(seed);
    const auto labels = label_counts(scene);
    for (SemanticLabel label : {SemanticLabel::Road, SemanticLabel::Sidewalk, SemanticLabel::Kerb, SemanticLabel::Facade,
                                SemanticLabel::Pole, SemanticLabel::Car, SemanticLabel::Bollard, SemanticLabel::TrafficCone})
      EXPECT_GT(labels.count(label) ? labels.at(label) : 0, 0) << "seed " << seed << " lacks " << semantic_label_name(label);
    EXPECT_EQ(labels.count(SemanticLabel::Trunk) ? labels.at(SemanticLabel::Trunk) : 0,
              labels.count(SemanticLabel::Vegetation) ? labels.at(SemanticLabel::Vegetation) : 0);
    EXPECT_GE(labels.at(SemanticLabel::Facade), 12) << "seed " << seed;
    EXPECT_GE(labels.at(SemanticLabel::Pole), 8) << "seed " << seed;
    for (const auto& primitive : scene.primitives) {
      if (primitive.label == SemanticLabel::Pole) EXPECT_EQ(primitive.model_type, QuadricType::Line);
      else EXPECT_EQ(primitive.model_type, primitive.surface_type) << primitive.name;
    }
    ASSERT_EQ(scene.default_lidar_poses.size(), 2u);
    const Eigen::Isometry3d relative = relative_transform(scene.default_lidar_poses[0], scene.default_lidar_poses[1]);
    const double distance = relative.translation().norm();
    const double angle = Eigen::AngleAxisd(relative.linear()).angle() * 180.0 / kPi;
    EXPECT_GE(distance, 3.0);
    EXPECT_LE(distance, 9.0);
    EXPECT_GE(angle, 15.0);
    EXPECT_LE(angle, 46.0);
  }
}

TEST(Corridor, HasNoEndWallsAndRepetitivePoles) {
  const Scene scene = make_corridor_scene(5);
  std::vector<double> pole_x;
  for (const auto& primitive : scene.primitives) {
    EXPECT_NE(primitive.label, SemanticLabel::Facade);
    if (primitive.surface_type == QuadricType::Plane) {
      // Every plane runs the whole length: nothing fixes the position along the road.
      const Eigen::Vector3d start = primitive.pose * Eigen::Vector3d(0.0, primitive.extent.minimum.y(), 0.0);
      const Eigen::Vector3d end = primitive.pose * Eigen::Vector3d(0.0, primitive.extent.maximum.y(), 0.0);
      EXPECT_NEAR(std::abs(end.x() - start.x()), 320.0, 1e-9) << primitive.name;
    }
    if (primitive.name.rfind("median_lamp_post", 0) == 0) pole_x.push_back(primitive.pose.translation().x());
  }
  ASSERT_GE(pole_x.size(), 7u);
  for (std::size_t i = 2; i < pole_x.size(); ++i)
    EXPECT_NEAR(pole_x[i] - pole_x[i - 1], pole_x[1] - pole_x[0], 1e-9);
}

/// Every true-surface sample lies on the primitive according to the geometry library's own
/// decomposition and orthogonal distance, and the model quadric decomposes to the model type.
TEST(GroundTruth, SamplesLieOnTheQuadricAndModelTypesDecompose) {
  std::vector<Scene> scenes = {make_monument_scene(1), make_corridor_scene(2)};
  for (std::uint64_t seed = 0; seed < 3; ++seed) scenes.push_back(make_street_scene(seed));
  for (const Scene& scene : scenes) {
    for (const auto& primitive : scene.primitives) {
      const QuadricDecomposition surface = surface_quadric(primitive).decompose();
      EXPECT_EQ(surface.type, primitive.surface_type) << scene.name << " " << primitive.name;
      EXPECT_EQ(model_quadric(primitive).decompose().type, primitive.model_type) << scene.name << " " << primitive.name;
      const double area = primitive_surface_area(primitive);
      ASSERT_GT(area, 0.0) << primitive.name;
      const Eigen::Matrix3Xd samples = sample_primitive_surface(primitive, std::sqrt(area / 300.0));
      ASSERT_GT(samples.cols(), 20) << primitive.name;
      const double size = primitive.pose.translation().norm() + primitive.extent.maximum.cwiseAbs().maxCoeff();
      for (Eigen::Index i = 0; i < samples.cols(); ++i) {
        const Eigen::Vector3d point = samples.col(i);
        ASSERT_LT(orthogonal_distance(surface, point), 1e-9 * (1.0 + size)) << scene.name << " " << primitive.name;
        ASSERT_TRUE(inside_primitive_bounds(primitive, primitive.pose.inverse() * point, 1e-9)) << primitive.name;
      }
    }
  }
}

TEST(GroundTruth, RecordsCarryLabelQuadricAndTrueCentres) {
  const Scene scene = make_monument_scene(1);
  for (const auto& primitive : scene.primitives) {
    const QuadricRecord record = ground_truth_record(primitive, 2000);
    EXPECT_EQ(record.label, static_cast<std::uint32_t>(primitive.label));
    // The record's quadric is the model quadric up to scale.
    const Vector10d expected = model_quadric(primitive).parameters().normalized();
    const Vector10d actual = record.q.normalized();
    EXPECT_LT(std::min((expected - actual).norm(), (expected + actual).norm()), 1e-6) << primitive.name;
    if (primitive.name == "finial_left" || primitive.name == "finial_right") {
      // Spheres are central: the full centre is the true centre even though the bottom is clipped.
      EXPECT_LT((record.full_center - primitive.pose.translation()).norm(), 1e-6) << primitive.name;
      EXPECT_NEAR(record.full_scale.x(), 0.8, 1e-6);
    }
    if (primitive.surface_type == QuadricType::Plane) {
      // The plane's full centre is on the plane, inside its bounded surface.
      const Eigen::Vector3d local = primitive.pose.inverse() * record.full_center;
      EXPECT_NEAR(local.x(), 0.0, 1e-6) << primitive.name;
      EXPECT_TRUE(inside_primitive_bounds(primitive, local, 1e-6)) << primitive.name;
    }
  }
}

TEST(PoseSpec, InlineEntriesAndFilesParse) {
  const auto poses = parse_pose_spec("1,2,3,90; -4, 5, 6, 0, 10 ;");
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_TRUE(poses[0].translation().isApprox(Eigen::Vector3d(1, 2, 3)));
  EXPECT_TRUE((poses[0].linear() * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-12));
  EXPECT_NEAR(Eigen::AngleAxisd(poses[1].linear()).angle(), 10.0 * kPi / 180.0, 1e-12);

  const std::filesystem::path file = std::filesystem::temp_directory_path() / "quadrix_test_pose_spec.txt";
  {
    std::ofstream stream(file);
    stream << "# sensor poses\n1 0 0 5 0 1 0 6 0 0 1 7\n\n0 -1 0 1 1 0 0 2 0 0 1 3 0 0 0 1\n8 9 10 45\n";
  }
  const auto from_file = parse_pose_spec(file.string());
  ASSERT_EQ(from_file.size(), 3u);
  EXPECT_TRUE(from_file[0].translation().isApprox(Eigen::Vector3d(5, 6, 7)));
  EXPECT_TRUE((from_file[1].linear() * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-12));
  {
    std::ofstream stream(file);
    stream << "1 0 0 5 0 1 0 6 0 0 1 7\n2 0 0 5 0 1 0 6 0 0 1 7\n";
  }
  try {
    parse_pose_spec(file.string());
    FAIL() << "expected quadrix::Error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find(":2"), std::string::npos) << error.what();
  }
  std::filesystem::remove(file);

  try {
    parse_pose_spec("1,2,3,4;1,2,x,4");
    FAIL() << "expected quadrix::Error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("entry 2"), std::string::npos) << error.what();
  }
  EXPECT_THROW(parse_pose_spec("1,2,3"), Error);
  EXPECT_THROW(parse_pose_spec(";;"), Error);
}

TEST(PortableRandom, ReproducibleInRangeAndStatisticallySound) {
  PortableRandom first(42), second(42), other(43);
  bool differs = false;
  for (int i = 0; i < 100; ++i) {
    const double value = first.uniform(-2.0, 3.0);
    EXPECT_EQ(value, second.uniform(-2.0, 3.0));
    differs = differs || value != other.uniform(-2.0, 3.0);
    EXPECT_GE(value, -2.0);
    EXPECT_LT(value, 3.0);
  }
  EXPECT_TRUE(differs);
  PortableRandom random(7);
  const int count = 200000;
  double sum = 0.0, squares = 0.0;
  std::map<int, int> dice;
  for (int i = 0; i < count; ++i) {
    const double value = random.normal(1.0, 2.0);
    sum += value;
    squares += value * value;
    ++dice[random.uniform_integer(1, 6)];
  }
  const double mean = sum / count, variance = squares / count - mean * mean;
  EXPECT_NEAR(mean, 1.0, 5.0 * 2.0 / std::sqrt(count));
  EXPECT_NEAR(variance, 4.0, 5.0 * 4.0 * std::sqrt(2.0 / count));
  ASSERT_EQ(dice.size(), 6u);
  for (const auto& [face, hits] : dice) EXPECT_NEAR(hits, count / 6.0, 5.0 * std::sqrt(count / 6.0)) << face;
}

}  // namespace
}  // namespace quadrix
