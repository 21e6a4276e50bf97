// Quadric distance, its Jacobian, factor construction (f_pp, Augment, ground) and robust kernels.
#include "estimation/quadric_distance.h"

#include "geometry/constants.h"
#include "geometry/error.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <string>

namespace quadrix {
namespace {

bool all_finite(const Eigen::Vector3d& v) { return v.allFinite(); }

// An orthonormal, right-handed basis whose first column is the unit vector `axis`.
Eigen::Matrix3d basis_with_first_axis(const Eigen::Vector3d& axis) {
  const Eigen::Vector3d a = axis.normalized();
  const Eigen::Vector3d helper = std::abs(a.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d b = a.cross(helper).normalized();
  const Eigen::Vector3d c = a.cross(b);
  Eigen::Matrix3d basis;
  basis << a, b, c;
  return basis;
}

bool is_structure(const QuadricRecord& record, const QuadricDecomposition& shape,
                  const std::vector<std::uint32_t>& structure_labels) {
  if (structure_labels.empty())
    return shape.center_kind == CenterKind::LinearCenter || shape.center_kind == CenterKind::PlanarCenter;
  return std::find(structure_labels.begin(), structure_labels.end(), record.label) != structure_labels.end();
}

}  // namespace

QuadricFactor make_quadric_factor(const QuadricRecord& source, const QuadricDecomposition& source_shape,
                                  const QuadricRecord& target, const QuadricDecomposition& target_shape,
                                  std::size_t source_index, std::size_t target_index) {
  QuadricFactor factor;
  factor.source_axes = source_shape.rotation;
  factor.source_center = source.full_center;
  factor.target_axes = target_shape.rotation;
  factor.target_center = target.full_center;
  factor.rotation_mask = target_shape.indicators.rotation.cwiseProduct(source_shape.indicators.rotation);
  factor.translation_mask = target_shape.indicators.translation;
  factor.kind = FactorKind::Correspondence;
  factor.source_index = source_index;
  factor.target_index = target_index;
  return factor;
}

QuadricFactor make_quadric_factor(const QuadricRecord& source, const QuadricRecord& target) {
  return make_quadric_factor(source, source.quadric().decompose(), target, target.quadric().decompose());
}

// Eq. (quadrics distance).
Vector12d quadric_distance(const QuadricFactor& factor, const Eigen::Isometry3d& transform) {
  const Eigen::Matrix3d rotation = transform.linear();
  Vector12d residual;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d rotated_source_axis = rotation * factor.source_axes.col(i);
    residual.segment<3>(3 * i) = factor.rotation_mask[i] * rotated_source_axis.cross(factor.target_axes.col(i));
  }
  const Eigen::Vector3d center_offset = rotation * factor.source_center + transform.translation() - factor.target_center;
  residual.segment<3>(9) = factor.translation_mask.asDiagonal() * (factor.target_axes.transpose() * center_offset);
  return residual;
}

// Eq. (quadrics distance) and Eq. (Jacobian of quadrics distance) under T [+] delta.
void quadric_distance_with_jacobian(const QuadricFactor& factor, const Eigen::Isometry3d& transform,
                                    Vector12d* residual, Matrix12x6d* jacobian) {
  const Eigen::Matrix3d rotation = transform.linear();
  if (residual) *residual = quadric_distance(factor, transform);
  if (!jacobian) return;
  jacobian->setZero();
  for (int i = 0; i < 3; ++i) {
    if (factor.rotation_mask[i] == 0.0) continue;
    // d[(R Exp(phi) a) x b]/d phi = [b]x R [a]x: the rotated axis moves by -R [a]x phi.
    jacobian->block<3, 3>(3 * i, 0) =
        factor.rotation_mask[i] * skew(factor.target_axes.col(i)) * rotation * skew(factor.source_axes.col(i));
  }
  const Eigen::Matrix3d masked_target_frame = factor.translation_mask.asDiagonal() * factor.target_axes.transpose();
  jacobian->block<3, 3>(9, 0) = -masked_target_frame * rotation * skew(factor.source_center);
  jacobian->block<3, 3>(9, 3) = masked_target_frame * rotation;
}

QuadricFactor make_ground_factor(const GroundPlane& source_ground, const GroundPlane& target_ground, double weight,
                                 double tilt_lever_arm) {
  const auto check = [](const GroundPlane& plane, const char* which) {
    if (!all_finite(plane.normal) || !std::isfinite(plane.offset) || plane.normal.norm() <= 0.0)
      throw Error(std::string("make_ground_factor: ") + which + " ground normal must be finite and non-zero");
  };
  check(source_ground, "source");
  check(target_ground, "target");
  if (!(weight >= 0.0) || !std::isfinite(weight)) throw Error("make_ground_factor: weight must be finite and >= 0");
  if (!(tilt_lever_arm > 0.0) || !std::isfinite(tilt_lever_arm))
    throw Error("make_ground_factor: tilt lever arm must be finite and > 0");
  const double source_norm = source_ground.normal.norm();
  const double target_norm = target_ground.normal.norm();
  const Eigen::Vector3d source_normal = source_ground.normal / source_norm;
  const Eigen::Vector3d target_normal = target_ground.normal / target_norm;
  QuadricFactor factor;
  factor.source_axes = basis_with_first_axis(source_normal);
  factor.source_center = -(source_ground.offset / source_norm) * source_normal;
  factor.target_axes = basis_with_first_axis(target_normal);
  factor.target_center = -(target_ground.offset / target_norm) * target_normal;
  factor.rotation_mask = Eigen::Vector3d(tilt_lever_arm, 0.0, 0.0);  // plane: I_R = [1, 0, 0], scaled
  factor.translation_mask = Eigen::Vector3d(1.0, 0.0, 0.0);           // plane: I_t = [1, 0, 0]
  factor.weight = weight;
  factor.kind = FactorKind::Ground;
  return factor;
}

// f_pp (paper §"Transformation Candidate Estimation"), negated: true means the structure is kept.
bool is_manhattan_aligned(const QuadricDecomposition& shape, const Eigen::Vector3d& ground_normal,
                          double tolerance_degrees) {
  if (!all_finite(ground_normal) || ground_normal.norm() <= 0.0)
    throw Error("is_manhattan_aligned: ground normal must be finite and non-zero");
  if (!(tolerance_degrees >= 0.0)) throw Error("is_manhattan_aligned: tolerance_degrees must be >= 0");
  const Eigen::Vector3d normal = ground_normal.normalized();
  constexpr double kDegreesPerRadian = 180.0 / kPi;
  for (int i = 0; i < 3; ++i) {
    if (shape.indicators.rotation[i] == 0.0) continue;
    const Eigen::Vector3d axis = shape.rotation.col(i).normalized();
    // theta folded into [0, 90]: 0 = parallel or antiparallel, 90 = perpendicular.
    const double folded = std::acos(std::clamp(std::abs(axis.dot(normal)), 0.0, 1.0)) * kDegreesPerRadian;
    const bool parallel = folded <= tolerance_degrees;
    const bool perpendicular = folded >= 90.0 - tolerance_degrees;
    if (!parallel && !perpendicular) return false;
  }
  return true;
}

std::vector<QuadricDecomposition> decompose_records(const std::vector<QuadricRecord>& records,
                                                    const DecompositionTolerances& tolerances) {
  std::vector<QuadricDecomposition> shapes;
  shapes.reserve(records.size());
  for (const QuadricRecord& record : records) shapes.push_back(record.quadric().decompose(tolerances));
  return shapes;
}

// Algorithm 1, inner loop: f_pp filter, Augment(), AddFactor().
FactorSet build_quadric_factors(const std::vector<QuadricRecord>& source, const std::vector<QuadricDecomposition>& source_shapes,
                                const std::vector<QuadricRecord>& target, const std::vector<QuadricDecomposition>& target_shapes,
                                const std::vector<RecordCorrespondence>& correspondences,
                                const FactorBuildOptions& options) {
  if (source_shapes.size() != source.size() || target_shapes.size() != target.size())
    throw Error("build_quadric_factors: decomposition lists must have one entry per record (use decompose_records)");
  if (!(options.augmented_weight >= 0.0)) throw Error("build_quadric_factors: augmented_weight must be >= 0");
  FactorSet result;
  result.correspondence_count = correspondences.size();
  result.factors.reserve(correspondences.size() * 3 + 1);
  for (std::size_t k = 0; k < correspondences.size(); ++k) {
    const RecordCorrespondence& pair = correspondences[k];
    if (pair.source_index >= source.size() || pair.target_index >= target.size())
      throw Error("build_quadric_factors: correspondence " + std::to_string(k) + " refers to record (" +
                  std::to_string(pair.source_index) + ", " + std::to_string(pair.target_index) + ") but there are " +
                  std::to_string(source.size()) + " source and " + std::to_string(target.size()) + " target records");
    const QuadricRecord& source_record = source[pair.source_index];
    const QuadricRecord& target_record = target[pair.target_index];
    const QuadricDecomposition& source_shape = source_shapes[pair.source_index];
    const QuadricDecomposition& target_shape = target_shapes[pair.target_index];

    // f_pp: drop structures neither parallel nor perpendicular to the (estimated) ground normal.
    const bool source_rejected = options.source_ground_normal &&
                                 is_structure(source_record, source_shape, options.structure_labels) &&
                                 !is_manhattan_aligned(source_shape, *options.source_ground_normal, options.manhattan_tolerance_degrees);
    const bool target_rejected = options.target_ground_normal &&
                                 is_structure(target_record, target_shape, options.structure_labels) &&
                                 !is_manhattan_aligned(target_shape, *options.target_ground_normal, options.manhattan_tolerance_degrees);
    if (source_rejected || target_rejected) {
      ++result.filtered_count;
      continue;
    }

    const QuadricFactor factor =
        make_quadric_factor(source_record, source_shape, target_record, target_shape, pair.source_index, pair.target_index);
    result.factors.push_back(factor);

    // Augment(): samples on the source's centre line (2) or centre plane (4), radius = mean full scale.
    if (!options.augment_non_central) continue;
    const Eigen::Vector3d& source_translation_indicator = source_shape.indicators.translation;
    const int free_axes = static_cast<int>((source_translation_indicator.array() == 0.0).count());
    if (free_axes != 1 && free_axes != 2) continue;
    const double radius = source_record.full_scale.mean();
    if (!(radius > 0.0) || !std::isfinite(radius)) continue;
    const Eigen::Matrix3d full_rotation = source_record.full_rotation.normalized().toRotationMatrix();
    for (int i = 0; i < 3; ++i) {
      if (source_translation_indicator[i] != 0.0) continue;
      const Eigen::Vector3d direction = full_rotation.col(i);
      for (const double side : {-1.0, 1.0}) {
        QuadricFactor sample = factor;
        sample.source_center = source_record.full_center + side * radius * direction;
        sample.rotation_mask.setZero();  // an augmented sample is a point: no rotation residual
        sample.weight = options.augmented_weight;
        sample.kind = FactorKind::Augmented;
        result.factors.push_back(sample);
        ++result.augmented_count;
      }
    }
  }
  if (options.source_ground && options.target_ground)
    result.factors.push_back(make_ground_factor(*options.source_ground, *options.target_ground, options.ground_weight,
                                                options.ground_tilt_lever_arm));
  // Ablations of Eq. (quadrics distance): drop the rotation or the translation part of every residual.
  for (QuadricFactor& factor : result.factors) {
    if (!options.use_rotation_error) factor.rotation_mask.setZero();
    if (!options.use_translation_error) factor.translation_mask.setZero();
  }
  return result;
}

LossValue evaluate_robust_loss(RobustLoss loss, double scale, double squared_norm) {
  if (loss != RobustLoss::None && !(scale > 0.0 && std::isfinite(scale)))
    throw Error(std::string("robust loss '") + robust_loss_name(loss) + "': scale must be finite and > 0");
  const double s = std::max(0.0, squared_norm);
  LossValue value;
  switch (loss) {
    case RobustLoss::None:
      value = {s, 1.0, 0.0};
      break;
    case RobustLoss::Huber: {
      const double threshold = scale * scale;
      if (s <= threshold) {
        value = {s, 1.0, 0.0};
      } else {
        const double root = std::sqrt(s);
        value = {2.0 * scale * root - threshold, scale / root, -0.5 * scale / (s * root)};
      }
      break;
    }
    case RobustLoss::Cauchy: {
      const double b = scale * scale;
      const double ratio = 1.0 + s / b;
      value = {b * std::log1p(s / b), 1.0 / ratio, -1.0 / (b * ratio * ratio)};
      break;
    }
    case RobustLoss::Dcs: {
      const double phi = scale;
      if (s <= phi) {
        value = {s, 1.0, 0.0};
      } else {
        const double sum = phi + s;
        value = {phi * (3.0 * s - phi) / sum, 4.0 * phi * phi / (sum * sum), -8.0 * phi * phi / (sum * sum * sum)};
      }
      break;
    }
  }
  return value;
}

const char* robust_loss_name(RobustLoss loss) {
  switch (loss) {
    case RobustLoss::None: return "none";
    case RobustLoss::Huber: return "huber";
    case RobustLoss::Cauchy: return "cauchy";
    case RobustLoss::Dcs: return "dcs";
  }
  return "none";
}

RobustLoss robust_loss_from_name(const std::string& name) {
  if (name == "none") return RobustLoss::None;
  if (name == "huber") return RobustLoss::Huber;
  if (name == "cauchy") return RobustLoss::Cauchy;
  if (name == "dcs") return RobustLoss::Dcs;
  throw Error("unknown robust loss '" + name + "' (expected none, huber, cauchy or dcs)");
}

Eigen::Isometry3d apply_increment(const Eigen::Isometry3d& transform, const Vector6d& increment) {
  const Eigen::Vector3d phi = increment.head<3>();
  const double angle = phi.norm();
  const Eigen::Matrix3d exp_phi =
      angle > 0.0 ? Eigen::AngleAxisd(angle, phi / angle).toRotationMatrix() : Eigen::Matrix3d::Identity();
  Eigen::Isometry3d updated = Eigen::Isometry3d::Identity();
  updated.linear() = transform.linear() * exp_phi;
  updated.translation() = transform.translation() + transform.linear() * increment.tail<3>();
  return updated;
}

// Rank of H = sum w J^T J at the pose, on the Jacobi-scaled H so rotation and translation units
// do not bias the comparison (a zero diagonal entry is a fully unconstrained parameter).
ConstraintAnalysis analyse_constraints(const std::vector<QuadricFactor>& factors, const Eigen::Isometry3d& pose,
                                       double relative_threshold) {
  if (!(relative_threshold > 0.0 && relative_threshold < 1.0))
    throw Error("analyse_constraints: relative_threshold must be in (0, 1)");
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
  Matrix12x6d jacobian;
  for (const QuadricFactor& factor : factors) {
    quadric_distance_with_jacobian(factor, pose, nullptr, &jacobian);
    information.noalias() += factor.weight * jacobian.transpose() * jacobian;
  }
  Vector6d inverse_root_diagonal;
  for (int i = 0; i < 6; ++i) {
    const double d = information(i, i);
    inverse_root_diagonal[i] = d > 0.0 ? 1.0 / std::sqrt(d) : 1.0;
  }
  const Eigen::Matrix<double, 6, 6> scaled =
      inverse_root_diagonal.asDiagonal() * information * inverse_root_diagonal.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> solver(scaled);
  ConstraintAnalysis analysis;
  analysis.eigenvalues = solver.eigenvalues();
  const double largest = analysis.eigenvalues[5];
  for (int i = 0; i < 6; ++i) {
    if (largest > 0.0 && analysis.eigenvalues[i] > relative_threshold * largest) {
      ++analysis.rank;
    } else {
      const Vector6d direction = inverse_root_diagonal.asDiagonal() * solver.eigenvectors().col(i);
      analysis.weak_directions.push_back(direction.normalized());
    }
  }
  return analysis;
}

double refinement_cost(const std::vector<QuadricFactor>& factors, const Eigen::Isometry3d& pose, RobustLoss loss,
                       double loss_scale) {
  double cost = 0.0;
  for (const QuadricFactor& factor : factors)
    cost += evaluate_robust_loss(loss, loss_scale, factor.weight * quadric_distance(factor, pose).squaredNorm()).rho;
  return 0.5 * cost;
}

}  // namespace quadrix
