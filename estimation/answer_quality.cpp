// Fitness, inlier RMSE, correspondences and information of an answer (see answer_quality.h).
#include "estimation/answer_quality.h"

#include "geometry/error.h"
#include "geometry/spatial_index.h"

#include <Eigen/Eigenvalues>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <optional>
#include <sstream>
#include <string>

namespace quadrix {

void validate_answer_quality_options(const AnswerQualityOptions& options) {
  if (!(options.correspondence_distance > 0.0) || !std::isfinite(options.correspondence_distance)) {
    std::ostringstream message;
    message << "option 'quality.correspondence_distance' must be positive and finite, got " << options.correspondence_distance;
    throw Error(message.str());
  }
  if (options.normal_neighbours < 3)
    throw Error("option 'quality.normal_neighbours' must be at least 3, got " + std::to_string(options.normal_neighbours));
}

namespace {

// The finite points of `cloud` as a 3xN matrix, with the cloud index of each column.
Eigen::Matrix3Xd finite_points(const PointCloud& cloud, std::vector<std::size_t>& indices) {
  indices.clear();
  for (std::size_t i = 0; i < cloud.size(); ++i)
    if (cloud.point(i).allFinite()) indices.push_back(i);
  Eigen::Matrix3Xd points(3, static_cast<Eigen::Index>(indices.size()));
  for (std::size_t k = 0; k < indices.size(); ++k) points.col(static_cast<Eigen::Index>(k)) = cloud.point(indices[k]);
  return points;
}

// The least-variance direction of the `count` indexed points nearest to column `column` (zero with fewer than 3).
Eigen::Vector3d fitted_normal(const PointIndex& index, Eigen::Index column, std::size_t count) {
  const std::vector<Neighbor> neighbours = index.nearest(index.points().col(column), count);
  if (neighbours.size() < 3) return Eigen::Vector3d::Zero();
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Neighbor& n : neighbours) mean += index.points().col(static_cast<Eigen::Index>(n.index));
  mean /= static_cast<double>(neighbours.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const Neighbor& n : neighbours) {
    const Eigen::Vector3d d = index.points().col(static_cast<Eigen::Index>(n.index)) - mean;
    scatter += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
  solver.computeDirect(scatter);
  const Eigen::Vector3d normal = solver.eigenvectors().col(0);
  return normal.allFinite() && normal.norm() > 0.0 ? Eigen::Vector3d(normal.normalized()) : Eigen::Vector3d::Zero();
}

// x ↦ exp([ω]×) x + τ for δ = (ω, τ): the left perturbation of AnswerQuality::information.
Eigen::Isometry3d perturbation_of(const Eigen::Matrix<double, 6, 1>& delta) {
  Eigen::Isometry3d update = Eigen::Isometry3d::Identity();
  const double angle = delta.head<3>().norm();
  if (angle > 0.0) update.linear() = Eigen::AngleAxisd(angle, delta.head<3>() / angle).toRotationMatrix();
  update.translation() = delta.tail<3>();
  return update;
}

}  // namespace

AnswerQuality measure_answer_quality(const PointCloud& source, const PointCloud& target, const Eigen::Isometry3d& transform,
                                     const AnswerQualityOptions& options) {
  validate_answer_quality_options(options);
  AnswerQuality quality;
  std::vector<std::size_t> target_indices;
  const PointIndex index(finite_points(target, target_indices));
  std::size_t finite_source = 0;
  for (std::size_t i = 0; i < source.size(); ++i) finite_source += source.point(i).allFinite() ? 1 : 0;
  if (finite_source == 0 || index.size() == 0) return quality;

  // Each source point's nearest target point in parallel blocks; the sums are taken after, in
  // source order, so the result is the same on any thread count.
  struct Found {
    std::size_t column = 0;  // column of the nearest target point in the index
    double distance = 0.0;
    bool inlier = false;
  };
  std::vector<Found> found(source.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, source.size(), 256), [&](const tbb::blocked_range<std::size_t>& block) {
    for (std::size_t i = block.begin(); i < block.end(); ++i) {
      const Eigen::Vector3d p = source.point(i);
      if (!p.allFinite()) continue;
      const std::optional<Neighbor> nearest = index.nearest_within(transform * p, options.correspondence_distance);
      if (!nearest) continue;
      found[i].column = nearest->index;
      found[i].distance = nearest->distance;
      found[i].inlier = true;
    }
  });
  double squared_sum = 0.0;
  std::vector<std::size_t> inlier_sources;
  for (std::size_t i = 0; i < found.size(); ++i) {
    if (!found[i].inlier) continue;
    inlier_sources.push_back(i);
    quality.correspondences.emplace_back(i, target_indices[found[i].column]);
    squared_sum += found[i].distance * found[i].distance;
  }

  // The information from evenly spaced inliers (a normal fit each is most of the cost), weighed so
  // that it estimates the sum over every inlier.
  const std::size_t count = inlier_sources.size();
  const std::size_t stride =
      options.information_samples == 0 || count <= options.information_samples
          ? 1
          : (count + options.information_samples - 1) / options.information_samples;
  quality.normals.assign(count, Eigen::Vector3d::Zero());
  // Sampled by source index (every stride-th source point that is an inlier), so two measures of
  // the same source against slightly different inlier sets sample the same points.
  std::vector<std::size_t> sampled;
  for (std::size_t k = 0; k < count; ++k)
    if (inlier_sources[k] % stride == 0) sampled.push_back(k);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, sampled.size(), 64), [&](const tbb::blocked_range<std::size_t>& block) {
    for (std::size_t j = block.begin(); j < block.end(); ++j) {
      const std::size_t k = sampled[j];
      quality.normals[k] =
          fitted_normal(index, static_cast<Eigen::Index>(found[inlier_sources[k]].column), options.normal_neighbours);
    }
  });
  quality.information_weight = sampled.empty() ? 1.0 : static_cast<double>(count) / static_cast<double>(sampled.size());
  for (const std::size_t k : sampled) {
    // Row of J: d/dδ of n · (Exp(δ) T s − t) at 0 is ((T s) × n, n).
    const Eigen::Vector3d moved = transform * source.point(inlier_sources[k]);
    Eigen::Matrix<double, 6, 1> row;
    row << moved.cross(quality.normals[k]), quality.normals[k];
    quality.information.noalias() += row * row.transpose();
  }
  quality.information *= quality.information_weight;
  const std::size_t inliers = quality.correspondences.size();
  quality.fitness = static_cast<double>(inliers) / static_cast<double>(finite_source);
  quality.inlier_rmse = inliers > 0 ? std::sqrt(squared_sum / static_cast<double>(inliers)) : 0.0;
  return quality;
}

double point_to_plane_cost(const PointCloud& source, const PointCloud& target, const Eigen::Isometry3d& transform,
                           const std::vector<PointCorrespondence>& correspondences,
                           const std::vector<Eigen::Vector3d>& normals, const Eigen::Matrix<double, 6, 1>& delta) {
  if (normals.size() != correspondences.size())
    throw Error("point_to_plane_cost: " + std::to_string(normals.size()) + " normals for " +
                std::to_string(correspondences.size()) + " correspondences");
  const Eigen::Isometry3d moved = perturbation_of(delta) * transform;
  double cost = 0.0;
  for (std::size_t k = 0; k < correspondences.size(); ++k) {
    const auto [s, t] = correspondences[k];
    if (s >= source.size() || t >= target.size())
      throw Error("point_to_plane_cost: correspondence " + std::to_string(k) + " (" + std::to_string(s) + ", " +
                  std::to_string(t) + ") is outside the clouds (" + std::to_string(source.size()) + " and " +
                  std::to_string(target.size()) + " points)");
    const double residual = normals[k].dot(moved * source.point(s) - target.point(t));
    cost += 0.5 * residual * residual;
  }
  return cost;
}

Eigen::Matrix<double, 6, 6> information_about_shifted_origin(const Eigen::Matrix<double, 6, 6>& information,
                                                             const Eigen::Vector3d& target_origin) {
  // A^-1 = [[I, 0], [-[t]×, I]].
  Eigen::Matrix<double, 6, 6> inverse = Eigen::Matrix<double, 6, 6>::Identity();
  Eigen::Matrix3d skew;
  skew << 0.0, -target_origin.z(), target_origin.y(), target_origin.z(), 0.0, -target_origin.x(), -target_origin.y(),
      target_origin.x(), 0.0;
  inverse.bottomLeftCorner<3, 3>() = -skew;
  return inverse.transpose() * information * inverse;
}

}  // namespace quadrix
