// The baseline registration methods (experiments/baselines/baselines.h): each one recovers a known rigid
// motion of a real KITTI frame and the real loop closure 0 -> 4438 within the paper's success rule
// (RTE <= 2 m, RRE <= 5 deg), returns the transform that maps source points into the target frame,
// and reports bad names, bad options and empty or too sparse clouds clearly.
#include "estimation/registration.h"
#include "experiments/baselines/baselines.h"
#include "experiments/benchmark/baseline_process.h"
#include "geometry/error.h"
#include "geometry/io.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

namespace quadrix {
namespace {

const char* const kSourceFrame = "kitti00/velodyne/000000.bin";
const char* const kLoopTarget = "kitti00/velodyne/004438.ply";
const char* const kLoopTruth = "kitti00/gt/T_004438_from_000000.txt";

/// Points of `cloud` within `radius` metres of the sensor (keeps the tests fast).
PointCloud crop(const PointCloud& cloud, float radius) {
  PointCloud cropped;
  cropped.positions.resize(3, static_cast<Eigen::Index>(cloud.size()));
  Eigen::Index kept = 0;
  for (Eigen::Index i = 0; i < cloud.positions.cols(); ++i)
    if (cloud.positions.col(i).norm() <= radius) cropped.positions.col(kept++) = cloud.positions.col(i);
  cropped.positions.conservativeResize(3, kept);
  return cropped;
}

/// `cloud` moved by `motion` (every point p becomes motion * p).
PointCloud moved(const PointCloud& cloud, const Eigen::Isometry3d& motion) {
  PointCloud result;
  result.positions = (motion.cast<float>() * cloud.positions.colwise().homogeneous()).eval();
  return result;
}

/// A motion of a loop-closure size that is not its own inverse: 35 deg of yaw, a little roll, 6 m.
Eigen::Isometry3d known_motion() {
  Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
  motion.linear() = (Eigen::AngleAxisd(35.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ()) *
                     Eigen::AngleAxisd(2.0 * M_PI / 180.0, Eigen::Vector3d::UnitX()))
                        .toRotationMatrix();
  motion.translation() = Eigen::Vector3d(5.0, -3.0, 0.4);
  return motion;
}

/// Options that keep one run of the slowest baseline (PCL) to a few seconds: a 0.8 m voxel with the
/// radii scaled as in the defaults (normals 2x, FPFH 5x, inliers 1.5x) and fewer prerejective iterations.
BaselineOptions fast_options() {
  BaselineOptions options;
  options.voxel_size = 0.8;
  options.normal_radius = 2.0 * options.voxel_size;
  options.feature_radius = 5.0 * options.voxel_size;
  options.max_correspondence_distance = 1.5 * options.voxel_size;
  options.prerejective_iterations = 20000;
  return options;
}

class BaselineOnRealPair : public ::testing::TestWithParam<std::string> {};

TEST_P(BaselineOnRealPair, RecoversAKnownMotionOfAKittiFrame) {
  QUADRIX_REQUIRE_SHARED_DATA(kSourceFrame);
  const PointCloud source = crop(read_point_cloud(testing::shared_data_path(kSourceFrame)), 40.0f);
  const Eigen::Isometry3d truth = known_motion();
  const PointCloud target = moved(source, truth);

  // The target holds the source's own points, so nearly every PCL hypothesis survives the polygon
  // pre-rejection and is scored on the whole cloud: 2000 iterations cost as much as 20000 on real pairs.
  BaselineOptions options = fast_options();
  options.prerejective_iterations = 2000;
  const BaselineResult result = run_baseline(GetParam(), source, target, options);
  ASSERT_TRUE(result.solved) << result.message;
  EXPECT_LE(translation_error(result.transform, truth), 2.0) << result.message;
  EXPECT_LE(rotation_error_degrees(result.transform, truth), 5.0) << result.message;
  // The inverse motion is far from the truth, so passing above also pins the convention down.
  EXPECT_GT(translation_error(result.transform.inverse(), truth), 2.0);
  for (const char* stage : {"downsample", "normals", "features", "registration", "total"})
    EXPECT_EQ(result.timings_ms.count(stage), 1u) << stage;
  EXPECT_GE(result.timings_ms.at("total"), result.timings_ms.at("registration"));
  EXPECT_GE(result.counts.at("inliers"), 3.0);
}

TEST_P(BaselineOnRealPair, SolvesTheLoopClosureZeroTo4438) {
  QUADRIX_REQUIRE_SHARED_DATA(kSourceFrame);
  QUADRIX_REQUIRE_SHARED_DATA(kLoopTarget);
  QUADRIX_REQUIRE_SHARED_DATA(kLoopTruth);
  const PointCloud source = crop(read_point_cloud(testing::shared_data_path(kSourceFrame)), 40.0f);
  const PointCloud target = crop(read_point_cloud(testing::shared_data_path(kLoopTarget)), 40.0f);
  const Eigen::Isometry3d truth = read_pose_matrix(testing::shared_data_path(kLoopTruth));

  const BaselineResult result = run_baseline(GetParam(), source, target, fast_options());
  ASSERT_TRUE(result.solved) << result.message;
  EXPECT_LE(translation_error(result.transform, truth), 2.0) << result.message;
  EXPECT_LE(rotation_error_degrees(result.transform, truth), 5.0) << result.message;
}

TEST_P(BaselineOnRealPair, EmptyCloudIsUnsolvedWithAMessage) {
  PointCloud points;
  points.positions = Eigen::Matrix3Xf::Random(3, 50) * 10.0f;
  for (bool empty_source : {true, false}) {
    const PointCloud empty;
    const BaselineResult result =
        empty_source ? run_baseline(GetParam(), empty, points) : run_baseline(GetParam(), points, empty);
    EXPECT_FALSE(result.solved);
    EXPECT_NE(result.message.find(empty_source ? "source" : "target"), std::string::npos) << result.message;
    EXPECT_TRUE(result.transform.isApprox(Eigen::Isometry3d::Identity()));
  }
}

TEST_P(BaselineOnRealPair, TooSparseCloudIsUnsolvedWithAMessage) {
  PointCloud two_points;
  two_points.positions = Eigen::Matrix3Xf::Zero(3, 2);
  two_points.positions(0, 1) = 0.1f;  // both in one 0.5 m voxel
  PointCloud points;
  points.positions = Eigen::Matrix3Xf::Random(3, 50) * 10.0f;
  const BaselineResult result = run_baseline(GetParam(), two_points, points);
  EXPECT_FALSE(result.solved);
  EXPECT_NE(result.message.find("too few points"), std::string::npos) << result.message;
}

INSTANTIATE_TEST_SUITE_P(EveryBaseline, BaselineOnRealPair, ::testing::ValuesIn(baseline_method_names()),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           std::string name = info.param;
                           for (char& c : name)
                             if (c == '-') c = '_';
                           return name;
                         });

TEST(Baselines, NamesAreTheThreeOfTheBenchmark) {
  EXPECT_EQ(baseline_method_names(), (std::vector<std::string>{"open3d-ransac", "open3d-fgr", "pcl-prerejective"}));
}

TEST(Baselines, UnknownMethodThrowsListingTheKnownOnes) {
  PointCloud points;
  points.positions = Eigen::Matrix3Xf::Random(3, 10);
  try {
    run_baseline("teaser", points, points);
    FAIL() << "an unknown method must throw";
  } catch (const std::invalid_argument& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("teaser"), std::string::npos) << message;
    EXPECT_NE(message.find("open3d-ransac"), std::string::npos) << message;
  }
}

TEST(Baselines, InvalidOptionThrowsNamingTheField) {
  PointCloud points;
  points.positions = Eigen::Matrix3Xf::Random(3, 10);
  BaselineOptions options;
  options.voxel_size = 0.0;
  try {
    run_baseline("open3d-ransac", points, points, options);
    FAIL() << "a zero voxel size must throw";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("voxel_size"), std::string::npos) << error.what();
  }
  options = BaselineOptions{};
  options.threads = 0;
  EXPECT_THROW(run_baseline("pcl-prerejective", points, points, options), std::invalid_argument);
}

TEST(BaselineProtocol, OptionsAndResultsSurviveTheirJsonForm) {
  BaselineOptions options;
  options.voxel_size = 0.7;
  options.mutual_filter = false;
  options.ransac_iterations = 1234;
  options.seed = 7;
  const BaselineOptions read = baseline_options_from_json(baseline_options_to_json(options));
  EXPECT_EQ(baseline_options_to_json(read), baseline_options_to_json(options));
  EXPECT_DOUBLE_EQ(read.voxel_size, 0.7);
  EXPECT_FALSE(read.mutual_filter);
  EXPECT_EQ(read.ransac_iterations, 1234);
  EXPECT_EQ(read.seed, 7u);

  BaselineResult result;
  result.transform = known_motion();
  result.solved = true;
  result.message = "12 inliers";
  result.timings_ms = {{"features", 1.25}, {"total", 3.5}};
  result.cpu_ms = 2.0;
  result.counts = {{"inliers", 12.0}};
  const BaselineResult back = baseline_result_from_json(baseline_result_to_json(result));
  EXPECT_TRUE(back.transform.isApprox(result.transform, 1e-15));
  EXPECT_TRUE(back.solved);
  EXPECT_EQ(back.message, result.message);
  EXPECT_EQ(back.timings_ms, result.timings_ms);
  EXPECT_EQ(back.counts, result.counts);
}

TEST(BaselineProtocol, UnknownOrMistypedFieldsAreErrorsNamingThem) {
  try {
    baseline_options_from_json("{\"voxel\": 0.5}");
    FAIL() << "an unknown field must throw";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("'voxel'"), std::string::npos) << error.what();
  }
  try {
    baseline_options_from_json("{\"threads\": \"two\"}");
    FAIL() << "a mistyped field must throw";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("'threads'"), std::string::npos) << error.what();
  }
  EXPECT_THROW(baseline_result_from_json("{\"solved\": true}"), Error);
  EXPECT_THROW(baseline_result_from_json("not json"), Error);
}

// The benchmark runs each baseline in a quadrix-baselines child process: the same answer as in process.
TEST(BaselineProcess, GivesTheInProcessAnswerAndReportsChildErrors) {
  QUADRIX_REQUIRE_SHARED_DATA(kSourceFrame);
  const PointCloud source = crop(read_point_cloud(testing::shared_data_path(kSourceFrame)), 30.0f);
  const Eigen::Isometry3d truth = known_motion();
  const PointCloud target = moved(source, truth);
  const BaselineOptions options = fast_options();
  const BaselineResult child = run_baseline_process("open3d-fgr", source, target, options);
  ASSERT_TRUE(child.solved) << child.message;
  EXPECT_LE(translation_error(child.transform, truth), 2.0) << child.message;
  EXPECT_LE(rotation_error_degrees(child.transform, truth), 5.0) << child.message;
  EXPECT_GT(child.timings_ms.at("total"), 0.0);
  try {
    run_baseline_process("teaser", source, target, options);
    FAIL() << "an unknown method must throw";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("teaser"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace quadrix
