// The registration's status, its comparisons and its frames (see registration_types.h).
#include "estimation/registration_types.h"

#include "geometry/error.h"
#include "geometry/output_paths.h"

#include <cmath>

namespace quadrix {

const char* registration_status_name(RegistrationStatus status) {
  switch (status) {
    case RegistrationStatus::Ok: return "ok";
    case RegistrationStatus::Ambiguous: return "ambiguous";
    case RegistrationStatus::Degenerate: return "degenerate";
    case RegistrationStatus::Failed: return "failed";
  }
  return "failed";
}

RegistrationStatus decide_registration_status(const RegistrationFindings& findings) {
  if (findings.estimation_failure) return *findings.estimation_failure;
  const bool sure = findings.settled_by_dense_search || (!findings.scores_close && !findings.weak_support);
  const bool fits = !findings.fits_worse_than_identity && !findings.overlaps_too_little && !findings.half_turn_rival &&
                    !findings.half_turn_unclear && !findings.dense_search_unclear &&
                    !findings.overlap_unconfirmed && !findings.in_free_space && !findings.free_space_unjudged &&
                    !findings.grounds_disagree && !findings.guess_disagrees;
  return sure && fits ? RegistrationStatus::Ok : RegistrationStatus::Ambiguous;
}

void apply_registration_status(RegistrationResult& result) {
  result.status = decide_registration_status(result.findings);
  if (result.status != RegistrationStatus::Ok && result.status != RegistrationStatus::Ambiguous)
    result.transform = Eigen::Isometry3d::Identity();
}

PointCloud centred_on_sensor(PointCloud cloud, const Eigen::Vector3d& sensor_origin) {
  if (!sensor_origin.allFinite()) throw Error("the sensor origin must be finite");
  // The file-frame point is local_origin + position: the shift is formed in double, so a cloud read
  // relative to a local origin near the sensor keeps its precision.
  const Eigen::Vector3d shift = cloud.local_origin - sensor_origin;
  cloud.local_origin.setZero();
  if (shift.isZero(0.0)) return cloud;  // already there
  for (Eigen::Index i = 0; i < cloud.positions.cols(); ++i)
    cloud.positions.col(i) = (cloud.positions.col(i).cast<double>() + shift).cast<float>();
  return cloud;
}

PointCloud in_modelling_frame(const PointCloud& cloud, const ModellingFrame& frame, const std::string& what) {
  PointCloud moved;
  if (!frame.sensor_origin.isZero(0.0)) {
    moved = centred_on_sensor(cloud, frame.sensor_origin);
    require_finite_points(moved, what);
  } else {
    moved = cloud;
  }
  if (frame.metres_per_unit != 1.0) moved.positions *= static_cast<float>(frame.metres_per_unit);
  return moved;
}

SceneModel in_file_frame(SceneModel model, const ModellingFrame& frame, const Eigen::Vector3d& local_origin) {
  if (frame.metres_per_unit != 1.0) model = scaled(std::move(model), 1.0 / frame.metres_per_unit);
  const Eigen::Vector3d offset = frame.sensor_origin.isZero(0.0) ? local_origin : frame.sensor_origin;
  return offset.isZero(0.0) ? model : translated(std::move(model), offset);
}

Eigen::Isometry3d between_cloud_frames(const Eigen::Isometry3d& between_sensors, const Eigen::Vector3d& source_origin,
                                       const Eigen::Vector3d& target_origin) {
  return Eigen::Translation3d(target_origin) * between_sensors * Eigen::Translation3d(-source_origin);
}

Eigen::Isometry3d between_sensor_frames(const Eigen::Isometry3d& between_clouds, const Eigen::Vector3d& source_origin,
                                        const Eigen::Vector3d& target_origin) {
  return Eigen::Translation3d(-target_origin) * between_clouds * Eigen::Translation3d(source_origin);
}

double translation_error(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& truth) {
  return (estimate.translation() - truth.translation()).norm();
}

double rotation_error_degrees(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& truth) {
  // The angle of R^T R_gt through atan2(|axis part|, cos part): exact near 0 and 180 degrees, where
  // arccos((tr - 1) / 2) loses precision; mathematically identical to the paper's formula.
  const Eigen::Matrix3d difference = estimate.linear().transpose() * truth.linear();
  const Eigen::Vector3d skew(difference(2, 1) - difference(1, 2), difference(0, 2) - difference(2, 0),
                             difference(1, 0) - difference(0, 1));
  const double angle = std::atan2(0.5 * skew.norm(), 0.5 * (difference.trace() - 1.0));
  return std::abs(angle) * 180.0 / M_PI;
}

bool registration_succeeded(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& truth, double max_translation,
                            double max_rotation_degrees) {
  return translation_error(estimate, truth) <= max_translation &&
         rotation_error_degrees(estimate, truth) <= max_rotation_degrees;
}

}  // namespace quadrix
