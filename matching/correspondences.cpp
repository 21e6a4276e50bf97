// Putative correspondences, paper §"Quadric Correspondence Initialization" and Eq. (f_qsq).
#include "matching/correspondences.h"

#include "geometry/error.h"

#include <Eigen/Dense>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <set>
#include <string>

namespace quadrix {
namespace {

/// Record indices per semantic label within [begin, end).
std::map<std::uint32_t, std::vector<std::uint32_t>> indices_by_label(const SceneModel& model, std::size_t begin,
                                                                     std::size_t end) {
  std::map<std::uint32_t, std::vector<std::uint32_t>> groups;
  for (std::size_t i = begin; i < end; ++i) groups[model.records[i].label].push_back(static_cast<std::uint32_t>(i));
  return groups;
}

void check_model(const SceneModel& model, const char* side) {
  if (model.types.size() != model.records.size() || model.augmented_begin > model.records.size())
    throw Error(std::string(side) + " model: " + std::to_string(model.records.size()) + " records but " +
                std::to_string(model.types.size()) + " types and augmented_begin " +
                std::to_string(model.augmented_begin) + " (expected one type per record, augmented_begin <= records)");
  if (model.augmented_descriptors.size() != model.augmented_count() && !model.augmented_descriptors.empty())
    throw Error(std::string(side) + " model: " + std::to_string(model.augmented_descriptors.size()) +
                " FPFH descriptors for " + std::to_string(model.augmented_count()) + " augmented points");
}

/// Ranking key of a candidate: masked scale distance first (Eq. f_qsq), full-scale distance second.
struct SimilarityKey {
  double masked = 0.0;  ///< ||diag(I_s)(s_x - s_y)||
  double full = 0.0;    ///< ||s_x - s_y||, tie-breaker (0 when ties keep model order)
  bool operator<(const SimilarityKey& other) const {
    return masked != other.masked ? masked < other.masked : full < other.full;
  }
};

/// Top-K_s mutual matches of one semantic class: I^l = I_x^l ∩ I_y^l.
void match_class(const SceneModel& source, const SceneModel& target, const std::vector<std::uint32_t>& sources,
                 const std::vector<std::uint32_t>& targets, std::uint32_t label, const CorrespondenceOptions& options,
                 std::vector<Correspondence>& out) {
  const std::size_t rows = sources.size();
  const std::size_t columns = targets.size();
  std::vector<SimilarityKey> keys(rows * columns);
  for (std::size_t i = 0; i < rows; ++i) {
    const QuadricRecord& x = source.records[sources[i]];
    const Eigen::Vector3d mask = degeneracy_indicators(source.types[sources[i]]).scale;
    for (std::size_t j = 0; j < columns; ++j) {
      const QuadricRecord& y = target.records[targets[j]];
      const Eigen::Vector3d difference = x.full_scale - y.full_scale;
      keys[i * columns + j] = {mask.cwiseProduct(difference).norm(),
                               options.break_ties_with_full_scale ? difference.norm() : 0.0};
    }
  }
  const std::size_t keep_per_source = std::min<std::size_t>(static_cast<std::size_t>(options.top_k_similar), columns);
  const std::size_t keep_per_target = std::min<std::size_t>(static_cast<std::size_t>(options.top_k_similar), rows);
  // I_x: for each source element, its K_s most similar targets (stable: ties keep model order).
  std::vector<char> chosen_by_source(rows * columns, 0);
  std::vector<std::uint32_t> order(columns);
  for (std::size_t i = 0; i < rows; ++i) {
    std::iota(order.begin(), order.end(), 0u);
    std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(keep_per_source), order.end(),
                      [&](std::uint32_t a, std::uint32_t b) {
                        const SimilarityKey& ka = keys[i * columns + a];
                        const SimilarityKey& kb = keys[i * columns + b];
                        return ka < kb || (!(kb < ka) && a < b);
                      });
    for (std::size_t k = 0; k < keep_per_source; ++k) chosen_by_source[i * columns + order[k]] = 1;
  }
  // I_y: for each target element, its K_s most similar sources; keep pairs chosen both ways.
  std::vector<std::uint32_t> source_order(rows);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> kept;
  for (std::size_t j = 0; j < columns; ++j) {
    std::iota(source_order.begin(), source_order.end(), 0u);
    std::partial_sort(source_order.begin(), source_order.begin() + static_cast<std::ptrdiff_t>(keep_per_target),
                      source_order.end(), [&](std::uint32_t a, std::uint32_t b) {
                        const SimilarityKey& ka = keys[a * columns + j];
                        const SimilarityKey& kb = keys[b * columns + j];
                        return ka < kb || (!(kb < ka) && a < b);
                      });
    for (std::size_t k = 0; k < keep_per_target; ++k)
      if (chosen_by_source[source_order[k] * columns + j]) kept.emplace_back(source_order[k], static_cast<std::uint32_t>(j));
  }
  std::sort(kept.begin(), kept.end());
  for (const auto& [i, j] : kept)
    out.push_back({sources[i], targets[j], label, false, -keys[i * columns + j].masked});
}

/// Mutual nearest neighbours in FPFH space between augmented points of one label.
void match_augmented(const SceneModel& source, const SceneModel& target, const std::vector<std::uint32_t>& sources,
                     const std::vector<std::uint32_t>& targets, std::uint32_t label, std::vector<Correspondence>& out) {
  const Eigen::Index rows = static_cast<Eigen::Index>(sources.size());
  const Eigen::Index columns = static_cast<Eigen::Index>(targets.size());
  Eigen::MatrixXf source_features(kFpfhSize, rows);
  Eigen::MatrixXf target_features(kFpfhSize, columns);
  for (Eigen::Index i = 0; i < rows; ++i)
    source_features.col(i) = Eigen::Map<const Eigen::VectorXf>(
        source.augmented_descriptors[sources[static_cast<std::size_t>(i)] - source.augmented_begin].data(), kFpfhSize);
  for (Eigen::Index j = 0; j < columns; ++j)
    target_features.col(j) = Eigen::Map<const Eigen::VectorXf>(
        target.augmented_descriptors[targets[static_cast<std::size_t>(j)] - target.augmented_begin].data(), kFpfhSize);
  // Squared distances |a|^2 + |b|^2 - 2 a.b as one matrix product (brute force beats a KD-tree in 33-D).
  Eigen::MatrixXf distances = -2.0f * source_features.transpose() * target_features;
  distances.colwise() += source_features.colwise().squaredNorm().transpose();
  distances.rowwise() += target_features.colwise().squaredNorm();
  std::vector<Eigen::Index> best_target(static_cast<std::size_t>(rows));
  for (Eigen::Index i = 0; i < rows; ++i) distances.row(i).minCoeff(&best_target[static_cast<std::size_t>(i)]);
  for (Eigen::Index j = 0; j < columns; ++j) {
    Eigen::Index best_source = 0;
    const float value = distances.col(j).minCoeff(&best_source);
    if (best_target[static_cast<std::size_t>(best_source)] == j)
      out.push_back({sources[static_cast<std::size_t>(best_source)], targets[static_cast<std::size_t>(j)], label, true,
                     -std::sqrt(std::max(0.0f, value))});
  }
}

Eigen::Matrix3Xd centers_of(const SceneModel& model, const std::vector<Correspondence>& correspondences, bool source_side) {
  Eigen::Matrix3Xd centers(3, static_cast<Eigen::Index>(correspondences.size()));
  for (std::size_t k = 0; k < correspondences.size(); ++k) {
    const std::uint32_t index = source_side ? correspondences[k].source : correspondences[k].target;
    if (index >= model.records.size())
      throw Error("correspondence " + std::to_string(k) + " names record " + std::to_string(index) + " of a model with " +
                  std::to_string(model.records.size()) + " records");
    centers.col(static_cast<Eigen::Index>(k)) = model.records[index].full_center;
  }
  return centers;
}

}  // namespace

Eigen::Matrix3Xd CorrespondenceSet::source_centers(const SceneModel& source) const {
  return centers_of(source, correspondences, true);
}

Eigen::Matrix3Xd CorrespondenceSet::target_centers(const SceneModel& target) const {
  return centers_of(target, correspondences, false);
}

double scale_similarity(const QuadricRecord& source, const QuadricRecord& target, QuadricType type) {
  return -degeneracy_indicators(type).scale.cwiseProduct(source.full_scale - target.full_scale).norm();
}

CorrespondenceSet establish_correspondences(const SceneModel& source, const SceneModel& target,
                                            const CorrespondenceOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  check_model(source, "source");
  check_model(target, "target");
  if (options.top_k_similar < 1)
    throw Error("correspondences: top_k_similar (K_s) must be at least 1, got " + std::to_string(options.top_k_similar));
  CorrespondenceSet result;
  const auto source_groups = indices_by_label(source, 0, source.augmented_begin);
  const auto target_groups = indices_by_label(target, 0, target.augmented_begin);
  for (const auto& [label, sources] : source_groups) {  // L_∩ = unique(L_x) ∩ unique(L_y)
    const auto found = target_groups.find(label);
    if (found == target_groups.end()) continue;
    ++result.shared_classes;
    match_class(source, target, sources, found->second, label, options, result.correspondences);
  }
  result.quadric_matches = result.correspondences.size();
  if (options.match_augmented_points && !source.augmented_descriptors.empty() && !target.augmented_descriptors.empty()) {
    const auto source_augmented = indices_by_label(source, source.augmented_begin, source.records.size());
    const auto target_augmented = indices_by_label(target, target.augmented_begin, target.records.size());
    for (const auto& [label, sources] : source_augmented) {
      const auto found = target_augmented.find(label);
      if (found != target_augmented.end()) match_augmented(source, target, sources, found->second, label, result.correspondences);
    }
  }
  result.augmented_matches = result.correspondences.size() - result.quadric_matches;
  result.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return result;
}

CorrespondenceQuality evaluate_correspondences(const SceneModel& source, const SceneModel& target,
                                               const std::vector<Correspondence>& correspondences,
                                               const Eigen::Isometry3d& source_to_target, double inlier_distance,
                                               std::size_t minimum_inliers) {
  CorrespondenceQuality quality;
  quality.count = correspondences.size();
  const Eigen::Matrix3Xd source_centers = centers_of(source, correspondences, true);
  const Eigen::Matrix3Xd target_centers = centers_of(target, correspondences, false);
  for (Eigen::Index k = 0; k < source_centers.cols(); ++k)
    if ((source_to_target * Eigen::Vector3d(source_centers.col(k)) - target_centers.col(k)).norm() <= inlier_distance)
      ++quality.inliers;
  quality.inlier_ratio = quality.count ? static_cast<double>(quality.inliers) / static_cast<double>(quality.count) : 0.0;
  quality.recalled = quality.inliers >= minimum_inliers;
  return quality;
}

std::size_t count_true_partners(const SceneModel& source, const SceneModel& target,
                                const Eigen::Isometry3d& source_to_target, double inlier_distance) {
  // Models hold at most a few hundred fitted records, so every pair of a label is compared.
  const auto target_groups = indices_by_label(target, 0, target.augmented_begin);
  std::size_t found = 0;
  for (std::size_t i = 0; i < source.augmented_begin; ++i) {
    const auto group = target_groups.find(source.records[i].label);
    if (group == target_groups.end()) continue;
    const Eigen::Vector3d placed = source_to_target * source.records[i].full_center;
    found += std::any_of(group->second.begin(), group->second.end(), [&](std::uint32_t j) {
      return (placed - target.records[j].full_center).norm() <= inlier_distance;
    }) ? 1 : 0;
  }
  return found;
}

}  // namespace quadrix
