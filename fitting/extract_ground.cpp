// Ground segmentation (paper §"Quadric Extraction", step 1(a); the paper uses TRAVEL, we use a
// concentric-zone patch model in the spirit of Patchwork, with continuity-checked region growing
// over patches in the spirit of TRAVEL's traversable-ground graph). See GroundOptions for the steps.
#include "fitting/extraction.h"
#include "fitting/extraction_internal.h"
#include "geometry/constants.h"

#include <algorithm>
#include <cmath>

namespace quadrix {
namespace {


struct Patch {
  std::vector<std::uint32_t> members;        // candidate points in the patch
  std::vector<std::uint32_t> inliers;        // ground points of the fitted plane
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // local frame, up-oriented
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero(); // local frame
  bool candidate = false;                    // passed the per-patch tests
  bool accepted = false;                     // connected to the ground component
};

// Height of the patch plane at local horizontal position (x, y).
double plane_height(const Patch& patch, double x, double y) {
  const Eigen::Vector3d& n = patch.normal;
  return patch.centroid.z() - (n.x() * (x - patch.centroid.x()) + n.y() * (y - patch.centroid.y())) / n.z();
}

// Rotation into the local frame: rows e1, e2 horizontal, e3 = up.
Eigen::Matrix3d local_frame(const Eigen::Vector3d& up) {
  const Eigen::Vector3d helper = std::abs(up.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d e1 = (helper - helper.dot(up) * up).normalized();
  const Eigen::Vector3d e2 = up.cross(e1);
  Eigen::Matrix3d to_local;
  to_local.row(0) = e1.transpose();
  to_local.row(1) = e2.transpose();
  to_local.row(2) = up.transpose();
  return to_local;
}

// The concentric-zone patches (rings by GroundOptions::ring_edges, sectors per ring growing outwards)
// with their candidate points, each candidate's patch (-1 outside the rings) and local coordinates.
struct PatchGrid {
  std::vector<Patch> patches;
  std::vector<int> point_patch;  // per candidate
  Eigen::Matrix3Xd local;        // per cloud point (filled for candidates only)
};

PatchGrid assign_patches(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& candidates,
                         const GroundOptions& options, const Eigen::Vector3d& sensor_origin, const Eigen::Matrix3d& to_local) {
  const int ring_count = static_cast<int>(options.ring_edges.size()) - 1;
  std::vector<int> sectors(ring_count), ring_offset(ring_count + 1, 0);
  for (int ring = 0; ring < ring_count; ++ring) {
    sectors[ring] = std::min(options.sectors_max, options.sectors_near * (ring + 1));
    ring_offset[ring + 1] = ring_offset[ring] + sectors[ring];
  }
  PatchGrid grid;
  grid.patches.resize(ring_offset[ring_count]);
  grid.local.resize(3, points.cols());
  grid.point_patch.assign(candidates.size(), -1);
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const Eigen::Vector3d p = to_local * (points.col(candidates[i]) - sensor_origin);
    grid.local.col(candidates[i]) = p;
    const double radius = std::hypot(p.x(), p.y());
    const auto edge = std::upper_bound(options.ring_edges.begin(), options.ring_edges.end(), radius);
    const int ring = static_cast<int>(edge - options.ring_edges.begin()) - 1;
    if (ring < 0 || ring >= ring_count) continue;
    const double angle = std::atan2(p.y(), p.x()) + kPi;
    const int sector = std::min(sectors[ring] - 1, static_cast<int>(angle / (2.0 * kPi) * sectors[ring]));
    grid.point_patch[i] = ring_offset[ring] + sector;
    grid.patches[grid.point_patch[i]].members.push_back(candidates[i]);
  }
  return grid;
}

// Per-patch plane: PCA of the points near the lowest band, refined on inliers; an upright, flat,
// two-dimensional patch with enough inliers becomes a candidate. Returns whether a plane was fitted.
bool fit_patch_plane(Patch& patch, const Eigen::Matrix3Xd& local, const GroundOptions& options, double cos_slope) {
  if (static_cast<int>(patch.members.size()) < options.minimum_patch_points) return false;
  std::vector<double> heights;
  heights.reserve(patch.members.size());
  for (const std::uint32_t index : patch.members) heights.push_back(local(2, index));
  const std::size_t lowest = std::min<std::size_t>(std::max(1, options.lowest_points), heights.size());
  std::nth_element(heights.begin(), heights.begin() + static_cast<std::ptrdiff_t>(lowest - 1), heights.end());
  std::sort(heights.begin(), heights.begin() + static_cast<std::ptrdiff_t>(lowest));
  // Skip the very lowest few (below-ground reflections) as Patchwork does: mean of the lowest band.
  double floor_height = 0.0;
  for (std::size_t k = 0; k < lowest; ++k) floor_height += heights[k];
  floor_height /= static_cast<double>(lowest);
  detail::Moments moments;
  for (const std::uint32_t index : patch.members)
    if (local(2, index) < floor_height + options.seed_height) moments.add(local.col(index));
  if (moments.count < 3) return true;
  detail::Principal axes;
  for (int iteration = 0; iteration <= options.refinement_iterations; ++iteration) {
    axes = detail::principal_axes(moments.covariance());
    Eigen::Vector3d normal = axes.vectors.col(0);
    if (normal.z() < 0) normal = -normal;
    patch.normal = normal;
    patch.centroid = moments.mean();
    if (iteration == options.refinement_iterations) break;
    detail::Moments refined;
    for (const std::uint32_t index : patch.members)
      if (std::abs(normal.dot(local.col(index) - patch.centroid)) <= options.inlier_distance) refined.add(local.col(index));
    if (refined.count < 3) break;
    moments = refined;
  }
  const double total = axes.values.sum();
  const bool upright = patch.normal.z() >= cos_slope;
  const bool flat = total > 0.0 && axes.values(0) <= options.max_flatness * total;
  const bool two_dimensional = axes.values(2) > 0.0 && axes.values(1) >= 1e-3 * axes.values(2);
  if (!(upright && flat && two_dimensional)) return true;
  for (const std::uint32_t index : patch.members)
    if (std::abs(patch.normal.dot(local.col(index) - patch.centroid)) <= options.inlier_distance)
      patch.inliers.push_back(index);
  patch.candidate = static_cast<int>(patch.inliers.size()) >= options.minimum_patch_points;
  return true;
}

// Region growing over candidate patches (TRAVEL's traversable graph): neighbours are patches whose
// centroids are close horizontally, and both planes must agree in height at their midpoint and in
// slope. Every connected region is grown, and the one holding the most inlier points is the ground:
// its patches are marked accepted. Growing only from the best-supported patch let one tilted patch
// with many points (a car's flank, a bank, up to max_slope_deg off up) be the whole ground when no
// neighbour continued it; which patch leads depends on where the sectors fall, so the ground then
// changed with the scan's heading (docs/modelling.md, "The ground's region").
void grow_ground_region(std::vector<Patch>& patches, const GroundOptions& options) {
  std::vector<int> candidate_patches;
  for (int index = 0; index < static_cast<int>(patches.size()); ++index)
    if (patches[index].candidate) candidate_patches.push_back(index);
  if (candidate_patches.empty()) return;
  const double cos_neighbour = std::cos(options.max_neighbour_angle_deg * kPi / 180.0);
  const auto is_neighbour = [&](const Patch& a, const Patch& b) {
    const Eigen::Vector2d delta = (a.centroid - b.centroid).head<2>();
    const double radius = std::max(a.centroid.head<2>().norm(), b.centroid.head<2>().norm());
    const double reach = std::max(8.0, 0.35 * radius);
    if (delta.norm() > reach) return false;
    const Eigen::Vector2d middle = 0.5 * (a.centroid + b.centroid).head<2>();
    const double step = std::abs(plane_height(a, middle.x(), middle.y()) - plane_height(b, middle.x(), middle.y()));
    return step <= options.max_step_height && a.normal.dot(b.normal) >= cos_neighbour;
  };
  // Seeds in order of support, so that of two regions equally large the one holding the
  // best-supported patch wins.
  std::stable_sort(candidate_patches.begin(), candidate_patches.end(),
                   [&](int a, int b) { return patches[a].inliers.size() > patches[b].inliers.size(); });
  std::vector<int> region_of(patches.size(), -1);
  std::vector<int> best_region;
  std::size_t best_points = 0;
  for (const int seed : candidate_patches) {
    if (region_of[seed] >= 0) continue;
    std::vector<int> region = {seed};
    std::size_t points = 0;
    region_of[seed] = seed;
    for (std::size_t next = 0; next < region.size(); ++next) {
      const int current = region[next];
      points += patches[current].inliers.size();
      for (const int other : candidate_patches) {
        if (region_of[other] >= 0 || !is_neighbour(patches[current], patches[other])) continue;
        region_of[other] = seed;
        region.push_back(other);
      }
    }
    if (points > best_points) {
      best_points = points;
      best_region = std::move(region);
    }
  }
  for (const int index : best_region) patches[index].accepted = true;
}

}  // namespace

GroundSegmentation segment_ground(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& candidates,
                                  const GroundOptions& options, const Eigen::Vector3d& sensor_origin,
                                  const Eigen::Vector3d& up_axis) {
  GroundSegmentation result;
  if (candidates.empty() || options.ring_edges.size() < 2) {
    result.other_indices = candidates;
    result.other_heights.assign(candidates.size(), 0.0f);
    return result;
  }
  const Eigen::Vector3d up = up_axis.normalized();
  const Eigen::Matrix3d to_local = local_frame(up);
  PatchGrid grid = assign_patches(points, candidates, options, sensor_origin, to_local);
  std::vector<Patch>& patches = grid.patches;
  const double cos_slope = std::cos(options.max_slope_deg * kPi / 180.0);
  for (Patch& patch : patches)
    if (fit_patch_plane(patch, grid.local, options, cos_slope)) ++result.patches_fitted;
  grow_ground_region(patches, options);

  // Global plane: PCA over the accepted ground points (the model's ground normal and offset).
  detail::Moments ground_moments;
  std::vector<char> is_ground(static_cast<std::size_t>(points.cols()), 0);
  for (const Patch& patch : patches) {
    if (!patch.accepted) continue;
    ++result.patches_accepted;
    for (const std::uint32_t index : patch.inliers) {
      is_ground[index] = 1;
      ground_moments.add(points.col(index));
    }
  }
  result.found = ground_moments.count >= 3;
  Patch global_plane;  // in the local frame; the fallback reference of points outside accepted patches
  if (result.found) {
    const detail::Principal axes = detail::principal_axes(ground_moments.covariance());
    Eigen::Vector3d normal = axes.vectors.col(0);
    if (normal.dot(up) < 0) normal = -normal;
    result.normal = normal;
    result.offset = -normal.dot(ground_moments.mean());
    global_plane.centroid = to_local * (ground_moments.mean() - sensor_origin);
    global_plane.normal = to_local * normal;
  }
  // Every other candidate with its height above its own accepted patch's plane, else the global one.
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const std::uint32_t index = candidates[i];
    if (is_ground[index]) {
      result.ground_indices.push_back(index);
      continue;
    }
    const Patch* reference = &global_plane;
    if (grid.point_patch[i] >= 0 && patches[grid.point_patch[i]].accepted) reference = &patches[grid.point_patch[i]];
    const Eigen::Vector3d p = grid.local.col(index);
    const double height = result.found || reference != &global_plane ? p.z() - plane_height(*reference, p.x(), p.y()) : 1e9;
    result.other_indices.push_back(index);
    result.other_heights.push_back(static_cast<float>(height));
  }
  return result;
}

}  // namespace quadrix
