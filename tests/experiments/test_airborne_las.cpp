// Airborne LAS through `quadrix model --preset airborne`: a synthetic nadir scan of gabled and flat
// roofs on flat ground, written in international feet at a UTM-sized offset, is modelled in metres
// and written back in the file's feet (roofs and ground where the scene put them); the real Autzen
// tile (state-plane feet, classes 1 and 2) gets a model whose checks need no primitive truth.
#include "geometry/io.h"
#include "geometry/las.h"
#include "tests/geometry/las_test_writer.h"
#include "test_data.h"
#include "test_folder.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <sys/wait.h>

namespace quadrix {
namespace {

using testing::LasTestFile;
using testing::LasTestPoint;
using testing::LasTestVlr;

constexpr double kFoot = 0.3048;  // international foot, m (GeoTIFF unit 9002)

using Folder = testing::TemporaryFolder;

/// Runs `quadrix model INPUT ARGUMENTS --out NAME.json`; returns the JSON (empty on failure) and the log.
nlohmann::json run_model(const Folder& folder, const std::string& input, const std::string& arguments, const std::string& name,
                         std::string* log_text = nullptr) {
  const std::string log = folder.file(name + ".txt");
  const std::string command = std::string(QUADRIX_EXECUTABLE) + " model '" + input + "' --no-page " + arguments + " --out '" +
                              folder.file(name + ".json") + "' > '" + log + "' 2>&1";
  const int status = std::system(command.c_str());
  std::ifstream log_file(log);
  const std::string text((std::istreambuf_iterator<char>(log_file)), std::istreambuf_iterator<char>());
  if (log_text != nullptr) *log_text = text;
  EXPECT_EQ(status, 0) << command << "\n" << text;
  std::ifstream json_file(folder.file(name + ".json"));
  if (!json_file) return nlohmann::json::object();
  return nlohmann::json::parse(json_file);
}

/// Runs `quadrix ARGUMENTS --out OUT` (OUT a name in `folder`) and expects it refused: exit 2, every
/// one of `words` in the message, nothing written at OUT.
void expect_refused(const Folder& folder, const std::string& arguments, const std::string& out, const std::vector<std::string>& words) {
  const std::string command = std::string(QUADRIX_EXECUTABLE) + " " + arguments + " --out '" + folder.file(out) + "' > '" +
                              folder.file("log.txt") + "' 2>&1";
  const int status = std::system(command.c_str());
  std::ifstream log_file(folder.file("log.txt"));
  const std::string text((std::istreambuf_iterator<char>(log_file)), std::istreambuf_iterator<char>());
  EXPECT_EQ(WEXITSTATUS(status), 2) << command << "\n" << text;
  for (const std::string& word : words) EXPECT_NE(text.find(word), std::string::npos) << "'" << word << "' in\n" << text;
  EXPECT_FALSE(std::filesystem::exists(folder.file(out))) << text;
}

Eigen::Vector3d vector_of(const nlohmann::json& values) {
  return Eigen::Vector3d(values[0].get<double>(), values[1].get<double>(), values[2].get<double>());
}

/// A plane record of the model: unit normal, offset (n . x + offset = 0) and centre, file coordinates.
struct ModelPlane {
  Eigen::Vector3d normal;
  double offset = 0.0;
  Eigen::Vector3d centre;
};

std::vector<ModelPlane> planes_of_class(const nlohmann::json& model, const std::string& element_class) {
  std::vector<ModelPlane> planes;
  for (const auto& quadric : model["quadrics"]) {
    if (quadric["class"] != element_class || quadric["type"] != "plane") continue;
    ModelPlane plane;
    plane.normal = vector_of(quadric["shape"]["normal"]);
    plane.offset = quadric["shape"]["offset"].get<double>();
    plane.centre = vector_of(quadric["center"]);
    const double norm = plane.normal.norm();
    plane.normal /= norm;
    plane.offset /= norm;
    if (plane.normal.z() < 0.0) {
      plane.normal = -plane.normal;
      plane.offset = -plane.offset;
    }
    planes.push_back(plane);
  }
  return planes;
}

// A GeoKeyDirectory record (LASF_Projection 34735) of a projected CRS in international feet:
// GTModelType 1 (projected), ProjLinearUnits 9002 and VerticalUnits 9002 (foot).
LasTestVlr feet_geo_keys() {
  const std::vector<std::uint16_t> words = {1, 1, 0, 3, 1024, 0, 1, 1, 3076, 0, 1, 9002, 4099, 0, 1, 9002};
  LasTestVlr vlr;
  vlr.record_id = 34735;
  vlr.payload.assign(reinterpret_cast<const char*>(words.data()), 2 * words.size());
  return vlr;
}

/// One roof facet of the synthetic scene, metres in the scene's frame: the points x = centre +
/// a u + b v (|a| <= half_u, |b| <= half_v) with u, v horizontal; its height rises along v by tan(pitch).
struct Facet {
  Eigen::Vector2d centre;     ///< footprint centre
  Eigen::Vector2d u, v;       ///< unit horizontal directions (v: up the slope)
  double half_u = 0.0, half_v = 0.0;
  double height = 0.0;        ///< height at the footprint centre
  double pitch_deg = 0.0;     ///< slope along v
  bool contains(const Eigen::Vector2d& p) const {
    const Eigen::Vector2d d = p - centre;
    return std::abs(d.dot(u)) <= half_u && std::abs(d.dot(v)) <= half_v;
  }
  double height_at(const Eigen::Vector2d& p) const { return height + (p - centre).dot(v) * std::tan(pitch_deg * M_PI / 180.0); }
  Eigen::Vector3d normal() const {  // of z = height + t (x - centre) . v, pointing up
    const double t = std::tan(pitch_deg * M_PI / 180.0);
    return Eigen::Vector3d(-t * v.x(), -t * v.y(), 1.0).normalized();
  }
};

// A gabled roof: two facets meeting at a ridge along `ridge` (unit), eaves at `eave` m, pitched by
// `pitch_deg`, over a footprint `length` along the ridge and `width` across it.
void add_gable(std::vector<Facet>& facets, Eigen::Vector2d centre, Eigen::Vector2d ridge, double length, double width, double eave,
               double pitch_deg) {
  const Eigen::Vector2d across(-ridge.y(), ridge.x());
  const double rise_to_middle = (width / 4.0) * std::tan(pitch_deg * M_PI / 180.0);
  for (const double side : {-1.0, 1.0}) {
    Facet facet;
    facet.centre = centre + side * (width / 4.0) * across;
    facet.u = ridge;
    facet.v = -side * across;  // up the slope: toward the ridge
    facet.half_u = length / 2.0;
    facet.half_v = width / 4.0;
    facet.height = eave + rise_to_middle;
    facet.pitch_deg = pitch_deg;
    facets.push_back(facet);
  }
}

/// The synthetic scene's roof facets: three gables (one turned 30 degrees) and a flat roof, each
/// facet at least 80 m^2.
std::vector<Facet> synthetic_roofs() {
  std::vector<Facet> facets;
  add_gable(facets, {-40.0, -40.0}, {1.0, 0.0}, 20.0, 12.0, 6.0, 30.0);
  add_gable(facets, {40.0, -30.0}, {0.0, 1.0}, 16.0, 10.0, 8.0, 40.0);
  add_gable(facets, {35.0, 40.0}, {std::cos(M_PI / 6.0), std::sin(M_PI / 6.0)}, 18.0, 12.0, 5.0, 25.0);
  Facet flat;
  flat.centre = {-35.0, 40.0};
  flat.u = {1.0, 0.0};
  flat.v = {0.0, 1.0};
  flat.half_u = 12.0;
  flat.half_v = 9.0;
  flat.height = 10.0;
  facets.push_back(flat);
  return facets;
}

// A nadir airborne scan of `roofs` on flat ground at height 0 over a 160 m square: points uniform in
// x-y at `density` points/m^2 (the highest surface below the aircraft is hit), heights with Gaussian
// noise of `noise` m; ground class 2, roofs class 6 (building). Metres, scene frame.
struct ScenePoint {
  Eigen::Vector3d position;
  std::uint8_t classification = 2;
};
std::vector<ScenePoint> nadir_scan(const std::vector<Facet>& roofs, double density, double noise, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> coordinate(-80.0, 80.0);
  std::normal_distribution<double> height_noise(0.0, noise);
  const std::size_t count = static_cast<std::size_t>(density * 160.0 * 160.0);
  std::vector<ScenePoint> points;
  points.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    const Eigen::Vector2d xy(coordinate(random), coordinate(random));
    ScenePoint point;
    double height = 0.0;
    for (const Facet& facet : roofs)
      if (facet.contains(xy) && facet.height_at(xy) > height) {
        height = facet.height_at(xy);
        point.classification = 6;
      }
    point.position = Eigen::Vector3d(xy.x(), xy.y(), height + height_noise(random));
    points.push_back(point);
  }
  return points;
}

// Where the scene's frame sits in the projected CRS, metres: UTM-sized easting and northing.
const Eigen::Vector3d kSceneOrigin(512345.0, 5123456.0, 120.0);

// Writes the scan as LAS 1.2 point format 1 in international feet (0.01 ft steps) at kSceneOrigin.
void write_feet_las(const std::string& path, const std::vector<ScenePoint>& points) {
  LasTestFile file;
  file.version_minor = 2;
  file.point_format = 1;
  file.vlrs = {feet_geo_keys()};
  file.scale = Eigen::Vector3d::Constant(0.01);
  file.offset = (kSceneOrigin / kFoot).array().floor();
  for (const ScenePoint& point : points) {
    const Eigen::Vector3d feet = (kSceneOrigin + point.position) / kFoot;
    LasTestPoint record;
    record.X = static_cast<std::int32_t>(std::lround((feet.x() - file.offset.x()) / file.scale.x()));
    record.Y = static_cast<std::int32_t>(std::lround((feet.y() - file.offset.y()) / file.scale.y()));
    record.Z = static_cast<std::int32_t>(std::lround((feet.z() - file.offset.z()) / file.scale.z()));
    record.classification = point.classification;
    file.points.push_back(record);
  }
  testing::write_bytes(path, testing::las_test_bytes(file));
}

// The model of the synthetic nadir scene in feet (`log`: the run's output, for messages): the ground
// is one horizontal plane at the scene's ground height, every roof facet is a plane of the model at
// its place (normal within 2 degrees, the facet's centre within 0.1 m of the plane, the plane's
// centre over the facet), and no other plane is found. Tolerances: 2 degrees and 0.1 m are several
// times the error of a least-squares plane through 80+ points with 0.05 m height noise (about 0.3
// degrees and 0.01 m), and far below a wrong roof's (the nearest other facet differs by 25 degrees
// or more).
void expect_ground_and_every_roof(const nlohmann::json& model, const std::vector<Facet>& roofs, const std::string& log) {
  const std::vector<ModelPlane> grounds = planes_of_class(model, "ground");
  ASSERT_EQ(grounds.size(), 1u) << log;
  EXPECT_GT(grounds[0].normal.z(), std::cos(1.0 * M_PI / 180.0));
  const Eigen::Vector3d scene_centre_feet = kSceneOrigin / kFoot;
  const double ground_height_feet = -(grounds[0].offset + grounds[0].normal.head<2>().dot(scene_centre_feet.head<2>())) / grounds[0].normal.z();
  EXPECT_NEAR(ground_height_feet * kFoot, kSceneOrigin.z(), 0.02) << "ground height, m";

  const std::vector<ModelPlane> planes = planes_of_class(model, "plane");
  std::vector<int> matches(planes.size(), 0);
  for (std::size_t f = 0; f < roofs.size(); ++f) {
    const Facet& facet = roofs[f];
    const Eigen::Vector3d centre_feet = (kSceneOrigin + Eigen::Vector3d(facet.centre.x(), facet.centre.y(), facet.height)) / kFoot;
    int found = 0;
    for (std::size_t p = 0; p < planes.size(); ++p) {
      const ModelPlane& plane = planes[p];
      const Eigen::Vector2d plane_centre_in_scene = plane.centre.head<2>() * kFoot - kSceneOrigin.head<2>();
      if (std::abs(plane.normal.dot(facet.normal())) < std::cos(2.0 * M_PI / 180.0)) continue;
      if (std::abs(plane.normal.dot(centre_feet) + plane.offset) * kFoot > 0.1) continue;
      if (!facet.contains(plane_centre_in_scene)) continue;
      ++found;
      ++matches[p];
    }
    EXPECT_EQ(found, 1) << "facet " << f << " (pitch " << facet.pitch_deg << " deg) found as " << found << " planes\n" << log;
  }
  for (std::size_t p = 0; p < planes.size(); ++p)
    EXPECT_EQ(matches[p], 1) << "plane " << p << " normal " << planes[p].normal.transpose() << " centre "
                             << planes[p].centre.transpose() << " ft matches " << matches[p] << " facets";
  EXPECT_EQ(model["stats"]["counts_by_type"].value("circular_cylinder", 0), 0);
}

// The synthetic nadir scene in feet, modelled whole (ground from the file's classification) and tile
// by tile: every roof where the scene put it, in the file's feet (expect_ground_and_every_roof).
TEST(AirborneLas, SyntheticRoofsInFeetAreFoundInFileCoordinates) {
  const Folder folder("quadrix_airborne_synthetic");
  const std::vector<Facet> roofs = synthetic_roofs();
  write_feet_las(folder.file("scene.las"), nadir_scan(roofs, 1.0, 0.05, 2024));
  std::string log;
  const nlohmann::json model = run_model(folder, folder.file("scene.las"), "--preset airborne", "scene", &log);
  ASSERT_TRUE(model.contains("stats")) << log;
  const nlohmann::json& stats = model["stats"];
  EXPECT_EQ(stats["preset"], "airborne");
  EXPECT_EQ(stats["status"], "ok") << log;
  EXPECT_EQ(stats["units"]["name"], "foot");
  EXPECT_DOUBLE_EQ(stats["units"]["metres_per_unit"].get<double>(), kFoot);
  EXPECT_EQ(stats["ground_source"], "classification");
  expect_ground_and_every_roof(model, roofs, log);

  // Tile by tile: the tiles are cut and modelled in metres (their sizes, margins and merge rules are
  // metres) and the model is written in the file's feet, with the same roofs (60 m tiles over the
  // 160 m scene cut the roofs' plane pieces apart, so each facet found once means the merge joined
  // them). Tile groups for separate processes (--tile i/n) are refused with the reason, as their
  // parts are joined in metres and carry no unit.
  const nlohmann::json tiled = run_model(folder, folder.file("scene.las"), "--preset airborne --tile-size 60", "tiled", &log);
  ASSERT_TRUE(tiled.contains("stats")) << log;
  EXPECT_EQ(tiled["stats"]["status"], "ok") << log;
  EXPECT_EQ(tiled["stats"]["units"]["name"], "foot");
  EXPECT_GT(tiled["stats"]["tiling"]["tiles"].get<int>(), 1) << log;
  expect_ground_and_every_roof(tiled, roofs, log);
  expect_refused(folder, "model '" + folder.file("scene.las") + "' --no-page --preset airborne --tile 1/2", "part.json",
                 {"foot", "--tile i/n"});

  // `auto` measures the same scene as a nadir view.
  const nlohmann::json automatic = run_model(folder, folder.file("scene.las"), "", "auto");
  ASSERT_TRUE(automatic.contains("stats"));
  EXPECT_EQ(automatic["stats"]["preset"], "airborne") << automatic["stats"]["preset_notes"];
}

// A LAS file whose CRS says degrees is refused with the reason, not modelled as lengths.
TEST(AirborneLas, GeographicCoordinatesAreRefused) {
  const Folder folder("quadrix_airborne_geographic");
  LasTestFile file;
  const std::vector<std::uint16_t> words = {1, 1, 0, 1, 1024, 0, 1, 2};  // GTModelType 2: geographic
  LasTestVlr vlr;
  vlr.record_id = 34735;
  vlr.payload.assign(reinterpret_cast<const char*>(words.data()), 2 * words.size());
  file.vlrs = {vlr};
  file.points = testing::random_las_points(200, 5);
  testing::write_bytes(folder.file("degrees.las"), testing::las_test_bytes(file));
  expect_refused(folder, "model '" + folder.file("degrees.las") + "' --no-page --preset airborne", "m.json", {"degrees"});
}

// Registration and maps work in metres only: a scan in feet is refused before any work, with an
// error naming the file and its unit (exit 2, nothing written), never registered as if in metres.
TEST(AirborneLas, RegisterAndMapRefuseScansInFeet) {
  const Folder folder("quadrix_airborne_refused");
  write_feet_las(folder.file("a.las"), nadir_scan(synthetic_roofs(), 0.2, 0.05, 11));
  write_feet_las(folder.file("b.las"), nadir_scan(synthetic_roofs(), 0.2, 0.05, 12));
  {
    std::ofstream list(folder.file("scans.tsv"));
    // One session of two scans without odometry (`-`): the refusal must come before any modelling.
    list << "session\tscan\todometry\n" << "s\ta.las\t-\n" << "s\tb.las\t-\n";
  }
  expect_refused(folder, "register '" + folder.file("a.las") + "' '" + folder.file("b.las") + "'", "registration",
                 {"a.las", "foot", "metres"});
  expect_refused(folder, "map '" + folder.file("scans.tsv") + "'", "map", {"a.las", "foot", "metres"});
}

// The real airborne tile (Autzen, state-plane feet, classes 1 and 2) has no primitive truth. What is
// checked, each from a rule rather than from this tile's numbers:
// - the model is in the file's coordinates: every centre inside the header's bounds (feet);
// - the ground is the class-2 points' plane: within 1 m of their median height at their median
//   x-y (a plane through the tile's terrain, which falls a few metres across it);
// - a nadir view sees roofs, not walls: at most 10% of the plane elements' points lie in planes
//   steeper than 60 degrees;
// - each plane element's points lie near one model plane: median distance at most epsilon plus the
//   merge distance (0.2 + 0.15 m), since every piece Efficient RANSAC returns lies within epsilon of
//   its own plane and pieces are merged only when their planes lie within the merge distance.
TEST(AirborneLas, AutzenTileIsModelledInItsOwnFeet) {
  QUADRIX_REQUIRE_SHARED_DATA("als_autzen/autzen_trim.las");
  const Folder folder("quadrix_airborne_autzen");
  const std::string las = testing::shared_data_path("als_autzen/autzen_trim.las");
  const LasHeader header = read_las_header(las);
  ASSERT_GT(header.units.horizontal_metres, 0.3) << "the tile declares feet";
  const double unit = header.units.horizontal_metres;
  std::string log;
  const nlohmann::json model =
      run_model(folder, las, "--preset airborne --elements '" + folder.file("elements.ply") + "'", "autzen", &log);
  ASSERT_TRUE(model.contains("stats")) << log;
  EXPECT_EQ(model["stats"]["status"], "ok") << log;
  EXPECT_EQ(model["stats"]["ground_source"], "classification");
  EXPECT_NEAR(model["stats"]["units"]["metres_per_unit"].get<double>(), unit, 1e-12);

  const double margin = 0.2 / unit;  // the preset's epsilon, in the file's unit
  for (const auto& quadric : model["quadrics"]) {
    const Eigen::Vector3d centre = vector_of(quadric["center"]);
    EXPECT_TRUE((centre.array() >= header.min.array() - margin).all() && (centre.array() <= header.max.array() + margin).all())
        << quadric["class"] << " centre " << centre.transpose() << " outside the header's bounds";
  }

  // The ground against the class-2 points.
  const PointCloud cloud = read_point_cloud(las);
  std::vector<double> ground_x, ground_y, ground_z;
  for (std::size_t i = 0; i < cloud.size(); ++i)
    if (cloud.labels[i] == 2) {
      const Eigen::Vector3d p = cloud.point_in_file_frame(i);
      ground_x.push_back(p.x());
      ground_y.push_back(p.y());
      ground_z.push_back(p.z());
    }
  ASSERT_GT(ground_z.size(), 1000u);
  const auto median = [](std::vector<double> values) {
    std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2), values.end());
    return values[values.size() / 2];
  };
  const std::vector<ModelPlane> grounds = planes_of_class(model, "ground");
  ASSERT_EQ(grounds.size(), 1u) << log;
  const ModelPlane& ground = grounds[0];
  const double height_at_median =
      -(ground.offset + ground.normal.x() * median(ground_x) + ground.normal.y() * median(ground_y)) / ground.normal.z();
  EXPECT_NEAR(height_at_median * unit, median(ground_z) * unit, 1.0) << "ground plane vs the class-2 median height, m";

  // Plane elements against the model's planes.
  const std::vector<ModelPlane> planes = planes_of_class(model, "plane");
  ASSERT_GT(planes.size(), 0u) << log;
  const PointCloud elements = read_point_cloud(folder.file("elements.ply"));
  const std::vector<float>& element_of = elements.extra_fields.at("element");
  std::map<int, std::vector<Eigen::Vector3d>> plane_elements;
  for (std::size_t i = 0; i < elements.size(); ++i)
    if (elements.labels[i] == 2) plane_elements[static_cast<int>(element_of[i])].push_back(elements.point_in_file_frame(i));
  EXPECT_EQ(plane_elements.size(), planes.size());
  std::size_t plane_points = 0, steep_points = 0;
  for (const auto& [element, points] : plane_elements) {
    double best = 1e300;
    const ModelPlane* nearest = nullptr;
    for (const ModelPlane& plane : planes) {
      std::vector<double> distances;
      for (const Eigen::Vector3d& p : points) distances.push_back(std::abs(plane.normal.dot(p) + plane.offset));
      const double typical = median(distances);
      if (typical < best) {
        best = typical;
        nearest = &plane;
      }
    }
    EXPECT_LE(best * unit, 0.2 + 0.15) << "element " << element << " (" << points.size()
                                       << " points): median distance to the nearest model plane, m";
    plane_points += points.size();
    if (nearest != nullptr && nearest->normal.z() < std::cos(60.0 * M_PI / 180.0)) steep_points += points.size();
  }
  EXPECT_LE(static_cast<double>(steep_points), 0.1 * static_cast<double>(plane_points))
      << steep_points << " of " << plane_points << " plane points in planes steeper than 60 deg";
}

// `auto` takes the tile for a nadir view (it covers its x-y extent evenly and is flat against it).
TEST(AirborneLas, AutoChoosesAirborneForTheAutzenTile) {
  QUADRIX_REQUIRE_SHARED_DATA("als_autzen/autzen_trim.las");
  const Folder folder("quadrix_airborne_auto");
  const nlohmann::json model = run_model(folder, testing::shared_data_path("als_autzen/autzen_trim.las"), "", "auto");
  ASSERT_TRUE(model.contains("stats"));
  EXPECT_EQ(model["stats"]["preset"], "airborne") << model["stats"]["preset_notes"];
}

}  // namespace
}  // namespace quadrix
