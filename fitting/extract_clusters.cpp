// Euclidean clustering of the points left after ground and planes (paper §"Quadric Extraction",
// step 1(c) and key objects): connected components of the graph "closer than the radius".
// Two exact backends: a sorted grid with union-find (default; cells of edge r/sqrt(3) are complete
// subgraphs, so only pairs of cells need one witness pair) and PCL's EuclideanClusterExtraction.
#include "fitting/extraction.h"
#include "fitting/extraction_internal.h"

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

class UnionFind {
 public:
  explicit UnionFind(std::size_t size) : parent_(size) { std::iota(parent_.begin(), parent_.end(), 0u); }
  std::uint32_t find(std::uint32_t x) {
    while (parent_[x] != x) {
      parent_[x] = parent_[parent_[x]];
      x = parent_[x];
    }
    return x;
  }
  bool unite(std::uint32_t a, std::uint32_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return false;
    parent_[std::max(a, b)] = std::min(a, b);
    return true;
  }

 private:
  std::vector<std::uint32_t> parent_;
};

// Open-addressing hash table from a cell key to its index (linear probing, power-of-two size, at
// most half full). One flat allocation instead of a node per cell as in std::unordered_map.
class CellTable {
 public:
  explicit CellTable(std::size_t cells) {
    std::size_t size = 16;
    while (size < 2 * cells) size <<= 1;
    mask_ = size - 1;
    keys_.assign(size, kEmpty);
    values_.resize(size);
  }
  void insert(std::uint64_t key, std::uint32_t value) {
    std::size_t slot = hash(key);
    while (keys_[slot] != kEmpty) slot = (slot + 1) & mask_;
    keys_[slot] = key;
    values_[slot] = value;
  }
  /// Index of the cell with `key`, or -1.
  std::int64_t find(std::uint64_t key) const {
    for (std::size_t slot = hash(key);; slot = (slot + 1) & mask_) {
      if (keys_[slot] == key) return values_[slot];
      if (keys_[slot] == kEmpty) return -1;
    }
  }

 private:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t(0);  // voxel_key never sets the top bit
  std::size_t hash(std::uint64_t key) const { return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> 20) & mask_; }
  std::size_t mask_ = 0;
  std::vector<std::uint64_t> keys_;
  std::vector<std::uint32_t> values_;
};

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
  const double inverse = 1.0 / cell;
  const double radius_squared = radius * radius;
  const std::size_t count = candidates.size();
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(count);  // (cell key, position in candidates)
  for (std::uint32_t i = 0; i < count; ++i) {
    const Eigen::Vector3d p = points.col(candidates[i]);
    keyed[i] = {detail::voxel_key(static_cast<std::int64_t>(std::floor(p.x() * inverse)),
                                  static_cast<std::int64_t>(std::floor(p.y() * inverse)),
                                  static_cast<std::int64_t>(std::floor(p.z() * inverse))),
                i};
  }
  std::sort(keyed.begin(), keyed.end());
  // Sorted copy of the coordinates; cell c holds sorted points [first[c], first[c + 1]); column k
  // holds cells [column_first[k], column_first[k + 1]).
  Eigen::Matrix3Xd sorted(3, static_cast<Eigen::Index>(count));
  std::vector<std::uint32_t> first, column_first;
  std::vector<Eigen::Vector3i> coordinate;
  std::vector<Eigen::AlignedBox3d> box;
  first.reserve(count / 2 + 1);
  for (std::size_t i = 0; i < count; ++i) {
    const Eigen::Vector3d p = points.col(candidates[keyed[i].second]);
    sorted.col(static_cast<Eigen::Index>(i)) = p;
    if (i > 0 && keyed[i].first == keyed[i - 1].first) {
      box.back().extend(p);
      continue;
    }
    const Eigen::Vector3i c(static_cast<int>(std::floor(p.x() * inverse)), static_cast<int>(std::floor(p.y() * inverse)),
                            static_cast<int>(std::floor(p.z() * inverse)));
    if (coordinate.empty() || c.head<2>() != coordinate.back().head<2>())
      column_first.push_back(static_cast<std::uint32_t>(first.size()));
    first.push_back(static_cast<std::uint32_t>(i));
    coordinate.push_back(c);
    box.emplace_back(p, p);
  }
  const std::size_t cells = first.size(), columns = column_first.size();
  first.push_back(static_cast<std::uint32_t>(count));
  column_first.push_back(static_cast<std::uint32_t>(cells));
  CellTable column_table(columns);
  for (std::uint32_t k = 0; k < columns; ++k) {
    const Eigen::Vector3i& c = coordinate[column_first[k]];
    column_table.insert(detail::voxel_key(c.x(), c.y(), 0), k);
  }

  UnionFind sets(cells);
  const auto try_join = [&](std::uint32_t a, std::uint32_t b) {
    if (sets.find(a) == sets.find(b)) return;
    // Box-to-box distance bounds the distance of every pair of their points.
    const Eigen::Vector3d gap = (box[a].min() - box[b].max()).cwiseMax(box[b].min() - box[a].max()).cwiseMax(0.0);
    if (gap.squaredNorm() > radius_squared) return;
    if (box[a].merged(box[b]).diagonal().squaredNorm() <= radius_squared) {
      sets.unite(a, b);
      return;
    }
    for (std::uint32_t i = first[a]; i < first[a + 1]; ++i) {
      const Eigen::Vector3d p = sorted.col(i);
      for (std::uint32_t j = first[b]; j < first[b + 1]; ++j)
        if ((sorted.col(j) - p).squaredNorm() <= radius_squared) {
          sets.unite(a, b);
          return;
        }
    }
  };
  // Neighbouring columns "after" this one ((dx, dy) lexicographically positive), each pair of
  // columns once; the column itself is handled with dz > 0.
  std::vector<Eigen::Vector2i> forward;
  for (int dx = 0; dx <= 2; ++dx)
    for (int dy = -2; dy <= 2; ++dy)
      if (dx > 0 || dy > 0) forward.emplace_back(dx, dy);
  for (std::uint32_t k = 0; k < columns; ++k) {
    const std::uint32_t begin = column_first[k], end = column_first[k + 1];
    for (std::uint32_t a = begin; a < end; ++a)
      for (std::uint32_t b = a + 1; b < end && coordinate[b].z() - coordinate[a].z() <= 2; ++b) try_join(a, b);
    const Eigen::Vector3i& c = coordinate[begin];
    for (const Eigen::Vector2i& offset : forward) {
      const std::int64_t found = column_table.find(detail::voxel_key(c.x() + offset.x(), c.y() + offset.y(), 0));
      if (found < 0) continue;
      const std::uint32_t other_begin = column_first[static_cast<std::size_t>(found)];
      const std::uint32_t other_end = column_first[static_cast<std::size_t>(found) + 1];
      std::uint32_t low = other_begin;  // first cell of the other column not below z - 2 (z rises with a)
      for (std::uint32_t a = begin; a < end; ++a) {
        const int z = coordinate[a].z();
        while (low < other_end && coordinate[low].z() < z - 2) ++low;
        for (std::uint32_t b = low; b < other_end && coordinate[b].z() <= z + 2; ++b) try_join(a, b);
      }
    }
  }
  std::vector<std::int32_t> cluster_of_root(cells, -1);
  std::vector<std::vector<std::uint32_t>> clusters;
  for (std::uint32_t a = 0; a < cells; ++a) {
    const std::uint32_t root = sets.find(a);
    if (cluster_of_root[root] < 0) {
      cluster_of_root[root] = static_cast<std::int32_t>(clusters.size());
      clusters.emplace_back();
    }
    auto& cluster = clusters[static_cast<std::size_t>(cluster_of_root[root])];
    for (std::uint32_t i = first[a]; i < first[a + 1]; ++i) cluster.push_back(candidates[keyed[i].second]);
  }
  return clusters;
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
