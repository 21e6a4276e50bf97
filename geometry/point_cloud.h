// PointCloud: positions in float storage (math is done in double), optional per-point fields.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace quadrix {

/// A point cloud: positions plus optional per-point intensity, semantic labels, colours and
/// any other scalar fields a reader kept. Every non-empty optional field has size() entries.
struct PointCloud {
  Eigen::Matrix3Xf positions;                              ///< x, y, z in metres, one column a point
  std::vector<float> intensity;                            ///< reflectance, empty when absent
  std::vector<uint32_t> labels;                            ///< semantic label per point, empty when absent
  std::vector<std::array<uint8_t, 3>> colors;              ///< RGB per point, empty when absent
  std::map<std::string, std::vector<float>> extra_fields;  ///< other scalar properties kept from the file

  /// Number of points.
  std::size_t size() const { return static_cast<std::size_t>(positions.cols()); }
  /// True when the cloud has no points.
  bool empty() const { return positions.cols() == 0; }
  /// Position of point i in double precision.
  Eigen::Vector3d point(std::size_t i) const { return positions.col(static_cast<Eigen::Index>(i)).cast<double>(); }
};

}  // namespace quadrix
