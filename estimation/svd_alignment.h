// Closed-form rigid alignment of corresponding points (Arun et al. 1987 / Umeyama 1991, no scale):
// the SVD initialisation T^0 = SVD(R_x, R_y, I*) of Algorithm 1 on the records' full centres t_f.
#pragma once

#include "estimation/quadric_distance.h"
#include "geometry/quadric_record.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace quadrix {

/// Outcome of a closed-form alignment.
enum class AlignmentStatus : std::uint8_t {
  Ok,          ///< a unique rotation and translation were found
  Degenerate,  ///< fewer than 3 (positively weighted) points, or the points of either side are collinear
};

/// The rigid transform minimising sum_i w_i ||R x_i + t - y_i||^2, with diagnostics.
struct RigidAlignment {
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();  ///< T = (R, t), det R = +1 (identity when degenerate)
  AlignmentStatus status = AlignmentStatus::Degenerate;         ///< Ok or Degenerate
  std::size_t point_count = 0;                                  ///< points with positive weight
  double rms_error = 0.0;                                       ///< weighted RMS of ||R x + t - y||, metres
  bool reflection_corrected = false;                            ///< the unconstrained optimum was a reflection (det -1) and was fixed
  std::string message;                                          ///< why the alignment is degenerate (empty when Ok)
};

/// Options of the alignment.
struct AlignmentOptions {
  double collinearity_tolerance = 1e-9;  ///< second eigenvalue of the weighted scatter below this * first: collinear
};

/// Aligns source points (columns) to target points (columns) with optional non-negative weights
/// (empty: all 1). The reflection case is handled by flipping the sign of the least singular
/// direction (Umeyama), so the result is always a rotation. Throws quadrix::Error if the sizes
/// differ, a weight is negative or not finite, or a coordinate is not finite.
RigidAlignment align_points(const Eigen::Matrix3Xd& source, const Eigen::Matrix3Xd& target,
                            const std::vector<double>& weights = {}, const AlignmentOptions& options = {});

/// The SVD initialisation of Algorithm 1: aligns the full centres t_f of corresponding records.
/// Throws quadrix::Error for an index out of range or a weight list whose size differs.
RigidAlignment align_full_centers(const std::vector<QuadricRecord>& source, const std::vector<QuadricRecord>& target,
                                  const std::vector<RecordCorrespondence>& correspondences,
                                  const std::vector<double>& weights = {}, const AlignmentOptions& options = {});

}  // namespace quadrix
