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

/// A noisy relative pose: the true one with a random rotation of `rotation_sigma` (rad, per axis)
/// and translation of `translation_sigma` (m, per axis) applied.
Eigen::Isometry3d noisy(const Eigen::Isometry3d& relative, double rotation_sigma, double translation_sigma,
                        std::mt19937& random) {
  std::normal_distribution<double> noise(0.0, 1.0);
  const Eigen::Vector3d axis_angle(rotation_sigma * noise(random), rotation_sigma * noise(random), rotation_sigma * noise(random));
  Eigen::Isometry3d error = Eigen::Isometry3d::Identity();
  if (axis_angle.norm() > 0) error.linear() = Eigen::AngleAxisd(axis_angle.norm(), axis_angle.normalized()).toRotationMatrix();
  error.translation() = translation_sigma * Eigen::Vector3d(noise(random), noise(random), noise(random));
  return relative * error;
}

// Two groups of loop edges, one ten times less accurate than the other (a sparse sensor's), and an
// odometry far better than its stated drift, all given the same wrong information: after three
// rounds the factors find the groups' variance ratio (100) within a factor 4 and the odometry's
// rotation variance (1/1600 of what it was given) within a factor 6, and the graph lies closer to the
// truth (CGAL-style acceptance over seeds: every seed must show it). Without the redundancy the
// accurate group, whose residuals the graph shrinks most, came out 550-16,000 times better.
TEST(PoseGraph, VarianceFactorsFindEachGroupsAccuracyAndImproveTheMap) {
  for (unsigned seed : {31u, 32u, 33u, 34u, 35u}) {
    std::mt19937 random(seed);
    std::vector<Eigen::Isometry3d> truth;
    for (int index = 0; index < 80; ++index) truth.push_back(pose_at(2.0 * index, 5.0 * std::sin(0.05 * index), 0.02 * index));
    const double degree = kPi / 180;
    std::vector<PoseGraphEdge> edges;
    std::vector<std::size_t> group;
    std::vector<Eigen::Isometry3d> odometry{truth[0]};
    for (std::size_t index = 1; index < truth.size(); ++index) {
      const Eigen::Isometry3d step = noisy(truth[index - 1].inverse() * truth[index], 0.05 * degree, 0.02, random);
      odometry.push_back(odometry.back() * step);
      edges.push_back({index, index - 1, step, information(2.0 * degree, 0.1), false});  // stated: 40 x the rotation error
      group.push_back(0);
    }
    for (std::size_t index = 4; index < truth.size(); ++index) {
      const bool sparse = index % 2 == 1;
      const double rotation_sigma = (sparse ? 0.5 : 0.05) * degree, translation_sigma = sparse ? 0.1 : 0.01;
      edges.push_back({index, index - 4, noisy(truth[index - 4].inverse() * truth[index], rotation_sigma, translation_sigma, random),
                       information(0.5 * degree, 0.1), true});
      group.push_back(sparse ? 2 : 1);
    }
    std::vector<Eigen::Isometry3d> poses = odometry;
    optimise_pose_graph(poses, edges);
    const double before = position_rmse(poses, truth);
    Eigen::Vector3d rotation_factor = Eigen::Vector3d::Ones(), translation_factor = Eigen::Vector3d::Ones();
    for (int round = 0; round < 3; ++round) {
      const std::vector<VarianceFactors> factors = estimate_variance_factors(poses, edges, group, 3, {0, 1, 1}, 10);
      for (std::size_t k = 0; k < edges.size(); ++k)
        edges[k].information = scaled_information(edges[k].information, factors[group[k]].rotation, factors[group[k]].translation);
      for (std::size_t g = 0; g < 3; ++g) {
        rotation_factor[g] *= factors[g].rotation;
        translation_factor[g] *= factors[g].translation;
        EXPECT_FALSE(factors[g].pooled);
      }
      optimise_pose_graph(poses, edges);
    }
    const double after = position_rmse(poses, truth);
    // True variance ratios: sparse over accurate loop edges 100 in both blocks; odometry rotation
    // (0.05 deg)^2 / (2 deg)^2 = 1/1600 of what it was given.
    EXPECT_GT(rotation_factor[2] / rotation_factor[1], 25.0) << "seed " << seed;
    EXPECT_LT(rotation_factor[2] / rotation_factor[1], 400.0) << "seed " << seed;
    EXPECT_GT(translation_factor[2] / translation_factor[1], 25.0) << "seed " << seed;
    EXPECT_LT(translation_factor[2] / translation_factor[1], 400.0) << "seed " << seed;
    EXPECT_GT(rotation_factor[0], 1.0 / 1600 / 6) << "seed " << seed;
    EXPECT_LT(rotation_factor[0], 6.0 / 1600) << "seed " << seed;
    EXPECT_LT(after, before) << "seed " << seed;
  }
}

TEST(PoseGraph, VarianceFactorsPoolSmallGroupsAndLeaveUncontradictedOnesAlone) {
  // A chain with no loop: its residuals are zero, nothing measures it.
  std::vector<Eigen::Isometry3d> poses = {pose_at(0, 0, 0), pose_at(1, 0, 0), pose_at(2, 0, 0)};
  std::vector<PoseGraphEdge> edges = {{1, 0, pose_at(1, 0, 0), information(0.01, 0.1), false},
                                      {2, 1, pose_at(1, 0, 0), information(0.01, 0.1), false}};
  std::vector<VarianceFactors> factors = estimate_variance_factors(poses, edges, {0, 0}, 1, {0}, 1);
  EXPECT_FALSE(factors[0].measured);
  EXPECT_EQ(factors[0].rotation, 1.0);
  EXPECT_EQ(factors[0].translation, 1.0);
  // A group of one edge below the minimum takes its pool's factors: the pool's median over all three.
  // Three equal edges between poses 0 (the gauge) and 1 share pose 1's six degrees of freedom: each
  // keeps a redundancy of 2 of 3 per block, so each χ² counts 3/2 times.
  Eigen::Isometry3d off = poses[1].inverse() * poses[0];
  off.translation().x() += 0.2;
  edges = {{0, 1, off, information(0.01, 0.1), true}, {0, 1, off, information(0.01, 0.1), true},
           {0, 1, poses[1].inverse() * poses[0], information(0.01, 0.1), true}};
  factors = estimate_variance_factors(poses, edges, {0, 0, 1}, 2, {0, 0}, 2);
  EXPECT_FALSE(factors[0].pooled);
  EXPECT_TRUE(factors[1].pooled);
  const std::vector<EdgeRedundancy> redundancy = edge_redundancies(poses, edges);
  for (const EdgeRedundancy& edge : redundancy) {
    EXPECT_NEAR(edge.rotation, 2.0, 1e-4);
    EXPECT_NEAR(edge.translation, 2.0, 1e-4);
  }
  EXPECT_NEAR(factors[1].translation, 1.5 * 0.2 * 0.2 / (0.1 * 0.1) / 2.365974, 1e-4);
  EXPECT_EQ(factors[1].rotation, 1.0);  // every rotation agrees: nothing measured
  EXPECT_FALSE(factors[1].measured);
  // A pose that only an edge without information reaches: no covariance, an error (not a crash).
  const std::vector<PoseGraphEdge> blind = {{1, 0, pose_at(1, 0, 0), information(0.01, 0.1), false},
                                            {2, 1, pose_at(1, 0, 0), Information6d::Zero(), false}};
  EXPECT_THROW(edge_redundancies(poses, blind), Error);
  EXPECT_THROW(estimate_variance_factors(poses, blind, {0, 0}, 1, {0}, 1), Error);
  EXPECT_THROW(estimate_variance_factors(poses, edges, {0, 0}, 2, {0, 0}, 2), Error);     // one group per edge
  EXPECT_THROW(estimate_variance_factors(poses, edges, {0, 0, 5}, 2, {0, 0}, 2), Error);  // no such group
  // Scaling keeps the matrix symmetric and scales each block's variances as stated.
  Information6d omega = information(0.01, 0.1);
  omega(0, 3) = omega(3, 0) = 5.0;
  const Information6d scaled = scaled_information(omega, 4.0, 0.25);
  EXPECT_NEAR(scaled(0, 0), omega(0, 0) / 4.0, 1e-9);
  EXPECT_NEAR(scaled(3, 3), omega(3, 3) / 0.25, 1e-9);
  EXPECT_NEAR(scaled(0, 3), omega(0, 3), 1e-9);
  EXPECT_TRUE(scaled.isApprox(scaled.transpose()));
}

// Baarda's data snooping on a calibrated graph: a loop edge that slid 3 m along the path with its
// heading right (a street's degeneracy), and one 10 deg off, among right loop edges whose
// information states their true accuracy. Over seeds, the outlier test removes exactly the two wrong
// edges, first, and no right one (each right edge's statistic has expectation 1; the threshold is 100).
TEST(PoseGraph, DataSnoopingRemovesTheWrongLoopEdgesAndNoRightOne) {
  const double degree = kPi / 180;
  for (unsigned seed : {41u, 42u, 43u, 44u, 45u, 46u}) {
    std::mt19937 random(seed);
    std::vector<Eigen::Isometry3d> truth;
    for (int index = 0; index < 80; ++index) truth.push_back(pose_at(2.0 * index, 5.0 * std::sin(0.05 * index), 0.02 * index));
    std::vector<PoseGraphEdge> edges;
    std::vector<Eigen::Isometry3d> poses{truth[0]};
    for (std::size_t index = 1; index < truth.size(); ++index) {
      const Eigen::Isometry3d step = noisy(truth[index - 1].inverse() * truth[index], 0.05 * degree, 0.02, random);
      poses.push_back(poses.back() * step);
      edges.push_back({index, index - 1, step, information(0.05 * degree, 0.02), false});
    }
    const std::size_t first_loop = edges.size();
    for (std::size_t index = 2; index < truth.size(); ++index)
      edges.push_back({index, index - 2, noisy(truth[index - 2].inverse() * truth[index], 0.05 * degree, 0.01, random),
                       information(0.05 * degree, 0.01), true});
    std::uniform_int_distribution<std::size_t> pick(first_loop + 5, edges.size() - 5);
    const std::size_t slid = pick(random);
    std::size_t turned = pick(random);
    while (turned + 2 >= slid && turned <= slid + 2) turned = pick(random);  // apart, so each is tested by right neighbours
    // Slide: 3 m along the `to` scan's heading (its x axis), rotation right.
    Eigen::Isometry3d along = Eigen::Isometry3d::Identity();
    along.translation() = 3.0 * Eigen::Vector3d::UnitX();
    edges[slid].measurement = along * edges[slid].measurement;
    Eigen::Isometry3d turn = Eigen::Isometry3d::Identity();
    turn.linear() = Eigen::AngleAxisd(10.0 * degree, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    edges[turned].measurement = turn * edges[turned].measurement;
    std::vector<bool> testable(edges.size(), false);
    for (std::size_t k = first_loop; k < edges.size(); ++k) testable[k] = true;
    const DataSnooping snooping = snoop_pose_graph(poses, edges, testable, 100.0, 10);
    ASSERT_EQ(snooping.removed.size(), 2u) << "seed " << seed;
    EXPECT_TRUE((snooping.removed[0] == slid && snooping.removed[1] == turned) ||
                (snooping.removed[0] == turned && snooping.removed[1] == slid)) << "seed " << seed;
    EXPECT_FALSE(snooping.exhausted);
    for (double statistic : snooping.statistic) EXPECT_GT(statistic, 100.0);
    // The poses come back solved without them: as the graph of the right edges alone solves.
    std::vector<PoseGraphEdge> remaining;
    for (std::size_t k = 0; k < edges.size(); ++k)
      if (k != slid && k != turned) remaining.push_back(edges[k]);
    std::vector<Eigen::Isometry3d> right_only = poses;
    optimise_pose_graph(right_only, remaining);
    EXPECT_LT(position_rmse(poses, right_only), 1e-4) << "seed " << seed;
    // Right edges after the removal: their statistics scatter around 1.
    double sum = 0.0;
    std::size_t tested = 0;
    for (const EdgeOutlierStatistic& statistic : edge_outlier_statistics(poses, remaining))
      if (statistic.translation > 0.0) sum += statistic.translation, ++tested;
    EXPECT_GT(sum / tested, 0.5) << "seed " << seed;
    EXPECT_LT(sum / tested, 2.0) << "seed " << seed;
  }
}

// What data snooping must not do: remove an edge that alone joins two parts of the graph (nothing
// tests it, its redundancy is 0), an edge not marked testable, or go past its budget silently.
TEST(PoseGraph, DataSnoopingLeavesBridgesAndUntestableEdgesAndReportsItsBudget) {
  const double degree = kPi / 180;
  std::vector<Eigen::Isometry3d> truth;
  for (int index = 0; index < 6; ++index) truth.push_back(pose_at(index, 0, 0));
  // Two chains, 0-1-2 and 3-4-5, joined by one wrong edge only (3 -> 2 off by 5 m).
  std::vector<PoseGraphEdge> edges;
  for (std::size_t index : {1u, 2u, 4u, 5u})
    edges.push_back({index, index - 1, truth[index - 1].inverse() * truth[index], information(0.1 * degree, 0.01), false});
  Eigen::Isometry3d bridge = truth[2].inverse() * truth[3];
  bridge.translation().y() += 5.0;
  edges.push_back({3, 2, bridge, information(0.1 * degree, 0.01), true});
  std::vector<Eigen::Isometry3d> poses = truth;
  DataSnooping snooping = snoop_pose_graph(poses, edges, std::vector<bool>(edges.size(), true), 100.0, 10);
  EXPECT_TRUE(snooping.removed.empty());
  // Two edges each shifted 1 m in a triangle 0-1-2, both far above the threshold: the testable one
  // leaves, the other stays.
  edges = {{1, 0, truth[0].inverse() * truth[1], information(0.1 * degree, 0.01), false},
           {2, 1, truth[1].inverse() * truth[2], information(0.1 * degree, 0.01), false}};
  Eigen::Isometry3d shifted = truth[0].inverse() * truth[2];
  shifted.translation().y() += 1.0;
  edges.push_back({2, 0, shifted, information(0.1 * degree, 0.01), true});
  edges.push_back({2, 0, shifted, information(0.1 * degree, 0.01), true});
  poses = truth;
  snooping = snoop_pose_graph(poses, edges, {false, false, true, false}, 100.0, 10);
  ASSERT_EQ(snooping.removed.size(), 1u);
  EXPECT_EQ(snooping.removed[0], 2u);
  EXPECT_FALSE(snooping.exhausted);
  // Testable with a budget of one: one leaves, and the run says it stopped with more above.
  poses = truth;
  snooping = snoop_pose_graph(poses, edges, {false, false, true, true}, 100.0, 1);
  EXPECT_EQ(snooping.removed.size(), 1u);
  EXPECT_TRUE(snooping.exhausted);
  EXPECT_THROW(snoop_pose_graph(poses, edges, {true}, 100.0, 1), Error);
}

}  // namespace
}  // namespace quadrix
