// Reading speed of the point-cloud readers on real files, next to the physical limit (a memory copy
// of the same bytes). Skips a benchmark with a message when ../shared/data is absent.
#include "geometry/io.h"

#include <benchmark/benchmark.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace {

std::string data_path(const std::string& relative) {
  if (const char* root = std::getenv("QUADRIX_DATA_DIR")) return (std::filesystem::path(root) / relative).string();
  return (std::filesystem::path(QUADRIX_DATA_DIR) / relative).string();
}

void read_cloud(benchmark::State& state, const std::string& relative) {
  const std::string path = data_path(relative);
  if (!std::filesystem::exists(path)) {
    state.SkipWithError(("real data absent: " + path).c_str());
    return;
  }
  std::size_t points = 0;
  for (auto _ : state) {
    const quadrix::PointCloud cloud = quadrix::read_point_cloud(path);
    points = cloud.size();
    benchmark::DoNotOptimize(cloud.positions.data());
  }
  state.counters["points"] = static_cast<double>(points);
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) *
                          static_cast<std::int64_t>(std::filesystem::file_size(path)));
}

// The floor: copying the file's bytes once in memory (the file is in the page cache during the runs).
void copy_bytes(benchmark::State& state, const std::string& relative) {
  const std::string path = data_path(relative);
  if (!std::filesystem::exists(path)) {
    state.SkipWithError(("real data absent: " + path).c_str());
    return;
  }
  std::ifstream stream(path, std::ios::binary);
  const std::vector<char> source((std::istreambuf_iterator<char>(stream)), std::istreambuf_iterator<char>());
  std::vector<char> destination(source.size());
  for (auto _ : state) {
    std::memcpy(destination.data(), source.data(), source.size());
    benchmark::DoNotOptimize(destination.data());
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(source.size()));
}

void BM_ReadKittiBin(benchmark::State& state) { read_cloud(state, "kitti00/velodyne/000000.bin"); }
void BM_ReadBinaryPly(benchmark::State& state) { read_cloud(state, "hdl32_pair/source.ply"); }
void BM_ReadAsciiPly(benchmark::State& state) { read_cloud(state, "kitti00/velodyne/004438.ply"); }
void BM_ReadCompressedPcd(benchmark::State& state) { read_cloud(state, "single_scans/table_scene_mug_stereo_textured.pcd"); }
void BM_MemcpyKittiBin(benchmark::State& state) { copy_bytes(state, "kitti00/velodyne/000000.bin"); }
void BM_MemcpyBinaryPly(benchmark::State& state) { copy_bytes(state, "hdl32_pair/source.ply"); }

BENCHMARK(BM_ReadKittiBin)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MemcpyKittiBin)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadBinaryPly)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MemcpyBinaryPly)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadAsciiPly)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadCompressedPcd)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
