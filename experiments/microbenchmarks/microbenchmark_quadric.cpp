// Cost of the quadric kernels: decomposition (Eq. (Q=PCP), (solve t)), exact orthogonal distance
// (closed forms, Lagrange/bisection for ellipsoid and elliptic cone), Sampson distance, sampling.
#include "geometry/mesh.h"
#include "geometry/quadric.h"

#include <benchmark/benchmark.h>

#include <random>
#include <vector>

namespace {

using quadrix::Quadric;
using quadrix::QuadricType;

Eigen::Isometry3d pose_for(std::mt19937_64& random) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::Quaterniond(normal(random), normal(random), normal(random), normal(random)).normalized().toRotationMatrix();
  pose.translation() = 10.0 * Eigen::Vector3d(normal(random), normal(random), normal(random));
  return pose;
}

Eigen::Vector3d scale_for(QuadricType type) {
  switch (type) {
    case QuadricType::EllipticCone: return Eigen::Vector3d(0.4, 0.9, 0.0);
    case QuadricType::EllipticCylinder: return Eigen::Vector3d(0.5, 1.2, 0.0);
    case QuadricType::CircularCylinder: return Eigen::Vector3d(0.5, 0.5, 0.0);
    case QuadricType::Plane: return Eigen::Vector3d::Zero();
    default: return Eigen::Vector3d(0.5, 1.0, 2.0);
  }
}

void decompose(benchmark::State& state, QuadricType type) {
  std::mt19937_64 random(1);
  std::vector<Quadric> quadrics;
  for (int i = 0; i < 256; ++i) quadrics.push_back(Quadric::from_canonical(type, scale_for(type), pose_for(random)));
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(quadrics[i++ & 255].decompose());
  }
  state.SetItemsProcessed(state.iterations());
}

void orthogonal_distance(benchmark::State& state, QuadricType type) {
  std::mt19937_64 random(2);
  const quadrix::QuadricDecomposition shape = Quadric::from_canonical(type, scale_for(type), pose_for(random)).decompose();
  std::normal_distribution<double> normal(0.0, 2.0);
  std::vector<Eigen::Vector3d> queries;
  for (int i = 0; i < 1024; ++i) queries.push_back(shape.pose() * Eigen::Vector3d(normal(random), normal(random), normal(random)));
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(quadrix::orthogonal_distance(shape, queries[i++ & 1023]));
  }
  state.SetItemsProcessed(state.iterations());
}

void sampson_distance(benchmark::State& state) {
  std::mt19937_64 random(3);
  const Quadric quadric = Quadric::from_canonical(QuadricType::Ellipsoid, scale_for(QuadricType::Ellipsoid), pose_for(random));
  Eigen::Vector3d x(1.0, 2.0, 3.0);
  for (auto _ : state) {
    benchmark::DoNotOptimize(quadric.sampson_distance(x));
    x[0] += 1e-9;
  }
  state.SetItemsProcessed(state.iterations());
}

void sample_ellipsoid(benchmark::State& state) {
  std::mt19937_64 random(4);
  const quadrix::QuadricDecomposition shape =
      Quadric::from_canonical(QuadricType::Ellipsoid, scale_for(QuadricType::Ellipsoid), pose_for(random)).decompose();
  quadrix::LocalExtent extent;
  extent.minimum = Eigen::Vector3d::Constant(-3.0);
  extent.maximum = Eigen::Vector3d::Constant(3.0);
  std::size_t points = 0;
  for (auto _ : state) {
    const Eigen::Matrix3Xd samples = quadrix::sample_surface(shape, extent, 0.02);
    points = std::size_t(samples.cols());
    benchmark::DoNotOptimize(samples.data());
  }
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(points));
}

BENCHMARK_CAPTURE(decompose, ellipsoid, QuadricType::Ellipsoid);
BENCHMARK_CAPTURE(decompose, plane, QuadricType::Plane);
BENCHMARK_CAPTURE(decompose, elliptic_cone, QuadricType::EllipticCone);
BENCHMARK_CAPTURE(orthogonal_distance, ellipsoid, QuadricType::Ellipsoid);
BENCHMARK_CAPTURE(orthogonal_distance, elliptic_cylinder, QuadricType::EllipticCylinder);
BENCHMARK_CAPTURE(orthogonal_distance, elliptic_cone, QuadricType::EllipticCone);
BENCHMARK_CAPTURE(orthogonal_distance, circular_cylinder, QuadricType::CircularCylinder);
BENCHMARK(sampson_distance);
BENCHMARK(sample_ellipsoid);

}  // namespace

BENCHMARK_MAIN();
