// QuadricRecord: the 21-number representation of one scene element (paper Struct. 1) and the
// rule that completes degenerate attributes from the element's statistical pose and scale
// (paper Eq. (full attributes) in §"Quadric Modeling").
#pragma once

#include "geometry/quadric.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <cstdint>

namespace quadrix {

/// Statistical pose and scale of an element's points (paper §"Quadric Fitting", statistical method):
/// t_s = mean, R_s = covariance eigenvectors (descending variance, det +1), s_s = k_s * sigma_s.
struct StatisticalPose {
  Eigen::Vector3d scale = Eigen::Vector3d::Zero();          ///< s_s = k_s * sqrt(eigenvalues), descending
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();   ///< R_s, columns = principal directions
  Eigen::Vector3d center = Eigen::Vector3d::Zero();         ///< t_s, mean of the points
};

/// k_s of the statistical fitter: the Gaussian 90% two-sided quantile (paper: k_s ~ 1.645).
inline constexpr double kStatisticalScaleFactor = 1.645;

/// Statistical pose of a set of points (columns); k_s scales the standard deviations.
/// Fewer than one point gives a zero scale and identity rotation.
StatisticalPose statistical_pose(const Eigen::Matrix3Xd& points, double scale_factor = kStatisticalScaleFactor);

/// One element of a scene model: paper Struct. 1 (21 numbers).
struct QuadricRecord {
  std::uint32_t label = 0;                                        ///< l, semantic label
  Vector10d q = Vector10d::Zero();                                ///< quadric parameters A..J
  Eigen::Vector3d full_scale = Eigen::Vector3d::Zero();           ///< s_f
  Eigen::Quaterniond full_rotation = Eigen::Quaterniond::Identity();  ///< eta_f (w, x, y, z)
  Eigen::Vector3d full_center = Eigen::Vector3d::Zero();          ///< t_f

  /// [l, q(10), s_f(3), eta_f(w,x,y,z), t_f(3)]: the 21 numbers in Struct. 1 order.
  std::array<double, 21> to_array() const;
  /// Inverse of to_array(); throws quadrix::Error if the label is not a non-negative integer or
  /// any number is not finite.
  static QuadricRecord from_array(const std::array<double, 21>& values);
  /// The quadric of q.
  Quadric quadric() const { return Quadric::from_parameters(q); }
};

/// Builds the record of an element whose quadric was fitted as `type` (paper Eq. (full attributes)):
/// s_f = I_s s_q + (1-I_s) s_s;  R_f keeps the defined columns of R_q and completes the others from
/// R_s (projected orthogonal to the kept ones, re-orthonormalised, det +1);  t_f = t_q if I_t is all
/// ones, else t_s. Indicators come from the decomposition of `quadric` (symmetry-aware).
QuadricRecord make_quadric_record(std::uint32_t label, const Quadric& quadric, const StatisticalPose& statistics,
                                  const DecompositionTolerances& tolerances = {});

}  // namespace quadrix
