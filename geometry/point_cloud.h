// PointCloud: positions in float storage relative to a local origin kept in double (math is done
// in double), optional per-point fields.
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
/// Positions are float32 relative to `local_origin` (double): a point's coordinates in the file's
/// frame are local_origin + positions.col(i). Georeferenced coordinates (UTM northings ~5e6 m) lose
/// 0.25-0.5 m as float32, so a reader asked for a local origin subtracts one in double first.
struct PointCloud {
  Eigen::Matrix3Xf positions;                              ///< x, y, z in metres relative to local_origin, one column a point
  std::vector<float> intensity;                            ///< reflectance, empty when absent
  std::vector<uint32_t> labels;                            ///< semantic label per point, empty when absent
  std::vector<std::array<uint8_t, 3>> colors;              ///< RGB per point, empty when absent
  std::map<std::string, std::vector<float>> extra_fields;  ///< other scalar properties kept from the file
  Eigen::Vector3d local_origin = Eigen::Vector3d::Zero();  ///< the file-frame point positions are relative to (zero: none)

  /// Number of points.
  std::size_t size() const { return static_cast<std::size_t>(positions.cols()); }
  /// True when the cloud has no points.
  bool empty() const { return positions.cols() == 0; }
  /// Position of point i in double precision, relative to local_origin (the frame the cloud is processed in).
  Eigen::Vector3d point(std::size_t i) const { return positions.col(static_cast<Eigen::Index>(i)).cast<double>(); }
  /// Position of point i in the file's frame: local_origin + point(i).
  Eigen::Vector3d point_in_file_frame(std::size_t i) const { return local_origin + point(i); }
};

}  // namespace quadrix
