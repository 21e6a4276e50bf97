// Dense overlap of a registration: how much of the source lands on the target after the transform,
// beside leaving it where it is. Judges pairs without ground truth and guards `ok` answers
// (register_clouds demotes an answer that overlaps clearly less than not moving).
#pragma once

#include "geometry/point_cloud.h"

#include <Eigen/Geometry>

#include <cstddef>
#include <optional>

namespace quadrix {

/// How much of the source lands on the target, for pairs without ground truth: the fraction of
/// source points standing above the source's ground (when the model has one) that have a target
/// point within `distance` after the transform, beside the same fraction without moving (identity).
struct OverlapMeasure {
  double distance = 0.3;        ///< a source point within this of a target point overlaps, m
  double transformed = 0.0;     ///< overlapping fraction after the registration's transform, [0, 1]
  double identity = 0.0;        ///< overlapping fraction without moving the source, [0, 1]
  std::size_t sampled = 0;      ///< source points tested (an even stride of at most 5,000 above the ground)
};

/// Measures OverlapMeasure with a voxel hash of the target (cells of `distance`); points within
/// 0.5 m of `source_ground` (n . x + offset = 0 with `source_ground` = (n, offset)) are skipped
/// when it is given, since a shared ground plane overlaps under any motion along it.
OverlapMeasure measure_overlap(const PointCloud& source, const PointCloud& target, const Eigen::Isometry3d& transform,
                               const std::optional<Eigen::Vector4d>& source_ground = std::nullopt, double distance = 0.3);

}  // namespace quadrix
