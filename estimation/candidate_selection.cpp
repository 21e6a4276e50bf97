// Optimal transformation selection (Algorithm 1): SNN, f_pp, Augment(), mean DCS quadric distance.
#include "estimation/candidate_selection.h"

#include "geometry/error.h"
#include "geometry/spatial_index.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <queue>
#include <string>
#include <tuple>

namespace quadrix {

namespace {

// Target full centres grouped by semantic label, each group with its k-d tree (built once per
// selection, reused for every candidate transform).
struct LabelledCenters {
  std::vector<std::size_t> record_indices;  // target record of each indexed centre, increasing
  PointIndex index;
};
using TargetCenterIndex = std::map<std::uint32_t, LabelledCenters>;

TargetCenterIndex index_target_centers(const std::vector<QuadricRecord>& target) {
  std::map<std::uint32_t, std::vector<std::size_t>> members;
  for (std::size_t j = 0; j < target.size(); ++j) members[target[j].label].push_back(j);
  TargetCenterIndex index;
  for (auto& [label, records] : members) {
    Eigen::Matrix3Xd centers(3, static_cast<Eigen::Index>(records.size()));
    for (std::size_t n = 0; n < records.size(); ++n) centers.col(static_cast<Eigen::Index>(n)) = target[records[n]].full_center;
    index.emplace(label, LabelledCenters{std::move(records), PointIndex(std::move(centers))});
  }
  return index;
}

// SNN of Algorithm 1 against a prepared target index: the greedy one-to-one assignment by
// increasing (distance, source, target) over all same-label pairs, computed lazily with a heap
// holding each unmatched source's nearest not-yet-taken target (a k-d tree query that skips taken
// targets). Equal to sorting every same-label pair and taking them greedily, without that
// quadratic pair list (seconds and hundreds of MB with thousands of augmented points per label).
std::vector<RecordCorrespondence> nearest_pairs(const std::vector<QuadricRecord>& source,
                                                const std::vector<QuadricRecord>& target,
                                                const TargetCenterIndex& target_index,
                                                const Eigen::Isometry3d& transform, double max_distance) {
  std::map<std::uint32_t, std::vector<bool>> taken;  // per label, per indexed centre
  for (const auto& [label, group] : target_index) taken[label].assign(group.index.size(), false);
  std::vector<const LabelledCenters*> groups(source.size(), nullptr);
  std::vector<std::vector<bool>*> taken_of_source(source.size(), nullptr);
  std::vector<Eigen::Vector3d> moved(source.size());
  using Entry = std::tuple<double, std::size_t, std::size_t>;  // (distance, source, indexed centre of its label)
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> heap;
  // Pushes source i's nearest untaken same-label target when within max_distance.
  const auto offer = [&](std::size_t i) {
    const std::optional<Neighbor> nearest = groups[i]->index.nearest_not_excluded(moved[i], *taken_of_source[i]);
    if (!nearest) return;
    const std::size_t j = groups[i]->record_indices[nearest->index];
    const double distance = (moved[i] - target[j].full_center).norm();  // exact, as the brute-force definition
    if (distance <= max_distance) heap.emplace(distance, i, nearest->index);
  };
  for (std::size_t i = 0; i < source.size(); ++i) {
    const auto group = target_index.find(source[i].label);
    if (group == target_index.end()) continue;
    groups[i] = &group->second;
    taken_of_source[i] = &taken[source[i].label];
    moved[i] = transform * source[i].full_center;
    offer(i);
  }
  std::vector<RecordCorrespondence> pairs;
  while (!heap.empty()) {
    const auto [distance, i, local] = heap.top();
    heap.pop();
    (void)distance;
    std::vector<bool>& label_taken = *taken_of_source[i];
    if (label_taken[local]) {
      offer(i);  // its target went to a nearer pair: its next nearest untaken one
      continue;
    }
    label_taken[local] = true;
    pairs.push_back({i, groups[i]->record_indices[local]});
  }
  return pairs;
}

// D_v(T) against a prepared target index.
CandidateScore score_with_index(const std::vector<QuadricRecord>& source, const std::vector<QuadricDecomposition>& source_shapes,
                                const std::vector<QuadricRecord>& target, const std::vector<QuadricDecomposition>& target_shapes,
                                const TargetCenterIndex& target_index, const Eigen::Isometry3d& transform,
                                const SelectionOptions& options);

}  // namespace

// SNN of Algorithm 1: one-to-one nearest neighbours on full centres within each semantic label.
std::vector<RecordCorrespondence> semantic_nearest_neighbors(const std::vector<QuadricRecord>& source,
                                                             const std::vector<QuadricRecord>& target,
                                                             const Eigen::Isometry3d& transform, double max_distance) {
  return nearest_pairs(source, target, index_target_centers(target), transform, max_distance);
}

// D_v(T) of Eq. (optimal transformation selection).
CandidateScore score_candidate(const std::vector<QuadricRecord>& source, const std::vector<QuadricDecomposition>& source_shapes,
                               const std::vector<QuadricRecord>& target, const std::vector<QuadricDecomposition>& target_shapes,
                               const Eigen::Isometry3d& transform, const SelectionOptions& options) {
  return score_with_index(source, source_shapes, target, target_shapes, index_target_centers(target), transform, options);
}

namespace {

CandidateScore score_with_index(const std::vector<QuadricRecord>& source, const std::vector<QuadricDecomposition>& source_shapes,
                                const std::vector<QuadricRecord>& target, const std::vector<QuadricDecomposition>& target_shapes,
                                const TargetCenterIndex& target_index, const Eigen::Isometry3d& transform,
                                const SelectionOptions& options) {
  if (!(options.dcs_phi > 0.0) || !std::isfinite(options.dcs_phi))
    throw Error("select_candidate: dcs_phi must be finite and > 0");
  if (!transform.matrix().allFinite()) throw Error("select_candidate: candidate transform is not finite");
  CandidateScore score;
  const std::vector<RecordCorrespondence> pairs =
      nearest_pairs(source, target, target_index, transform, options.max_neighbor_distance);
  score.pair_count = pairs.size();

  FactorBuildOptions build;
  build.augment_non_central = options.augment_non_central;
  build.source_ground_normal = options.source_ground_normal;
  build.target_ground_normal = options.target_ground_normal;
  build.manhattan_tolerance_degrees = options.manhattan_tolerance_degrees;
  build.structure_labels = options.structure_labels;
  const FactorSet factors = build_quadric_factors(source, source_shapes, target, target_shapes, pairs, build);
  score.filtered_count = factors.filtered_count;
  score.term_count = factors.factors.size();
  if (factors.factors.empty()) return score;

  double sum = 0.0;
  for (const QuadricFactor& factor : factors.factors) {
    const Vector12d residual = quadric_distance(factor, transform);
    const double distance = residual.head<9>().norm() + residual.tail<3>().norm();
    sum += evaluate_robust_loss(RobustLoss::Dcs, options.dcs_phi, distance * distance).rho;
  }
  score.score = sum / static_cast<double>(factors.factors.size());
  return score;
}

}  // namespace

// Algorithm 1: T* = argmin over the candidates of D_v.
SelectionResult select_candidate(const std::vector<QuadricRecord>& source, const std::vector<QuadricRecord>& target,
                                 const std::vector<Eigen::Isometry3d>& candidates, const SelectionOptions& options) {
  SelectionResult result;
  if (candidates.empty()) return result;
  const std::vector<QuadricDecomposition> source_shapes = decompose_records(source);
  const std::vector<QuadricDecomposition> target_shapes = decompose_records(target);
  const TargetCenterIndex target_index = index_target_centers(target);
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    CandidateScore score = score_with_index(source, source_shapes, target, target_shapes, target_index, candidates[k], options);
    score.index = k;
    result.scores.push_back(score);
  }
  std::vector<const CandidateScore*> valid;
  for (const CandidateScore& score : result.scores)
    if (score.term_count > 0 && std::isfinite(score.score)) valid.push_back(&score);
  if (valid.empty()) {
    result.status = SelectionStatus::NoValidScore;
    return result;
  }
  std::stable_sort(valid.begin(), valid.end(),
                   [](const CandidateScore* a, const CandidateScore* b) { return a->score < b->score; });
  result.status = SelectionStatus::Ok;
  result.best_index = valid.front()->index;
  result.best_transform = candidates[result.best_index];
  if (valid.size() >= 2) {
    const double second = valid[1]->score;
    result.best_to_second_ratio = second > 0.0 ? valid.front()->score / second : (valid.front()->score > 0.0 ? 1.0 : 0.0);
  }
  return result;
}

}  // namespace quadrix
