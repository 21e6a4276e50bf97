// LAS reading: every point format 0-10 in versions 1.2/1.3/1.4 against the values the test wrote,
// scale and offset in double, the local origin, truncated and lying headers, LAZ, and the real
// airborne tile of ../shared/data.
#include "geometry/io.h"
#include "geometry/las.h"
#include "tests/geometry/las_test_writer.h"
#include "tests/geometry/test_io_helpers.h"
#include "tests/test_data.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>

#include <cmath>
#include <functional>
#include <set>

namespace quadrix {
namespace {

using testing::las_test_bytes;
using testing::LasTestFile;
using testing::LasTestVlr;
using testing::random_las_points;
using testing::ScratchDirectory;
using ::testing::HasSubstr;

std::string error_of(const std::function<void()>& action) {
  try {
    action();
  } catch (const Error& error) {
    return error.what();
  }
  return "(no error)";
}

// Every format in every version it can appear in: positions, intensity, classification, returns and
// colours come back exactly as written.
TEST(LasReader, EveryPointFormatAndVersionReadsWhatWasWritten) {
  ScratchDirectory scratch;
  for (int minor : {2, 3, 4}) {
    for (int format = 0; format <= 10; ++format) {
      SCOPED_TRACE("LAS 1." + std::to_string(minor) + " format " + std::to_string(format));
      LasTestFile file;
      file.version_minor = minor;
      file.point_format = format;
      file.extra_bytes = format % 3 == 0 ? 7 : 0;  // extra bytes are skipped
      file.vlr_payload = format % 2 == 0 ? 40 : 0;
      file.scale = Eigen::Vector3d(0.001, 0.01, 0.0025);
      file.offset = Eigen::Vector3d(-12.5, 3000.0, 7.0);
      file.points = random_las_points(257, 100u * minor + format, format >= 6 ? 255 : 31);
      const std::string path = scratch.file("f" + std::to_string(minor) + "_" + std::to_string(format) + ".las");
      testing::write_bytes(path, las_test_bytes(file));

      CloudReadReport report;
      const PointCloud cloud = read_point_cloud(path, {}, &report);
      ASSERT_EQ(cloud.size(), file.points.size());
      EXPECT_EQ(report.format, CloudFormat::Las);
      EXPECT_EQ(report.points_in_file, file.points.size());
      EXPECT_THAT(report.encoding, HasSubstr("point format " + std::to_string(format)));
      ASSERT_EQ(cloud.labels.size(), cloud.size());
      ASSERT_EQ(cloud.intensity.size(), cloud.size());
      const bool has_rgb = format == 2 || format == 3 || format == 5 || format == 7 || format == 8 || format == 10;
      EXPECT_EQ(cloud.colors.size(), has_rgb ? cloud.size() : 0u);
      for (std::size_t i = 0; i < cloud.size(); ++i) {
        const auto& p = file.points[i];
        const Eigen::Vector3d expected(p.X * file.scale.x() + file.offset.x(), p.Y * file.scale.y() + file.offset.y(),
                                       p.Z * file.scale.z() + file.offset.z());
        ASSERT_EQ(cloud.positions.col(static_cast<Eigen::Index>(i)), expected.cast<float>()) << "point " << i;
        ASSERT_EQ(cloud.intensity[i], static_cast<float>(p.intensity));
        ASSERT_EQ(cloud.labels[i], p.classification);
        ASSERT_EQ(cloud.extra_fields.at("return_number")[i], p.return_number);
        ASSERT_EQ(cloud.extra_fields.at("number_of_returns")[i], p.number_of_returns);
        if (has_rgb) {
          for (int c = 0; c < 3; ++c) ASSERT_EQ(cloud.colors[i][c], p.rgb[c] >> 8);  // 16-bit colours scaled to 8
        }
      }
      const LasHeader header = read_las_header(path);
      EXPECT_EQ(header.version_minor, minor);
      EXPECT_EQ(header.point_format, format);
      EXPECT_EQ(header.point_count, file.points.size());
      EXPECT_EQ(header.extra_bytes, file.extra_bytes);
      EXPECT_EQ(header.scale, file.scale);
      EXPECT_EQ(header.offset, file.offset);
    }
  }
}

TEST(LasReader, EightBitColoursAreKeptAsWritten) {
  ScratchDirectory scratch;
  LasTestFile file;
  file.point_format = 2;
  file.points = random_las_points(50, 3);
  for (auto& p : file.points)
    for (auto& c : p.rgb) c = static_cast<std::uint16_t>(c % 256);
  const std::string path = scratch.file("rgb8.las");
  testing::write_bytes(path, las_test_bytes(file));
  const PointCloud cloud = read_point_cloud(path);
  for (std::size_t i = 0; i < cloud.size(); ++i)
    for (int c = 0; c < 3; ++c) ASSERT_EQ(cloud.colors[i][c], file.points[i].rgb[c]);
}

// Coordinates near UTM northings: float32 of the file value is off by up to 0.25 m; with a local
// origin the positions keep the scale's resolution, and the cloud is written back in the file's frame.
TEST(LasReader, LocalOriginKeepsGeoreferencedCoordinatesExact) {
  ScratchDirectory scratch;
  LasTestFile file;
  file.version_minor = 4;
  file.point_format = 6;
  file.scale = Eigen::Vector3d::Constant(0.001);
  file.offset = Eigen::Vector3d(500000.0, 5400000.0, 0.0);
  file.points = random_las_points(1000, 9);
  const std::string path = scratch.file("utm.las");
  testing::write_bytes(path, las_test_bytes(file));

  CloudReadOptions options;
  options.local_origin = LocalOrigin::Auto;
  const PointCloud cloud = read_point_cloud(path, options);
  const PointCloud rounded = read_point_cloud(path);
  EXPECT_TRUE(rounded.local_origin.isZero(0.0));
  EXPECT_EQ(cloud.local_origin.z(), 0.0);  // heights are small: that axis keeps its frame
  EXPECT_NEAR(cloud.local_origin.y(), 5400000.0, 1000.0);
  EXPECT_EQ(cloud.local_origin, cloud.local_origin.array().round().matrix());
  double worst_local = 0.0, worst_rounded = 0.0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const auto& p = file.points[i];
    const Eigen::Vector3d truth(p.X * 0.001 + 500000.0, p.Y * 0.001 + 5400000.0, p.Z * 0.001);
    worst_local = std::max(worst_local, (cloud.point_in_file_frame(i) - truth).cwiseAbs().maxCoeff());
    worst_rounded = std::max(worst_rounded, (rounded.point_in_file_frame(i) - truth).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst_local, 1e-4);     // float32 of values below 1000 m: 61 micrometres at most
  EXPECT_GT(worst_rounded, 0.05);   // float32 spacing at 5.4e6 m is 0.5 m

  // Written back in the file's frame: a PLY of doubles, read back without an origin, matches the truth.
  const std::string ply = scratch.file("back.ply");
  write_point_cloud(ply, cloud);
  CloudReadOptions keep;
  keep.local_origin = LocalOrigin::Auto;
  const PointCloud again = read_point_cloud(ply, keep);
  ASSERT_EQ(again.size(), cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i)  // both float32 below 1000 m from their origins: 61 um each
    ASSERT_LT((again.point_in_file_frame(i) - cloud.point_in_file_frame(i)).norm(), 2e-4);
  const std::string pcd = scratch.file("back.pcd");
  write_point_cloud(pcd, cloud);
  const PointCloud from_pcd = read_point_cloud(pcd, keep);
  ASSERT_EQ(from_pcd.size(), cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i)
    ASSERT_LT((from_pcd.point_in_file_frame(i) - cloud.point_in_file_frame(i)).norm(), 2e-4);
}

TEST(LocalOrigin, SmallCoordinatesKeepTheirFrame) {
  EXPECT_TRUE(local_origin_near(Eigen::Vector3d(120.0, -9999.0, 3.0)).isZero(0.0));
  EXPECT_EQ(local_origin_near(Eigen::Vector3d(5.4e6 + 0.4, 12.0, -2e4 - 0.6)), Eigen::Vector3d(5.4e6, 0.0, -2e4 - 1.0));
  EXPECT_TRUE(local_origin_near(Eigen::Vector3d(NAN, INFINITY, 1e5)).head<2>().isZero(0.0));
}

// Text and double PLY readers keep the local origin too (they parse doubles before storing floats).
TEST(LocalOrigin, TextAndDoublePlyReadersSubtractItInDouble) {
  ScratchDirectory scratch;
  const std::string xyz = scratch.file("far.xyz");
  testing::write_bytes(xyz, "5400000.123 400000.456 100.5\n5400001.001 400002.002 101.25\n");
  CloudReadOptions options;
  options.local_origin = LocalOrigin::Auto;
  const PointCloud cloud = read_point_cloud(xyz, options);
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.local_origin, Eigen::Vector3d(5400001.0, 400001.0, 0.0));
  EXPECT_NEAR(cloud.point_in_file_frame(0).x(), 5400000.123, 1e-6);
  EXPECT_NEAR(cloud.point_in_file_frame(1).y(), 400002.002, 1e-6);
  EXPECT_NEAR(cloud.point_in_file_frame(1).z(), 101.25, 1e-6);
  const PointCloud plain = read_point_cloud(xyz);
  EXPECT_TRUE(plain.local_origin.isZero(0.0));
  EXPECT_GT(std::abs(plain.point(0).x() - 5400000.123), 0.05);
}

// Damaged and lying headers: a clear error naming the file and the field.
TEST(LasReader, BadHeadersNameTheFileAndTheField) {
  ScratchDirectory scratch;
  LasTestFile file;
  file.version_minor = 4;
  file.point_format = 1;
  file.points = random_las_points(20, 5);
  const std::string good = las_test_bytes(file);
  struct Case {
    const char* name;
    std::function<void(std::string&)> damage;
    const char* expected;
  };
  const std::vector<Case> cases = {
      {"magic", [](std::string& b) { b[0] = 'X'; }, "LASF"},
      {"short", [](std::string& b) { b.resize(100); }, "truncated"},
      {"version", [](std::string& b) { b[25] = 7; }, "'version'"},
      {"header_size", [](std::string& b) { testing::put_at<std::uint16_t>(b, 94, 227); }, "'header size'"},
      {"format", [](std::string& b) { b[104] = 11; }, "'point data format'"},
      {"record_length", [](std::string& b) { testing::put_at<std::uint16_t>(b, 105, 20); }, "'point data record length'"},
      {"offset_inside_header", [](std::string& b) { testing::put_at<std::uint32_t>(b, 96, 100); }, "'offset to point data'"},
      {"offset_past_end", [](std::string& b) { testing::put_at<std::uint32_t>(b, 96, 1u << 30); }, "'offset to point data'"},
      {"count_lies", [](std::string& b) { testing::put_at<std::uint64_t>(b, 247, 21); testing::put_at<std::uint32_t>(b, 107, 21); }, "'number of point records'"},
      {"count_huge", [](std::string& b) { testing::put_at<std::uint64_t>(b, 247, ~0ull); testing::put_at<std::uint32_t>(b, 107, 0); }, "'number of point records'"},
      {"counts_disagree", [](std::string& b) { testing::put_at<std::uint32_t>(b, 107, 19); }, "disagree"},
      {"truncated_points", [](std::string& b) { b.resize(b.size() - 5); }, "'number of point records'"},
      {"scale_zero", [](std::string& b) { testing::put_at<double>(b, 139, 0.0); }, "'y scale factor'"},
      {"scale_nan", [](std::string& b) { testing::put_at<double>(b, 131, NAN); }, "'x scale factor'"},
      {"offset_inf", [](std::string& b) { testing::put_at<double>(b, 171, INFINITY); }, "'z offset'"},
      {"min_above_max", [](std::string& b) { testing::put_at<double>(b, 187, 1e9); }, "'min x'"},
      {"box_lies", [](std::string& b) { testing::put_at<double>(b, 195, -1e9); testing::put_at<double>(b, 203, -2e9); }, "'max y'"},
      {"vlr_count_lies", [](std::string& b) { testing::put_at<std::uint32_t>(b, 100, 3); }, "variable-length record"},
      {"laz_bits", [](std::string& b) { b[104] = static_cast<char>(0x80 | 1); }, "laszip"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    std::string bytes = good;
    c.damage(bytes);
    const std::string path = scratch.file(std::string(c.name) + ".las");
    testing::write_bytes(path, bytes);
    const std::string message = error_of([&] { read_point_cloud(path); });
    EXPECT_THAT(message, HasSubstr(path));
    EXPECT_THAT(message, HasSubstr(c.expected));
  }
}

TEST(LasReader, LazIsRefusedNamingTheDecompressor) {
  ScratchDirectory scratch;
  const std::string laz = scratch.file("tile.laz");
  testing::write_bytes(laz, "LASF");
  const std::string message = error_of([&] { read_point_cloud(laz); });
  EXPECT_THAT(message, HasSubstr(laz));
  EXPECT_THAT(message, HasSubstr("laszip"));
  EXPECT_THAT(message, HasSubstr("pdal translate"));
  // A LASzip record in an otherwise plain header.
  LasTestFile file;
  file.vlr_payload = 34;
  file.points = random_las_points(3, 1);
  std::string bytes = las_test_bytes(file);
  std::memset(&bytes[227 + 2], 0, 16);
  std::memcpy(&bytes[227 + 2], "laszip encoded", 14);
  testing::put_at<std::uint16_t>(bytes, 227 + 18, 22204);
  const std::string hidden = scratch.file("hidden.las");
  testing::write_bytes(hidden, bytes);
  EXPECT_THAT(error_of([&] { read_point_cloud(hidden); }), HasSubstr("pdal translate"));
}

TEST(LasReader, EmptyFileOfZeroPointsIsAnEmptyCloud) {
  ScratchDirectory scratch;
  LasTestFile file;
  file.version_minor = 3;
  const std::string path = scratch.file("empty.las");
  testing::write_bytes(path, las_test_bytes(file));
  EXPECT_TRUE(read_point_cloud(path).empty());
}

// A GeoKeyDirectory record (LASF_Projection 34735): header (1, 1, 0, count) then (id, location, count, value) per key.
LasTestVlr geo_keys(const std::vector<std::array<std::uint16_t, 4>>& keys, std::uint16_t declared_count = 0) {
  std::vector<std::uint16_t> words = {1, 1, 0, declared_count ? declared_count : static_cast<std::uint16_t>(keys.size())};
  for (const auto& key : keys) words.insert(words.end(), key.begin(), key.end());
  LasTestVlr vlr;
  vlr.record_id = 34735;
  vlr.payload.assign(reinterpret_cast<const char*>(words.data()), 2 * words.size());
  return vlr;
}

LasHeader header_with(const ScratchDirectory& scratch, const std::vector<LasTestVlr>& vlrs, const std::string& name) {
  LasTestFile file;
  file.vlrs = vlrs;
  file.points = random_las_points(5, 3);
  const std::string path = scratch.file(name);
  testing::write_bytes(path, las_test_bytes(file));
  EXPECT_EQ(read_point_cloud(path).size(), 5u) << "the points are read whatever the CRS records say";
  return read_las_header(path);
}

TEST(LasUnits, GeoKeysGiveTheLinearAndVerticalUnits) {
  ScratchDirectory scratch;
  const LasHeader survey = header_with(scratch, {geo_keys({{{1024, 0, 1, 1}}, {{3076, 0, 1, 9003}}, {{4099, 0, 1, 9001}}})}, "survey.las");
  EXPECT_EQ(survey.units.source, "GeoTIFF keys");
  EXPECT_EQ(survey.units.horizontal_name, "US survey foot");
  EXPECT_DOUBLE_EQ(survey.units.horizontal_metres, 1200.0 / 3937.0);
  EXPECT_EQ(survey.units.vertical_name, "metre");
  EXPECT_DOUBLE_EQ(survey.units.vertical_metres, 1.0);
  EXPECT_FALSE(survey.units.geographic);
  // A user-defined unit: 3076 = 32767 and its size in metres among the double parameters (34736).
  LasTestVlr doubles;
  doubles.record_id = 34736;
  const double values[2] = {7.0, 0.5};
  doubles.payload.assign(reinterpret_cast<const char*>(values), sizeof(values));
  const LasHeader user = header_with(scratch, {geo_keys({{{3076, 0, 1, 32767}}, {{3077, 34736, 1, 1}}}), doubles}, "user.las");
  EXPECT_DOUBLE_EQ(user.units.horizontal_metres, 0.5);
  // Longitude and latitude: geographic, no metres per unit.
  const LasHeader geographic = header_with(scratch, {geo_keys({{{1024, 0, 1, 2}}})}, "geographic.las");
  EXPECT_TRUE(geographic.units.geographic);
  EXPECT_EQ(geographic.units.horizontal_metres, 0.0);
  // No CRS record at all.
  EXPECT_TRUE(header_with(scratch, {}, "plain.las").units.source.empty());
}

TEST(LasUnits, WktGivesTheProjectedUnitNotTheGeographicOne) {
  ScratchDirectory scratch;
  LasTestVlr wkt;
  wkt.record_id = 2112;
  wkt.payload = R"(COMPD_CS["x",PROJCS["y",GEOGCS["g",DATUM["d",SPHEROID["s",6378137,298.25]],PRIMEM["Greenwich",0],)"
                R"(UNIT["degree",0.0174532925199433]],PROJECTION["Transverse_Mercator"],PARAMETER["k",0.9996],)"
                R"(UNIT["metre",1,AUTHORITY["EPSG","9001"]]],VERT_CS["v",VERT_DATUM["n",2005],UNIT["foot",0.3048]]])";
  wkt.payload += '\0';
  // The WKT wins over GeoTIFF keys that say otherwise (LAS 1.4 makes the WKT the required form).
  const LasHeader header = header_with(scratch, {geo_keys({{{3076, 0, 1, 9002}}}), wkt}, "wkt.las");
  EXPECT_EQ(header.units.source, "WKT");
  EXPECT_EQ(header.units.horizontal_name, "metre");
  EXPECT_DOUBLE_EQ(header.units.horizontal_metres, 1.0);
  EXPECT_EQ(header.units.vertical_name, "foot");
  EXPECT_DOUBLE_EQ(header.units.vertical_metres, 0.3048);
}

TEST(LasUnits, MalformedCrsRecordsLeaveTheUnitsUndeclaredAndThePointsRead) {
  ScratchDirectory scratch;
  // A key directory that claims 1,000 keys but holds 3: the 3 it holds are read, nothing past them.
  const LasHeader claims = header_with(scratch, {geo_keys({{{3076, 0, 1, 9002}}, {{4099, 0, 1, 9001}}, {{1024, 0, 1, 1}}}, 1000)}, "claims.las");
  EXPECT_DOUBLE_EQ(claims.units.horizontal_metres, 0.3048);
  // A double parameter index past the doubles; an unknown unit code; a WKT cut off inside PROJCS; a
  // WKT unit that is not a number; a key directory of one byte.
  LasTestVlr cut, not_a_number, odd;
  cut.record_id = not_a_number.record_id = 2112;
  cut.payload = R"(PROJCS["y",GEOGCS["g",UNIT["degree",0.01745]],UNIT["metre")";
  not_a_number.payload = R"(PROJCS["y",UNIT["metre",abc]])";
  odd.record_id = 34735;
  odd.payload = "\x01";
  for (const auto& [vlrs, name] : std::vector<std::pair<std::vector<LasTestVlr>, std::string>>{
           {{geo_keys({{{3076, 0, 1, 32767}}, {{3077, 34736, 1, 40}}})}, "index.las"},
           {{geo_keys({{{3076, 0, 1, 9999}}})}, "unknown.las"},
           {{cut}, "cut.las"},
           {{not_a_number}, "nan.las"},
           {{odd}, "odd.las"}}) {
    const LasHeader header = header_with(scratch, vlrs, name);
    EXPECT_EQ(header.units.horizontal_metres, 0.0) << name;
    EXPECT_TRUE(header.units.horizontal_name.empty()) << name;
  }
}

// The real airborne tile: 110,000 points in international feet, state plane; ground and unclassified.
TEST(LasReader, SharedAutzenTile) {
  QUADRIX_REQUIRE_SHARED_DATA("als_autzen/autzen_trim.las");
  const std::string path = testing::shared_data_path("als_autzen/autzen_trim.las");
  const LasHeader header = read_las_header(path);
  EXPECT_EQ(header.version_minor, 2);
  EXPECT_EQ(header.point_count, 110000u);
  EXPECT_EQ(header.units.horizontal_name, "foot");
  EXPECT_DOUBLE_EQ(header.units.horizontal_metres, 0.3048);
  CloudReadOptions options;
  options.local_origin = LocalOrigin::Auto;
  CloudReadReport report;
  const PointCloud cloud = read_point_cloud(path, options, &report);
  ASSERT_EQ(cloud.size(), 110000u);
  EXPECT_EQ(report.non_finite_dropped, 0u);
  EXPECT_FALSE(cloud.local_origin.isZero(0.0));  // state-plane feet: hundreds of thousands
  std::set<std::uint32_t> classes(cloud.labels.begin(), cloud.labels.end());
  EXPECT_TRUE(classes.count(2)) << "ground (class 2) expected";
  Eigen::Vector3d low = cloud.point_in_file_frame(0), high = low;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    low = low.cwiseMin(cloud.point_in_file_frame(i));
    high = high.cwiseMax(cloud.point_in_file_frame(i));
  }
  // The points span the header's box within a unit of its scale (read in double, stored relative).
  for (int axis = 0; axis < 3; ++axis) {
    EXPECT_NEAR(low[axis], header.min[axis], header.scale[axis] + 1e-6);
    EXPECT_NEAR(high[axis], header.max[axis], header.scale[axis] + 1e-6);
  }
}

}  // namespace
}  // namespace quadrix
