// The pose graph on randomised synthetic trajectories: a loop driven with drifting odometry is
// pulled back onto the truth by true loop edges, a false loop edge is scaled down by DCS, separate
// components each keep their gauge, and bad edges are errors.
#include "estimation/pose_graph.h"
#include "geometry/error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace quadrix {
namespace {

constexpr double kPi = 3.14159265358979323846;

Eigen::Isometry3d pose_at(double x, double y, double yaw) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  pose.translation() = Eigen::Vector3d(x, y, 0.0);
  return pose;
}

/// A square loop of 4 x 10 m sampled every metre (41 poses, the last back at the start).
std::vector<Eigen::Isometry3d> square_loop() {
  std::vector<Eigen::Isometry3d> poses;
  for (int side = 0; side < 4; ++side)
    for (int step = 0; step < 10; ++step) {
      const double yaw = side * kPi / 2;
      const Eigen::Vector2d corner = side == 0 ? Eigen::Vector2d(0, 0) : side == 1 ? Eigen::Vector2d(10, 0)
                                   : side == 2 ? Eigen::Vector2d(10, 10) : Eigen::Vector2d(0, 10);
      const Eigen::Vector2d position = corner + step * Eigen::Vector2d(std::cos(yaw), std::sin(yaw));
      poses.push_back(pose_at(position.x(), position.y(), yaw));
    }
  poses.push_back(pose_at(0, 0, 2 * kPi));
  return poses;
}

Information6d information(double rotation_sigma, double translation_sigma) {
  Information6d omega = Information6d::Zero();
  omega.diagonal() << Eigen::Vector3d::Constant(1 / (rotation_sigma * rotation_sigma)),
      Eigen::Vector3d::Constant(1 / (translation_sigma * translation_sigma));
  return omega;
}

/// Odometry with a yaw bias of 1 deg per step and noise, integrated from the truth's first pose.
std::vector<Eigen::Isometry3d> drifted(const std::vector<Eigen::Isometry3d>& truth, std::mt19937& random,
                                       std::vector<PoseGraphEdge>& edges) {
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<Eigen::Isometry3d> odometry{truth[0]};
  for (std::size_t index = 1; index < truth.size(); ++index) {
    Eigen::Isometry3d step = truth[index - 1].inverse() * truth[index];
    Eigen::Isometry3d error = Eigen::Isometry3d::Identity();
    error.linear() = Eigen::AngleAxisd(kPi / 180 * (1.0 + 0.2 * noise(random)), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    error.translation() = 0.03 * Eigen::Vector3d(noise(random), noise(random), noise(random));
    step = step * error;
    odometry.push_back(odometry.back() * step);
    // Edge from index to index - 1: maps index's points into index - 1's frame.
    edges.push_back({index, index - 1, step, information(2 * kPi / 180, 0.05), false});
  }
  return odometry;
}

double position_rmse(const std::vector<Eigen::Isometry3d>& estimate, const std::vector<Eigen::Isometry3d>& truth) {
  double sum = 0.0;
  for (std::size_t index = 0; index < truth.size(); ++index) sum += (estimate[index].translation() - truth[index].translation()).squaredNorm();
  return std::sqrt(sum / truth.size());
}

TEST(PoseGraph, ErrorIsZeroAtTheMeasurementAndDcsScaleFollowsItsFormula) {
  const Eigen::Isometry3d a = pose_at(1, 2, 0.3), b = pose_at(-4, 0.5, 1.2);
  EXPECT_LT(pose_graph_error(a, b, b.inverse() * a).norm(), 1e-12);
  Eigen::Isometry3d off = b.inverse() * a;
  off.translation().x() += 0.5;
  EXPECT_NEAR(pose_graph_error(a, b, off).norm(), 0.5, 1e-9);
  EXPECT_DOUBLE_EQ(dcs_scale(0.1, 0.5), 1.0);
  EXPECT_DOUBLE_EQ(dcs_scale(9.5, 0.5), 2 * 0.5 / (0.5 + 9.5));
}

TEST(PoseGraph, TrueLoopEdgesUndoOdometryDriftOverRandomSeeds) {
  for (unsigned seed : {11u, 12u, 13u, 14u, 15u}) {
    std::mt19937 random(seed);
    const std::vector<Eigen::Isometry3d> truth = square_loop();
    std::vector<PoseGraphEdge> edges;
    std::vector<Eigen::Isometry3d> poses = drifted(truth, random, edges);
    const double before = position_rmse(poses, truth);
    // Loop edges: the closing pose to the start and the second side's start seen again at the end.
    for (std::size_t from : {std::size_t{40}, std::size_t{39}, std::size_t{38}})
      edges.push_back({from, 0, truth[0].inverse() * truth[from], information(0.5 * kPi / 180, 0.05), true});
    const PoseGraphSummary summary = optimise_pose_graph(poses, edges);
    const double after = position_rmse(poses, truth);
    EXPECT_GT(before, 1.0) << "seed " << seed << ": the drift should be large";
    EXPECT_LT(after, 0.35 * before) << "seed " << seed;
    EXPECT_LT(summary.final_cost, summary.initial_cost) << "seed " << seed;
    EXPECT_EQ(summary.gauges.size(), 1u);
    EXPECT_TRUE(poses[0].isApprox(truth[0], 1e-9)) << "the gauge moved";
  }
}

TEST(PoseGraph, DcsScalesDownAFalseSwitchableEdgeAndKeepsATrueOne) {
  for (unsigned seed : {21u, 22u, 23u}) {
    std::mt19937 random(seed);
    const std::vector<Eigen::Isometry3d> truth = square_loop();
    std::vector<PoseGraphEdge> edges;
    std::vector<Eigen::Isometry3d> poses = drifted(truth, random, edges);
    for (std::size_t from : {std::size_t{40}, std::size_t{39}, std::size_t{38}})
      edges.push_back({from, 0, truth[0].inverse() * truth[from], information(0.5 * kPi / 180, 0.05), true});
    // A false unsure loop: pose 25 "seen" at pose 5 (they are 10 m apart), switchable.
    edges.push_back({25, 5, Eigen::Isometry3d::Identity(), information(0.5 * kPi / 180, 0.05), false, true});
    const PoseGraphSummary summary = optimise_pose_graph(poses, edges);
    EXPECT_LT(summary.final_scale.back(), 0.05) << "seed " << seed;
    EXPECT_LT(position_rmse(poses, truth), 0.5) << "seed " << seed;
    // A true switchable edge keeps its weight.
    std::vector<PoseGraphEdge> true_edges(edges.begin(), edges.end() - 1);
    true_edges.push_back({25, 5, truth[5].inverse() * truth[25], information(0.5 * kPi / 180, 0.05), false, true});
    std::vector<Eigen::Isometry3d> again = drifted(truth, random, edges);
    const PoseGraphSummary kept = optimise_pose_graph(again, true_edges);
    EXPECT_GT(kept.final_scale.back(), 0.5) << "seed " << seed;
  }
}

TEST(PoseGraph, ComponentsKeepTheirOwnGauge) {
  std::vector<Eigen::Isometry3d> poses = {pose_at(0, 0, 0), pose_at(1, 0, 0), pose_at(50, 0, 0), pose_at(52, 0, 0)};
  const std::vector<PoseGraphEdge> edges = {{1, 0, pose_at(-2, 0, 0), information(0.01, 0.1), false},
                                            {3, 2, pose_at(2, 0, 0), information(0.01, 0.1), false}};
  const PoseGraphSummary summary = optimise_pose_graph(poses, edges);
  ASSERT_EQ(summary.gauges.size(), 2u);
  EXPECT_EQ(summary.component, (std::vector<std::size_t>{0, 0, 1, 1}));
  EXPECT_TRUE(poses[0].isApprox(pose_at(0, 0, 0)));
  EXPECT_TRUE(poses[2].isApprox(pose_at(50, 0, 0)));
  EXPECT_NEAR(poses[1].translation().x(), -2.0, 1e-6);
  EXPECT_NEAR(poses[3].translation().x(), 52.0, 1e-6);
}

TEST(PoseGraph, BadEdgesAreErrors) {
  std::vector<Eigen::Isometry3d> poses(2, Eigen::Isometry3d::Identity());
  EXPECT_THROW(optimise_pose_graph(poses, {{0, 5, Eigen::Isometry3d::Identity(), Information6d::Identity(), false}}), Error);
  EXPECT_THROW(optimise_pose_graph(poses, {{1, 1, Eigen::Isometry3d::Identity(), Information6d::Identity(), false}}), Error);
  EXPECT_THROW(optimise_pose_graph(poses, {{0, 1, Eigen::Isometry3d::Identity(), -Information6d::Identity(), false}}), Error);
}

}  // namespace
}  // namespace quadrix
