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

// One source's same-label targets by increasing (distance, target index), fetched from the tree
// in growing batches so most sources touch only their few nearest targets.
struct SourceQueue {
  const LabelledCenters* group = nullptr;
  Eigen::Vector3d moved = Eigen::Vector3d::Zero();
  std::vector<std::pair<double, std::size_t>> fetched;  // (distance, target record), sorted
  std::size_t cursor = 0;
  std::size_t batch = 0;

  // The next not-yet-offered target within max_distance, or false when there is none.
  bool next(const std::vector<QuadricRecord>& target, double max_distance, std::pair<double, std::size_t>& out) {
    while (cursor == fetched.size()) {
      const std::size_t available = group->index.size();
      if (fetched.size() >= available) return false;
      // More than already fetched (which may exceed the last batch through ties), so the set grows.
      batch = std::min(available, std::max({std::size_t{4}, 2 * batch, fetched.size() + 1}));
      const std::size_t skip = fetched.size();
      fetched.clear();
      // Widen the k nearest to everything as near as the k-th, so targets tied at the batch
      // boundary are all fetched and the (distance, index) order stays exact across batches.
      const std::vector<Neighbor> nearest = group->index.nearest(moved, batch);
      const double reach = nearest.back().distance * (1.0 + 1e-9) + 1e-12;
      for (const Neighbor& neighbor : group->index.within_radius(moved, reach)) {
        const std::size_t j = group->record_indices[neighbor.index];
        fetched.emplace_back((moved - target[j].full_center).norm(), j);  // exact distance, as the brute force
      }
      std::sort(fetched.begin(), fetched.end());
      cursor = skip;
    }
    out = fetched[cursor++];
    return out.first <= max_distance;
  }
};

// SNN of Algorithm 1 against a prepared target index: the greedy one-to-one assignment by
// increasing (distance, source, target) over all same-label pairs, computed lazily with a heap
// holding each unmatched source's nearest not-yet-taken target. Equal to sorting every pair and
// taking them greedily (the previous quadratic form), in O((n + m) log m) for typical scenes.
std::vector<RecordCorrespondence> nearest_pairs(const std::vector<QuadricRecord>& source,
                                                const std::vector<QuadricRecord>& target,
                                                const TargetCenterIndex& target_index,
                                                const Eigen::Isometry3d& transform, double max_distance) {
  using Entry = std::tuple<double, std::size_t, std::size_t>;  // (distance, source, target)
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> heap;
  std::vector<SourceQueue> queues(source.size());
  for (std::size_t i = 0; i < source.size(); ++i) {
    const auto group = target_index.find(source[i].label);
    if (group == target_index.end()) continue;
    queues[i].group = &group->second;
    queues[i].moved = transform * source[i].full_center;
    std::pair<double, std::size_t> first;
    if (queues[i].next(target, max_distance, first)) heap.emplace(first.first, i, first.second);
  }
  std::vector<bool> target_used(target.size(), false);
  std::vector<RecordCorrespondence> pairs;
  while (!heap.empty()) {
    const auto [distance, i, j] = heap.top();
    heap.pop();
    if (!target_used[j]) {
      target_used[j] = true;
      pairs.push_back({i, j});
      continue;
    }
    std::pair<double, std::size_t> candidate;
    while (queues[i].next(target, max_distance, candidate)) {
      if (target_used[candidate.second]) continue;
      heap.emplace(candidate.first, i, candidate.second);
      break;
    }
    (void)distance;
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
