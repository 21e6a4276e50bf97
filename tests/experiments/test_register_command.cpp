// Registration presets and the YAML configuration (every key of the table round-trips, unknown keys
// and bad values are errors naming key and file), the `auto` preset on real scans, and the report
// files of `quadrix register --out`.
#include "estimation/overlap.h"
#include "estimation/registration_config.h"
#include "experiments/reports/registration_report.h"
#include "experiments/synthetic/synthetic_output.h"
#include "geometry/error.h"
#include "geometry/io.h"
#include "test_data.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <type_traits>
#include <variant>

namespace quadrix {
namespace {

std::filesystem::path temporary_folder(const std::string& name) {
  const std::filesystem::path folder = std::filesystem::temp_directory_path() / ("quadrix_test_register_" + name);
  std::filesystem::remove_all(folder);
  std::filesystem::create_directories(folder);
  return folder;
}

std::string write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path) << text;
  return path.string();
}

// Sets the member of `key` (of `side` for per-side keys) to a valid value different from its
// current one: bools flipped, numbers changed within the key's range, another valid name, another
// list or axis.
void change_member(const RegistrationConfigKey& key, RegistrationOptions& options, ConfigSide side) {
  std::visit(
      [&key](auto* value) {
        using T = std::remove_pointer_t<decltype(value)>;
        if constexpr (std::is_same_v<T, bool>) {
          *value = !*value;
        } else if constexpr (std::is_same_v<T, int> || std::is_same_v<T, std::size_t>) {
          if (static_cast<double>(*value) + 1.0 <= key.maximum) *value += 1;
          else *value -= 1;
        } else if constexpr (std::is_same_v<T, double>) {
          if (*value + 0.125 <= key.maximum) *value += 0.125;
          else *value -= 0.125;
        } else if constexpr (std::is_same_v<T, std::string>) {
          ASSERT_NE(key.choices, nullptr) << key.path << ": a string key without choices needs a value here";
          const std::vector<std::string> choices = key.choices();
          const auto other = std::find_if(choices.begin(), choices.end(), [&](const std::string& name) { return name != *value; });
          ASSERT_NE(other, choices.end()) << key.path;
          *value = *other;
        } else if constexpr (std::is_same_v<T, std::vector<double>>) {
          *value = {0.15, 0.35, 1.5};
        } else {
          *value = Eigen::Vector3d(0.1, -0.2, 0.97).normalized();
        }
      },
      key.member(options, side));
}

// Whether two members of the same key hold equal values.
bool same_value(const RegistrationConfigMember& a, const RegistrationConfigMember& b) {
  return std::visit([&b](auto* value) { return *value == *std::get<decltype(value)>(b); }, a);
}

// The dotted paths of the leaf keys of block YAML as registration_config_yaml writes it (nested
// mappings indented by 2 spaces, one key per line).
std::vector<std::string> written_key_paths(const std::string& yaml) {
  std::vector<std::string> sections, paths;
  std::istringstream lines(yaml);
  for (std::string line; std::getline(lines, line);) {
    const std::size_t indent = line.find_first_not_of(' ');
    const std::size_t colon = line.find(':');
    if (indent == std::string::npos || line[indent] == '#' || colon == std::string::npos) continue;
    sections.resize(indent / 2);
    const std::string name = line.substr(indent, colon - indent);
    std::string path;
    for (const std::string& section : sections) path += section + ".";
    if (colon + 1 == line.size())
      sections.push_back(name);  // a section: its keys follow, indented
    else
      paths.push_back(path + name);
  }
  return paths;
}

TEST(RegistrationConfig, EveryKeyRoundTripsThroughTheWrittenYaml) {
  const std::filesystem::path folder = temporary_folder("every_key");
  const RegistrationOptions defaults;
  for (const ConfigSide side : {ConfigSide::Source, ConfigSide::Target}) {
    const std::string side_name = side == ConfigSide::Source ? "source" : "target";
    const ConfigSide other_side = side == ConfigSide::Source ? ConfigSide::Target : ConfigSide::Source;
    RegistrationOptions changed;
    for (const RegistrationConfigKey& key : registration_config_keys()) {
      change_member(key, changed, side);
      RegistrationOptions unchanged;
      ASSERT_FALSE(same_value(key.member(changed, side), key.member(unchanged, side))) << key.path;
    }
    const std::string yaml = registration_config_yaml(changed, side_name);
    const std::string file = write_text(folder / (side_name + ".yaml"), yaml);
    RegistrationOptions applied;  // fresh defaults
    apply_registration_config(file, applied, side_name);
    RegistrationOptions fresh;
    for (const RegistrationConfigKey& key : registration_config_keys()) {
      EXPECT_TRUE(same_value(key.member(applied, side), key.member(changed, side))) << side_name << " " << key.path << "\n" << yaml;
      if (key.per_side) {  // the other side keeps its defaults
        EXPECT_TRUE(same_value(key.member(applied, other_side), key.member(fresh, other_side))) << side_name << " " << key.path;
      }
    }
    EXPECT_EQ(registration_config_yaml(applied, side_name), yaml);
  }
  EXPECT_THROW(registration_config_yaml(defaults, "both"), Error);
}

TEST(RegistrationConfig, EveryKeyIsInTheSchemaAndTheWrittenYaml) {
  const std::string schema = registration_config_schema();
  const std::string yaml = registration_config_yaml(RegistrationOptions{});
  std::vector<std::string> table;
  for (const RegistrationConfigKey& key : registration_config_keys()) {
    table.push_back(key.path);
    EXPECT_NE(schema.find("\n" + key.path + " "), std::string::npos) << key.path << "\n" << schema;
    EXPECT_FALSE(key.description.empty()) << key.path;
    EXPECT_NE(key.member, nullptr) << key.path;
  }
  EXPECT_EQ(written_key_paths(yaml), table) << yaml;  // every key once, in table order
  std::vector<std::string> unique = table;
  std::sort(unique.begin(), unique.end());
  EXPECT_EQ(std::unique(unique.begin(), unique.end()), unique.end()) << "a key is listed twice";
}

// Characteristic values of every preset, as `quadrix config --preset NAME` prints them, and every
// preset's printed configuration reading back to that preset.
TEST(RegistrationConfig, PresetsKeepTheirValues) {
  const RegistrationOptions vlp64 = registration_preset("vlp64");
  EXPECT_DOUBLE_EQ(vlp64.source_extraction.planes.voxel_size, 1.0);
  EXPECT_DOUBLE_EQ(vlp64.target_extraction.planes.eigenvalue_ratio, 30.0);
  EXPECT_DOUBLE_EQ(vlp64.source_extraction.minimum_range, 2.0);
  EXPECT_EQ(vlp64.modelling.fitter, "statistical");
  const RegistrationOptions vlp16 = registration_preset("vlp16");
  EXPECT_DOUBLE_EQ(vlp16.source_extraction.planes.voxel_size, 1.4);
  EXPECT_DOUBLE_EQ(vlp16.target_extraction.planes.merge_distance, 0.28);
  EXPECT_DOUBLE_EQ(vlp16.source_extraction.planes.eigenvalue_ratio, 16.0);
  const RegistrationOptions mid360 = registration_preset("mid360");
  EXPECT_DOUBLE_EQ(mid360.source_extraction.planes.voxel_size, 1.2);
  EXPECT_DOUBLE_EQ(mid360.target_extraction.minimum_range, 0.5);
  EXPECT_FALSE(mid360.source_extraction.trunks.enabled);
  EXPECT_DOUBLE_EQ(mid360.source_extraction.planes.cluster_plane_width, 0.5);
  const RegistrationOptions avia = registration_preset("avia");
  EXPECT_DOUBLE_EQ(avia.source_extraction.planes.merge_distance, 0.22);
  EXPECT_DOUBLE_EQ(avia.target_extraction.planes.eigenvalue_ratio, 20.0);
  EXPECT_DOUBLE_EQ(avia.source_extraction.planes.cluster_plane_area, 2.0);
  // The sparse and forward-looking presets keep the default margins: the free-space check catches
  // the mirror images and shifts along a street they once needed their own margins for.
  for (const RegistrationOptions* preset : {&avia, &mid360, &vlp16}) {
    EXPECT_DOUBLE_EQ(preset->dense_search.ok_margin, DenseSearchOptions{}.ok_margin);
    EXPECT_DOUBLE_EQ(preset->ambiguity.half_turn_ok_margin, AmbiguityOptions{}.half_turn_ok_margin);
    EXPECT_DOUBLE_EQ(preset->ambiguity.free_space_limit, AmbiguityOptions{}.free_space_limit);
  }
  const RegistrationOptions monument = registration_preset("monument");
  EXPECT_TRUE(monument.source_extraction.static_scan);
  EXPECT_DOUBLE_EQ(monument.target_extraction.maximum_range, 0.0);
  EXPECT_EQ(monument.modelling.fitter, "constrained");
  EXPECT_EQ(monument.source_extraction.shapes.minimum_points, 60);
  EXPECT_LT(monument.ambiguity.free_space_limit, 0.0) << "merged stations have no single sensor's free space";
  EXPECT_DOUBLE_EQ(vlp64.ambiguity.free_space_limit, AmbiguityOptions{}.free_space_limit);
  // Every preset's printed configuration, applied over another preset, gives that preset back.
  const std::filesystem::path folder = temporary_folder("presets");
  for (const std::string& name : registration_preset_names()) {
    const std::string yaml = registration_config_yaml(registration_preset(name));
    const std::string file = write_text(folder / (name + ".yaml"), yaml);
    RegistrationOptions applied = registration_preset(name == "vlp16" ? "monument" : "vlp16");
    apply_registration_config(file, applied);
    EXPECT_EQ(registration_config_yaml(applied, "target"), yaml) << name;
    EXPECT_EQ(applied.source_extraction.preset, name);
  }
}

TEST(RegistrationConfig, OverridesApplyPerSideAndUnknownKeysNameKeyAndFile) {
  const std::filesystem::path folder = temporary_folder("config");
  const std::string good = write_text(folder / "good.yaml",
                                      "sensor: vlp16\nextraction:\n  planes:\n    voxel_size: 2.5\n"
                                      "matching:\n  thresholds: [0.3, 0.9]\nestimation:\n  refiner: nlopt\n");
  RegistrationOptions options = registration_preset("vlp64");
  apply_registration_config(good, options, "target");
  EXPECT_EQ(options.source_extraction.preset, "vlp64");
  EXPECT_DOUBLE_EQ(options.source_extraction.planes.voxel_size, 1.0);
  EXPECT_EQ(options.target_extraction.preset, "vlp16");
  EXPECT_DOUBLE_EQ(options.target_extraction.planes.voxel_size, 2.5);
  EXPECT_EQ(options.graphs.thresholds, (std::vector<double>{0.3, 0.9}));
  EXPECT_EQ(options.estimation.refiner, "nlopt");
  // `sensor` restarts the extraction before the other keys, wherever it stands in the file.
  const std::string sensor_last = write_text(folder / "sensor_last.yaml", "extraction:\n  planes:\n    voxel_size: 2.5\nsensor: mid360\n");
  RegistrationOptions restarted = registration_preset("vlp64");
  apply_registration_config(sensor_last, restarted);
  for (const ExtractionOptions* side : {&restarted.source_extraction, &restarted.target_extraction}) {
    EXPECT_EQ(side->preset, "mid360");
    EXPECT_DOUBLE_EQ(side->planes.voxel_size, 2.5);
    EXPECT_DOUBLE_EQ(side->planes.merge_distance, 0.25);
  }

  const auto expect_error_naming = [&](const std::string& file_name, const std::string& text, const std::string& needle) {
    const std::string path = write_text(folder / file_name, text);
    RegistrationOptions ignored;
    try {
      apply_registration_config(path, ignored);
      ADD_FAILURE() << "no error for " << text;
    } catch (const Error& error) {
      const std::string message = error.what();
      EXPECT_NE(message.find(path), std::string::npos) << message;
      EXPECT_NE(message.find(needle), std::string::npos) << message;
    }
  };
  expect_error_naming("unknown_top.yaml", "colour: red\n", "'colour'");
  expect_error_naming("unknown_nested.yaml", "extraction:\n  planes:\n    voxle_size: 1\n", "'extraction.planes.voxle_size'");
  expect_error_naming("bad_type.yaml", "modelling:\n  quadrics_per_class: many\n", "'modelling.quadrics_per_class'");
  expect_error_naming("bad_sensor.yaml", "sensor: hdl999\n", "'sensor'");
  expect_error_naming("bad_thresholds.yaml", "matching:\n  thresholds: [0.5, 0.2]\n", "'matching.thresholds'");
  expect_error_naming("bad_refiner.yaml", "estimation:\n  refiner: gauss\n", "'estimation.refiner'");
  expect_error_naming("bad_voxel.yaml", "dense_search:\n  voxel_size: 0\n", "'dense_search.voxel_size'");
  expect_error_naming("bad_fitter.yaml", "modelling:\n  fitter: magic\n", "'modelling.fitter'");
  expect_error_naming("zero_up.yaml", "extraction:\n  up: [0, 0, 0]\n", "'extraction.up'");
  expect_error_naming("short_up.yaml", "extraction:\n  up: [0, 1]\n", "'extraction.up'");
  expect_error_naming("scalar_section.yaml", "extraction:\n  planes: 3\n", "'extraction.planes'");
  expect_error_naming("list_for_number.yaml", "selection:\n  dcs_phi: [1, 2]\n", "'selection.dcs_phi'");
  expect_error_naming("negative_isolation.yaml", "extraction:\n  isolation_cell: -0.3\n", "'extraction.isolation_cell' must lie in [0.01, 100] or 0");
  expect_error_naming("no_neighbours.yaml", "extraction:\n  isolation_neighbours: 0\n", "'extraction.isolation_neighbours' must lie in [1, 1000]");
  expect_error_naming("no_check_neighbours.yaml", "ambiguity:\n  isolation_neighbours: 0\n", "'ambiguity.isolation_neighbours' must lie in [1, 1000]");
  expect_error_naming("low_free_space.yaml", "ambiguity:\n  free_space_height: -1\n", "'ambiguity.free_space_height' must lie in [0, 100]");
  expect_error_naming("nan_ground_tilt.yaml", "ambiguity:\n  ground_tilt_limit_deg: .nan\n", "ambiguity.ground_tilt_limit_deg' must be a finite number");
  expect_error_naming("nan_free_space.yaml", "ambiguity:\n  free_space_limit: .nan\n", "key 'ambiguity.free_space_limit' must be a finite number");
  expect_error_naming("no_lever_arm.yaml", "estimation:\n  level_ground_lever_arm_m: 0\n", "'estimation.level_ground_lever_arm_m' must lie in [0.001, ");
  expect_error_naming("gain_above_one.yaml", "ambiguity:\n  confirm_over_identity: 1.5\n", "'ambiguity.confirm_over_identity' must lie in [0, 1]");
  RegistrationOptions ignored;
  EXPECT_THROW(apply_registration_config((folder / "missing.yaml").string(), ignored), Error);
  EXPECT_THROW(registration_preset("hdl999"), Error);
}

// Crash reproducers of fuzz_registration_config (tests/fuzz/regressions/registration_config/): each
// is now an Error naming the file and what was wrong, not an escaping YAML exception.
TEST(RegistrationConfig, FuzzRegressionsGiveErrorsNamingTheFile) {
  const auto expect_error = [](const std::string& name, const std::string& detail) {
    const std::string path = testing::fuzz_regression_path("registration_config", name);
    RegistrationOptions options;
    try {
      apply_registration_config(path, options);
      ADD_FAILURE() << name << " was accepted";
    } catch (const Error& error) {
      EXPECT_NE(std::string(error.what()).find(path), std::string::npos) << error.what();
      EXPECT_NE(std::string(error.what()).find(detail), std::string::npos) << error.what();
    }
  };
  // `{up:,[0 1]}` makes a list a key: YAML::TypedBadConversion escaped from the key's as<std::string>().
  expect_error("list_as_key.yaml", "line 1: a key in 'extraction' is a list, a mapping or empty; keys are names");
  // -.inf was accepted, and registration_config_yaml wrote "-inf", which does not read back.
  expect_error("epsilon_minus_inf.yaml", "key 'extraction.shapes.epsilon' must be a finite number, got '-.inf'");
  // up: [1e308, 1e308, 0] overflowed the squared norm and was normalised to the zero vector.
  RegistrationOptions options;
  apply_registration_config(testing::fuzz_regression_path("registration_config", "up_norm_overflows.yaml"), options);
  for (const ExtractionOptions* side : {&options.source_extraction, &options.target_extraction})
    EXPECT_TRUE(side->up.isApprox(Eigen::Vector3d(1, 1, 0).normalized(), 1e-15)) << side->up.transpose();
}

TEST(RegistrationConfig, AutoPresetChoosesFromMeasuredCloudProperties) {
  // A synthetic 16-ring spinning scan and a synthetic 70-degree non-repetitive scan.
  PointCloud rings;
  PointCloud narrow;
  std::vector<Eigen::Vector3f> ring_points;
  for (int ring = 0; ring < 16; ++ring)
    for (int step = 0; step < 1800; ++step) {
      const double elevation = (-15.0 + 2.0 * ring) * M_PI / 180.0;
      const double azimuth = step * 2.0 * M_PI / 1800.0;
      const double range = 20.0 + 5.0 * std::sin(3.0 * azimuth);
      ring_points.emplace_back(range * std::cos(elevation) * std::cos(azimuth), range * std::cos(elevation) * std::sin(azimuth),
                               range * std::sin(elevation));
    }
  rings.positions.resize(3, static_cast<Eigen::Index>(ring_points.size()));
  for (std::size_t i = 0; i < ring_points.size(); ++i) rings.positions.col(static_cast<Eigen::Index>(i)) = ring_points[i];
  EXPECT_EQ(guess_sensor_preset(rings).preset, "vlp16") << guess_sensor_preset(rings).reason;
  EXPECT_EQ(guess_sensor_preset(rings).ring_count, 16);

  narrow.positions.resize(3, 20000);
  for (int i = 0; i < 20000; ++i) {
    const double azimuth = (-35.0 + 70.0 * ((i * 7919) % 20000) / 20000.0) * M_PI / 180.0;
    const double elevation = (-35.0 + 70.0 * ((i * 104729) % 20000) / 20000.0) * M_PI / 180.0;
    narrow.positions.col(i) = Eigen::Vector3f(static_cast<float>(30.0 * std::cos(elevation) * std::cos(azimuth)),
                                              static_cast<float>(30.0 * std::cos(elevation) * std::sin(azimuth)),
                                              static_cast<float>(30.0 * std::sin(elevation)));
  }
  EXPECT_EQ(guess_sensor_preset(narrow).preset, "avia") << guess_sensor_preset(narrow).reason;
  EXPECT_EQ(guess_sensor_preset(PointCloud{}).preset, "vlp64");
}

TEST(RegistrationConfig, AutoPresetOnRealScans) {
  QUADRIX_REQUIRE_SHARED_DATA("kitti00/velodyne/000000.bin");
  const SensorGuess kitti = guess_sensor_preset(read_point_cloud(testing::shared_data_path("kitti00/velodyne/000000.bin")));
  std::printf("kitti 000000: %s\n", kitti.reason.c_str());
  EXPECT_EQ(kitti.preset, "vlp64") << kitti.reason;
  for (const auto& [file, expected] : std::vector<std::pair<std::string, std::string>>{
           {"quadricsreg_demo/vlp16_source.ply", "vlp16"}, {"quadricsreg_demo/avia_source.ply", "avia"},
           {"quadricsreg_demo/mid360_source.ply", "mid360"}}) {
    if (!std::filesystem::exists(testing::shared_data_path(file))) continue;
    const SensorGuess guess = guess_sensor_preset(read_point_cloud(testing::shared_data_path(file)));
    std::printf("%s: %s\n", file.c_str(), guess.reason.c_str());
    EXPECT_EQ(guess.preset, expected) << file << ": " << guess.reason;
  }
}

// `cloud` with `fraction` of its point count added uniformly over its bounding box (as
// `quadrix bench --corrupt outliers-P` does).
PointCloud with_uniform_outliers(const PointCloud& cloud, double fraction, std::uint32_t seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  const Eigen::Vector3f low = cloud.positions.rowwise().minCoeff(), high = cloud.positions.rowwise().maxCoeff();
  const Eigen::Index count = cloud.positions.cols(), added = static_cast<Eigen::Index>(fraction * static_cast<double>(count));
  PointCloud noisy;
  noisy.positions.resize(3, count + added);
  noisy.positions.leftCols(count) = cloud.positions;
  for (Eigen::Index i = 0; i < added; ++i)
    noisy.positions.col(count + i) = low + Eigen::Vector3f(unit(random), unit(random), unit(random)).cwiseProduct(high - low);
  return noisy;
}

// Spurious returns spread through the scene widen a spinning scanner's elevation span: measured on
// every point, a VLP-16 scan under 30% uniform outliers spans more than 35 deg and was taken for a
// Mid-360. auto measures the points that keep company, and both spinning heads keep their preset.
TEST(RegistrationConfig, AutoPresetIgnoresUniformOutliers) {
  for (const auto& [file, expected] : std::vector<std::pair<std::string, std::string>>{
           {"kitti00/velodyne/000000.bin", "vlp64"}, {"quadricsreg_demo/vlp16_source.ply", "vlp16"}}) {
    if (!std::filesystem::exists(testing::shared_data_path(file))) GTEST_SKIP() << "absent: " << file;
    const PointCloud clean = read_point_cloud(testing::shared_data_path(file));
    for (const double fraction : {0.1, 0.3, 0.5}) {
      const SensorGuess guess = guess_sensor_preset(with_uniform_outliers(clean, fraction, 7));
      std::printf("%s + %.0f%% outliers: %s\n", file.c_str(), 100.0 * fraction, guess.reason.c_str());
      EXPECT_EQ(guess.preset, expected) << file << " + " << fraction << ": " << guess.reason;
      EXPECT_NE(guess.reason.find("isolated left out"), std::string::npos) << guess.reason;
      EXPECT_LT(guess.elevation_span_degrees, 35.0) << file << " + " << fraction;
    }
  }
}

// Rotates every point of `cloud` by `rotation` (a tilted mount of the same sensor).
PointCloud rotated(PointCloud cloud, const Eigen::Matrix3d& rotation) {
  cloud.positions = (rotation.cast<float>() * cloud.positions).eval();
  return cloud;
}

TEST(RegistrationConfig, AutoPresetMeasuresTheUpAxisOfTiltedScans) {
  QUADRIX_REQUIRE_SHARED_DATA("kitti00/velodyne/000000.bin");
  const PointCloud level = read_point_cloud(testing::shared_data_path("kitti00/velodyne/000000.bin"));
  const UpDirectionEstimate upright = estimate_up_direction(level);
  std::printf("kitti 000000: %s\n", upright.reason.c_str());
  ASSERT_TRUE(upright.found);
  EXPECT_LT(upright.tilt_degrees, 3.0) << upright.reason;  // the HDL-64E is mounted level
  for (const auto& [axis, degrees] : std::vector<std::pair<Eigen::Vector3d, double>>{
           {Eigen::Vector3d::UnitX(), 25.0}, {Eigen::Vector3d(1, 1, 0).normalized(), -35.0}, {Eigen::Vector3d::UnitY(), 15.0}}) {
    const Eigen::Matrix3d tilt = Eigen::AngleAxisd(degrees * M_PI / 180.0, axis).toRotationMatrix();
    const UpDirectionEstimate estimate = estimate_up_direction(rotated(level, tilt));
    const double error = std::acos(std::clamp(estimate.up.dot(tilt * upright.up), -1.0, 1.0)) * 180.0 / M_PI;
    EXPECT_LT(error, 2.0) << degrees << " deg tilt: " << estimate.reason;
    EXPECT_NEAR(estimate.tilt_degrees, std::abs(degrees), 3.0) << estimate.reason;
  }
}

// Unit normal of the road (label 40) points of a simulated scan, oriented up: the ground truth
// of the up axis in the sensor frame.
Eigen::Vector3d road_normal(const PointCloud& scan) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
  double count = 0.0;
  for (std::size_t i = 0; i < scan.size(); ++i)
    if (scan.labels[i] == static_cast<std::uint32_t>(SemanticLabel::Road)) {
      sum += scan.point(i);
      outer += scan.point(i) * scan.point(i).transpose();
      count += 1.0;
    }
  const Eigen::Vector3d mean = sum / count;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(outer / count - mean * mean.transpose());
  const Eigen::Vector3d normal = solver.eigenvectors().col(0);
  return normal.z() < 0.0 ? Eigen::Vector3d(-normal) : normal;
}

TEST(RegistrationConfig, AutoUpAxisFollowsTheGroundOfSimulatedStreetsForEverySensor) {
  // A 16-ring scanner's ground voxels mostly hold one scan line each, whose PCA normal leans by the
  // beam's elevation: the mean of voxel normals came out 2-9 deg off on every such scan. The up
  // axis is now fitted to the points of the fullest plane; on 137 scans of the tuning set it is
  // within 1.2 deg of the road for every sensor (a kerb can tilt it by up to ~1 deg).
  for (const char* sensor_name : {"vlp16", "hdl64", "livox"}) {
    const SensorModel sensor = sensor_preset(sensor_name);
    for (const std::uint64_t seed : {11u, 12u, 13u}) {
      const Scene scene = make_street_scene(seed);
      const SyntheticRun run = run_synthetic(scene, sensor, scene.default_lidar_poses, seed);
      for (const SimulatedScan& scan : run.scans) {
        const UpDirectionEstimate estimate = estimate_up_direction(scan.cloud);
        const double error = std::acos(std::clamp(estimate.up.dot(road_normal(scan.cloud)), -1.0, 1.0)) * 180.0 / M_PI;
        std::printf("%s street %llu: %.2f deg from the road; %s\n", sensor_name, static_cast<unsigned long long>(seed), error,
                    estimate.reason.c_str());
        EXPECT_TRUE(estimate.found) << estimate.reason;
        EXPECT_LT(error, 2.0) << sensor_name << " street " << seed << ": " << estimate.reason;
      }
    }
  }
}

TEST(RegistrationConfig, AutoPresetRegistersATiltedSourceScan) {
  QUADRIX_REQUIRE_SHARED_DATA("kitti00/velodyne/000000.bin");
  // kitti00_lc_0_4438 of pairs.tsv with the source sensor tilted by 20 deg: T_gt' = T_gt * tilt^-1.
  const Eigen::Matrix3d tilt = Eigen::AngleAxisd(20.0 * M_PI / 180.0, Eigen::Vector3d(0.6, 0.8, 0.0)).toRotationMatrix();
  const PointCloud source = rotated(read_point_cloud(testing::shared_data_path("kitti00/velodyne/000000.bin")), tilt);
  const PointCloud target = read_point_cloud(testing::shared_data_path("kitti00/velodyne/004438.ply"));
  Eigen::Isometry3d truth = read_pose_matrix(testing::shared_data_path("kitti00/gt/T_004438_from_000000.txt"));
  truth = truth * Eigen::Isometry3d(tilt.transpose());
  std::string notes;
  const RegistrationOptions options = resolve_registration_options("auto", source, "auto", target, &notes);
  std::printf("%s\n", notes.c_str());
  EXPECT_LT(std::acos(std::clamp(options.source_extraction.up.dot(tilt * Eigen::Vector3d::UnitZ()), -1.0, 1.0)) * 180.0 / M_PI, 3.0);
  const RegistrationResult result = register_clouds(source, target, options);
  const double rte = translation_error(result.transform, truth);
  const double rre = rotation_error_degrees(result.transform, truth);
  std::printf("tilted source: status %s, RTE %.3f m, RRE %.3f deg\n", registration_status_name(result.status), rte, rre);
  EXPECT_EQ(result.status, RegistrationStatus::Ok) << result.message;
  EXPECT_TRUE(registration_succeeded(result.transform, truth)) << "RTE " << rte << " m, RRE " << rre << " deg";
}

TEST(RegistrationReport, JsonFollowsTheContractAndPicturesAreWritten) {
  RegistrationResult result;
  result.status = RegistrationStatus::Ok;
  result.transform = Eigen::Isometry3d::Identity();
  result.transform.translation() = Eigen::Vector3d(1.0, 2.0, 3.0);
  result.timings_ms = {{"modelling_source", 10.0}, {"modelling_target", 11.0}, {"correspondences", 1.0}, {"graphs", 0.5},
                       {"cliques", 0.4}, {"estimation", 3.0}, {"selection", 0.2}, {"total", 26.1}};
  result.counts.correspondences = 42;
  result.counts.clique_sizes = {5, 7};
  RegistrationCandidate first;
  first.score.score = std::numeric_limits<double>::infinity();  // unscored -> null
  RegistrationCandidate second;
  second.level = 1;
  second.valid = true;
  second.score.score = 0.25;
  second.transform = result.transform;
  result.candidates = {first, second};
  result.best_candidate = 1;
  RegistrationReportContext context;
  context.total_ms = 40.0;
  context.load_ms = 13.9;
  context.ground_truth = Eigen::Isometry3d::Identity();

  const nlohmann::json report = nlohmann::json::parse(registration_report_json(result, context));
  ASSERT_EQ(report["transform"].size(), 4u);
  EXPECT_DOUBLE_EQ(report["transform"][1][3].get<double>(), 2.0);
  EXPECT_DOUBLE_EQ(report["transform"][3][3].get<double>(), 1.0);
  EXPECT_EQ(report["status"], "ok");
  EXPECT_DOUBLE_EQ(report["timings_ms"]["total"].get<double>(), 40.0);
  for (const char* stage : {"load", "modelling_source", "modelling_target", "correspondences", "graphs", "cliques",
                            "estimation", "selection", "registration"})
    EXPECT_TRUE(report["timings_ms"].contains(stage)) << stage;
  EXPECT_EQ(report["counts"]["correspondences"], 42);
  ASSERT_EQ(report["candidates"].size(), 2u);
  EXPECT_TRUE(report["candidates"][0]["score"].is_null());
  EXPECT_TRUE(report["candidates"][1]["selected"].get<bool>());
  EXPECT_NEAR(report["ground_truth"]["rte_m"].get<double>(), std::sqrt(14.0), 1e-12);
  EXPECT_TRUE(report["ground_truth"]["success"].is_boolean());
  EXPECT_FALSE(report.contains("dense_search")) << "only when the search ran";

  DenseSearchResult search;
  search.weakest_direction = Eigen::Vector3d(0.0, 1.0, 0.0);
  search.optima.resize(2);
  search.optima[1].start = "answer+2.0m";
  search.optima[1].overlap = 0.625;
  search.best = 1;
  search.rival = 0;
  search.margin = 0.5;
  result.dense_search = search;
  const nlohmann::json searched = nlohmann::json::parse(registration_report_json(result, context));
  ASSERT_EQ(searched["dense_search"]["optima"].size(), 2u);
  EXPECT_EQ(searched["dense_search"]["optima"][1]["start"], "answer+2.0m");
  EXPECT_DOUBLE_EQ(searched["dense_search"]["optima"][1]["overlap"].get<double>(), 0.625);
  EXPECT_EQ(searched["dense_search"]["best"], 1);
  EXPECT_EQ(searched["dense_search"]["rival"], 0);
  EXPECT_DOUBLE_EQ(searched["dense_search"]["weakest_direction"][1].get<double>(), 1.0);
  EXPECT_FALSE(searched.contains("ground_correlation")) << "only when the correlation ran";
  GroundPose pose;
  pose.share = 0.375;
  pose.yaw_degrees = -90.0;
  pose.transform.translation() = Eigen::Vector3d(12.0, 0.5, 0.0);
  result.ground_correlation = {pose};
  const nlohmann::json correlated = nlohmann::json::parse(registration_report_json(result, context));
  ASSERT_EQ(correlated["ground_correlation"].size(), 1u);
  EXPECT_DOUBLE_EQ(correlated["ground_correlation"][0]["share"].get<double>(), 0.375);
  EXPECT_DOUBLE_EQ(correlated["ground_correlation"][0]["yaw_deg"].get<double>(), -90.0);
  EXPECT_DOUBLE_EQ(correlated["ground_correlation"][0]["transform"][0][3].get<double>(), 12.0);

  PointCloud source;
  source.positions = Eigen::Matrix3Xf::Random(3, 500) * 20.0f;
  PointCloud target = source;
  const std::filesystem::path folder = temporary_folder("report");
  write_registration_report((folder / "report.json").string(), result, context);
  write_birds_eye_png((folder / "bev.png").string(), source, target, result.transform);
  const PointCloud merged = merge_aligned_clouds(source, target, result.transform);
  ASSERT_EQ(merged.size(), 1000u);
  EXPECT_TRUE(merged.positions.col(500).isApprox(source.positions.col(0) + Eigen::Vector3f(1, 2, 3)));
  EXPECT_EQ(merged.colors[0], (std::array<std::uint8_t, 3>{160, 160, 160}));
  write_point_cloud((folder / "merged.ply").string(), merged);
  std::ifstream png(folder / "bev.png", std::ios::binary);
  char magic[8] = {};
  png.read(magic, 8);
  EXPECT_EQ(std::string(magic + 1, 3), "PNG");
  EXPECT_TRUE(std::filesystem::exists(folder / "report.json"));
  EXPECT_EQ(read_point_cloud((folder / "merged.ply").string()).size(), 1000u);
}

TEST(RegistrationReport, OverlapCountsSourcePointsLandingOnTheTargetAboveTheGround) {
  // Target: 3000 points of a 20 m box above a ground at z = 0, plus 2000 ground points. Source: the
  // same scene seen from 8 m away and rotated 30 deg, so the right transform overlaps everything.
  PointCloud target;
  target.positions.resize(3, 5000);
  target.positions.leftCols(3000) = (Eigen::Matrix3Xf::Random(3, 3000).array() + 1.0f) * 10.0f;
  target.positions.leftCols(3000).row(2).array() += 1.0f;  // at least 1 m above the ground
  target.positions.rightCols(2000) = Eigen::Matrix3Xf::Random(3, 2000) * 20.0f;
  target.positions.rightCols(2000).row(2).setZero();
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();
  transform.linear() = Eigen::AngleAxisd(M_PI / 6.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  transform.translation() = Eigen::Vector3d(8.0, 0.0, 0.0);
  PointCloud source;
  source.positions = (transform.inverse().cast<float>() * target.positions).eval();
  const OverlapMeasure right = measure_overlap(source, target, transform, Eigen::Vector4d(0, 0, 1, 0));
  EXPECT_EQ(right.sampled, 3000u);  // the ground points are skipped
  EXPECT_DOUBLE_EQ(right.transformed, 1.0);
  EXPECT_LT(right.identity, 0.5);  // 3000 random points in 8000 m^3 rarely sit within 0.3 m of each other
  const OverlapMeasure with_ground = measure_overlap(source, target, transform);
  EXPECT_EQ(with_ground.sampled, 5000u);
  Eigen::Isometry3d off = transform;
  off.translation().x() += 1.0;  // 1 m off: the sparse box no longer lines up
  EXPECT_LT(measure_overlap(source, target, off, Eigen::Vector4d(0, 0, 1, 0)).transformed, 0.5);
  EXPECT_THROW(measure_overlap(source, target, transform, std::nullopt, 0.0), Error);
}

TEST(RegistrationReport, IsolatedPointsAreLeftOutAndScannedSurfacesKept) {
  // A wall sampled every 5 cm, one far scan line every 25 cm (a sparse surface at range), a pair of
  // points 20 cm apart alone in space, a NaN, and 300 points uniformly spread over a 200 m cube.
  std::vector<Eigen::Vector3f> points;
  for (int i = 0; i < 100; ++i)
    for (int j = 0; j < 40; ++j) points.emplace_back(0.05f * static_cast<float>(i), 10.0f, 0.05f * static_cast<float>(j));
  const std::size_t wall = points.size();
  for (int i = 0; i < 40; ++i) points.emplace_back(0.25f * static_cast<float>(i), 60.0f, 3.0f);
  points.emplace_back(-50.0f, -50.0f, 5.0f);
  points.emplace_back(-50.2f, -50.0f, 5.0f);
  points.emplace_back(std::nanf(""), 0.0f, 0.0f);
  const std::size_t surfaces = points.size() - 1;
  std::mt19937 random(5);
  std::uniform_real_distribution<float> anywhere(-100.0f, 100.0f);
  const std::size_t strays = 300;
  for (std::size_t i = 0; i < strays; ++i) points.emplace_back(anywhere(random), anywhere(random), anywhere(random) + 300.0f);
  PointCloud cloud;
  cloud.positions.resize(3, static_cast<Eigen::Index>(points.size()));
  for (std::size_t i = 0; i < points.size(); ++i) cloud.positions.col(static_cast<Eigen::Index>(i)) = points[i];
  cloud.intensity.assign(points.size(), 1.0f);

  const PointCloud kept = without_isolated_points(cloud, 0.3);
  // Every surface point stays, in order; of the strays (one per 26,700 m^3) none has company within
  // the 0.9 m block, so all go, and so does the NaN.
  ASSERT_EQ(kept.size(), surfaces);
  for (std::size_t i = 0; i < surfaces; ++i) EXPECT_EQ(kept.positions.col(static_cast<Eigen::Index>(i)), cloud.positions.col(static_cast<Eigen::Index>(i))) << i;
  EXPECT_TRUE(kept.intensity.empty());  // only positions are kept
  // The overlap's hash of a target applies the same rule with its own cells, and its isolated
  // points then cover nothing.
  TargetCoverage coverage(cloud, 0.3);
  const Eigen::Vector3d stray = cloud.point(surfaces + 1), on_wall(1.0, 10.0, 1.0);
  EXPECT_TRUE(coverage.covers(stray));
  const std::vector<Eigen::Index> hashed_kept = coverage.leave_out_isolated_points();
  ASSERT_EQ(hashed_kept.size(), surfaces);
  for (std::size_t i = 0; i < surfaces; ++i) EXPECT_EQ(hashed_kept[i], static_cast<Eigen::Index>(i));
  EXPECT_FALSE(coverage.covers(stray));
  EXPECT_TRUE(coverage.covers(on_wall));
  // Asking for two neighbours: the pair alone in space goes, every wall point stays, and the hash
  // keeps the very points the count map keeps.
  const PointCloud two = without_isolated_points(cloud, 0.3, 2);
  TargetCoverage coverage_two(cloud, 0.3);
  const std::vector<Eigen::Index> hashed_two = coverage_two.leave_out_isolated_points(2);
  ASSERT_EQ(hashed_two.size(), two.size());
  for (std::size_t k = 0; k < hashed_two.size(); ++k) EXPECT_EQ(two.positions.col(static_cast<Eigen::Index>(k)), cloud.positions.col(hashed_two[k])) << k;
  EXPECT_GE(hashed_two.size(), wall);
  EXPECT_EQ(hashed_two[wall - 1], static_cast<Eigen::Index>(wall - 1));
  EXPECT_EQ(std::count_if(hashed_two.begin(), hashed_two.end(), [&](Eigen::Index i) { return i == static_cast<Eigen::Index>(wall + 40) || i == static_cast<Eigen::Index>(wall + 41); }), 0);
  EXPECT_FALSE(coverage_two.covers(cloud.point(wall + 40)));
  EXPECT_THROW(TargetCoverage(cloud, 0.3).leave_out_isolated_points(0), Error);
  EXPECT_THROW(without_isolated_points(cloud, 0.3, 0), Error);
  // A lone stray beside the wall has company and stays: the rule looks at neighbours, not at surfaces.
  cloud.positions.col(static_cast<Eigen::Index>(surfaces + 1)) = Eigen::Vector3f(1.0f, 10.2f, 1.0f);
  EXPECT_EQ(without_isolated_points(cloud, 0.3).size(), surfaces + 1);
  // The cube sets the reach: the scan line's points, 0.25 m apart, keep each other company in 0.3 m
  // cubes and are alone in 0.1 m ones.
  PointCloud line;
  line.positions = cloud.positions.middleCols(static_cast<Eigen::Index>(wall), 40);
  EXPECT_EQ(without_isolated_points(line, 0.3).size(), 40u);
  EXPECT_EQ(without_isolated_points(line, 0.1).size(), 0u);
  EXPECT_EQ(without_isolated_points(PointCloud{}, 0.3).size(), 0u);
  EXPECT_THROW(without_isolated_points(cloud, 0.0), Error);
}

TEST(RegistrationReport, BirdsEyePictureFramesBothCloudsWhereverTheyAre) {
  // A 30 m x 10 m scene 200 m east of the target origin, plus 1% stray points 5 km away; the
  // source is the same scene, moved by the registration's transform onto the target.
  PointCloud target;
  target.positions = Eigen::Matrix3Xf::Random(3, 2000);
  target.positions.row(0) = target.positions.row(0) * 15.0f + Eigen::RowVectorXf::Constant(2000, 200.0f);
  target.positions.row(1) = target.positions.row(1) * 5.0f + Eigen::RowVectorXf::Constant(2000, -50.0f);
  for (Eigen::Index i = 0; i < 20; ++i) target.positions.col(i) = Eigen::Vector3f(5000.0f, 5000.0f, 0.0f);
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();
  transform.translation() = Eigen::Vector3d(10.0, 0.0, 0.0);
  PointCloud source = target;
  source.positions = (transform.inverse().cast<float>() * target.positions).eval();
  const BirdsEyeFrame frame = birds_eye_frame(source, target, transform);
  EXPECT_NEAR(frame.center.x(), 200.0, 1.5);
  EXPECT_NEAR(frame.center.y(), -50.0, 1.5);
  EXPECT_GT(frame.half_extent, 15.0);  // the whole 30 m width fits
  EXPECT_LT(frame.half_extent, 20.0);  // and the strays do not shrink it
  // A 3 m room keeps a 5 m half side (whole-metre scale bar); a fixed half extent centres on the origin.
  PointCloud room;
  room.positions = Eigen::Matrix3Xf::Random(3, 500) * 1.5f;
  EXPECT_DOUBLE_EQ(birds_eye_frame(room, room, Eigen::Isometry3d::Identity()).half_extent, 5.0);
  BirdsEyeOptions fixed;
  fixed.half_extent = 30.0;
  const BirdsEyeFrame around_origin = birds_eye_frame(source, target, transform, fixed);
  EXPECT_DOUBLE_EQ(around_origin.half_extent, 30.0);
  EXPECT_TRUE(around_origin.center.isZero());
}

}  // namespace
}  // namespace quadrix
