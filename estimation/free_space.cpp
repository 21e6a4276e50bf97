// Free space of a registration (see free_space.h).
#include "estimation/free_space.h"

#include "geometry/constants.h"
#include "geometry/error.h"

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace quadrix {

namespace {

// Direction cells: 0.5 deg of azimuth (an HDL-64E or a VLP-16 fires every 0.1-0.4 deg, so a cell
// holds a few beams) by 1 deg of elevation, centred on whole degrees: a VLP-16's rings, at odd
// whole degrees 2 deg apart, each fall in the middle of a cell of their own. Cells edged on whole
// degrees put each ring on an edge, where rounding alone chose the cell it fell in; the sums of
// the simulated VLP-16 runs then moved by up to 0.14 with the last bits of the angle.
constexpr int kAzimuthCells = 720;
constexpr int kElevationCells = 180;
constexpr double kRadiansToAzimuthCells = kAzimuthCells / (2.0 * kPi);
constexpr double kRadiansToElevationCells = kElevationCells / kPi;

// atan2(y, x) within 4e-8 rad (a near-minimax odd polynomial of degree 15 in y/x or x/y), for
// finite input. A cell only has to be the same for the image and its lookups, and this is far
// finer than a cell: building a KITTI scan's image took 9 ms with std::atan2 and std::hypot
// (microbenchmark_dense_search, BM_FreeSpaceKitti52), most of it in the two.
double approximate_atan2(double y, double x) {
  const double ax = std::abs(x), ay = std::abs(y);
  if (ax == 0.0 && ay == 0.0) return 0.0;
  const bool steep = ay > ax;
  const double t = steep ? ax / ay : ay / ax;  // in [0, 1]
  const double s = t * t;
  double angle = t * (0.9999993355721538 +
                      s * (-0.3332986075920071 +
                           s * (0.19946565359151494 +
                                s * (-0.13908628064472733 +
                                     s * (0.09642193474029291 +
                                          s * (-0.05591227347642544 + s * (0.021862920491458784 + s * -0.004054556757913205)))))));
  if (steep) angle = 0.5 * kPi - angle;
  if (x < 0.0) angle = kPi - angle;
  return y < 0.0 ? -angle : angle;
}

// The cell of direction `offset` (from the sensor), or -1 for the sensor's own position.
int cell_of(const Eigen::Vector3d& offset) {
  const double horizontal = std::sqrt(offset.x() * offset.x() + offset.y() * offset.y());
  if (!(horizontal > 0.0 || offset.z() != 0.0)) return -1;
  const int azimuth = std::clamp(static_cast<int>((approximate_atan2(offset.y(), offset.x()) + kPi) * kRadiansToAzimuthCells),
                                 0, kAzimuthCells - 1);
  const int elevation = std::clamp(
      static_cast<int>((approximate_atan2(offset.z(), horizontal) + 0.5 * kPi) * kRadiansToElevationCells + 0.5), 0,
      kElevationCells - 1);
  return azimuth * kElevationCells + elevation;
}

// Of `points` standing more than `height` above `ground`, mapped by `transform` into the frame of
// `image`: the share in its sensor's free space, and how many were tested.
std::pair<double, std::size_t> share_in_free_space(const PointCloud& points, const Eigen::Vector4d& ground, double height,
                                                   const Eigen::Isometry3d& transform, const RangeImage& image,
                                                   double tolerance) {
  std::size_t tested = 0, inside = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d p = points.point(i);
    if (!p.allFinite() || ground.head<3>().dot(p) + ground(3) <= height) continue;
    const Eigen::Vector3d moved = transform * p;
    const std::optional<float> nearest = image.nearest_return(moved);
    if (!nearest) continue;
    ++tested;
    inside += (moved - image.sensor_origin()).norm() < static_cast<double>(*nearest) - tolerance ? 1 : 0;
  }
  return {tested > 0 ? static_cast<double>(inside) / static_cast<double>(tested) : 0.0, tested};
}

}  // namespace

RangeImage::RangeImage(const PointCloud& cloud, const Eigen::Vector3d& sensor_origin)
    : sensor_origin_(sensor_origin),
      nearest_(static_cast<std::size_t>(kAzimuthCells) * kElevationCells, std::numeric_limits<float>::infinity()) {
  if (!sensor_origin.allFinite()) throw Error("RangeImage: the sensor origin must be finite");
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d p = cloud.point(i);
    if (!p.allFinite()) continue;
    const Eigen::Vector3d offset = p - sensor_origin;
    const int cell = cell_of(offset);
    if (cell < 0) continue;
    float& nearest = nearest_[static_cast<std::size_t>(cell)];
    nearest = std::min(nearest, static_cast<float>(offset.norm()));
  }
}

std::optional<float> RangeImage::nearest_return(const Eigen::Vector3d& point) const {
  const int cell = cell_of(point - sensor_origin_);
  if (cell < 0) return std::nullopt;
  const float nearest = nearest_[static_cast<std::size_t>(cell)];
  if (!std::isfinite(nearest)) return std::nullopt;
  return nearest;
}

FreeSpaceMeasure measure_free_space(const PointCloud& source, const PointCloud& target, const RangeImage& source_image,
                                    const RangeImage& target_image, const Eigen::Isometry3d& transform,
                                    const Eigen::Vector4d& source_ground, const Eigen::Vector4d& target_ground,
                                    double height, double tolerance) {
  if (!(tolerance >= 0.0)) throw Error("measure_free_space: the tolerance must be >= 0 m, got " + std::to_string(tolerance));
  FreeSpaceMeasure measure;
  tbb::parallel_invoke(
      [&] {
        std::tie(measure.source_in_target_free_space, measure.source_tested) =
            share_in_free_space(source, source_ground, height, transform, target_image, tolerance);
      },
      [&] {
        std::tie(measure.target_in_source_free_space, measure.target_tested) =
            share_in_free_space(target, target_ground, height, transform.inverse(), source_image, tolerance);
      });
  return measure;
}

}  // namespace quadrix
