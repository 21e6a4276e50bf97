// Plane extraction (paper §"Quadric Extraction", step 1(b)): the non-ground points are voxelised,
// each voxel's eigenvalue ratio lambda_2 / lambda_1 decides whether it is planar, and neighbouring
// planar voxels with agreeing normals and nearby centroids are merged by region growing (as in
// G3Reg). The alternative is CGAL's region growing on the point set (cgal_shape_detection.cpp).
#include "fitting/extraction.h"
#include "fitting/extraction_internal.h"
#include "geometry/constants.h"
#include "geometry/voxel_cells.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <queue>
#include <random>
#include <unordered_map>

namespace quadrix {
namespace {

struct Voxel {
  Eigen::Vector3i coordinate;            // integer voxel coordinate
  std::vector<std::uint32_t> members;    // points inside
  detail::Moments moments;               // their moments
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // smallest principal axis
  bool planar = false;                   // passed the eigenvalue-ratio test
  int region = -1;                       // region id while growing
};

}  // namespace

bool detail::plane_is_large_enough(const detail::Moments& moments, std::size_t voxels, const PlaneOptions& options) {
  if (moments.count < options.minimum_plane_points || static_cast<int>(voxels) < options.minimum_plane_voxels) return false;
  const detail::Principal axes = detail::principal_axes(moments.covariance());
  const double length = kStatisticalScaleFactor * std::sqrt(axes.values(2));
  const double width = kStatisticalScaleFactor * std::sqrt(axes.values(1));
  return width >= options.minimum_plane_width && length * width >= options.minimum_plane_area;
}

std::vector<std::uint32_t> detail::dominant_cluster_plane(const Eigen::Matrix3Xd& points,
                                                         const std::vector<std::uint32_t>& cluster,
                                                         const PlaneOptions& options, double minimum_fraction) {
  const std::size_t count = cluster.size();
  if (count < 3 || static_cast<int>(count) < options.minimum_plane_points) return {};
  // RANSAC over point triples (deterministic: the seed mixes in the cluster's first index), then
  // the inliers of the PCA plane of the best hypothesis' inliers.
  std::mt19937_64 engine(0x5DEECE66Dull ^ (0x9E3779B97F4A7C15ull * (cluster.front() + 1)));
  std::uniform_int_distribution<std::size_t> pick(0, count - 1);
  const auto inliers_of = [&](const Eigen::Vector3d& normal, const Eigen::Vector3d& on_plane) {
    std::size_t inliers = 0;
    for (const std::uint32_t index : cluster) inliers += std::abs(normal.dot(points.col(index) - on_plane)) <= options.merge_distance;
    return inliers;
  };
  Eigen::Vector3d best_normal = Eigen::Vector3d::UnitZ(), best_point = points.col(cluster.front());
  std::size_t best = 0;
  for (int iteration = 0; iteration < 60; ++iteration) {
    const Eigen::Vector3d a = points.col(cluster[pick(engine)]), b = points.col(cluster[pick(engine)]),
                          c = points.col(cluster[pick(engine)]);
    const Eigen::Vector3d normal = (b - a).cross(c - a);
    if (!(normal.norm() > 1e-9)) continue;
    const std::size_t inliers = inliers_of(normal.normalized(), a);
    if (inliers > best) {
      best = inliers;
      best_normal = normal.normalized();
      best_point = a;
    }
  }
  if (static_cast<double>(best) < minimum_fraction * static_cast<double>(count)) return {};
  detail::Moments moments;
  for (const std::uint32_t index : cluster)
    if (std::abs(best_normal.dot(points.col(index) - best_point)) <= options.merge_distance) moments.add(points.col(index));
  const detail::Principal axes = detail::principal_axes(moments.covariance());
  const Eigen::Vector3d normal = axes.vectors.col(0), centre = moments.mean();
  std::vector<std::uint32_t> plane;
  detail::Moments plane_moments;
  for (const std::uint32_t index : cluster)
    if (std::abs(normal.dot(points.col(index) - centre)) <= options.merge_distance) {
      plane.push_back(index);
      plane_moments.add(points.col(index));
    }
  const double smallest = std::max(detail::principal_axes(plane_moments.covariance()).values(0), 1e-12);
  const bool flat = detail::principal_axes(plane_moments.covariance()).values(1) > options.eigenvalue_ratio * smallest;
  if (static_cast<double>(plane.size()) < minimum_fraction * static_cast<double>(count) || !flat ||
      !plane_is_large_enough(plane_moments, static_cast<std::size_t>(options.minimum_plane_voxels), options))
    return {};
  return plane;
}

namespace {

// The cluster's indices in ascending order.
std::vector<std::uint32_t> sorted_copy(const std::vector<std::uint32_t>& cluster) {
  std::vector<std::uint32_t> sorted = cluster;
  std::sort(sorted.begin(), sorted.end());
  return sorted;
}

// Whether the planes are faces of one convex solid: every plane has (nearly) all the cluster on
// one side of it, and one of them is a roof (normal within 30 degrees of up). Walls around a recess
// are not: they stand upright, and a jamb has the facade on one side and the back wall on the other.
bool encloses_a_solid(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& cluster,
                      const std::vector<std::vector<std::uint32_t>>& planes, double distance, const Eigen::Vector3d& up) {
  const double tolerance = 0.05 * static_cast<double>(cluster.size());
  bool has_roof = false;
  for (const std::vector<std::uint32_t>& plane : planes) {
    detail::Moments moments;
    for (const std::uint32_t index : plane) moments.add(points.col(index));
    const Eigen::Vector3d normal = detail::principal_axes(moments.covariance()).vectors.col(0), centre = moments.mean();
    std::size_t in_front = 0, behind = 0;
    for (const std::uint32_t index : cluster) {
      const double offset = normal.dot(points.col(index) - centre);
      in_front += offset > distance;
      behind += offset < -distance;
    }
    if (static_cast<double>(std::min(in_front, behind)) > tolerance) return false;
    has_roof = has_roof || std::abs(normal.dot(up)) > std::cos(30.0 * kPi / 180.0);
  }
  return has_roof;
}

}  // namespace

std::vector<std::vector<std::uint32_t>> cluster_planes(const Eigen::Matrix3Xd& points,
                                                       const std::vector<std::uint32_t>& cluster,
                                                       const PlaneOptions& options, const Eigen::Vector3d& up) {
  // A cluster's walls are the parts a spinning LiDAR saw of them (a narrow band of beams, broken by
  // occlusion), so they get their own, smaller size tests.
  PlaneOptions piece = options;
  piece.minimum_plane_width = options.cluster_plane_width;
  piece.minimum_plane_area = options.cluster_plane_area;
  piece.merge_distance = options.cluster_plane_distance;
  std::vector<std::vector<std::uint32_t>> planes;
  std::vector<std::uint32_t> rest = sorted_copy(cluster);
  std::size_t covered = 0;
  while (static_cast<int>(rest.size()) >= options.minimum_plane_points) {
    std::vector<std::uint32_t> plane = detail::dominant_cluster_plane(points, rest, piece, options.cluster_plane_share);
    if (plane.empty()) break;
    // Only upright walls get the smaller size tests; a tilted or level piece (terrain, a roof) needs the full ones.
    detail::Moments moments;
    for (const std::uint32_t index : plane) moments.add(points.col(index));
    const bool upright = std::abs(detail::principal_axes(moments.covariance()).vectors.col(0).dot(up.normalized())) <
                         std::sin(options.cluster_plane_tilt_deg * kPi / 180.0);
    if (!upright && !detail::plane_is_large_enough(moments, static_cast<std::size_t>(options.minimum_plane_voxels), options)) break;
    std::vector<std::uint32_t> left;
    std::set_difference(rest.begin(), rest.end(), plane.begin(), plane.end(), std::back_inserter(left));
    rest = std::move(left);
    covered += plane.size();
    planes.push_back(std::move(plane));
  }
  if (static_cast<double>(covered) < options.cluster_plane_coverage * static_cast<double>(cluster.size())) return {};
  if (planes.size() >= 2 && encloses_a_solid(points, cluster, planes, piece.merge_distance, up.normalized())) {
    // A car or a box: its faces are planes, but it is one object. Only a wall holding most of the
    // cluster (with the full size tests) is taken from it.
    std::vector<std::uint32_t> wall =
        detail::dominant_cluster_plane(points, sorted_copy(cluster), options, options.cluster_plane_coverage);
    if (wall.empty()) return {};
    return {std::move(wall)};
  }
  std::stable_sort(planes.begin(), planes.end(), [](const auto& a, const auto& b) { return a.size() > b.size(); });
  return planes;
}

namespace {

// The candidates in voxels of options.voxel_size, each with its points' moments.
struct VoxelGrid {
  std::vector<Voxel> voxels;
  CellMap<int> voxel_of_key;

  // Index of the voxel at integer coordinate `c`, or -1.
  int find(const Eigen::Vector3i& c) const {
    const int* found = voxel_of_key.find(detail::voxel_key(c.x(), c.y(), c.z()));
    return found ? *found : -1;
  }
};

VoxelGrid build_voxels(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& candidates, double voxel_size) {
  VoxelGrid grid;
  grid.voxel_of_key = CellMap<int>(candidates.size() / 4 + 16);
  const double inverse = 1.0 / voxel_size;
  for (const std::uint32_t index : candidates) {
    const Eigen::Vector3d p = points.col(index);
    const Eigen::Vector3i c((p * inverse).array().floor().cast<int>());
    const std::uint64_t key = detail::voxel_key(c.x(), c.y(), c.z());
    const auto [id, inserted] = grid.voxel_of_key.try_emplace(key, static_cast<int>(grid.voxels.size()));
    if (inserted) {
      grid.voxels.emplace_back();
      grid.voxels.back().coordinate = c;
    }
    Voxel& voxel = grid.voxels[static_cast<std::size_t>(id)];
    voxel.members.push_back(index);
    voxel.moments.add(p);
  }
  return grid;
}

// Eigenvalue-ratio test per voxel (ratio of the second smallest to the smallest eigenvalue): marks
// planar voxels with their normals and returns them, largest first (the seeds of region growing).
std::vector<int> planar_voxels_by_size(std::vector<Voxel>& voxels, const PlaneOptions& options) {
  std::vector<int> planar_order;
  for (int id = 0; id < static_cast<int>(voxels.size()); ++id) {
    Voxel& voxel = voxels[id];
    if (static_cast<int>(voxel.members.size()) < options.minimum_voxel_points) continue;
    const detail::Principal axes = detail::principal_axes(voxel.moments.covariance());
    const double smallest = std::max(axes.values(0), 1e-12 * options.voxel_size * options.voxel_size);
    voxel.planar = axes.values(1) > options.eigenvalue_ratio * smallest && axes.values(1) > 0.05 * axes.values(2);
    voxel.normal = axes.vectors.col(0);
    if (voxel.planar) planar_order.push_back(id);
  }
  std::sort(planar_order.begin(), planar_order.end(),
            [&](int a, int b) { return voxels[a].members.size() > voxels[b].members.size(); });
  return planar_order;
}

// Grows region `region` from planar voxel `seed` over 26-neighbours whose normal agrees within
// normal_cosine and whose centroid lies within merge_distance of the growing plane (refitted after
// every voxel). Returns the region's voxels; `moments` ends as the region's points' moments.
std::vector<int> grow_plane_region(VoxelGrid& grid, int seed, int region, const PlaneOptions& options,
                                   detail::Moments& moments) {
  std::vector<Voxel>& voxels = grid.voxels;
  moments = voxels[seed].moments;
  Eigen::Vector3d normal = voxels[seed].normal;
  Eigen::Vector3d center = moments.mean();
  std::vector<int> members = {seed};
  voxels[seed].region = region;
  std::queue<int> queue;
  queue.push(seed);
  while (!queue.empty()) {
    const Eigen::Vector3i coordinate = voxels[queue.front()].coordinate;
    queue.pop();
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          if (dx == 0 && dy == 0 && dz == 0) continue;
          const int id = grid.find(coordinate + Eigen::Vector3i(dx, dy, dz));
          if (id < 0) continue;
          Voxel& neighbour = voxels[id];
          if (!neighbour.planar || neighbour.region >= 0) continue;
          if (std::abs(neighbour.normal.dot(normal)) < options.normal_cosine) continue;
          if (std::abs(normal.dot(neighbour.moments.mean() - center)) > options.merge_distance) continue;
          neighbour.region = region;
          members.push_back(id);
          queue.push(id);
          moments.add(neighbour.moments);
          normal = detail::principal_axes(moments.covariance()).vectors.col(0);
          center = moments.mean();
        }
  }
  return members;
}

// Point-level completion: points of non-planar voxels touching `plane` (wall bottoms, edges, voxels
// split by a boundary) join it when they lie within the merge distance of its final plane.
void absorb_touching_points(const Eigen::Matrix3Xd& points, const VoxelGrid& grid, const std::vector<char>& in_plane,
                            int region, double merge_distance, Element& plane,
                            std::unordered_map<std::uint32_t, char>& absorbed) {
  detail::Moments moments;
  for (const std::uint32_t index : plane.point_indices) moments.add(points.col(index));
  const Eigen::Vector3d normal = detail::principal_axes(moments.covariance()).vectors.col(0);
  const Eigen::Vector3d center = moments.mean();
  std::vector<int> touched;
  for (std::size_t id = 0; id < grid.voxels.size(); ++id) {
    if (!in_plane[id] || grid.voxels[id].region != region) continue;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const int neighbour = grid.find(grid.voxels[id].coordinate + Eigen::Vector3i(dx, dy, dz));
          if (neighbour >= 0 && !in_plane[neighbour]) touched.push_back(neighbour);
        }
  }
  std::sort(touched.begin(), touched.end());
  touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
  for (const int id : touched)
    for (const std::uint32_t index : grid.voxels[id].members) {
      if (absorbed.count(index) != 0) continue;
      if (std::abs(normal.dot(points.col(index) - center)) > merge_distance) continue;
      absorbed[index] = 1;
      plane.point_indices.push_back(index);
    }
}

std::vector<Element> voxel_region_growing(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& candidates,
                                          const PlaneOptions& options, std::vector<std::uint32_t>& remaining) {
  VoxelGrid grid = build_voxels(points, candidates, options.voxel_size);
  std::vector<Voxel>& voxels = grid.voxels;
  const std::vector<int> planar_order = planar_voxels_by_size(voxels, options);

  std::vector<Element> planes;
  std::vector<char> in_plane(voxels.size(), 0);
  std::vector<int> plane_regions;  // region id of each accepted plane
  int region_id = 0;
  for (const int seed : planar_order) {
    if (voxels[seed].region >= 0) continue;
    const int region = region_id++;
    detail::Moments moments;
    const std::vector<int> members = grow_plane_region(grid, seed, region, options, moments);
    if (!detail::plane_is_large_enough(moments, members.size(), options)) continue;  // voxels go back to clustering
    Element plane;
    plane.element_class = ElementClass::Plane;
    for (const int id : members) {
      in_plane[id] = 1;
      plane.point_indices.insert(plane.point_indices.end(), voxels[id].members.begin(), voxels[id].members.end());
    }
    planes.push_back(std::move(plane));
    plane_regions.push_back(region);
  }
  std::unordered_map<std::uint32_t, char> absorbed;
  for (std::size_t p = 0; p < planes.size(); ++p)
    absorb_touching_points(points, grid, in_plane, plane_regions[p], options.merge_distance, planes[p], absorbed);
  remaining.clear();
  for (std::size_t id = 0; id < voxels.size(); ++id)
    if (!in_plane[id])
      for (const std::uint32_t index : voxels[id].members)
        if (absorbed.count(index) == 0) remaining.push_back(index);
  return planes;
}

}  // namespace

std::vector<Element> extract_planes(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& candidates,
                                    const PlaneOptions& options, std::vector<std::uint32_t>& remaining) {
  if (candidates.empty()) {
    remaining.clear();
    return {};
  }
  if (options.method == PlaneMethod::VoxelRegionGrowing) return voxel_region_growing(points, candidates, options, remaining);

  const std::vector<std::vector<std::uint32_t>> regions = detail::cgal_region_growing_planes(points, candidates, options);
  std::vector<char> in_plane(static_cast<std::size_t>(points.cols()), 0);
  std::vector<Element> planes;
  for (const auto& region : regions) {
    detail::Moments moments;
    for (const std::uint32_t index : region) moments.add(points.col(index));
    // A region spanning the minimum voxel count of the voxel method: its width already covers it.
    if (!detail::plane_is_large_enough(moments, static_cast<std::size_t>(options.minimum_plane_voxels), options)) continue;
    Element plane;
    plane.element_class = ElementClass::Plane;
    plane.point_indices = region;
    for (const std::uint32_t index : region) in_plane[index] = 1;
    planes.push_back(std::move(plane));
  }
  remaining.clear();
  for (const std::uint32_t index : candidates)
    if (!in_plane[index]) remaining.push_back(index);
  return planes;
}

}  // namespace quadrix
