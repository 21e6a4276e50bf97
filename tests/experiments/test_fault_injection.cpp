// Fault injection (`quadrix bench --corrupt`): the corruptions do what their names say, and on real
// pairs a damaged source never crashes registration and never comes back `ok` and wrong.
#include "experiments/benchmark/benchmark_runner.h"
#include "experiments/benchmark/fault_injection.h"
#include "geometry/error.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <string>

#include <unistd.h>

namespace quadrix {
namespace {

// A horizontal ring of `count` points at radius 10 m around the origin, with every optional field.
PointCloud ring_with_fields(std::size_t count) {
  PointCloud cloud;
  cloud.positions.resize(3, static_cast<Eigen::Index>(count));
  for (std::size_t i = 0; i < count; ++i) {
    const double angle = 2.0 * M_PI * double(i) / double(count);
    cloud.positions.col(static_cast<Eigen::Index>(i)) =
        Eigen::Vector3f(float(10.0 * std::cos(angle)), float(10.0 * std::sin(angle)), float(i % 7));
    cloud.intensity.push_back(float(i));
    cloud.labels.push_back(static_cast<std::uint32_t>(i));
    cloud.colors.push_back({static_cast<std::uint8_t>(i % 256), 1, 2});
    cloud.extra_fields["ring"].push_back(float(i % 64));
  }
  return cloud;
}

// Every optional field still has one entry per point.
void expect_fields_follow(const PointCloud& cloud) {
  EXPECT_EQ(cloud.intensity.size(), cloud.size());
  EXPECT_EQ(cloud.labels.size(), cloud.size());
  EXPECT_EQ(cloud.colors.size(), cloud.size());
  EXPECT_EQ(cloud.extra_fields.at("ring").size(), cloud.size());
}

TEST(FaultInjection, DropKeepsTheExpectedShareWithItsFields) {
  const PointCloud cloud = ring_with_fields(20000);
  for (const double percent : {30.0, 60.0, 90.0}) {
    const PointCloud kept = corrupt_cloud(cloud, parse_corruption("drop-" + std::to_string(int(percent))), 7);
    const double expected = (1.0 - percent / 100.0) * double(cloud.size());
    // Binomial: 5 standard deviations of the kept count.
    const double sigma = std::sqrt(double(cloud.size()) * percent / 100.0 * (1.0 - percent / 100.0));
    EXPECT_NEAR(double(kept.size()), expected, 5.0 * sigma) << percent;
    expect_fields_follow(kept);
    // A kept point keeps its own fields: intensity i belongs to the point made with index i.
    for (std::size_t k = 0; k < kept.size(); k += 97) {
      const std::size_t original = static_cast<std::size_t>(kept.intensity[k]);
      EXPECT_EQ(kept.labels[k], original);
      EXPECT_TRUE(kept.positions.col(Eigen::Index(k)).isApprox(cloud.positions.col(Eigen::Index(original))));
    }
  }
}

TEST(FaultInjection, SectorRemovesOneWedgeOfTheGivenAngle) {
  const PointCloud cloud = ring_with_fields(3600);
  for (const std::uint64_t seed : {1u, 2u, 3u}) {
    const PointCloud kept = corrupt_cloud(cloud, parse_corruption("sector-90"), seed);
    EXPECT_NEAR(double(kept.size()), 2700.0, 2.0);
    expect_fields_follow(kept);
    // The missing azimuths form one contiguous wedge: sorted kept azimuths have one gap of ~90 deg.
    std::vector<double> azimuths;
    for (std::size_t i = 0; i < kept.size(); ++i)
      azimuths.push_back(std::atan2(kept.positions(1, Eigen::Index(i)), kept.positions(0, Eigen::Index(i))) * 180.0 / M_PI);
    std::sort(azimuths.begin(), azimuths.end());
    double widest = azimuths.front() + 360.0 - azimuths.back();
    for (std::size_t i = 1; i < azimuths.size(); ++i) widest = std::max(widest, azimuths[i] - azimuths[i - 1]);
    EXPECT_NEAR(widest, 90.0, 0.2) << "seed " << seed;
  }
}

TEST(FaultInjection, OutliersNoiseDuplicateAndScale) {
  const PointCloud cloud = ring_with_fields(10000);
  const PointCloud outliers = corrupt_cloud(cloud, parse_corruption("outliers-30"), 3);
  EXPECT_EQ(outliers.size(), 13000u);
  expect_fields_follow(outliers);
  const Eigen::Vector3f low = cloud.positions.rowwise().minCoeff();
  const Eigen::Vector3f high = cloud.positions.rowwise().maxCoeff();
  for (Eigen::Index i = 10000; i < 13000; ++i) {
    EXPECT_TRUE((outliers.positions.col(i).array() >= low.array()).all() &&
                (outliers.positions.col(i).array() <= high.array()).all());
    EXPECT_EQ(outliers.labels[std::size_t(i)], 0u);
  }

  const PointCloud noisy = corrupt_cloud(cloud, parse_corruption("noise-0.5"), 4);
  ASSERT_EQ(noisy.size(), cloud.size());
  std::size_t moved = 0;
  double squared = 0.0;
  for (Eigen::Index i = 0; i < cloud.positions.cols(); ++i) {
    const double distance = (noisy.positions.col(i) - cloud.positions.col(i)).norm();
    if (distance > 0.0) {
      ++moved;
      squared += distance * distance;
    }
  }
  EXPECT_NEAR(double(moved), kNoisyPointFraction * 10000.0, 5.0 * std::sqrt(10000.0 * 0.2 * 0.8));
  EXPECT_NEAR(std::sqrt(squared / double(moved) / 3.0), 0.5, 0.03);  // per-axis sigma of the moved points

  const PointCloud doubled = corrupt_cloud(cloud, parse_corruption("duplicate"), 5);
  ASSERT_EQ(doubled.size(), 20000u);
  expect_fields_follow(doubled);
  EXPECT_EQ(doubled.labels[12345], cloud.labels[2345]);
  EXPECT_TRUE(doubled.positions.col(12345).isApprox(cloud.positions.col(2345)));

  const PointCloud scaled = corrupt_cloud(cloud, parse_corruption("scale-1.001"), 6);
  EXPECT_NEAR(scaled.positions.col(0).norm() / cloud.positions.col(0).norm(), 1.001, 1e-6);
}

TEST(FaultInjection, BadNamesAreErrorsNamingTheValue) {
  for (const char* bad : {"drop-100", "drop-0", "drop-x", "sector-400", "outliers-0", "noise-20", "scale-3", "shuffle"}) {
    try {
      parse_corruption(bad);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const Error& error) {
      EXPECT_NE(std::string(error.what()).find(std::string("--corrupt ") + bad), std::string::npos) << error.what();
    }
  }
  EXPECT_EQ(parse_corruption("none").kind, CorruptionKind::None);
  EXPECT_EQ(parse_corruption("").kind, CorruptionKind::None);
  for (const std::string& name : standard_corruption_names()) EXPECT_NO_THROW(parse_corruption(name)) << name;
}

// Every standard corruption of the source of one real pair per (sensor, kind) of pairs.tsv with
// ground truth below the paper's hard bin (t_m < 20 m, as the KITTI success test): each run finishes
// with a status (none throws), and no answer is `ok` and wrong. A damaged pair may fail.
TEST(FaultInjectionRealData, DamagedSourcesNeverCrashAndAreNeverOkAndWrong) {
  QUADRIX_REQUIRE_SHARED_DATA("pairs.tsv");
  std::vector<BenchPair> pairs;
  std::set<std::pair<std::string, std::string>> groups;
  for (const BenchPair& pair : read_pairs_tsv(testing::shared_data_path("pairs.tsv")))
    if (pair.ground_truth && pair.distance < 20.0 && groups.emplace(pair.sensor, pair.kind).second) pairs.push_back(pair);
  if (pairs.size() < 2) GTEST_SKIP() << "pairs.tsv holds fewer than two kinds of pairs with ground truth";
  std::size_t rows_run = 0;
  std::size_t successes = 0;
  for (const std::string& corruption : standard_corruption_names()) {
    BenchOptions options;
    options.corruption = corruption;
    options.jobs = 2;
    options.progress = false;
    for (const BenchRow& row : run_benchmark(pairs, options)) {
      EXPECT_NE(row.status, "error") << row.pair_id << " " << corruption << ": " << row.message;
      ++rows_run;
      successes += row.success ? 1 : 0;
      EXPECT_FALSE(row.status == "ok" && !row.success)
          << row.pair_id << " " << corruption << " came back ok and wrong: RTE " << row.rte << " m, RRE " << row.rre
          << " deg; " << row.message;
    }
  }
  EXPECT_GT(rows_run, 0u);
  // The mild corruptions (30 % dropped, duplicates, 1.001 scale, noise on 20 % of the points) leave
  // these pairs solvable, so most rows must succeed: a run that failed everything would pass the
  // check above vacuously.
  EXPECT_GE(successes, rows_run / 2) << successes << " of " << rows_run << " rows succeeded";
}

// The rows of `pairs` with 30% uniform outliers added to every source (`trials` draws a pair from
// `seed`): first with the default options, then with the YAML `switched_off` applied.
std::array<std::vector<BenchRow>, 2> run_under_outliers_with_and_without(const std::vector<BenchPair>& pairs,
                                                                         const std::string& switched_off, int trials,
                                                                         std::uint64_t seed) {
  const std::filesystem::path config =
      std::filesystem::temp_directory_path() / ("quadrix_switched_off_" + std::to_string(::getpid()) + ".yaml");
  std::ofstream(config) << switched_off;
  std::array<std::vector<BenchRow>, 2> rows;
  for (const bool with_rule : {true, false}) {
    BenchOptions options;
    options.corruption = "outliers-30";
    options.trials = trials;
    options.seed = seed;
    options.jobs = 2;
    options.progress = false;
    if (!with_rule) options.config = config.string();
    rows[with_rule ? 0 : 1] = run_benchmark(pairs, options);
  }
  std::filesystem::remove(config);
  return rows;
}

// Uniform outliers never land on the target. Left in, they count against the right answer in every
// check, and loop closures come back `ambiguous`. The checks leave isolated points out
// (AmbiguityOptions::isolation_cell), and the KITTI pairs of pairs.tsv closer than the paper's hard
// bin with 30% outliers added to the source stay right and mostly `ok`. With the checks' rule
// switched off (the extraction's kept), fewer are `ok`.
TEST(FaultInjectionRealData, UniformOutliersLeaveRightAnswersOk) {
  QUADRIX_REQUIRE_SHARED_DATA("pairs.tsv");
  std::vector<BenchPair> pairs;
  for (const BenchPair& pair : read_pairs_tsv(testing::shared_data_path("pairs.tsv")))
    if (pair.ground_truth && pair.distance < 20.0 && pair.id.rfind("kitti00_lc_", 0) == 0) pairs.push_back(pair);
  if (pairs.empty()) GTEST_SKIP() << "pairs.tsv holds no KITTI loop closure closer than 20 m";
  const auto rows = run_under_outliers_with_and_without(pairs, "ambiguity:\n  isolation_cell: 0\n", 1, 1);
  std::size_t ok_with = 0, ok_without = 0;
  for (const bool leave_out : {true, false}) {
    for (const BenchRow& row : rows[leave_out ? 0 : 1]) {
      std::printf("%-20s isolated points %s: %s, RTE %.2f m, overlap %.3f\n", row.pair_id.c_str(), leave_out ? "left out" : "kept",
                  row.status.c_str(), row.rte, row.overlap);
      EXPECT_FALSE(row.status == "ok" && !row.success) << row.pair_id << ": " << row.message;
      if (leave_out) {
        EXPECT_TRUE(row.success) << row.pair_id << ": " << row.message;
      }
      (leave_out ? ok_with : ok_without) += row.status == "ok" && row.success ? 1 : 0;
    }
  }
  EXPECT_GE(ok_with, (3 * pairs.size() + 3) / 4) << ok_with << " of " << pairs.size() << " ok and right";
  EXPECT_GT(ok_with, ok_without);
}

// In the small scenes of pairs.tsv (3DTK's campus scans and the HDL-32E pair, tens of metres
// across) 30% uniform outliers are dense enough to reach the modelling: they join the ground and the
// clusters. The extraction leaves isolated points out before modelling
// (ExtractionOptions::isolation_cell). Over four outlier draws a pair, with the rule and without:
// no answer is `ok` and wrong, the HDL-32E pair is always right, and the rule does not lose right
// answers (docs/registration.md, "Isolated points", gives the measured counts).
TEST(FaultInjectionRealData, UniformOutliersInSmallScenesAreLeftOutBeforeModelling) {
  QUADRIX_REQUIRE_SHARED_DATA("pairs.tsv");
  std::vector<BenchPair> pairs;
  for (const BenchPair& pair : read_pairs_tsv(testing::shared_data_path("pairs.tsv")))
    if (pair.ground_truth && (pair.id.rfind("3dtk_", 0) == 0 || pair.id.rfind("hdl32", 0) == 0)) pairs.push_back(pair);
  if (pairs.empty()) GTEST_SKIP() << "pairs.tsv holds no 3DTK or HDL-32E pair with ground truth";
  const auto rows = run_under_outliers_with_and_without(pairs, "extraction:\n  isolation_cell: 0\n", 4, 5);
  std::size_t right_with = 0, right_without = 0;
  for (const bool leave_out : {true, false}) {
    for (const BenchRow& row : rows[leave_out ? 0 : 1]) {
      std::printf("%-12s trial %d, isolated points %s the modelling: %s, RTE %.2f m\n", row.pair_id.c_str(), row.trial,
                  leave_out ? "left out of" : "kept in", row.status.c_str(), row.rte);
      EXPECT_FALSE(row.status == "ok" && !row.success) << row.pair_id << ": " << row.message;
      if (row.pair_id.rfind("hdl32", 0) == 0) {
        EXPECT_TRUE(row.success) << row.pair_id << ": " << row.message;
      }
      (leave_out ? right_with : right_without) += row.success ? 1 : 0;
    }
  }
  std::printf("right: %zu of %zu with the rule, %zu without\n", right_with, 4 * pairs.size(), right_without);
  EXPECT_GE(right_with, right_without);
}

}  // namespace
}  // namespace quadrix
