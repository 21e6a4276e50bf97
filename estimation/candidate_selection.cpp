// Optimal transformation selection (Algorithm 1): SNN, f_pp, Augment(), mean DCS quadric distance.
#include "estimation/candidate_selection.h"

#include "geometry/error.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <tuple>

namespace quadrix {

// SNN of Algorithm 1: one-to-one nearest neighbours on full centres within each semantic label.
std::vector<RecordCorrespondence> semantic_nearest_neighbors(const std::vector<QuadricRecord>& source,
                                                             const std::vector<QuadricRecord>& target,
                                                             const Eigen::Isometry3d& transform, double max_distance) {
  std::map<std::uint32_t, std::vector<std::size_t>> targets_by_label;
  for (std::size_t j = 0; j < target.size(); ++j) targets_by_label[target[j].label].push_back(j);

  // Each source's nearest target of its label, then greedy one-to-one by increasing distance.
  std::vector<std::tuple<double, std::size_t, std::size_t>> candidates;
  for (std::size_t i = 0; i < source.size(); ++i) {
    const auto found = targets_by_label.find(source[i].label);
    if (found == targets_by_label.end()) continue;
    const Eigen::Vector3d moved = transform * source[i].full_center;
    // All same-label targets ordered by distance, so a source whose nearest is taken can fall back.
    for (const std::size_t j : found->second) {
      const double distance = (moved - target[j].full_center).norm();
      if (distance <= max_distance) candidates.emplace_back(distance, i, j);
    }
  }
  std::sort(candidates.begin(), candidates.end());
  std::vector<bool> source_used(source.size(), false);
  std::vector<bool> target_used(target.size(), false);
  std::vector<RecordCorrespondence> pairs;
  for (const auto& [distance, i, j] : candidates) {
    (void)distance;
    if (source_used[i] || target_used[j]) continue;
    source_used[i] = true;
    target_used[j] = true;
    pairs.push_back({i, j});
  }
  return pairs;
}

// D_v(T) of Eq. (optimal transformation selection).
CandidateScore score_candidate(const std::vector<QuadricRecord>& source, const std::vector<QuadricDecomposition>& source_shapes,
                               const std::vector<QuadricRecord>& target, const std::vector<QuadricDecomposition>& target_shapes,
                               const Eigen::Isometry3d& transform, const SelectionOptions& options) {
  if (!(options.dcs_phi > 0.0) || !std::isfinite(options.dcs_phi))
    throw Error("select_candidate: dcs_phi must be finite and > 0");
  if (!transform.matrix().allFinite()) throw Error("select_candidate: candidate transform is not finite");
  CandidateScore score;
  const std::vector<RecordCorrespondence> pairs =
      semantic_nearest_neighbors(source, target, transform, options.max_neighbor_distance);
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

// Algorithm 1: T* = argmin over the candidates of D_v.
SelectionResult select_candidate(const std::vector<QuadricRecord>& source, const std::vector<QuadricRecord>& target,
                                 const std::vector<Eigen::Isometry3d>& candidates, const SelectionOptions& options) {
  SelectionResult result;
  if (candidates.empty()) return result;
  const std::vector<QuadricDecomposition> source_shapes = decompose_records(source);
  const std::vector<QuadricDecomposition> target_shapes = decompose_records(target);
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    CandidateScore score = score_candidate(source, source_shapes, target, target_shapes, candidates[k], options);
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
