// Random rotations and poses for tests, over any standard random engine (std::mt19937,
// std::mt19937_64): the draws of each helper are fixed, so a test's sequence depends only on its seed.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <random>

namespace quadrix::testing {

/// Uniform random rotation: a normalised quaternion of four standard Gaussian draws.
template <class Random>
Eigen::Matrix3d random_rotation(Random& random) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::Quaterniond q(normal(random), normal(random), normal(random), normal(random));
  return q.normalized().toRotationMatrix();
}

/// How random_pose draws each translation coordinate.
enum class TranslationDraw {
  Uniform,   ///< uniform in [-translation_range, translation_range]
  Gaussian,  ///< Gaussian with standard deviation translation_range
};

/// Random pose: random_rotation, then three translation coordinates drawn as `draw` says.
template <class Random>
Eigen::Isometry3d random_pose(Random& random, double translation_range, TranslationDraw draw = TranslationDraw::Uniform) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = random_rotation(random);
  if (draw == TranslationDraw::Gaussian) {
    std::normal_distribution<double> normal(0.0, 1.0);
    pose.translation() = Eigen::Vector3d(normal(random), normal(random), normal(random)) * translation_range;
  } else {
    std::uniform_real_distribution<double> uniform(-translation_range, translation_range);
    pose.translation() = Eigen::Vector3d(uniform(random), uniform(random), uniform(random));
  }
  return pose;
}

}  // namespace quadrix::testing
