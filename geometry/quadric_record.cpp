// Struct. 1 (21-number quadric record) and Eq. (full attributes) of paper §"Quadric Modeling";
// statistical pose of paper §"Quadric Fitting" (statistics-based method, steps 1-2).
#include "geometry/quadric_record.h"

#include "geometry/error.h"

#include <Eigen/Eigenvalues>

#include <cmath>
#include <limits>
#include <string>

namespace quadrix {
namespace {

// Largest-magnitude component positive: a deterministic sign for a principal direction.
Eigen::Vector3d sign_normalized(const Eigen::Vector3d& v) {
  Eigen::Index index = 0;
  v.cwiseAbs().maxCoeff(&index);
  return v[index] < 0.0 ? Eigen::Vector3d(-v) : v;
}

}  // namespace

StatisticalPose statistical_pose(const Eigen::Matrix3Xd& points, double scale_factor) {
  StatisticalPose pose;
  const Eigen::Index count = points.cols();
  if (count < 1) return pose;
  pose.center = points.rowwise().mean();  // t_s
  const Eigen::Matrix3Xd centred = points.colwise() - pose.center;
  const Eigen::Matrix3d covariance = centred * centred.transpose() / double(count);  // (1/n_e) e_c^T e_c
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  // Eigen returns ascending eigenvalues: reverse to descending variance.
  Eigen::Matrix3d rotation;
  Eigen::Vector3d variance;
  for (int k = 0; k < 3; ++k) {
    rotation.col(k) = solver.eigenvectors().col(2 - k);
    variance[k] = std::max(0.0, solver.eigenvalues()[2 - k]);
  }
  rotation.col(0) = sign_normalized(rotation.col(0));
  rotation.col(1) = sign_normalized(rotation.col(1));
  rotation.col(2) = rotation.col(0).cross(rotation.col(1));  // det R_s = +1
  pose.rotation = rotation;
  pose.scale = scale_factor * variance.cwiseSqrt();  // s_s = k_s sigma_s
  return pose;
}

std::array<double, 21> QuadricRecord::to_array() const {
  std::array<double, 21> values{};
  values[0] = double(label);
  for (int i = 0; i < 10; ++i) values[1 + i] = q[i];
  for (int i = 0; i < 3; ++i) values[11 + i] = full_scale[i];
  values[14] = full_rotation.w();
  values[15] = full_rotation.x();
  values[16] = full_rotation.y();
  values[17] = full_rotation.z();
  for (int i = 0; i < 3; ++i) values[18 + i] = full_center[i];
  return values;
}

QuadricRecord QuadricRecord::from_array(const std::array<double, 21>& values) {
  static const char* const kFieldNames[21] = {
      "label", "q.A", "q.B", "q.C", "q.D", "q.E", "q.F", "q.G", "q.H", "q.I", "q.J",
      "full_scale.a", "full_scale.b", "full_scale.c", "full_rotation.w", "full_rotation.x",
      "full_rotation.y", "full_rotation.z", "full_center.x", "full_center.y", "full_center.z"};
  for (int i = 0; i < 21; ++i) {
    if (!std::isfinite(values[i]))
      throw Error("quadric record: field " + std::to_string(i) + " (" + kFieldNames[i] + ") is not finite");
  }
  const double label = values[0];
  if (label < 0.0 || label != std::floor(label) || label > double(std::numeric_limits<std::uint32_t>::max()))
    throw Error("quadric record: field 0 (label) must be a non-negative integer below 2^32, got " +
                std::to_string(label));
  QuadricRecord record;
  record.label = static_cast<std::uint32_t>(label);
  for (int i = 0; i < 10; ++i) record.q[i] = values[1 + i];
  for (int i = 0; i < 3; ++i) record.full_scale[i] = values[11 + i];
  Eigen::Quaterniond rotation(values[14], values[15], values[16], values[17]);
  double norm = rotation.norm();
  if (std::isinf(norm)) {  // the squares overflowed: scale by the largest coefficient first
    rotation.coeffs() /= rotation.coeffs().cwiseAbs().maxCoeff();
    norm = rotation.norm();
  }
  if (!(norm > 1e-12))
    throw Error("quadric record: fields 14-17 (full_rotation w, x, y, z) must be a non-zero quaternion");
  if (std::abs(norm - 1.0) > 1e-12) rotation.coeffs() /= norm;  // unit input round-trips bit for bit
  record.full_rotation = rotation;
  for (int i = 0; i < 3; ++i) record.full_center[i] = values[18 + i];
  return record;
}

QuadricRecord make_quadric_record(std::uint32_t label, const Quadric& quadric, const StatisticalPose& statistics,
                                  const DecompositionTolerances& tolerances) {
  const Quadric normalized = quadric.normalized(tolerances);
  const QuadricDecomposition shape = normalized.decompose(tolerances);
  const DegeneracyIndicators& indicators = shape.indicators;

  QuadricRecord record;
  record.label = label;
  record.q = normalized.parameters();

  // Eq. (full attributes), scale: s_f = diag(I_s) s_q + diag(1 - I_s) s_s.
  for (int k = 0; k < 3; ++k)
    record.full_scale[k] = indicators.scale[k] > 0.5 ? shape.scale[k] : statistics.scale[k];

  // Eq. (full attributes), rotation: keep the defined columns of R_q; each undefined column but the
  // last takes the first unused column of R_s (in descending-variance order) whose part orthogonal
  // to the columns already set has squared norm >= 1/2 (else the unused one with the largest such
  // part), orthogonalised and normalised; the last undefined column completes a right-handed frame,
  // so R_f is a proper rotation whatever the order of R_s's columns relative to R_q's.
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Zero();
  std::array<bool, 3> set{{false, false, false}};
  for (int k = 0; k < 3; ++k) {
    if (indicators.rotation[k] > 0.5) {
      rotation.col(k) = shape.rotation.col(k);
      set[k] = true;
    }
  }
  std::array<bool, 3> used{{false, false, false}};
  auto orthogonal_part = [&](const Eigen::Vector3d& v) {
    Eigen::Vector3d rest = v;
    for (int k = 0; k < 3; ++k)
      if (set[k]) rest -= rest.dot(rotation.col(k)) * rotation.col(k);
    return rest;
  };
  int unset = 3 - (int(set[0]) + int(set[1]) + int(set[2]));
  for (int k = 0; k < 3 && unset > 1; ++k) {
    if (set[k]) continue;
    int chosen = -1;
    int best = -1;
    double best_norm = -1.0;
    for (int j = 0; j < 3; ++j) {
      if (used[j]) continue;
      const double squared = orthogonal_part(statistics.rotation.col(j)).squaredNorm();
      if (chosen < 0 && squared >= 0.5) chosen = j;
      if (squared > best_norm) {
        best_norm = squared;
        best = j;
      }
    }
    if (chosen < 0) chosen = best;
    used[chosen] = true;
    Eigen::Vector3d column = orthogonal_part(statistics.rotation.col(chosen));
    if (!(column.norm() > 1e-12)) column = orthogonal_part(Eigen::Vector3d::Unit(k));  // degenerate R_s
    rotation.col(k) = column.normalized();
    set[k] = true;
    --unset;
  }
  for (int k = 0; k < 3; ++k) {
    if (set[k]) continue;
    rotation.col(k) = rotation.col((k + 1) % 3).cross(rotation.col((k + 2) % 3));
  }
  if (rotation.determinant() < 0.0) rotation.col(2) = -rotation.col(2);  // only when R_q itself was improper
  Eigen::Quaterniond quaternion(rotation);
  quaternion.normalize();
  if (quaternion.w() < 0.0) quaternion.coeffs() = -quaternion.coeffs();  // deterministic sign: w >= 0
  record.full_rotation = quaternion;

  // Eq. (full attributes), centre: I'_t = I_t if every element is 1, else the zero vector.
  const bool center_defined = indicators.translation.minCoeff() > 0.5;
  record.full_center = center_defined ? shape.center : statistics.center;
  return record;
}

}  // namespace quadrix
