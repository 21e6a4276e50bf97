// SVD initialisation (Arun/Umeyama) on full centres: exact recovery, weights, reflections, degeneracy.
#include "estimation/svd_alignment.h"
#include "estimation/synthetic_scene.h"
#include "geometry/error.h"

#include <gtest/gtest.h>

#include <random>

namespace quadrix {
namespace {

Eigen::Matrix3Xd random_points(std::mt19937& rng, int count, double extent) {
  std::uniform_real_distribution<double> uniform(-extent, extent);
  Eigen::Matrix3Xd points(3, count);
  for (int i = 0; i < count; ++i) points.col(i) = Eigen::Vector3d(uniform(rng), uniform(rng), uniform(rng));
  return points;
}

TEST(SvdAlignment, RecoversRandomTransformsExactlyFromNoiseFreePoints) {
  std::mt19937 rng(21);
  for (int trial = 0; trial < 200; ++trial) {
    const int count = 3 + trial % 20;
    const Eigen::Matrix3Xd source = random_points(rng, count, 30.0);
    const Eigen::Isometry3d truth = testing::random_pose(rng, 50.0);
    const Eigen::Matrix3Xd target = truth * source;
    const RigidAlignment alignment = align_points(source, target);
    ASSERT_EQ(alignment.status, AlignmentStatus::Ok) << alignment.message;
    EXPECT_EQ(alignment.point_count, static_cast<std::size_t>(count));
    EXPECT_LT((alignment.transform.matrix() - truth.matrix()).cwiseAbs().maxCoeff(), 1e-9) << "trial " << trial;
    EXPECT_LT(alignment.rms_error, 1e-9);
    EXPECT_NEAR(alignment.transform.linear().determinant(), 1.0, 1e-12);
  }
}

TEST(SvdAlignment, CoplanarPointsNeverYieldAReflection) {
  // Coplanar sets are where the unconstrained optimum can be the mirror image; we must return the rotation.
  std::mt19937 rng(22);
  int corrected = 0;
  for (int trial = 0; trial < 100; ++trial) {
    Eigen::Matrix3Xd source = random_points(rng, 6, 10.0);
    source.row(2).setZero();
    const Eigen::Isometry3d truth = testing::random_pose(rng, 20.0);
    const RigidAlignment alignment = align_points(source, truth * source);
    ASSERT_EQ(alignment.status, AlignmentStatus::Ok);
    EXPECT_NEAR(alignment.transform.linear().determinant(), 1.0, 1e-12);
    EXPECT_LT((alignment.transform.matrix() - truth.matrix()).cwiseAbs().maxCoeff(), 1e-8);
    corrected += alignment.reflection_corrected ? 1 : 0;
  }
  // A mirrored (non-rigid) target: the best proper rotation is returned and flagged.
  const Eigen::Matrix3Xd source = random_points(rng, 10, 5.0);
  Eigen::Matrix3Xd mirrored = source;
  mirrored.row(0) *= -1.0;
  const RigidAlignment alignment = align_points(source, mirrored);
  ASSERT_EQ(alignment.status, AlignmentStatus::Ok);
  EXPECT_TRUE(alignment.reflection_corrected);
  EXPECT_NEAR(alignment.transform.linear().determinant(), 1.0, 1e-12);
  EXPECT_GT(alignment.rms_error, 0.1);
  (void)corrected;
}

TEST(SvdAlignment, WeightsSelectWhichPointsCount) {
  std::mt19937 rng(23);
  const Eigen::Matrix3Xd source = random_points(rng, 12, 10.0);
  const Eigen::Isometry3d truth = testing::random_pose(rng, 10.0);
  Eigen::Matrix3Xd target = truth * source;
  std::vector<double> weights(12, 1.0);
  for (int i = 0; i < 4; ++i) {
    target.col(i) += Eigen::Vector3d(5.0, -3.0, 8.0);  // gross outliers...
    weights[static_cast<std::size_t>(i)] = 0.0;        // ...given zero weight
  }
  const RigidAlignment weighted = align_points(source, target, weights);
  ASSERT_EQ(weighted.status, AlignmentStatus::Ok);
  EXPECT_EQ(weighted.point_count, 8u);
  EXPECT_LT((weighted.transform.matrix() - truth.matrix()).cwiseAbs().maxCoeff(), 1e-9);
  const RigidAlignment unweighted = align_points(source, target);
  EXPECT_GT((unweighted.transform.translation() - truth.translation()).norm(), 0.5);
  // Doubling every weight changes nothing.
  std::vector<double> doubled = weights;
  for (double& w : doubled) w *= 2.0;
  EXPECT_LT((align_points(source, target, doubled).transform.matrix() - weighted.transform.matrix()).norm(), 1e-10);
}

TEST(SvdAlignment, DegenerateInputIsAStatusAndMisuseThrows) {
  std::mt19937 rng(24);
  const Eigen::Matrix3Xd two = random_points(rng, 2, 5.0);
  EXPECT_EQ(align_points(two, two).status, AlignmentStatus::Degenerate);
  Eigen::Matrix3Xd collinear(3, 5);
  for (int i = 0; i < 5; ++i) collinear.col(i) = Eigen::Vector3d(1.0, 2.0, 3.0) * i + Eigen::Vector3d(4.0, 0.0, 1.0);
  const RigidAlignment line = align_points(collinear, collinear);
  EXPECT_EQ(line.status, AlignmentStatus::Degenerate);
  EXPECT_FALSE(line.message.empty());
  EXPECT_TRUE(line.transform.isApprox(Eigen::Isometry3d::Identity()));
  const Eigen::Matrix3Xd three = random_points(rng, 3, 5.0);
  EXPECT_EQ(align_points(three, three, {1.0, 1.0, 0.0}).status, AlignmentStatus::Degenerate);  // 2 weighted points
  EXPECT_THROW(align_points(three, two), Error);
  EXPECT_THROW(align_points(three, three, {1.0, 1.0}), Error);
  EXPECT_THROW(align_points(three, three, {1.0, -1.0, 1.0}), Error);
  Eigen::Matrix3Xd not_finite = three;
  not_finite(0, 0) = std::nan("");
  EXPECT_THROW(align_points(not_finite, three), Error);
}

TEST(SvdAlignment, FullCentersOfRecordsGiveTheTruePose) {
  std::mt19937 rng(25);
  for (int trial = 0; trial < 20; ++trial) {
    const auto scene = testing::make_scene(rng, testing::SceneSpec{});
    const RigidAlignment alignment = align_full_centers(scene.source, scene.target, scene.correspondences);
    ASSERT_EQ(alignment.status, AlignmentStatus::Ok);
    const auto [translation_error, angle_error] = testing::pose_error(alignment.transform, scene.truth);
    EXPECT_LT(translation_error, 1e-8);
    EXPECT_LT(angle_error, 1e-7);
  }
  const auto scene = testing::make_scene(rng, testing::SceneSpec{});
  EXPECT_THROW(align_full_centers(scene.source, scene.target, {{0, 1000}}), Error);
  EXPECT_THROW(align_full_centers(scene.source, scene.target, scene.correspondences, {1.0}), Error);
}

}  // namespace
}  // namespace quadrix
