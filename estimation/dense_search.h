// Dense search that settles an ambiguous answer (beyond the paper, which stops at selection; its
// failure cases are scenes whose structure barely fixes one translation, such as a long wall that
// repeats along the motion). The quadrics then support several answers a few metres apart, or
// only one wrong one. The points still tell them apart: point-to-plane ICP is started from a grid
// around the answer (fine along the direction the target's surfaces constrain least, coarse across
// it), from the other quadric candidates and from not moving, and the local optimum that puts the
// most source points on the target wins. verify_registration calls it `ok` only when it beats
// every distinct optimum by a clear margin and lands enough of the source on the target.
#pragma once

#include "estimation/ground_correlation.h"
#include "estimation/overlap.h"
#include "geometry/point_cloud.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace quadrix {

/// Options of search_weakest_direction.
struct DenseSearchOptions {
  bool enabled = true;                   ///< register_clouds runs the search on `ambiguous` answers
  double voxel_size = 0.15;              ///< both clouds are thinned to one point per cube of this edge, m
  std::size_t source_samples = 3000;     ///< source points ICP aligns (an even stride over the thinned source)
  std::size_t normal_neighbours = 10;    ///< target neighbours of each target normal's plane fit
  double correspondence_distance = 0.5;  ///< ICP drops pairs farther apart than this, m
  std::size_t iterations = 20;           ///< point-to-plane Gauss-Newton iterations per start (fewer when converged)
  double step = 1.0;                     ///< spacing of the starts along the weakest direction, m
  double range = 8.0;                    ///< the starts reach this far either side of the answer along it, m
  double across_step = 2.5;              ///< spacing of the starts across the weakest direction (along the ground), m
  double across_range = 5.0;             ///< the starts reach this far either side of the answer across it, m
  double range_with_correlation = 4.0;   ///< with global starts (the correlation over the ground's poses), the grid reaches only this far along the weakest direction, m: the poses reach the rest of the street (no status changed on the synthetic sets or pairs.tsv; docs/registration.md)
  double step_with_correlation = 2.0;    ///< with global starts, spacing of the grid along the weakest direction, m
  double across_range_with_correlation = 0.0;  ///< with global starts, the grid reaches this far across the weakest direction, m
  double refine_band = 0.1;              ///< optima whose first-pass overlap is within this of the best are refined on all samples
  std::size_t max_refined = 12;          ///< at most this many (the best first); more in the band leaves the search unsettled
  double minimum_overlap = 0.4;          ///< and put at least this fraction of the source on the target (wrong settles measured 0.23-0.33, right ones 0.44-0.79)
  double decisive_margin = 0.03;         ///< the winner's overlap must beat every distinct optimum's by this to be `ok` (about 2.5 standard errors of a difference of two fractions over the same 3,000 samples)
  double ok_margin = 0.03;               ///< a winner that settles must also beat them by this to be `ok`, else it is the answer, `ambiguous` (at or below decisive_margin: no effect)
  GroundCorrelationOptions correlation;  ///< register_clouds also starts ICP from the poses of the correlation over yaw and ground translation (correlation.poses 0: none)
};

/// Throws quadrix::Error naming the first option out of range (e.g. "option 'dense_search.voxel_size'
/// must be positive, got 0"): voxel_size, correspondence_distance, step, across_step and
/// step_with_correlation positive, range, across_range, range_with_correlation,
/// across_range_with_correlation, refine_band, decisive_margin and ok_margin not negative, minimum_overlap in [0, 1],
/// max_refined at least 1, normal_neighbours at least 3, source_samples at least 6, at most 1,000
/// grid starts (with and without the correlation's poses); then the
/// correlation's options (validate_ground_correlation_options).
void validate_dense_search_options(const DenseSearchOptions& options);

/// Where one ICP run started and where it ended.
struct DenseOptimum {
  std::string start;                                            ///< "answer+2.0m" (shift along the weakest direction), "candidate 1", "identity"
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();  ///< the local optimum ICP reached
  double overlap = 0.0;                                         ///< measure_overlap's fraction there (same sampling for every optimum)
  double median_residual = 0.0;                                 ///< median point-to-plane distance of its ICP pairs, m
  bool refined = false;                                         ///< refined on all samples (else the first pass's third, too far below the best to matter)
  bool screened_out = false;                                    ///< refined, and the search's screen ruled it out: neither best nor rival while another optimum is not
};

/// Rules out a refined optimum of a dense search by its transform (true: neither best nor rival),
/// e.g. one that puts façades where the other sensor saw through (check_free_space).
using OptimumScreen = std::function<bool(const Eigen::Isometry3d&)>;

/// What search_weakest_direction found.
struct DenseSearchResult {
  Eigen::Vector3d weakest_direction = Eigen::Vector3d::UnitX();  ///< unit translation the target's normals constrain least (target frame)
  double weakest_share = 0.0;                                    ///< its eigenvalue over the largest of the translation information, [0, 1]
  std::vector<DenseOptimum> optima;                              ///< one per start, in start order
  std::size_t best = 0;                                          ///< index of the highest overlap in `optima`
  std::optional<std::size_t> rival;                              ///< the highest-overlap optimum that disagrees with the best, if any
  double margin = 0.0;                                           ///< best overlap minus the rival's (the best overlap when there is no rival)
  bool best_in_searched_region = false;                         ///< global starts were given, or the best lies inside the grid of starts (within range - step along, across_range across); else the search cannot settle
  std::size_t unrefined_contenders = 0;                          ///< optima within refine_band of the best left unrefined (beyond max_refined): the search cannot settle
  std::size_t screened_out = 0;                                  ///< refined optima the screen ruled out (distinct local optima, twins not counted)
  std::size_t source_points = 0;                                 ///< thinned source points ICP aligned
  std::size_t target_points = 0;                                 ///< thinned target points with a normal
};

/// Aligns `source` to `target` by point-to-plane ICP from `start` (Gauss-Newton on the linearised
/// rotation, pairs by nearest target point within `options.correspondence_distance`). Both are
/// thinned by `options.voxel_size`; target normals come from plane fits over the nearest
/// `options.normal_neighbours` points. Returns the optimum and its median residual.
/// Throws quadrix::Error for options out of range (validate_dense_search_options).
DenseOptimum align_point_to_plane(const PointCloud& source, const PointCloud& target, const Eigen::Isometry3d& start,
                                  const DenseSearchOptions& options = {});

/// Both clouds of dense searches prepared once: thinned to one point per cube of
/// `options.voxel_size` (the first point met), the target indexed (k-d tree) and hashed at
/// measure_overlap's distance. Each target normal is fitted (over `options.normal_neighbours`
/// points) the first time a search pairs a source point with it, and kept for every later search.
/// verify_registration builds one for an answer's half-turn checks and dense search. Throws
/// quadrix::Error for options out of range (validate_dense_search_options).
class DenseSearchPair {
 public:
  /// Prepares `source` and `target` with `options.voxel_size` and `options.normal_neighbours`.
  DenseSearchPair(const PointCloud& source, const PointCloud& target, const DenseSearchOptions& options = {});
  /// Thinned source points (searches align an even stride of at most `source_samples` of them).
  std::size_t source_points() const;
  /// Thinned target points.
  std::size_t target_points() const;
  /// The prepared clouds (defined in dense_search.cpp, opaque to callers).
  struct Prepared;
  /// The prepared clouds, for the searches in dense_search.cpp.
  const Prepared& prepared() const { return *prepared_; }

 private:
  std::shared_ptr<const Prepared> prepared_;
};

/// Refines `answer` by point-to-plane ICP on `pair` as search_weakest_direction refines its answer's
/// start: half of `options.iterations` on a third of the `options.source_samples`, then all of them
/// on all; the optimum's overlap is measured on those samples (points near `source_ground` skipped).
/// `options.voxel_size` and `options.normal_neighbours` must be those `pair` was prepared with
/// (else quadrix::Error).
DenseOptimum refine_answer(const DenseSearchPair& pair, const Eigen::Isometry3d& answer,
                           const std::optional<Eigen::Vector4d>& source_ground, const DenseSearchOptions& options = {});

/// Runs ICP from `answer` shifted by k·step (|k·step| ≤ range) along the weakest translation
/// direction of the target's normals at `answer` (orthogonal to `up` when given: motions along the
/// ground) and by j·across_step (|j·across_step| ≤ across_range) across it, from each of
/// `other_starts`, from each of `global_starts` (poses of a search over the whole scene, such as
/// correlate_over_ground's, named "correlation k"; when there are any, the grid uses the
/// *_with_correlation range and step instead), and from the identity; scores every optimum by
/// measure_overlap (points near `source_ground` skipped) and names the best and its best distinct
/// rival (farther than `translation_disagreement` m or `rotation_disagreement_degrees` apart).
/// Throws quadrix::Error for options out of range (validate_dense_search_options).
DenseSearchResult search_weakest_direction(const PointCloud& source, const PointCloud& target, const Eigen::Isometry3d& answer,
                                           const std::vector<Eigen::Isometry3d>& other_starts,
                                           const std::vector<Eigen::Isometry3d>& global_starts,
                                           const std::optional<Eigen::Vector3d>& up,
                                           const std::optional<Eigen::Vector4d>& source_ground,
                                           double translation_disagreement, double rotation_disagreement_degrees,
                                           const DenseSearchOptions& options = {});

/// search_weakest_direction over clouds already prepared: `options.voxel_size` and
/// `options.normal_neighbours` must be those `pair` was prepared with (else quadrix::Error). When
/// `screen` is given, every refined optimum it rules out is neither the best nor the rival, unless
/// it rules out all the refined ones.
DenseSearchResult search_weakest_direction(const DenseSearchPair& pair, const Eigen::Isometry3d& answer,
                                           const std::vector<Eigen::Isometry3d>& other_starts,
                                           const std::vector<Eigen::Isometry3d>& global_starts,
                                           const std::optional<Eigen::Vector3d>& up,
                                           const std::optional<Eigen::Vector4d>& source_ground,
                                           double translation_disagreement, double rotation_disagreement_degrees,
                                           const DenseSearchOptions& options = {}, const OptimumScreen& screen = {});

/// Translations that land the most source points in space the target occupies under `rotation`,
/// best first (at most `count`, at least 3 m apart): the count of up to 300 source points (an even
/// stride) whose rotated and translated position falls in a 1 m cell holding target points, over
/// translations every 2 m within `reach` of `around` along the ground (orthogonal to `up`), then
/// every 1 m around the 16 best; the height stays `around`'s. Points within 0.5 m of their cloud's
/// ground plane (n . x + offset = 0, given as (n, offset)) are left out, since a shared ground is
/// occupied under any slide along it. check_half_turn starts ICP from these: the quadric votes reach
/// only translations that same-class quadrics agree on, this reaches a street's mirror image
/// anywhere along the street. Empty when either cloud has no point above its ground, `count` is 0,
/// or the target's box exceeds 2^31 cells of 1 m.
std::vector<Eigen::Vector3d> correlate_translations(const PointCloud& source, const PointCloud& target,
                                                    const std::optional<Eigen::Vector4d>& source_ground,
                                                    const std::optional<Eigen::Vector4d>& target_ground,
                                                    const Eigen::Matrix3d& rotation, const Eigen::Vector3d& around,
                                                    const Eigen::Vector3d& up, double reach, std::size_t count);

}  // namespace quadrix
