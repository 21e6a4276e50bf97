// Multi-level compatibility graphs (paper Eq. of d_ij) and the planted-inlier recovery of the
// graduated maximum-clique search (paper §"Graph-based Outlier Pruning").
#include "matching/compatibility_graph.h"

#include "geometry/error.h"
#include "test_geometry.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace quadrix {
namespace {

Eigen::Matrix3Xd random_points(Eigen::Index count, double box, std::mt19937& random) {
  std::uniform_real_distribution<double> uniform(-box, box);
  Eigen::Matrix3Xd points(3, count);
  for (Eigen::Index i = 0; i < count; ++i)
    for (int r = 0; r < 3; ++r) points(r, i) = uniform(random);
  return points;
}

TEST(CompatibilityGraph, EdgesMatchBruteForceDistanceCheck) {
  std::mt19937 random(11);
  for (int round = 0; round < 20; ++round) {
    const Eigen::Index n = 1 + round * 13;  // crosses word boundaries (64, 128, 192)
    // A small box makes the distance differences straddle the thresholds.
    const Eigen::Matrix3Xd source = random_points(n, 1.0, random);
    Eigen::Matrix3Xd target = testing::random_pose(random, 20.0, testing::TranslationDraw::Gaussian) * source;
    target += random_points(n, 0.3, random);
    const CompatibilityGraphOptions options;
    const CompatibilityGraphs graphs = build_compatibility_graphs(source, target, options);
    ASSERT_EQ(graphs.levels.size(), 4u);
    ASSERT_EQ(graphs.thresholds, options.thresholds);
    std::size_t edges_seen = 0;
    for (std::size_t k = 0; k < graphs.levels.size(); ++k) {
      const BitsetGraph& level = graphs.levels[k];
      ASSERT_EQ(level.vertex_count(), static_cast<std::size_t>(n));
      for (Eigen::Index i = 0; i < n; ++i) {
        EXPECT_FALSE(level.has_edge(static_cast<int>(i), static_cast<int>(i)));
        for (Eigen::Index j = 0; j < n; ++j) {
          if (i == j) continue;
          const double d = std::abs((source.col(i) - source.col(j)).norm() - (target.col(i) - target.col(j)).norm());
          ASSERT_EQ(level.has_edge(static_cast<int>(i), static_cast<int>(j)), d <= options.thresholds[k])
              << "i=" << i << " j=" << j << " d=" << d << " level " << k;
        }
      }
      edges_seen += level.edge_count();
      if (k > 0) {
        EXPECT_TRUE(graphs.levels[k - 1].is_subgraph_of(level));
      }
    }
    if (n > 20) {
      EXPECT_GT(edges_seen, 0u);
    }
  }
}

TEST(CompatibilityGraph, DistanceIsTheAbsoluteDifferenceOfCentreDistances) {
  Eigen::Matrix3Xd source(3, 2), target(3, 2);
  source << 0, 3, 0, 4, 0, 0;  // |x_0 - x_1| = 5
  target << 1, 1, 1, 1, 1, 7;  // |y_0 - y_1| = 6
  EXPECT_DOUBLE_EQ(pairwise_consistency_distance(source, target, 0, 1), 1.0);
  EXPECT_DOUBLE_EQ(pairwise_consistency_distance(source, target, 1, 0), 1.0);
  CompatibilityGraphOptions options;
  options.thresholds = {0.5, 1.0};  // inclusive: d == δ is an edge
  const CompatibilityGraphs graphs = build_compatibility_graphs(source, target, options);
  EXPECT_FALSE(graphs.levels[0].has_edge(0, 1));
  EXPECT_TRUE(graphs.levels[1].has_edge(0, 1));
}

TEST(CompatibilityGraph, EmptyCorrespondenceSetGivesEmptyGraphs) {
  const CompatibilityGraphs graphs = build_compatibility_graphs(Eigen::Matrix3Xd(3, 0), Eigen::Matrix3Xd(3, 0));
  ASSERT_EQ(graphs.levels.size(), 4u);
  EXPECT_EQ(graphs.levels[0].vertex_count(), 0u);
  const GraduatedCliqueResult cliques = find_graduated_maximum_cliques(graphs.levels);
  for (const MaxCliqueResult& level : cliques.levels) EXPECT_EQ(level.status, CliqueStatus::empty_graph);
}

TEST(CompatibilityGraph, BadInputThrows) {
  std::mt19937 random(3);
  const Eigen::Matrix3Xd source = random_points(5, 1.0, random);
  EXPECT_THROW(build_compatibility_graphs(source, random_points(4, 1.0, random)), Error);
  Eigen::Matrix3Xd with_nan = source;
  with_nan(1, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(build_compatibility_graphs(source, with_nan), Error);
  for (const std::vector<double>& thresholds :
       {std::vector<double>{}, std::vector<double>{0.4, 0.2}, std::vector<double>{0.2, 0.2}, std::vector<double>{-0.1},
        std::vector<double>{0.2, std::numeric_limits<double>::infinity()}}) {
    CompatibilityGraphOptions options;
    options.thresholds = thresholds;
    EXPECT_THROW(build_compatibility_graphs(source, source, options), Error);
  }
}

// Planted rigid-transform inliers with bounded noise among random outliers: the maximum clique of
// every level contains (nearly) all inliers, and the strictest level contains all of them.
TEST(CompatibilityGraph, GraduatedCliquesRecoverPlantedInliers) {
  std::mt19937 random(2024);
  const Eigen::Index correspondence_count = 400;
  const Eigen::Index inlier_count = 60;
  for (int round = 0; round < 10; ++round) {
    const Eigen::Isometry3d pose = testing::random_pose(random, 20.0, testing::TranslationDraw::Gaussian);
    const Eigen::Matrix3Xd source = random_points(correspondence_count, 50.0, random);
    Eigen::Matrix3Xd target = pose * source;
    // Inliers: noise of at most 0.05 m per axis (|noise| <= 0.087 m, so d_ij <= 0.174 m < δ_1 = 0.2 m).
    target.leftCols(inlier_count) += random_points(inlier_count, 0.05, random);
    // Outliers: target centres anywhere in the scene.
    target.rightCols(correspondence_count - inlier_count) =
        pose * random_points(correspondence_count - inlier_count, 50.0, random);
    // Shuffle so inliers are not a prefix.
    std::vector<int> permutation(static_cast<std::size_t>(correspondence_count));
    for (std::size_t i = 0; i < permutation.size(); ++i) permutation[i] = static_cast<int>(i);
    std::shuffle(permutation.begin(), permutation.end(), random);
    Eigen::Matrix3Xd shuffled_source(3, correspondence_count), shuffled_target(3, correspondence_count);
    std::vector<bool> is_inlier(permutation.size());
    for (std::size_t i = 0; i < permutation.size(); ++i) {
      shuffled_source.col(static_cast<Eigen::Index>(i)) = source.col(permutation[i]);
      shuffled_target.col(static_cast<Eigen::Index>(i)) = target.col(permutation[i]);
      is_inlier[i] = permutation[i] < inlier_count;
    }

    const CompatibilityGraphs graphs = build_compatibility_graphs(shuffled_source, shuffled_target);
    MaxCliqueOptions options;
    options.thread_count = 2;
    const GraduatedCliqueResult cliques = find_graduated_maximum_cliques(graphs.levels, options);
    ASSERT_EQ(cliques.levels.size(), 4u);
    for (std::size_t k = 0; k < cliques.levels.size(); ++k) {
      const MaxCliqueResult& level = cliques.levels[k];
      ASSERT_EQ(level.status, CliqueStatus::optimal);
      ASSERT_TRUE(graphs.levels[k].is_clique(level.clique));
      const auto inliers_found =
          std::count_if(level.clique.begin(), level.clique.end(), [&](int v) { return is_inlier[static_cast<std::size_t>(v)]; });
      const auto outliers_found = static_cast<long>(level.size()) - inliers_found;
      if (k == 0) {
        EXPECT_EQ(inliers_found, inlier_count) << "round " << round;
      } else {
        EXPECT_GE(inliers_found, inlier_count - 2) << "round " << round << " level " << k;
      }
      EXPECT_LE(outliers_found, 2) << "round " << round << " level " << k;
    }
  }
}

}  // namespace
}  // namespace quadrix
