// Optimal transformation selection (paper §"Optimal Transformation Selection", Algorithm 1 second
// half): for every candidate T_k, one-to-one nearest neighbours per semantic class (SNN) between
// the transformed source full centres and the target full centres, the f_pp filter, augmentation,
// and the score D_v(T_k) = mean over the kept pairs of rho_DCS(||e_R|| + ||e_t||); lowest wins.
#pragma once

#include "estimation/quadric_distance.h"
#include "geometry/quadric_record.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace quadrix {

/// Options of select_candidate (published defaults).
struct SelectionOptions {
  double dcs_phi = 0.5;                          ///< Φ of the DCS kernel applied to d = ||e_R|| + ||e_t|| (as rho(d^2))
  double manhattan_tolerance_degrees = 5.0;      ///< δ_g^e of f_pp in selection, degrees
  bool augment_non_central = true;               ///< Augment() the SNN pairs like in refinement
  std::optional<Eigen::Vector3d> source_ground_normal;  ///< v̂_g of the source cloud; unset: no f_pp filter
  std::optional<Eigen::Vector3d> target_ground_normal;  ///< v̂_g of the target cloud; unset: no f_pp filter
  std::vector<std::uint32_t> structure_labels;   ///< labels f_pp applies to; empty: every non-central quadric
  double max_neighbor_distance = std::numeric_limits<double>::infinity();  ///< SNN pairs farther apart are dropped, metres (paper: none)
};

/// The score of one candidate.
struct CandidateScore {
  std::size_t index = 0;           ///< position in the candidate list
  double score = std::numeric_limits<double>::infinity();  ///< D_v: mean DCS distance (inf when no term)
  std::size_t pair_count = 0;      ///< SNN pairs found (one-to-one per class)
  std::size_t filtered_count = 0;  ///< SNN pairs removed by f_pp
  std::size_t term_count = 0;      ///< terms averaged (kept pairs + augmented samples)
};

/// Outcome of the selection.
enum class SelectionStatus : std::uint8_t {
  Ok,             ///< a candidate with at least one scored term was chosen
  NoCandidates,   ///< the candidate list was empty
  NoValidScore,   ///< no candidate had a scored term (no shared labels, or everything filtered)
};

/// Every candidate's score and the winner.
struct SelectionResult {
  SelectionStatus status = SelectionStatus::NoCandidates;     ///< see SelectionStatus
  std::size_t best_index = 0;                                 ///< index of T* in the candidate list
  Eigen::Isometry3d best_transform = Eigen::Isometry3d::Identity();  ///< T* (identity unless Ok)
  std::vector<CandidateScore> scores;                         ///< one per candidate, in input order
  double best_to_second_ratio = std::numeric_limits<double>::quiet_NaN();  ///< D_v(best) / D_v(second best): near 1 = unclear choice (NaN with < 2 valid scores)
};

/// SNN: one-to-one nearest neighbours per semantic label between T * t_f,x and t_f,y (greedy by
/// increasing distance among each source's nearest target of the same label); pairs farther than
/// max_distance are dropped. Returned in increasing distance order.
std::vector<RecordCorrespondence> semantic_nearest_neighbors(const std::vector<QuadricRecord>& source,
                                                             const std::vector<QuadricRecord>& target,
                                                             const Eigen::Isometry3d& transform,
                                                             double max_distance = std::numeric_limits<double>::infinity());

/// The selection score D_v of one transform (Algorithm 1): SNN pairs, f_pp, Augment(), then the
/// mean of rho_DCS((||e_R|| + ||e_t||)^2) with Φ = options.dcs_phi, where rho_DCS is the kernel of
/// RobustLoss::Dcs. Shapes come from decompose_records (sizes must match the records).
CandidateScore score_candidate(const std::vector<QuadricRecord>& source, const std::vector<QuadricDecomposition>& source_shapes,
                               const std::vector<QuadricRecord>& target, const std::vector<QuadricDecomposition>& target_shapes,
                               const Eigen::Isometry3d& transform, const SelectionOptions& options = {});

/// T* = argmin_k D_v(T_k) over the candidates (Algorithm 1, Optimal Transformation Selection).
/// Throws quadrix::Error if dcs_phi <= 0 or a candidate is not finite.
SelectionResult select_candidate(const std::vector<QuadricRecord>& source, const std::vector<QuadricRecord>& target,
                                 const std::vector<Eigen::Isometry3d>& candidates, const SelectionOptions& options = {});

}  // namespace quadrix
