// Dense overlap of a registration: how much of the source lands on the target after the transform,
// beside leaving it where it is. Judges pairs without ground truth and guards `ok` answers
// (register_clouds demotes an answer that overlaps clearly less than not moving).
#pragma once

#include "geometry/point_cloud.h"
#include "geometry/voxel_cells.h"

#include <Eigen/Geometry>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

namespace quadrix {

/// The target's points hashed by cells of `distance`, built once and asked many times whether a
/// point has a target point within `distance` (measure_overlap, and the dense search for every
/// optimum it scores). Its cells also tell which target points stand alone.
class TargetCoverage {
 public:
  /// Hashes the finite points of `target`; `distance` must be positive (else quadrix::Error).
  TargetCoverage(const PointCloud& target, double distance);
  /// Whether some target point lies within distance() of `point`.
  bool covers(const Eigen::Vector3d& point) const;
  /// The distance it was built for, m.
  double distance() const { return distance_; }
  /// Leaves out the target's isolated points by the rule of accompanied_points (geometry/voxel_cells.h) with cubes of
  /// distance() (the hash's own cells hold the counts): they cover nothing from then on. Returns the
  /// indices, ascending, of the target points kept (non-finite points were never hashed). A point
  /// is kept when at least `neighbours` (>= 1, else quadrix::Error) other points share its block.
  std::vector<Eigen::Index> leave_out_isolated_points(int neighbours = 1);

 private:
  /// A hashed target point: its position and its index in the target.
  struct KeyedPoint {
    Eigen::Vector3f position;
    std::uint32_t index;
  };
  Eigen::Vector3i cell_of(const Eigen::Vector3d& point) const;
  double distance_;
  std::size_t target_size_;                                                           // points of the target, hashed or not
  std::vector<KeyedPoint> keyed_;                                        // target points grouped by cell
  CellMap<std::pair<std::uint32_t, std::uint32_t>> cells_;               // key -> [begin, end) in keyed_ (empty once left out)
};

/// How much of the source lands on the target, for pairs without ground truth: the fraction of
/// source points standing above the source's ground (when the model has one) that have a target
/// point within `distance` after the transform, beside the same fraction without moving (identity).
struct OverlapMeasure {
  double distance = 0.3;        ///< a source point within this of a target point overlaps, m
  double transformed = 0.0;     ///< overlapping fraction after the registration's transform, [0, 1]
  double identity = 0.0;        ///< overlapping fraction without moving the source, [0, 1]
  std::size_t sampled = 0;      ///< source points tested (an even stride of at most 5,000 above the ground)
  std::optional<Eigen::Vector3d> transformed_centre;  ///< centre of the tested points that overlap after the transform, target frame (none overlap: empty)
};

/// Measures OverlapMeasure with a voxel hash of the target (cells of `distance`); points within
/// 0.5 m of `source_ground` (n . x + offset = 0 with `source_ground` = (n, offset)) are skipped
/// when it is given, since a shared ground plane overlaps under any motion along it.
OverlapMeasure measure_overlap(const PointCloud& source, const PointCloud& target, const Eigen::Isometry3d& transform,
                               const std::optional<Eigen::Vector4d>& source_ground = std::nullopt, double distance = 0.3);

/// measure_overlap against a target already hashed, at `coverage.distance()`: the checks hash the
/// target once for every answer they measure.
OverlapMeasure measure_overlap(const PointCloud& source, const TargetCoverage& coverage, const Eigen::Isometry3d& transform,
                               const std::optional<Eigen::Vector4d>& source_ground = std::nullopt);

}  // namespace quadrix
