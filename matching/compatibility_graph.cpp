// Multi-level compatibility graphs (paper §"Graph-based Outlier Pruning", Eq. of d_ij).
#include "matching/compatibility_graph.h"

#include "geometry/error.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <string>

namespace quadrix {

double pairwise_consistency_distance(const Eigen::Matrix3Xd& source_centres, const Eigen::Matrix3Xd& target_centres,
                                     Eigen::Index i, Eigen::Index j) {
  const double source_distance = (source_centres.col(i) - source_centres.col(j)).norm();
  const double target_distance = (target_centres.col(i) - target_centres.col(j)).norm();
  return std::abs(source_distance - target_distance);
}

CompatibilityGraphs build_compatibility_graphs(const Eigen::Matrix3Xd& source_centres,
                                               const Eigen::Matrix3Xd& target_centres,
                                               const CompatibilityGraphOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  if (source_centres.cols() != target_centres.cols())
    throw Error("build_compatibility_graphs: source_centres has " + std::to_string(source_centres.cols()) +
                " columns but target_centres has " + std::to_string(target_centres.cols()) +
                " (column i must be correspondence i in both)");
  if (!source_centres.allFinite() || !target_centres.allFinite())
    throw Error("build_compatibility_graphs: a full centre is not finite (NaN or infinity)");
  const std::vector<double>& thresholds = options.thresholds;
  if (thresholds.empty()) throw Error("CompatibilityGraphOptions::thresholds must not be empty");
  if (thresholds.size() >= 255)
    throw Error("CompatibilityGraphOptions::thresholds: at most 254 levels, got " + std::to_string(thresholds.size()));
  for (std::size_t k = 0; k < thresholds.size(); ++k) {
    if (!std::isfinite(thresholds[k]) || thresholds[k] < 0.0)
      throw Error("CompatibilityGraphOptions::thresholds[" + std::to_string(k) + "] = " +
                  std::to_string(thresholds[k]) + " must be finite and >= 0 (metres)");
    if (k > 0 && !(thresholds[k] > thresholds[k - 1]))
      throw Error("CompatibilityGraphOptions::thresholds must be strictly ascending (progressively relaxed "
                  "δ_m); thresholds[" + std::to_string(k) + "] = " + std::to_string(thresholds[k]) +
                  " follows " + std::to_string(thresholds[k - 1]));
  }

  const std::size_t n = static_cast<std::size_t>(source_centres.cols());
  const std::size_t level_count = thresholds.size();
  const auto no_edge = static_cast<std::uint8_t>(level_count);

  // Pass 1: d_ij once per unordered pair -> the first level whose threshold it meets (both halves
  // of the symmetric matrix are written; distinct bytes, so rows run in parallel without races).
  std::vector<std::uint8_t> first_level(n * n, no_edge);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 16), [&](const tbb::blocked_range<std::size_t>& rows) {
    for (std::size_t i = rows.begin(); i != rows.end(); ++i) {
      for (std::size_t j = i + 1; j < n; ++j) {
        const double d = pairwise_consistency_distance(source_centres, target_centres, static_cast<Eigen::Index>(i),
                                                       static_cast<Eigen::Index>(j));
        std::uint8_t level = 0;
        while (level < no_edge && d > thresholds[level]) ++level;
        first_level[i * n + j] = level;
        first_level[j * n + i] = level;
      }
    }
  });

  // Pass 2: each row's words for every level (row i is written only by its own task).
  CompatibilityGraphs graphs;
  graphs.thresholds = thresholds;
  graphs.levels.assign(level_count, BitsetGraph(n));
  const std::size_t words = graphs.levels.front().words_per_row();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 16), [&](const tbb::blocked_range<std::size_t>& rows) {
    std::vector<BitsetGraph::Word> level_words(level_count);
    for (std::size_t i = rows.begin(); i != rows.end(); ++i) {
      const std::uint8_t* row_levels = first_level.data() + i * n;
      for (std::size_t w = 0; w < words; ++w) {
        std::fill(level_words.begin(), level_words.end(), 0);
        const std::size_t end = std::min(n, (w + 1) * BitsetGraph::kBitsPerWord);
        for (std::size_t j = w * BitsetGraph::kBitsPerWord; j < end; ++j) {
          const BitsetGraph::Word bit = BitsetGraph::Word{1} << (j % BitsetGraph::kBitsPerWord);
          for (std::size_t k = row_levels[j]; k < level_count; ++k) level_words[k] |= bit;
        }
        for (std::size_t k = 0; k < level_count; ++k) graphs.levels[k].mutable_row(i)[w] = level_words[k];
      }
    }
  });
  graphs.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return graphs;
}

}  // namespace quadrix
