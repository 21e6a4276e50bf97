// The three baselines (experiments/baselines/baselines.h) with their default KITTI settings on the paper's
// demo loop closure kitti00 0 -> 4438 (full clouds, as `quadrix bench` gives them), at 1 and 2
// threads. Counters: per-stage wall times (ms), RTE (m), RRE (deg), success by the paper's rule and
// the down-sampled point counts. Skips with a message when ../shared/data is absent.
#include "estimation/registration.h"
#include "experiments/baselines/baselines.h"
#include "geometry/io.h"

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <string>

namespace {

std::string data_path(const std::string& relative) {
  if (const char* root = std::getenv("QUADRIX_DATA_DIR")) return (std::filesystem::path(root) / relative).string();
  return (std::filesystem::path(QUADRIX_DATA_DIR) / relative).string();
}

/// Runs `method` on the demo pair with `state.range(0)` threads and reports stages and errors.
void run_on_demo_pair(benchmark::State& state, const std::string& method) {
  const std::string source_path = data_path("kitti00/velodyne/000000.bin");
  const std::string target_path = data_path("kitti00/velodyne/004438.ply");
  const std::string truth_path = data_path("kitti00/gt/T_004438_from_000000.txt");
  for (const std::string& path : {source_path, target_path, truth_path}) {
    if (!std::filesystem::exists(path)) {
      state.SkipWithError(("real data absent: " + path).c_str());
      return;
    }
  }
  const quadrix::PointCloud source = quadrix::read_point_cloud(source_path);
  const quadrix::PointCloud target = quadrix::read_point_cloud(target_path);
  const Eigen::Isometry3d truth = quadrix::read_pose_matrix(truth_path);
  quadrix::BaselineOptions options;
  options.threads = static_cast<int>(state.range(0));

  quadrix::BaselineResult result;
  for (auto _ : state) {
    result = quadrix::run_baseline(method, source, target, options);
    benchmark::DoNotOptimize(result.transform.data());
  }
  for (const auto& [stage, milliseconds] : result.timings_ms) state.counters[stage + "_ms"] = milliseconds;
  for (const auto& [name, count] : result.counts) state.counters[name] = count;
  const double rte = quadrix::translation_error(result.transform, truth);
  const double rre = quadrix::rotation_error_degrees(result.transform, truth);
  state.counters["rte_m"] = rte;
  state.counters["rre_deg"] = rre;
  state.counters["success"] = result.solved && quadrix::registration_succeeded(result.transform, truth) ? 1.0 : 0.0;
  state.SetLabel(result.message);
}

void BM_Open3dRansac(benchmark::State& state) { run_on_demo_pair(state, "open3d-ransac"); }
void BM_Open3dFgr(benchmark::State& state) { run_on_demo_pair(state, "open3d-fgr"); }
void BM_PclPrerejective(benchmark::State& state) { run_on_demo_pair(state, "pcl-prerejective"); }

// One registration per run: whole-pair times are seconds, and RANSAC is seeded, so repeats measure
// the machine's load rather than the method.
BENCHMARK(BM_Open3dRansac)->ArgName("threads")->Arg(1)->Arg(2)->Iterations(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Open3dFgr)->ArgName("threads")->Arg(1)->Arg(2)->Iterations(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_PclPrerejective)->ArgName("threads")->Arg(1)->Arg(2)->Iterations(1)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
