// Scanner simulator: sensor patterns, exact ray casting (hand-made scenes with known answers, the
// hierarchy against brute force), points on their primitives, occlusion, noise and dropout
// statistics, per-primitive counts, thread-count independence, ground-truth relative transforms and
// the byte-identical output folder.
#include "experiments/synthetic/mesh_ray_caster.h"
#include "experiments/synthetic/scanner_simulator.h"
#include "experiments/synthetic/synthetic_output.h"
#include "geometry/constants.h"
#include "geometry/error.h"
#include "geometry/io.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <sstream>

namespace quadrix {
namespace {

/// Float storage of sensor-frame coordinates: each coordinate is off by at most half an ulp.
double float_tolerance(const Eigen::Vector3d& sensor_point) { return 1e-6 + 2e-7 * sensor_point.norm(); }

std::vector<QuadricDecomposition> surface_shapes(const Scene& scene) {
  std::vector<QuadricDecomposition> shapes;
  for (const auto& primitive : scene.primitives) shapes.push_back(surface_quadric(primitive).decompose());
  return shapes;
}

/// A sphere of radius 1 at `centre`.
ScenePrimitive unit_sphere(const std::string& name, SemanticLabel label, const Eigen::Vector3d& centre) {
  ScenePrimitive sphere;
  sphere.name = name;
  sphere.label = label;
  sphere.surface_type = sphere.model_type = QuadricType::Sphere;
  sphere.scale = Eigen::Vector3d::Constant(1.0);
  sphere.pose.translation() = centre;
  sphere.extent.minimum = Eigen::Vector3d::Constant(-1.0);
  sphere.extent.maximum = Eigen::Vector3d::Constant(1.0);
  return sphere;
}

Scene hand_made_scene() {
  Scene scene;
  scene.name = "hand_made";
  const auto add = [&scene](ScenePrimitive primitive) {
    primitive.id = static_cast<std::uint32_t>(scene.primitives.size());
    scene.primitives.push_back(primitive);
  };
  ScenePrimitive wall;  // plane x = 10, y in [-5, 5], z in [-2, 3]
  wall.name = "wall";
  wall.label = SemanticLabel::Wall;
  wall.surface_type = wall.model_type = QuadricType::Plane;
  wall.pose.linear() << 1, 0, 0, 0, 1, 0, 0, 0, 1;
  wall.pose.translation() = Eigen::Vector3d(10, -5, -2);
  wall.extent.minimum = Eigen::Vector3d(0, 0, 0);
  wall.extent.maximum = Eigen::Vector3d(0, 10, 5);
  add(wall);
  add(unit_sphere("ball", SemanticLabel::Ornament, Eigen::Vector3d(5, 0, 0)));
  ScenePrimitive post;  // vertical cylinder radius 0.5 at (5, 3), z in [-1, 1]
  post.name = "post";
  post.label = SemanticLabel::Pole;
  post.surface_type = post.model_type = QuadricType::CircularCylinder;
  post.scale = Eigen::Vector3d(0.5, 0.5, 0.5);
  post.pose.translation() = Eigen::Vector3d(5, 3, 0);
  post.extent.minimum = Eigen::Vector3d(-0.5, -0.5, -1.0);
  post.extent.maximum = Eigen::Vector3d(0.5, 0.5, 1.0);
  add(post);
  ScenePrimitive cone;  // apex (5, -3, 1), axis +z, 45 degrees, lower nappe c in [-1, 0]
  cone.name = "cone";
  cone.label = SemanticLabel::TrafficCone;
  cone.surface_type = cone.model_type = QuadricType::CircularCone;
  cone.scale = Eigen::Vector3d(1.0, 1.0, 1.0);
  cone.pose.translation() = Eigen::Vector3d(5, -3, 1);
  cone.extent.minimum = Eigen::Vector3d(-1, -1, -1);
  cone.extent.maximum = Eigen::Vector3d(1, 1, 0);
  add(cone);
  return scene;
}

TEST(Sensors, PresetsMatchTheirDatasheets) {
  const SensorModel hdl = sensor_preset("hdl64");
  ASSERT_EQ(hdl.beam_elevations_deg.size(), 64u);
  EXPECT_DOUBLE_EQ(hdl.beam_elevations_deg.front(), 2.0);
  EXPECT_DOUBLE_EQ(hdl.beam_elevations_deg.back(), -24.8);
  EXPECT_EQ(hdl.ray_count(), 128000u);
  const SensorModel vlp = sensor_preset("vlp16");
  EXPECT_EQ(vlp.beam_elevations_deg.size(), 16u);
  EXPECT_EQ(vlp.ray_count(), 16u * 1800u);
  EXPECT_THROW(sensor_preset("hdl32"), Error);
  for (const auto& name : sensor_names()) {
    const SensorModel sensor = sensor_preset(name);
    const auto directions = sensor_ray_directions(sensor);
    EXPECT_EQ(directions.size(), sensor.ray_count()) << name;
    for (const auto& direction : directions) ASSERT_NEAR(direction.norm(), 1.0, 1e-12) << name;
  }
}

TEST(Sensors, LivoxRosetteStaysInItsConeAndDoesNotRepeat) {
  const SensorModel livox = sensor_preset("livox");
  const auto directions = sensor_ray_directions(livox);
  const double half_angle = 0.5 * livox.rosette_field_of_view_deg * kPi / 180.0;
  std::set<std::pair<int, int>> cells;
  for (const auto& direction : directions) {
    ASSERT_GT(direction.x(), 0.0);
    const double azimuth = std::atan2(direction.y(), direction.x());
    const double elevation = std::asin(direction.z());
    ASSERT_LE(std::hypot(azimuth, elevation), half_angle + 1e-9);
    cells.insert({static_cast<int>(std::floor(azimuth * 180.0 / kPi)), static_cast<int>(std::floor(elevation * 180.0 / kPi))});
  }
  // Non-repetitive coverage: a frame spreads over most 1-degree cells of the 70-degree disc.
  const double disc_cells = kPi * 35.2 * 35.2;
  EXPECT_GT(cells.size(), 0.6 * disc_cells);
}

TEST(Sensors, ValidationNamesTheField) {
  SensorModel sensor = sensor_preset("vlp16");
  sensor.range_noise_sigma = -1.0;
  try {
    validate_sensor(sensor);
    FAIL() << "expected quadrix::Error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("range_noise_sigma"), std::string::npos);
  }
  sensor = sensor_preset("vlp16");
  sensor.dropout_probability = 1.0;
  EXPECT_THROW(validate_sensor(sensor), Error);
  sensor = sensor_preset("tls");
  sensor.dome_angular_step_deg = 0.0;
  EXPECT_THROW(validate_sensor(sensor), Error);
}

TEST(RayCaster, HandMadeSceneGivesTheAnalyticHits) {
  const Scene scene = hand_made_scene();
  const RayCaster caster(scene);
  const Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  RayHit hit = caster.cast(origin, Eigen::Vector3d::UnitX(), 0.0, 100.0);
  EXPECT_EQ(hit.primitive, 1);  // the ball occludes the wall
  EXPECT_NEAR(hit.range, 4.0, 1e-12);
  hit = caster.cast(origin, Eigen::Vector3d(10, 4.5, 0).normalized(), 0.0, 100.0);
  EXPECT_EQ(hit.primitive, 0);
  EXPECT_NEAR(hit.range, std::hypot(10.0, 4.5), 1e-12);
  hit = caster.cast(origin, Eigen::Vector3d(10, 6, 2.5).normalized(), 0.0, 100.0);  // over the post, beside the wall
  EXPECT_FALSE(hit.hit());
  hit = caster.cast(origin, Eigen::Vector3d(5, 3, 0).normalized(), 0.0, 100.0);  // post, near side
  EXPECT_EQ(hit.primitive, 2);
  EXPECT_NEAR(hit.range, std::hypot(5.0, 3.0) - 0.5, 1e-12);
  hit = caster.cast(origin, Eigen::Vector3d(5, 3, 1.5).normalized(), 0.0, 100.0);  // above the post's extent
  EXPECT_NE(hit.primitive, 2);
  // Cone: a horizontal ray at z = 0.5 meets the 45-degree cone where its radius is 0.5.
  hit = caster.cast(Eigen::Vector3d(0, -3, 0.5), Eigen::Vector3d::UnitX(), 0.0, 100.0);
  EXPECT_EQ(hit.primitive, 3);
  EXPECT_NEAR(hit.range, 4.5, 1e-12);
  // min/max range: the ball is skipped when nearer than min_range; nothing beyond max_range.
  hit = caster.cast(origin, Eigen::Vector3d::UnitX(), 4.5, 100.0);
  EXPECT_EQ(hit.primitive, 1);  // the far side of the ball at 6
  EXPECT_NEAR(hit.range, 6.0, 1e-12);
  EXPECT_FALSE(caster.cast(origin, Eigen::Vector3d::UnitX(), 0.0, 3.9).hit());
  const auto both = caster.intersect_primitive(1, origin, Eigen::Vector3d::UnitX(), 0.0, 100.0);
  ASSERT_EQ(both.size(), 2u);
  EXPECT_NEAR(both[0], 4.0, 1e-12);
  EXPECT_NEAR(both[1], 6.0, 1e-12);
  EXPECT_THROW(caster.intersect_primitive(9, origin, Eigen::Vector3d::UnitX(), 0.0, 1.0), Error);
}

TEST(RayCaster, RejectsUnsupportedPrimitives) {
  Scene scene = hand_made_scene();
  scene.primitives[1].surface_type = QuadricType::HyperboloidOneSheet;
  EXPECT_THROW(RayCaster{scene}, Error);
  scene = hand_made_scene();
  scene.primitives[2].id = 7;
  EXPECT_THROW(RayCaster{scene}, Error);
}

TEST(RayCaster, HierarchyAgreesWithBruteForce) {
  for (std::uint64_t seed : {3u, 4u}) {
    for (const Scene& scene : {make_street_scene(seed), make_monument_scene(seed), make_corridor_scene(seed)}) {
      const RayCaster caster(scene);
      EXPECT_GT(caster.hierarchy_node_count(), scene.primitives.size());
      std::mt19937_64 engine(seed);
      std::normal_distribution<double> normal;  // only generates test rays; results are compared, not stored
      const Eigen::Vector3d origin = scene.default_lidar_poses[0].translation();
      int hits = 0;
      for (int i = 0; i < 5000; ++i) {
        const Eigen::Vector3d direction = Eigen::Vector3d(normal(engine), normal(engine), normal(engine)).normalized();
        const RayHit fast = caster.cast(origin, direction, 0.0, 150.0);
        const RayHit reference = caster.cast_brute_force(origin, direction, 0.0, 150.0);
        ASSERT_EQ(fast.primitive, reference.primitive) << scene.name << " ray " << i;
        if (fast.hit()) {
          ++hits;
          ASSERT_EQ(fast.range, reference.range);
        }
      }
      EXPECT_GT(hits, 1000) << scene.name;
    }
  }
  // Porous foliage: the hierarchy and brute force stop every ray at the same place inside the crowns
  // and hedges too.
  StreetOptions porous;
  porous.foliage = Foliage::Porous;
  const Scene street = make_street_scene(3, porous);
  const RayCaster caster(street);
  std::mt19937_64 engine(3);
  std::normal_distribution<double> normal;
  const Eigen::Vector3d origin = street.default_lidar_poses[0].translation();
  int foliage_hits = 0;
  for (int i = 0; i < 20000; ++i) {
    const Eigen::Vector3d direction = Eigen::Vector3d(normal(engine), normal(engine), 0.3 * normal(engine)).normalized();
    const RayHit fast = caster.cast(origin, direction, 0.0, 150.0);
    const RayHit reference = caster.cast_brute_force(origin, direction, 0.0, 150.0);
    ASSERT_EQ(fast.primitive, reference.primitive) << "ray " << i;
    if (fast.hit()) {
      ASSERT_EQ(fast.range, reference.range);
      foliage_hits += street.primitives[static_cast<std::size_t>(fast.primitive)].mean_free_path > 0.0;
    }
  }
  EXPECT_GT(foliage_hits, 100);
}

// A porous sphere stops a ray at an exponential depth past its entry (Beer-Lambert): rays through its
// centre pass with probability exp(-chord / mean free path), the stops fall inside the sphere with the
// truncated exponential's mean depth, and one ray always stops at the same place.
TEST(RayCaster, PorousVolumeStopsRaysAtExponentialDepths) {
  Scene scene;
  scene.name = "porous";
  ScenePrimitive crown = unit_sphere("crown", SemanticLabel::Vegetation, Eigen::Vector3d(10, 0, 0));
  crown.mean_free_path = 0.8;
  scene.primitives.push_back(crown);
  const RayCaster caster(scene);
  std::mt19937_64 engine(5);
  std::uniform_real_distribution<double> height(-1e-3, 1e-3);  // distinct rays through the centre
  const int rays = 20000;
  int stopped = 0;
  double depth_sum = 0.0;
  for (int i = 0; i < rays; ++i) {
    const Eigen::Vector3d origin(0.0, height(engine), height(engine));
    const Eigen::Vector3d direction = (Eigen::Vector3d(10, 0, 0) - origin).normalized();
    const RayHit hit = caster.cast(origin, direction, 0.0, 100.0);
    const RayHit again = caster.cast(origin, direction, 0.0, 100.0);
    ASSERT_EQ(hit.primitive, again.primitive);
    if (!hit.hit()) continue;
    ASSERT_EQ(hit.range, again.range);
    ASSERT_GE(hit.range, 9.0 - 1e-6);
    ASSERT_LE(hit.range, 11.0 + 1e-6);
    ++stopped;
    depth_sum += hit.range - 9.0;
  }
  // Chord 2 m, mean free path 0.8 m: P(stop) = 1 - exp(-2.5) = 0.918; the stops' mean depth is
  // l - L e^(-L/l) / (1 - e^(-L/l)) = 0.621 m. Standard errors: 0.0019 and about 0.004 (5 sigma within).
  const double expected_stop = 1.0 - std::exp(-2.0 / 0.8);
  EXPECT_NEAR(static_cast<double>(stopped) / rays, expected_stop, 0.01);
  const double expected_depth = 0.8 - 2.0 * std::exp(-2.0 / 0.8) / expected_stop;
  EXPECT_NEAR(depth_sum / stopped, expected_depth, 0.02);
  // The mesh caster has no porous surfaces and says so.
  EXPECT_THROW(MeshRayCaster(scene, 8), Error);
}

// The meshed alternative (CGAL AABB tree, measured in microbenchmark_simulator) sees the same surfaces: on
// random rays from the sensor almost every ray hits the same primitive at the same range, up to the
// chord error of the mesh; the rest graze primitive edges where a mesh and the exact bounds differ.
TEST(MeshRayCaster, AgreesWithTheExactCasterUpToTheMeshChordError) {
  for (const Scene& scene : {make_street_scene(3), make_monument_scene(3)}) {
    const RayCaster exact(scene);
    const MeshRayCaster meshed(scene, 64);
    EXPECT_GT(meshed.triangle_count(), 1000u * scene.primitives.size() / 10);
    std::mt19937_64 engine(5);
    std::normal_distribution<double> normal;
    const Eigen::Vector3d origin = scene.default_lidar_poses[0].translation();
    int hits = 0, same = 0;
    std::vector<double> range_differences;
    for (int i = 0; i < 4000; ++i) {
      const Eigen::Vector3d direction = Eigen::Vector3d(normal(engine), normal(engine), normal(engine)).normalized();
      const RayHit reference = exact.cast(origin, direction, 0.5, 150.0);
      const RayHit mesh_hit = meshed.cast(origin, direction, 0.5, 150.0);
      if (!reference.hit() && !mesh_hit.hit()) continue;
      ++hits;
      if (reference.primitive != mesh_hit.primitive) continue;
      ++same;
      range_differences.push_back(std::abs(reference.range - mesh_hit.range));
    }
    ASSERT_GT(hits, 1000) << scene.name;
    EXPECT_GE(same, 0.98 * hits) << scene.name << ": " << same << " of " << hits << " rays agree";
    std::sort(range_differences.begin(), range_differences.end());
    EXPECT_LT(range_differences[range_differences.size() / 2], 0.005) << scene.name;
    EXPECT_LT(range_differences[range_differences.size() * 99 / 100], 0.05) << scene.name;
  }
  EXPECT_THROW(MeshRayCaster(make_street_scene(1), 2), Error);
}

struct ScanCheck {
  std::size_t points = 0;
  double worst_distance_ratio = 0.0;
};

/// Every noise-free point lies on the primitive it is labelled with, inside its bounds.
ScanCheck check_points_on_primitives(const Scene& scene, const SimulatedScan& scan) {
  const auto shapes = surface_shapes(scene);
  const auto& ids = scan.cloud.extra_fields.at("primitive_id");
  ScanCheck check;
  for (std::size_t i = 0; i < scan.cloud.size(); ++i) {
    const auto id = static_cast<std::size_t>(ids[i]);
    const ScenePrimitive& primitive = scene.primitives.at(id);
    EXPECT_EQ(scan.cloud.labels[i], static_cast<std::uint32_t>(primitive.label));
    const Eigen::Vector3d sensor_point = scan.cloud.point(i);
    const Eigen::Vector3d world = scan.sensor_pose * sensor_point;
    const double distance = orthogonal_distance(shapes[id], world);
    check.worst_distance_ratio = std::max(check.worst_distance_ratio, distance / float_tolerance(sensor_point));
    EXPECT_TRUE(inside_primitive_bounds(primitive, primitive.pose.inverse() * world, 1e-4)) << primitive.name;
    ++check.points;
  }
  return check;
}

TEST(Simulation, NoiseFreeStreetPointsLieOnTheirPrimitives) {
  const Scene scene = make_street_scene(11);
  const RayCaster caster(scene);
  SensorModel sensor = sensor_preset("hdl64");
  sensor.range_noise_sigma = 0.0;
  sensor.dropout_probability = 0.0;
  const SimulatedScan scan = simulate_scan(scene, caster, sensor, scene.default_lidar_poses[0], 11, 0);
  EXPECT_GT(scan.cloud.size(), 110000u);
  EXPECT_LT(scan.cloud.size(), 128001u);
  const ScanCheck check = check_points_on_primitives(scene, scan);
  EXPECT_LE(check.worst_distance_ratio, 1.0);
  // Bookkeeping: every ray is accounted for and the per-primitive counts match the ids.
  EXPECT_EQ(scan.rays, scan.cloud.size() + scan.misses + scan.too_near + scan.dropped);
  EXPECT_EQ(scan.dropped, 0u);
  std::vector<std::size_t> histogram(scene.primitives.size(), 0);
  for (float id : scan.cloud.extra_fields.at("primitive_id")) ++histogram[static_cast<std::size_t>(id)];
  EXPECT_EQ(histogram, scan.points_per_primitive);
  // A street sweep sees the road, both facade rows, poles, cars and trees.
  std::set<SemanticLabel> seen;
  for (std::uint32_t label : scan.cloud.labels) seen.insert(static_cast<SemanticLabel>(label));
  for (SemanticLabel label : {SemanticLabel::Road, SemanticLabel::Sidewalk, SemanticLabel::Facade, SemanticLabel::Pole,
                              SemanticLabel::Car, SemanticLabel::Kerb})
    EXPECT_TRUE(seen.count(label)) << semantic_label_name(label);
}

TEST(Simulation, EveryScenePatternPutsPointsOnPrimitives) {
  for (const std::string& scene_name : scene_names()) {
    const Scene scene = make_scene(scene_name, 2);
    const RayCaster caster(scene);
    for (const char* sensor_name : {"vlp16", "livox"}) {
      SensorModel sensor = sensor_preset(sensor_name);
      sensor.range_noise_sigma = 0.0;
      const SimulatedScan scan = simulate_scan(scene, caster, sensor, scene.default_lidar_poses[1], 2, 1);
      EXPECT_GT(scan.cloud.size(), sensor.ray_count() / 4) << scene_name << " " << sensor_name;
      EXPECT_LE(check_points_on_primitives(scene, scan).worst_distance_ratio, 1.0) << scene_name << " " << sensor_name;
    }
  }
}

TEST(Simulation, OcclusionIsHonoured) {
  const Scene scene = make_street_scene(21);
  const RayCaster caster(scene);
  SensorModel sensor = sensor_preset("hdl64");
  sensor.range_noise_sigma = 0.0;
  sensor.dropout_probability = 0.0;
  const SimulatedScan scan = simulate_scan(scene, caster, sensor, scene.default_lidar_poses[1], 21, 1);
  const Eigen::Vector3d origin = scan.sensor_pose.translation();
  int checked = 0;
  for (std::size_t i = 0; i < scan.cloud.size(); i += 97) {
    const Eigen::Vector3d world = scan.sensor_pose * scan.cloud.point(i);
    const double range = (world - origin).norm();
    const Eigen::Vector3d direction = (world - origin) / range;
    const auto own = static_cast<std::size_t>(scan.cloud.extra_fields.at("primitive_id")[i]);
    for (std::size_t primitive = 0; primitive < scene.primitives.size(); ++primitive) {
      // No surface crosses the ray before the returned point (float storage: 1e-4 m margin).
      const auto nearer = caster.intersect_primitive(primitive, origin, direction, 0.0, range - 1e-4);
      ASSERT_TRUE(nearer.empty()) << "point " << i << " of " << scene.primitives[own].name << " at " << range
                                  << " m is behind " << scene.primitives[primitive].name << " at " << nearer.front();
    }
    ++checked;
  }
  EXPECT_GT(checked, 1000);
}

TEST(Simulation, NoiseAndDropoutFollowTheirModel) {
  const Scene scene = make_street_scene(5);
  const RayCaster caster(scene);
  SensorModel sensor = sensor_preset("vlp16");
  sensor.range_noise_sigma = 0.05;
  sensor.dropout_probability = 0.2;
  const SimulatedScan scan = simulate_scan(scene, caster, sensor, scene.default_lidar_poses[0], 5, 0);
  const Eigen::Vector3d origin = scan.sensor_pose.translation();
  // Range residual = measured range minus the exact range of the true surface along the same ray.
  double sum = 0.0, squares = 0.0;
  std::size_t count = 0;
  for (std::size_t i = 0; i < scan.cloud.size(); ++i) {
    const Eigen::Vector3d world = scan.sensor_pose * scan.cloud.point(i);
    const double measured = (world - origin).norm();
    const Eigen::Vector3d direction = (world - origin) / measured;
    const RayHit truth = caster.cast(origin, direction, 0.0, 200.0);
    if (!truth.hit() || truth.primitive != static_cast<std::int32_t>(scan.cloud.extra_fields.at("primitive_id")[i]))
      continue;  // float rounding of the direction moved the ray onto a neighbouring surface
    const double residual = measured - truth.range;
    sum += residual;
    squares += residual * residual;
    ++count;
  }
  ASSERT_GT(count, 0.95 * scan.cloud.size());
  const double mean = sum / count, sigma = std::sqrt(squares / count - mean * mean);
  EXPECT_NEAR(mean, 0.0, 5.0 * 0.05 / std::sqrt(count));
  EXPECT_NEAR(sigma, 0.05, 5.0 * 0.05 / std::sqrt(2.0 * count));
  const double returns = static_cast<double>(scan.cloud.size() + scan.dropped);
  EXPECT_NEAR(scan.dropped / returns, 0.2, 5.0 * std::sqrt(0.2 * 0.8 / returns));
}

TEST(Simulation, IdenticalForAnyThreadCount) {
  const Scene scene = make_monument_scene(3);
  const RayCaster caster(scene);
  SensorModel sensor = sensor_preset("tls");
  sensor.dome_angular_step_deg = 1.0;
  const SimulatedScan parallel = simulate_scan(scene, caster, sensor, scene.default_tls_stations[4], 3, 4);
  SimulatedScan serial;
  {
    tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    serial = simulate_scan(scene, caster, sensor, scene.default_tls_stations[4], 3, 4);
  }
  ASSERT_EQ(parallel.cloud.size(), serial.cloud.size());
  EXPECT_TRUE(parallel.cloud.positions == serial.cloud.positions);
  EXPECT_EQ(parallel.cloud.labels, serial.cloud.labels);
  EXPECT_EQ(parallel.points_per_primitive, serial.points_per_primitive);
  // Another scan index draws other noise.
  const SimulatedScan other = simulate_scan(scene, caster, sensor, scene.default_tls_stations[4], 3, 5);
  EXPECT_FALSE(other.cloud.positions == parallel.cloud.positions);
}

TEST(Simulation, MonumentStationsSeeEveryPrimitiveType) {
  const Scene scene = make_monument_scene(1);
  SensorModel sensor = sensor_preset("tls");
  sensor.dome_angular_step_deg = 0.5;
  const SyntheticRun run = run_synthetic(scene, sensor, scene.default_tls_stations, 1);
  ASSERT_EQ(run.scans.size(), 7u);
  std::map<std::string, int> seen_types;
  std::set<std::size_t> seen;
  for (const auto& scan : run.scans)
    for (std::size_t id = 0; id < scan.points_per_primitive.size(); ++id)
      if (scan.points_per_primitive[id] > 0 && seen.insert(id).second)
        ++seen_types[quadric_type_name(scene.primitives[id].model_type)];
  // The survey sees every face, roofs included (the block-roof station).
  EXPECT_EQ(seen_types["sphere"], 3);
  EXPECT_EQ(seen_types["circular_cone"], 1);
  EXPECT_EQ(seen_types["circular_cylinder"], 33);
  EXPECT_EQ(seen_types["plane"], 25);
  // The interior stations see the dome from inside.
  const auto dome = std::find_if(scene.primitives.begin(), scene.primitives.end(),
                                 [](const ScenePrimitive& p) { return p.name == "dome"; });
  EXPECT_GT(run.scans[4].points_per_primitive[dome->id], 1000u);
}

TEST(Simulation, GroundTruthTransformMapsSourceOntoTargetPrimitives) {
  const Scene scene = make_street_scene(9);
  SensorModel sensor = sensor_preset("hdl64");
  sensor.range_noise_sigma = 0.0;
  const SyntheticRun run = run_synthetic(scene, sensor, scene.default_lidar_poses, 9);
  ASSERT_EQ(run.scans.size(), 2u);
  const SimulatedScan& target = run.scans[0];
  const SimulatedScan& source = run.scans[1];
  const Eigen::Isometry3d transform = relative_transform(target.sensor_pose, source.sensor_pose);
  // Every primitive expressed in the target frame.
  std::vector<QuadricDecomposition> in_target;
  for (const auto& primitive : scene.primitives)
    in_target.push_back(surface_quadric(primitive).transformed(target.sensor_pose.inverse()).decompose());
  const auto& ids = source.cloud.extra_fields.at("primitive_id");
  std::size_t shared = 0;
  for (std::size_t i = 0; i < source.cloud.size(); i += 7) {
    const auto id = static_cast<std::size_t>(ids[i]);
    const Eigen::Vector3d mapped = transform * source.cloud.point(i);
    ASSERT_LT(orthogonal_distance(in_target[id], mapped), 1e-5) << scene.primitives[id].name;
    if (target.points_per_primitive[id] > 0) ++shared;
  }
  EXPECT_GT(shared, 0.8 * (source.cloud.size() / 7));
}

std::map<std::string, std::string> folder_bytes(const std::filesystem::path& directory) {
  std::map<std::string, std::string> files;
  for (const auto& entry : std::filesystem::directory_iterator(directory)) {
    std::ifstream stream(entry.path(), std::ios::binary);
    std::ostringstream bytes;
    bytes << stream.rdbuf();
    files[entry.path().filename().string()] = bytes.str();
  }
  return files;
}

TEST(Output, FolderIsSelfDescribingAndByteIdenticalPerSeed) {
  const auto base = std::filesystem::temp_directory_path() / "quadrix_test_synth_output";
  std::filesystem::remove_all(base);
  const SensorModel sensor = sensor_preset("vlp16");
  const auto write = [&](std::uint64_t seed, const std::string& name) {
    const Scene scene = make_street_scene(seed);
    std::vector<Eigen::Isometry3d> poses = scene.default_lidar_poses;
    poses.push_back(scene.default_tls_stations[2]);
    const SyntheticRun run = run_synthetic(scene, sensor, poses, seed);
    return write_synthetic_folder((base / name).string(), run);
  };
  const auto files = write(4, "a");
  write(4, "b");
  write(5, "c");
  const auto a = folder_bytes(base / "a"), b = folder_bytes(base / "b"), c = folder_bytes(base / "c");
  EXPECT_EQ(a, b);
  EXPECT_NE(a.at("primitives.json"), c.at("primitives.json"));
  EXPECT_NE(a.at("scan_000.ply"), c.at("scan_000.ply"));
  // scene.json lists exactly the files of the folder.
  const auto scene_json = nlohmann::json::parse(a.at("scene.json"));
  std::set<std::string> listed;
  for (const auto& file : scene_json.at("files")) listed.insert(file.at("path").get<std::string>());
  std::set<std::string> present;
  for (const auto& [name, bytes] : a) present.insert(name);
  EXPECT_EQ(listed, present);
  EXPECT_EQ(std::set<std::string>(files.begin(), files.end()), present);
  EXPECT_EQ(scene_json.at("pairs").size(), 3u);  // 3 scans -> 3 pairs
  EXPECT_EQ(scene_json.at("scans").size(), 3u);
  // The transform file agrees with the sensor poses and maps SOURCE into TARGET.
  const Eigen::Isometry3d pose0 = read_pose_matrix((base / "a" / "pose_000.txt").string());
  const Eigen::Isometry3d pose2 = read_pose_matrix((base / "a" / "pose_002.txt").string());
  const Eigen::Isometry3d transform = read_pose_matrix((base / "a" / "T_000_from_002.txt").string());
  EXPECT_TRUE((pose0 * transform).matrix().isApprox(pose2.matrix(), 1e-12));
  // The cloud reads back with its labels and primitive ids.
  const PointCloud cloud = read_point_cloud((base / "a" / "scan_001.ply").string());
  const auto primitives = nlohmann::json::parse(a.at("primitives.json")).at("primitives");
  ASSERT_GT(cloud.size(), 10000u);
  ASSERT_EQ(cloud.labels.size(), cloud.size());
  ASSERT_TRUE(cloud.extra_fields.count("primitive_id"));
  for (std::size_t i = 0; i < cloud.size(); i += 101) {
    const auto id = static_cast<std::size_t>(cloud.extra_fields.at("primitive_id")[i]);
    EXPECT_EQ(primitives.at(id).at("label").get<std::uint32_t>(), cloud.labels[i]);
  }
  std::ifstream pairs(base / "a" / "pairs.tsv");
  std::string header;
  std::getline(pairs, header);
  EXPECT_EQ(header, "id\tsource\ttarget\tgt\tgt_quality\tsensor\tkind\tt_m\trot_deg");
  std::filesystem::remove_all(base);
}

TEST(Output, RejectsFormatsThatCannotCarryLabels) {
  const Scene scene = make_corridor_scene(1);
  SensorModel sensor = sensor_preset("vlp16");
  const SyntheticRun run = run_synthetic(scene, sensor, {scene.default_lidar_poses[0]}, 1);
  SyntheticOutputOptions options;
  options.cloud_format = CloudFormat::KittiBin;
  EXPECT_THROW(write_synthetic_folder((std::filesystem::temp_directory_path() / "quadrix_test_bad").string(), run, options),
               Error);
  EXPECT_THROW(run_synthetic(scene, sensor, {}, 1), Error);
}

}  // namespace
}  // namespace quadrix
