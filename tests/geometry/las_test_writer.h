// A minimal LAS writer for tests: every point format 0-10, versions 1.0-1.4, extra bytes and
// variable-length records, built byte by byte from the specification's tables (LAS 1.4 R15).
#pragma once

#include "tests/geometry/test_io_helpers.h"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <vector>

namespace quadrix::testing {

/// One LAS point as stored (integer coordinates before scale and offset).
struct LasTestPoint {
  std::int32_t X = 0, Y = 0, Z = 0;
  std::uint16_t intensity = 0;
  std::uint8_t return_number = 1, number_of_returns = 1, classification = 0;
  std::array<std::uint16_t, 3> rgb{};
};

/// A variable-length record to write after the header.
struct LasTestVlr {
  std::string user = "LASF_Projection";  ///< user ID (16 bytes, NUL-padded)
  std::uint16_t record_id = 0;            ///< record ID
  std::string payload;                    ///< the record's bytes
};

/// What to write.
struct LasTestFile {
  int version_minor = 2;
  int point_format = 0;
  std::size_t extra_bytes = 0;
  std::size_t vlr_payload = 0;  ///< one VLR with this many payload bytes, when > 0
  std::vector<LasTestVlr> vlrs; ///< further VLRs, after that one
  Eigen::Vector3d scale = Eigen::Vector3d::Constant(0.01);
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  std::vector<LasTestPoint> points;
};

/// Base record sizes of formats 0..10.
inline std::size_t las_test_base_size(int format) {
  static const std::size_t sizes[11] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
  return sizes[format];
}

/// Public header size of a version.
inline std::size_t las_test_header_size(int minor) { return minor <= 2 ? 227 : minor == 3 ? 235 : 375; }

template <typename T>
void put_at(std::string& bytes, std::size_t offset, T value) {
  std::memcpy(&bytes[offset], &value, sizeof(T));
}

/// The file's bytes, with a correct header (counts, bounds, offsets).
inline std::string las_test_bytes(const LasTestFile& file) {
  const std::size_t header_size = las_test_header_size(file.version_minor);
  const std::size_t record = las_test_base_size(file.point_format) + file.extra_bytes;
  std::size_t vlr_bytes = file.vlr_payload > 0 ? 54 + file.vlr_payload : 0;
  for (const LasTestVlr& vlr : file.vlrs) vlr_bytes += 54 + vlr.payload.size();
  const std::size_t offset_to_points = header_size + vlr_bytes;
  std::string bytes(offset_to_points + record * file.points.size(), '\0');
  std::memcpy(&bytes[0], "LASF", 4);
  bytes[24] = 1;
  bytes[25] = static_cast<char>(file.version_minor);
  std::memcpy(&bytes[26], "quadrix test", 12);
  put_at<std::uint16_t>(bytes, 94, static_cast<std::uint16_t>(header_size));
  put_at<std::uint32_t>(bytes, 96, static_cast<std::uint32_t>(offset_to_points));
  put_at<std::uint32_t>(bytes, 100, static_cast<std::uint32_t>((file.vlr_payload > 0 ? 1u : 0u) + file.vlrs.size()));
  bytes[104] = static_cast<char>(file.point_format);
  put_at<std::uint16_t>(bytes, 105, static_cast<std::uint16_t>(record));
  const bool legacy_allowed = file.point_format < 6;
  put_at<std::uint32_t>(bytes, 107, legacy_allowed || file.version_minor < 4 ? static_cast<std::uint32_t>(file.points.size()) : 0u);
  Eigen::Vector3d low = Eigen::Vector3d::Zero(), high = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < file.points.size(); ++i) {
    const LasTestPoint& p = file.points[i];
    const Eigen::Vector3d x(p.X * file.scale.x() + file.offset.x(), p.Y * file.scale.y() + file.offset.y(),
                            p.Z * file.scale.z() + file.offset.z());
    low = i == 0 ? x : low.cwiseMin(x);
    high = i == 0 ? x : high.cwiseMax(x);
  }
  for (int axis = 0; axis < 3; ++axis) {
    put_at<double>(bytes, 131 + 8 * axis, file.scale[axis]);
    put_at<double>(bytes, 155 + 8 * axis, file.offset[axis]);
    put_at<double>(bytes, 179 + 16 * axis, high[axis]);
    put_at<double>(bytes, 187 + 16 * axis, low[axis]);
  }
  if (file.version_minor >= 4) put_at<std::uint64_t>(bytes, 247, file.points.size());
  std::size_t at_vlr = header_size;
  if (file.vlr_payload > 0) {
    std::memcpy(&bytes[header_size + 2], "LASF_Projection", 15);
    put_at<std::uint16_t>(bytes, header_size + 18, 2112);
    put_at<std::uint16_t>(bytes, header_size + 20, static_cast<std::uint16_t>(file.vlr_payload));
    at_vlr += 54 + file.vlr_payload;
  }
  for (const LasTestVlr& vlr : file.vlrs) {
    std::memcpy(&bytes[at_vlr + 2], vlr.user.data(), std::min<std::size_t>(vlr.user.size(), 16));
    put_at<std::uint16_t>(bytes, at_vlr + 18, vlr.record_id);
    put_at<std::uint16_t>(bytes, at_vlr + 20, static_cast<std::uint16_t>(vlr.payload.size()));
    if (!vlr.payload.empty()) std::memcpy(&bytes[at_vlr + 54], vlr.payload.data(), vlr.payload.size());
    at_vlr += 54 + vlr.payload.size();
  }
  static const std::size_t rgb_offsets[11] = {0, 0, 20, 28, 0, 28, 0, 30, 30, 0, 30};
  for (std::size_t i = 0; i < file.points.size(); ++i) {
    const LasTestPoint& p = file.points[i];
    const std::size_t at = offset_to_points + i * record;
    put_at<std::int32_t>(bytes, at, p.X);
    put_at<std::int32_t>(bytes, at + 4, p.Y);
    put_at<std::int32_t>(bytes, at + 8, p.Z);
    put_at<std::uint16_t>(bytes, at + 12, p.intensity);
    if (file.point_format < 6) {
      bytes[at + 14] = static_cast<char>((p.return_number & 7) | ((p.number_of_returns & 7) << 3));
      bytes[at + 15] = static_cast<char>((p.classification & 31) | 0x80);  // withheld flag set: must not leak into the class
    } else {
      bytes[at + 14] = static_cast<char>((p.return_number & 15) | ((p.number_of_returns & 15) << 4));
      bytes[at + 15] = static_cast<char>(0xFF);  // flags, channel, scan direction, edge: all set
      bytes[at + 16] = static_cast<char>(p.classification);
    }
    if (rgb_offsets[file.point_format] != 0)
      for (int c = 0; c < 3; ++c) put_at<std::uint16_t>(bytes, at + rgb_offsets[file.point_format] + 2 * c, p.rgb[c]);
    for (std::size_t e = 0; e < file.extra_bytes; ++e) bytes[at + las_test_base_size(file.point_format) + e] = '\x5A';
  }
  return bytes;
}

/// `count` random points around `centre` (file units) with the given scale; classes below 32.
inline std::vector<LasTestPoint> random_las_points(std::size_t count, unsigned seed, int max_class = 31) {
  std::mt19937 random(seed);
  std::uniform_int_distribution<std::int32_t> coordinate(-500000, 500000);
  std::uniform_int_distribution<int> small(0, 65535);
  std::vector<LasTestPoint> points(count);
  for (LasTestPoint& p : points) {
    p.X = coordinate(random);
    p.Y = coordinate(random);
    p.Z = coordinate(random) / 10;
    p.intensity = static_cast<std::uint16_t>(small(random));
    p.classification = static_cast<std::uint8_t>(small(random) % (max_class + 1));
    p.number_of_returns = static_cast<std::uint8_t>(1 + small(random) % 5);
    p.return_number = static_cast<std::uint8_t>(1 + small(random) % p.number_of_returns);
    for (int c = 0; c < 3; ++c) p.rgb[c] = static_cast<std::uint16_t>(small(random));
  }
  return points;
}

}  // namespace quadrix::testing
