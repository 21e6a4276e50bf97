// Pair sources of `quadrix bench`: the paper's loop-closure rule on a tiny KITTI-layout folder made of
// symlinks into ../shared/data, the odometry rule, uniform spatial sampling on the full sequence-00
// poses, the published lc_sample lists, and pairs.tsv parsing errors that name the file and line.
#include "experiments/benchmark/bench_pairs.h"
#include "estimation/registration.h"
#include "geometry/error.h"
#include "geometry/io.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace quadrix {
namespace {

namespace fs = std::filesystem;
using quadrix::testing::shared_data_path;

const char* kFrames[] = {"000000.bin", "000001.bin", "000002.bin", "000003.bin", "000004.bin", "000005.bin", "004438.ply"};

// A KITTI layout ROOT/sequences/00/velodyne + ROOT/poses/00.txt made of symlinks (no data is copied).
class TinyKitti : public ::testing::Test {
 protected:
  void SetUp() override {
    QUADRIX_REQUIRE_SHARED_DATA("kitti00/velodyne/004438.ply");
    QUADRIX_REQUIRE_SHARED_DATA("kitti_poses/00.txt");
    root_ = fs::temp_directory_path() / ("quadrix_tiny_kitti_" + std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_ / "sequences" / "00" / "velodyne");
    fs::create_directories(root_ / "poses");
    for (const char* frame : kFrames)
      fs::create_symlink(shared_data_path(std::string("kitti00/velodyne/") + frame), root_ / "sequences" / "00" / "velodyne" / frame);
    fs::create_symlink(shared_data_path("kitti_poses/00.txt"), root_ / "poses" / "00.txt");
    calibration_ = shared_data_path("kitti_poses/calib_Tr_velo_to_cam.txt");
  }
  void TearDown() override {
    if (!root_.empty()) fs::remove_all(root_);
  }
  fs::path root_;
  std::string calibration_;
};

// The rule written out independently: LiDAR positions P(i) Tr, every i < j among the frames present.
std::set<std::pair<int, int>> loop_pairs_by_rule(const std::vector<int>& frames, double minimum, double maximum, int gap) {
  const std::vector<Eigen::Isometry3d> poses = read_kitti_poses(shared_data_path("kitti_poses/00.txt"));
  const Eigen::Isometry3d tr = read_kitti_calibration(shared_data_path("kitti_poses/calib_Tr_velo_to_cam.txt"), 0);
  std::set<std::pair<int, int>> expected;
  for (const int i : frames)
    for (const int j : frames) {
      if (j <= i || j - i < gap) continue;
      const double d = ((poses[i] * tr).translation() - (poses[j] * tr).translation()).norm();
      if (d >= minimum && d <= maximum) expected.insert({i, j});
    }
  return expected;
}

// LiDAR poses P(i) Tr of every frame of sequence 00.
std::vector<Eigen::Isometry3d> sequence00_lidar_poses() {
  const Eigen::Isometry3d tr = read_kitti_calibration(shared_data_path("kitti_poses/calib_Tr_velo_to_cam.txt"), 0);
  std::vector<Eigen::Isometry3d> lidar;
  for (const Eigen::Isometry3d& pose : read_kitti_poses(shared_data_path("kitti_poses/00.txt"))) lidar.push_back(pose * tr);
  return lidar;
}

int frame_of(const std::string& path) { return std::stoi(fs::path(path).stem().string()); }

TEST_F(TinyKitti, LoopClosureRuleGivesExactlyThePairsOfThePaperEquation) {
  const KittiSequence sequence = load_kitti_sequence(root_.string(), "00", calibration_);
  EXPECT_EQ(sequence.frames, (std::vector<int>{0, 1, 2, 3, 4, 5, 4438}));
  const std::vector<DistanceBin> bins = parse_distance_bins("0-10,10-20,20-30");
  const std::vector<BenchPair> pairs = generate_loop_closure_pairs(sequence, bins);
  for (const DistanceBin& bin : bins) {
    std::set<std::pair<int, int>> generated;
    for (const BenchPair& pair : pairs)
      if (pair.difficulty == bin.name()) generated.insert({frame_of(pair.source), frame_of(pair.target)});
    EXPECT_EQ(generated, loop_pairs_by_rule(sequence.frames, bin.minimum, bin.maximum, 100)) << "bin " << bin.name();
  }
  // The data README: frames 0..5 -> 4438 are the real loop closures of 5.3-8.6 m; nothing else is.
  ASSERT_EQ(pairs.size(), 6u);
  for (const BenchPair& pair : pairs) {
    EXPECT_EQ(pair.difficulty, "0-10");
    EXPECT_EQ(frame_of(pair.target), 4438);
    EXPECT_GT(pair.distance, 5.0);
    EXPECT_LT(pair.distance, 9.0);
  }
  // The relative transform from the poses agrees with the ICP-checked ground-truth file.
  const Eigen::Isometry3d truth = read_pose_matrix(shared_data_path("kitti00/gt/T_004438_from_000000.txt"));
  ASSERT_TRUE(pairs.front().ground_truth.has_value());
  EXPECT_LT(translation_error(*pairs.front().ground_truth, truth), 0.1);
  EXPECT_LT(rotation_error_degrees(*pairs.front().ground_truth, truth), 0.5);
  // t_lc matters: with a gap larger than the sequence nothing is a loop.
  LoopClosureOptions strict;
  strict.minimum_frame_gap = 5000;
  EXPECT_TRUE(generate_loop_closure_pairs(sequence, bins, strict).empty());
}

TEST_F(TinyKitti, OdometryRuleTakesTheFrameWhoseDistanceIsClosestToTheOdometryDistance) {
  const KittiSequence sequence = load_kitti_sequence(root_.string(), "00", calibration_);
  const std::vector<double> distances = parse_odometry_distances("1..3");
  ASSERT_EQ(distances, (std::vector<double>{1.0, 2.0, 3.0}));
  const std::vector<BenchPair> pairs = generate_odometry_pairs(sequence, distances);
  ASSERT_FALSE(pairs.empty());
  for (const BenchPair& pair : pairs) {
    const int i = frame_of(pair.source);
    const int j = frame_of(pair.target);
    const double d_odo = std::stod(pair.difficulty);
    EXPECT_LE(std::abs(pair.distance - d_odo), 0.5) << pair.id;
    for (const int k : sequence.frames) {  // j is the argmin over later frames
      if (k <= i) continue;
      const double dk = (sequence.lidar_poses[k].translation() - sequence.lidar_poses[i].translation()).norm();
      EXPECT_GE(std::abs(dk - d_odo) + 1e-12, std::abs(pair.distance - d_odo)) << pair.id << " vs frame " << k;
    }
    EXPECT_LT(j, 4438);
  }
}

TEST(KittiPairs, UniformSpatialSamplingKeepsTheCapFromRulePairsSpreadOverSpace) {
  QUADRIX_REQUIRE_SHARED_DATA("kitti_poses/00.txt");
  const std::vector<Eigen::Isometry3d> lidar = sequence00_lidar_poses();
  const KittiSequence sequence = kitti_sequence_from_poses("00", lidar);
  const DistanceBin bin{10.0, 20.0};
  LoopClosureOptions all;
  all.pairs_per_bin = 100000000;
  const std::vector<BenchPair> every = generate_loop_closure_pairs(sequence, {bin}, all);
  ASSERT_GT(every.size(), 1000u);
  LoopClosureOptions sampled;
  sampled.pairs_per_bin = 200;
  const std::vector<BenchPair> kept = generate_loop_closure_pairs(sequence, {bin}, sampled);
  ASSERT_EQ(kept.size(), 200u);
  std::set<std::string> every_ids;
  for (const BenchPair& pair : every) every_ids.insert(pair.id);
  std::set<std::pair<long, long>> cells;
  std::set<std::pair<long, long>> all_cells;
  for (const BenchPair& pair : every) {
    const std::size_t i = std::stoul(pair.id.substr(pair.id.find("_lc_") + 4));
    all_cells.insert({std::lround(std::floor(lidar[i].translation().x() / 10.0)), std::lround(std::floor(lidar[i].translation().y() / 10.0))});
  }
  for (const BenchPair& pair : kept) {
    EXPECT_TRUE(every_ids.count(pair.id)) << pair.id << " does not satisfy the rule";
    const std::size_t i = std::stoul(pair.id.substr(pair.id.find("_lc_") + 4));
    cells.insert({std::lround(std::floor(lidar[i].translation().x() / 10.0)), std::lround(std::floor(lidar[i].translation().y() / 10.0))});
  }
  // Round-robin over cells: as many cells as possible are represented.
  EXPECT_EQ(cells.size(), std::min<std::size_t>(200, all_cells.size()));
  EXPECT_EQ(generate_loop_closure_pairs(sequence, {bin}, sampled).front().id, kept.front().id);  // deterministic
}

TEST(KittiPairs, PublishedListsAreReadExactlyAndSatisfyTheLoopRule) {
  QUADRIX_REQUIRE_SHARED_DATA("kitti_poses/lc_sample/KITTI/test_0_10.txt");
  const std::vector<Eigen::Isometry3d> lidar = sequence00_lidar_poses();
  const KittiSequence sequence = kitti_sequence_from_poses("00", lidar);
  LoopClosureOptions all;
  all.pairs_per_bin = 100000000;
  const std::vector<std::pair<std::string, DistanceBin>> lists{
      {"test_0_10", {0.0, 10.0}}, {"test_10_20", {10.0, 20.0}}, {"test_20_30", {20.0, 30.0}}};
  for (const auto& [name, bin] : lists) {
    const std::string path = shared_data_path("kitti_poses/lc_sample/KITTI/" + name + ".txt");
    const std::string difficulty = bin.name();
    // Expected lines, read independently: every non-header line's four indices.
    std::ifstream file(path);
    std::string line;
    std::getline(file, line);
    std::vector<std::array<int, 4>> expected;
    while (std::getline(file, line)) {
      std::array<int, 4> index{};
      if (std::sscanf(line.c_str(), "%d %d %d %d", &index[0], &index[1], &index[2], &index[3]) == 4) expected.push_back(index);
    }
    const std::vector<ListedPair> listed = read_pair_list(path);
    ASSERT_EQ(listed.size(), expected.size()) << path;
    const std::vector<BenchPair> pairs = listed_pairs_to_bench(listed, path);
    std::set<std::string> rule_ids;
    for (const BenchPair& pair : generate_loop_closure_pairs(sequence, {bin}, all)) rule_ids.insert(pair.id);
    for (std::size_t k = 0; k < listed.size(); ++k) {
      EXPECT_EQ(listed[k].sequence, expected[k][0]);
      EXPECT_EQ(listed[k].frame, expected[k][1]);
      EXPECT_EQ(listed[k].database_sequence, expected[k][2]);
      EXPECT_EQ(listed[k].database_frame, expected[k][3]);
      EXPECT_EQ(pairs[k].difficulty, difficulty);
      // The listed relative transform is the one of the poses (within the list's 6 decimals and ICP).
      const Eigen::Isometry3d from_poses = lidar[listed[k].database_frame].inverse() * lidar[listed[k].frame];
      EXPECT_LT(translation_error(listed[k].transform, from_poses), 0.3) << path << " line " << k + 2;
      EXPECT_LT(rotation_error_degrees(listed[k].transform, from_poses), 1.0) << path << " line " << k + 2;
      const std::string rule_id = "kitti00_lc_" + std::to_string(listed[k].frame) + "_" + std::to_string(listed[k].database_frame);
      EXPECT_TRUE(rule_ids.count(rule_id)) << path << ": listed pair " << rule_id << " is not in the rule's bin " << bin.name();
    }
  }
  // The list's 0 -> 4438 equals the ground-truth file of pairs.tsv.
  const std::vector<ListedPair> easy = read_pair_list(shared_data_path("kitti_poses/lc_sample/KITTI/test_0_10.txt"));
  const Eigen::Isometry3d truth = read_pose_matrix(shared_data_path("kitti00/gt/T_004438_from_000000.txt"));
  EXPECT_LT(translation_error(easy.front().transform, truth), 0.1);
}

TEST_F(TinyKitti, ListedPairsFindTheirCloudsOrNameTheMissingFrame) {
  const std::string path = (root_ / "list.txt").string();
  {
    std::ofstream list(path);
    list << "seq i seq_db j mot1 mot2 mot3 mot4 mot5 mot6 mot7 mot8 mot9 mot10 mot11 mot12 mot13 mot14 mot15 mot16\n"
         << "0 0 0 4438 1 0 0 5 0 1 0 1 0 0 1 0 0 0 0 1\n";
  }
  const std::vector<BenchPair> pairs = listed_pairs_to_bench(read_pair_list(path), path, root_.string());
  ASSERT_EQ(pairs.size(), 1u);
  EXPECT_EQ(fs::path(pairs[0].target).filename(), "004438.ply");
  {
    std::ofstream list(path, std::ios::app);
    list << "0 6 0 4438 1 0 0 5 0 1 0 1 0 0 1 0 0 0 0 1\n";
  }
  try {
    listed_pairs_to_bench(read_pair_list(path), path, root_.string());
    FAIL() << "missing frame 6 accepted";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("000006"), std::string::npos) << error.what();
  }
  {
    std::ofstream list(path, std::ios::app);
    list << "0 7 0 4438 1 0 0 5\n";
  }
  try {
    read_pair_list(path);
    FAIL() << "short line accepted";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find(path + ":4"), std::string::npos) << error.what();
  }
}

class PairsTsv : public ::testing::Test {
 protected:
  void SetUp() override {
    folder_ = fs::temp_directory_path() / ("quadrix_pairs_tsv_" + std::to_string(::getpid()));
    fs::create_directories(folder_);
    std::ofstream(folder_ / "T.txt") << "1 0 0 1\n0 1 0 0\n0 0 1 0\n0 0 0 1\n";
  }
  void TearDown() override { fs::remove_all(folder_); }
  // Writes `text` as pairs.tsv and returns the error message of reading it ("" when it reads).
  std::string error_of(const std::string& text) {
    const std::string path = (folder_ / "pairs.tsv").string();
    std::ofstream(path) << text;
    try {
      read_pairs_tsv(path);
    } catch (const Error& error) {
      return error.what();
    }
    return "";
  }
  std::string path() const { return (folder_ / "pairs.tsv").string(); }
  fs::path folder_;
};

TEST_F(PairsTsv, ErrorsNameTheFileAndLine) {
  const std::string header = "id\tsource\ttarget\tgt\tgt_quality\tsensor\tkind\tt_m\trot_deg\n";
  EXPECT_EQ(error_of(header + "a\ts.bin\tt.bin\tT.txt\texact\tx\tlocal\t1.0\t2\n"), "");
  const std::string missing_column = error_of("id\tsource\ttarget\n");
  EXPECT_NE(missing_column.find(path() + ":1"), std::string::npos) << missing_column;
  EXPECT_NE(missing_column.find("'gt'"), std::string::npos) << missing_column;
  const std::string short_line = error_of(header + "a\ts.bin\tt.bin\tT.txt\texact\n");
  EXPECT_NE(short_line.find(path() + ":2"), std::string::npos) << short_line;
  const std::string duplicate = error_of(header + "a\ts\tt\tT.txt\texact\tx\tlocal\t-\t-\n\na\ts\tt\t-\tnone\tx\tlocal\t-\t-\n");
  EXPECT_NE(duplicate.find(path() + ":4"), std::string::npos) << duplicate;
  EXPECT_NE(duplicate.find("duplicate"), std::string::npos) << duplicate;
  const std::string bad_gt = error_of(header + "a\ts\tt\tmissing.txt\texact\tx\tlocal\t-\t-\n");
  EXPECT_NE(bad_gt.find(path() + ":2"), std::string::npos) << bad_gt;
  EXPECT_NE(bad_gt.find("missing.txt"), std::string::npos) << bad_gt;
  const std::string bad_distance = error_of(header + "a\ts\tt\t-\tnone\tx\tlocal\tfar\t-\n");
  EXPECT_NE(bad_distance.find(path() + ":2"), std::string::npos) << bad_distance;
}

TEST(PairsTsvShared, ReadsEverySharedPairRelativeToTheFile) {
  QUADRIX_REQUIRE_SHARED_DATA("pairs.tsv");
  const std::vector<BenchPair> pairs = read_pairs_tsv(shared_data_path("pairs.tsv"));
  // The expected counts follow the file itself (the shared list grows): its non-empty lines after
  // the header, and those whose fourth column names a ground-truth file rather than "-".
  std::size_t expected_rows = 0, expected_with_truth = 0;
  {
    std::ifstream file(shared_data_path("pairs.tsv"));
    std::string line;
    std::getline(file, line);  // header
    while (std::getline(file, line)) {
      if (line.empty()) continue;
      ++expected_rows;
      std::istringstream fields(line);
      std::string column;
      for (int i = 0; i < 4; ++i) std::getline(fields, column, '\t');
      if (column != "-") ++expected_with_truth;
    }
  }
  ASSERT_GT(expected_rows, 0u);
  ASSERT_EQ(pairs.size(), expected_rows);
  std::size_t with_truth = 0;
  for (const BenchPair& pair : pairs) {
    EXPECT_TRUE(fs::exists(pair.source)) << pair.source;
    EXPECT_TRUE(fs::exists(pair.target)) << pair.target;
    with_truth += pair.ground_truth ? 1 : 0;
    EXPECT_EQ(pair.ground_truth.has_value(), pair.ground_truth_quality != "none") << pair.id;
  }
  EXPECT_EQ(with_truth, expected_with_truth);
  EXPECT_EQ(pairs.front().kind, "loop_closure");
  EXPECT_NEAR(pairs.front().distance, 5.28, 1e-12);
}

}  // namespace
}  // namespace quadrix
