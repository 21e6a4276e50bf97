// Maximum-clique benchmarks (paper §"Graph-based Outlier Pruning"):
//  * random geometric graphs of 500 / 1,500 / 4,000 vertices at densities 1–30%, our solver
//    (1 and 2 threads) against igraph's igraph_clique_number on the same graphs;
//  * the four-level compatibility graphs of a planted-inlier correspondence set (1,500
//    correspondences): construction, graduated search, and igraph on the same four graphs.
// igraph runs are capped at kIgraphCapSeconds through igraph's interruption handler; a capped run
// is reported as an error row "capped: igraph exceeded … s".
// Numbers depend on the machine; ours were measured on 2 shared cores.
#include "fitting/extraction.h"
#include "fitting/scene_modelling.h"
#include "geometry/io.h"
#include "matching/compatibility_graph.h"
#include "matching/correspondences.h"
#include "matching/max_clique.h"

#include <Eigen/Geometry>
#include <benchmark/benchmark.h>
#include <igraph/igraph.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <tuple>
#include <vector>

namespace {

using quadrix::BitsetGraph;
using Clock = std::chrono::steady_clock;

/// Wall-clock budget of one igraph run before it is interrupted and reported as capped.
constexpr double kIgraphCapSeconds = 20.0;
/// Deadline of one run of our solver on the geometric graphs (counter optimal = 0 when it hit it).
constexpr double kOurCapSeconds = 20.0;

// ---------------------------------------------------------------------------------------------
// Graphs

/// Random geometric graph: n points uniform in the unit cube, an edge when two points are closer
/// than the radius giving exactly the requested density (the matching quantile of all distances).
BitsetGraph random_geometric_graph(std::size_t n, double density, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::vector<Eigen::Vector3d> points(n);
  for (Eigen::Vector3d& point : points) point = Eigen::Vector3d(uniform(random), uniform(random), uniform(random));
  std::vector<float> distances;
  distances.reserve(n * (n - 1) / 2);
  for (std::size_t u = 0; u < n; ++u)
    for (std::size_t v = u + 1; v < n; ++v) distances.push_back(static_cast<float>((points[u] - points[v]).norm()));
  const std::size_t edges = static_cast<std::size_t>(density * static_cast<double>(distances.size()));
  std::vector<float> sorted = distances;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(edges), sorted.end());
  const float radius = sorted[edges];
  BitsetGraph graph(n);
  std::size_t index = 0;
  for (std::size_t u = 0; u < n; ++u)
    for (std::size_t v = u + 1; v < n; ++v)
      if (distances[index++] < radius) graph.add_edge_unchecked(u, v);
  return graph;
}

/// Geometric graphs are built once per (n, density %) and shared by our runs and igraph's.
const BitsetGraph& geometric_graph(std::size_t n, int density_percent) {
  static std::map<std::pair<std::size_t, int>, BitsetGraph> cache;
  const auto key = std::make_pair(n, density_percent);
  auto found = cache.find(key);
  if (found == cache.end())
    found = cache.emplace(key, random_geometric_graph(n, density_percent / 100.0, 1000u + static_cast<unsigned>(n) +
                                                                                     static_cast<unsigned>(density_percent)))
                .first;
  return found->second;
}

/// Planted-inlier correspondences in a LiDAR-like scene (120 m x 120 m x 8 m): 10% inliers
/// (rigid motion + 0.05 m Gaussian noise on the centres), the rest matched to other scene objects.
struct PlantedCorrespondences {
  Eigen::Matrix3Xd source, target;
  std::size_t inlier_count = 0;
};

const PlantedCorrespondences& planted_correspondences() {
  static const PlantedCorrespondences planted = [] {
    constexpr Eigen::Index kCount = 1500;
    constexpr Eigen::Index kInliers = 150;
    std::mt19937 random(6);
    std::uniform_real_distribution<double> horizontal(-60.0, 60.0), vertical(-2.0, 6.0);
    std::normal_distribution<double> noise(0.0, 0.05);
    Eigen::Matrix3Xd scene(3, kCount);
    for (Eigen::Index i = 0; i < kCount; ++i) scene.col(i) = Eigen::Vector3d(horizontal(random), horizontal(random), vertical(random));
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    pose.translation() = Eigen::Vector3d(12.0, -5.0, 0.3);
    PlantedCorrespondences result;
    result.inlier_count = kInliers;
    result.source = scene;
    result.target.resize(3, kCount);
    std::uniform_int_distribution<Eigen::Index> other(0, kCount - 1);
    for (Eigen::Index i = 0; i < kCount; ++i) {
      if (i < kInliers) {
        result.target.col(i) = pose * scene.col(i) + Eigen::Vector3d(noise(random), noise(random), noise(random));
      } else {
        Eigen::Index j = other(random);
        while (j == i) j = other(random);
        result.target.col(i) = pose * scene.col(j);
      }
    }
    return result;
  }();
  return planted;
}

const quadrix::CompatibilityGraphs& planted_graphs() {
  static const quadrix::CompatibilityGraphs graphs = quadrix::build_compatibility_graphs(
      planted_correspondences().source, planted_correspondences().target);
  return graphs;
}

// ---------------------------------------------------------------------------------------------
// igraph reference

Clock::time_point igraph_deadline;

igraph_error_t interrupt_after_deadline(void*) {
  return Clock::now() > igraph_deadline ? IGRAPH_INTERRUPTED : IGRAPH_SUCCESS;
}

/// An igraph copy of a BitsetGraph (built outside the timed loops).
class IgraphCopy {
 public:
  explicit IgraphCopy(const BitsetGraph& graph) {
    igraph_vector_int_t edges;
    igraph_vector_int_init(&edges, 0);
    for (std::size_t u = 0; u < graph.vertex_count(); ++u)
      for (int v : graph.neighbours(static_cast<int>(u)))
        if (static_cast<std::size_t>(v) > u) {
          igraph_vector_int_push_back(&edges, static_cast<igraph_integer_t>(u));
          igraph_vector_int_push_back(&edges, v);
        }
    igraph_create(&graph_, &edges, static_cast<igraph_integer_t>(graph.vertex_count()), IGRAPH_UNDIRECTED);
    igraph_vector_int_destroy(&edges);
  }
  ~IgraphCopy() { igraph_destroy(&graph_); }
  IgraphCopy(const IgraphCopy&) = delete;
  IgraphCopy& operator=(const IgraphCopy&) = delete;

  /// Clique number, or -1 when the run exceeded kIgraphCapSeconds.
  long clique_number() const {
    igraph_deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(kIgraphCapSeconds));
    igraph_integer_t size = 0;
    if (igraph_clique_number(&graph_, &size) != IGRAPH_SUCCESS) return -1;
    return static_cast<long>(size);
  }

 private:
  igraph_t graph_;
};

void install_igraph_handlers() {
  static const bool installed = [] {
    igraph_set_error_handler(igraph_error_handler_ignore);
    igraph_set_interruption_handler(interrupt_after_deadline);
    return true;
  }();
  (void)installed;
}

/// Mean seconds per iteration of our solver, by case name, for the igraph/ours ratio.
std::map<std::string, double>& our_seconds() {
  static std::map<std::string, double> seconds;
  return seconds;
}

/// Our (optimal) clique size by case name, to check igraph agrees.
std::map<std::string, long>& our_clique_sizes() {
  static std::map<std::string, long> sizes;
  return sizes;
}

std::string geometric_key(std::size_t n, int density) { return std::to_string(n) + "/" + std::to_string(density); }

// ---------------------------------------------------------------------------------------------
// Random geometric graphs

void BM_Geometric_Ours(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  const int density = static_cast<int>(state.range(1));
  const BitsetGraph& graph = geometric_graph(n, density);
  quadrix::MaxCliqueOptions options;
  options.thread_count = static_cast<int>(state.range(2));
  quadrix::MaxCliqueResult result;
  const Clock::time_point start = Clock::now();
  for (auto _ : state) {
    options.deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(kOurCapSeconds));
    result = quadrix::find_maximum_clique(graph, options);
    benchmark::DoNotOptimize(result.clique.data());
  }
  const double mean = std::chrono::duration<double>(Clock::now() - start).count() / static_cast<double>(state.iterations());
  if (options.thread_count == 1 && result.status == quadrix::CliqueStatus::optimal) {
    our_seconds()[geometric_key(n, density)] = mean;
    our_clique_sizes()[geometric_key(n, density)] = static_cast<long>(result.size());
  }
  state.counters["clique"] = static_cast<double>(result.size());
  state.counters["optimal"] = result.status == quadrix::CliqueStatus::optimal ? 1.0 : 0.0;
  state.counters["branches"] = static_cast<double>(result.statistics.branches);
  state.counters["pruned"] = static_cast<double>(result.statistics.pruned_vertices);
  state.counters["degeneracy"] = static_cast<double>(result.statistics.degeneracy);
}

void BM_Geometric_Igraph(benchmark::State& state) {
  install_igraph_handlers();
  const auto n = static_cast<std::size_t>(state.range(0));
  const int density = static_cast<int>(state.range(1));
  const BitsetGraph& graph = geometric_graph(n, density);
  const IgraphCopy copy(graph);
  long size = 0;
  const Clock::time_point start = Clock::now();
  for (auto _ : state) {
    size = copy.clique_number();
    if (size < 0) {
      state.SkipWithError(("capped: igraph exceeded " + std::to_string(static_cast<int>(kIgraphCapSeconds)) + " s").c_str());
      break;
    }
  }
  if (size < 0) return;
  const double mean = std::chrono::duration<double>(Clock::now() - start).count() / static_cast<double>(state.iterations());
  state.counters["clique"] = static_cast<double>(size);
  const auto our_time = our_seconds().find(geometric_key(n, density));
  if (our_time != our_seconds().end()) state.counters["igraph_over_ours"] = mean / our_time->second;
  const auto our_size = our_clique_sizes().find(geometric_key(n, density));
  if (our_size != our_clique_sizes().end()) state.counters["agrees"] = size == our_size->second ? 1.0 : 0.0;
}

void geometric_arguments(benchmark::internal::Benchmark* benchmark, bool with_threads) {
  for (long n : {500L, 1500L, 4000L})
    for (long density : {1L, 5L, 10L, 20L, 30L}) {
      if (with_threads) {
        benchmark->Args({n, density, 1});
        benchmark->Args({n, density, 2});
      } else {
        benchmark->Args({n, density});
      }
    }
}

// ---------------------------------------------------------------------------------------------
// Compatibility graphs of planted correspondences (paper's four levels δ_m = 0.2 … 0.8 m)

void BM_Compatibility_Build(benchmark::State& state) {
  const PlantedCorrespondences& planted = planted_correspondences();
  for (auto _ : state) {
    quadrix::CompatibilityGraphs graphs = quadrix::build_compatibility_graphs(planted.source, planted.target);
    benchmark::DoNotOptimize(graphs.levels.data());
  }
  state.counters["correspondences"] = static_cast<double>(planted.source.cols());
  for (std::size_t k = 0; k < planted_graphs().levels.size(); ++k)
    state.counters["density_" + std::to_string(k + 1)] = planted_graphs().levels[k].density();
}

void BM_Compatibility_Graduated_Ours(benchmark::State& state) {
  const quadrix::CompatibilityGraphs& graphs = planted_graphs();
  quadrix::MaxCliqueOptions options;
  options.thread_count = static_cast<int>(state.range(0));
  quadrix::GraduatedCliqueResult result;
  const Clock::time_point start = Clock::now();
  for (auto _ : state) {
    result = quadrix::find_graduated_maximum_cliques(graphs.levels, options);
    benchmark::DoNotOptimize(result.levels.data());
  }
  const double mean = std::chrono::duration<double>(Clock::now() - start).count() / static_cast<double>(state.iterations());
  if (options.thread_count == 1) our_seconds()["compatibility"] = mean;
  for (std::size_t k = 0; k < result.levels.size(); ++k)
    state.counters["clique_" + std::to_string(k + 1)] = static_cast<double>(result.levels[k].size());
}

void BM_Compatibility_Graduated_Igraph(benchmark::State& state) {
  install_igraph_handlers();
  const quadrix::CompatibilityGraphs& graphs = planted_graphs();
  std::vector<std::unique_ptr<IgraphCopy>> copies;
  for (const BitsetGraph& level : graphs.levels) copies.push_back(std::make_unique<IgraphCopy>(level));
  std::vector<long> sizes(copies.size(), 0);
  bool capped = false;
  const Clock::time_point start = Clock::now();
  for (auto _ : state) {
    for (std::size_t k = 0; k < copies.size() && !capped; ++k) {
      sizes[k] = copies[k]->clique_number();
      capped = sizes[k] < 0;
    }
    if (capped) {
      state.SkipWithError(("capped: igraph exceeded " + std::to_string(static_cast<int>(kIgraphCapSeconds)) + " s").c_str());
      break;
    }
  }
  if (capped) return;
  const double mean = std::chrono::duration<double>(Clock::now() - start).count() / static_cast<double>(state.iterations());
  for (std::size_t k = 0; k < sizes.size(); ++k) state.counters["clique_" + std::to_string(k + 1)] = static_cast<double>(sizes[k]);
  const auto ours = our_seconds().find("compatibility");
  if (ours != our_seconds().end()) state.counters["igraph_over_ours"] = mean / ours->second;
}

/// The KITTI pairs of ../shared/data/pairs.tsv: loop closures k -> 4438 (k = 0..5) and odometry
/// 0 -> k (k = 1..5), as (source frame, target frame).
const std::vector<std::pair<int, int>> kKittiPairs = {{0, 4438}, {1, 4438}, {2, 4438}, {3, 4438}, {4, 4438}, {5, 4438},
                                                      {0, 1},    {0, 2},    {0, 3},    {0, 4},    {0, 5}};

/// One KITTI pair: both frames modelled with the HDL-64E preset, their quadric correspondences and
/// the four compatibility levels, built once. Not available when ../shared/data is absent.
struct KittiGraphs {
  std::size_t correspondences = 0;            ///< putative correspondences of the pair
  quadrix::CorrespondenceQuality quality;     ///< inliers within 0.5 m under the ground truth, recall (>= 3)
  quadrix::CompatibilityGraphs graphs;        ///< the four levels (delta_m = 0.2 ... 0.8 m)
  bool available = false;                     ///< false when the KITTI files are missing
};

/// The scene model of KITTI 00 frame `frame`, cached; nullptr when the file is absent.
const quadrix::SceneModel* kitti_model(int frame) {
  static std::map<int, std::unique_ptr<quadrix::SceneModel>> models;
  auto found = models.find(frame);
  if (found != models.end()) return found->second.get();
  char name[32];
  std::snprintf(name, sizeof(name), frame == 4438 ? "%06d.ply" : "%06d.bin", frame);
  const std::string path = std::string(QUADRIX_DATA_DIR) + "/kitti00/velodyne/" + name;
  std::unique_ptr<quadrix::SceneModel> model;
  if (std::filesystem::exists(path))
    model = std::make_unique<quadrix::SceneModel>(
        quadrix::model_scene(quadrix::read_point_cloud(path), quadrix::extraction_preset("vlp64"), quadrix::ModellingOptions{}).model);
  return models.emplace(frame, std::move(model)).first->second.get();
}

const KittiGraphs& kitti_graphs(std::size_t pair_index) {
  static std::map<std::size_t, KittiGraphs> cache;
  auto found = cache.find(pair_index);
  if (found != cache.end()) return found->second;
  KittiGraphs result;
  const quadrix::SceneModel* source = kitti_model(kKittiPairs[pair_index].first);
  const quadrix::SceneModel* target = kitti_model(kKittiPairs[pair_index].second);
  if (source && target) {
    const quadrix::CorrespondenceSet set = quadrix::establish_correspondences(*source, *target);
    result.correspondences = set.correspondences.size();
    char truth[64];
    std::snprintf(truth, sizeof(truth), "/kitti00/gt/T_%06d_from_%06d.txt", kKittiPairs[pair_index].second,
                  kKittiPairs[pair_index].first);
    result.quality = quadrix::evaluate_correspondences(*source, *target, set.correspondences,
                                                       quadrix::read_pose_matrix(std::string(QUADRIX_DATA_DIR) + truth));
    result.graphs = quadrix::build_compatibility_graphs(set.source_centers(*source), set.target_centers(*target));
    result.available = true;
  }
  return cache.emplace(pair_index, std::move(result)).first->second;
}

std::string kitti_key(std::size_t pair_index) { return "kitti" + std::to_string(pair_index); }

void kitti_arguments(benchmark::internal::Benchmark* benchmark) {
  for (std::size_t i = 0; i < kKittiPairs.size(); ++i) benchmark->Arg(static_cast<int64_t>(i));
  benchmark->ArgName("pair");
}

/// All four levels of a KITTI pair with our graduated solver (target: <= 20 ms).
void BM_Kitti_Graduated_Ours(benchmark::State& state) {
  const std::size_t pair_index = static_cast<std::size_t>(state.range(0));
  const KittiGraphs& kitti = kitti_graphs(pair_index);
  if (!kitti.available) {
    state.SkipWithError("real data absent: ../shared/data/kitti00");
    return;
  }
  quadrix::GraduatedCliqueResult result;
  const Clock::time_point start = Clock::now();
  for (auto _ : state) {
    result = quadrix::find_graduated_maximum_cliques(kitti.graphs.levels, quadrix::MaxCliqueOptions{});
    benchmark::DoNotOptimize(result.levels.data());
  }
  our_seconds()[kitti_key(pair_index)] =
      std::chrono::duration<double>(Clock::now() - start).count() / static_cast<double>(state.iterations());
  state.counters["correspondences"] = static_cast<double>(kitti.correspondences);
  state.counters["inliers"] = static_cast<double>(kitti.quality.inliers);
  state.counters["inlier_ratio"] = kitti.quality.inlier_ratio;
  state.counters["recalled"] = kitti.quality.recalled ? 1.0 : 0.0;
  for (std::size_t k = 0; k < result.levels.size(); ++k)
    state.counters["clique_" + std::to_string(k + 1)] = static_cast<double>(result.levels[k].size());
}

/// igraph's clique number on the same four levels of a KITTI pair, and its time over ours.
void BM_Kitti_Igraph(benchmark::State& state) {
  install_igraph_handlers();
  const std::size_t pair_index = static_cast<std::size_t>(state.range(0));
  const KittiGraphs& kitti = kitti_graphs(pair_index);
  if (!kitti.available) {
    state.SkipWithError("real data absent: ../shared/data/kitti00");
    return;
  }
  std::vector<std::unique_ptr<IgraphCopy>> copies;
  for (const BitsetGraph& level : kitti.graphs.levels) copies.push_back(std::make_unique<IgraphCopy>(level));
  std::vector<long> sizes(copies.size(), 0);
  const Clock::time_point start = Clock::now();
  for (auto _ : state) {
    for (std::size_t k = 0; k < copies.size(); ++k) sizes[k] = copies[k]->clique_number();
    if (std::any_of(sizes.begin(), sizes.end(), [](long size) { return size < 0; })) {
      state.SkipWithError(("capped: igraph exceeded " + std::to_string(static_cast<int>(kIgraphCapSeconds)) + " s").c_str());
      return;
    }
  }
  const double mean = std::chrono::duration<double>(Clock::now() - start).count() / static_cast<double>(state.iterations());
  for (std::size_t k = 0; k < sizes.size(); ++k) state.counters["clique_" + std::to_string(k + 1)] = static_cast<double>(sizes[k]);
  const auto ours = our_seconds().find(kitti_key(pair_index));
  if (ours != our_seconds().end()) state.counters["igraph_over_ours"] = mean / ours->second;
}

void BM_Compatibility_BuildAndGraduated(benchmark::State& state) {
  const PlantedCorrespondences& planted = planted_correspondences();
  std::size_t inliers_at_strictest = 0;
  for (auto _ : state) {
    const quadrix::CompatibilityGraphs graphs = quadrix::build_compatibility_graphs(planted.source, planted.target);
    const quadrix::GraduatedCliqueResult result = quadrix::find_graduated_maximum_cliques(graphs.levels);
    inliers_at_strictest = static_cast<std::size_t>(std::count_if(result.levels[0].clique.begin(), result.levels[0].clique.end(),
                                                                  [&](int v) { return static_cast<std::size_t>(v) < planted.inlier_count; }));
    benchmark::DoNotOptimize(result.levels.data());
  }
  state.counters["planted_inliers"] = static_cast<double>(planted.inlier_count);
  state.counters["inliers_in_level1_clique"] = static_cast<double>(inliers_at_strictest);
}

}  // namespace

BENCHMARK(BM_Geometric_Ours)->Apply([](benchmark::internal::Benchmark* b) { geometric_arguments(b, true); })
    ->ArgNames({"n", "density_pct", "threads"})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Geometric_Igraph)->Apply([](benchmark::internal::Benchmark* b) { geometric_arguments(b, false); })
    ->ArgNames({"n", "density_pct"})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Compatibility_Build)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Compatibility_Graduated_Ours)->Arg(1)->Arg(2)->ArgName("threads")->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Compatibility_Graduated_Igraph)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Compatibility_BuildAndGraduated)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Kitti_Graduated_Ours)->Apply(kitti_arguments)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Kitti_Igraph)->Apply(kitti_arguments)->Unit(benchmark::kMillisecond)->UseRealTime();

BENCHMARK_MAIN();
