// Scanner simulator benchmarks: one HDL-64E sweep of `street` (~120k points, target
// <= 100 ms on the 2-core machine) and the monument from 6 TLS stations (~6 M points, target
// <= 15 s), plus the hierarchy build and single-ray casts for context.
#include "experiments/synthetic/mesh_ray_caster.h"
#include "experiments/synthetic/scanner_simulator.h"
#include "experiments/synthetic/synthetic_output.h"

#include <benchmark/benchmark.h>

#include <chrono>

namespace {

void BM_StreetHdl64Sweep(benchmark::State& state) {
  const quadrix::Scene scene = quadrix::make_street_scene(1);
  const quadrix::RayCaster caster(scene);
  const quadrix::SensorModel sensor = quadrix::sensor_preset("hdl64");
  std::size_t points = 0;
  for (auto _ : state) {
    const auto scan = quadrix::simulate_scan(scene, caster, sensor, scene.default_lidar_poses[0], 1, 0);
    points = scan.cloud.size();
    benchmark::DoNotOptimize(scan.cloud.positions.data());
  }
  state.counters["points"] = static_cast<double>(points);
  state.counters["primitives"] = static_cast<double>(scene.primitives.size());
  state.counters["rays_per_second"] =
      benchmark::Counter(static_cast<double>(sensor.ray_count()), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_StreetHdl64Sweep)->Unit(benchmark::kMillisecond)->MinTime(2.0);

void BM_MonumentTlsSixStations(benchmark::State& state) {
  const quadrix::Scene scene = quadrix::make_monument_scene(1);
  const quadrix::SensorModel sensor = quadrix::sensor_preset("tls");
  std::size_t points = 0;
  for (auto _ : state) {
    const auto run = quadrix::run_synthetic(scene, sensor, scene.default_tls_stations, 1);
    points = 0;
    for (const auto& scan : run.scans) points += scan.cloud.size();
    benchmark::DoNotOptimize(points);
  }
  state.counters["points"] = static_cast<double>(points);
  state.counters["rays"] = static_cast<double>(6 * sensor.ray_count());
}
BENCHMARK(BM_MonumentTlsSixStations)->Unit(benchmark::kSecond)->Iterations(1);

void BM_StreetSceneAndHierarchyBuild(benchmark::State& state) {
  std::uint64_t seed = 0;
  for (auto _ : state) {
    const quadrix::Scene scene = quadrix::make_street_scene(seed++);
    const quadrix::RayCaster caster(scene);
    benchmark::DoNotOptimize(caster.hierarchy_node_count());
  }
}
BENCHMARK(BM_StreetSceneAndHierarchyBuild)->Unit(benchmark::kMicrosecond);

void BM_SingleRayHierarchyVersusBruteForce(benchmark::State& state) {
  const bool brute_force = state.range(0) != 0;
  const quadrix::Scene scene = quadrix::make_street_scene(1);
  const quadrix::RayCaster caster(scene);
  const auto directions = quadrix::sensor_ray_directions(quadrix::sensor_preset("vlp16"));
  const Eigen::Isometry3d pose = scene.default_lidar_poses[0];
  std::size_t ray = 0;
  for (auto _ : state) {
    const Eigen::Vector3d direction = pose.linear() * directions[ray++ % directions.size()];
    const auto hit = brute_force ? caster.cast_brute_force(pose.translation(), direction, 0.0, 120.0)
                                 : caster.cast(pose.translation(), direction, 0.0, 120.0);
    benchmark::DoNotOptimize(hit);
  }
  state.SetLabel(brute_force ? "brute force" : "hierarchy");
}
BENCHMARK(BM_SingleRayHierarchyVersusBruteForce)->Arg(0)->Arg(1)->Unit(benchmark::kNanosecond);

// Occlusion model choice (exact casting or meshes): every ray of one HDL-64E sweep of `street` through the exact
// ray-quadric caster (arg 0) or CGAL's AABB tree on the meshed primitives (arg 1, resolution 64).
void BM_StreetHdl64RaysExactVersusMesh(benchmark::State& state) {
  const bool mesh = state.range(0) != 0;
  const quadrix::Scene scene = quadrix::make_street_scene(1);
  const quadrix::RayCaster exact(scene);
  const auto build_start = std::chrono::steady_clock::now();
  const quadrix::MeshRayCaster meshed(scene, 64);
  const double build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - build_start).count();
  const auto directions = quadrix::sensor_ray_directions(quadrix::sensor_preset("hdl64"));
  const Eigen::Isometry3d pose = scene.default_lidar_poses[0];
  std::size_t hits = 0;
  for (auto _ : state) {
    hits = 0;
    for (const Eigen::Vector3d& local : directions) {
      const Eigen::Vector3d direction = pose.linear() * local;
      const auto hit = mesh ? meshed.cast(pose.translation(), direction, 0.9, 120.0)
                            : exact.cast(pose.translation(), direction, 0.9, 120.0);
      hits += hit.hit() ? 1 : 0;
    }
    benchmark::DoNotOptimize(hits);
  }
  state.counters["rays"] = static_cast<double>(directions.size());
  state.counters["hits"] = static_cast<double>(hits);
  if (mesh) {
    state.counters["triangles"] = static_cast<double>(meshed.triangle_count());
    state.counters["mesh_tree_build_ms"] = build_ms;
  }
  state.SetLabel(mesh ? "CGAL AABB tree on meshes (single thread)" : "exact ray-quadric (single thread)");
}
BENCHMARK(BM_StreetHdl64RaysExactVersusMesh)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->MinTime(2.0);

}  // namespace

BENCHMARK_MAIN();
