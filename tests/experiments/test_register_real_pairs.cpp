// Registration acceptance on the non-KITTI pairs of ../shared/data/pairs.tsv that have ground truth (HDL-32E, 3DTK,
// 3DMatch), each side with `--preset auto`, as `quadrix register` runs them. (The KITTI pairs are in
// tests/estimation/test_registration.cpp.) Every pair is printed beside the identity's errors, so a
// "success" that the identity would also achieve is visible; the assertions are the rule "never a
// confident wrong answer" on every pair, and the pairs measured to succeed.
#include "estimation/registration.h"
#include "experiments/benchmark/bench_pairs.h"
#include "estimation/registration_config.h"
#include "geometry/constants.h"
#include "geometry/io.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>

namespace quadrix {
namespace {

TEST(RegisterRealPairs, NonKittiPairsAreSolvedOrFlaggedNeverConfidentlyWrong) {
  QUADRIX_REQUIRE_SHARED_DATA("pairs.tsv");
  int pairs_run = 0;
  for (const BenchPair& pair : read_pairs_tsv(testing::shared_data_path("pairs.tsv"))) {
    if (!pair.ground_truth || pair.id.rfind("kitti", 0) == 0) continue;
    if (!std::filesystem::exists(pair.source) || !std::filesystem::exists(pair.target)) {
      std::printf("%-14s absent, not run\n", pair.id.c_str());
      continue;
    }
    SCOPED_TRACE(pair.id);
    const PointCloud source = read_point_cloud(pair.source);
    const PointCloud target = read_point_cloud(pair.target);
    const RegistrationOptions options = resolve_registration_options("auto", source, "auto", target);
    const RegistrationResult result = register_clouds(source, target, options);
    const Eigen::Isometry3d& truth = *pair.ground_truth;
    const bool success = registration_succeeded(result.transform, truth);
    const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
    std::printf("%-14s status %-10s RTE %6.3f m RRE %6.3f deg %s | identity: RTE %6.3f m RRE %6.3f deg %s | %s\n",
                pair.id.c_str(), registration_status_name(result.status), translation_error(result.transform, truth),
                rotation_error_degrees(result.transform, truth), success ? "SUCCESS" : "FAILURE",
                translation_error(identity, truth), rotation_error_degrees(identity, truth),
                registration_succeeded(identity, truth) ? "success" : "failure", result.message.c_str());
    ++pairs_run;
    // A transform reported `ok` must be right; a wrong answer has to carry a non-ok status.
    if (result.status == RegistrationStatus::Ok) {
      EXPECT_TRUE(success) << "confident wrong answer: RTE " << translation_error(result.transform, truth) << " m, RRE "
                           << rotation_error_degrees(result.transform, truth) << " deg";
    }
    // Measured to succeed (docs/registration.md, results on pairs.tsv): the HDL-32E pair and all three
    // 3DTK pairs, within 0.5 m, where the identity is 1.6-3.4 m off (the ground truth is good to
    // 5-20 cm). Each is `ok` unless the answer lands less of the source on the target than not
    // moving (3DTK 2->0, whose truth does: 0.69 against 0.76), which is `ambiguous` by the overlap
    // guard, or puts points where the other sensor saw through, which leaves it `ambiguous`.
    if (pair.id == "hdl32_local" || pair.id.rfind("3dtk", 0) == 0) {
      ASSERT_TRUE(result.overlap.has_value());
      const bool beats_not_moving = result.overlap->transformed >= result.overlap->identity;
      const bool sure = beats_not_moving && !result.findings.in_free_space;
      EXPECT_EQ(result.status, sure ? RegistrationStatus::Ok : RegistrationStatus::Ambiguous) << result.message;
      EXPECT_TRUE(success) << "RTE " << translation_error(result.transform, truth) << " m, RRE "
                           << rotation_error_degrees(result.transform, truth) << " deg";
      EXPECT_LT(translation_error(result.transform, truth), 0.5);
    }
  }
  EXPECT_GT(pairs_run, 0);
}

// The dense search on real scans: each KITTI loop closure, the HDL-32E pair and the 3DTK pairs,
// modelled under `auto`, handed to verify_registration as an `ambiguous` answer 5, 10 or 15 m off
// along a random horizontal direction. It must come back `ok` at the ground truth or stay
// `ambiguous`; never `ok` and wrong. At 5 m, inside the grid of starts (8 m along the weakest
// direction, 5 m across), every pair must settle.
TEST(RegisterRealPairs, DenseSearchNeverSettlesAnAnswerWrongly) {
  QUADRIX_REQUIRE_SHARED_DATA("pairs.tsv");
  std::mt19937 rng(23);
  int run = 0;
  for (const BenchPair& pair : read_pairs_tsv(testing::shared_data_path("pairs.tsv"))) {
    const bool wanted = pair.id.rfind("kitti00_lc", 0) == 0 || pair.id == "hdl32_local" || pair.id.rfind("3dtk", 0) == 0;
    if (!pair.ground_truth || !wanted) continue;
    if (!std::filesystem::exists(pair.source) || !std::filesystem::exists(pair.target)) continue;
    const PointCloud source = read_point_cloud(pair.source);
    const PointCloud target = read_point_cloud(pair.target);
    const RegistrationOptions options = resolve_registration_options("auto", source, "auto", target);
    const RegistrationResult modelled = register_clouds(source, target, options);  // for the models' grounds
    const Eigen::Isometry3d& truth = *pair.ground_truth;
    for (const double offset : {5.0, 10.0, 15.0}) {
      SCOPED_TRACE(pair.id + " offset " + std::to_string(offset));
      const double heading = std::uniform_real_distribution<double>(0.0, 2.0 * kPi)(rng);
      RegistrationResult result;
      result.status = RegistrationStatus::Ambiguous;
      result.transform = Eigen::Translation3d(offset * std::cos(heading), offset * std::sin(heading), 0.0) * truth;
      result.source_model = modelled.source_model;
      result.target_model = modelled.target_model;
      verify_registration(result, source, target, options);
      ++run;
      const DenseSearchResult& search = *result.dense_search;
      std::printf("%-18s %4.0f m off: %-9s RTE %6.3f m RRE %5.3f deg margin %.3f best %s (%.3f)%s dense %.0f ms\n",
                  pair.id.c_str(), offset, registration_status_name(result.status), translation_error(result.transform, truth),
                  rotation_error_degrees(result.transform, truth), search.margin, search.optima[search.best].start.c_str(),
                  search.optima[search.best].overlap, search.best_in_searched_region ? "" : " outside the grid",
                  result.timings_ms.at("dense_search"));
      if (result.status == RegistrationStatus::Ok) {
        EXPECT_LT(translation_error(result.transform, truth), 0.3);
        EXPECT_LT(rotation_error_degrees(result.transform, truth), 2.0);  // 3DTK's approximate truth: ~1.4 deg
      } else {
        EXPECT_EQ(result.status, RegistrationStatus::Ambiguous);
      }
      if (offset == 5.0) {
        // Inside the grid every pair settles, at the truth; the overlap guard may still call the
        // settled answer `ambiguous` where the truth lands less of the source than not moving.
        EXPECT_TRUE(result.findings.settled_by_dense_search) << result.message;
        EXPECT_LT(translation_error(result.transform, truth), 0.3) << result.message;
      }
    }
  }
  if (run == 0) GTEST_SKIP() << "none of the pairs is in pairs.tsv";
}

}  // namespace
}  // namespace quadrix
