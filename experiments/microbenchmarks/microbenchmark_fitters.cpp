// Time per fit of every registered fitter (targets: statistical <= 50 us and taubin <= 1 ms
// on 10k points; constrained and cgal per type). Segments come from the study's generator
// (full surfaces, 1 cm noise, fixed seeds). Every benchmark name says how the fit's residual
// statistics were evaluated (evaluate_fit): skip (the fit alone, as scene modelling runs it),
// subsample (at most 2,000 evenly strided points) or exact (every point, as `quadrix fit` prints).
// The counter residual_points repeats it, evaluation_us is the part of each fit spent evaluating.
// Run: build/bin/microbenchmark_fitters [--benchmark_filter=fit/taubin/]
#include "experiments/studies/fitter_study.h"

#include <benchmark/benchmark.h>

#include <map>
#include <string>
#include <utility>

namespace {

using quadrix::QuadricType;
using quadrix::ResidualEvaluation;

/// One segment per (type, size), built once.
const Eigen::Matrix3Xd& segment(QuadricType type, int points) {
  static std::map<std::pair<int, int>, Eigen::Matrix3Xd> cache;
  const auto key = std::make_pair(static_cast<int>(type), points);
  auto found = cache.find(key);
  if (found == cache.end()) {
    quadrix::SyntheticSegmentSpec spec;
    spec.type = type;
    spec.noise = 0.01;
    spec.points = points;
    spec.seed = 99;
    found = cache.emplace(key, quadrix::make_synthetic_segment(spec).points).first;
  }
  return found->second;
}

void fit(benchmark::State& state, const std::string& fitter_name, QuadricType type, ResidualEvaluation residuals) {
  quadrix::FitEvaluationOptions evaluation;
  evaluation.residuals = residuals;
  const auto fitter = quadrix::make_quadric_fitter(fitter_name, evaluation);
  const Eigen::Matrix3Xd& points = segment(type, static_cast<int>(state.range(0)));
  const Eigen::Matrix3Xd no_normals;
  double evaluation_ms = 0.0;
  Eigen::Index residual_points = 0;
  for (auto _ : state) {
    quadrix::QuadricFit result = fitter->fit(points, no_normals, type);
    benchmark::DoNotOptimize(result.quadric);
    evaluation_ms += result.evaluation_ms;
    residual_points = result.residual_points;
    if (result.status != quadrix::FitStatus::Ok && result.status != quadrix::FitStatus::NotConverged) {
      state.SkipWithError(("fit failed: " + result.message).c_str());
      break;
    }
  }
  state.SetItemsProcessed(state.iterations() * points.cols());
  state.counters["residual_points"] = static_cast<double>(residual_points);
  state.counters["evaluation_us"] =
      state.iterations() > 0 ? 1000.0 * evaluation_ms / static_cast<double>(state.iterations()) : 0.0;
}

void register_all() {
  const std::pair<const char*, QuadricType> types[] = {
      {"plane", QuadricType::Plane},
      {"sphere", QuadricType::Sphere},
      {"cylinder", QuadricType::CircularCylinder},
      {"cone", QuadricType::CircularCone},
      {"ellipsoid", QuadricType::Ellipsoid},
  };
  const ResidualEvaluation modes[] = {ResidualEvaluation::Skip, ResidualEvaluation::Subsample, ResidualEvaluation::Exact};
  for (const auto& name : quadrix::quadric_fitter_names())
    for (const auto& [type_name, type] : types)
      for (const ResidualEvaluation mode : modes) {
        const std::string title = "fit/" + name + "/" + type_name + "/" + quadrix::residual_evaluation_name(mode);
        auto* bench = benchmark::RegisterBenchmark(title.c_str(), [name = name, type = type, mode](benchmark::State& state) {
          fit(state, name, type, mode);
        });
        bench->Unit(benchmark::kMicrosecond)->Arg(1000)->Arg(10000);
      }
}

}  // namespace

int main(int argc, char** argv) {
  register_all();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
