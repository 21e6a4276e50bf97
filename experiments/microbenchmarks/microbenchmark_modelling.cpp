// Scene modelling benchmarks: a 124,668-point KITTI frame -> SceneModel (target <= 150 ms
// on the 2-core machine) and each of its stages, and the ~6 M-point synthetic monument from 6 TLS
// stations (target <= 30 s). Stage timings inside a run are also reported as counters (ms).
#include "experiments/studies/modelling_evaluation.h"
#include "experiments/synthetic/scanner_simulator.h"
#include "fitting/scene_modelling.h"
#include "geometry/io.h"

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <map>

namespace {

std::string data_path(const std::string& relative) {
  if (const char* root = std::getenv("QUADRIX_DATA_DIR")) return (std::filesystem::path(root) / relative).string();
  return (std::filesystem::path(QUADRIX_DATA_DIR) / relative).string();
}

// The KITTI frame, read once; empty when the shared data is absent.
const quadrix::PointCloud& kitti_frame() {
  static const quadrix::PointCloud cloud = [] {
    const std::string path = data_path("kitti00/velodyne/000000.bin");
    return std::filesystem::exists(path) ? quadrix::read_point_cloud(path) : quadrix::PointCloud();
  }();
  return cloud;
}

bool require_kitti(benchmark::State& state) {
  if (!kitti_frame().empty()) return true;
  state.SkipWithError(("real data absent: " + data_path("kitti00/velodyne/000000.bin")).c_str());
  return false;
}

// Mean of every stage's timings_ms over the iterations, as counters.
void report_stages(benchmark::State& state, const std::map<std::string, double>& sums, double iterations) {
  for (const auto& [stage, sum] : sums) state.counters[stage + "_ms"] = sum / iterations;
}

void BM_KittiFrameToSceneModel(benchmark::State& state) {
  if (!require_kitti(state)) return;
  const quadrix::ExtractionOptions extraction = quadrix::extraction_preset("vlp64");
  const quadrix::ModellingOptions modelling;
  std::map<std::string, double> sums;
  double iterations = 0.0;
  std::size_t records = 0, elements = 0;
  for (auto _ : state) {
    const quadrix::ModellingResult result = quadrix::model_scene(kitti_frame(), extraction, modelling);
    for (const auto& [stage, ms] : result.model.timings_ms) sums[stage] += ms;
    iterations += 1.0;
    records = result.model.size();
    elements = result.extraction.elements.size();
  }
  report_stages(state, sums, iterations);
  state.counters["records"] = static_cast<double>(records);
  state.counters["elements"] = static_cast<double>(elements);
  state.counters["points"] = static_cast<double>(kitti_frame().size());
}
BENCHMARK(BM_KittiFrameToSceneModel)->Unit(benchmark::kMillisecond)->MinTime(3.0)->UseRealTime();

// The stages one at a time, each on the previous stage's output (computed once outside the loop).
struct KittiStages {
  Eigen::Matrix3Xd points;
  std::vector<std::uint32_t> in_range;
  quadrix::GroundSegmentation ground;
  std::vector<std::uint32_t> remaining;
  std::vector<std::vector<std::uint32_t>> clusters;
  quadrix::ExtractionResult extraction;
};

const KittiStages& kitti_stages() {
  static const KittiStages stages = [] {
    KittiStages s;
    const quadrix::ExtractionOptions options = quadrix::extraction_preset("vlp64");
    s.points = kitti_frame().positions.cast<double>();
    for (std::uint32_t i = 0; i < s.points.cols(); ++i) {
      const double range = s.points.col(i).norm();
      if (range >= options.minimum_range && range <= options.maximum_range) s.in_range.push_back(i);
    }
    s.ground = quadrix::segment_ground(s.points, s.in_range, options.ground, options.sensor_origin, options.up);
    quadrix::extract_planes(s.points, s.ground.other_indices, options.planes, s.remaining);
    s.clusters = quadrix::euclidean_clusters(s.points, s.remaining, options.clusters);
    s.extraction = quadrix::extract_elements(kitti_frame(), options);
    return s;
  }();
  return stages;
}

void BM_KittiStageGround(benchmark::State& state) {
  if (!require_kitti(state)) return;
  const KittiStages& s = kitti_stages();
  const quadrix::ExtractionOptions options = quadrix::extraction_preset("vlp64");
  for (auto _ : state)
    benchmark::DoNotOptimize(quadrix::segment_ground(s.points, s.in_range, options.ground, options.sensor_origin, options.up));
  state.counters["points"] = static_cast<double>(s.in_range.size());
}
BENCHMARK(BM_KittiStageGround)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_KittiStagePlanes(benchmark::State& state) {
  if (!require_kitti(state)) return;
  const KittiStages& s = kitti_stages();
  quadrix::ExtractionOptions options = quadrix::extraction_preset("vlp64");
  options.planes.method = state.range(0) == 0 ? quadrix::PlaneMethod::VoxelRegionGrowing : quadrix::PlaneMethod::CgalRegionGrowing;
  std::vector<std::uint32_t> remaining;
  for (auto _ : state) benchmark::DoNotOptimize(quadrix::extract_planes(s.points, s.ground.other_indices, options.planes, remaining));
  state.SetLabel(state.range(0) == 0 ? "voxel region growing (paper)" : "CGAL region growing");
  state.counters["points"] = static_cast<double>(s.ground.other_indices.size());
}
BENCHMARK(BM_KittiStagePlanes)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_KittiStageClusters(benchmark::State& state) {
  if (!require_kitti(state)) return;
  const KittiStages& s = kitti_stages();
  quadrix::ClusterOptions options = quadrix::extraction_preset("vlp64").clusters;
  options.method = state.range(0) == 0 ? quadrix::ClusterMethod::Grid : quadrix::ClusterMethod::Pcl;
  std::size_t clusters = 0;
  for (auto _ : state) {
    const auto found = quadrix::euclidean_clusters(s.points, s.remaining, options);
    clusters = found.size();
    benchmark::DoNotOptimize(found.data());
  }
  state.SetLabel(state.range(0) == 0 ? "sorted grid + union-find" : "PCL EuclideanClusterExtraction");
  state.counters["points"] = static_cast<double>(s.remaining.size());
  state.counters["clusters"] = static_cast<double>(clusters);
}
BENCHMARK(BM_KittiStageClusters)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_KittiStageLines(benchmark::State& state) {
  if (!require_kitti(state)) return;
  const KittiStages& s = kitti_stages();
  const quadrix::ExtractionOptions options = quadrix::extraction_preset("vlp64");
  std::vector<std::uint32_t> rest;
  for (auto _ : state)
    for (const auto& cluster : s.clusters)
      benchmark::DoNotOptimize(quadrix::extract_lines(s.points, cluster, options.lines, options.up, rest));
  state.counters["clusters"] = static_cast<double>(s.clusters.size());
}
BENCHMARK(BM_KittiStageLines)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_KittiStageFittingAndSelection(benchmark::State& state) {
  if (!require_kitti(state)) return;
  const KittiStages& s = kitti_stages();
  quadrix::ModellingOptions options;
  options.maximum_fit_points = static_cast<int>(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(quadrix::model_elements(s.points, s.extraction, options).model.records.data());
  state.SetLabel(state.range(0) == 0 ? "every point to the fitter" : "fitter sees <= " + std::to_string(state.range(0)) + " points");
  state.counters["elements"] = static_cast<double>(s.extraction.elements.size());
}
BENCHMARK(BM_KittiStageFittingAndSelection)->Arg(0)->Arg(4000)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_MonumentSixTlsStationsToSceneModel(benchmark::State& state) {
  const quadrix::Scene scene = quadrix::make_monument_scene(1);
  const quadrix::SensorModel sensor = quadrix::sensor_preset("tls");
  const quadrix::PointCloud cloud =
      quadrix::merge_scans_in_world(quadrix::run_synthetic(scene, sensor, scene.default_tls_stations, 1));
  std::map<std::string, double> sums;
  double iterations = 0.0;
  std::map<quadrix::QuadricType, int> types;
  for (auto _ : state) {
    const quadrix::ModellingResult result =
        quadrix::model_scene(cloud, quadrix::extraction_preset("monument"), quadrix::ModellingOptions());
    for (const auto& [stage, ms] : result.model.timings_ms) sums[stage] += ms;
    iterations += 1.0;
    types.clear();
    for (std::size_t r = 0; r < result.model.augmented_begin; ++r) ++types[result.model.types[r]];
  }
  report_stages(state, sums, iterations);
  state.counters["points"] = static_cast<double>(cloud.size());
  for (const auto& [type, count] : types) state.counters[quadrix::quadric_type_name(type)] = count;
}
BENCHMARK(BM_MonumentSixTlsStationsToSceneModel)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
