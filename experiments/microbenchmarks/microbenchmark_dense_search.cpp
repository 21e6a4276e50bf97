// The dense search that settles ambiguous answers (estimation/dense_search.h) on the real 3DTK pair
// 2->0 (81k points a scan, the robot's self-hits within 2 m cropped as `auto` does): one
// point-to-plane ICP from the identity, and the whole search along the weakest direction (17 shifts
// plus the identity); and the correlation over yaw and ground translation on KITTI-00 frames
// 52 -> 88 (29.9 m apart); and leaving out the isolated points of KITTI frame 52 (as the extraction
// and every check do), as scanned and with 30% uniform outliers; and the free-space check's range
// image and measure on frame 52. Skips with a message when ../shared/data is absent.
#include "estimation/answer_quality.h"
#include "estimation/dense_search.h"
#include "estimation/ground_correlation.h"
#include "estimation/registration.h"
#include "estimation/registration_config.h"
#include "geometry/io.h"
#include "geometry/voxel_cells.h"

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <cstdlib>
#include <filesystem>
#include <optional>
#include <random>
#include <string>
#include <vector>

namespace {

std::string data_path(const std::string& relative) {
  if (const char* root = std::getenv("QUADRIX_DATA_DIR")) return (std::filesystem::path(root) / relative).string();
  return (std::filesystem::path(QUADRIX_DATA_DIR) / relative).string();
}

// A 3DTK scan without the points within 2 m of the scanner; empty when the shared data is absent.
quadrix::PointCloud cropped_scan(const std::string& name) {
  const std::string path = data_path("3dtk/" + name);
  if (!std::filesystem::exists(path)) return {};
  const quadrix::PointCloud cloud = quadrix::read_point_cloud(path);
  std::vector<Eigen::Index> kept;
  for (Eigen::Index i = 0; i < cloud.positions.cols(); ++i)
    if (cloud.positions.col(i).norm() >= 2.0f) kept.push_back(i);
  quadrix::PointCloud cropped;
  cropped.positions.resize(3, static_cast<Eigen::Index>(kept.size()));
  for (std::size_t i = 0; i < kept.size(); ++i) cropped.positions.col(static_cast<Eigen::Index>(i)) = cloud.positions.col(kept[i]);
  return cropped;
}

struct Pair {
  quadrix::PointCloud source = cropped_scan("scan002_RH_m.xyz");
  quadrix::PointCloud target = cropped_scan("scan000_RH_m.xyz");
};

const Pair& pair_2_to_0() {
  static const Pair pair;
  return pair;
}

bool require_pair(benchmark::State& state) {
  if (!pair_2_to_0().source.empty() && !pair_2_to_0().target.empty()) return true;
  state.SkipWithError(("real data absent: " + data_path("3dtk/scan002_RH_m.xyz")).c_str());
  return false;
}

void BM_AlignPointToPlane3dtk(benchmark::State& state) {
  if (!require_pair(state)) return;
  for (auto _ : state)
    benchmark::DoNotOptimize(quadrix::align_point_to_plane(pair_2_to_0().source, pair_2_to_0().target, Eigen::Isometry3d::Identity()).overlap);
}
BENCHMARK(BM_AlignPointToPlane3dtk)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_SearchWeakestDirection3dtk(benchmark::State& state) {
  if (!require_pair(state)) return;
  for (auto _ : state)
    benchmark::DoNotOptimize(quadrix::search_weakest_direction(pair_2_to_0().source, pair_2_to_0().target, Eigen::Isometry3d::Identity(), {}, {},
                                                               Eigen::Vector3d::UnitZ(), std::nullopt, 2.0, 5.0)
                                 .margin);
}
BENCHMARK(BM_SearchWeakestDirection3dtk)->Unit(benchmark::kMillisecond)->UseRealTime();

// Reads two files of the shared data into `source` and `target`; skips the benchmark when either is absent.
bool read_shared_pair(benchmark::State& state, const std::string& source_name, const std::string& target_name,
                      quadrix::PointCloud& source, quadrix::PointCloud& target) {
  for (const std::string& name : {source_name, target_name})
    if (!std::filesystem::exists(data_path(name))) {
      state.SkipWithError(("real data absent: " + data_path(name)).c_str());
      return false;
    }
  source = quadrix::read_point_cloud(data_path(source_name));
  target = quadrix::read_point_cloud(data_path(target_name));
  return true;
}

// The correlation over yaw and ground translation (estimation/ground_correlation.h) on KITTI-00
// frames 52 -> 88, 29.9 m apart, with the ground each frame's sensor sees 1.73 m below it.
void BM_CorrelateOverGroundKitti52To88(benchmark::State& state) {
  quadrix::PointCloud source, target;
  if (!read_shared_pair(state, "kitti00/velodyne/000052.bin", "kitti00/velodyne/000088.bin", source, target)) return;
  const Eigen::Vector4d ground(0.0, 0.0, 1.0, 1.73);
  for (auto _ : state) benchmark::DoNotOptimize(quadrix::correlate_over_ground(source, target, ground, ground).size());
}
BENCHMARK(BM_CorrelateOverGroundKitti52To88)->Unit(benchmark::kMillisecond)->UseRealTime();

// KITTI-00 0 -> 4438 (5.3 m apart, `auto` on both scans) and its `ok` answer; nothing once `state` is
// skipped because the shared data is absent or the pair did not register `ok`.
struct RegisteredKittiPair {
  quadrix::PointCloud source, target;
  quadrix::RegistrationOptions options;
  quadrix::RegistrationResult registered;
};
std::optional<RegisteredKittiPair> registered_kitti_0_to_4438(benchmark::State& state) {
  RegisteredKittiPair pair;
  if (!read_shared_pair(state, "kitti00/velodyne/000000.bin", "kitti00/velodyne/004438.ply", pair.source, pair.target)) return std::nullopt;
  pair.options = quadrix::resolve_registration_options("auto", pair.source, "auto", pair.target);
  pair.registered = quadrix::register_clouds(pair.source, pair.target, pair.options);
  if (pair.registered.status != quadrix::RegistrationStatus::Ok) {
    state.SkipWithError(("the pair did not register ok: " + pair.registered.message).c_str());
    return std::nullopt;
  }
  return pair;
}

// verify_registration on the `ok` answer register_clouds gives KITTI-00 0 -> 4438 (5.3 m apart,
// `auto` on both scans): what every `ok` answer pays for its checks. Reports the half-turn check's
// share, and that of preparing both clouds for it, as counters.
void BM_VerifyOkAnswerKitti0To4438(benchmark::State& state) {
  const std::optional<RegisteredKittiPair> pair = registered_kitti_0_to_4438(state);
  if (!pair) return;
  const auto& [source, target, options, registered] = *pair;
  double half_turn_ms = 0.0, preparation_ms = 0.0;
  for (auto _ : state) {
    quadrix::RegistrationResult result = registered;
    result.timings_ms.clear();
    quadrix::verify_registration(result, source, target, options);
    half_turn_ms += result.timings_ms["half_turn"];
    preparation_ms += result.timings_ms["dense_preparation"];
    benchmark::DoNotOptimize(result.status);
  }
  state.counters["half_turn_ms"] = benchmark::Counter(half_turn_ms / static_cast<double>(state.iterations()));
  state.counters["dense_preparation_ms"] = benchmark::Counter(preparation_ms / static_cast<double>(state.iterations()));
}
BENCHMARK(BM_VerifyOkAnswerKitti0To4438)->Unit(benchmark::kMillisecond)->UseRealTime();

// measure_answer_quality (estimation/answer_quality.h) of the `ok` answer of KITTI-00 0 -> 4438: the
// fitness, inlier RMSE, correspondences and information every `ok` answer carries, on the whole
// clouds (about 120k points each); state.range(0) threads (0: TBB's default).
void BM_MeasureAnswerQualityKitti0To4438(benchmark::State& state) {
  const std::optional<RegisteredKittiPair> pair = registered_kitti_0_to_4438(state);
  if (!pair) return;
  const auto& [source, target, options, registered] = *pair;
  std::optional<tbb::global_control> threads;
  if (state.range(0) > 0) threads.emplace(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(state.range(0)));
  for (auto _ : state)
    benchmark::DoNotOptimize(quadrix::measure_answer_quality(source, target, registered.transform, options.quality).fitness);
}
BENCHMARK(BM_MeasureAnswerQualityKitti0To4438)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();

// KITTI-00 frame 52, or nothing once `state` is skipped because the shared data is absent.
std::optional<quadrix::PointCloud> kitti_frame_52(benchmark::State& state) {
  const std::string path = data_path("kitti00/velodyne/000052.bin");
  if (!std::filesystem::exists(path)) {
    state.SkipWithError(("real data absent: " + path).c_str());
    return std::nullopt;
  }
  return quadrix::read_point_cloud(path);
}

// without_isolated_points (geometry/voxel_cells.h) on KITTI-00 frame 52 (121k points), with
// state.range(0) percent of its point count added uniformly over its bounding box.
void BM_WithoutIsolatedPointsKitti52(benchmark::State& state) {
  const std::optional<quadrix::PointCloud> frame = kitti_frame_52(state);
  if (!frame) return;
  const quadrix::PointCloud& scan = *frame;
  const Eigen::Index count = scan.positions.cols(), added = count * state.range(0) / 100;
  quadrix::PointCloud cloud;
  cloud.positions.resize(3, count + added);
  cloud.positions.leftCols(count) = scan.positions;
  const Eigen::Vector3f low = scan.positions.rowwise().minCoeff(), high = scan.positions.rowwise().maxCoeff();
  std::mt19937 random(1);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (Eigen::Index i = 0; i < added; ++i)
    cloud.positions.col(count + i) = low + Eigen::Vector3f(unit(random), unit(random), unit(random)).cwiseProduct(high - low);
  for (auto _ : state) benchmark::DoNotOptimize(quadrix::without_isolated_points(cloud, 0.3).size());
}
BENCHMARK(BM_WithoutIsolatedPointsKitti52)->Arg(0)->Arg(30)->Unit(benchmark::kMillisecond)->UseRealTime();

// The free-space check's range image of KITTI-00 frame 52 (121k points) around its sensor, and the
// check of the identity of the frame onto itself against that image both ways (state.range(0): 0
// the image, 1 the measure; points higher than 2 m above a level ground at -1.73 m).
void BM_FreeSpaceKitti52(benchmark::State& state) {
  const std::optional<quadrix::PointCloud> frame = kitti_frame_52(state);
  if (!frame) return;
  const quadrix::PointCloud& cloud = *frame;
  const quadrix::RangeImage image(cloud, Eigen::Vector3d::Zero());
  const Eigen::Vector4d ground(0.0, 0.0, 1.0, 1.73);
  for (auto _ : state) {
    if (state.range(0) == 0) {
      const quadrix::RangeImage built(cloud, Eigen::Vector3d::Zero());
      benchmark::DoNotOptimize(built.nearest_return(Eigen::Vector3d(10.0, 0.0, 0.0)));
    } else {
      benchmark::DoNotOptimize(
          quadrix::measure_free_space(cloud, cloud, image, image, Eigen::Isometry3d::Identity(), ground, ground, 2.0).sum());
    }
  }
  state.SetLabel(state.range(0) == 0 ? "range image" : "measure both ways");
  state.counters["points"] = static_cast<double>(cloud.size());
}
BENCHMARK(BM_FreeSpaceKitti52)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
