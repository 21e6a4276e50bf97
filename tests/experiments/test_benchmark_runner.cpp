// The benchmark harness: a run split in 3 shards and merged gives exactly the outputs of one run;
// rows round-trip through CSV; pairs without ground truth are never counted; ablations are applied;
// and on real KITTI pairs Quadrix is run through the cache with (and without) random yaw trials.
#include "experiments/benchmark/bench_paper.h"
#include "experiments/benchmark/benchmark_runner.h"
#include "geometry/error.h"
#include "geometry/io.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <set>
#include <string>
#include <vector>

namespace quadrix {
namespace {

namespace fs = std::filesystem;
using quadrix::testing::shared_data_path;

std::string read_text(const fs::path& path) {
  std::ifstream file(path);
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

class BenchFolder : public ::testing::Test {
 protected:
  void SetUp() override {
    folder_ = fs::temp_directory_path() / ("quadrix_bench_test_" + std::to_string(::getpid()) + "_" +
                                           ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(folder_);
    fs::create_directories(folder_);
  }
  void TearDown() override { fs::remove_all(folder_); }
  fs::path folder_;
};

// Pairs over two tiny clouds; every third pair has no ground truth.
std::vector<BenchPair> tiny_pairs(const fs::path& folder, std::size_t count) {
  PointCloud cloud;
  cloud.positions = Eigen::Matrix3Xf::Random(3, 20);
  write_point_cloud((folder / "a.ply").string(), cloud);
  write_point_cloud((folder / "b.ply").string(), cloud);
  std::vector<BenchPair> pairs;
  for (std::size_t k = 0; k < count; ++k) {
    BenchPair pair;
    pair.id = "pair" + std::to_string(k);
    pair.source = (folder / (k % 2 ? "a.ply" : "b.ply")).string();
    pair.target = (folder / "a.ply").string();
    if (k % 3 != 2) pair.ground_truth = Eigen::Isometry3d(Eigen::Translation3d(double(k), 0.0, 0.0));
    pair.difficulty = k < count / 2 ? "easy" : "hard";
    pairs.push_back(pair);
  }
  return pairs;
}

// A deterministic stand-in method: right on even tasks' pairs, 3 m off on odd ones, fixed "times".
BenchMethodOutput fake_method(const BenchMethodInput& input) {
  BenchMethodOutput output;
  const std::size_t k = std::stoul(input.pair->id.substr(4));
  const Eigen::Isometry3d truth = input.pair->ground_truth.value_or(Eigen::Isometry3d::Identity()) * input.perturbation.inverse();
  output.transform = truth;
  if (k % 2) output.transform.translation().x() += 3.0;
  output.status = "solved";
  output.message = "fake, with a comma, and \"quotes\"";
  output.timings_ms = {{"features", 1.5 + double(k)}, {"total", 10.0 + 3.0 * double(k)}};
  return output;
}

// Registers "fake" and "fake-slow" (the same answers, four times the time).
void register_fake_methods() {
  register_bench_method("fake", fake_method);
  register_bench_method("fake-slow", [](const BenchMethodInput& input) {
    BenchMethodOutput output = fake_method(input);
    output.timings_ms["total"] *= 4.0;
    return output;
  });
}

TEST_F(BenchFolder, ThreeShardsMergedGiveExactlyTheOutputsOfOneRun) {
  register_fake_methods();
  const std::vector<BenchPair> pairs = tiny_pairs(folder_, 7);
  BenchOptions options;
  options.methods = {"fake", "fake-slow"};
  options.yaw_range_degrees = 180.0;
  options.translation_range = 3.0;
  options.trials = 2;
  options.seed = 5;
  options.progress = false;
  BenchRunInfo info;
  info.title = "shard test";
  info.methods = options.methods;
  info.task_count = pairs.size() * 2;
  info.options_text = "tiny pairs, yaw 180, trials 2";

  options.jobs = 2;
  const std::vector<BenchRow> whole = run_benchmark(pairs, options);
  ASSERT_EQ(whole.size(), 28u);
  write_bench_outputs((folder_ / "whole").string(), whole, info);

  std::vector<std::string> shard_folders;
  std::size_t shard_rows = 0;
  options.jobs = 1;
  for (int shard = 1; shard <= 3; ++shard) {
    options.shard_index = shard;
    options.shard_count = 3;
    info.shard_index = shard;
    info.shard_count = 3;
    const std::vector<BenchRow> part = run_benchmark(pairs, options);
    shard_rows += part.size();
    for (const BenchRow& row : part) EXPECT_EQ(row.task % 3, static_cast<std::size_t>(shard - 1));
    shard_folders.push_back((folder_ / ("shard" + std::to_string(shard))).string());
    write_bench_outputs(shard_folders.back(), part, info);
  }
  EXPECT_EQ(shard_rows, whole.size());
  merge_bench_outputs(shard_folders, (folder_ / "merged").string());
  for (const char* file : {"pairs.csv", "summary.md", "run.json", "success_by_difficulty.svg", "error_cdf.svg", "time_per_stage.svg"})
    EXPECT_EQ(read_text(folder_ / "whole" / file), read_text(folder_ / "merged" / file)) << file;

  // The summary itself: 2 of 3 pairs have ground truth; even pairs succeed.
  const std::vector<MethodSummary> summaries = summarize_bench(whole, options.methods);
  ASSERT_EQ(summaries.size(), 2u);
  EXPECT_EQ(summaries[0].with_ground_truth, 10u);  // pairs 0,1,3,4,6 x 2 trials
  EXPECT_EQ(summaries[0].without_ground_truth, 4u);
  EXPECT_EQ(summaries[0].successes, 6u);           // pairs 0,4,6 x 2 trials
  EXPECT_NEAR(summaries[1].time_ratio_to_quadrix, 0.0, 0.0);  // no quadrix in this run
  // Perturbations are recorded and reproducible from the seed.
  EXPECT_NE(whole[0].yaw_degrees, whole[2].yaw_degrees);
  EXPECT_EQ(whole[0].seed, 5u * 1000003u);

  // An incomplete merge names what is missing.
  try {
    merge_bench_outputs({shard_folders[0], shard_folders[2]}, (folder_ / "bad").string());
    FAIL() << "a merge without shard 2 was accepted";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("missing"), std::string::npos) << error.what();
  }
}

TEST_F(BenchFolder, RunsOfDifferentMethodsOverTheSameTasksMergeIntoOneRun) {
  register_fake_methods();
  const std::vector<BenchPair> pairs = tiny_pairs(folder_, 5);
  BenchOptions options;
  options.yaw_range_degrees = 90.0;
  options.trials = 2;
  options.seed = 3;
  options.progress = false;
  BenchRunInfo info;
  info.title = "method merge test";
  info.task_count = pairs.size() * 2;
  const auto run = [&](const std::vector<std::string>& methods, const std::string& folder, unsigned seed) {
    options.methods = methods;
    options.seed = seed;
    info.methods = methods;
    std::string list;
    for (const std::string& method : methods) list += (list.empty() ? "" : ",") + method;
    info.options_text = "--pairs tiny.tsv --method " + list + " --preset auto --seed " + std::to_string(seed);
    write_bench_outputs((folder_ / folder).string(), run_benchmark(pairs, options), info);
    return (folder_ / folder).string();
  };
  const std::string whole = run({"fake", "fake-slow"}, "both", 3);
  const std::string fast = run({"fake"}, "fast", 3);
  const std::string slow = run({"fake-slow"}, "slow", 3);
  merge_bench_outputs({fast, slow}, (folder_ / "merged").string());
  for (const char* file : {"pairs.csv", "summary.md", "run.json", "success_by_difficulty.svg", "error_cdf.svg", "time_per_stage.svg"})
    EXPECT_EQ(read_text(fs::path(whole) / file), read_text(folder_ / "merged" / file)) << file;
  // Another seed is another run: refused, naming the folder.
  const std::string other = run({"fake-slow"}, "other-seed", 4);
  try {
    merge_bench_outputs({fast, other}, (folder_ / "bad").string());
    FAIL() << "runs with different seeds were merged";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("other-seed"), std::string::npos) << error.what();
  }
}

TEST_F(BenchFolder, RowsRoundTripThroughCsvExactly) {
  register_bench_method("fake", fake_method);
  BenchOptions options;
  options.methods = {"fake"};
  options.yaw_range_degrees = 45.0;
  options.tilt_range_degrees = 25.0;
  options.trials = 3;
  options.progress = false;
  const std::vector<BenchRow> rows = run_benchmark(tiny_pairs(folder_, 3), options);
  for (const BenchRow& row : rows) {
    EXPECT_GT(row.tilt_degrees, 0.0);
    EXPECT_LE(row.tilt_degrees, 25.0 + 1e-9);
  }
  const std::string path = (folder_ / "rows.csv").string();
  write_bench_rows_csv(path, rows);
  const std::vector<BenchRow> read = read_bench_rows_csv(path);
  ASSERT_EQ(read.size(), rows.size());
  for (std::size_t k = 0; k < rows.size(); ++k) {
    EXPECT_EQ(read[k].pair_id, rows[k].pair_id);
    EXPECT_EQ(read[k].message, rows[k].message);
    EXPECT_EQ(read[k].rte, rows[k].rte);
    EXPECT_EQ(read[k].yaw_degrees, rows[k].yaw_degrees);
    EXPECT_EQ(read[k].tilt_degrees, rows[k].tilt_degrees);
    EXPECT_EQ(read[k].timings_ms, rows[k].timings_ms);
    EXPECT_EQ(read[k].has_ground_truth, rows[k].has_ground_truth);
    EXPECT_EQ(read[k].true_partners, rows[k].true_partners);
    EXPECT_EQ(read[k].clique_inliers, rows[k].clique_inliers);
    EXPECT_EQ(read[k].success, rows[k].success);
  }
  std::ofstream(path, std::ios::app) << "1,x,0\n";
  try {
    read_bench_rows_csv(path);
    FAIL() << "a short row was accepted";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find(path + ":" + std::to_string(rows.size() + 2)), std::string::npos) << error.what();
  }
  // A file written before the overlap and tilt columns existed still reads, with those values unset.
  const std::string old_path = (folder_ / "old.csv").string();
  std::ofstream(old_path) << "task,pair_id,trial,method,difficulty,kind,has_gt,status,success,rte_m,rre_deg,yaw_deg,"
                             "shift_x_m,shift_y_m,seed,correspondences,inliers,recalled,source_model_bytes,"
                             "target_model_bytes,timings_ms,message\n"
                             "0,p,0,quadrix,easy,loop_closure,1,ok,1,0.1,0.2,30,1,2,7,100,9,1,500,600,total=12.5,fine\n";
  const std::vector<BenchRow> old_rows = read_bench_rows_csv(old_path);
  ASSERT_EQ(old_rows.size(), 1u);
  EXPECT_EQ(old_rows[0].yaw_degrees, 30.0);
  EXPECT_EQ(old_rows[0].tilt_degrees, 0.0);
  EXPECT_EQ(old_rows[0].overlap, -1.0);
  EXPECT_EQ(old_rows[0].true_partners, -1);
  EXPECT_EQ(old_rows[0].best_clique_inliers, -1);
  EXPECT_EQ(old_rows[0].target_model_bytes, 600);
  EXPECT_EQ(old_rows[0].timings_ms.at("total"), 12.5);
  EXPECT_EQ(old_rows[0].message, "fine");
  // A header without a column every file has is refused, naming the column.
  std::ofstream(old_path) << "task,pair_id,trial\n0,p,0\n";
  try {
    read_bench_rows_csv(old_path);
    FAIL() << "a header without the method column was accepted";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("no column method"), std::string::npos) << error.what();
  }
}

TEST_F(BenchFolder, PaperPagePutsOurAblationRunBesideThePaperRow) {
  BenchOptions options;
  options.methods = {"quadrix-stand-in"};
  register_bench_method("quadrix-stand-in", fake_method);
  options.progress = false;
  const std::vector<BenchRow> rows = run_benchmark(tiny_pairs(folder_, 3), options);
  std::vector<BenchRow> as_quadrix = rows;
  for (BenchRow& row : as_quadrix) row.method = "quadrix";
  BenchRunInfo info;
  info.title = "ks25 run";
  info.methods = {"quadrix"};
  info.task_count = 3;
  info.options_text = "--ablation ks25";
  write_bench_outputs((folder_ / "results" / "ablation-ks25").string(), as_quadrix, info);
  fs::create_directories(folder_ / "tables");
  std::ofstream(folder_ / "tables" / "ablation.csv")
      << "dataset,module,setting,sequence,level,success_rate_percent\n"
      << "KITTI-LC,correspondence establishment,K_s=25,00,easy,100.00\n"
      << "KITTI-LC,correspondence establishment,K_s=25,02,easy,93.60\n";
  const std::string page =
      quadricsreg_paper_page((folder_ / "results").string(), (folder_ / "tables").string(), folder_.string());
  // Pairs 0 and 1 have ground truth; pair 0 succeeds: 1 of 2.
  EXPECT_NE(page.find("| correspondence establishment | K_s=25 | 100.00 | `--ablation ks25` | 50.0 (1/2) |"), std::string::npos)
      << page;
  EXPECT_EQ(page.find("93.60 | `--ablation"), std::string::npos) << "only sequence 00 is beside ours";
  std::ofstream(folder_ / "tables" / "broken.csv") << "a,b\n1,2,3\n";
  try {
    quadricsreg_paper_page((folder_ / "results").string(), (folder_ / "tables").string(), folder_.string());
    FAIL() << "a malformed table was accepted";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("broken.csv:2"), std::string::npos) << error.what();
  }
}

TEST(BenchAblations, OptionsAndModelsChangeAsTheTableRowSays) {
  RegistrationOptions options;
  apply_ablation("ks25", options);
  EXPECT_EQ(options.correspondences.top_k_similar, 25);
  apply_ablation("dm-0.2-0.8", options);
  EXPECT_EQ(options.graphs.thresholds, (std::vector<double>{0.2, 0.8}));
  apply_ablation("no-refinement", options);
  EXPECT_FALSE(options.estimation.refine);
  EXPECT_THROW(apply_ablation("no-such-row", options), Error);

  SceneModel model;
  const QuadricType types[] = {QuadricType::Plane, QuadricType::Line, QuadricType::Ellipsoid, QuadricType::Plane, QuadricType::Point};
  for (const QuadricType type : types) {
    QuadricRecord record;
    record.label = static_cast<std::uint32_t>(type == QuadricType::Plane ? ElementClass::Plane : ElementClass::Object);
    model.records.push_back(record);
    model.types.push_back(type);
    model.element_point_counts.push_back(10);
  }
  model.augmented_begin = 4;  // the last record is an augmented point
  const SceneModel without_planes = apply_model_ablation("no-planar-center", model);
  EXPECT_EQ(without_planes.records.size(), 3u);
  EXPECT_EQ(without_planes.augmented_begin, 2u);
  EXPECT_EQ(without_planes.types.back(), QuadricType::Point);
  const SceneModel without_central = apply_model_ablation("no-central", model);
  EXPECT_EQ(without_central.records.size(), 4u);  // the ellipsoid goes, the augmented point stays
  const SceneModel unlabelled = apply_model_ablation("no-semantics", model);
  for (const QuadricRecord& record : unlabelled.records) EXPECT_EQ(record.label, static_cast<std::uint32_t>(ElementClass::Object));
}

TEST_F(BenchFolder, QuadrixOnRealKittiPairsWithAndWithoutYawTrials) {
  QUADRIX_REQUIRE_SHARED_DATA("pairs.tsv");
  QUADRIX_REQUIRE_SHARED_DATA("kitti00/velodyne/004438.ply");
  std::vector<BenchPair> pairs;
  for (const BenchPair& pair : read_pairs_tsv(shared_data_path("pairs.tsv")))
    if (pair.id == "kitti00_lc_0_4438" || pair.id == "kitti00_lc_3_4438") pairs.push_back(pair);
  ASSERT_EQ(pairs.size(), 2u);
  BenchOptions options;
  options.progress = false;
  options.jobs = 2;
  const std::vector<BenchRow> plain = run_benchmark(pairs, options);
  ASSERT_EQ(plain.size(), 2u);
  for (const BenchRow& row : plain) {
    EXPECT_TRUE(row.success) << row.pair_id << ": RTE " << row.rte << " RRE " << row.rre << " " << row.message;
    EXPECT_GE(row.inliers, 3) << row.pair_id;
    EXPECT_EQ(row.recalled, 1) << row.pair_id;
    EXPECT_GT(row.source_model_bytes, 0);
    EXPECT_EQ(row.target_model_bytes, plain[0].target_model_bytes);  // the same target, modelled alike per pair
    for (const char* stage : {"preset", "modelling_source", "modelling_target", "correspondences", "cliques", "estimation", "total"})
      EXPECT_TRUE(row.timings_ms.count(stage)) << stage;
    // Both clouds are modelled at the same time, as register_clouds does: the total holds the longer
    // modelling time and every later stage, not the two modellings one after the other. The checks'
    // inputs and the dense search's preparation are made while the quadrics are matched: the longer
    // of those two runs counts.
    const std::set<std::string> matching = {"correspondences", "graphs", "cliques", "estimation", "selection"};
    const std::set<std::string> preparing = {"check_inputs", "dense_preparation"};
    double later_stages = 0.0, matching_ms = 0.0, preparing_ms = 0.0;
    for (const auto& [stage, ms] : row.timings_ms) {
      if (stage == "total" || stage.rfind("modelling_", 0) == 0) continue;
      if (matching.count(stage)) matching_ms += ms;
      else if (preparing.count(stage)) preparing_ms += ms;
      else later_stages += ms;
    }
    later_stages += std::max(matching_ms, preparing_ms);
    EXPECT_GE(row.timings_ms.at("total"),
              std::max(row.timings_ms.at("modelling_source"), row.timings_ms.at("modelling_target")) + later_stages);
  }

  // The no-refinement ablation keeps each candidate's SVD estimate (not the identity).
  BenchOptions unrefined = options;
  unrefined.ablation = "no-refinement";
  const std::vector<BenchRow> svd_only = run_benchmark({pairs[0]}, unrefined);
  ASSERT_EQ(svd_only.size(), 1u);
  EXPECT_TRUE(svd_only[0].success) << "RTE " << svd_only[0].rte << " RRE " << svd_only[0].rre << " " << svd_only[0].message;
  EXPECT_NE(svd_only[0].rte, plain[0].rte);

  // Random yaw about the up axis: the ground truth follows the perturbation.
  options.yaw_range_degrees = 180.0;
  options.translation_range = 5.0;
  options.trials = 2;
  options.seed = 11;
  const std::vector<BenchRow> turned = run_benchmark({pairs[0]}, options);
  ASSERT_EQ(turned.size(), 2u);
  for (const BenchRow& row : turned) {
    EXPECT_GT(std::abs(row.yaw_degrees), 1.0);
    EXPECT_TRUE(row.success) << "yaw " << row.yaw_degrees << ": RTE " << row.rte << " RRE " << row.rre << " " << row.message;
  }

  // Tilted too, up to 25 degrees about a random horizontal axis: auto finds the tilted up axis itself
  // (docs/benchmark.md: 70 of 70 KITTI loop-closure trials under yaw +-180 and tilt <= 25 succeed).
  options.tilt_range_degrees = 25.0;
  options.seed = 5;
  const std::vector<BenchRow> tilted = run_benchmark({pairs[0]}, options);
  ASSERT_EQ(tilted.size(), 2u);
  for (const BenchRow& row : tilted) {
    EXPECT_GT(row.tilt_degrees, 0.0);
    EXPECT_LE(row.tilt_degrees, 25.0 + 1e-9);
    EXPECT_TRUE(row.success) << "yaw " << row.yaw_degrees << ", tilt " << row.tilt_degrees << ": RTE " << row.rte << " RRE "
                             << row.rre << " " << row.message;
  }
}

TEST_F(BenchFolder, LabelsModeNeedsLabelsForEveryCloud) {
  BenchOptions options;
  options.labels = true;
  options.progress = false;
  const std::vector<BenchRow> rows = run_benchmark(tiny_pairs(folder_, 1), options);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].status, "error");
  EXPECT_NE(rows[0].message.find("--labels needs per-point labels"), std::string::npos) << rows[0].message;
  // pairs.tsv names the label files in two optional columns ("-": none).
  const fs::path tsv = folder_ / "pairs.tsv";
  std::ofstream(tsv) << "id\tsource\ttarget\tgt\tsource_labels\ttarget_labels\n"
                     << "p\ta.ply\tb.ply\t-\tlabels/a.label\t-\n";
  const std::vector<BenchPair> pairs = read_pairs_tsv(tsv.string());
  ASSERT_EQ(pairs.size(), 1u);
  EXPECT_EQ(pairs[0].source_labels, (folder_ / "labels" / "a.label").lexically_normal().string());
  EXPECT_EQ(pairs[0].target_labels, "");
}

// The stage table on every pair of pairs.tsv whose two frames have SemanticKITTI labels (a
// labels/ folder beside velodyne/): with the labels each is solved and true correspondences reach the
// chosen clique; every row's counts shrink stage by stage.
TEST_F(BenchFolder, TrueCorrespondencesPerStageOnTheLabelledKittiPairs) {
  QUADRIX_REQUIRE_SHARED_DATA("pairs.tsv");
  const auto labels_of = [](const std::string& cloud) {
    const fs::path path = fs::path(cloud).parent_path().parent_path() / "labels" / (fs::path(cloud).stem().string() + ".label");
    return fs::exists(path) ? path.string() : std::string();
  };
  std::vector<BenchPair> pairs;
  for (BenchPair pair : read_pairs_tsv(shared_data_path("pairs.tsv"))) {
    pair.source_labels = labels_of(pair.source);
    pair.target_labels = labels_of(pair.target);
    if (!pair.source_labels.empty() && !pair.target_labels.empty() && pair.ground_truth) pairs.push_back(pair);
  }
  if (pairs.empty()) GTEST_SKIP() << "no pair of pairs.tsv has SemanticKITTI labels for both frames";
  BenchOptions options;
  options.progress = false;
  std::vector<BenchRow> rows = run_benchmark(pairs, options);
  options.labels = true;
  const std::vector<BenchRow> labelled = run_benchmark(pairs, options);
  ASSERT_EQ(labelled.size(), pairs.size());
  for (const BenchRow& row : labelled) {
    EXPECT_TRUE(row.success) << row.pair_id << ": RTE " << row.rte << " RRE " << row.rre << " " << row.message;
    EXPECT_GE(row.clique_inliers, 3) << row.pair_id;
  }
  rows.insert(rows.end(), labelled.begin(), labelled.end());
  for (const BenchRow& row : rows) {
    EXPECT_GE(row.true_partners, 0);
    EXPECT_GE(row.quadric_inliers, row.best_clique_inliers);
    EXPECT_GE(row.best_clique_inliers, row.clique_inliers);
    EXPECT_GE(row.clique_inliers, 0);
  }
  const std::string summary = bench_summary_markdown(summarize_bench(rows, {"quadrix"}), "stages");
  EXPECT_NE(summary.find("## Where the true correspondences are lost"), std::string::npos);
}

}  // namespace
}  // namespace quadrix
