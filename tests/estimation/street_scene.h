// A synthetic street world (ground, façades, poles, cars) and the clouds a level sensor sees of it,
// shared by the registration tests: seeded, so every run draws the same scenes.
#pragma once

#include "geometry/point_cloud.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

namespace quadrix::testing {

inline Eigen::Isometry3d make_pose(double yaw_degrees, const Eigen::Vector3d& translation, double roll_degrees = 0.0) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = (Eigen::AngleAxisd(yaw_degrees * M_PI / 180.0, Eigen::Vector3d::UnitZ()) *
                   Eigen::AngleAxisd(roll_degrees * M_PI / 180.0, Eigen::Vector3d::UnitX()))
                      .toRotationMatrix();
  pose.translation() = translation;
  return pose;
}

// A street-like world (z up, ground at z = 0): ground, facades in two directions and a slanted one,
// poles and car-sized boxes at seeded random places. Surfaces are sampled densely with small noise.
inline std::vector<Eigen::Vector3d> make_street_world(std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<Eigen::Vector3d> points;
  const auto add = [&](const Eigen::Vector3d& p) {
    points.push_back(p + Eigen::Vector3d(noise(random), noise(random), noise(random)));
  };
  for (double x = -45.0; x <= 45.0; x += 0.4)
    for (double y = -45.0; y <= 45.0; y += 0.4) add(Eigen::Vector3d(x, y, 0.0));
  // Facades: start, direction (horizontal), length, height.
  struct Wall {
    Eigen::Vector3d start;
    double angle_degrees;
    double length;
    double height;
  };
  std::vector<Wall> walls = {{{-35.0, 9.0, 0.0}, 0.0, 28.0, 9.0},  {{2.0, 10.0, 0.0}, 0.0, 22.0, 6.0},
                             {{-30.0, -9.0, 0.0}, 0.0, 18.0, 12.0}, {{5.0, -10.0, 0.0}, 0.0, 25.0, 7.0},
                             {{26.0, -8.0, 0.0}, 90.0, 14.0, 8.0},  {{-12.0, 14.0, 0.0}, 90.0, 20.0, 10.0},
                             {{-20.0, -30.0, 0.0}, 60.0, 15.0, 5.0}, {{15.0, 25.0, 0.0}, 120.0, 12.0, 6.0},
                             {{-40.0, -20.0, 0.0}, 90.0, 16.0, 9.0}, {{30.0, 12.0, 0.0}, 0.0, 12.0, 11.0}};
  for (Wall& wall : walls) wall.start += Eigen::Vector3d(uniform(random), uniform(random), 0.0);
  for (const Wall& wall : walls) {
    const Eigen::Vector3d direction(std::cos(wall.angle_degrees * M_PI / 180.0), std::sin(wall.angle_degrees * M_PI / 180.0), 0.0);
    for (double s = 0.0; s <= wall.length; s += 0.15)
      for (double z = 0.0; z <= wall.height; z += 0.15) add(wall.start + s * direction + Eigen::Vector3d(0, 0, z));
  }
  // Poles: thin vertical cylinders of varied heights.
  for (int i = 0; i < 28; ++i) {
    const Eigen::Vector3d base(-34.0 + 2.5 * i + uniform(random), (i % 2 ? 8.0 : -8.0) + uniform(random), 0.0);
    const double height = 4.0 + 1.5 * (1.0 + uniform(random));
    for (double z = 0.0; z <= height; z += 0.05)
      for (int k = 0; k < 8; ++k) {
        const double a = 2.0 * M_PI * k / 8.0;
        add(base + Eigen::Vector3d(0.12 * std::cos(a), 0.12 * std::sin(a), z));
      }
  }
  // Cars and other boxes of varied sizes and headings (surface samples).
  for (int i = 0; i < 48; ++i) {
    const Eigen::Vector3d size(3.5 + 1.0 * (1.0 + uniform(random)), 1.6 + 0.4 * (1.0 + uniform(random)),
                               1.3 + 0.6 * (1.0 + uniform(random)));
    const double row_y[4] = {3.5, -3.5, 22.0, -20.0};
    const Eigen::Vector3d centre(-36.0 + 1.5 * i + 0.5 * uniform(random), row_y[i % 4] + 1.0 * uniform(random),
                                 0.3 + size.z() / 2.0);
    const Eigen::Matrix3d rotation = Eigen::AngleAxisd(0.3 * uniform(random), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    for (double u = -0.5; u <= 0.5; u += 0.04)
      for (double v = -0.5; v <= 0.5; v += 0.04)
        for (int face = 0; face < 3; ++face)
          for (const double side : {-0.5, 0.5}) {
            Eigen::Vector3d local;
            local[face] = side;
            local[(face + 1) % 3] = u;
            local[(face + 2) % 3] = v;
            add(centre + rotation * local.cwiseProduct(size));
          }
  }
  return points;
}

// The cloud a sensor at `pose` (sensor frame: 1.73 m above the ground) sees within 60 m.
inline PointCloud observe(const std::vector<Eigen::Vector3d>& world, const Eigen::Isometry3d& pose) {
  const Eigen::Isometry3d world_to_sensor = pose.inverse();
  std::vector<Eigen::Vector3d> kept;
  for (const Eigen::Vector3d& p : world) {
    const Eigen::Vector3d local = world_to_sensor * p;
    if (local.norm() <= 60.0) kept.push_back(local);
  }
  PointCloud cloud;
  cloud.positions.resize(3, static_cast<Eigen::Index>(kept.size()));
  for (std::size_t i = 0; i < kept.size(); ++i) cloud.positions.col(static_cast<Eigen::Index>(i)) = kept[i].cast<float>();
  return cloud;
}

}  // namespace quadrix::testing
