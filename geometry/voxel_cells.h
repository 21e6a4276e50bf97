// Integer cells of a voxel grid and the isolated-point rule built on them: a spurious return
// (rain, dust, a multipath echo, an injected outlier) stands alone, while a point of a scanned
// surface has its scan line's neighbours within a few decimetres. The extraction leaves isolated
// points out before modelling, and registration's checks before measuring any overlap.
#pragma once

#include "geometry/point_cloud.h"

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace quadrix {

/// A 64-bit key of an integer cell (21 bits per axis, so cells of 0.3 m reach ±314 km): the voxel
/// hashes of the isolation rule, the overlap and the dense search's thinning share it.
std::uint64_t cell_key(const Eigen::Vector3i& cell);

/// The isolated-point rule for a point of `cell` over any occupancy structure: whether its
/// `others_in_own_cell` plus the points of the 26 cells around (`points_in(key)` counting a cell
/// by cell_key) reach `neighbours`. Stops counting as soon as they do.
template <typename PointsIn>
bool has_enough_company(const Eigen::Vector3i& cell, std::uint32_t others_in_own_cell, std::uint32_t neighbours,
                        const PointsIn& points_in) {
  std::uint32_t others = others_in_own_cell;
  for (int dx = -1; dx <= 1; ++dx)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dz = -1; dz <= 1; ++dz) {
        if (others >= neighbours) return true;
        if (dx != 0 || dy != 0 || dz != 0) others += points_in(cell_key(cell + Eigen::Vector3i(dx, dy, dz)));
      }
  return others >= neighbours;
}

/// The `candidates` (columns of `points`) that other candidates keep company: at least
/// `neighbours` of them lie in the point's cube of edge `cell` or in the 26 around it. Order is
/// kept; non-finite points are left out. `cell` must be positive and `neighbours` at least 1 (else
/// quadrix::Error).
std::vector<std::uint32_t> accompanied_points(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& candidates,
                                              double cell, int neighbours = 1);

/// The finite points of `cloud` that at least `neighbours` other points keep company, by the rule
/// of accompanied_points. Only positions are kept. `cell` must be positive and `neighbours` at
/// least 1 (else quadrix::Error).
PointCloud without_isolated_points(const PointCloud& cloud, double cell, int neighbours = 1);

}  // namespace quadrix
