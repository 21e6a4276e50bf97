// A global search over the four degrees of freedom two ground-levelled scans leave: the yaw about
// the up axis and the translation along the ground (beyond the paper, which reaches a hard pair only
// through its quadric correspondences; the estimated ground planes fix roll, pitch and height).
// Each scan is levelled by its own ground plane, the points between
// `minimum_height` and `maximum_height` above it are projected onto it as a bird's-eye occupancy
// grid, and every yaw (one `yaw_step_degrees` apart) and every translation within `reach` is scored
// by the share of occupied source cells that land on occupied target cells: a correlation of the
// two grids (correlative scan matching, as Olson's, over a full turn). The dense search starts ICP
// from the best poses it finds, so a pair whose quadric correspondences hold no true inlier (scans
// 20-30 m apart, where the quadrics the two scans share are few) still gets its truth as a start.
// Measured in docs/registration.md ("Correlation over the ground").
#pragma once

#include "geometry/point_cloud.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstddef>
#include <vector>

namespace quadrix {

/// Options of correlate_over_ground.
struct GroundCorrelationOptions {
  std::size_t poses = 6;           ///< at most this many poses, best first (0: none)
  double reach = 40.0;             ///< translations searched within this of not moving, along the ground, m
  double yaw_step_degrees = 2.0;   ///< spacing of the yaws searched over a full turn, degrees
  double coarse_cell = 2.0;        ///< cell edge of the first pass over every yaw and translation, m
  double fine_cell = 1.0;          ///< cell edge of the second pass around the best coarse poses, m
  double minimum_height = 0.5;     ///< points lower than this above their ground are left out (a shared ground matches any slide), m
  double maximum_height = 4.0;     ///< and points higher than this (tree tops and roofs, seen differently from afar), m
  double separation = 3.0;         ///< poses closer than this in translation to a better one ...
  double separation_degrees = 6.0; ///< ... and closer than this in yaw are not reported, degrees
};

/// Throws quadrix::Error naming the first option out of range (e.g. "option
/// 'dense_search.correlation.reach' must be positive, got 0"): reach positive, yaw_step_degrees in
/// (0, 180], coarse_cell and fine_cell at least 0.05 m, maximum_height above minimum_height,
/// separations not negative.
void validate_ground_correlation_options(const GroundCorrelationOptions& options);

/// One pose the correlation proposes.
struct GroundPose {
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();  ///< source to target, grounds on each other
  double share = 0.0;                                           ///< occupied source cells (fine grid) landing on occupied target cells, [0, 1]
  double yaw_degrees = 0.0;                                     ///< its rotation about the levelled up axis
};

/// The poses that best overlay the two scans' bird's-eye occupancy above their grounds, best first.
/// `source_ground` and `target_ground` are each cloud's ground plane (n, d) with n . x + d = 0 and
/// n pointing up. The returned transforms put the source ground on the target ground. Empty when
/// either cloud has no point in the height band, `options.poses` is 0, or the target's band spans
/// more than 2^26 cells (8 km across at 1 m); points farther than 1,000 km are left out.
/// Throws quadrix::Error for options out of range (validate_ground_correlation_options).
std::vector<GroundPose> correlate_over_ground(const PointCloud& source, const PointCloud& target,
                                              const Eigen::Vector4d& source_ground, const Eigen::Vector4d& target_ground,
                                              const GroundCorrelationOptions& options = {});

}  // namespace quadrix
