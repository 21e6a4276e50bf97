// Georeferenced clouds through `quadrix model`: a scan moved to UTM-sized coordinates and modelled
// with --sensor-origin gives the model of the unmoved scan (float32 before centring used to cost
// 0.25-0.5 m there), and the real LAS tile is modelled in the file's own coordinates and units.
#include "estimation/registration.h"
#include "geometry/io.h"
#include "geometry/las.h"
#include "tests/geometry/las_test_writer.h"
#include "test_data.h"
#include "test_folder.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <string>

namespace quadrix {
namespace {

using Folder = testing::TemporaryFolder;

/// Runs `quadrix model INPUT ARGUMENTS --out NAME.json`; returns the JSON (the log on failure).
nlohmann::json run_model(const Folder& folder, const std::string& input, const std::string& arguments,
                         const std::string& name) {
  const std::string log = folder.file(name + ".txt");
  const std::string command = std::string(QUADRIX_EXECUTABLE) + " model '" + input + "' --no-page " + arguments +
                              " --out '" + folder.file(name + ".json") + "' > '" + log + "' 2>&1";
  const int status = std::system(command.c_str());
  std::ifstream log_file(log);
  const std::string text((std::istreambuf_iterator<char>(log_file)), std::istreambuf_iterator<char>());
  EXPECT_EQ(status, 0) << command << "\n" << text;
  std::ifstream json_file(folder.file(name + ".json"));
  if (!json_file) return nlohmann::json::object();
  return nlohmann::json::parse(json_file);
}

/// Quadrics per "class/type".
std::map<std::string, int> counts(const nlohmann::json& model) {
  std::map<std::string, int> result;
  for (const auto& quadric : model["quadrics"])
    ++result[quadric["class"].get<std::string>() + "/" + quadric["type"].get<std::string>()];
  return result;
}

Eigen::Vector3d centre(const nlohmann::json& quadric) {
  return Eigen::Vector3d(quadric["center"][0].get<double>(), quadric["center"][1].get<double>(),
                         quadric["center"][2].get<double>());
}

const Eigen::Vector3d kUtmOffset(5.4e6, 4e5, 100.0);

// KITTI frame 0 written in double at a UTM-sized position: read with a local origin and centred on
// its sensor in double, it is the scan itself to float32's resolution near the sensor; read in float32
// first (the old path), it is off by decimetres.
TEST(LocalOriginCentring, GeoreferencedScanCentredOnItsSensorIsTheScan) {
  QUADRIX_REQUIRE_SHARED_DATA("kitti00/velodyne/000000.bin");
  const Folder folder("quadrix_local_origin_centring");
  const PointCloud scan = read_point_cloud(testing::shared_data_path("kitti00/velodyne/000000.bin"));
  PointCloud moved = scan;
  moved.local_origin = kUtmOffset;  // written in the file's frame, as doubles
  write_point_cloud(folder.file("moved.ply"), moved);
  CloudReadOptions options;
  options.local_origin = LocalOrigin::Auto;
  const PointCloud exact = centred_on_sensor(read_point_cloud(folder.file("moved.ply"), options), kUtmOffset);
  const PointCloud rounded = centred_on_sensor(read_point_cloud(folder.file("moved.ply")), kUtmOffset);
  ASSERT_EQ(exact.size(), scan.size());
  EXPECT_TRUE(exact.local_origin.isZero(0.0));
  // KITTI points lie within 128 m of the sensor: float32 spacing there is 7.6 um, two roundings.
  EXPECT_LT((exact.positions - scan.positions).cwiseAbs().maxCoeff(), 2e-5f);
  EXPECT_GT((rounded.positions - scan.positions).cwiseAbs().maxCoeff(), 0.1f);
}

// The same scan through the command: the model of the moved file with --sensor-origin has the
// unmoved scan's quadrics, each moved by the offset.
TEST(ModelCommand, GeoreferencedScanWithSensorOriginModelsAsTheUnmovedScan) {
  QUADRIX_REQUIRE_SHARED_DATA("kitti00/velodyne/000000.bin");
  const Folder folder("quadrix_local_origin_model");
  const std::string original = testing::shared_data_path("kitti00/velodyne/000000.bin");
  PointCloud moved = read_point_cloud(original);
  moved.local_origin = kUtmOffset;
  write_point_cloud(folder.file("moved.ply"), moved);
  const nlohmann::json unmoved_model = run_model(folder, original, "", "unmoved");
  const nlohmann::json moved_model =
      run_model(folder, folder.file("moved.ply"), "--sensor-origin 5400000,400000,100", "moved");
  ASSERT_GE(unmoved_model["quadrics"].size(), 20u);
  EXPECT_EQ(counts(moved_model), counts(unmoved_model));
  ASSERT_EQ(moved_model["quadrics"].size(), unmoved_model["quadrics"].size());
  double worst = 0.0;
  for (std::size_t i = 0; i < unmoved_model["quadrics"].size(); ++i)
    worst = std::max(worst, (centre(moved_model["quadrics"][i]) - kUtmOffset - centre(unmoved_model["quadrics"][i])).norm());
  EXPECT_LT(worst, 1e-3) << "largest centre difference, metres";
}

// The real airborne LAS tile (state-plane feet, ~6e5 and ~8e5): modelled relative to a local origin
// (in metres, as its CRS declares feet) and written in the file's coordinates. The same points,
// classes and units given near the origin (the floats the reader stored, as a LAS in feet without
// an offset) give the same model, moved by that origin.
TEST(ModelCommand, LasTileIsModelledInTheFilesOwnCoordinates) {
  QUADRIX_REQUIRE_SHARED_DATA("als_autzen/autzen_trim.las");
  const Folder folder("quadrix_local_origin_las");
  const std::string las = testing::shared_data_path("als_autzen/autzen_trim.las");
  CloudReadOptions options;
  options.local_origin = LocalOrigin::Auto;
  const PointCloud local = read_point_cloud(las, options);
  const Eigen::Vector3d origin = local.local_origin;
  ASSERT_GT(origin.head<2>().cwiseAbs().minCoeff(), 1e5);
  testing::LasTestFile near_origin_file;
  near_origin_file.point_format = 1;
  // GeoTIFF keys: projected CRS (GTModelType 1), x, y and z in feet (ProjLinearUnits, VerticalUnits 9002).
  const std::vector<std::uint16_t> words = {1, 1, 0, 3, 1024, 0, 1, 1, 3076, 0, 1, 9002, 4099, 0, 1, 9002};
  testing::LasTestVlr feet;
  feet.record_id = 34735;
  feet.payload.assign(reinterpret_cast<const char*>(words.data()), 2 * words.size());
  near_origin_file.vlrs = {feet};
  for (std::size_t i = 0; i < local.size(); ++i) {
    testing::LasTestPoint point;  // the tile's 0.01 ft steps, exact in float32 at these magnitudes
    point.X = static_cast<std::int32_t>(std::lround(local.positions(0, static_cast<Eigen::Index>(i)) * 100.0));
    point.Y = static_cast<std::int32_t>(std::lround(local.positions(1, static_cast<Eigen::Index>(i)) * 100.0));
    point.Z = static_cast<std::int32_t>(std::lround(local.positions(2, static_cast<Eigen::Index>(i)) * 100.0));
    point.classification = static_cast<std::uint8_t>(local.labels[i]);
    near_origin_file.points.push_back(point);
  }
  testing::write_bytes(folder.file("local.las"), testing::las_test_bytes(near_origin_file));
  const nlohmann::json file_frame = run_model(folder, las, "--preset airborne", "las");
  const nlohmann::json near_origin = run_model(folder, folder.file("local.las"), "--preset airborne", "local");
  ASSERT_TRUE(file_frame["quadrics"].is_array());
  EXPECT_GT(file_frame["quadrics"].size(), 10u);
  EXPECT_EQ(counts(file_frame), counts(near_origin));
  ASSERT_EQ(file_frame["quadrics"].size(), near_origin["quadrics"].size());
  const LasHeader header = read_las_header(las);
  EXPECT_TRUE((origin.head<2>().array() >= header.min.head<2>().array()).all() &&
              (origin.head<2>().array() <= header.max.head<2>().array()).all())
      << "local origin " << origin.transpose() << " outside the tile";
  for (std::size_t i = 0; i < file_frame["quadrics"].size(); ++i)
    EXPECT_LT((centre(file_frame["quadrics"][i]) - origin - centre(near_origin["quadrics"][i])).norm(), 1e-6)
        << "quadric " << i;
}

}  // namespace
}  // namespace quadrix
