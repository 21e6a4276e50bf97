// Streaming point-cloud readers: a file read in chunks of at most N points, so a survey larger
// than memory can be binned or modelled piece by piece. Formats with fixed-size records (binary
// PLY, LAS, KITTI .bin, nuScenes .pcd.bin, binary PCD) and XYZ text. Every size a header declares
// is checked against the file before anything is read; errors are quadrix::Error naming the file.
#pragma once

#include "geometry/io.h"

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace quadrix {

/// Axis-aligned box in the file's coordinates.
struct PointBounds {
  Eigen::Vector3d min = Eigen::Vector3d::Zero();  ///< smallest x, y, z
  Eigen::Vector3d max = Eigen::Vector3d::Zero();  ///< largest x, y, z
};

/// Points read by one PointStream::read call, in file order. Points with a non-finite coordinate
/// are dropped (and counted by the stream), as read_point_cloud drops them.
struct PointChunk {
  Eigen::Matrix3Xd positions;        ///< x, y, z in the file's coordinates (double), one column a point
  std::vector<float> intensity;      ///< one a point when the file has an intensity field, else empty
  std::vector<std::uint32_t> labels; ///< one a point when the file has labels (LAS: classification), else empty

  /// Number of points.
  std::size_t size() const { return static_cast<std::size_t>(positions.cols()); }
  /// Positions as float32 relative to `origin` (subtracted in double first: no precision lost to large coordinates).
  Eigen::Matrix3Xf relative_to(const Eigen::Vector3d& origin) const;
};

/// Options of open_point_stream.
struct PointStreamOptions {
  CloudFormat format = CloudFormat::Auto;  ///< override the extension (Csv and Npy are not streamed)
};

/// A point-cloud file open for reading in chunks.
class PointStream {
 public:
  virtual ~PointStream() = default;
  /// Replaces `chunk` by the next at most `max_points` records' finite points (max_points >= 1);
  /// false, with `chunk` empty, when the file is exhausted. Throws quadrix::Error on bad data.
  virtual bool read(std::size_t max_points, PointChunk& chunk) = 0;

  /// Records in the file (finite or not) when its header or size says; nullopt for text formats.
  std::optional<std::size_t> point_count() const { return point_count_; }
  /// The header's bounding box (LAS); nullopt when the format has none.
  std::optional<PointBounds> bounds() const { return bounds_; }
  /// A local origin for float storage, fixed when the file was opened (local_origin_near, from the
  /// LAS header's box centre or the first record): zero on every axis whose coordinates are small.
  const Eigen::Vector3d& origin() const { return origin_; }
  /// The format being read.
  CloudFormat format() const { return format_; }
  /// The file's path.
  const std::string& path() const { return path_; }
  /// Records consumed so far (finite or not).
  std::size_t records_read() const { return records_read_; }
  /// Records dropped so far because a coordinate was NaN or inf.
  std::size_t non_finite_dropped() const { return non_finite_dropped_; }

 protected:
  std::string path_;
  CloudFormat format_ = CloudFormat::Auto;
  std::optional<std::size_t> point_count_;
  std::optional<PointBounds> bounds_;
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
  std::size_t records_read_ = 0;
  std::size_t non_finite_dropped_ = 0;
};

/// Opens `path` for chunked reading: binary PLY (the vertex element's scalar properties; lists
/// allowed only after it), LAS 1.0-1.4 (formats 0-10), KITTI .bin, nuScenes .pcd.bin, binary PCD,
/// and XYZ text. Throws quadrix::Error naming the file for other encodings (ascii PLY/PCD,
/// binary_compressed PCD: read them whole with read_point_cloud), a bad header, or a size that
/// does not match the header.
std::unique_ptr<PointStream> open_point_stream(const std::string& path, const PointStreamOptions& options = {});

}  // namespace quadrix
