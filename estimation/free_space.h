// Free space of a registration: how many points of each scan the answer puts where the other
// scan's sensor saw through. Overlap alone cannot tell a street from its mirror image in sparse
// scans (docs/registration.md, "Free space"); what each sensor saw as empty can.
#pragma once

#include "geometry/point_cloud.h"

#include <Eigen/Geometry>

#include <cstddef>
#include <optional>
#include <vector>

namespace quadrix {

/// What a scan saw from its sensor: the nearest return in each direction cell of 0.5 deg of azimuth
/// by 1 deg of elevation about the sensor. A point nearer than a cell's nearest return lies in space
/// the sensor's beams crossed.
class RangeImage {
 public:
  /// Bins the finite points of `cloud` as seen from `sensor_origin` (the cloud's own frame).
  RangeImage(const PointCloud& cloud, const Eigen::Vector3d& sensor_origin);
  /// The nearest return in the direction of `point` (the cloud's frame), or nullopt when the sensor
  /// had no return in that direction cell.
  std::optional<float> nearest_return(const Eigen::Vector3d& point) const;
  /// The sensor position the image was built around.
  const Eigen::Vector3d& sensor_origin() const { return sensor_origin_; }

 private:
  Eigen::Vector3d sensor_origin_;
  std::vector<float> nearest_;  // azimuth-major cells; +infinity where no return fell
};

/// Free space of an answer, each way: of the points standing higher than the height limit above
/// their scan's ground and in a direction cell where the other scan's sensor had a return, the
/// share lying more than `tolerance` in front of that return.
struct FreeSpaceMeasure {
  double source_in_target_free_space = 0.0;  ///< share of the tested source points, after the answer, in the target sensor's free space
  double target_in_source_free_space = 0.0;  ///< share of the tested target points, moved back by the answer, in the source sensor's free space
  std::size_t source_tested = 0;             ///< source points tested (high enough, in a cell where the target had a return)
  std::size_t target_tested = 0;             ///< target points tested
  /// Both shares summed: the number AmbiguityOptions::free_space_limit bounds.
  double sum() const { return source_in_target_free_space + target_in_source_free_space; }
};

/// Measures FreeSpaceMeasure of `transform` (source into target): source points more than
/// `height` above `source_ground` (n . x + offset, n up) against `target_image`, and target points
/// more than `height` above `target_ground`, moved by the inverse, against `source_image`. Points
/// lower than that are left out: cars and people that moved between the scans stand there.
/// `tolerance` (m) allows for range noise and cells that straddle an edge. The two ways are measured
/// at the same time.
FreeSpaceMeasure measure_free_space(const PointCloud& source, const PointCloud& target, const RangeImage& source_image,
                                    const RangeImage& target_image, const Eigen::Isometry3d& transform,
                                    const Eigen::Vector4d& source_ground, const Eigen::Vector4d& target_ground,
                                    double height, double tolerance = 0.5);

}  // namespace quadrix
