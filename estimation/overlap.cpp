// Dense overlap of a registration (see overlap.h).
#include "estimation/overlap.h"

#include "geometry/error.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace quadrix {

OverlapMeasure measure_overlap(const PointCloud& source, const PointCloud& target, const Eigen::Isometry3d& transform,
                               const std::optional<Eigen::Vector4d>& source_ground, double distance) {
  if (!(distance > 0.0)) throw Error("measure_overlap: distance must be positive, got " + std::to_string(distance));
  OverlapMeasure measure;
  measure.distance = distance;
  // Voxel hash of the target with cells of `distance`: a neighbour within `distance` lies in one of
  // the 27 cells around the query's cell.
  const double inverse = 1.0 / distance;
  const auto cell_of = [inverse](const Eigen::Vector3d& p) -> Eigen::Vector3i {
    return (p * inverse).array().floor().cast<int>();
  };
  const auto key_of = [](const Eigen::Vector3i& c) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.x()) & 0x1FFFFFu) << 42) |
           (static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.y()) & 0x1FFFFFu) << 21) |
           static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.z()) & 0x1FFFFFu);
  };
  // The target's points sorted by cell, and each occupied cell's range in that order: one sort and
  // one map instead of a vector per cell (this runs on every registration).
  std::vector<std::pair<std::uint64_t, Eigen::Vector3f>> keyed;
  keyed.reserve(target.size());
  for (std::size_t i = 0; i < target.size(); ++i) {
    const Eigen::Vector3d p = target.point(i);
    if (p.allFinite()) keyed.emplace_back(key_of(cell_of(p)), p.cast<float>());
  }
  std::sort(keyed.begin(), keyed.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::unordered_map<std::uint64_t, std::pair<std::uint32_t, std::uint32_t>> cells;  // key -> [begin, end)
  cells.reserve(keyed.size() / 4 + 1);
  for (std::size_t begin = 0, end = 0; begin < keyed.size(); begin = end) {
    for (end = begin + 1; end < keyed.size() && keyed[end].first == keyed[begin].first;) ++end;
    cells.emplace(keyed[begin].first, std::make_pair(static_cast<std::uint32_t>(begin), static_cast<std::uint32_t>(end)));
  }
  const float squared = static_cast<float>(distance * distance);
  const auto overlaps = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector3i c = cell_of(p);
    const Eigen::Vector3f point = p.cast<float>();
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto found = cells.find(key_of(c + Eigen::Vector3i(dx, dy, dz)));
          if (found == cells.end()) continue;
          for (std::uint32_t k = found->second.first; k < found->second.second; ++k)
            if ((keyed[k].second - point).squaredNorm() <= squared) return true;
        }
    return false;
  };
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
  for (std::size_t i = 0; i < above.size(); i += stride) {
    ++measure.sampled;
    moved += overlaps(transform * above[i]) ? 1 : 0;
    still += overlaps(above[i]) ? 1 : 0;
  }
  if (measure.sampled > 0) {
    measure.transformed = static_cast<double>(moved) / static_cast<double>(measure.sampled);
    measure.identity = static_cast<double>(still) / static_cast<double>(measure.sampled);
  }
  return measure;
}

}  // namespace quadrix
