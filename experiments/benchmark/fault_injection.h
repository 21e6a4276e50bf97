// Fault injection for `quadrix bench --corrupt NAME`: damages the source cloud of every task in a
// controlled, seeded way (points lost, a sector missing, outliers, noise, duplicates, a scale error),
// so the benchmark shows what registration answers when its input is bad. The point of the exercise
// is the status: a damaged pair may fail, but it must never crash and never come back `ok` and wrong.
#pragma once

#include "geometry/point_cloud.h"

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace quadrix {

/// What one corruption does to a cloud.
enum class CorruptionKind {
  None,            ///< the cloud as it is
  DropPoints,      ///< removes a random fraction of the points
  DropSector,      ///< removes every point whose azimuth about the sensor lies in a wedge of `amount` degrees
  AddOutliers,     ///< adds uniform outliers in the cloud's bounding box, `amount` times the point count
  AddNoise,        ///< adds Gaussian noise of `amount` metres (per axis) to a random 20 % of the points
  DuplicatePoints, ///< every point twice (with all its fields)
  Scale,           ///< multiplies every position by `amount` about the sensor origin
};

/// A named corruption: `drop-30`, `sector-90`, `outliers-10`, `noise-0.5`, `duplicate`, `scale-1.001`.
struct Corruption {
  CorruptionKind kind = CorruptionKind::None;  ///< what it does
  double amount = 0.0;                         ///< its size: a fraction, degrees, metres or a factor (see the kind)
  std::string name;                            ///< the name it was parsed from ("" for none)
};

/// Fraction of the points that AddNoise moves.
constexpr double kNoisyPointFraction = 0.2;

/// The corruptions of the reliability table (docs/reliability.md), in its order.
std::vector<std::string> standard_corruption_names();

/// Parses `drop-P` (P percent, 0 < P < 100), `sector-D` (0 < D < 360 degrees), `outliers-P`
/// (0 < P <= 1000 percent of the point count), `noise-S` (0 < S <= 10 m), `duplicate`,
/// `scale-F` (0.5 <= F <= 2); "" or "none" is no corruption. Throws quadrix::Error naming the value
/// and listing the forms otherwise.
Corruption parse_corruption(const std::string& name);

/// Returns `cloud` damaged by `corruption` with the random stream of `seed`; `sensor_origin` is the
/// centre of the sector and of the scale. Every per-point field follows its point: dropped with it,
/// copied with a duplicate, zero (label 0, black, intensity 0) for an outlier.
PointCloud corrupt_cloud(const PointCloud& cloud, const Corruption& corruption, std::uint64_t seed,
                         const Eigen::Vector3d& sensor_origin = Eigen::Vector3d::Zero());

}  // namespace quadrix
