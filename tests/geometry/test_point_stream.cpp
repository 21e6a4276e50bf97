// Streaming readers: every streamed format read in chunks gives exactly what read_point_cloud gives
// for the whole file (positions, intensity, labels, dropped non-finite points), and sizes are
// checked before anything is read.
#include "geometry/io.h"
#include "geometry/point_stream.h"
#include "tests/geometry/las_test_writer.h"
#include "tests/geometry/test_io_helpers.h"
#include "tests/test_data.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

namespace quadrix {
namespace {

using testing::ScratchDirectory;
using ::testing::HasSubstr;

/// Everything a stream yields, concatenated.
struct Streamed {
  Eigen::Matrix3Xd positions;
  std::vector<float> intensity;
  std::vector<std::uint32_t> labels;
  std::size_t chunks = 0;
  std::size_t records = 0;
  std::size_t dropped = 0;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
};

Streamed stream_all(const std::string& path, std::size_t chunk_points) {
  const std::unique_ptr<PointStream> stream = open_point_stream(path);
  Streamed all;
  all.origin = stream->origin();
  PointChunk chunk;
  // Positions gathered in a std::vector: growing the matrix chunk by chunk would copy it every time
  // (quadratic under AddressSanitizer, whose realloc never extends in place).
  std::vector<double> coordinates;
  while (stream->read(chunk_points, chunk)) {
    EXPECT_LE(chunk.size(), chunk_points);
    coordinates.insert(coordinates.end(), chunk.positions.data(), chunk.positions.data() + chunk.positions.size());
    all.intensity.insert(all.intensity.end(), chunk.intensity.begin(), chunk.intensity.end());
    all.labels.insert(all.labels.end(), chunk.labels.begin(), chunk.labels.end());
    ++all.chunks;
  }
  EXPECT_EQ(chunk.size(), 0u);
  EXPECT_FALSE(stream->read(chunk_points, chunk));  // stays exhausted
  all.positions = Eigen::Map<const Eigen::Matrix3Xd>(coordinates.data(), 3, static_cast<Eigen::Index>(coordinates.size() / 3));
  all.records = stream->records_read();
  all.dropped = stream->non_finite_dropped();
  if (stream->point_count()) {
    EXPECT_EQ(*stream->point_count(), all.records);
  }
  return all;
}

/// Chunked reading (several chunk sizes) equals the whole-file reader's positions, intensity and labels.
void expect_stream_matches_whole(const std::string& path, bool expect_intensity, bool expect_labels) {
  CloudReadReport report;
  const PointCloud whole = read_point_cloud(path, {}, &report);
  for (std::size_t chunk : {std::size_t{1}, std::size_t{7}, std::size_t{1000}, std::size_t{1} << 30}) {
    SCOPED_TRACE("chunk " + std::to_string(chunk));
    const Streamed streamed = stream_all(path, chunk);
    ASSERT_EQ(static_cast<std::size_t>(streamed.positions.cols()), whole.size());
    EXPECT_TRUE(streamed.positions.cast<float>() == whole.positions);
    EXPECT_EQ(streamed.records, report.points_in_file);
    EXPECT_EQ(streamed.dropped, report.non_finite_dropped);
    if (expect_intensity) EXPECT_EQ(streamed.intensity, whole.intensity);
    else EXPECT_TRUE(streamed.intensity.empty());
    if (expect_labels) EXPECT_EQ(streamed.labels, whole.labels);
    else EXPECT_TRUE(streamed.labels.empty());
  }
}

TEST(PointStream, BinaryPlyChunkedEqualsWhole) {
  ScratchDirectory scratch;
  PointCloud cloud = testing::random_cloud(2500, 11);
  cloud.positions(1, 17) = NAN;  // dropped by both
  const std::string path = scratch.file("cloud.ply");
  write_point_cloud(path, cloud);
  expect_stream_matches_whole(path, true, true);
  // Big-endian with doubles and an element before the vertices.
  std::string bytes = "ply\nformat binary_big_endian 1.0\nelement camera 2\nproperty float f\nelement vertex 3\n"
                      "property double x\nproperty double y\nproperty double z\nproperty uchar label\nend_header\n";
  for (int camera = 0; camera < 2; ++camera) testing::append_big_endian(bytes, 1.5f);
  for (int v = 0; v < 3; ++v) {
    for (int axis = 0; axis < 3; ++axis) testing::append_big_endian(bytes, 5.4e6 + v + 0.125 * axis);
    bytes.push_back(static_cast<char>(v + 1));
  }
  const std::string big = scratch.file("big.ply");
  testing::write_bytes(big, bytes);
  expect_stream_matches_whole(big, false, true);
  const Streamed streamed = stream_all(big, 2);
  EXPECT_EQ(streamed.positions(0, 2), 5.4e6 + 2);  // double kept: float32 would round to 5400002
  EXPECT_EQ(streamed.positions(2, 1), 5.4e6 + 1.25);
  EXPECT_EQ(streamed.origin, Eigen::Vector3d(5.4e6, 5.4e6, 5.4e6));
}

TEST(PointStream, LasChunkedEqualsWholeInEveryFormat) {
  ScratchDirectory scratch;
  for (int format : {0, 1, 3, 6, 8, 10}) {
    SCOPED_TRACE("format " + std::to_string(format));
    testing::LasTestFile file;
    file.version_minor = format >= 6 ? 4 : 2;
    file.point_format = format;
    file.extra_bytes = 3;
    file.offset = Eigen::Vector3d(637000.0, 851000.0, 0.0);
    file.points = testing::random_las_points(1234, 40u + format, format >= 6 ? 255 : 31);
    const std::string path = scratch.file("f" + std::to_string(format) + ".las");
    testing::write_bytes(path, testing::las_test_bytes(file));
    expect_stream_matches_whole(path, true, true);
    const std::unique_ptr<PointStream> stream = open_point_stream(path);
    ASSERT_TRUE(stream->bounds().has_value());
    EXPECT_NEAR(stream->origin().x(), 637000.0, 6000.0);
    EXPECT_EQ(stream->origin().z(), 0.0);
    // Positions in double: exactly X * scale + offset.
    PointChunk chunk;
    ASSERT_TRUE(stream->read(5, chunk));
    for (int i = 0; i < 5; ++i)
      EXPECT_EQ(chunk.positions(0, i), file.points[static_cast<std::size_t>(i)].X * 0.01 + 637000.0);
  }
}

TEST(PointStream, KittiAndNuScenesBinChunkedEqualWhole) {
  ScratchDirectory scratch;
  std::string kitti, nuscenes;
  std::mt19937 random(3);
  std::uniform_real_distribution<float> value(-50.0f, 50.0f);
  for (int i = 0; i < 999; ++i) {
    for (int k = 0; k < 4; ++k) testing::append_raw(kitti, i == 500 && k == 2 ? INFINITY : value(random));
    for (int k = 0; k < 5; ++k) testing::append_raw(nuscenes, value(random));
  }
  testing::write_bytes(scratch.file("scan.bin"), kitti);
  testing::write_bytes(scratch.file("scan.pcd.bin"), nuscenes);
  expect_stream_matches_whole(scratch.file("scan.bin"), true, false);
  expect_stream_matches_whole(scratch.file("scan.pcd.bin"), true, false);
  EXPECT_EQ(stream_all(scratch.file("scan.bin"), 100).dropped, 1u);
}

TEST(PointStream, BinaryPcdChunkedEqualsWhole) {
  ScratchDirectory scratch;
  const PointCloud cloud = testing::random_cloud(3001, 5);
  const std::string path = scratch.file("cloud.pcd");
  write_point_cloud(path, cloud);
  expect_stream_matches_whole(path, true, true);
}

TEST(PointStream, XyzChunkedEqualsWholeAcrossBlockBoundaries) {
  ScratchDirectory scratch;
  std::string text = "# a comment line\n\n";
  std::mt19937 random(8);
  std::uniform_real_distribution<double> value(-1000.0, 1000.0);
  char line[160];
  // About 2.5 MB: lines cross the reader's 1 MB blocks; CRLF endings and trailing comments mixed in.
  for (int i = 0; i < 60000; ++i) {
    std::snprintf(line, sizeof(line), "%.9f %.9f %.9f %.4f%s", value(random), value(random), value(random),
                  value(random), i % 3 == 0 ? "\r\n" : i % 5 == 0 ? "  # note\n" : "\n");
    text += line;
  }
  text += "nan 1 2 3\n1 2 3 4";  // a non-finite point, and a last line without a newline
  const std::string path = scratch.file("cloud.xyz");
  testing::write_bytes(path, text);
  expect_stream_matches_whole(path, true, false);
  EXPECT_EQ(stream_all(path, 4096).dropped, 1u);
}

TEST(PointStream, XyzErrorsNameTheLine) {
  ScratchDirectory scratch;
  const std::string path = scratch.file("bad.xyz");
  testing::write_bytes(path, "1 2 3\n4 5 6\n7 eight 9\n");
  const std::unique_ptr<PointStream> stream = open_point_stream(path);
  PointChunk chunk;
  try {
    while (stream->read(1, chunk)) {
    }
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_THAT(error.what(), HasSubstr(path));
    EXPECT_THAT(error.what(), HasSubstr("line 3"));
  }
}

// Sizes are checked when the stream is opened, before anything is read or allocated.
TEST(PointStream, LyingHeadersAndUnstreamableEncodingsAreRefusedAtOpen) {
  ScratchDirectory scratch;
  auto open_error = [](const std::string& path) -> std::string {
    try {
      open_point_stream(path);
    } catch (const Error& error) {
      return error.what();
    }
    return "(no error)";
  };
  const std::string ply = scratch.file("lies.ply");
  testing::write_bytes(ply, "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n"
                            "property float y\nproperty float z\nend_header\n0123456789ab");
  EXPECT_THAT(open_error(ply), HasSubstr("truncated"));
  const std::string ascii = scratch.file("ascii.ply");
  testing::write_bytes(ascii, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                              "property float z\nend_header\n1 2 3\n");
  EXPECT_THAT(open_error(ascii), HasSubstr("ascii"));
  const std::string pcd = scratch.file("lies.pcd");
  testing::write_bytes(pcd, "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 99\nHEIGHT 1\n"
                            "POINTS 99\nDATA binary\n0123456789ab");
  EXPECT_THAT(open_error(pcd), HasSubstr("truncated"));
  const std::string bin = scratch.file("odd.bin");
  testing::write_bytes(bin, std::string(17, '\0'));
  EXPECT_THAT(open_error(bin), HasSubstr("multiple of 16"));
  testing::LasTestFile file;
  file.points = testing::random_las_points(10, 2);
  std::string las = testing::las_test_bytes(file);
  las.resize(las.size() - 1);
  testing::write_bytes(scratch.file("short.las"), las);
  EXPECT_THAT(open_error(scratch.file("short.las")), HasSubstr("'number of point records'"));
  EXPECT_THAT(open_error(scratch.file("missing.ply")), HasSubstr("cannot open"));
  testing::write_bytes(scratch.file("c.csv"), "x,y,z\n1,2,3\n");
  EXPECT_THAT(open_error(scratch.file("c.csv")), HasSubstr("not streamed"));
}

TEST(PointStream, SharedAutzenTileChunkedEqualsWhole) {
  QUADRIX_REQUIRE_SHARED_DATA("als_autzen/autzen_trim.las");
  expect_stream_matches_whole(testing::shared_data_path("als_autzen/autzen_trim.las"), true, true);
}

TEST(PointStream, SharedKittiScanChunkedEqualsWhole) {
  QUADRIX_REQUIRE_SHARED_DATA("kitti00/velodyne/000000.bin");
  const std::string path = testing::shared_data_path("kitti00/velodyne/000000.bin");
  const Streamed streamed = stream_all(path, 10000);
  const PointCloud whole = read_point_cloud(path);
  EXPECT_TRUE(streamed.positions.cast<float>() == whole.positions);
  EXPECT_TRUE(streamed.origin.isZero(0.0));  // a sensor-frame scan keeps its frame
}

}  // namespace
}  // namespace quadrix
