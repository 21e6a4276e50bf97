// Corrupted variants of every format fail with a quadrix::Error naming the file and what was wrong;
// NaN coordinates are dropped and counted (or rejected on request); writers are atomic.
#include "geometry/io.h"
#include "tests/geometry/test_io_helpers.h"
#include "tests/test_data.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <limits>

namespace quadrix {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;
using testing::append_raw;
using testing::random_cloud;
using testing::read_bytes;
using testing::ScratchDirectory;
using testing::write_bytes;

// Expects reading `path` (content `bytes`) to throw an Error containing the path and `detail`.
void expect_read_error(const std::string& path, const std::string& bytes, const std::string& detail,
                       const CloudReadOptions& options = {}) {
  write_bytes(path, bytes);
  EXPECT_THAT([&] { read_point_cloud(path, options); },
              ThrowsMessage<Error>(AllOf(HasSubstr(path), HasSubstr(detail))))
      << "content: " << bytes.substr(0, 200);
}

std::string float_records(const std::vector<float>& values) {
  std::string bytes;
  for (float value : values) append_raw(bytes, value);
  return bytes;
}

const std::string kPlyHeader =
    "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n";

TEST(IoErrors, MissingFileAndDirectory) {
  ScratchDirectory scratch;
  EXPECT_THAT([&] { read_point_cloud(scratch.file("absent.ply")); },
              ThrowsMessage<Error>(AllOf(HasSubstr(scratch.file("absent.ply")), HasSubstr("cannot open"))));
  const std::string directory = scratch.file("folder.ply");
  std::filesystem::create_directories(directory);
  EXPECT_THAT([&] { read_point_cloud(directory); }, ThrowsMessage<Error>(HasSubstr(directory)));
}

TEST(IoErrors, KittiAndNuScenesSizes) {
  ScratchDirectory scratch;
  expect_read_error(scratch.file("a.bin"), float_records({1, 2, 3, 4, 5}) + "x", "not a multiple of 16");
  expect_read_error(scratch.file("a.pcd.bin"), float_records({1, 2, 3, 4}), "not a multiple of 20");
  write_bytes(scratch.file("a.label"), "12345");
  EXPECT_THAT([&] { read_semantic_kitti_labels(scratch.file("a.label")); },
              ThrowsMessage<Error>(AllOf(HasSubstr(scratch.file("a.label")), HasSubstr("multiple of 4"))));
  write_bytes(scratch.file("a.label"), "12345678");
  EXPECT_THAT([&] { read_semantic_kitti_labels(scratch.file("a.label"), 3); },
              ThrowsMessage<Error>(AllOf(HasSubstr(scratch.file("a.label")), HasSubstr("2 labels but the scan has 3"))));
}

TEST(IoErrors, PlyHeaderProblems) {
  ScratchDirectory scratch;
  const std::string path = scratch.file("bad.ply");
  expect_read_error(path, "plx\nformat ascii 1.0\nend_header\n", "bad magic");
  expect_read_error(path, "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n", "no 'end_header'");
  expect_read_error(path, "ply\nformat ascii 2.0\nend_header\n", "version '2.0'");
  expect_read_error(path, "ply\nformat binary_middle_endian 1.0\nend_header\n", "unknown encoding 'binary_middle_endian'");
  expect_read_error(path, "ply\nformat ascii 1.0\nelement vertex nan\nend_header\n", "header line 3");
  expect_read_error(path, "ply\nformat ascii 1.0\nelement vertex -5\nend_header\n", "non-negative integer count");
  expect_read_error(path,
                    "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float16 x\nend_header\n",
                    "unknown property type 'float16'");
  expect_read_error(path, "ply\nformat ascii 1.0\nelement vertex 1\nproperty list uchar half idx\nend_header\n",
                    "unknown property type 'half'");
  expect_read_error(path, "ply\nformat ascii 1.0\nproperty float x\nend_header\n", "'property' before any 'element'");
  expect_read_error(path, "ply\nformat ascii 1.0\nelement face 0\nend_header\n", "no 'vertex' element");
  expect_read_error(path, "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nend_header\n",
                    "no 'z' field");
  expect_read_error(path, "ply\nelement vertex 0\nend_header\n", "no 'format' line");
  expect_read_error(path, "ply\nformat ascii 1.0\nbogus line\nend_header\n", "unknown header keyword 'bogus'");
}

TEST(IoErrors, PlyBodyProblems) {
  ScratchDirectory scratch;
  const std::string path = scratch.file("bad.ply");
  expect_read_error(path, kPlyHeader + "1 2 3\n", "truncated");
  expect_read_error(path, kPlyHeader + "1 2 3\n4 5\n", "line 9");
  expect_read_error(path, kPlyHeader + "1 2 3\n4 5 abc\n", "'abc' is not a number");
  expect_read_error(path, kPlyHeader + "1 2 3\n4 5 6 7\n", "line 9");
  std::string binary = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                       "property float z\nend_header\n";
  expect_read_error(path, binary + float_records({1, 2, 3, 4, 5, 6, 7, 8}), "truncated");
  std::string with_list = "ply\nformat binary_little_endian 1.0\nelement face 1\nproperty list uchar int idx\n"
                          "element vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  expect_read_error(path, with_list + std::string(1, '\x03') + float_records({0}), "truncated");
  expect_read_error(path,
                    "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                    "property int label\nend_header\n1 2 3 -1\n",
                    "labels must be integers");
}

TEST(IoErrors, PcdProblems) {
  ScratchDirectory scratch;
  const std::string path = scratch.file("bad.pcd");
  const std::string header = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\n"
                             "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\n";
  expect_read_error(path, "hello world\n", "unknown PCD header key 'hello'");
  expect_read_error(path, "", "bad magic");
  expect_read_error(path, "VERSION 0.7\nFIELDS x y z\n", "no DATA line");
  expect_read_error(path, header + "DATA ascii\n1 2 3\n", "truncated");
  expect_read_error(path, header + "DATA ascii\n1 2 3\n1 2\n", "line 12");
  expect_read_error(path, header + "DATA ascii\n1 2 3\n1 2 oops\n", "'oops' is not a number");
  expect_read_error(path, header + "DATA binary\n" + float_records({1, 2, 3, 4}), "truncated");
  expect_read_error(path, header + "DATA binary_compressed\n" + float_records({0}), "truncated");
  std::string compressed = header + "DATA binary_compressed\n";
  append_raw(compressed, std::uint32_t{4});
  append_raw(compressed, std::uint32_t{24});
  compressed += "\xff\xff\xff\xff";
  expect_read_error(path, compressed, "LZF data is corrupt");
  expect_read_error(path, header + "DATA zipped\n", "DATA must be ascii, binary or binary_compressed");
  expect_read_error(path,
                    "FIELDS x y z\nSIZE 4 4\nTYPE F F F\nWIDTH 1\nPOINTS 1\nDATA ascii\n1 2 3\n",
                    "SIZE has 2 entries for 3 FIELDS");
  expect_read_error(path, "FIELDS x y z\nSIZE 4 4 2\nTYPE F F F\nWIDTH 1\nPOINTS 1\nDATA ascii\n1 2 3\n",
                    "unsupported TYPE F SIZE 2");
  expect_read_error(path, "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 2\nHEIGHT 2\nPOINTS 3\nDATA ascii\n",
                    "POINTS 3 differs from WIDTH x HEIGHT = 4");
}

TEST(IoErrors, NpyProblems) {
  ScratchDirectory scratch;
  const std::string path = scratch.file("bad.npy");
  auto npy = [](const std::string& dict, const std::string& data) {
    std::string bytes = "\x93NUMPY\x01";
    bytes += '\0';
    append_raw(bytes, static_cast<std::uint16_t>(dict.size()));
    return bytes + dict + data;
  };
  expect_read_error(path, "PK\x03\x04 not numpy", "bad magic");
  expect_read_error(path, npy("{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }\n", float_records({1, 2})),
                    "truncated");
  expect_read_error(path, npy("{'descr': '<i4', 'fortran_order': False, 'shape': (1, 3), }\n", float_records({1, 2, 3})),
                    "dtype '<i4' is not supported");
  expect_read_error(path, npy("{'descr': '<f4', 'fortran_order': False, 'shape': (2, 2), }\n", float_records({1, 2, 3, 4})),
                    "2 column(s)");
  expect_read_error(path, npy("{'descr': '<f4', 'shape': (1, 3), }\n", float_records({1, 2, 3})), "fortran_order");
  expect_read_error(path, npy("{'descr': '<f4', 'fortran_order': False, 'shape': (1, 3, 1), }\n", float_records({1, 2, 3})),
                    "not 1-D or 2-D");
  std::string huge_header = "\x93NUMPY\x01";
  huge_header += '\0';
  append_raw(huge_header, std::uint16_t{60000});
  expect_read_error(path, huge_header + "{'descr'", "truncated .npy header");
}

TEST(IoErrors, TextProblems) {
  ScratchDirectory scratch;
  expect_read_error(scratch.file("a.xyz"), "1 2 3\n4 5 6\n7 8 nine\n", "line 3: 'nine' is not a number");
  expect_read_error(scratch.file("a.xyz"), "1 2 3\n4 5 6 7\n", "line 2: has 4 values, expected 3");
  expect_read_error(scratch.file("a.xyz"), "1 2\n", "expected at least x, y, z");
  expect_read_error(scratch.file("a.xyz"), "x y z\n1 2 3\n", "line 1: 'x' is not a number");
  expect_read_error(scratch.file("a.csv"), "a,b,c\n1,2,3\n", "no 'x' field");
  expect_read_error(scratch.file("a.csv"), "x,y,z\n1,2\n", "line 2: has 2 values but the header names 3 columns");
  expect_read_error(scratch.file("a.csv"), "x,y,z\n1,2,3\n1,,3\n", "line 3: '' is not a number");
}

TEST(IoErrors, UnknownExtensionNamesFile) {
  ScratchDirectory scratch;
  expect_read_error(scratch.file("cloud.e57"), "ASTM-E57", "unknown point-cloud extension");
}

// NaN coordinates in an otherwise good file: dropped and counted by default, an Error on request.
TEST(IoErrors, NanCoordinatesDroppedOrRejected) {
  ScratchDirectory scratch;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  PointCloud cloud = random_cloud(4, 2);
  cloud.positions(1, 1) = nan;
  write_point_cloud(scratch.file("nan.ply"), cloud);
  write_point_cloud(scratch.file("nan.pcd"), cloud, {CloudFormat::Auto, false});
  write_bytes(scratch.file("nan.bin"), float_records({1, 2, 3, 0, 4, nan, 6, 0, 7, 8, 9, 0}));
  write_bytes(scratch.file("nan.xyz"), "1 2 3\n4 nan 6\n7 8 inf\n");
  for (const char* name : {"nan.ply", "nan.pcd", "nan.bin", "nan.xyz"}) {
    SCOPED_TRACE(name);
    const std::string path = scratch.file(name);
    CloudReadReport report;
    const PointCloud read = read_point_cloud(path, {}, &report);
    EXPECT_GE(report.non_finite_dropped, 1u);
    EXPECT_EQ(read.size() + report.non_finite_dropped, report.points_in_file);
    EXPECT_TRUE(read.positions.allFinite());
    CloudReadOptions strict;
    strict.reject_non_finite = true;
    EXPECT_THAT([&] { read_point_cloud(path, strict); },
                ThrowsMessage<Error>(AllOf(HasSubstr(path), HasSubstr("point 1 has a non-finite y"))));
  }
}

TEST(IoErrors, AtomicWriterKeepsOldFileOnFailure) {
  ScratchDirectory scratch;
  const std::string path = scratch.file("keep.ply");
  write_bytes(path, "original contents");
  EXPECT_THROW(write_file_atomically(path,
                                     [](std::ostream& stream) {
                                       stream << "half a file";
                                       throw Error("simulated failure while writing");
                                     }),
               Error);
  EXPECT_EQ(read_bytes(path), "original contents");
  // No temporary is left behind.
  std::size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(scratch.path())) {
    ++files;
    EXPECT_EQ(entry.path().filename(), "keep.ply");
  }
  EXPECT_EQ(files, 1u);
  write_file_atomically(path, [](std::ostream& stream) { stream << "new"; });
  EXPECT_EQ(read_bytes(path), "new");
  EXPECT_THAT([&] { write_file_atomically(scratch.file("no/such/dir/x.ply"), [](std::ostream&) {}); },
              ThrowsMessage<Error>(HasSubstr("does not exist")));
}

TEST(IoErrors, WritersRejectInconsistentClouds) {
  ScratchDirectory scratch;
  PointCloud cloud = random_cloud(5, 1);
  cloud.intensity.pop_back();
  const std::string path = scratch.file("x.ply");
  EXPECT_THAT([&] { write_point_cloud(path, cloud); },
              ThrowsMessage<Error>(AllOf(HasSubstr(path), HasSubstr("'intensity' has 4 values for 5 points"))));
  EXPECT_FALSE(std::filesystem::exists(path));
  cloud = random_cloud(5, 1);
  cloud.extra_fields["bad name"] = std::vector<float>(5, 0.0f);
  EXPECT_THAT([&] { write_point_cloud(path, cloud); }, ThrowsMessage<Error>(HasSubstr("'bad name'")));
  cloud.extra_fields.erase("bad name");
  cloud.extra_fields["intensity"] = std::vector<float>(5, 0.0f);
  EXPECT_THAT([&] { write_point_cloud(path, cloud); }, ThrowsMessage<Error>(HasSubstr("would be read back")));
  EXPECT_THAT([&] { write_point_cloud(scratch.file("x.xyz"), random_cloud(2, 1)); },
              ThrowsMessage<Error>(HasSubstr("not supported")));
}

TEST(IoErrors, PoseFiles) {
  ScratchDirectory scratch;
  const std::string path = scratch.file("T.txt");
  auto expect_pose_error = [&](const std::string& text, const std::string& detail) {
    write_bytes(path, text);
    EXPECT_THAT([&] { read_pose_matrix(path); }, ThrowsMessage<Error>(AllOf(HasSubstr(path), HasSubstr(detail))))
        << text;
  };
  expect_pose_error("1 0 0 0\n0 1 0 0\n0 0 x 0\n0 0 0 1\n", "line 3: 'x' is not a number");
  write_bytes(path, "1 0 0 0.5\n0 1 0 0\n0 0 1 0\n");
  EXPECT_EQ(read_pose_matrix(path).translation(), Eigen::Vector3d(0.5, 0, 0));
  expect_pose_error("1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n5\n", "more than 16 numbers");
  expect_pose_error("1 0 0 0\n0 1 0 0\n", "found 8 numbers");
  expect_pose_error("1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 1 1\n", "bottom row is not 0 0 0 1");
  expect_pose_error("1 0 0 0\n0 1.1 0 0\n0 0 1 0\n0 0 0 1\n", "not orthonormal");
  expect_pose_error("1 0 0 0\n0 1 0 0\n0 0 -1 0\n0 0 0 1\n", "reflection");
  expect_pose_error("1 0 0 nan\n0 1 0 0\n0 0 1 0\n0 0 0 1\n", "non-finite");

  write_bytes(path, "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 1 0 1 0 0 0 0 1 0 7\n");
  EXPECT_THAT([&] { read_kitti_poses(path); },
              ThrowsMessage<Error>(AllOf(HasSubstr(path), HasSubstr("line 2: expected 12 numbers"))));
  write_bytes(path, "P0: 1 0 0 0 0 1 0 0 0 0 1 0\nTr: 1 0 0 0 0 1 0 0 0 0 1\n");
  EXPECT_THAT([&] { read_kitti_calibration(path); },
              ThrowsMessage<Error>(AllOf(HasSubstr(path), HasSubstr("line 2"), HasSubstr("found 11"))));
  write_bytes(path, "P0: 1 0 0 0 0 1 0 0 0 0 1 0\n");
  EXPECT_THAT([&] { read_kitti_calibration(path); }, ThrowsMessage<Error>(HasSubstr("no 'Tr:'")));
  write_bytes(path, "P0: 1 0 0 0 0 1 0 0 0 0 1 0\nTr: 0 -1 0 1 0 0 -1 2 1 0 0 3\n");
  const Eigen::Isometry3d tr = read_kitti_calibration(path);
  EXPECT_EQ(tr.translation(), Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(tr(2, 0), 1.0);
}

TEST(IoErrors, PoseWriteReadExact) {
  ScratchDirectory scratch;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  pose.translation() = Eigen::Vector3d(1.0 / 3.0, -2e-17, 12345.6789);
  write_pose_matrix(scratch.file("T.txt"), pose);
  EXPECT_TRUE(read_pose_matrix(scratch.file("T.txt")).matrix() == pose.matrix());
}

// Truncated copies of the real files fail with a clear Error naming the copy.
TEST(IoErrors, TruncatedRealFiles) {
  ScratchDirectory scratch;
  const std::pair<const char*, const char*> cases[] = {
      {"kitti00/velodyne/000000.bin", "multiple of 16"},
      {"hdl32_pair/source.ply", "truncated"},
      {"kitti00/velodyne/004438.ply", "truncated"},
      {"single_scans/table_scene_mug_stereo_textured.pcd", "truncated"},
      {"quadricsreg_demo/cross_avia_vlp_source_1.pcd", "truncated"},
      {"single_scans/lamppost.pcd", "truncated"},
      {"3dmatch_demo/src.npy", "truncated"},
      {"single_scans/nuscenes_n008-2018-08-01-15-16-36-0400__LIDAR_TOP__1533151603597909.pcd.bin", "multiple of 20"},
  };
  for (const auto& [relative, detail] : cases) {
    QUADRIX_REQUIRE_SHARED_DATA(relative);
    SCOPED_TRACE(relative);
    const std::string bytes = read_bytes(testing::shared_data_path(relative));
    const std::string name = std::filesystem::path(relative).filename().string();
    // Cut in the middle of a record (odd offset) at 60% of the file.
    const std::size_t cut = bytes.size() * 3 / 5 | 1;
    expect_read_error(scratch.file(name), bytes.substr(0, cut), detail);
  }
}

// Crash reproducers of the fuzz harnesses (tests/fuzz/regressions/<harness>/): each is now an Error
// naming the file and what was wrong, found before anything is sized to a count in the file.
void expect_reproducer_error(const std::string& harness, const std::string& name, const std::string& detail) {
  const std::string path = testing::fuzz_regression_path(harness, name);
  ASSERT_TRUE(std::filesystem::exists(path)) << path;
  EXPECT_THAT([&] { read_point_cloud(path); }, ThrowsMessage<Error>(AllOf(HasSubstr(path), HasSubstr(detail))));
}

TEST(IoErrorsFuzzRegressions, NpyWithZeroRowsAndBillionsOfColumns) {
  // shape (0, 400000000000): decoding looped over every column; the cloud reader then allocated one each.
  expect_reproducer_error("npy", "rows_0_columns_4e11.npy", ".npy array has 400000000000 columns, more than the 65536");
  const std::string path = testing::fuzz_regression_path("npy", "rows_0_columns_4e11.npy");
  EXPECT_THAT([&] { read_pose_matrix(path); },
              ThrowsMessage<Error>(AllOf(HasSubstr(path), HasSubstr("4x4 or 3x4 array, found 0x400000000000"))));
}

TEST(IoErrorsFuzzRegressions, PcdCountBeyondTheValuesAPointSupported) {
  // COUNT 19999999 for two points: 20 million columns were allocated before the data size was checked.
  expect_reproducer_error("pcd", "count_19999999.pcd", "COUNT of field 'x' is 19999999, more than the 65536 values");
}

// Header counts a PCD body cannot hold are refused before any allocation sized to them (ascii
// columns grow line by line instead).
TEST(IoErrorsFuzzRegressions, PcdPointCountsTheDataCannotHold) {
  ScratchDirectory scratch;
  const std::string path = scratch.file("huge.pcd");
  const std::string header = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1000000000000\nPOINTS 1000000000000\n";
  expect_read_error(path, header + "DATA ascii\n1 2 3\n", "header declares 1000000000000 points, the data has 1 lines");
  expect_read_error(path, header + "DATA binary\n" + float_records({1, 2, 3}), "truncated: binary data needs");
  const std::string small = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 100000\nPOINTS 100000\nDATA binary_compressed\n";
  std::string lzf = small;
  append_raw(lzf, std::uint32_t{4});
  append_raw(lzf, std::uint32_t{1200000});
  lzf += std::string("\xe0\xff\x00\x00", 4);
  expect_read_error(path, lzf, "4 compressed bytes cannot hold 1200000 uncompressed bytes");
  // An empty LZF stream: PCL's decoder reads its first control byte before checking the length.
  std::string empty_stream = small;
  append_raw(empty_stream, std::uint32_t{0});
  append_raw(empty_stream, std::uint32_t{1200000});
  expect_read_error(path, empty_stream, "0 compressed bytes cannot hold 1200000 uncompressed bytes");
}

TEST(IoErrorsFuzzRegressions, PlyElementCountBeyondTheFileSize) {
  // An ascii vertex count of 444444444444442: 3 columns of that many values were allocated before the
  // first line was read. Ascii columns now grow line by line, and line 12 is not a number (the message
  // quotes the token, whose first byte is NUL, so what() ends there).
  const std::string name = "vertex_count_444444444444442.ply";
  expect_reproducer_error("ply_mesh", name, "line 12: '");
  const std::string path = testing::fuzz_regression_path("ply_mesh", name);
  EXPECT_THAT([&] { read_mesh_ply(path); }, ThrowsMessage<Error>(AllOf(HasSubstr(path), HasSubstr("line 12: '"))));
  // The same count in a binary file is refused before anything is sized to it.
  ScratchDirectory scratch;
  expect_read_error(scratch.file("huge.ply"),
                    "ply\nformat binary_little_endian 1.0\nelement vertex 444444444444442\nproperty float x\n"
                    "property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                    "end_header\n" + float_records({1, 2, 3}),
                    "element 'vertex' needs 444444444444442 records of 12 bytes but only 12 bytes follow");
}

TEST(IoErrorsFuzzRegressions, PlyAsciiListLengthInfinity) {
  // A face list of length "inf" passed the integer check and was cast to std::size_t: undefined behaviour.
  const std::string path = testing::fuzz_regression_path("ply_mesh", "list_length_inf.ply");
  EXPECT_THAT([&] { read_mesh_ply(path); },
              ThrowsMessage<Error>(AllOf(HasSubstr(path), HasSubstr("line 25: list 'vertex_indices' length inf exceeds "
                                                                   "the 3 values left on the line"))));
}

}  // namespace
}  // namespace quadrix
