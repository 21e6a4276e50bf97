// The refiner study: the convergence target on the synthetic monument and street (every
// backend/algorithm converges from 5 m / 20 deg starts on noise-free models without wrong
// correspondences), a tiny study whose rows are internally consistent and reproducible, the writers,
// bad options, and the real KITTI loop-closure problems when the data exists.
#include "estimation/refiner.h"
#include "experiments/studies/refiner_study.h"
#include "geometry/error.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <tuple>

namespace quadrix {
namespace {

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

RefinerStudyOptions synthetic_only() {
  RefinerStudyOptions options;
  options.real_data = false;
  return options;
}

// Convergence target: from 5 m / 20 degree perturbations with no wrong correspondences every backend
// and algorithm reaches < 1 cm / 0.05 deg on the noise-free monument and street models.
TEST(RefinerStudy, EveryBackendAndAlgorithmConvergesFromFiveMetresAndTwentyDegreesOnNoiseFreeModels) {
  RefinerStudyOptions options = synthetic_only();
  options.losses = {RobustLoss::None};
  options.outlier_fractions = {0.0};
  options.noise_levels = {AttributeNoise{}};
  options.trials = 10;
  options.minimum_translation = options.maximum_translation = 5.0;
  options.minimum_rotation_degrees = options.maximum_rotation_degrees = 20.0;
  const RefinerStudyResult result = run_refiner_study(options);
  const std::vector<RefinerConfiguration> expected = refiner_study_configurations({}, options.losses);
  ASSERT_EQ(result.configurations.size(), expected.size());
  ASSERT_GE(expected.size(), 5u);  // ceres LM + dogleg, nlopt L-BFGS + SLSQP + BOBYQA
  ASSERT_EQ(result.rows.size(), expected.size() * options.scenes.size() * static_cast<std::size_t>(options.trials));
  std::map<std::pair<std::string, std::string>, int> converged;
  for (const RefinerStudyRow& row : result.rows) {
    EXPECT_EQ(row.criterion, "truth");
    EXPECT_NEAR(row.start_translation, 5.0, 1e-9);
    EXPECT_NEAR(row.start_rotation_degrees, 20.0, 1e-6);
    EXPECT_EQ(row.wrong_correspondences, 0u);
    EXPECT_TRUE(row.converged) << row.source << " " << row.backend << "/" << row.algorithm << " trial " << row.trial << ": "
                               << row.status << ", RTE " << row.rte << " m, RRE " << row.rre_degrees << " deg";
    EXPECT_LT(row.rte, 0.01);
    EXPECT_LT(row.rre_degrees, 0.05);
    converged[{row.source, row.backend + "/" + row.algorithm}] += row.converged ? 1 : 0;
  }
  EXPECT_EQ(converged.size(), expected.size() * options.scenes.size());  // both scenes, every algorithm
}

RefinerStudyOptions tiny_study() {
  RefinerStudyOptions options = synthetic_only();
  options.scenes = {"monument"};
  options.backends = {"ceres"};
  options.losses = {RobustLoss::None, RobustLoss::Cauchy};
  options.outlier_fractions = {0.0, 0.25};
  options.noise_levels = {AttributeNoise{}, AttributeNoise{0.02, 0.5, 0.05}};
  options.trials = 3;
  return options;
}

TEST(RefinerStudy, TinyStudyRowsAreConsistent) {
  const RefinerStudyOptions options = tiny_study();
  const RefinerStudyResult result = run_refiner_study(options);
  ASSERT_EQ(result.configurations.size(), 4u);  // ceres {LM, dogleg} x {none, cauchy}
  ASSERT_EQ(result.rows.size(), 4u * 2u * 2u * 3u);
  std::map<std::tuple<std::string, std::string, double, double>, int> per_cell;
  for (const RefinerStudyRow& row : result.rows) {
    ++per_cell[{row.algorithm, row.loss, row.noise, row.outlier_fraction}];
    EXPECT_EQ(row.source, "monument");
    EXPECT_EQ(row.correspondence_set, "synthetic");
    EXPECT_EQ(row.backend, "ceres");
    EXPECT_GE(row.start_translation, options.minimum_translation - 1e-9);
    EXPECT_LE(row.start_translation, options.maximum_translation + 1e-9);
    EXPECT_GE(row.start_rotation_degrees, options.minimum_rotation_degrees - 1e-6);
    EXPECT_LE(row.start_rotation_degrees, options.maximum_rotation_degrees + 1e-6);
    EXPECT_EQ(row.correspondences, 62u);  // the monument's 62 primitives
    EXPECT_EQ(row.wrong_correspondences, static_cast<std::size_t>(std::llround(row.outlier_fraction * 62.0)));
    EXPECT_GT(row.factors, row.correspondences);  // augmentation of planes and cylinders
    const bool exact = row.noise == 0.0 && row.outlier_fraction == 0.0;
    EXPECT_EQ(row.criterion, exact ? "truth" : "reference");
    if (exact) {
      EXPECT_DOUBLE_EQ(row.gap_translation, row.rte);
      EXPECT_DOUBLE_EQ(row.gap_rotation_degrees, row.rre_degrees);
      EXPECT_LT(row.reference_rte, 1e-3);  // from the truth a noise-free problem stays there
    }
    const bool usable = row.status == "converged" || row.status == "max_iterations";
    EXPECT_EQ(row.converged, usable && row.gap_translation < options.converged_translation &&
                                 row.gap_rotation_degrees < options.converged_rotation_degrees)
        << row.algorithm << " " << row.loss << " trial " << row.trial;
    EXPECT_LE(row.final_cost, row.initial_cost);
    EXPECT_GT(row.evaluations, 0);
    EXPECT_GE(row.time_ms, 0.0);
    EXPECT_GE(row.cpu_ms, 0.0);
  }
  ASSERT_EQ(per_cell.size(), 16u);
  for (const auto& cell : per_cell) EXPECT_EQ(cell.second, options.trials);
  // Common random numbers: the same trial starts from the same pose in every cell and configuration.
  for (const RefinerStudyRow& row : result.rows)
    for (const RefinerStudyRow& other : result.rows)
      if (row.trial == other.trial) {
        EXPECT_DOUBLE_EQ(row.start_translation, other.start_translation);
      }
  // Without wrong correspondences and noise the plain loss recovers the truth exactly; with 25% wrong
  // ones its own minimum (the reference) is pulled away while Cauchy's stays close.
  double plain_reference = 0.0, cauchy_reference = 0.0;
  for (const RefinerStudyRow& row : result.rows)
    if (row.outlier_fraction == 0.25 && row.noise == 0.0 && row.algorithm == "levenberg_marquardt")
      (row.loss == "none" ? plain_reference : cauchy_reference) += row.reference_rte;
  EXPECT_GT(plain_reference, cauchy_reference);

  // Reproducible: the same options give the same rows (times aside).
  const RefinerStudyResult again = run_refiner_study(options);
  ASSERT_EQ(again.rows.size(), result.rows.size());
  for (std::size_t i = 0; i < result.rows.size(); ++i) {
    EXPECT_EQ(again.rows[i].rte, result.rows[i].rte) << i;
    EXPECT_EQ(again.rows[i].iterations, result.rows[i].iterations) << i;
    EXPECT_EQ(again.rows[i].converged, result.rows[i].converged) << i;
  }

  // Writers: a CSV line per row, a Markdown report with its command line, an SVG.
  const std::filesystem::path folder = std::filesystem::temp_directory_path() / "quadrix_test_refiner_study";
  std::filesystem::remove_all(folder);
  std::filesystem::create_directories(folder);
  write_refiner_study_csv((folder / "refiners.csv").string(), result);
  write_refiner_study_markdown((folder / "refiners.md").string(), result, options, "quadrix compare-refiners --tiny");
  write_refiner_study_svg((folder / "refiners.svg").string(), result);
  const std::string csv = read_text(folder / "refiners.csv");
  EXPECT_EQ(static_cast<std::size_t>(std::count(csv.begin(), csv.end(), '\n')), result.rows.size() + 1);
  EXPECT_EQ(csv.rfind("source,correspondence_set,backend,algorithm,loss,", 0), 0u);
  const std::string markdown = read_text(folder / "refiners.md");
  EXPECT_NE(markdown.find("`quadrix compare-refiners --tiny`"), std::string::npos);
  EXPECT_NE(markdown.find("| ceres/dogleg | cauchy |"), std::string::npos);
  const std::string svg = read_text(folder / "refiners.svg");
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("polyline"), std::string::npos);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  std::filesystem::remove_all(folder);
}

TEST(RefinerStudy, BadOptionsAreErrors) {
  RefinerStudyOptions options = tiny_study();
  options.scenes = {"cathedral"};
  EXPECT_THROW(run_refiner_study(options), Error);
  options = tiny_study();
  options.backends = {"gauss_newton_by_hand"};
  EXPECT_THROW(run_refiner_study(options), Error);
  options = tiny_study();
  options.outlier_fractions = {1.0};
  EXPECT_THROW(run_refiner_study(options), Error);
  options = tiny_study();
  options.trials = 0;
  EXPECT_THROW(run_refiner_study(options), Error);
  options = tiny_study();
  options.maximum_translation = 0.1;  // below the minimum
  EXPECT_THROW(run_refiner_study(options), Error);
}

TEST(RefinerStudy, RealLoopClosureGivesGroundTruthInliersAndThePipelineClique) {
  QUADRIX_REQUIRE_SHARED_DATA("pairs.tsv");
  QUADRIX_REQUIRE_SHARED_DATA("kitti00/velodyne/000000.bin");
  QUADRIX_REQUIRE_SHARED_DATA("kitti00/velodyne/004438.ply");
  RefinerStudyOptions options;
  options.scenes.clear();
  options.backends = {"ceres"};
  options.losses = {RobustLoss::None};
  options.trials = 2;
  options.max_real_pairs = 1;
  options.data_root = testing::shared_data_root().string();
  const RefinerStudyResult result = run_refiner_study(options);
  ASSERT_EQ(result.notes.size(), 1u);
  EXPECT_EQ(result.notes.front().rfind("kitti00_lc_0_4438", 0), 0u) << result.notes.front();
  std::map<std::string, int> per_set;
  for (const RefinerStudyRow& row : result.rows) {
    ++per_set[row.correspondence_set];
    EXPECT_EQ(row.source, "kitti00_lc_0_4438");
    EXPECT_EQ(row.criterion, "reference");
    EXPECT_GE(row.correspondences, 3u);
    if (row.correspondence_set == "gt_inliers") {
      EXPECT_EQ(row.wrong_correspondences, 0u);
    }
    // Real correspondences are inliers within 0.5 m: their minimum lies within the success rule.
    EXPECT_LT(row.reference_rte, 2.0) << row.correspondence_set;
    EXPECT_LT(row.reference_rre_degrees, 5.0) << row.correspondence_set;
  }
  EXPECT_EQ(per_set["gt_inliers"], 2 * 2);  // LM + dogleg, 2 starts
  EXPECT_EQ(per_set["clique"], 2 * 2);
}

}  // namespace
}  // namespace quadrix
