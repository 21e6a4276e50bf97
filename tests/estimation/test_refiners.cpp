// Refiners ("ceres", "nlopt"): convergence from perturbed starts on synthetic mixed-type scenes
// (noise-free, noisy, with wrong correspondences under robust losses), agreement of the backends,
// the degeneracy refusal and the registry.
#include "estimation/refiner.h"
#include "estimation/synthetic_scene.h"
#include "geometry/constants.h"
#include "geometry/error.h"

#include <gtest/gtest.h>

#include <iostream>
#include <random>
#include <string>

namespace quadrix {
namespace {

using testing::make_scene;
using testing::pose_error;
using testing::SceneSpec;

struct Backend {
  std::string name;       // registry name
  std::string algorithm;  // RefinerOptions::algorithm
};

std::string label(const Backend& backend) { return backend.name + "/" + backend.algorithm; }

const std::vector<Backend>& all_backends() {
  static const std::vector<Backend> backends{{"ceres", "levenberg_marquardt"}, {"ceres", "dogleg"},
                                             {"nlopt", "lbfgs"}, {"nlopt", "slsqp"}, {"nlopt", "bobyqa"}};
  return backends;
}

std::vector<QuadricFactor> factors_of(const testing::SyntheticScene& scene, bool augment = true) {
  FactorBuildOptions options;
  options.augment_non_central = augment;
  return build_quadric_factors(scene.source, decompose_records(scene.source), scene.target,
                               decompose_records(scene.target), scene.correspondences, options)
      .factors;
}

// Perturbs the truth by 0.5-5 m and 2-20 degrees (the refiner study's start range).
Eigen::Isometry3d perturbed_start(std::mt19937& rng, const Eigen::Isometry3d& truth) {
  std::uniform_real_distribution<double> translation(0.5, 5.0);
  std::uniform_real_distribution<double> degrees(2.0, 20.0);
  return testing::perturbation(rng, translation(rng), degrees(rng) * kPi / 180.0) * truth;
}

struct TrialStatistics {
  int within = 0;
  int trials = 0;
  int failed = 0;
  double worst_translation = 0.0;
  double worst_degrees = 0.0;
};

TrialStatistics run_trials(const Backend& backend, const SceneSpec& spec, const RefinerOptions& base_options,
                           int trials, double max_translation, double max_degrees, unsigned seed) {
  std::mt19937 rng(seed);
  const auto refiner = make_refiner(backend.name);
  RefinerOptions options = base_options;
  options.algorithm = backend.algorithm;
  TrialStatistics statistics;
  for (int trial = 0; trial < trials; ++trial) {
    const auto scene = make_scene(rng, spec);
    const std::vector<QuadricFactor> factors = factors_of(scene);
    const Eigen::Isometry3d start = perturbed_start(rng, scene.truth);
    const RefinementResult result = refiner->refine(factors, start, options);
    ++statistics.trials;
    if (result.status == RefinementStatus::Failed || result.status == RefinementStatus::Degenerate) {
      ++statistics.failed;
      continue;
    }
    EXPECT_LE(result.final_cost, result.initial_cost) << label(backend);
    const auto [translation_error, degrees_error] = pose_error(result.transform, scene.truth);
    if (translation_error <= max_translation && degrees_error <= max_degrees) ++statistics.within;
    statistics.worst_translation = std::max(statistics.worst_translation, translation_error);
    statistics.worst_degrees = std::max(statistics.worst_degrees, degrees_error);
  }
  return statistics;
}

TEST(Refiners, RegistryKnowsBothBackendsAndRejectsUnknownNames) {
  const auto names = refiner_names();
  EXPECT_NE(std::find(names.begin(), names.end(), "ceres"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "nlopt"), names.end());
  EXPECT_EQ(make_refiner("ceres")->name(), "ceres");
  EXPECT_EQ(make_refiner("nlopt")->name(), "nlopt");
  EXPECT_THROW(make_refiner("gauss_newton_by_hand"), Error);
  std::mt19937 rng(31);
  const auto scene = make_scene(rng, SceneSpec{});
  RefinerOptions options;
  options.algorithm = "nelder_mead";
  EXPECT_THROW(make_refiner("ceres")->refine(factors_of(scene), scene.truth, options), Error);
  EXPECT_THROW(make_refiner("nlopt")->refine(factors_of(scene), scene.truth, options), Error);
  options.algorithm.clear();
  options.loss = RobustLoss::Cauchy;
  options.loss_scale = 0.0;
  EXPECT_THROW(make_refiner("ceres")->refine(factors_of(scene), scene.truth, options), Error);
  EXPECT_THROW(make_refiner("nlopt")->refine(factors_of(scene), scene.truth, options), Error);
}

// Convergence target: from 5 m / 20 degree perturbations, noise-free, every backend reaches < 1 cm / 0.05 deg.
TEST(Refiners, EveryBackendConvergesToTheTruePoseFromPerturbedStartsWithoutNoise) {
  for (const Backend& backend : all_backends()) {
    const TrialStatistics statistics = run_trials(backend, SceneSpec{}, RefinerOptions{}, 100, 0.01, 0.05, 32);
    EXPECT_GE(statistics.within, 95) << label(backend) << ": " << statistics.within << "/" << statistics.trials
                                     << " within 1 cm / 0.05 deg, " << statistics.failed << " failed";
    RecordProperty(label(backend) + "_within", statistics.within);
  }
}

TEST(Refiners, NoisyAttributesGiveCentimetreLevelPoses) {
  SceneSpec spec;
  spec.rotation_noise = 0.5 * kPi / 180.0;  // 0.5 deg per axis on every target element
  spec.translation_noise = 0.02;             // 2 cm per axis
  for (const Backend& backend : all_backends()) {
    const TrialStatistics statistics = run_trials(backend, spec, RefinerOptions{}, 100, 0.05, 0.3, 33);
    EXPECT_GE(statistics.within, 95) << label(backend) << ": " << statistics.within << "/" << statistics.trials
                                     << " within 5 cm / 0.3 deg (worst " << statistics.worst_translation << " m, "
                                     << statistics.worst_degrees << " deg)";
  }
}

TEST(Refiners, RobustLossesRejectWrongCorrespondences) {
  SceneSpec spec;
  spec.copies_per_type = 3;
  spec.outlier_fraction = 0.2;
  spec.rotation_noise = 0.2 * kPi / 180.0;
  spec.translation_noise = 0.01;
  // Without a robust loss the wrong correspondences pull the pose away.
  const TrialStatistics plain = run_trials({"ceres", "levenberg_marquardt"}, spec, RefinerOptions{}, 100, 0.1, 0.5, 34);
  EXPECT_LT(plain.within, 50) << plain.within;
  for (const RobustLoss loss : {RobustLoss::Huber, RobustLoss::Cauchy, RobustLoss::Dcs}) {
    RefinerOptions options;
    options.loss = loss;
    options.loss_scale = 0.5;
    for (const Backend& backend : {Backend{"ceres", "levenberg_marquardt"}, Backend{"nlopt", "lbfgs"}}) {
      const TrialStatistics statistics = run_trials(backend, spec, options, 100, 0.1, 0.5, 34);
      std::cout << label(backend) << " " << robust_loss_name(loss) << ": " << statistics.within
                << "/100 within 10 cm / 0.5 deg (no loss: " << plain.within << ")\n";
      if (loss == RobustLoss::Huber) {
        // Huber bounds but does not cancel outlier influence (not redescending): better than none only.
        EXPECT_GT(statistics.within, plain.within + 10) << label(backend);
      } else {
        // Redescending kernels (Cauchy, DCS) reject the 20% wrong correspondences.
        EXPECT_GE(statistics.within, 90) << label(backend) << " " << robust_loss_name(loss);
      }
    }
  }
}

TEST(Refiners, BackendsMinimiseTheSameObjective) {
  std::mt19937 rng(35);
  SceneSpec spec;
  spec.rotation_noise = 1.0 * kPi / 180.0;
  spec.translation_noise = 0.05;
  for (int trial = 0; trial < 20; ++trial) {
    const auto scene = make_scene(rng, spec);
    const std::vector<QuadricFactor> factors = factors_of(scene);
    const Eigen::Isometry3d start = perturbed_start(rng, scene.truth);
    RefinerOptions options;
    options.loss = RobustLoss::Huber;
    options.loss_scale = 0.3;
    const RefinementResult ceres = make_refiner("ceres")->refine(factors, start, options);
    const RefinementResult nlopt = make_refiner("nlopt")->refine(factors, start, options);
    EXPECT_NEAR(ceres.initial_cost, nlopt.initial_cost, 1e-12 * ceres.initial_cost);
    EXPECT_NEAR(ceres.initial_cost, refinement_cost(factors, start, options.loss, options.loss_scale), 1e-9);
    EXPECT_NEAR(ceres.final_cost, nlopt.final_cost, 1e-5 * ceres.final_cost + 1e-12) << "trial " << trial;
    const auto [translation_gap, degrees_gap] = pose_error(ceres.transform, nlopt.transform);
    EXPECT_LT(translation_gap, 1e-3);
    EXPECT_LT(degrees_gap, 1e-2);
    for (const RefinementResult* result : {&ceres, &nlopt}) {
      EXPECT_EQ(result->status, RefinementStatus::Converged) << result->backend << ": " << result->message;
      EXPECT_GT(result->evaluations, 0);
      EXPECT_GT(result->iterations, 0);
      EXPECT_EQ(result->factor_count, factors.size());
      EXPECT_EQ(result->constrained_rank, 6);
      EXPECT_TRUE(result->weak_directions.empty());
      EXPECT_GE(result->seconds, 0.0);
    }
  }
}

TEST(Refiners, ParallelPlanesAreRefusedAsDegenerate) {
  std::mt19937 rng(36);
  const Eigen::Isometry3d truth = testing::random_pose(rng, 10.0);
  const Eigen::Vector3d normal = testing::random_unit_vector(rng);
  std::vector<QuadricRecord> source;
  std::vector<QuadricRecord> target;
  std::vector<RecordCorrespondence> pairs;
  for (int k = 0; k < 8; ++k) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitX(), normal).toRotationMatrix();
    pose.translation() = 2.0 * k * normal + testing::random_pose(rng, 10.0).translation();
    const Quadric plane = Quadric::from_canonical(QuadricType::Plane, Eigen::Vector3d::Ones(), pose);
    StatisticalPose statistics;
    statistics.center = pose.translation();
    statistics.scale = Eigen::Vector3d(5.0, 3.0, 0.05);
    statistics.rotation = testing::random_rotation(rng);
    StatisticalPose moved = statistics;
    moved.center = truth * statistics.center;
    moved.rotation = truth.linear() * statistics.rotation;
    pairs.push_back({source.size(), target.size()});
    source.push_back(make_quadric_record(2, plane, statistics));
    target.push_back(make_quadric_record(2, plane.transformed(truth), moved));
  }
  const auto factors = build_quadric_factors(source, decompose_records(source), target, decompose_records(target), pairs, {});
  EXPECT_EQ(factors.augmented_count, 32u);  // augmentation does not help: samples stay point-to-plane
  // Start misplaced by translation only: the normals are aligned, the check refuses before optimising.
  const Eigen::Isometry3d shifted = testing::perturbation(rng, 3.0, 0.0) * truth;
  // Start also rotated: misaligned planes constrain one more direction (rank 4, still < 6).
  const Eigen::Isometry3d start = perturbed_start(rng, truth);
  for (const Backend& backend : all_backends()) {
    RefinerOptions options;
    options.algorithm = backend.algorithm;
    const RefinementResult refused = make_refiner(backend.name)->refine(factors.factors, shifted, options);
    EXPECT_EQ(refused.status, RefinementStatus::Degenerate) << label(backend);
    EXPECT_EQ(refused.constrained_rank, 3) << label(backend);
    EXPECT_EQ(refused.weak_directions.size(), 3u) << label(backend);
    EXPECT_TRUE(refused.transform.isApprox(shifted)) << label(backend);
    EXPECT_EQ(refused.evaluations, 0);
    EXPECT_FALSE(refused.message.empty());
    const RefinementResult detected = make_refiner(backend.name)->refine(factors.factors, start, options);
    EXPECT_EQ(detected.status, RefinementStatus::Degenerate) << label(backend) << ": " << detected.message;
    EXPECT_LT(detected.constrained_rank, 6) << label(backend);
    EXPECT_EQ(detected.weak_directions.size(), static_cast<std::size_t>(6 - detected.constrained_rank)) << label(backend);
  }
  // No factors at all: degenerate too.
  EXPECT_EQ(make_refiner("ceres")->refine({}, start).status, RefinementStatus::Degenerate);
  EXPECT_EQ(make_refiner("nlopt")->refine({}, start).status, RefinementStatus::Degenerate);
}

TEST(Refiners, TightBudgetsReportMaxIterations) {
  std::mt19937 rng(37);
  const auto scene = make_scene(rng, SceneSpec{});
  const auto factors = factors_of(scene);
  const Eigen::Isometry3d start = testing::perturbation(rng, 5.0, 0.35) * scene.truth;
  RefinerOptions options;
  options.max_iterations = 1;
  options.max_evaluations = 3;
  const RefinementResult ceres = make_refiner("ceres")->refine(factors, start, options);
  EXPECT_EQ(ceres.status, RefinementStatus::MaxIterations) << ceres.message;
  EXPECT_LT(ceres.final_cost, ceres.initial_cost);
  const RefinementResult nlopt = make_refiner("nlopt")->refine(factors, start, options);
  EXPECT_EQ(nlopt.status, RefinementStatus::MaxIterations) << nlopt.message;
  EXPECT_EQ(nlopt.evaluations, 3);
  options.max_iterations = 0;
  EXPECT_THROW(make_refiner("ceres")->refine(factors, start, options), Error);
}

}  // namespace
}  // namespace quadrix
