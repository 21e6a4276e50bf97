// Estimation kernels: refining one candidate with ~100 correspondences (plus augmentation) per
// backend/algorithm, the quadric distance + Jacobian, scoring 8 candidates in selection, `auto`'s
// up-axis estimate of one simulated street scan per sensor, and all of `auto` on a KITTI scan.
// Target: Ceres refinement of ~100 correspondences in <= 2 ms.
#include "estimation/candidate_selection.h"
#include "estimation/mapping.h"
#include "estimation/pose_graph.h"
#include "estimation/refiner.h"
#include "estimation/registration_config.h"
#include "experiments/synthetic/mesh_ray_caster.h"
#include "experiments/synthetic/scanner_simulator.h"
#include "geometry/io.h"

#include <benchmark/benchmark.h>

#include <filesystem>
#include <random>

namespace {

using namespace quadrix;

struct Scene {
  std::vector<QuadricRecord> source;
  std::vector<QuadricRecord> target;
  std::vector<RecordCorrespondence> pairs;
  Eigen::Isometry3d truth = Eigen::Isometry3d::Identity();
};

Eigen::Matrix3d random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> gauss;
  return Eigen::Quaterniond(gauss(rng), gauss(rng), gauss(rng), gauss(rng)).normalized().toRotationMatrix();
}

// `count` records cycling through point, line, plane, sphere, ellipsoid, cylinder and cone, the
// target moved by a random truth with 1 cm / 0.2 degree per-element noise.
Scene make_scene(int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(-30.0, 30.0);
  std::normal_distribution<double> gauss;
  const QuadricType types[] = {QuadricType::Point, QuadricType::Line, QuadricType::Plane, QuadricType::Sphere,
                               QuadricType::Ellipsoid, QuadricType::CircularCylinder, QuadricType::CircularCone};
  Scene scene;
  scene.truth.linear() = random_rotation(rng);
  scene.truth.translation() = Eigen::Vector3d(uniform(rng), uniform(rng), uniform(rng)) / 3.0;
  for (int k = 0; k < count; ++k) {
    const QuadricType type = types[k % 7];
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = random_rotation(rng);
    pose.translation() = Eigen::Vector3d(uniform(rng), uniform(rng), uniform(rng));
    Eigen::Vector3d scale(1.0, 1.0, 1.0);
    if (type == QuadricType::Ellipsoid) scale = Eigen::Vector3d(1.0, 1.6, 2.5);
    if (type == QuadricType::CircularCone) scale = Eigen::Vector3d(0.5, 0.5, 1.0);
    const Quadric quadric = Quadric::from_canonical(type, scale, pose);
    StatisticalPose statistics;
    statistics.scale = Eigen::Vector3d(3.0, 2.0, 1.0);
    statistics.rotation = random_rotation(rng);
    statistics.center = pose.translation();
    Eigen::Isometry3d noise = Eigen::Isometry3d::Identity();
    noise.linear() = Eigen::AngleAxisd(0.0035 * std::abs(gauss(rng)), Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized()).toRotationMatrix();
    noise.translation() = 0.01 * Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng));
    const Eigen::Isometry3d motion = noise * scene.truth;
    StatisticalPose moved = statistics;
    moved.rotation = motion.linear() * statistics.rotation;
    moved.center = motion * statistics.center;
    scene.pairs.push_back({scene.source.size(), scene.target.size()});
    scene.source.push_back(make_quadric_record(static_cast<std::uint32_t>(type), quadric, statistics));
    scene.target.push_back(make_quadric_record(static_cast<std::uint32_t>(type), quadric.transformed(motion), moved));
  }
  return scene;
}

void refine_candidate(benchmark::State& state, const char* backend, const char* algorithm) {
  const Scene scene = make_scene(static_cast<int>(state.range(0)), 7);
  const auto factors = build_quadric_factors(scene.source, decompose_records(scene.source), scene.target,
                                             decompose_records(scene.target), scene.pairs, {});
  Eigen::Isometry3d start = scene.truth;
  start.linear() = scene.truth.linear() * Eigen::AngleAxisd(0.1, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  start.translation() += Eigen::Vector3d(1.0, -0.5, 0.7);
  const auto refiner = make_refiner(backend);
  RefinerOptions options;
  options.algorithm = algorithm;
  RefinementResult result;
  for (auto _ : state) {
    result = refiner->refine(factors.factors, start, options);
    benchmark::DoNotOptimize(result.transform);
  }
  state.counters["factors"] = static_cast<double>(factors.factors.size());
  state.counters["iterations"] = result.iterations;
  state.counters["evaluations"] = result.evaluations;
  state.counters["converged"] = result.status == RefinementStatus::Converged ? 1.0 : 0.0;
  state.counters["t_err_m"] = (result.transform.translation() - scene.truth.translation()).norm();
}

void BM_QuadricDistanceWithJacobian(benchmark::State& state) {
  const Scene scene = make_scene(7, 3);
  const QuadricFactor factor = make_quadric_factor(scene.source[4], scene.target[4]);
  Vector12d residual;
  Matrix12x6d jacobian;
  for (auto _ : state) {
    quadric_distance_with_jacobian(factor, scene.truth, &residual, &jacobian);
    benchmark::DoNotOptimize(jacobian);
  }
}
BENCHMARK(BM_QuadricDistanceWithJacobian);

void BM_RefineCeresLM(benchmark::State& state) { refine_candidate(state, "ceres", "levenberg_marquardt"); }
void BM_RefineNloptLbfgs(benchmark::State& state) { refine_candidate(state, "nlopt", "lbfgs"); }
void BM_RefineNloptSlsqp(benchmark::State& state) { refine_candidate(state, "nlopt", "slsqp"); }
void BM_RefineNloptBobyqa(benchmark::State& state) { refine_candidate(state, "nlopt", "bobyqa"); }
BENCHMARK(BM_RefineCeresLM)->Arg(20)->Arg(100)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RefineNloptLbfgs)->Arg(100)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RefineNloptSlsqp)->Arg(100)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RefineNloptBobyqa)->Arg(100)->Unit(benchmark::kMillisecond);

void BM_SelectAmong8Candidates(benchmark::State& state) {
  const Scene scene = make_scene(100, 9);
  std::vector<Eigen::Isometry3d> candidates(8, scene.truth);
  for (int k = 1; k < 8; ++k) candidates[static_cast<std::size_t>(k)].translation() += Eigen::Vector3d(0.3 * k, 0.0, 0.0);
  for (auto _ : state) benchmark::DoNotOptimize(select_candidate(scene.source, scene.target, candidates).best_index);
}
BENCHMARK(BM_SelectAmong8Candidates)->Unit(benchmark::kMillisecond);

// One level scan of street 1 by `sensor` (a sensor_preset name) from the street's first pose.
SimulatedScan street_scan(const char* sensor) {
  const quadrix::Scene street = make_street_scene(1);
  const RayCaster caster(street);
  return simulate_scan(street, caster, sensor_preset(sensor), street.default_lidar_poses[0], 1, 0);
}

// estimate_up_direction on one level scan of street 1: voxel-normal mode, then the fullest plane's
// points (docs/registration.md, "How auto finds the up axis"). Arg: 0 HDL-64E, 1 VLP-16, 2 Livox.
void BM_EstimateUpDirection(benchmark::State& state) {
  const char* sensors[] = {"hdl64", "vlp16", "livox"};
  const SimulatedScan scan = street_scan(sensors[state.range(0)]);
  double tilt = 0.0;
  for (auto _ : state) {
    const UpDirectionEstimate estimate = estimate_up_direction(scan.cloud);
    tilt = estimate.tilt_degrees;
    benchmark::DoNotOptimize(estimate.up.data());
  }
  state.SetLabel(sensors[state.range(0)]);
  state.counters["points"] = static_cast<double>(scan.cloud.size());
  state.counters["tilt_deg"] = tilt;
}
BENCHMARK(BM_EstimateUpDirection)->DenseRange(0, 2)->Unit(benchmark::kMillisecond);

// All that `--preset auto` measures on one real KITTI scan (sensor, up axis, crop), and its parts.
// Skipped when the shared data is absent.
void BM_GuessSensorPresetKitti(benchmark::State& state) {
  const std::string path = std::string(QUADRIX_DATA_DIR) + "/kitti00/velodyne/000000.bin";
  if (!std::filesystem::exists(path)) {
    state.SkipWithError("shared data absent");
    return;
  }
  const PointCloud cloud = read_point_cloud(path);
  const PointCloud accompanied = without_isolated_points(cloud, AmbiguityOptions{}.isolation_cell);
  for (auto _ : state) {
    switch (state.range(0)) {
      case 0: benchmark::DoNotOptimize(guess_sensor_preset(cloud).preset.size()); break;
      case 1: benchmark::DoNotOptimize(without_isolated_points(cloud, AmbiguityOptions{}.isolation_cell).size()); break;
      default: benchmark::DoNotOptimize(estimate_up_direction(accompanied).up.data()); break;
    }
  }
  const char* labels[] = {"guess_sensor_preset", "without_isolated_points", "estimate_up_direction"};
  state.SetLabel(labels[state.range(0)]);
  state.counters["points"] = static_cast<double>(cloud.size());
}
BENCHMARK(BM_GuessSensorPresetKitti)->DenseRange(0, 2)->Unit(benchmark::kMillisecond);

// The map's place recognition on simulated scans of street 1 (docs/mapping.md, step 4): the
// descriptor of one scan, and one comparison under all 60 headings (an HDL-64E scan against a Livox
// scan of the same place). Arg: 0 HDL-64E, 1 VLP-16, 2 Livox.
void BM_PlaceDescriptor(benchmark::State& state) {
  const char* sensors[] = {"hdl64", "vlp16", "livox"};
  const SimulatedScan scan = street_scan(sensors[state.range(0)]);
  for (auto _ : state) benchmark::DoNotOptimize(place_descriptor(scan.cloud, Eigen::Vector3d::UnitZ()).data());
  state.SetLabel(sensors[state.range(0)]);
  state.counters["points"] = static_cast<double>(scan.cloud.size());
}
BENCHMARK(BM_PlaceDescriptor)->DenseRange(0, 2)->Unit(benchmark::kMillisecond);

void BM_PlaceDistance(benchmark::State& state) {
  const Eigen::VectorXd first = place_descriptor(street_scan("hdl64").cloud, Eigen::Vector3d::UnitZ());
  const Eigen::VectorXd second = place_descriptor(street_scan("livox").cloud, Eigen::Vector3d::UnitZ());
  double distance = 0.0;
  for (auto _ : state) benchmark::DoNotOptimize(distance = place_distance(first, second));
  state.counters["distance"] = distance;
}
BENCHMARK(BM_PlaceDistance);

// The outlier statistics of a pose graph the size of a three-sensor town drive (docs/mapping.md,
// step 8): a chain of N poses 8 m apart with a loop edge from each pose to the one two back, the
// redundancy of every edge from one sparse factorisation and N six-column solves.
void BM_EdgeOutlierStatistics(benchmark::State& state) {
  const std::size_t count = static_cast<std::size_t>(state.range(0));
  std::vector<Eigen::Isometry3d> poses(count, Eigen::Isometry3d::Identity());
  for (std::size_t index = 0; index < count; ++index) poses[index].translation() = Eigen::Vector3d(8.0 * index, 0.0, 0.0);
  std::vector<PoseGraphEdge> edges;
  Information6d information = Information6d::Identity() * 100.0;
  for (std::size_t index = 1; index < count; ++index) {
    edges.push_back({index, index - 1, poses[index - 1].inverse() * poses[index], information, false, false});
    if (index >= 2) edges.push_back({index, index - 2, poses[index - 2].inverse() * poses[index], information, true, false});
  }
  for (auto _ : state) benchmark::DoNotOptimize(edge_outlier_statistics(poses, edges).data());
  state.counters["edges"] = static_cast<double>(edges.size());
}
BENCHMARK(BM_EdgeOutlierStatistics)->Arg(453)->Arg(1000)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
