// Every reader round-trips through the writers: random clouds with all fields, ascii and binary,
// bit-exact floats; hand-made files for the read-only formats (bin, npy, xyz, csv, big-endian PLY).
#include "geometry/io.h"
#include "tests/geometry/test_io_helpers.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace quadrix {
namespace {

using testing::append_big_endian;
using testing::append_raw;
using testing::expect_clouds_equal;
using testing::random_cloud;
using testing::ScratchDirectory;
using testing::write_bytes;

struct WriterCase {
  const char* file;
  bool binary;
  const char* encoding;
};

class WriterRoundTrip : public ::testing::TestWithParam<WriterCase> {};

TEST_P(WriterRoundTrip, AllFieldsBitExact) {
  ScratchDirectory scratch;
  const std::string path = scratch.file(GetParam().file);
  const PointCloud cloud = random_cloud(1000, 7);
  CloudWriteOptions options;
  options.binary = GetParam().binary;
  write_point_cloud(path, cloud, options);
  CloudReadReport report;
  const PointCloud back = read_point_cloud(path, {}, &report);
  expect_clouds_equal(cloud, back);
  EXPECT_EQ(report.encoding, GetParam().encoding);
  EXPECT_EQ(report.points_in_file, 1000u);
  EXPECT_EQ(report.non_finite_dropped, 0u);
}

TEST_P(WriterRoundTrip, PositionsOnlyAndEmptyCloud) {
  ScratchDirectory scratch;
  const std::string path = scratch.file(GetParam().file);
  CloudWriteOptions options;
  options.binary = GetParam().binary;
  const PointCloud cloud = random_cloud(257, 11, false);
  write_point_cloud(path, cloud, options);
  expect_clouds_equal(cloud, read_point_cloud(path));
  write_point_cloud(path, PointCloud{}, options);
  EXPECT_TRUE(read_point_cloud(path).empty());
}

TEST_P(WriterRoundTrip, ExtremeFloatsSurviveText) {
  ScratchDirectory scratch;
  const std::string path = scratch.file(GetParam().file);
  PointCloud cloud;
  cloud.positions.resize(3, 3);
  cloud.positions << std::numeric_limits<float>::max(), std::numeric_limits<float>::denorm_min(), -0.0f,
      std::numeric_limits<float>::min(), 1e-30f, 123456.789f, 0.1f, -std::numeric_limits<float>::max(), 3.0f;
  CloudWriteOptions options;
  options.binary = GetParam().binary;
  write_point_cloud(path, cloud, options);
  const PointCloud back = read_point_cloud(path);
  ASSERT_EQ(back.size(), 3u);
  for (Eigen::Index i = 0; i < 9; ++i) {
    float a = cloud.positions.data()[i], b = back.positions.data()[i];
    EXPECT_EQ(0, std::memcmp(&a, &b, 4)) << "value " << i << ": " << a << " vs " << b;
  }
}

INSTANTIATE_TEST_SUITE_P(Formats, WriterRoundTrip,
                         ::testing::Values(WriterCase{"cloud.ply", true, "binary_little_endian"},
                                           WriterCase{"cloud.ply", false, "ascii"},
                                           WriterCase{"cloud.pcd", true, "binary"},
                                           WriterCase{"cloud.pcd", false, "ascii"}),
                         [](const auto& info) {
                           return std::string(info.param.file).substr(6) + (info.param.binary ? "_binary" : "_ascii");
                         });

TEST(IoRoundTrip, KittiBinThroughPly) {
  ScratchDirectory scratch;
  const PointCloud cloud = random_cloud(500, 3);
  std::string bytes;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    for (int axis = 0; axis < 3; ++axis) append_raw(bytes, cloud.positions(axis, static_cast<Eigen::Index>(i)));
    append_raw(bytes, cloud.intensity[i]);
  }
  write_bytes(scratch.file("scan.bin"), bytes);
  CloudReadReport report;
  const PointCloud read = read_point_cloud(scratch.file("scan.bin"), {}, &report);
  EXPECT_EQ(report.format, CloudFormat::KittiBin);
  EXPECT_EQ(report.fields, (std::vector<std::string>{"x", "y", "z", "intensity"}));
  EXPECT_TRUE(read.positions == cloud.positions);
  EXPECT_EQ(read.intensity, cloud.intensity);
  EXPECT_TRUE(read.labels.empty());
  write_point_cloud(scratch.file("scan.ply"), read);
  expect_clouds_equal(read, read_point_cloud(scratch.file("scan.ply")));
}

TEST(IoRoundTrip, NuScenesBinKeepsRing) {
  ScratchDirectory scratch;
  const PointCloud cloud = random_cloud(300, 4);
  std::string bytes;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    for (int axis = 0; axis < 3; ++axis) append_raw(bytes, cloud.positions(axis, static_cast<Eigen::Index>(i)));
    append_raw(bytes, cloud.intensity[i]);
    append_raw(bytes, static_cast<float>(i % 32));
  }
  write_bytes(scratch.file("scan.pcd.bin"), bytes);
  const PointCloud read = read_point_cloud(scratch.file("scan.pcd.bin"));
  EXPECT_TRUE(read.positions == cloud.positions);
  EXPECT_EQ(read.intensity, cloud.intensity);
  ASSERT_EQ(read.extra_fields.count("ring"), 1u);
  EXPECT_EQ(read.extra_fields.at("ring")[33], 1.0f);
  write_point_cloud(scratch.file("scan.pcd"), read, {CloudFormat::Auto, false});
  expect_clouds_equal(read, read_point_cloud(scratch.file("scan.pcd")));
  CloudReadOptions no_extras;
  no_extras.keep_extra_fields = false;
  EXPECT_TRUE(read_point_cloud(scratch.file("scan.pcd.bin"), no_extras).extra_fields.empty());
}

// Builds a .npy file of `rows` x `columns` doubles/floats with the given header options.
std::string make_npy(const Eigen::MatrixXd& values, bool float32, bool big_endian, bool fortran, int version) {
  const std::string descr = std::string(big_endian ? ">" : "<") + (float32 ? "f4" : "f8");
  std::string dict = "{'descr': '" + descr + "', 'fortran_order': " + (fortran ? "True" : "False") + ", 'shape': (" +
                     std::to_string(values.rows()) + ", " + std::to_string(values.cols()) + "), }";
  const std::size_t prefix = version == 1 ? 10 : 12;
  while ((prefix + dict.size() + 1) % 64 != 0) dict += ' ';
  dict += '\n';
  std::string bytes = "\x93NUMPY";
  bytes += static_cast<char>(version);
  bytes += '\0';
  if (version == 1) {
    append_raw(bytes, static_cast<std::uint16_t>(dict.size()));
  } else {
    append_raw(bytes, static_cast<std::uint32_t>(dict.size()));
  }
  bytes += dict;
  auto put = [&](double value) {
    if (float32) {
      big_endian ? append_big_endian(bytes, static_cast<float>(value)) : append_raw(bytes, static_cast<float>(value));
    } else {
      big_endian ? append_big_endian(bytes, value) : append_raw(bytes, value);
    }
  };
  if (fortran) {
    for (Eigen::Index c = 0; c < values.cols(); ++c)
      for (Eigen::Index r = 0; r < values.rows(); ++r) put(values(r, c));
  } else {
    for (Eigen::Index r = 0; r < values.rows(); ++r)
      for (Eigen::Index c = 0; c < values.cols(); ++c) put(values(r, c));
  }
  return bytes;
}

TEST(IoRoundTrip, NpyEveryVariant) {
  ScratchDirectory scratch;
  std::mt19937 generator(5);
  std::uniform_real_distribution<double> value(-50, 50);
  Eigen::MatrixXd values(40, 4);
  for (Eigen::Index i = 0; i < values.size(); ++i) values.data()[i] = value(generator);
  for (bool float32 : {false, true})
    for (bool big_endian : {false, true})
      for (bool fortran : {false, true})
        for (int version : {1, 2, 3}) {
          SCOPED_TRACE(::testing::Message() << "float32=" << float32 << " big=" << big_endian << " fortran=" << fortran
                                            << " v" << version);
          const std::string path = scratch.file("cloud.npy");
          write_bytes(path, make_npy(values, float32, big_endian, fortran, version));
          CloudReadReport report;
          const PointCloud cloud = read_point_cloud(path, {}, &report);
          ASSERT_EQ(cloud.size(), 40u);
          EXPECT_EQ(report.fields, (std::vector<std::string>{"x", "y", "z", "intensity"}));
          for (Eigen::Index r = 0; r < 40; ++r) {
            for (int axis = 0; axis < 3; ++axis) EXPECT_EQ(cloud.positions(axis, r), static_cast<float>(values(r, axis)));
            EXPECT_EQ(cloud.intensity[r], static_cast<float>(values(r, 3)));
          }
          write_point_cloud(scratch.file("cloud.ply"), cloud);
          expect_clouds_equal(cloud, read_point_cloud(scratch.file("cloud.ply")));
        }
}

TEST(IoRoundTrip, XyzColumnRulesAndComments) {
  ScratchDirectory scratch;
  write_bytes(scratch.file("a.xyz"), "# a comment\n1 2 3\n\n  4\t5 6  # trailing comment\r\n7e0 +8 -9.5\n");
  CloudReadReport report;
  PointCloud cloud = read_point_cloud(scratch.file("a.xyz"), {}, &report);
  ASSERT_EQ(cloud.size(), 3u);
  EXPECT_EQ(cloud.positions(2, 2), -9.5f);
  EXPECT_EQ(cloud.positions(1, 2), 8.0f);
  EXPECT_TRUE(cloud.intensity.empty());
  write_bytes(scratch.file("b.txt"), "1 2 3 0.5\n4 5 6 0.25\n");
  cloud = read_point_cloud(scratch.file("b.txt"));
  EXPECT_EQ(cloud.intensity, (std::vector<float>{0.5f, 0.25f}));
  write_bytes(scratch.file("c.xyz"), "1 2 3 255 0 10\n4 5 6 1 2 3\n");
  cloud = read_point_cloud(scratch.file("c.xyz"));
  ASSERT_EQ(cloud.colors.size(), 2u);
  EXPECT_EQ(cloud.colors[0], (std::array<std::uint8_t, 3>{255, 0, 10}));
  write_bytes(scratch.file("d.xyz"), "1 2 3 7 8\n");
  cloud = read_point_cloud(scratch.file("d.xyz"), {}, &report);
  EXPECT_EQ(report.fields, (std::vector<std::string>{"x", "y", "z", "column_4", "column_5"}));
  EXPECT_EQ(cloud.extra_fields.at("column_5")[0], 8.0f);
  write_point_cloud(scratch.file("d.ply"), cloud, {CloudFormat::Auto, false});
  expect_clouds_equal(cloud, read_point_cloud(scratch.file("d.ply")));
}

TEST(IoRoundTrip, CsvWithAndWithoutHeader) {
  ScratchDirectory scratch;
  write_bytes(scratch.file("a.csv"), "\"Z\", X ,y,Intensity,label,temperature\n3,1,2,0.5,7,20.5\n6,4,5,0.75,9,-1\n");
  CloudReadReport report;
  const PointCloud cloud = read_point_cloud(scratch.file("a.csv"), {}, &report);
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.point(0), Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(cloud.point(1), Eigen::Vector3d(4, 5, 6));
  EXPECT_EQ(cloud.intensity, (std::vector<float>{0.5f, 0.75f}));
  EXPECT_EQ(cloud.labels, (std::vector<std::uint32_t>{7, 9}));
  EXPECT_EQ(cloud.extra_fields.at("temperature"), (std::vector<float>{20.5f, -1.0f}));
  EXPECT_EQ(report.fields, (std::vector<std::string>{"Z", "X", "y", "Intensity", "label", "temperature"}));
  write_bytes(scratch.file("b.csv"), "1,2,3\n4, 5, 6\n");
  EXPECT_EQ(read_point_cloud(scratch.file("b.csv")).size(), 2u);
  write_point_cloud(scratch.file("a.pcd"), cloud);
  expect_clouds_equal(cloud, read_point_cloud(scratch.file("a.pcd")));
}

// Builds a binary PLY with every property type, in either byte order, with faces before and after the vertices.
std::string make_typed_ply(bool big_endian) {
  std::string header = std::string("ply\nformat ") + (big_endian ? "binary_big_endian" : "binary_little_endian") +
                       " 1.0\ncomment test\nelement face 1\nproperty list uchar int vertex_indices\n"
                       "element vertex 2\nproperty double x\nproperty float32 y\nproperty int16 z\n"
                       "property uint8 red\nproperty uchar green\nproperty uchar blue\nproperty ushort reflectance\n"
                       "property uint label\nproperty char tag\nproperty int count\nproperty list uint8 float32 extra_list\n"
                       "element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n";
  std::string bytes = header;
  auto put = [&](auto value) { big_endian ? append_big_endian(bytes, value) : append_raw(bytes, value); };
  put(std::uint8_t{3});
  put(std::int32_t{0});
  put(std::int32_t{1});
  put(std::int32_t{0});
  for (int v = 0; v < 2; ++v) {
    put(1.5 + v);
    put(-2.25f - v);
    put(static_cast<std::int16_t>(-300 + v));
    put(std::uint8_t{10});
    put(std::uint8_t{20});
    put(static_cast<std::uint8_t>(250 + v));
    put(static_cast<std::uint16_t>(65535 - v));
    put(static_cast<std::uint32_t>(4000000000u + v));
    put(static_cast<std::int8_t>(-5));
    put(static_cast<std::int32_t>(-70000));
    put(std::uint8_t{2});
    put(1.0f);
    put(2.0f);
  }
  put(std::int32_t{0});
  put(std::int32_t{1});
  return bytes;
}

TEST(IoRoundTrip, PlyEveryPropertyTypeBothByteOrders) {
  ScratchDirectory scratch;
  for (bool big_endian : {false, true}) {
    SCOPED_TRACE(big_endian ? "big endian" : "little endian");
    write_bytes(scratch.file("typed.ply"), make_typed_ply(big_endian));
    CloudReadReport report;
    const PointCloud cloud = read_point_cloud(scratch.file("typed.ply"), {}, &report);
    EXPECT_EQ(report.encoding, big_endian ? "binary_big_endian" : "binary_little_endian");
    ASSERT_EQ(cloud.size(), 2u);
    EXPECT_EQ(cloud.point(1), Eigen::Vector3d(2.5, -3.25, -299));
    EXPECT_EQ(cloud.colors[1], (std::array<std::uint8_t, 3>{10, 20, 251}));
    EXPECT_EQ(cloud.intensity, (std::vector<float>{65535.0f, 65534.0f}));
    EXPECT_EQ(cloud.labels, (std::vector<std::uint32_t>{4000000000u, 4000000001u}));
    EXPECT_EQ(cloud.extra_fields.at("tag"), (std::vector<float>{-5.0f, -5.0f}));
    EXPECT_EQ(cloud.extra_fields.at("count"), (std::vector<float>{-70000.0f, -70000.0f}));
    EXPECT_EQ(cloud.extra_fields.count("extra_list"), 0u);
    write_point_cloud(scratch.file("back.ply"), cloud, {CloudFormat::Auto, false});
    expect_clouds_equal(cloud, read_point_cloud(scratch.file("back.ply")));
  }
}

TEST(IoRoundTrip, AsciiPlySkipsFacesBeforeVertices) {
  ScratchDirectory scratch;
  write_bytes(scratch.file("mesh.ply"),
              "ply\r\nformat ascii 1.0\r\nelement face 2\r\nproperty list uchar int vertex_indices\r\n"
              "element vertex 3\r\nproperty float x\r\nproperty float y\r\nproperty float z\r\n"
              "property float red\r\nproperty float green\r\nproperty float blue\r\nend_header\r\n"
              "3 0 1 2\r\n4 0 1 2 0\r\n0 0 0 1 0.5 0\r\n1 0 0 0 1 0\r\n0 1 0 0 0 1\r\n");
  const PointCloud cloud = read_point_cloud(scratch.file("mesh.ply"));
  ASSERT_EQ(cloud.size(), 3u);
  EXPECT_EQ(cloud.point(1), Eigen::Vector3d(1, 0, 0));
  EXPECT_EQ(cloud.colors[0], (std::array<std::uint8_t, 3>{255, 128, 0}));
}

TEST(IoRoundTrip, MeshPlyWithColours) {
  ScratchDirectory scratch;
  TriangleMesh mesh;
  mesh.vertices.resize(3, 4);
  mesh.vertices << 0, 1, 0, 1e6 + 0.123456789, 0, 0, 1, 2, 0, 0, 0, -3;
  mesh.triangles = {Eigen::Vector3i(0, 1, 2), Eigen::Vector3i(1, 3, 2)};
  mesh.colors = {{{1, 2, 3}}, {{4, 5, 6}}, {{7, 8, 9}}, {{250, 251, 252}}};
  write_mesh_ply(scratch.file("mesh.ply"), mesh);
  const TriangleMesh back = read_mesh_ply(scratch.file("mesh.ply"));
  EXPECT_TRUE(back.vertices == mesh.vertices);
  EXPECT_EQ(back.triangles, mesh.triangles);
  EXPECT_EQ(back.colors, mesh.colors);
  const PointCloud vertices = read_point_cloud(scratch.file("mesh.ply"));
  EXPECT_EQ(vertices.size(), 4u);
  EXPECT_EQ(vertices.colors, mesh.colors);
  mesh.colors.clear();
  write_mesh_ply(scratch.file("plain.ply"), mesh);
  EXPECT_TRUE(read_mesh_ply(scratch.file("plain.ply")).colors.empty());
  mesh.triangles.push_back(Eigen::Vector3i(0, 1, 4));
  EXPECT_THROW(write_mesh_ply(scratch.file("bad.ply"), mesh), Error);
  EXPECT_FALSE(std::filesystem::exists(scratch.file("bad.ply")));
}

TEST(IoRoundTrip, NonFinitePointsDroppedAndCounted) {
  ScratchDirectory scratch;
  PointCloud cloud = random_cloud(10, 9);
  cloud.positions(0, 2) = std::numeric_limits<float>::quiet_NaN();
  cloud.positions(2, 5) = -std::numeric_limits<float>::infinity();
  for (const char* name : {"nan.ply", "nan.pcd"}) {
    for (bool binary : {true, false}) {
      SCOPED_TRACE(std::string(name) + (binary ? " binary" : " ascii"));
      write_point_cloud(scratch.file(name), cloud, {CloudFormat::Auto, binary});
      CloudReadReport report;
      const PointCloud back = read_point_cloud(scratch.file(name), {}, &report);
      EXPECT_EQ(report.points_in_file, 10u);
      EXPECT_EQ(report.non_finite_dropped, 2u);
      ASSERT_EQ(back.size(), 8u);
      EXPECT_TRUE(back.positions.allFinite());
      EXPECT_EQ(back.labels[2], cloud.labels[3]);
      EXPECT_EQ(back.colors[4], cloud.colors[6]);
      EXPECT_EQ(back.extra_fields.at("normal_x")[7], cloud.extra_fields.at("normal_x")[9]);
    }
  }
}

TEST(IoRoundTrip, SemanticKittiLabels) {
  ScratchDirectory scratch;
  std::string bytes;
  for (std::uint32_t i = 0; i < 5; ++i) append_raw(bytes, (i << 16) | (40 + i));
  write_bytes(scratch.file("000000.label"), bytes);
  const std::vector<std::uint32_t> labels = read_semantic_kitti_labels(scratch.file("000000.label"), 5);
  ASSERT_EQ(labels.size(), 5u);
  EXPECT_EQ(labels[3] & 0xFFFF, 43u);
  EXPECT_EQ(labels[3] >> 16, 3u);
  EXPECT_EQ(read_semantic_kitti_labels(scratch.file("000000.label")).size(), 5u);
}

TEST(IoRoundTrip, FormatNamesAndExtensions) {
  EXPECT_EQ(cloud_format_from_path("/a/b/000000.bin"), CloudFormat::KittiBin);
  EXPECT_EQ(cloud_format_from_path("scan.PCD.BIN"), CloudFormat::NuScenesBin);
  EXPECT_EQ(cloud_format_from_path("x.Ply"), CloudFormat::Ply);
  EXPECT_EQ(cloud_format_from_path("x.pcd"), CloudFormat::Pcd);
  EXPECT_EQ(cloud_format_from_path("x.txt"), CloudFormat::Xyz);
  EXPECT_EQ(cloud_format_from_path("x.csv"), CloudFormat::Csv);
  EXPECT_EQ(cloud_format_from_path("x.npy"), CloudFormat::Npy);
  EXPECT_EQ(cloud_format_from_path("x.LAS"), CloudFormat::Las);
  for (CloudFormat format : {CloudFormat::Auto, CloudFormat::KittiBin, CloudFormat::NuScenesBin, CloudFormat::Ply,
                             CloudFormat::Pcd, CloudFormat::Xyz, CloudFormat::Csv, CloudFormat::Npy, CloudFormat::Las})
    EXPECT_EQ(cloud_format_from_name(cloud_format_name(format)), format);
  EXPECT_EQ(cloud_format_from_name("bin"), CloudFormat::KittiBin);
  EXPECT_THAT([] { cloud_format_from_name("e57"); }, ::testing::ThrowsMessage<Error>(::testing::HasSubstr("'e57'")));
  EXPECT_THAT([] { cloud_format_from_path("/tmp/cloud.e57"); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr("/tmp/cloud.e57")));
  EXPECT_THAT([] { cloud_format_from_path("/tmp/cloud.laz"); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr("pdal translate")));
}

TEST(IoRoundTrip, FormatOverrideReadsOddExtension) {
  ScratchDirectory scratch;
  const PointCloud cloud = random_cloud(20, 1);
  write_point_cloud(scratch.file("cloud.data"), cloud, {CloudFormat::Ply, true});
  CloudReadOptions options;
  options.format = CloudFormat::Ply;
  expect_clouds_equal(cloud, read_point_cloud(scratch.file("cloud.data"), options));
}

}  // namespace
}  // namespace quadrix
