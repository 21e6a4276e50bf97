// Registration from an initial guess (RegistrationOptions::initial_guess, local_only) and what every
// answer carries for a back end (fitness, inlier RMSE, correspondences into the caller's clouds,
// information): a synthetic street pair from guesses 1 m and 5 degrees off (statistical acceptance
// over seeds and directions), a far guess that must not come back `ok` and wrong, a guess competing
// with the global answer, and a real KITTI pair when ../shared/data is present.
#include "estimation/registration.h"
#include "estimation/street_scene.h"
#include "geometry/error.h"
#include "geometry/io.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <cmath>
#include <cstdio>
#include <random>

namespace quadrix {
namespace {

using testing::make_pose;
using testing::make_street_world;
using testing::observe;

// A perturbation of exactly `translation` metres along a random horizontal-ish direction and
// `angle_degrees` about a random axis.
Eigen::Isometry3d perturbation(std::mt19937& rng, double translation, double angle_degrees) {
  std::normal_distribution<double> gauss(0.0, 1.0);
  const Eigen::Vector3d axis = Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized();
  const Eigen::Vector3d direction = Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized();
  Eigen::Isometry3d delta = Eigen::Isometry3d::Identity();
  delta.linear() = Eigen::AngleAxisd(angle_degrees * M_PI / 180.0, axis).toRotationMatrix();
  delta.translation() = translation * direction;
  return delta;
}

// The synthetic street pair of a seed and its truth (source sensor -> target sensor).
struct StreetPair {
  PointCloud source, target;
  Eigen::Isometry3d truth;
};

StreetPair street_pair(std::uint64_t seed, double yaw_degrees) {
  const std::vector<Eigen::Vector3d> world = make_street_world(seed);
  const Eigen::Isometry3d source_pose = make_pose(0.0, {-4.0, -0.5, 1.73});
  const Eigen::Isometry3d target_pose = make_pose(yaw_degrees, {3.0, 1.0, 1.73});
  return {observe(world, source_pose), observe(world, target_pose), target_pose.inverse() * source_pose};
}

// The back-end fields of an `ok` or `ambiguous` answer hold together: every correspondence indexes
// the caller's clouds and lies within the distance under the answer, fitness counts them, the
// information is symmetric positive semi-definite.
void expect_back_end_fields(const RegistrationResult& result, const PointCloud& source, const PointCloud& target,
                            const RegistrationOptions& options) {
  ASSERT_TRUE(result.status == RegistrationStatus::Ok || result.status == RegistrationStatus::Ambiguous);
  ASSERT_FALSE(result.correspondences.empty());
  double squared = 0.0;
  std::size_t previous = 0;
  for (std::size_t k = 0; k < result.correspondences.size(); ++k) {
    const auto [s, t] = result.correspondences[k];
    ASSERT_LT(s, source.size());
    ASSERT_LT(t, target.size());
    if (k > 0) {
      ASSERT_GT(s, previous);  // each source point once, ascending
    }
    previous = s;
    const double distance = (result.transform * source.point(s) - target.point(t)).norm();
    ASSERT_LE(distance, options.quality.correspondence_distance + 1e-6);
    squared += distance * distance;
  }
  EXPECT_NEAR(result.inlier_rmse, std::sqrt(squared / static_cast<double>(result.correspondences.size())), 1e-6);
  // Fitness is over the checks' source points (within range, isolated ones left out): at most all.
  EXPECT_GE(result.fitness, static_cast<double>(result.correspondences.size()) / static_cast<double>(source.size()) - 1e-12);
  EXPECT_LE(result.fitness, 1.0);
  EXPECT_TRUE(result.information.isApprox(result.information.transpose(), 1e-9));
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> solver(result.information);
  EXPECT_GE(solver.eigenvalues()(0), -1e-9 * solver.eigenvalues()(5));
  EXPECT_GT(solver.eigenvalues()(5), 0.0);
}

RegistrationOptions street_options() {
  RegistrationOptions options;
  options.modelling.augmentation_threshold = 0;  // as the global street test: no augmented points
  return options;
}

TEST(RegisterLocally, ConvergesFromGuessesOneMetreAndFiveDegreesOff) {
  std::mt19937 rng(2024);
  int right = 0, runs = 0;
  for (std::uint64_t seed = 41; seed < 44; ++seed) {
    const StreetPair pair = street_pair(seed, 20.0 + 5.0 * static_cast<double>(seed - 41));
    for (int draw = 0; draw < 2; ++draw) {
      RegistrationOptions options = street_options();
      options.local_only = true;
      options.initial_guess = perturbation(rng, 1.0, 5.0) * pair.truth;
      const RegistrationResult result = register_clouds(pair.source, pair.target, options);
      const double rte = translation_error(result.transform, pair.truth), rre = rotation_error_degrees(result.transform, pair.truth);
      std::printf("seed %llu draw %d: %s, RTE %.3f m, RRE %.3f deg, fitness %.3f, RMSE %.3f m, %zu pairs, %.0f ms\n  %s\n",
                  static_cast<unsigned long long>(seed), draw, registration_status_name(result.status), rte, rre, result.fitness,
                  result.inlier_rmse, result.correspondences.size(), result.timings_ms.at("total"), result.message.c_str());
      EXPECT_TRUE(result.from_initial_guess);
      EXPECT_TRUE(result.candidates.empty());  // no quadric was matched
      EXPECT_EQ(result.timings_ms.count("correspondences"), 0u);
      EXPECT_EQ(result.timings_ms.count("guess_icp"), 1u);
      expect_back_end_fields(result, pair.source, pair.target, options);
      ++runs;
      if (result.status == RegistrationStatus::Ok && rte <= 0.1 && rre <= 0.5) ++right;
      // Never `ok` and wrong.
      EXPECT_FALSE(result.status == RegistrationStatus::Ok && !registration_succeeded(result.transform, pair.truth));
    }
  }
  EXPECT_GE(right, runs - 1) << right << " of " << runs << " guesses converged to an `ok` answer";
}

TEST(RegisterLocally, AFarGuessIsNeverOkAndWrong) {
  std::mt19937 rng(2025);
  int wrong_ok = 0;
  for (std::uint64_t seed = 51; seed < 54; ++seed) {
    const StreetPair pair = street_pair(seed, 30.0);
    RegistrationOptions options = street_options();
    options.local_only = true;
    // 15 m and 90 degrees off: beyond any ICP basin in a street.
    options.initial_guess = perturbation(rng, 15.0, 90.0) * pair.truth;
    const RegistrationResult result = register_clouds(pair.source, pair.target, options);
    const bool success = registration_succeeded(result.transform, pair.truth);
    std::printf("seed %llu: %s, %s, fitness %.3f\n  %s\n", static_cast<unsigned long long>(seed),
                registration_status_name(result.status), success ? "right" : "wrong", result.fitness, result.message.c_str());
    if (result.status == RegistrationStatus::Ok && !success) ++wrong_ok;
  }
  EXPECT_EQ(wrong_ok, 0);
}

TEST(RegisterLocally, NeedsAFiniteGuess) {
  const StreetPair pair = street_pair(61, 30.0);
  RegistrationOptions options = street_options();
  options.local_only = true;
  EXPECT_THROW(register_clouds(pair.source, pair.target, options), Error);
  Eigen::Isometry3d not_finite = Eigen::Isometry3d::Identity();
  not_finite.translation().x() = std::nan("");
  options.initial_guess = not_finite;
  EXPECT_THROW(register_clouds(pair.source, pair.target, options), Error);
  options.initial_guess = pair.truth;
  options.initial_guess_reach = 0.0;
  EXPECT_THROW(register_clouds(pair.source, pair.target, options), Error);
}

TEST(RegisterClouds, AGlobalAnswerCarriesTheBackEndFields) {
  const StreetPair pair = street_pair(11, 35.0);
  const RegistrationOptions options = street_options();
  const RegistrationResult result = register_clouds(pair.source, pair.target, options);
  ASSERT_EQ(result.status, RegistrationStatus::Ok) << result.message;
  EXPECT_FALSE(result.from_initial_guess);
  EXPECT_EQ(result.timings_ms.count("quality"), 1u);
  expect_back_end_fields(result, pair.source, pair.target, options);
  EXPECT_GT(result.fitness, 0.5);
  EXPECT_LT(result.inlier_rmse, 0.1);
}

TEST(RegisterClouds, AGuessCompetesWithTheGlobalAnswer) {
  std::mt19937 rng(2026);
  const StreetPair pair = street_pair(12, 40.0);
  // A good guess: the verified winner is right and `ok`, whichever run it came from.
  RegistrationOptions options = street_options();
  options.initial_guess = perturbation(rng, 1.0, 5.0) * pair.truth;
  const RegistrationResult near = register_clouds(pair.source, pair.target, options);
  EXPECT_EQ(near.status, RegistrationStatus::Ok) << near.message;
  EXPECT_TRUE(registration_succeeded(near.transform, pair.truth));
  EXPECT_EQ(near.timings_ms.count("initial_guess"), 1u);
  EXPECT_EQ(near.candidates.size(), options.graphs.thresholds.size());  // the global run's candidates are kept
  expect_back_end_fields(near, pair.source, pair.target, options);
  // A far guess loses to the global answer.
  options.initial_guess = perturbation(rng, 15.0, 90.0) * pair.truth;
  const RegistrationResult far = register_clouds(pair.source, pair.target, options);
  EXPECT_EQ(far.status, RegistrationStatus::Ok) << far.message;
  EXPECT_TRUE(registration_succeeded(far.transform, pair.truth));
  EXPECT_FALSE(far.from_initial_guess);
}

TEST(RegisterLocallyRealData, KittiPairFromAPerturbedGroundTruth) {
  QUADRIX_REQUIRE_SHARED_DATA("kitti00/velodyne/000052.bin");
  QUADRIX_REQUIRE_SHARED_DATA("kitti00/velodyne/000088.bin");
  const PointCloud source = read_point_cloud(testing::shared_data_path("kitti00/velodyne/000052.bin"));
  const PointCloud target = read_point_cloud(testing::shared_data_path("kitti00/velodyne/000088.bin"));
  const Eigen::Isometry3d truth = read_pose_matrix(testing::shared_data_path("kitti00/gt/T_000088_from_000052.txt"));
  std::mt19937 rng(2027);
  int right = 0;
  const int draws = 2;
  for (int draw = 0; draw < draws; ++draw) {
    RegistrationOptions options;
    options.local_only = true;
    options.initial_guess = perturbation(rng, 1.0, 5.0) * truth;
    const RegistrationResult result = register_clouds(source, target, options);
    const double rte = translation_error(result.transform, truth), rre = rotation_error_degrees(result.transform, truth);
    std::printf("KITTI 52 -> 88, draw %d: %s, RTE %.3f m, RRE %.3f deg, fitness %.3f, RMSE %.3f m, %zu pairs, "
                "total %.0f ms (guess ICP %.0f, quality %.0f)\n  %s\n",
                draw, registration_status_name(result.status), rte, rre, result.fitness, result.inlier_rmse,
                result.correspondences.size(), result.timings_ms.at("total"), result.timings_ms.at("guess_icp"),
                result.timings_ms.at("quality"), result.message.c_str());
    expect_back_end_fields(result, source, target, options);
    EXPECT_FALSE(result.status == RegistrationStatus::Ok && !registration_succeeded(result.transform, truth));
    if (result.status == RegistrationStatus::Ok && rte <= 0.3 && rre <= 1.0) ++right;
  }
  EXPECT_EQ(right, draws);
}

}  // namespace
}  // namespace quadrix
