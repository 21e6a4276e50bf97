// Multi-level compatibility graphs of putative correspondences (paper §"Graph-based Outlier
// Pruning", Eq. of d_ij): correspondences i and j are consistent at level k when
//   d_ij = | ‖t_x,i − t_x,j‖ − ‖t_y,i − t_y,j‖ | ≤ δ_m^k
// on the full centres t^f of the matched quadrics. Thresholds ascend, so G_1 ⊆ G_2 ⊆ … ⊆ G_Kg.
#pragma once

#include "matching/max_clique.h"

#include <Eigen/Core>

#include <vector>

namespace quadrix {

/// Options of build_compatibility_graphs.
struct CompatibilityGraphOptions {
  /// δ_m per level (m), strictly ascending and non-negative: the paper's [0.2, 0.4, 0.6, 0.8].
  std::vector<double> thresholds{0.2, 0.4, 0.6, 0.8};
};

/// The nested compatibility graphs G_1 ⊆ … ⊆ G_Kg, one per threshold.
struct CompatibilityGraphs {
  std::vector<double> thresholds;   ///< δ_m of each level (m), as given
  std::vector<BitsetGraph> levels;  ///< graph of each level; vertex i = correspondence i
  double seconds = 0.0;             ///< wall-clock time of the construction
};

/// d_ij of the paper's Eq. for correspondences i and j (columns of the two centre matrices):
/// the rigid-motion-invariant difference of their centre distances. No range checks.
double pairwise_consistency_distance(const Eigen::Matrix3Xd& source_centres, const Eigen::Matrix3Xd& target_centres,
                                     Eigen::Index i, Eigen::Index j);

/// Builds one compatibility graph per threshold. Column i of `source_centres` (t_x,i) and of
/// `target_centres` (t_y,i) are the full centres of correspondence i. Each pair's d_ij is computed
/// once and assigned to every level whose threshold it meets (parallel over rows). Throws
/// quadrix::Error when the column counts differ, a centre is not finite, or the thresholds are
/// empty, negative, not finite or not strictly ascending.
CompatibilityGraphs build_compatibility_graphs(const Eigen::Matrix3Xd& source_centres,
                                               const Eigen::Matrix3Xd& target_centres,
                                               const CompatibilityGraphOptions& options = {});

}  // namespace quadrix
