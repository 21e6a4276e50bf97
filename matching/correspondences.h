// Putative quadric correspondences (paper §"Quadric Correspondence Initialization"): per semantic
// class shared by both models, top-K_s most similar by scale in each direction, kept when both
// directions agree (I = I_x ∩ I_y); augmented points by mutual-nearest FPFH with equal labels.
#pragma once

#include "fitting/scene_model.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <optional>
#include <vector>

namespace quadrix {

/// Options of establish_correspondences (paper defaults).
struct CorrespondenceOptions {
  int top_k_similar = 20;               ///< K_s: candidates kept per element in each direction
  bool match_augmented_points = true;   ///< match augmented points by FPFH (paper: yes)
  /// Paper Eq. (f_qsq) masks degenerate scale axes with I_s, so all planes, lines and points tie at
  /// similarity 0. When true (default) ties are broken by the full-scale distance ||s_f,x - s_f,y||
  /// (statistical extents on degenerate axes); when false ties keep model order (literal paper).
  bool break_ties_with_full_scale = true;
};

/// One putative correspondence between a source record and a target record.
struct Correspondence {
  std::uint32_t source = 0;   ///< index into the source SceneModel's records
  std::uint32_t target = 0;   ///< index into the target SceneModel's records
  std::uint32_t label = 0;    ///< shared semantic label
  bool augmented = false;     ///< an augmented-point match (FPFH) rather than a quadric match
  double similarity = 0.0;    ///< f_qsq (quadrics, <= 0) or minus the FPFH distance (augmented points)
};

/// Correspondences and their counts.
struct CorrespondenceSet {
  std::vector<Correspondence> correspondences;  ///< quadric matches first, then augmented-point matches
  std::size_t quadric_matches = 0;              ///< matches among fitted quadrics
  std::size_t augmented_matches = 0;            ///< matches among augmented points
  std::size_t shared_classes = 0;               ///< |L_∩|: semantic classes present in both models
  double time_ms = 0.0;                         ///< wall time

  /// Full centres t_f of the source side, one column per correspondence (input of the compatibility graph).
  Eigen::Matrix3Xd source_centers(const SceneModel& source) const;
  /// Full centres t_f of the target side, one column per correspondence.
  Eigen::Matrix3Xd target_centers(const SceneModel& target) const;
};

/// Paper Eq. (f_qsq): -||diag(I_s)(s_f,x - s_f,y)|| with I_s the scale indicator of `type`.
double scale_similarity(const QuadricRecord& source, const QuadricRecord& target, QuadricType type);

/// Builds the putative correspondences between two models (paper §"Quadric Correspondence Initialization").
CorrespondenceSet establish_correspondences(const SceneModel& source, const SceneModel& target,
                                            const CorrespondenceOptions& options = {});

/// Quality of a correspondence set against a ground-truth transform (paper Table "Evaluation of
/// Correspondence Establishment").
struct CorrespondenceQuality {
  std::size_t count = 0;         ///< number of correspondences
  std::size_t inliers = 0;       ///< correspondences whose transformed source full centre lies within the inlier distance
  double inlier_ratio = 0.0;     ///< inliers / count (0 when empty)
  bool recalled = false;         ///< at least `minimum_inliers` inliers (the pair counts for correspondence recall)
};

/// Scores correspondences with the ground truth `source_to_target` (maps source points into the
/// target frame): inlier when ||T t_f,x - t_f,y|| <= inlier_distance (paper: 0.5 m); recalled when
/// at least minimum_inliers (paper: 3) inliers.
CorrespondenceQuality evaluate_correspondences(const SceneModel& source, const SceneModel& target,
                                               const std::vector<Correspondence>& correspondences,
                                               const Eigen::Isometry3d& source_to_target,
                                               double inlier_distance = 0.5, std::size_t minimum_inliers = 3);

/// The true quadric correspondences any matcher could find (the stage before matching, for finding
/// where they are lost): fitted source records (not augmented points: those sample surfaces densely,
/// so nearly every one has a partner) with a partner in the target under the ground truth
/// `source_to_target`, i.e. a fitted target record of the same label whose full centre lies within
/// `inlier_distance` of the transformed source full centre (evaluate_correspondences' inlier rule).
std::size_t count_true_partners(const SceneModel& source, const SceneModel& target,
                                const Eigen::Isometry3d& source_to_target, double inlier_distance = 0.5);

}  // namespace quadrix
