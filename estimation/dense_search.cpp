// Dense search that settles an ambiguous answer (see dense_search.h).
#include "estimation/dense_search.h"

#include "estimation/registration.h"
#include "geometry/error.h"
#include "geometry/spatial_index.h"

#include <Eigen/Eigenvalues>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iomanip>
#include <memory>
#include <mutex>
#include <sstream>
#include <optional>

namespace quadrix {

namespace {

// One point per occupied cube of edge `voxel` (the first met), as a 3×N matrix.
Eigen::Matrix3Xd thin(const PointCloud& cloud, double voxel) {
  CellMap<char> occupied(cloud.size() / 2);
  std::vector<Eigen::Vector3d> kept;
  kept.reserve(cloud.size() / 2);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d p = cloud.point(i);
    if (!p.allFinite()) continue;
    if (occupied.insert(cell_key((p / voxel).array().floor().cast<int>()))) kept.push_back(p);
  }
  Eigen::Matrix3Xd points(3, static_cast<Eigen::Index>(kept.size()));
  for (std::size_t i = 0; i < kept.size(); ++i) points.col(static_cast<Eigen::Index>(i)) = kept[i];
  return points;
}

// Optima are scored at measure_overlap's distance, the one check_overlap judges answers by, m.
constexpr double kOverlapDistance = 0.3;

}  // namespace

// Both clouds thinned, the target indexed and hashed once for scoring every optimum of every search
// that shares them. A target point's normal is fitted the first time ICP pairs a source point with
// it: the starts reach a fraction of the target (on KITTI, fitting all 46,000 thinned points up
// front took about 37 ms of a 65 ms preparation).
struct DenseSearchPair::Prepared {
  double voxel_size = 0.0;
  Eigen::Matrix3Xd source;  // thinned source points
  PointIndex target_index{Eigen::Matrix3Xd(3, 0)};
  std::optional<TargetCoverage> coverage;  // the thinned target at kOverlapDistance
  std::size_t normal_neighbours = 10;      // neighbours of each normal's plane fit
  mutable Eigen::Matrix3Xd target_normals;                  // column i valid once normal_fitted[i] has run
  mutable std::unique_ptr<std::once_flag[]> normal_fitted;  // one per target point; ICP threads share the pair

  // The normal of target point `index`: the least-variance direction of its nearest neighbours'
  // plane fit (zero with fewer than 3 neighbours).
  Eigen::Vector3d normal(Eigen::Index index) const {
    std::call_once(normal_fitted[static_cast<std::size_t>(index)], [&] {
      const std::vector<Neighbor> neighbours = target_index.nearest(target_index.points().col(index), normal_neighbours);
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (const Neighbor& n : neighbours) mean += target_index.points().col(static_cast<Eigen::Index>(n.index));
      mean /= static_cast<double>(std::max<std::size_t>(neighbours.size(), 1));
      Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
      for (const Neighbor& n : neighbours) {
        const Eigen::Vector3d d = target_index.points().col(static_cast<Eigen::Index>(n.index)) - mean;
        scatter += d * d.transpose();
      }
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
      solver.computeDirect(scatter);
      target_normals.col(index) = neighbours.size() >= 3 ? Eigen::Vector3d(solver.eigenvectors().col(0)) : Eigen::Vector3d::Zero();
    });
    return target_normals.col(index);
  }
};

DenseSearchPair::DenseSearchPair(const PointCloud& source, const PointCloud& target, const DenseSearchOptions& options) {
  validate_dense_search_options(options);
  // The source side and the target side are independent, and the target's coverage hash and k-d
  // tree are built from the same thinned points: on KITTI (two cores) building them concurrently
  // takes the preparation from about 35 to about 22 ms.
  auto prepared = std::make_shared<Prepared>();
  prepared->voxel_size = options.voxel_size;
  Eigen::Matrix3Xd thinned_target;
  tbb::parallel_invoke([&] { prepared->source = thin(source, options.voxel_size); },
                       [&] { thinned_target = thin(target, options.voxel_size); });
  tbb::parallel_invoke(
      [&] {
        PointCloud target_cloud;
        target_cloud.positions = thinned_target.cast<float>();
        prepared->coverage.emplace(target_cloud, kOverlapDistance);
      },
      [&] { prepared->target_index = PointIndex(thinned_target); });
  const Eigen::Index count = prepared->target_index.points().cols();
  prepared->normal_neighbours = options.normal_neighbours;
  prepared->target_normals.resize(3, count);
  prepared->normal_fitted = std::make_unique<std::once_flag[]>(static_cast<std::size_t>(count));
  prepared_ = std::move(prepared);
}

std::size_t DenseSearchPair::source_points() const { return static_cast<std::size_t>(prepared_->source.cols()); }

std::size_t DenseSearchPair::target_points() const { return static_cast<std::size_t>(prepared_->target_index.points().cols()); }

namespace {

// One search's view of a prepared pair: the shared clouds, and the source samples it aligns.
struct PreparedPair {
  const DenseSearchPair::Prepared& shared;
  Eigen::Matrix3Xd source;  // an even stride of at most source_samples thinned source points
  Eigen::Matrix3Xd coarse;  // every third of them, for the first pass of the search
};

// measure_overlap's fraction over the pair's own samples: those of `points` above `ground` (more
// than 0.5 m off it, when given) that the target covers after `transform`.
double covered_fraction(const PreparedPair& pair, const Eigen::Matrix3Xd& points, const Eigen::Isometry3d& transform,
                        const std::optional<Eigen::Vector4d>& ground) {
  std::size_t tested = 0, covered = 0;
  for (Eigen::Index i = 0; i < points.cols(); ++i) {
    const Eigen::Vector3d p = points.col(i);
    if (ground && std::abs(ground->head<3>().dot(p) + (*ground)(3)) < 0.5) continue;
    ++tested;
    covered += pair.shared.coverage->covers(transform * p) ? 1 : 0;
  }
  return tested > 0 ? static_cast<double>(covered) / static_cast<double>(tested) : 0.0;
}

// The search's samples of a prepared pair; its voxel size and normal fits must be the options'.
PreparedPair sample(const DenseSearchPair& prepared, const DenseSearchOptions& options) {
  const DenseSearchPair::Prepared& shared = prepared.prepared();
  if (shared.voxel_size != options.voxel_size || shared.normal_neighbours != options.normal_neighbours)
    throw Error("dense search: the pair was prepared with voxel_size " + std::to_string(shared.voxel_size) + " and " +
                std::to_string(shared.normal_neighbours) + " normal neighbours, the search asks for " +
                std::to_string(options.voxel_size) + " and " + std::to_string(options.normal_neighbours));
  PreparedPair pair{shared, {}, {}};
  const Eigen::Matrix3Xd& thinned_source = shared.source;
  const Eigen::Index samples = std::min<Eigen::Index>(thinned_source.cols(), static_cast<Eigen::Index>(std::max<std::size_t>(options.source_samples, 1)));
  pair.source.resize(3, samples);
  for (Eigen::Index i = 0; i < samples; ++i) pair.source.col(i) = thinned_source.col(i * thinned_source.cols() / std::max<Eigen::Index>(samples, 1));
  pair.coarse.resize(3, (samples + 2) / 3);
  for (Eigen::Index i = 0; i < pair.coarse.cols(); ++i) pair.coarse.col(i) = pair.source.col(3 * i);
  return pair;
}

// The point-to-plane pairs of `transform`: the rows of J (d residual / d [rotation, translation])
// and the residuals n·(T p − q), for source points whose nearest target point is close enough.
struct Linearisation {
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> gradient = Eigen::Matrix<double, 6, 1>::Zero();
  std::vector<double> residuals;
};

Linearisation linearise(const PreparedPair& pair, const Eigen::Matrix3Xd& source, const Eigen::Isometry3d& transform,
                        double maximum_distance) {
  // Each source point's pair (its nearest-point query and the target normal, most of the cost) is
  // found in parallel blocks, and the sums are taken after in point order, so the result is the
  // same on any number of threads. A search refining a single optimum then uses both cores: the
  // half-turn check's refinement of the answer took ~10 ms a KITTI pair on one.
  struct PointPair {
    Eigen::Matrix<double, 6, 1> row;  // d/dω of n·(exp(ω)p + τ) at 0, then d/dτ
    double residual = 0.0;
    bool paired = false;
  };
  std::vector<PointPair> pairs(static_cast<std::size_t>(source.cols()));
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, source.cols(), 128), [&](const tbb::blocked_range<Eigen::Index>& block) {
    for (Eigen::Index i = block.begin(); i < block.end(); ++i) {
      const Eigen::Vector3d p = transform * Eigen::Vector3d(source.col(i));
      const std::optional<Neighbor> nearest = pair.shared.target_index.nearest_within(p, maximum_distance);
      if (!nearest) continue;
      const Eigen::Vector3d n = pair.shared.normal(static_cast<Eigen::Index>(nearest->index));
      if (n.isZero()) continue;
      PointPair& found = pairs[static_cast<std::size_t>(i)];
      found.residual = n.dot(p - pair.shared.target_index.points().col(static_cast<Eigen::Index>(nearest->index)));
      found.row << p.cross(n), n;
      found.paired = true;
    }
  });
  Linearisation result;
  result.residuals.reserve(pairs.size());
  for (const PointPair& found : pairs) {
    if (!found.paired) continue;
    result.information += found.row * found.row.transpose();
    result.gradient += found.row * found.residual;
    result.residuals.push_back(std::abs(found.residual));
  }
  return result;
}

double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

// Point-to-plane ICP of `source` (the pair's samples or their coarse third) from `start`.
DenseOptimum run_icp(const PreparedPair& pair, const Eigen::Matrix3Xd& source, const Eigen::Isometry3d& start,
                     std::size_t iterations, const DenseSearchOptions& options) {
  DenseOptimum optimum;
  optimum.transform = start;
  for (std::size_t iteration = 0; iteration < iterations; ++iteration) {
    const Linearisation system = linearise(pair, source, optimum.transform, options.correspondence_distance);
    if (system.residuals.size() < 6) break;
    // Gauss-Newton step with a tiny damping so a rank-deficient corridor does not blow up.
    const Eigen::Matrix<double, 6, 6> damped = system.information + 1e-6 * system.information.trace() * Eigen::Matrix<double, 6, 6>::Identity();
    const Eigen::Matrix<double, 6, 1> step = -damped.ldlt().solve(system.gradient);
    if (!step.allFinite()) break;
    Eigen::Isometry3d update = Eigen::Isometry3d::Identity();
    const double angle = step.head<3>().norm();
    if (angle > 0.0) update.linear() = Eigen::AngleAxisd(angle, step.head<3>() / angle).toRotationMatrix();
    update.translation() = step.tail<3>();
    optimum.transform = update * optimum.transform;
    if (angle < 1e-5 && step.tail<3>().norm() < 1e-4) break;
  }
  optimum.median_residual = median(linearise(pair, source, optimum.transform, options.correspondence_distance).residuals);
  return optimum;
}

// "answer+2.0m" (along the weakest direction), "answer+2.0m/-2.5m" (and across it).
std::string shift_name(double along, double across) {
  std::ostringstream name;
  name << "answer" << std::showpos << std::fixed << std::setprecision(1) << along << "m";
  if (across != 0.0) name << "/" << across << "m";
  return name.str();
}

// The least-constrained translation at the answer, its share of the information, and the direction across it.
struct WeakestAxes {
  Eigen::Vector3d weakest;  // unit translation the target's normals constrain least
  double share = 0.0;       // its information over the largest eigenvalue, [0, 1]
  Eigen::Vector3d across;   // across it along the ground (without up: the middle eigenvector)
};

// Finds the weakest direction of the point-to-plane information at the answer, kept along the ground.
WeakestAxes find_weakest_axes(const Linearisation& at_answer, const std::optional<Eigen::Vector3d>& up) {
  // The weakest direction: the least-constrained translation of the point-to-plane information at
  // the answer (its translation block is the sum of n nᵀ over the pairs), kept along the ground.
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(at_answer.information.bottomRightCorner<3, 3>());
  Eigen::Vector3d direction = solver.eigenvectors().col(0);
  if (up && up->norm() > 0.0) {
    // Restricted to the ground plane: the 2×2 information in an orthonormal basis orthogonal to up.
    const Eigen::Vector3d u = up->normalized();
    Eigen::Matrix<double, 3, 2> basis;
    basis.col(0) = u.unitOrthogonal();
    basis.col(1) = u.cross(basis.col(0));
    const Eigen::Matrix2d along_ground = basis.transpose() * at_answer.information.bottomRightCorner<3, 3>() * basis;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> ground_solver(along_ground);
    direction = basis * ground_solver.eigenvectors().col(0);
  }
  WeakestAxes axes;
  axes.weakest = direction.normalized();
  const double largest = solver.eigenvalues()(2);
  axes.share = largest > 0.0 ? (axes.weakest.transpose() * at_answer.information.bottomRightCorner<3, 3>() *
                                axes.weakest)(0) / largest
                             : 0.0;
  axes.across = up && up->norm() > 0.0 ? Eigen::Vector3d(up->normalized().cross(axes.weakest).normalized())
                                       : Eigen::Vector3d(solver.eigenvectors().col(1));
  return axes;
}

// The starts of the search, each with the name its optimum reports.
struct NamedStarts {
  std::vector<Eigen::Isometry3d> transforms;
  std::vector<std::string> names;
  std::size_t first_global = 0;  // the global starts are [first_global, first_global + global_count)
  std::size_t global_count = 0;
};

// Lays out the starts: a grid around the answer, then every other candidate, then the identity.
NamedStarts lay_out_starts(const Eigen::Isometry3d& answer, const std::vector<Eigen::Isometry3d>& other_starts,
                           const std::vector<Eigen::Isometry3d>& global_starts, const WeakestAxes& axes,
                           const DenseSearchOptions& options) {
  NamedStarts starts;
  // A grid of starts: fine along the weakest direction, where the quadrics are least sure, and
  // coarse across it (along the ground), so an answer that is also off sideways is still reached.
  // With global starts the grid only covers the answer's neighbourhood: they reach the rest.
  const bool global = !global_starts.empty();
  const double range = global ? options.range_with_correlation : options.range;
  const double step = global ? options.step_with_correlation : options.step;
  const double across_range = global ? options.across_range_with_correlation : options.across_range;
  const long reach = static_cast<long>(std::floor(range / step + 1e-9));
  const long across_reach = static_cast<long>(std::floor(across_range / options.across_step + 1e-9));
  for (long j = -across_reach; j <= across_reach; ++j)
    for (long k = -reach; k <= reach; ++k) {
      const double along_shift = static_cast<double>(k) * step, across_shift = static_cast<double>(j) * options.across_step;
      Eigen::Isometry3d start = answer;
      start.pretranslate(along_shift * axes.weakest + across_shift * axes.across);
      starts.transforms.push_back(start);
      starts.names.push_back(shift_name(along_shift, across_shift));
    }
  for (std::size_t i = 0; i < other_starts.size(); ++i) {
    starts.transforms.push_back(other_starts[i]);
    starts.names.push_back("candidate " + std::to_string(i));
  }
  starts.first_global = starts.transforms.size();
  starts.global_count = global_starts.size();
  for (std::size_t i = 0; i < global_starts.size(); ++i) {
    starts.transforms.push_back(global_starts[i]);
    starts.names.push_back("correlation " + std::to_string(i));
  }
  starts.transforms.push_back(Eigen::Isometry3d::Identity());
  starts.names.push_back("identity");
  return starts;
}

// Runs the first pass: every start gets half the iterations on a third of the samples.
std::vector<DenseOptimum> run_coarse_pass(const PreparedPair& pair, const NamedStarts& starts,
                                          const std::optional<Eigen::Vector4d>& source_ground,
                                          const DenseSearchOptions& options) {
  std::vector<DenseOptimum> optima(starts.transforms.size());
  tbb::parallel_for(std::size_t(0), starts.transforms.size(), [&](std::size_t i) {
    optima[i] = run_icp(pair, pair.coarse, starts.transforms[i], (options.iterations + 1) / 2, options);
    optima[i].start = starts.names[i];
    optima[i].overlap = covered_fraction(pair, pair.coarse, optima[i].transform, source_ground);
  });
  return optima;
}

// Whether two coarse optima are one local optimum reached from two starts (ICP from nearby starts
// converges to within millimetres; distinct optima lie metres or degrees apart).
bool same_optimum(const DenseOptimum& a, const DenseOptimum& b) {
  return translation_error(a.transform, b.transform) < 0.05 && rotation_error_degrees(a.transform, b.transform) < 0.2;
}

// The optima to refine: within refine_band of the best coarse overlap, best first, one per local
// optimum, at most max_refined. `twins` gets, for every other optimum in the band that is the same
// local optimum as a contender, (its index, the contender's index).
std::vector<std::size_t> choose_contenders(DenseSearchResult& result, const DenseSearchOptions& options,
                                           std::vector<std::pair<std::size_t, std::size_t>>& twins) {
  double best_coarse = 0.0;
  for (const DenseOptimum& optimum : result.optima) best_coarse = std::max(best_coarse, optimum.overlap);
  std::vector<std::size_t> in_band;
  for (std::size_t i = 0; i < result.optima.size(); ++i)
    if (result.optima[i].overlap >= best_coarse - options.refine_band) in_band.push_back(i);
  std::stable_sort(in_band.begin(), in_band.end(),
                   [&](std::size_t a, std::size_t b) { return result.optima[a].overlap > result.optima[b].overlap; });
  std::vector<std::size_t> contenders;
  for (const std::size_t i : in_band) {
    const auto twin = std::find_if(contenders.begin(), contenders.end(),
                                   [&](std::size_t c) { return same_optimum(result.optima[i], result.optima[c]); });
    if (twin != contenders.end()) twins.emplace_back(i, *twin);
    else contenders.push_back(i);
  }
  // At most `max_refined`. Low-overlap pairs (nothing aligns) put every optimum in the band; the
  // ones left out are counted, and the search then cannot settle.
  if (contenders.size() > options.max_refined) {
    result.unrefined_contenders = contenders.size() - options.max_refined;
    contenders.resize(options.max_refined);
    twins.erase(std::remove_if(twins.begin(), twins.end(),
                               [&](const auto& twin) {
                                 return std::find(contenders.begin(), contenders.end(), twin.second) == contenders.end();
                               }),
                twins.end());
  }
  return contenders;
}

// Refines the contenders with the full iterations on all samples and scores them again.
void refine_contenders(const PreparedPair& pair, const std::vector<std::size_t>& contenders,
                       const std::optional<Eigen::Vector4d>& source_ground, const DenseSearchOptions& options,
                       std::vector<DenseOptimum>& optima) {
  tbb::parallel_for(std::size_t(0), contenders.size(), [&](std::size_t k) {
    DenseOptimum& optimum = optima[contenders[k]];
    const std::string start = optimum.start;
    optimum = run_icp(pair, pair.source, optimum.transform, options.iterations, options);
    optimum.start = start;
    optimum.refined = true;
    optimum.overlap = covered_fraction(pair, pair.source, optimum.transform, source_ground);
  });
}

// Picks the highest overlap, its best rival that disagrees with it, and the margin between the two,
// among the optima not screened out (among all when every refined one is).
void pick_best_and_rival(DenseSearchResult& result, double translation_disagreement,
                         double rotation_disagreement_degrees) {
  const bool any_kept = std::any_of(result.optima.begin(), result.optima.end(),
                                    [](const DenseOptimum& optimum) { return optimum.refined && !optimum.screened_out; });
  const auto eligible = [&](std::size_t i) { return !any_kept || !result.optima[i].screened_out; };
  std::optional<std::size_t> best_index;
  for (std::size_t i = 0; i < result.optima.size(); ++i)
    if (eligible(i) && (!best_index || result.optima[i].overlap > result.optima[*best_index].overlap)) best_index = i;
  result.best = *best_index;
  const Eigen::Isometry3d& best = result.optima[result.best].transform;
  for (std::size_t i = 0; i < result.optima.size(); ++i) {
    if (!eligible(i)) continue;
    const bool disagrees = translation_error(result.optima[i].transform, best) > translation_disagreement ||
                           rotation_error_degrees(result.optima[i].transform, best) > rotation_disagreement_degrees;
    if (disagrees && (!result.rival || result.optima[i].overlap > result.optima[*result.rival].overlap)) result.rival = i;
  }
  result.margin = result.optima[result.best].overlap - (result.rival ? result.optima[*result.rival].overlap : 0.0);
}

// Whether `best` lies inside the grid of starts, one fine step in from its ends along the weakest direction.
bool lies_inside_grid(const Eigen::Isometry3d& best, const Eigen::Isometry3d& answer, const WeakestAxes& axes,
                      const DenseSearchOptions& options) {
  // Beyond, a better optimum nobody started near may lie just outside, so the winner's
  // margin over the optima found means little (on the 3DTK pair 2->1 started 10 m off, the grid's
  // last start reaches a wrong optimum that beats the empty rest of the grid).
  const Eigen::Vector3d moved = best.translation() - answer.translation();
  return std::abs(moved.dot(axes.weakest)) <= options.range - options.step + 1e-9 &&
         std::abs(moved.dot(axes.across)) <= options.across_range + 1e-9;
}

}  // namespace

void validate_dense_search_options(const DenseSearchOptions& options) {
  const auto fail = [](const std::string& key, const std::string& expected, double value) {
    std::ostringstream message;
    message << "option 'dense_search." << key << "' must be " << expected << ", got " << value;
    throw Error(message.str());
  };
  if (!(options.voxel_size > 0.0)) fail("voxel_size", "positive", options.voxel_size);
  if (!(options.correspondence_distance > 0.0)) fail("correspondence_distance", "positive", options.correspondence_distance);
  if (!(options.step > 0.0)) fail("step", "positive", options.step);
  if (!(options.range >= 0.0)) fail("range", "non-negative", options.range);
  if (!(options.across_step > 0.0)) fail("across_step", "positive", options.across_step);
  if (!(options.across_range >= 0.0)) fail("across_range", "non-negative", options.across_range);
  if (!(options.step_with_correlation > 0.0)) fail("step_with_correlation", "positive", options.step_with_correlation);
  if (!(options.range_with_correlation >= 0.0)) fail("range_with_correlation", "non-negative", options.range_with_correlation);
  if (!(options.across_range_with_correlation >= 0.0))
    fail("across_range_with_correlation", "non-negative", options.across_range_with_correlation);
  if (!(options.refine_band >= 0.0)) fail("refine_band", "non-negative", options.refine_band);
  if (options.max_refined < 1) fail("max_refined", "at least 1", static_cast<double>(options.max_refined));
  if (!(options.decisive_margin >= 0.0)) fail("decisive_margin", "non-negative", options.decisive_margin);
  if (!(options.ok_margin >= 0.0)) fail("ok_margin", "non-negative", options.ok_margin);
  if (!(options.minimum_overlap >= 0.0 && options.minimum_overlap <= 1.0)) fail("minimum_overlap", "in [0, 1]", options.minimum_overlap);
  if (options.normal_neighbours < 3) fail("normal_neighbours", "at least 3", static_cast<double>(options.normal_neighbours));
  if (options.source_samples < 6) fail("source_samples", "at least 6", static_cast<double>(options.source_samples));
  // The grid of starts, each an ICP run, is bounded (the defaults start 85 and 5): a range of 1e19 m
  // would ask for more starts than a long holds, and ICP from every one of them would never end.
  constexpr double kMaxGridStarts = 1000.0;
  const auto grid_starts = [&](double range, double step, double across_range) {
    return (2.0 * std::floor(range / step + 1e-9) + 1.0) * (2.0 * std::floor(across_range / options.across_step + 1e-9) + 1.0);
  };
  if (!(grid_starts(options.range, options.step, options.across_range) <= kMaxGridStarts))
    fail("range", "at most 1000 starts with step, across_range and across_step (got that many starts)",
         grid_starts(options.range, options.step, options.across_range));
  if (!(grid_starts(options.range_with_correlation, options.step_with_correlation,
                    options.across_range_with_correlation) <= kMaxGridStarts))
    fail("range_with_correlation",
         "at most 1000 starts with step_with_correlation, across_range_with_correlation and across_step (got that many starts)",
         grid_starts(options.range_with_correlation, options.step_with_correlation, options.across_range_with_correlation));
  validate_ground_correlation_options(options.correlation);
}

DenseOptimum align_point_to_plane(const PointCloud& source, const PointCloud& target, const Eigen::Isometry3d& start,
                                  const DenseSearchOptions& options) {
  const DenseSearchPair prepared(source, target, options);
  const PreparedPair pair = sample(prepared, options);
  DenseOptimum optimum = run_icp(pair, pair.source, start, options.iterations, options);
  optimum.start = "given";
  optimum.overlap = covered_fraction(pair, pair.source, optimum.transform, std::nullopt);
  return optimum;
}

DenseOptimum refine_answer(const DenseSearchPair& prepared, const Eigen::Isometry3d& answer,
                           const std::optional<Eigen::Vector4d>& source_ground, const DenseSearchOptions& options) {
  validate_dense_search_options(options);
  const PreparedPair pair = sample(prepared, options);
  // The two passes of search_weakest_direction for its answer's start (run_coarse_pass, then
  // refine_contenders), so the answer comes out as a search that refines it would give it.
  DenseOptimum optimum = run_icp(pair, pair.coarse, answer, (options.iterations + 1) / 2, options);
  optimum = run_icp(pair, pair.source, optimum.transform, options.iterations, options);
  optimum.start = "answer";
  optimum.refined = true;
  optimum.overlap = covered_fraction(pair, pair.source, optimum.transform, source_ground);
  return optimum;
}

DenseSearchResult search_weakest_direction(const PointCloud& source, const PointCloud& target, const Eigen::Isometry3d& answer,
                                           const std::vector<Eigen::Isometry3d>& other_starts,
                                           const std::vector<Eigen::Isometry3d>& global_starts,
                                           const std::optional<Eigen::Vector3d>& up,
                                           const std::optional<Eigen::Vector4d>& source_ground,
                                           double translation_disagreement, double rotation_disagreement_degrees,
                                           const DenseSearchOptions& options) {
  return search_weakest_direction(DenseSearchPair(source, target, options), answer, other_starts, global_starts, up,
                                  source_ground, translation_disagreement, rotation_disagreement_degrees, options);
}

DenseSearchResult search_weakest_direction(const DenseSearchPair& prepared, const Eigen::Isometry3d& answer,
                                           const std::vector<Eigen::Isometry3d>& other_starts,
                                           const std::vector<Eigen::Isometry3d>& global_starts,
                                           const std::optional<Eigen::Vector3d>& up,
                                           const std::optional<Eigen::Vector4d>& source_ground,
                                           double translation_disagreement, double rotation_disagreement_degrees,
                                           const DenseSearchOptions& options, const OptimumScreen& screen) {
  validate_dense_search_options(options);
  DenseSearchResult result;
  const PreparedPair pair = sample(prepared, options);
  result.source_points = static_cast<std::size_t>(pair.source.cols());
  result.target_points = static_cast<std::size_t>(pair.shared.target_index.points().cols());
  const WeakestAxes axes = find_weakest_axes(linearise(pair, pair.source, answer, options.correspondence_distance), up);
  result.weakest_direction = axes.weakest;
  result.weakest_share = axes.share;
  const NamedStarts starts = lay_out_starts(answer, other_starts, global_starts, axes, options);
  // Two passes. Every start first gets half the iterations on a third of the samples. Only the
  // optima whose coarse overlap is within `refine_band` of the best are then refined on all samples
  // and scored again. The others are too far below to win or to decide the margin, so they keep
  // their coarse values (`refined` false). On the six KITTI loop closures (85 starts each) this picks
  // the same winners as one full-size pass in about a third of the time.
  result.optima = run_coarse_pass(pair, starts, source_ground, options);
  std::vector<std::pair<std::size_t, std::size_t>> twins;
  const std::vector<std::size_t> contenders = choose_contenders(result, options, twins);
  refine_contenders(pair, contenders, source_ground, options, result.optima);
  if (screen) {
    tbb::parallel_for(std::size_t(0), contenders.size(), [&](std::size_t k) {
      DenseOptimum& optimum = result.optima[contenders[k]];
      optimum.screened_out = screen(optimum.transform);
    });
    for (const std::size_t k : contenders) result.screened_out += result.optima[k].screened_out ? 1 : 0;
  }
  // A start that reached a contender's local optimum shares its refinement (refining it again gives
  // the same result): a search with many starts near the truth is not left unsettled for them.
  for (const auto& [twin, contender] : twins) {
    const std::string start = result.optima[twin].start;
    result.optima[twin] = result.optima[contender];
    result.optima[twin].start = start;
  }
  pick_best_and_rival(result, translation_disagreement, rotation_disagreement_degrees);
  // Global starts (a search over every yaw and translation within its reach) cover the scene, so
  // the grid's edge bounds nothing: a better optimum cannot hide just beyond it unseen.
  result.best_in_searched_region =
      starts.global_count > 0 || lies_inside_grid(result.optima[result.best].transform, answer, axes, options);
  return result;
}

std::vector<Eigen::Vector3d> correlate_translations(const PointCloud& source, const PointCloud& target,
                                                    const std::optional<Eigen::Vector4d>& source_ground,
                                                    const std::optional<Eigen::Vector4d>& target_ground,
                                                    const Eigen::Matrix3d& rotation, const Eigen::Vector3d& around,
                                                    const Eigen::Vector3d& up, double reach, std::size_t count) {
  static constexpr double kCell = 1.0, kGroundClearance = 0.5, kSeparation = 3.0;
  static constexpr double kCoarseStep = 2.0;
  static constexpr std::size_t kSamples = 300, kRefined = 16;
  static constexpr std::size_t kMaximumCells = std::size_t(1) << 31;  // 256 MB of bits: a scan hundreds of metres across
  if (count == 0) return {};
  const auto above = [&](const std::optional<Eigen::Vector4d>& ground, const Eigen::Vector3d& point) {
    return !ground || std::abs(ground->head<3>().dot(point) + (*ground)(3)) >= kGroundClearance;
  };
  // Indices, not copies, of the points off the ground, the two clouds at the same time: copying both
  // to doubles, one after the other, took ~3.5 of the ~8 ms this correlation cost a KITTI pair
  // (now ~1.2 of ~6), and the source is only sampled.
  const auto indices_above = [&](const PointCloud& cloud, const std::optional<Eigen::Vector4d>& ground) {
    std::vector<std::uint32_t> kept;
    kept.reserve(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i)
      if (above(ground, cloud.point(i))) kept.push_back(static_cast<std::uint32_t>(i));
    return kept;
  };
  // The target's occupied cells as a dense bit grid over its box: a lookup is a few multiplications,
  // where a hash set made the correlation four times slower (measured on KITTI pairs).
  Eigen::Vector3d low = Eigen::Vector3d::Zero();
  Eigen::Array3i size = Eigen::Array3i::Zero();
  std::vector<bool> occupied;
  const auto cell_index = [&](const Eigen::Vector3d& point) -> std::optional<std::size_t> {
    const Eigen::Array3d cell = ((point - low) / kCell).array().floor();
    if ((cell < 0.0).any() || (cell >= size.cast<double>()).any()) return std::nullopt;
    return (static_cast<std::size_t>(cell.x()) * static_cast<std::size_t>(size.y()) + static_cast<std::size_t>(cell.y())) *
               static_cast<std::size_t>(size.z()) + static_cast<std::size_t>(cell.z());
  };
  bool target_fits = false;
  const auto grid_target = [&] {
    const std::vector<std::uint32_t> kept = indices_above(target, target_ground);
    if (kept.empty()) return;
    Eigen::AlignedBox3d box;
    for (const std::uint32_t i : kept) box.extend(target.point(i));
    low = box.min();
    size = ((box.max() - low) / kCell).array().floor().cast<int>() + 1;
    const std::size_t cells = static_cast<std::size_t>(size.x()) * static_cast<std::size_t>(size.y()) * static_cast<std::size_t>(size.z());
    if (cells > kMaximumCells) return;
    occupied.assign(cells, false);
    for (const std::uint32_t i : kept) occupied[*cell_index(target.point(i))] = true;
    target_fits = true;
  };
  // An even stride of the source points off the ground, rotated.
  std::vector<Eigen::Vector3d> samples;
  const auto sample_source = [&] {
    const std::vector<std::uint32_t> kept = indices_above(source, source_ground);
    if (kept.empty()) return;
    const std::size_t sample_count = std::min(kSamples, kept.size());
    const double stride = static_cast<double>(kept.size()) / static_cast<double>(sample_count);
    for (std::size_t k = 0; k < sample_count; ++k) samples.push_back(rotation * source.point(kept[static_cast<std::size_t>(k * stride)]));
  };
  tbb::parallel_invoke(grid_target, sample_source);
  if (!target_fits || samples.empty()) return {};
  const auto score_of = [&](const Eigen::Vector3d& translation) {
    std::size_t hits = 0;
    for (const Eigen::Vector3d& sample : samples) {
      const std::optional<std::size_t> cell = cell_index(sample + translation);
      hits += cell && occupied[*cell];
    }
    return hits;
  };
  const Eigen::Vector3d first = up.unitOrthogonal(), second = up.cross(first);
  // Coarse to fine: every 2 m within reach, then every 1 m around the best coarse translations
  // (one 1 m grid cost about 27 ms a KITTI pair, this about a tenth of it).
  const int steps = static_cast<int>(std::floor(reach / kCoarseStep));
  const int side = 2 * steps + 1;
  std::vector<std::pair<std::size_t, Eigen::Vector3d>> coarse(static_cast<std::size_t>(side) * static_cast<std::size_t>(side));
  tbb::parallel_for(0, side, [&](int row) {
    for (int column = 0; column < side; ++column) {
      const Eigen::Vector3d translation = around + (row - steps) * kCoarseStep * first + (column - steps) * kCoarseStep * second;
      coarse[static_cast<std::size_t>(row) * static_cast<std::size_t>(side) + static_cast<std::size_t>(column)] = {
          score_of(translation), translation};
    }
  });
  const auto better = [](const auto& a, const auto& b) { return a.first > b.first; };
  std::stable_sort(coarse.begin(), coarse.end(), better);
  std::vector<std::pair<std::size_t, Eigen::Vector3d>> fine;
  for (std::size_t k = 0; k < std::min(kRefined, coarse.size()); ++k)
    for (int row = -1; row <= 1; ++row)
      for (int column = -1; column <= 1; ++column) {
        const Eigen::Vector3d translation = coarse[k].second + row * kCell * first + column * kCell * second;
        fine.emplace_back(score_of(translation), translation);
      }
  std::stable_sort(fine.begin(), fine.end(), better);
  std::vector<Eigen::Vector3d> chosen;
  for (const auto& scored : fine) {
    if (chosen.size() >= count || scored.first == 0) break;
    const Eigen::Vector3d& translation = scored.second;
    const bool near_better = std::any_of(chosen.begin(), chosen.end(), [&](const Eigen::Vector3d& other) {
      return (translation - other).norm() < kSeparation;
    });
    if (!near_better) chosen.push_back(translation);
  }
  return chosen;
}

}  // namespace quadrix
