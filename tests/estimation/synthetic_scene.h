// Synthetic record pairs for the estimation tests: random quadrics of every supported type built
// with Quadric::from_canonical, records with make_quadric_record, the target being the source moved
// by a known pose (optionally with per-element noise and wrong correspondences).
#pragma once

#include "estimation/quadric_distance.h"
#include "geometry/constants.h"
#include "geometry/quadric.h"
#include "geometry/quadric_record.h"
#include "test_geometry.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace quadrix::testing {

/// The quadric types the estimation stage handles (paper Table "Characteristics of typical quadrics").
inline const std::vector<QuadricType>& estimation_types() {
  static const std::vector<QuadricType> types{QuadricType::Point,           QuadricType::Line,
                                              QuadricType::Plane,           QuadricType::Sphere,
                                              QuadricType::Ellipsoid,       QuadricType::CircularCylinder,
                                              QuadricType::EllipticCylinder, QuadricType::CircularCone,
                                              QuadricType::EllipticCone};
  return types;
}

/// Uniform unit vector.
inline Eigen::Vector3d random_unit_vector(std::mt19937& rng) {
  std::normal_distribution<double> gauss(0.0, 1.0);
  return Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized();
}

/// A perturbation of exactly `translation` metres and `angle_radians` about random directions.
inline Eigen::Isometry3d perturbation(std::mt19937& rng, double translation, double angle_radians) {
  Eigen::Isometry3d delta = Eigen::Isometry3d::Identity();
  delta.linear() = Eigen::AngleAxisd(angle_radians, random_unit_vector(rng)).toRotationMatrix();
  delta.translation() = translation * random_unit_vector(rng);
  return delta;
}

/// Canonical scales for from_canonical with clearly distinct axes where the type is asymmetric.
inline Eigen::Vector3d canonical_scale(QuadricType type, std::mt19937& rng) {
  std::uniform_real_distribution<double> size(0.5, 2.0);
  const double r = size(rng);
  switch (type) {
    case QuadricType::Sphere: return Eigen::Vector3d(r, r, r);
    case QuadricType::Ellipsoid: return Eigen::Vector3d(r, 1.6 * r, 2.5 * r);
    case QuadricType::CircularCylinder: return Eigen::Vector3d(r, r, 1.0);
    case QuadricType::EllipticCylinder: return Eigen::Vector3d(r, 1.7 * r, 1.0);
    case QuadricType::CircularCone: return Eigen::Vector3d(std::tan(0.5), std::tan(0.5), 1.0);
    case QuadricType::EllipticCone: return Eigen::Vector3d(std::tan(0.35), std::tan(0.7), 1.0);
    default: return Eigen::Vector3d(1.0, 1.0, 1.0);
  }
}

/// Rotation and translation error of an estimate: (||t - t_true|| metres, angle degrees).
inline std::pair<double, double> pose_error(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& truth) {
  const Eigen::Matrix3d relative = truth.linear().transpose() * estimate.linear();
  // Angle from the quaternion (atan2-based): accurate near zero, unlike acos((tr - 1) / 2).
  const double angle = Eigen::AngleAxisd(Eigen::Quaterniond(relative).normalized()).angle();
  return {(estimate.translation() - truth.translation()).norm(), angle * 180.0 / kPi};
}

/// A source/target record pair set related by `truth`.
struct SyntheticScene {
  std::vector<QuadricRecord> source;                 ///< records in the source frame
  std::vector<QuadricRecord> target;                 ///< records in the target frame
  std::vector<RecordCorrespondence> correspondences; ///< source i <-> target i (some wrong if requested)
  Eigen::Isometry3d truth = Eigen::Isometry3d::Identity();  ///< maps source into target
};

/// Options of make_scene.
struct SceneSpec {
  int copies_per_type = 2;          ///< records per type in estimation_types()
  double extent = 20.0;             ///< element centres within +/- extent metres
  double rotation_noise = 0.0;      ///< per-element target rotation noise (radians, std dev per axis)
  double translation_noise = 0.0;   ///< per-element target translation noise (metres, std dev per axis)
  double outlier_fraction = 0.0;    ///< fraction of correspondences pointing at a wrong target record
  std::vector<QuadricType> types = estimation_types();  ///< types to draw from
};

/// One record of `type` in the source frame (its label is the type index).
inline void add_element(SyntheticScene& scene, QuadricType type, std::mt19937& rng, const SceneSpec& spec) {
  std::normal_distribution<double> gauss(0.0, 1.0);
  const Eigen::Isometry3d pose = random_pose(rng, spec.extent);
  const Quadric source_quadric = Quadric::from_canonical(type, canonical_scale(type, rng), pose);
  StatisticalPose source_statistics;
  source_statistics.scale = Eigen::Vector3d(3.0, 2.0, 1.0) * (1.0 + std::abs(gauss(rng)));
  source_statistics.rotation = random_rotation(rng);
  source_statistics.center = pose.translation() + Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng));
  const auto label = static_cast<std::uint32_t>(type);

  // Target: the same element moved by truth, then jittered about its own centre.
  Eigen::Isometry3d noise = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d anchor = scene.truth * pose.translation();
  const Eigen::Vector3d rotation_noise(gauss(rng), gauss(rng), gauss(rng));
  const Eigen::Vector3d translation_noise(gauss(rng), gauss(rng), gauss(rng));
  const Eigen::Vector3d axis_angle = spec.rotation_noise * rotation_noise;
  if (axis_angle.norm() > 0.0) noise.linear() = Eigen::AngleAxisd(axis_angle.norm(), axis_angle.normalized()).toRotationMatrix();
  noise.translation() = anchor - noise.linear() * anchor + spec.translation_noise * translation_noise;
  const Eigen::Isometry3d target_motion = noise * scene.truth;
  const Quadric target_quadric = source_quadric.transformed(target_motion);
  StatisticalPose target_statistics = source_statistics;
  target_statistics.rotation = target_motion.linear() * source_statistics.rotation;
  target_statistics.center = target_motion * source_statistics.center;

  scene.correspondences.push_back({scene.source.size(), scene.target.size()});
  scene.source.push_back(make_quadric_record(label, source_quadric, source_statistics));
  scene.target.push_back(make_quadric_record(label, target_quadric, target_statistics));
}

/// Builds a scene with every type of spec.types, `copies_per_type` times, related by a random truth.
inline SyntheticScene make_scene(std::mt19937& rng, const SceneSpec& spec) {
  SyntheticScene scene;
  scene.truth = random_pose(rng, 10.0);
  for (int copy = 0; copy < spec.copies_per_type; ++copy)
    for (const QuadricType type : spec.types) add_element(scene, type, rng, spec);
  const auto wrong = static_cast<std::size_t>(std::round(spec.outlier_fraction * static_cast<double>(scene.correspondences.size())));
  std::uniform_int_distribution<std::size_t> pick(0, scene.target.size() - 1);
  for (std::size_t k = 0; k < wrong; ++k) {
    RecordCorrespondence& pair = scene.correspondences[k * scene.correspondences.size() / std::max<std::size_t>(wrong, 1)];
    std::size_t other = pick(rng);
    while (other == pair.source_index) other = pick(rng);
    pair.target_index = other;
  }
  return scene;
}

}  // namespace quadrix::testing
