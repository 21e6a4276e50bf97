// Canonical surfaces sampled for fitter tests: exact points of each quadric type in its canonical
// frame (independent of geometry/mesh.cpp), under random poses, with fixed seeds.
#pragma once

#include "geometry/constants.h"
#include "geometry/quadric.h"
#include "test_geometry.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <random>

namespace quadrix::testing {

/// Points on a canonical surface; `visible_angle` limits the angular sector (cylinders, cones) or the
/// polar cap (ellipsoids) that is sampled.
inline Eigen::Matrix3Xd sample_surface_points(QuadricType type, const Eigen::Vector3d& scale, const Eigen::Isometry3d& pose,
                                       int count, std::mt19937_64& random, double visible_angle = 2.0 * kPi) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::Matrix3Xd points(3, count);
  for (int i = 0; i < count; ++i) {
    const double angle = visible_angle * unit(random);
    Eigen::Vector3d local;
    switch (type) {
      case QuadricType::Sphere:
      case QuadricType::Ellipsoid: {
        Eigen::Vector3d direction(normal(random), normal(random), normal(random));
        direction.normalize();
        local = direction.cwiseProduct(scale);
        break;
      }
      case QuadricType::CircularCylinder:
      case QuadricType::EllipticCylinder:
        local << scale(0) * std::cos(angle), scale(1) * std::sin(angle), (unit(random) - 0.5) * 3.0;
        break;
      case QuadricType::CircularCone:
      case QuadricType::EllipticCone: {
        const double height = 0.5 + 2.5 * unit(random);
        local << height * scale(0) * std::cos(angle), height * scale(1) * std::sin(angle), height;
        break;
      }
      case QuadricType::Plane:
        local << 0.0, (unit(random) - 0.5) * 10.0, (unit(random) - 0.5) * 4.0;
        break;
      case QuadricType::Line:
        local << 0.0, 0.0, (unit(random) - 0.5) * 8.0;
        break;
      default:
        local.setZero();
    }
    points.col(i) = pose * local;
  }
  return points;
}

inline Eigen::Vector3d random_scale(QuadricType type, std::mt19937_64& random) {
  std::uniform_real_distribution<double> size(0.3, 5.0);
  std::uniform_real_distribution<double> tangent(0.2, 1.5);
  switch (type) {
    case QuadricType::Sphere: { const double r = size(random); return Eigen::Vector3d::Constant(r); }
    case QuadricType::CircularCylinder: { const double r = size(random); return {r, r, 1.0}; }
    case QuadricType::EllipticCylinder: {
      const double a = size(random);
      return {a, a + 0.3 + 0.5 * std::abs(size(random) - 0.3), 1.0};
    }
    case QuadricType::CircularCone: { const double t = tangent(random); return {t, t, 1.0}; }
    case QuadricType::EllipticCone: { const double t = tangent(random); return {t, t + 0.2 + 0.2 * tangent(random), 1.0}; }
    case QuadricType::Ellipsoid: {
      const double a = size(random);
      return {a, a * 1.3 + 0.2, a * 1.8 + 0.4};  // distinct semi-axes
    }
    default: return {1.0, 1.0, 1.0};
  }
}

inline Eigen::Vector3d sorted(Eigen::Vector3d values, int count) {
  std::sort(values.data(), values.data() + count);
  return values;
}

}  // namespace quadrix::testing
