// Every point cloud and pose file under ../shared/data parses with the count its source documents
// (file headers / sizes); skips cleanly when the data is absent.
#include "geometry/io.h"
#include "tests/test_data.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

namespace quadrix {
namespace {

using testing::shared_data_path;

struct SharedCloud {
  const char* path;
  std::size_t points_in_file;
  std::size_t finite;
  CloudFormat format;
  const char* encoding;
  std::vector<std::string> fields;
};

// Counts: KITTI/nuScenes = file size / record size; PLY "element vertex"; PCD "POINTS"; XYZ/npy line count / shape.
// Finite counts were checked independently with a Python struct decoder (all finite except the stereo table scene).
const std::vector<std::string> kXyz = {"x", "y", "z"};
const std::vector<std::string> kXyzi = {"x", "y", "z", "intensity"};
const SharedCloud kSharedClouds[] = {
    {"kitti00/velodyne/000000.bin", 124668, 124668, CloudFormat::KittiBin, "binary float32", kXyzi},
    {"kitti00/velodyne/000001.bin", 124605, 124605, CloudFormat::KittiBin, "binary float32", kXyzi},
    {"kitti00/velodyne/000002.bin", 124478, 124478, CloudFormat::KittiBin, "binary float32", kXyzi},
    {"kitti00/velodyne/000003.bin", 124167, 124167, CloudFormat::KittiBin, "binary float32", kXyzi},
    {"kitti00/velodyne/000004.bin", 123969, 123969, CloudFormat::KittiBin, "binary float32", kXyzi},
    {"kitti00/velodyne/000005.bin", 123924, 123924, CloudFormat::KittiBin, "binary float32", kXyzi},
    {"kitti00/velodyne/004438.ply", 125336, 125336, CloudFormat::Ply, "ascii", kXyz},
    {"hdl32_pair/source.ply", 69792, 69792, CloudFormat::Ply, "binary_little_endian", {"x", "y", "z", "scalar_intensity"}},
    {"hdl32_pair/target.ply", 69088, 69088, CloudFormat::Ply, "binary_little_endian", {"x", "y", "z", "scalar_intensity"}},
    {"3dtk/scan000_RH_m.xyz", 81360, 81360, CloudFormat::Xyz, "ascii", kXyz},
    {"3dtk/scan001_RH_m.xyz", 81360, 81360, CloudFormat::Xyz, "ascii", kXyz},
    {"3dtk/scan002_RH_m.xyz", 81360, 81360, CloudFormat::Xyz, "ascii", kXyz},
    {"3dmatch_demo/src.npy", 15953, 15953, CloudFormat::Npy, "<f8", kXyz},
    {"3dmatch_demo/ref.npy", 18977, 18977, CloudFormat::Npy, "<f8", kXyz},
    {"quadricsreg_demo/vlp16_source.ply", 21354, 21354, CloudFormat::Ply, "binary_little_endian", kXyz},
    {"quadricsreg_demo/vlp16_target.ply", 20972, 20972, CloudFormat::Ply, "binary_little_endian", kXyz},
    {"quadricsreg_demo/mid360_source.ply", 9652, 9652, CloudFormat::Ply, "binary_little_endian", kXyz},
    {"quadricsreg_demo/mid360_target.ply", 6957, 6957, CloudFormat::Ply, "binary_little_endian", kXyz},
    {"quadricsreg_demo/avia_source.ply", 19839, 19839, CloudFormat::Ply, "binary_little_endian", kXyz},
    {"quadricsreg_demo/avia_target.ply", 22558, 22558, CloudFormat::Ply, "binary_little_endian", kXyz},
    {"quadricsreg_demo/cross_avia_vlp_source_1.pcd", 13494, 13494, CloudFormat::Pcd, "binary", kXyz},
    {"quadricsreg_demo/cross_avia_vlp_target_1.pcd", 20726, 20726, CloudFormat::Pcd, "binary", kXyz},
    {"quadricsreg_demo/cross_avia_vlp_source_2.pcd", 19450, 19450, CloudFormat::Pcd, "binary", kXyz},
    {"quadricsreg_demo/cross_avia_vlp_target_2.pcd", 24420, 24420, CloudFormat::Pcd, "binary", kXyz},
    {"quadricsreg_demo/cross_mid360_vlp_source_1.pcd", 6868, 6868, CloudFormat::Pcd, "binary", kXyz},
    {"quadricsreg_demo/cross_mid360_vlp_target_1.pcd", 21912, 21912, CloudFormat::Pcd, "binary", kXyz},
    {"single_scans/lamppost.pcd", 1771, 1771, CloudFormat::Pcd, "ascii", kXyz},
    {"single_scans/table_scene_mug_stereo_textured.pcd", 307200, 209280, CloudFormat::Pcd, "binary_compressed",
     {"x", "y", "z", "rgba"}},
    {"single_scans/n015-2018-07-24-11-22-45+0800__LIDAR_TOP__1532402927647951.pcd.bin", 34688, 34688,
     CloudFormat::NuScenesBin, "binary float32", {"x", "y", "z", "intensity", "ring"}},
    {"single_scans/nuscenes_n008-2018-08-01-15-16-36-0400__LIDAR_TOP__1533151603597909.pcd.bin", 34752, 34752,
     CloudFormat::NuScenesBin, "binary float32", {"x", "y", "z", "intensity", "ring"}},
};

class SharedCloudTest : public ::testing::TestWithParam<SharedCloud> {};

TEST_P(SharedCloudTest, ParsesWithDocumentedCount) {
  const SharedCloud& expected = GetParam();
  QUADRIX_REQUIRE_SHARED_DATA(expected.path);
  CloudReadReport report;
  const PointCloud cloud = read_point_cloud(shared_data_path(expected.path), {}, &report);
  EXPECT_EQ(report.format, expected.format);
  EXPECT_EQ(report.encoding, expected.encoding);
  EXPECT_EQ(report.points_in_file, expected.points_in_file);
  EXPECT_EQ(cloud.size(), expected.finite);
  EXPECT_EQ(report.non_finite_dropped, expected.points_in_file - expected.finite);
  EXPECT_EQ(report.fields, expected.fields);
  EXPECT_TRUE(cloud.positions.allFinite());
  // Real scans span metres to tens of metres: catches byte-order or stride mistakes that still parse.
  const Eigen::Vector3f extent = cloud.positions.rowwise().maxCoeff() - cloud.positions.rowwise().minCoeff();
  EXPECT_GT(extent.maxCoeff(), 0.5f);
  EXPECT_LT(extent.maxCoeff(), 1000.0f);
}

INSTANTIATE_TEST_SUITE_P(SharedData, SharedCloudTest, ::testing::ValuesIn(kSharedClouds), [](const auto& info) {
  std::string name = info.param.path;
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return name;
});

TEST(SharedData, KittiFirstPointAndIntensity) {
  QUADRIX_REQUIRE_SHARED_DATA("kitti00/velodyne/000000.bin");
  const PointCloud cloud = read_point_cloud(shared_data_path("kitti00/velodyne/000000.bin"));
  ASSERT_EQ(cloud.intensity.size(), cloud.size());
  for (float value : cloud.intensity) ASSERT_TRUE(value >= 0.0f && value <= 1.0f) << value;
}

TEST(SharedData, TableSceneColoursAndPlane) {
  QUADRIX_REQUIRE_SHARED_DATA("single_scans/table_scene_mug_stereo_textured.pcd");
  const PointCloud cloud =
      read_point_cloud(shared_data_path("single_scans/table_scene_mug_stereo_textured.pcd"));
  ASSERT_EQ(cloud.colors.size(), cloud.size());
  // A textured stereo scene: colours vary (not all one value, as a wrong unpacking would give).
  std::size_t differing = 0;
  for (const auto& color : cloud.colors) differing += color != cloud.colors.front();
  EXPECT_GT(differing, cloud.size() / 2);
}

TEST(SharedData, HdlIntensityField) {
  QUADRIX_REQUIRE_SHARED_DATA("hdl32_pair/source.ply");
  const PointCloud cloud = read_point_cloud(shared_data_path("hdl32_pair/source.ply"));
  EXPECT_EQ(cloud.intensity.size(), cloud.size());
  EXPECT_TRUE(cloud.extra_fields.empty());
}

// Pose files: every "maps source into target" matrix parses as a proper rigid transform.
class SharedPoseTest : public ::testing::TestWithParam<const char*> {};

TEST_P(SharedPoseTest, ParsesAsRigidTransform) {
  QUADRIX_REQUIRE_SHARED_DATA(GetParam());
  const Eigen::Isometry3d pose = read_pose_matrix(shared_data_path(GetParam()));
  const Eigen::Matrix3d rotation = pose.linear();
  EXPECT_LT((rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), 1e-5);
  EXPECT_NEAR(rotation.determinant(), 1.0, 1e-5);
  EXPECT_LT(pose.translation().norm(), 50.0);
}

INSTANTIATE_TEST_SUITE_P(
    SharedData, SharedPoseTest,
    ::testing::Values("kitti00/gt/T_000001_from_000000.txt", "kitti00/gt/T_000002_from_000000.txt",
                      "kitti00/gt/T_000003_from_000000.txt", "kitti00/gt/T_000004_from_000000.txt",
                      "kitti00/gt/T_000005_from_000000.txt", "kitti00/gt/T_000002_from_000001.txt",
                      "kitti00/gt/T_000003_from_000002.txt", "kitti00/gt/T_000004_from_000003.txt",
                      "kitti00/gt/T_000005_from_000004.txt", "kitti00/gt/T_004438_from_000000.txt",
                      "kitti00/gt/T_004438_from_000001.txt", "kitti00/gt/T_004438_from_000002.txt",
                      "kitti00/gt/T_004438_from_000003.txt", "kitti00/gt/T_004438_from_000004.txt",
                      "kitti00/gt/T_004438_from_000005.txt", "hdl32_pair/T_target_source.txt",
                      "3dtk/T_scan000_from_scan001_RH_m.txt", "3dtk/T_scan001_from_scan002_RH_m.txt",
                      "3dtk/T_scan000_from_scan002_RH_m.txt",
                      "quadricsreg_demo/estimates_not_gt/T_vlp16_target_from_source_estimate.txt",
                      "quadricsreg_demo/estimates_not_gt/T_mid360_target_from_source_estimate.txt",
                      "quadricsreg_demo/estimates_not_gt/T_avia_target_from_source_estimate_UNRELIABLE.txt",
                      "quadricsreg_demo/estimates_not_gt/T_cross_avia_vlp_1_target_from_source_estimate.txt",
                      "quadricsreg_demo/estimates_not_gt/T_cross_avia_vlp_2_target_from_source_estimate.txt",
                      "quadricsreg_demo/estimates_not_gt/T_cross_mid360_vlp_1_target_from_source_estimate.txt"),
    [](const auto& info) {
      std::string name = info.param;
      for (char& c : name)
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
      return name;
    });

TEST(SharedData, ThreeDMatchTextAndNpyGroundTruthAgree) {
  QUADRIX_REQUIRE_SHARED_DATA("3dmatch_demo/gt.npy");
  const Eigen::Isometry3d from_text = read_pose_matrix(shared_data_path("3dmatch_demo/gt_ref_from_src.txt"));
  const Eigen::Isometry3d from_npy = read_pose_matrix(shared_data_path("3dmatch_demo/gt.npy"));
  EXPECT_LT((from_text.matrix() - from_npy.matrix()).cwiseAbs().maxCoeff(), 1e-8);
  // The 3DMatch ground truth itself is only orthonormal to ~7.1e-5 (det 0.9999): accepted by the reader's
  // documented 1e-3 tolerance and kept as written, so callers comparing against it see the dataset's values.
  const Eigen::Matrix3d rotation = from_npy.linear();
  const double deviation = (rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  EXPECT_GT(deviation, 5e-5);
  EXPECT_LT(deviation, kPoseOrthonormalityTolerance);
}

TEST(SharedData, KittiPoseSequencesHaveDocumentedLengths) {
  // Frame counts of KITTI odometry sequences 00-10 (one pose line per frame).
  const std::size_t frames[11] = {4541, 1101, 4661, 801, 271, 2761, 1101, 1101, 4071, 1591, 1201};
  for (int sequence = 0; sequence <= 10; ++sequence) {
    char name[32];
    std::snprintf(name, sizeof(name), "kitti_poses/%02d.txt", sequence);
    QUADRIX_REQUIRE_SHARED_DATA(name);
    const std::vector<Eigen::Isometry3d> poses = read_kitti_poses(shared_data_path(name));
    EXPECT_EQ(poses.size(), frames[sequence]) << name;
    EXPECT_LT((poses.front().matrix() - Eigen::Matrix4d::Identity()).cwiseAbs().maxCoeff(), 1e-6) << name;
  }
}

TEST(SharedData, KittiCalibrationAndGroundTruthConvention) {
  QUADRIX_REQUIRE_SHARED_DATA("kitti_poses/calib_Tr_velo_to_cam.txt");
  const std::string calibration = shared_data_path("kitti_poses/calib_Tr_velo_to_cam.txt");
  EXPECT_THAT([&] { read_kitti_calibration(calibration); },
              ::testing::ThrowsMessage<Error>(::testing::AllOf(::testing::HasSubstr(calibration),
                                                               ::testing::HasSubstr("sequence"))));
  const Eigen::Isometry3d tr = read_kitti_calibration(calibration, 0);
  EXPECT_NEAR(tr(0, 0), 4.276802385584e-04, 1e-15);
  EXPECT_NEAR(tr(2, 3), -2.921968648686e-01, 1e-15);
  EXPECT_NEAR(read_kitti_calibration(calibration, 3)(0, 3), -2.796816941295e-03, 1e-15);
  EXPECT_NEAR(read_kitti_calibration(calibration, 7)(0, 0), -1.857739385241e-03, 1e-15);
  // README: T_lidar(i) = P(i) * Tr and T_b_from_a = T_lidar(b)^-1 * T_lidar(a); check against the gt file.
  const std::vector<Eigen::Isometry3d> poses = read_kitti_poses(shared_data_path("kitti_poses/00.txt"));
  const Eigen::Isometry3d lidar0 = poses[0] * tr, lidar4438 = poses[4438] * tr;
  const Eigen::Isometry3d derived = lidar4438.inverse() * lidar0;
  const Eigen::Isometry3d stored = read_pose_matrix(shared_data_path("kitti00/gt/T_004438_from_000000.txt"));
  EXPECT_LT((derived.translation() - stored.translation()).norm(), 0.5);
  EXPECT_LT(Eigen::AngleAxisd(derived.linear().transpose() * stored.linear()).angle(), 0.02);
}

}  // namespace
}  // namespace quadrix
