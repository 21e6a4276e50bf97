// What a back end needs from an answer (beyond the paper): Open3D's evaluation of a registration
// (fitness, inlier RMSE, the inlier correspondence set) and small_gicp's information matrix H =
// J^T J of the point-to-plane cost at the answer, for a pose graph's edge. Measured on the points
// the answer is judged by, after verification has settled it.
#pragma once

#include "geometry/point_cloud.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstddef>
#include <utility>
#include <vector>

namespace quadrix {

/// Options of measure_answer_quality.
struct AnswerQualityOptions {
  double correspondence_distance = 0.3;  ///< a source point with a target point within this after the answer is an inlier, m (the overlap check's distance, OverlapMeasure::distance)
  std::size_t normal_neighbours = 10;    ///< target points of each inlier target point's plane fit (its normal, for the information), at least 3 (the dense search's normal_neighbours)
  std::size_t information_samples = 5000;  ///< the information sums the rows of about this many inliers (those whose source index is a multiple of the stride inliers / this), each weighed by inliers / sampled (an unbiased estimate of the full sum; 0: every inlier). A normal fit per inlier took 340 ms of a 560 ms KITTI registration at 100k inliers; 5,000 rows take about 15 ms
};

/// Throws quadrix::Error naming the option out of range ("option 'quality.correspondence_distance'
/// must be positive, got 0"): correspondence_distance positive and finite, normal_neighbours at least 3.
void validate_answer_quality_options(const AnswerQualityOptions& options);

/// One inlier pair of an answer: (source index, target index), columns of the clouds measured.
using PointCorrespondence = std::pair<std::size_t, std::size_t>;

/// Open3D's RegistrationResult evaluation and small_gicp's information matrix of one answer.
struct AnswerQuality {
  double fitness = 0.0;      ///< inliers over the source's finite points, [0, 1] (Open3D's fitness)
  double inlier_rmse = 0.0;  ///< root mean square of the inliers' point-to-point distances, m (Open3D's inlier_rmse; 0 without inliers)
  std::vector<PointCorrespondence> correspondences;  ///< every inlier: source point and its nearest target point, by source index
  std::vector<Eigen::Vector3d> normals;              ///< the target normal of each correspondence (unit; zero where fewer than 3 target points were near, or where the correspondence is not among the information's samples: left out of the information)
  double information_weight = 1.0;                   ///< the weight of each sampled row in `information`: inliers / rows sampled (1 when every inlier is used)
  /// H = J^T J of the point-to-plane cost E(δ) = ½ Σ (n_k · (Exp(δ) T s_k − t_k))² over the
  /// correspondences (times information_weight), at δ = 0: the Gauss-Newton Hessian, the inverse of the answer's covariance
  /// for unit-variance residuals. δ = (ω, τ), rotation then translation, perturbs the answer on the
  /// left, in the TARGET frame: T = Exp(δ) T*, i.e. x ↦ exp([ω]×) x + τ applied after T* (rotation
  /// about the target frame's origin). Row k of J is ((T s_k) × n_k, n_k). Symmetric, positive
  /// semi-definite, and it grows with the number of inliers; a direction the surfaces do not fix
  /// (along a corridor) has an eigenvalue near zero.
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
};

/// Measures `transform` (source into target) on the two clouds: each finite source point's nearest
/// target point within `options.correspondence_distance` after the transform makes a correspondence;
/// fitness, inlier RMSE and the information follow (see AnswerQuality). The target is indexed here
/// (k-d tree), and each inlier target point's normal is the least-variance direction of its
/// `options.normal_neighbours` nearest target points. Throws quadrix::Error for options out of range.
AnswerQuality measure_answer_quality(const PointCloud& source, const PointCloud& target, const Eigen::Isometry3d& transform,
                                     const AnswerQualityOptions& options = {});

/// The point-to-plane cost the information stands for: E(δ) = ½ Σ (n_k · (Exp(δ) T s_k − t_k))² for the given correspondences and normals (Exp(δ) as
/// in AnswerQuality::information). Lets a caller (and the tests) check the information against a
/// numerical Hessian of the very cost it stands for.
double point_to_plane_cost(const PointCloud& source, const PointCloud& target, const Eigen::Isometry3d& transform,
                           const std::vector<PointCorrespondence>& correspondences,
                           const std::vector<Eigen::Vector3d>& normals, const Eigen::Matrix<double, 6, 1>& delta);

/// The information of an answer moved from one target frame to another: for clouds registered
/// centred on their sensors (centred_on_sensor), the information about the target file's frame,
/// whose origin lies at -`target_origin` from the sensor's. With δ_file = A δ_sensor, A = [[I, 0],
/// [[t]×, I]] (t = target_origin: the rotation's pivot moves), H_file = A^-T H_sensor A^-1.
Eigen::Matrix<double, 6, 6> information_about_shifted_origin(const Eigen::Matrix<double, 6, 6>& information,
                                                             const Eigen::Vector3d& target_origin);

}  // namespace quadrix
