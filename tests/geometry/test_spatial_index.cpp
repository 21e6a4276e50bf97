// PointIndex (k-d tree): nearest point not excluded and the k nearest, against brute force on random
// clouds (with exact ties for the former).
#include "geometry/error.h"
#include "geometry/spatial_index.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <optional>
#include <random>

namespace quadrix {
namespace {

std::vector<Neighbor> brute_force(const Eigen::Matrix3Xd& points, const Eigen::Vector3d& query) {
  std::vector<Neighbor> all;
  for (Eigen::Index i = 0; i < points.cols(); ++i)
    all.push_back({static_cast<std::size_t>(i), (points.col(i) - query).norm()});
  std::sort(all.begin(), all.end(), [](const Neighbor& a, const Neighbor& b) {
    return a.distance < b.distance || (a.distance == b.distance && a.index < b.index);
  });
  return all;
}

TEST(PointIndex, NearestNotExcludedMatchesBruteForceWithTies) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 30; ++trial) {
    const bool grid = trial % 2 == 0;
    const int count = std::uniform_int_distribution<int>(1, 300)(rng);
    Eigen::Matrix3Xd points(3, count);
    for (int i = 0; i < count; ++i)
      for (int d = 0; d < 3; ++d)
        points(d, i) = grid ? std::uniform_int_distribution<int>(-2, 2)(rng) : std::uniform_real_distribution<double>(-10, 10)(rng);
    const PointIndex index(points);
    std::vector<bool> excluded(count);
    const double fraction = std::uniform_real_distribution<double>(0.0, 1.0)(rng);
    for (int i = 0; i < count; ++i) excluded[i] = std::bernoulli_distribution(fraction)(rng);
    const Eigen::Vector3d query = grid ? Eigen::Vector3d(Eigen::Vector3d::Zero()) : Eigen::Vector3d(Eigen::Vector3d::Random() * 10.0);
    std::optional<Neighbor> expected;
    for (const Neighbor& neighbor : brute_force(points, query))
      if (!excluded[neighbor.index]) {
        expected = neighbor;
        break;
      }
    const std::optional<Neighbor> actual = index.nearest_not_excluded(query, excluded);
    ASSERT_EQ(actual.has_value(), expected.has_value()) << "trial " << trial;
    if (expected) {
      EXPECT_EQ(actual->index, expected->index) << "trial " << trial;  // ties by lowest index
      EXPECT_NEAR(actual->distance, expected->distance, 1e-12);
    }
  }
  const PointIndex index(Eigen::Matrix3Xd::Zero(3, 3));
  EXPECT_THROW(index.nearest_not_excluded(Eigen::Vector3d::Zero(), std::vector<bool>(2)), Error);
}

TEST(PointIndex, KNearestMatchBruteForceDistances) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const int count = std::uniform_int_distribution<int>(1, 400)(rng);
    Eigen::Matrix3Xd points(3, count);
    for (int i = 0; i < count; ++i)
      for (int d = 0; d < 3; ++d) points(d, i) = std::uniform_real_distribution<double>(-10, 10)(rng);
    const PointIndex index(points);
    const Eigen::Vector3d query = Eigen::Vector3d::Random() * 12.0;
    const std::size_t k = std::uniform_int_distribution<std::size_t>(1, 15)(rng);
    const std::vector<Neighbor> expected = brute_force(points, query);
    const std::vector<Neighbor> actual = index.nearest(query, k);
    ASSERT_EQ(actual.size(), std::min<std::size_t>(k, count)) << "trial " << trial;
    for (std::size_t i = 0; i < actual.size(); ++i) {
      EXPECT_NEAR(actual[i].distance, expected[i].distance, 1e-12) << "trial " << trial << " rank " << i;
      EXPECT_NEAR((points.col(static_cast<Eigen::Index>(actual[i].index)) - query).norm(), actual[i].distance, 1e-12);
    }
    const std::optional<Neighbor> single = index.nearest(query);
    ASSERT_TRUE(single.has_value());
    EXPECT_NEAR(single->distance, expected.front().distance, 1e-12);
  }
  EXPECT_TRUE(PointIndex(Eigen::Matrix3Xd(3, 0)).nearest(Eigen::Vector3d::Zero(), 3).empty());
  EXPECT_FALSE(PointIndex(Eigen::Matrix3Xd(3, 0)).nearest(Eigen::Vector3d::Zero()).has_value());
}

TEST(PointIndex, NearestWithinMatchesBruteForceAndItsBound) {
  std::mt19937 rng(23);
  for (int trial = 0; trial < 40; ++trial) {
    const int count = std::uniform_int_distribution<int>(1, 300)(rng);
    Eigen::Matrix3Xd points(3, count);
    for (int i = 0; i < count; ++i)
      for (int d = 0; d < 3; ++d) points(d, i) = std::uniform_real_distribution<double>(-10, 10)(rng);
    const PointIndex index(points);
    const Eigen::Vector3d query = Eigen::Vector3d::Random() * 14.0;
    const double bound = std::uniform_real_distribution<double>(0.0, 6.0)(rng);
    const Neighbor nearest = brute_force(points, query).front();
    const std::optional<Neighbor> actual = index.nearest_within(query, bound);
    ASSERT_EQ(actual.has_value(), nearest.distance <= bound) << "trial " << trial;
    if (actual) EXPECT_NEAR(actual->distance, nearest.distance, 1e-12) << "trial " << trial;
    // Exactly at the bound still counts.
    const std::optional<Neighbor> at_bound = index.nearest_within(query, nearest.distance);
    ASSERT_TRUE(at_bound.has_value()) << "trial " << trial;
    EXPECT_NEAR(at_bound->distance, nearest.distance, 1e-12);
  }
  EXPECT_FALSE(PointIndex(Eigen::Matrix3Xd(3, 0)).nearest_within(Eigen::Vector3d::Zero(), 1.0).has_value());
  EXPECT_FALSE(PointIndex(Eigen::Matrix3Xd::Zero(3, 2)).nearest_within(Eigen::Vector3d::Zero(), -1.0).has_value());
}

TEST(PointIndex, EmptyIndexAndBadInput) {
  const PointIndex empty(Eigen::Matrix3Xd(3, 0));
  EXPECT_EQ(empty.size(), 0u);
  EXPECT_FALSE(empty.nearest_not_excluded(Eigen::Vector3d::Zero(), {}).has_value());
  Eigen::Matrix3Xd bad = Eigen::Matrix3Xd::Zero(3, 4);
  bad(1, 2) = std::numeric_limits<double>::quiet_NaN();
  try {
    const PointIndex index(bad);
    FAIL() << "a NaN point must be rejected";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("point 2"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace quadrix
