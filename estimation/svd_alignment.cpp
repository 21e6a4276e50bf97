// Arun/Umeyama closed-form rigid alignment (the SVD step of Algorithm 1).
#include "estimation/svd_alignment.h"

#include "geometry/error.h"

#include <Eigen/SVD>
#include <Eigen/Eigenvalues>

#include <cmath>
#include <string>

namespace quadrix {
namespace {

// Second / first eigenvalue of the weighted scatter of centred points: ~0 for collinear sets.
double scatter_spread_ratio(const Eigen::Matrix3Xd& centred, const Eigen::VectorXd& weights) {
  const Eigen::Matrix3d scatter = centred * weights.asDiagonal() * centred.transpose();
  const Eigen::Vector3d eigenvalues = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(scatter).eigenvalues();  // ascending
  if (!(eigenvalues[2] > 0.0)) return 0.0;
  return eigenvalues[1] / eigenvalues[2];
}

}  // namespace

RigidAlignment align_points(const Eigen::Matrix3Xd& source, const Eigen::Matrix3Xd& target,
                            const std::vector<double>& weights, const AlignmentOptions& options) {
  if (source.cols() != target.cols())
    throw Error("align_points: " + std::to_string(source.cols()) + " source points but " +
                std::to_string(target.cols()) + " target points");
  if (!weights.empty() && weights.size() != static_cast<std::size_t>(source.cols()))
    throw Error("align_points: " + std::to_string(weights.size()) + " weights for " + std::to_string(source.cols()) + " points");
  if (!source.allFinite() || !target.allFinite()) throw Error("align_points: point coordinates must be finite");
  const Eigen::Index count = source.cols();
  Eigen::VectorXd w = Eigen::VectorXd::Ones(count);
  for (std::size_t i = 0; i < weights.size(); ++i) {
    if (!(weights[i] >= 0.0) || !std::isfinite(weights[i]))
      throw Error("align_points: weight " + std::to_string(i) + " must be finite and >= 0");
    w[static_cast<Eigen::Index>(i)] = weights[i];
  }

  RigidAlignment result;
  result.point_count = static_cast<std::size_t>((w.array() > 0.0).count());
  if (result.point_count < 3) {
    result.message = "need at least 3 points with positive weight, got " + std::to_string(result.point_count);
    return result;
  }
  const double weight_sum = w.sum();
  const Eigen::Vector3d source_mean = source * w / weight_sum;
  const Eigen::Vector3d target_mean = target * w / weight_sum;
  const Eigen::Matrix3Xd source_centred = source.colwise() - source_mean;
  const Eigen::Matrix3Xd target_centred = target.colwise() - target_mean;
  if (scatter_spread_ratio(source_centred, w) < options.collinearity_tolerance ||
      scatter_spread_ratio(target_centred, w) < options.collinearity_tolerance) {
    result.message = "the points are collinear: rotation about their line is undetermined";
    return result;
  }

  // Cross-covariance H = sum w_i (y_i - ȳ)(x_i - x̄)^T = U S V^T; R = U diag(1, 1, det(U V^T)) V^T.
  const Eigen::Matrix3d cross_covariance = target_centred * w.asDiagonal() * source_centred.transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(cross_covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Vector3d signs = Eigen::Vector3d::Ones();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0) {
    signs[2] = -1.0;
    result.reflection_corrected = true;
  }
  const Eigen::Matrix3d rotation = svd.matrixU() * signs.asDiagonal() * svd.matrixV().transpose();
  result.transform.linear() = rotation;
  result.transform.translation() = target_mean - rotation * source_mean;
  const Eigen::Matrix3Xd residuals = (rotation * source).colwise() + result.transform.translation() - target;
  result.rms_error = std::sqrt((residuals.colwise().squaredNorm().transpose().cwiseProduct(w)).sum() / weight_sum);
  result.status = AlignmentStatus::Ok;
  return result;
}

// Algorithm 1: T^0 = SVD(R_x, R_y, I*) on full centres.
RigidAlignment align_full_centers(const std::vector<QuadricRecord>& source, const std::vector<QuadricRecord>& target,
                                  const std::vector<RecordCorrespondence>& correspondences,
                                  const std::vector<double>& weights, const AlignmentOptions& options) {
  if (!weights.empty() && weights.size() != correspondences.size())
    throw Error("align_full_centers: " + std::to_string(weights.size()) + " weights for " +
                std::to_string(correspondences.size()) + " correspondences");
  Eigen::Matrix3Xd source_centers(3, static_cast<Eigen::Index>(correspondences.size()));
  Eigen::Matrix3Xd target_centers(3, static_cast<Eigen::Index>(correspondences.size()));
  for (std::size_t k = 0; k < correspondences.size(); ++k) {
    const RecordCorrespondence& pair = correspondences[k];
    if (pair.source_index >= source.size() || pair.target_index >= target.size())
      throw Error("align_full_centers: correspondence " + std::to_string(k) + " refers to record (" +
                  std::to_string(pair.source_index) + ", " + std::to_string(pair.target_index) + ") out of range");
    source_centers.col(static_cast<Eigen::Index>(k)) = source[pair.source_index].full_center;
    target_centers.col(static_cast<Eigen::Index>(k)) = target[pair.target_index].full_center;
  }
  return align_points(source_centers, target_centers, weights, options);
}

}  // namespace quadrix
