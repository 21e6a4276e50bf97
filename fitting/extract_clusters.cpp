// Euclidean clustering of the points left after ground and planes (paper §"Quadric Extraction",
// step 1(c) and key objects): connected components of the graph "closer than the radius".
// Two exact backends: a sorted grid with union-find (default; cells of edge r/sqrt(3) are complete
// subgraphs, so only pairs of cells need one witness pair) and PCL's EuclideanClusterExtraction.
#include "fitting/extraction.h"
#include "fitting/extraction_internal.h"
#include "geometry/voxel_cells.h"

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/extract_clusters.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace quadrix {
namespace {

/// The candidates sorted by cell: cells are runs of points, columns (x, y) are runs of cells ordered by z.
struct CellGrid {
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed;  // (cell key, position in candidates), sorted
  Eigen::Matrix3Xd sorted;                  // coordinates in sorted order
  std::vector<std::uint32_t> first;         // cell c holds sorted points [first[c], first[c + 1])
  std::vector<std::uint32_t> column_first;  // column k holds cells [column_first[k], column_first[k + 1])
  std::vector<Eigen::Vector3i> coordinate;  // integer cell coordinates
  std::vector<Eigen::AlignedBox3d> box;     // bounding box of each cell's points
  std::size_t cells = 0, columns = 0;
};

/// Sorts the candidates by cell key (x, then y, then z), so each cell is one contiguous run.
std::vector<std::pair<std::uint64_t, std::uint32_t>> sort_by_cell(const Eigen::Matrix3Xd& points,
                                                                   const std::vector<std::uint32_t>& candidates,
                                                                   double inverse) {
  const std::size_t count = candidates.size();
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(count);
  for (std::uint32_t i = 0; i < count; ++i) {
    const Eigen::Vector3d p = points.col(candidates[i]);
    keyed[i] = {detail::voxel_key(static_cast<std::int64_t>(std::floor(p.x() * inverse)),
                                  static_cast<std::int64_t>(std::floor(p.y() * inverse)),
                                  static_cast<std::int64_t>(std::floor(p.z() * inverse))),
                i};
  }
  std::sort(keyed.begin(), keyed.end());
  return keyed;
}

/// Builds the cell and column runs with each cell's box from the sorted candidates.
CellGrid build_cell_grid(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& candidates, double inverse) {
  CellGrid grid;
  grid.keyed = sort_by_cell(points, candidates, inverse);
  const std::size_t count = candidates.size();
  grid.sorted.resize(3, static_cast<Eigen::Index>(count));
  grid.first.reserve(count / 2 + 1);
  for (std::size_t i = 0; i < count; ++i) {
    const Eigen::Vector3d p = points.col(candidates[grid.keyed[i].second]);
    grid.sorted.col(static_cast<Eigen::Index>(i)) = p;
    if (i > 0 && grid.keyed[i].first == grid.keyed[i - 1].first) {
      grid.box.back().extend(p);
      continue;
    }
    const Eigen::Vector3i c(static_cast<int>(std::floor(p.x() * inverse)), static_cast<int>(std::floor(p.y() * inverse)),
                            static_cast<int>(std::floor(p.z() * inverse)));
    if (grid.coordinate.empty() || c.head<2>() != grid.coordinate.back().head<2>())
      grid.column_first.push_back(static_cast<std::uint32_t>(grid.first.size()));
    grid.first.push_back(static_cast<std::uint32_t>(i));
    grid.coordinate.push_back(c);
    grid.box.emplace_back(p, p);
  }
  grid.cells = grid.first.size();
  grid.columns = grid.column_first.size();
  grid.first.push_back(static_cast<std::uint32_t>(count));
  grid.column_first.push_back(static_cast<std::uint32_t>(grid.cells));
  return grid;
}

/// Joins cells a and b when a pair of their points is closer than the radius; the boxes settle most pairs.
void join_if_close(const CellGrid& grid, std::uint32_t a, std::uint32_t b, double radius_squared, detail::UnionFind& sets) {
  if (sets.find(a) == sets.find(b)) return;
  // Box-to-box distance bounds the distance of every pair of their points.
  const Eigen::Vector3d gap =
      (grid.box[a].min() - grid.box[b].max()).cwiseMax(grid.box[b].min() - grid.box[a].max()).cwiseMax(0.0);
  if (gap.squaredNorm() > radius_squared) return;
  if (grid.box[a].merged(grid.box[b]).diagonal().squaredNorm() <= radius_squared) {
    sets.unite(a, b);
    return;
  }
  for (std::uint32_t i = grid.first[a]; i < grid.first[a + 1]; ++i) {
    const Eigen::Vector3d p = grid.sorted.col(i);
    for (std::uint32_t j = grid.first[b]; j < grid.first[b + 1]; ++j)
      if ((grid.sorted.col(j) - p).squaredNorm() <= radius_squared) {
        sets.unite(a, b);
        return;
      }
  }
}

/// Joins cells within reach (|dx|, |dy|, |dz| <= 2), each pair once: a hash lookup per column pair, a merge along z.
void join_neighbouring_cells(const CellGrid& grid, double radius_squared, detail::UnionFind& sets) {
  CellMap<std::uint32_t> column_table(grid.columns);  // voxel_key of a column (z = 0) -> its index
  for (std::uint32_t k = 0; k < grid.columns; ++k) {
    const Eigen::Vector3i& c = grid.coordinate[grid.column_first[k]];
    column_table[detail::voxel_key(c.x(), c.y(), 0)] = k;
  }
  // Neighbouring columns "after" this one ((dx, dy) lexicographically positive), each pair of
  // columns once; the column itself is handled with dz > 0.
  std::vector<Eigen::Vector2i> forward;
  for (int dx = 0; dx <= 2; ++dx)
    for (int dy = -2; dy <= 2; ++dy)
      if (dx > 0 || dy > 0) forward.emplace_back(dx, dy);
  const std::vector<Eigen::Vector3i>& coordinate = grid.coordinate;
  for (std::uint32_t k = 0; k < grid.columns; ++k) {
    const std::uint32_t begin = grid.column_first[k], end = grid.column_first[k + 1];
    for (std::uint32_t a = begin; a < end; ++a)
      for (std::uint32_t b = a + 1; b < end && coordinate[b].z() - coordinate[a].z() <= 2; ++b)
        join_if_close(grid, a, b, radius_squared, sets);
    const Eigen::Vector3i& c = coordinate[begin];
    for (const Eigen::Vector2i& offset : forward) {
      const std::uint32_t* found = column_table.find(detail::voxel_key(c.x() + offset.x(), c.y() + offset.y(), 0));
      if (!found) continue;
      const std::uint32_t other_begin = grid.column_first[*found];
      const std::uint32_t other_end = grid.column_first[*found + 1];
      std::uint32_t low = other_begin;  // first cell of the other column not below z - 2 (z rises with a)
      for (std::uint32_t a = begin; a < end; ++a) {
        const int z = coordinate[a].z();
        while (low < other_end && coordinate[low].z() < z - 2) ++low;
        for (std::uint32_t b = low; b < other_end && coordinate[b].z() <= z + 2; ++b)
          join_if_close(grid, a, b, radius_squared, sets);
      }
    }
  }
}

/// The candidates of each set of joined cells, clusters in order of their first cell.
std::vector<std::vector<std::uint32_t>> collect_clusters(const CellGrid& grid, const std::vector<std::uint32_t>& candidates,
                                                         detail::UnionFind& sets) {
  std::vector<std::int32_t> cluster_of_root(grid.cells, -1);
  std::vector<std::vector<std::uint32_t>> clusters;
  for (std::uint32_t a = 0; a < grid.cells; ++a) {
    const std::uint32_t root = sets.find(a);
    if (cluster_of_root[root] < 0) {
      cluster_of_root[root] = static_cast<std::int32_t>(clusters.size());
      clusters.emplace_back();
    }
    auto& cluster = clusters[static_cast<std::size_t>(cluster_of_root[root])];
    for (std::uint32_t i = grid.first[a]; i < grid.first[a + 1]; ++i) cluster.push_back(candidates[grid.keyed[i].second]);
  }
  return clusters;
}

// Cells of edge r / sqrt(3) are complete subgraphs of the "closer than r" graph, so clusters are
// connected components of cells, and two cells join when one witness pair is closer than r. The
// points are sorted by cell key (x, then y, then z) once, so cells are runs of one contiguous array
// and the cells of one vertical column (x, y) are runs of the cell list, ordered by z. Each pair of
// cells within reach (|dx|, |dy|, |dz| <= 2) is visited once: one hash lookup per pair of columns,
// then a merge along z. The cells' bounding boxes settle most pairs without looking at points:
// boxes farther apart than r never join, boxes whose union fits in a ball of diameter r always do.
std::vector<std::vector<std::uint32_t>> grid_clusters(const Eigen::Matrix3Xd& points,
                                                      const std::vector<std::uint32_t>& candidates, double radius) {
  const double cell = radius / std::sqrt(3.0);
  const CellGrid grid = build_cell_grid(points, candidates, 1.0 / cell);
  detail::UnionFind sets(grid.cells);
  join_neighbouring_cells(grid, radius * radius, sets);
  return collect_clusters(grid, candidates, sets);
}

std::vector<std::vector<std::uint32_t>> pcl_clusters(const Eigen::Matrix3Xd& points,
                                                     const std::vector<std::uint32_t>& candidates,
                                                     const ClusterOptions& options) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  cloud->resize(candidates.size());
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const Eigen::Vector3d p = points.col(candidates[i]);
    (*cloud)[i] = pcl::PointXYZ(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
  }
  pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
  tree->setInputCloud(cloud);
  pcl::EuclideanClusterExtraction<pcl::PointXYZ> extraction;
  extraction.setClusterTolerance(options.radius);
  extraction.setMinClusterSize(1);
  extraction.setMaxClusterSize(static_cast<pcl::uindex_t>(candidates.size()));
  extraction.setSearchMethod(tree);
  extraction.setInputCloud(cloud);
  std::vector<pcl::PointIndices> found;
  extraction.extract(found);
  std::vector<std::vector<std::uint32_t>> clusters;
  for (const auto& indices : found) {
    clusters.emplace_back();
    for (const auto i : indices.indices) clusters.back().push_back(candidates[static_cast<std::size_t>(i)]);
  }
  return clusters;
}

}  // namespace

std::vector<std::vector<std::uint32_t>> euclidean_clusters(const Eigen::Matrix3Xd& points,
                                                           const std::vector<std::uint32_t>& candidates,
                                                           const ClusterOptions& options) {
  if (candidates.empty() || !(options.radius > 0.0)) return {};
  std::vector<std::vector<std::uint32_t>> clusters = options.method == ClusterMethod::Grid
                                                         ? grid_clusters(points, candidates, options.radius)
                                                         : pcl_clusters(points, candidates, options);
  clusters.erase(std::remove_if(clusters.begin(), clusters.end(),
                                [&](const std::vector<std::uint32_t>& cluster) {
                                  return static_cast<int>(cluster.size()) < options.minimum_points ||
                                         static_cast<int>(cluster.size()) > options.maximum_points;
                                }),
                 clusters.end());
  for (auto& cluster : clusters) std::sort(cluster.begin(), cluster.end());
  std::stable_sort(clusters.begin(), clusters.end(),
                   [](const auto& a, const auto& b) { return a.size() != b.size() ? a.size() > b.size() : a.front() < b.front(); });
  return clusters;
}

}  // namespace quadrix
