// Euclidean clustering of the points left after ground and planes (paper §"Quadric Extraction",
// step 1(c) and key objects): connected components of the graph "closer than the radius".
// Two exact backends: a hash grid with union-find (default; cells of edge r/sqrt(3) are complete
// subgraphs, so only pairs of cells need one witness pair) and PCL's EuclideanClusterExtraction.
#include "fitting/extraction.h"
#include "fitting/extraction_internal.h"

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/extract_clusters.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_map>

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

std::vector<std::vector<std::uint32_t>> grid_clusters(const Eigen::Matrix3Xd& points,
                                                      const std::vector<std::uint32_t>& candidates, double radius) {
  const double cell = radius / std::sqrt(3.0);
  const double inverse = 1.0 / cell;
  const double radius_squared = radius * radius;
  struct Cell {
    Eigen::Vector3i coordinate;
    std::vector<std::uint32_t> members;  // positions in `candidates`
  };
  std::vector<Cell> cells;
  std::unordered_map<std::uint64_t, std::uint32_t> cell_of_key;
  cell_of_key.reserve(candidates.size() / 2 + 16);
  for (std::uint32_t i = 0; i < candidates.size(); ++i) {
    const Eigen::Vector3i c((points.col(candidates[i]) * inverse).array().floor().cast<int>());
    auto [it, inserted] = cell_of_key.try_emplace(detail::voxel_key(c.x(), c.y(), c.z()), static_cast<std::uint32_t>(cells.size()));
    if (inserted) cells.push_back({c, {}});
    cells[it->second].members.push_back(i);
  }
  // Points in one cell are within the radius of each other: cells are the union-find items.
  UnionFind sets(cells.size());
  for (std::uint32_t a = 0; a < cells.size(); ++a) {
    const Cell& first = cells[a];
    for (int dx = -2; dx <= 2; ++dx)
      for (int dy = -2; dy <= 2; ++dy)
        for (int dz = -2; dz <= 2; ++dz) {
          const Eigen::Vector3i c = first.coordinate + Eigen::Vector3i(dx, dy, dz);
          const auto it = cell_of_key.find(detail::voxel_key(c.x(), c.y(), c.z()));
          if (it == cell_of_key.end() || it->second <= a) continue;
          const std::uint32_t b = it->second;
          if (sets.find(a) == sets.find(b)) continue;
          // Cells closer than the radius at their nearest corners may hold a witness pair.
          const Eigen::Vector3i gap = (Eigen::Vector3i(std::abs(dx), std::abs(dy), std::abs(dz)).array() - 1).cwiseMax(0);
          if (gap.cast<double>().squaredNorm() * cell * cell > radius_squared) continue;
          bool joined = false;
          for (const std::uint32_t i : first.members) {
            const Eigen::Vector3d p = points.col(candidates[i]);
            for (const std::uint32_t j : cells[b].members)
              if ((points.col(candidates[j]) - p).squaredNorm() <= radius_squared) {
                joined = true;
                break;
              }
            if (joined) break;
          }
          if (joined) sets.unite(a, b);
        }
  }
  std::unordered_map<std::uint32_t, std::uint32_t> cluster_of_root;
  std::vector<std::vector<std::uint32_t>> clusters;
  for (std::uint32_t a = 0; a < cells.size(); ++a) {
    const std::uint32_t root = sets.find(a);
    auto [it, inserted] = cluster_of_root.try_emplace(root, static_cast<std::uint32_t>(clusters.size()));
    if (inserted) clusters.emplace_back();
    for (const std::uint32_t i : cells[a].members) clusters[it->second].push_back(candidates[i]);
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
