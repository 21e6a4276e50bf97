// Dense overlap of a registration (see overlap.h).
#include "estimation/overlap.h"

#include "geometry/error.h"
#include "geometry/voxel_cells.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace quadrix {

TargetCoverage::TargetCoverage(const PointCloud& target, double distance)
    : distance_(distance), target_size_(target.size()), cells_(target.size() / 4 + 1) {
  if (!(distance > 0.0)) throw Error("TargetCoverage: distance must be positive, got " + std::to_string(distance));
  // The target's points grouped by cell, and each occupied cell's range in that order: a counting
  // sort (count per cell, then place) instead of a vector per cell. A neighbour within `distance`
  // lies in one of the 27 cells around the query's cell.
  std::vector<std::uint64_t> keys(target.size(), 0);
  std::vector<char> finite(target.size(), 0);
  for (std::size_t i = 0; i < target.size(); ++i) {
    const Eigen::Vector3d p = target.point(i);
    if (!p.allFinite()) continue;
    finite[i] = 1;
    keys[i] = cell_key(cell_of(p));
    ++cells_[keys[i]].second;
  }
  std::uint32_t placed = 0;
  cells_.for_each([&](std::uint64_t, std::pair<std::uint32_t, std::uint32_t>& range) {
    const std::uint32_t count = range.second;
    range = {placed, placed};  // `second` is the fill cursor below, then the end
    placed += count;
  });
  keyed_.resize(placed);
  for (std::size_t i = 0; i < target.size(); ++i)
    if (finite[i]) keyed_[cells_[keys[i]].second++] = {target.point(i).cast<float>(), static_cast<std::uint32_t>(i)};
}

std::vector<Eigen::Index> TargetCoverage::leave_out_isolated_points(int neighbours) {
  if (neighbours < 1) throw Error("TargetCoverage: at least one neighbour must be asked for, got " + std::to_string(neighbours));
  // The points of a cell holding at most `neighbours` are isolated when the 26 cells around do not
  // make up the rest. Decide every such cell first, then erase: erasing one must not make its
  // neighbour look isolated.
  const auto points_in = [this](std::uint64_t key) -> std::uint32_t {
    const std::pair<std::uint32_t, std::uint32_t>* found = cells_.find(key);
    return found ? found->second - found->first : 0u;
  };
  const std::uint32_t wanted = static_cast<std::uint32_t>(neighbours);
  std::vector<std::uint64_t> isolated;
  cells_.for_each([&](std::uint64_t key, const std::pair<std::uint32_t, std::uint32_t>& range) {
    const std::uint32_t in_own_cell = range.second - range.first;
    if (in_own_cell == 0 || in_own_cell > wanted) return;  // empty: left out before
    const Eigen::Vector3i cell = cell_of(keyed_[range.first].position.cast<double>());
    if (!has_enough_company(cell, in_own_cell - 1, wanted, points_in)) isolated.push_back(key);
  });
  // Every hashed point is kept but those of the isolated cells, listed in the target's order.
  std::vector<char> keep(target_size_, 0);
  for (const KeyedPoint& point : keyed_) keep[point.index] = 1;
  for (const std::uint64_t key : isolated) {
    std::pair<std::uint32_t, std::uint32_t>& range = cells_[key];
    for (std::uint32_t k = range.first; k < range.second; ++k) keep[keyed_[k].index] = 0;
    range.second = range.first;  // covers nothing from now on
  }
  std::vector<Eigen::Index> kept;
  kept.reserve(keyed_.size());
  for (std::size_t i = 0; i < keep.size(); ++i)
    if (keep[i]) kept.push_back(static_cast<Eigen::Index>(i));
  return kept;
}

Eigen::Vector3i TargetCoverage::cell_of(const Eigen::Vector3d& point) const {
  return (point / distance_).array().floor().cast<int>();
}

bool TargetCoverage::covers(const Eigen::Vector3d& point) const {
  const Eigen::Vector3i c = cell_of(point);
  const Eigen::Vector3f query = point.cast<float>();
  const float squared = static_cast<float>(distance_ * distance_);
  for (int dx = -1; dx <= 1; ++dx)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dz = -1; dz <= 1; ++dz) {
        const std::pair<std::uint32_t, std::uint32_t>* found = cells_.find(cell_key(c + Eigen::Vector3i(dx, dy, dz)));
        if (!found) continue;
        for (std::uint32_t k = found->first; k < found->second; ++k)
          if ((keyed_[k].position - query).squaredNorm() <= squared) return true;
      }
  return false;
}

OverlapMeasure measure_overlap(const PointCloud& source, const PointCloud& target, const Eigen::Isometry3d& transform,
                               const std::optional<Eigen::Vector4d>& source_ground, double distance) {
  if (!(distance > 0.0)) throw Error("measure_overlap: distance must be positive, got " + std::to_string(distance));
  return measure_overlap(source, TargetCoverage(target, distance), transform, source_ground);
}

OverlapMeasure measure_overlap(const PointCloud& source, const TargetCoverage& coverage, const Eigen::Isometry3d& transform,
                               const std::optional<Eigen::Vector4d>& source_ground) {
  OverlapMeasure measure;
  measure.distance = coverage.distance();
  std::vector<Eigen::Vector3d> above;
  above.reserve(source.size());
  for (std::size_t i = 0; i < source.size(); ++i) {
    const Eigen::Vector3d p = source.point(i);
    if (!p.allFinite()) continue;
    if (source_ground && std::abs(source_ground->head<3>().dot(p) + (*source_ground)(3)) < 0.5) continue;
    above.push_back(p);
  }
  // 5,000 samples give each fraction to about +-0.007 (one standard error at worst).
  const std::size_t stride = std::max<std::size_t>(1, (above.size() + 4999) / 5000);
  std::size_t moved = 0, still = 0;
  Eigen::Vector3d moved_sum = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < above.size(); i += stride) {
    ++measure.sampled;
    const Eigen::Vector3d placed = transform * above[i];
    if (coverage.covers(placed)) {
      ++moved;
      moved_sum += placed;
    }
    still += coverage.covers(above[i]) ? 1 : 0;
  }
  if (measure.sampled > 0) {
    measure.transformed = static_cast<double>(moved) / static_cast<double>(measure.sampled);
    measure.identity = static_cast<double>(still) / static_cast<double>(measure.sampled);
  }
  if (moved > 0) measure.transformed_centre = Eigen::Vector3d(moved_sum / static_cast<double>(moved));
  return measure;
}

}  // namespace quadrix
