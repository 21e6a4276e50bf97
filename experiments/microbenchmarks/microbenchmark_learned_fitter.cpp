// Speed of the learned fitter (target: <= 20 ms per segment): the whole fit of one segment
// per type (sampling, normalisation, Eigen PointNet inference, decoding, Q = P^-T C P^-1 and the
// shared residual evaluation with exact orthogonal distances on every point, the default; the counter
// residual_points says so), the network forward pass alone, and the auto policy.
#include "fitting/learned_fitter.h"
#include "fitting/quadric_fitter.h"

#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

namespace {

using quadrix::QuadricType;

/// A partial, noisy synthetic segment (3 x count points) of `type` under a fixed random pose.
Eigen::Matrix3Xd segment(QuadricType type, int count) {
  std::mt19937_64 random(7 + static_cast<int>(type));
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  const Eigen::Isometry3d pose = Eigen::Translation3d(3.0, -5.0, 12.0) *
                                 Eigen::AngleAxisd(0.8, Eigen::Vector3d(1.0, 2.0, 3.0).normalized());
  Eigen::Matrix3Xd points(3, count);
  for (int i = 0; i < count; ++i) {
    const double angle = 3.0 * unit(random);  // about half the circumference visible
    const double t = unit(random);
    Eigen::Vector3d local;
    switch (type) {
      case QuadricType::Plane: local << 0.0, 6.0 * t, 4.0 * unit(random); break;
      case QuadricType::Line: local << 0.05 * std::cos(angle), 0.05 * std::sin(angle), 5.0 * t; break;
      case QuadricType::Sphere: local = 1.5 * Eigen::Vector3d(std::cos(angle) * std::sin(2.0 * t), std::sin(angle) * std::sin(2.0 * t), std::cos(2.0 * t)); break;
      case QuadricType::CircularCylinder: local << 0.4 * std::cos(angle), 0.4 * std::sin(angle), 4.0 * t; break;
      case QuadricType::CircularCone: local << (1.0 + 2.0 * t) * 0.5 * std::cos(angle), (1.0 + 2.0 * t) * 0.5 * std::sin(angle), 1.0 + 2.0 * t; break;
      default: local = Eigen::Vector3d(2.0 * std::cos(angle) * std::sin(2.0 * t), 1.0 * std::sin(angle) * std::sin(2.0 * t), 0.6 * std::cos(2.0 * t)); break;
    }
    points.col(i) = pose * local + 0.02 * Eigen::Vector3d(normal(random), normal(random), normal(random));
  }
  return points;
}

void learned_fit(benchmark::State& state, QuadricType type) {
  const auto fitter = quadrix::make_quadric_fitter("learned");
  const Eigen::Matrix3Xd points = segment(type, static_cast<int>(state.range(0)));
  double f_p2s = 0.0;
  double residual_points = 0.0;
  for (auto _ : state) {
    const quadrix::QuadricFit fit = fitter->fit(points, Eigen::Matrix3Xd(), type);
    f_p2s = fit.algebraic_distance;
    residual_points = static_cast<double>(fit.residual_points);
    benchmark::DoNotOptimize(fit.quadric.matrix().data());
  }
  state.counters["f_p2s"] = f_p2s;
  state.counters["residual_points"] = residual_points;
}

void network_forward(benchmark::State& state, QuadricType type) {
  const quadrix::LearnedFitterModel model = quadrix::load_learned_fitter_model(quadrix::default_learned_fitter_directory());
  const quadrix::LearnedTypeNetwork* network = model.find(type);
  const Eigen::Matrix3Xd sampled = quadrix::learned_fitter_sample(segment(type, 2000), model.num_points);
  const quadrix::SegmentNormalisation frame = quadrix::normalise_segment(sampled);
  const Eigen::Matrix3Xf input =
      ((frame.rotation.transpose() * (sampled.colwise() - frame.center)) / frame.scale).cast<float>();
  for (auto _ : state) {
    const Eigen::VectorXf raw = network->network.forward(input);
    benchmark::DoNotOptimize(raw.data());
  }
  state.counters["parameters"] = static_cast<double>(network->network.parameter_count());
}

void auto_fit(benchmark::State& state) {
  const auto fitter = quadrix::make_quadric_fitter("auto");
  const Eigen::Matrix3Xd points = segment(QuadricType::CircularCylinder, static_cast<int>(state.range(0)));
  for (auto _ : state) {
    const quadrix::QuadricFit fit = fitter->fit(points, Eigen::Matrix3Xd(), QuadricType::CircularCylinder);
    benchmark::DoNotOptimize(fit.quadric.matrix().data());
  }
}

BENCHMARK_CAPTURE(learned_fit, plane, QuadricType::Plane)->Arg(2000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(learned_fit, line, QuadricType::Line)->Arg(2000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(learned_fit, sphere, QuadricType::Sphere)->Arg(2000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(learned_fit, cylinder, QuadricType::CircularCylinder)->Arg(2000)->Arg(10000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(learned_fit, cone, QuadricType::CircularCone)->Arg(2000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(learned_fit, ellipsoid, QuadricType::Ellipsoid)->Arg(2000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(network_forward, cylinder, QuadricType::CircularCylinder)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(network_forward, ellipsoid, QuadricType::Ellipsoid)->Unit(benchmark::kMillisecond);
BENCHMARK(auto_fit)->Arg(2000)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
