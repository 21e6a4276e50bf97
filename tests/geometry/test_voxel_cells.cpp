// The isolated-point rule (geometry/voxel_cells.h) on hand-placed points whose answer is known,
// and on a scanned surface with uniform strays added; the flat cell map against std::map on random
// cells.
#include "geometry/voxel_cells.h"

#include "geometry/error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <map>
#include <set>

namespace quadrix {
namespace {

TEST(VoxelCells, NeighbouringCellsHaveDistinctKeysOnBothSidesOfZero) {
  std::set<std::uint64_t> keys;
  for (int x = -2; x <= 2; ++x)
    for (int y = -2; y <= 2; ++y)
      for (int z = -2; z <= 2; ++z) keys.insert(cell_key(Eigen::Vector3i(x, y, z)));
  EXPECT_EQ(keys.size(), 125u);
}

TEST(VoxelCells, TheCellMapHoldsWhatAnOrderedMapHoldsThroughEveryGrowth) {
  // Cells clustered like a scan's (neighbours share high key bits) and some far apart; the map
  // starts small so it grows many times. Every insertion, count and lookup must match std::map.
  std::mt19937 random(7);
  std::uniform_int_distribution<int> near(-40, 40), far(-1000000, 1000000);
  CellMap<std::uint32_t> counts(4);
  std::map<std::uint64_t, std::uint32_t> reference;
  for (int k = 0; k < 60000; ++k) {
    const Eigen::Vector3i cell = k % 10 == 0 ? Eigen::Vector3i(far(random), far(random), far(random))
                                             : Eigen::Vector3i(near(random), near(random), near(random) / 8);
    const std::uint64_t key = cell_key(cell);
    const bool absent = reference.find(key) == reference.end();
    if (k % 3 == 0) {
      EXPECT_EQ(counts.insert(key), absent);
      reference[key];
    } else {
      ++counts[key];
      ++reference[key];
    }
  }
  EXPECT_EQ(counts.size(), reference.size());
  for (const auto& [key, count] : reference) {
    const std::uint32_t* found = counts.find(key);
    ASSERT_NE(found, nullptr);
    EXPECT_EQ(*found, count);
  }
  std::size_t visited = 0;
  counts.for_each([&](std::uint64_t key, std::uint32_t count) {
    ++visited;
    EXPECT_EQ(reference.at(key), count);
  });
  EXPECT_EQ(visited, reference.size());
  for (int x = 41; x < 1000; ++x) {  // beyond the clustered cells: absent unless a far draw hit it
    const std::uint64_t key = cell_key(Eigen::Vector3i(x, 0, 0));
    EXPECT_EQ(counts.find(key) != nullptr, reference.count(key) == 1);
  }
}

TEST(VoxelCells, APointIsKeptWhenAnotherCandidateLiesInItsCubeOrTheTwentySixAround) {
  // Cubes of 1 m. Columns: 0 and 1 share a cube; 2 is in the cube diagonally next to 1's; 3 is two
  // cubes from everything; 4 is not finite; 5 sits beside 3 but is no candidate.
  Eigen::Matrix3Xd points(3, 6);
  points.col(0) << 0.1, 0.1, 0.1;
  points.col(1) << 0.9, 0.9, 0.9;
  points.col(2) << 1.5, 1.5, 1.5;
  points.col(3) << 4.5, 0.5, 0.5;
  points.col(4) << std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0;
  points.col(5) << 5.5, 0.5, 0.5;
  EXPECT_EQ(accompanied_points(points, {0, 1, 2, 3, 4}, 1.0), (std::vector<std::uint32_t>{0, 1, 2}));
  // Candidates keep their order, and only candidates keep each other company.
  EXPECT_EQ(accompanied_points(points, {5, 2, 3, 1}, 1.0), (std::vector<std::uint32_t>{5, 2, 3, 1}));
  EXPECT_EQ(accompanied_points(points, {2, 3}, 1.0), (std::vector<std::uint32_t>{}));
  // A smaller cube separates 1 from 2 (0.6 m apart along each axis, two 0.25 m cubes between).
  EXPECT_EQ(accompanied_points(points, {1, 2}, 0.25), (std::vector<std::uint32_t>{}));
  // Asking for two neighbours: 0, 1 and 2 have two each within their blocks; with 2 gone, 0 and 1
  // keep only each other.
  EXPECT_EQ(accompanied_points(points, {0, 1, 2, 3}, 1.0, 2), (std::vector<std::uint32_t>{0, 1, 2}));
  EXPECT_EQ(accompanied_points(points, {0, 1, 3}, 1.0, 2), (std::vector<std::uint32_t>{}));
  EXPECT_EQ(accompanied_points(points, {0, 1, 3}, 1.0, 1), (std::vector<std::uint32_t>{0, 1}));
  EXPECT_THROW(accompanied_points(points, {0, 1}, 1.0, 0), Error);
  EXPECT_TRUE(accompanied_points(points, {}, 1.0).empty());
  EXPECT_THROW(accompanied_points(points, {0, 1}, 0.0), Error);
  EXPECT_THROW(accompanied_points(points, {0, 1}, -1.0), Error);
}

TEST(VoxelCells, StraysAroundAScannedWallAreLeftOutAndTheWallKept) {
  // A 10 x 2 m wall sampled every 5 cm (a scan line's spacing at 15 m), and strays drawn uniformly
  // in a 40 m box around it: sparse enough (one per 64 m^3) that few keep each other company.
  std::mt19937_64 engine(11);
  std::uniform_real_distribution<double> across(-20.0, 20.0);
  PointCloud cloud;
  const int wall = 200 * 40, strays = 1000;
  cloud.positions.resize(3, wall + strays);
  for (int i = 0; i < wall; ++i) cloud.positions.col(i) = Eigen::Vector3f(0.05f * static_cast<float>(i % 200), 3.0f, 0.05f * static_cast<float>(i / 200));
  for (int i = 0; i < strays; ++i) cloud.positions.col(wall + i) = Eigen::Vector3d(across(engine), across(engine), across(engine)).cast<float>();
  std::vector<std::uint32_t> all(static_cast<std::size_t>(wall + strays));
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<std::uint32_t>(i);
  const std::vector<std::uint32_t> kept = accompanied_points(cloud.positions.cast<double>(), all, 0.3);
  std::size_t wall_kept = 0;
  for (const std::uint32_t index : kept) wall_kept += index < static_cast<std::uint32_t>(wall);
  EXPECT_EQ(wall_kept, static_cast<std::size_t>(wall));
  // A stray keeps company when another point lies in its block of 27 cubes (0.73 m^3): another
  // stray for about 1.1% of them, the wall for about 0.1% (a 12 x 2 x 4 m box around it).
  const std::size_t strays_kept = kept.size() - wall_kept;
  EXPECT_LT(strays_kept, static_cast<std::size_t>(0.05 * strays)) << strays_kept;
  // The cloud form gives the same points, positions only.
  const PointCloud filtered = without_isolated_points(cloud, 0.3);
  ASSERT_EQ(filtered.size(), kept.size());
  EXPECT_TRUE(filtered.positions.col(0).isApprox(cloud.positions.col(static_cast<Eigen::Index>(kept[0]))));
  EXPECT_TRUE(filtered.positions.rightCols(1).isApprox(cloud.positions.col(static_cast<Eigen::Index>(kept.back()))));
}

}  // namespace
}  // namespace quadrix
