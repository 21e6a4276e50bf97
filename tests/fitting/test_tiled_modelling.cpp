// Tile-by-tile modelling: a small static scene whose tile border cuts through a pipe (cylinder), a
// wall and the floor; the pieces on both sides merge back into one primitive each, as the whole
// cloud gives, whatever the split into tile groups.
#include "fitting/extraction.h"
#include "fitting/extraction_internal.h"
#include "fitting/tiled_modelling.h"
#include "geometry/constants.h"
#include "geometry/error.h"
#include "geometry/io.h"
#include "tests/geometry/las_test_writer.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <random>

#include <unistd.h>

namespace quadrix {
namespace {

// Floor 23.8 x 10 m (z = 0, y in [1, 11]), a wall at y = 11 (4 m high) and a pipe of radius 0.5 m
// along x at y = 6, z = 1.5, from x = -10 to 10; the tile border x = 0 cuts all three.
Eigen::Matrix3Xf make_scene(std::uint64_t seed) {
  std::mt19937_64 engine(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.004);
  std::vector<Eigen::Vector3d> points;
  const auto add = [&](const Eigen::Vector3d& p) { points.push_back(p + Eigen::Vector3d(noise(engine), noise(engine), noise(engine))); };
  const auto count = [](double area) { return static_cast<int>(area * 150.0); };
  for (int i = 0; i < count(238.0); ++i) add({-11.9 + 23.8 * unit(engine), 1.0 + 10.0 * unit(engine), 0.0});
  for (int i = 0; i < count(95.2); ++i) add({-11.9 + 23.8 * unit(engine), 11.0, 4.0 * unit(engine)});
  for (int i = 0; i < count(2.0 * kPi * 0.5 * 20.0); ++i) {
    const double angle = 2.0 * kPi * unit(engine);
    add({-10.0 + 20.0 * unit(engine), 6.0 + 0.5 * std::cos(angle), 1.5 + 0.5 * std::sin(angle)});
  }
  Eigen::Matrix3Xf matrix(3, static_cast<Eigen::Index>(points.size()));
  for (std::size_t i = 0; i < points.size(); ++i) matrix.col(static_cast<Eigen::Index>(i)) = points[i].cast<float>();
  return matrix;
}

ExtractionOptions scene_extraction() {
  ExtractionOptions options = extraction_preset("monument");
  options.shapes = ShapeDetectionOptions();  // small-scene defaults (the preset is scaled for a 160 m monument)
  options.sensor_origin = Eigen::Vector3d(0.0, 3.0, 1.7);
  return options;
}

ModellingOptions scene_modelling() {
  ModellingOptions options;
  options.fitter = "constrained";
  return options;
}

std::map<QuadricType, int> type_counts(const SceneModel& model) {
  std::map<QuadricType, int> counts;
  for (std::size_t i = 0; i < model.augmented_begin; ++i) ++counts[model.types[i]];
  return counts;
}

class TiledModelling : public ::testing::Test {
 protected:
  void SetUp() override {
    folder = std::filesystem::temp_directory_path() / ("quadrix_test_tiles_" + std::to_string(::getpid()));
    std::filesystem::remove_all(folder);
    std::filesystem::create_directories(folder);
    tiling.tile_size = 12.0;
    tiling.margin = 1.0;
    tiling.temporary_parent = folder.string();
  }
  void TearDown() override { std::filesystem::remove_all(folder); }

  /// The scene's tiles modelled in three groups, each partial model written and read back.
  std::vector<PartialModel> model_in_three_groups(PointChunkSource& source) const {
    std::vector<PartialModel> parts;
    for (int group = 0; group < 3; ++group) {
      TilingOptions split = tiling;
      split.group = group;
      split.groups = 3;
      const std::string path = (folder / ("part" + std::to_string(group) + ".tiles")).string();
      write_partial_model(path, model_tile_group(source, scene_extraction(), split));
      parts.push_back(read_partial_model(path));
    }
    return parts;
  }

  std::filesystem::path folder;
  TilingOptions tiling;
};

/// Both models hold the same records in the same order, to 1e-9.
void expect_same_records(const SceneModel& model, const SceneModel& reference) {
  ASSERT_EQ(model.size(), reference.size());
  for (std::size_t i = 0; i < model.size(); ++i) {
    EXPECT_EQ(model.types[i], reference.types[i]);
    const auto a = model.records[i].to_array(), b = reference.records[i].to_array();
    for (std::size_t k = 0; k < a.size(); ++k) EXPECT_NEAR(a[k], b[k], 1e-9) << "record " << i << " value " << k;
  }
}

/// The model's cylinders are the scene's pipe: radius 0.5 m along x, holding its points from every tile.
void expect_the_whole_pipe(const SceneModel& model) {
  for (std::size_t i = 0; i < model.augmented_begin; ++i) {
    if (model.types[i] != QuadricType::CircularCylinder) continue;
    const QuadricDecomposition shape = model.records[i].quadric().decompose();
    EXPECT_NEAR(shape.scale.x(), 0.5, 0.02);
    EXPECT_GT(std::abs(shape.rotation.col(2).x()), 0.999);  // the axis runs along x
    // One primitive holds the pipe's points from all tiles (its 9.4k points, not a part of them).
    EXPECT_GT(model.element_point_counts[i], 0.9 * 150.0 * 2.0 * kPi * 0.5 * 20.0);
  }
}

TEST_F(TiledModelling, PiecesCutByATileBorderMergeBackIntoOnePrimitiveEach) {
  const Eigen::Matrix3Xf points = make_scene(3);
  // The whole cloud: the floor (ground), the wall and the pipe.
  PointCloud cloud;
  cloud.positions = points;
  const ExtractionResult whole = extract_elements(cloud, scene_extraction());
  std::map<QuadricType, int> whole_counts;
  for (const Element& element : whole.elements) ++whole_counts[element.detected_type];
  EXPECT_EQ(whole_counts[QuadricType::CircularCylinder], 1);
  EXPECT_EQ(whole_counts[QuadricType::Plane], 2);

  // Passes 1 and 2: the border at x = 0 leaves a piece of each primitive in both tiles.
  MatrixChunkSource source(points, "scene");
  const PartialModel part = model_tile_group(source, scene_extraction(), tiling);
  EXPECT_EQ(part.tiles, 2u);
  EXPECT_EQ(part.survey_points, static_cast<std::uint64_t>(points.cols()));
  std::map<QuadricType, int> piece_counts;
  std::uint64_t piece_points = 0;
  for (const TilePiece& piece : part.pieces) ++piece_counts[piece.type], piece_points += piece.point_count;
  EXPECT_GE(piece_counts[QuadricType::CircularCylinder], 2);
  EXPECT_GE(piece_counts[QuadricType::Plane], 4);
  EXPECT_LE(piece_points, part.survey_points);  // margins are not counted twice
  // The tile files are gone.
  EXPECT_TRUE(std::filesystem::is_empty(folder));

  // Pass 3: one cylinder and two planes, the pipe's radius and axis as built.
  const ModellingResult merged = merge_partial_models({part}, scene_extraction(), scene_modelling());
  const std::map<QuadricType, int> counts = type_counts(merged.model);
  EXPECT_EQ(counts.count(QuadricType::CircularCylinder) ? counts.at(QuadricType::CircularCylinder) : 0,
            whole_counts[QuadricType::CircularCylinder]);
  EXPECT_EQ(counts.count(QuadricType::Plane) ? counts.at(QuadricType::Plane) : 0, whole_counts[QuadricType::Plane]);
  EXPECT_TRUE(merged.model.has_ground);
  EXPECT_GT(merged.model.ground_normal.z(), 0.999);
  EXPECT_NEAR(merged.model.ground_offset, 0.0, 0.01);
  expect_the_whole_pipe(merged.model);
}

TEST_F(TiledModelling, AnySplitIntoTileGroupsGivesTheSameModel) {
  const Eigen::Matrix3Xf points = make_scene(4);
  MatrixChunkSource source(points, "scene");
  tiling.tile_size = 6.0;  // four tiles across x: borders at x = -6, 0 and 6 cut the pipe, the wall and the floor
  const ModellingResult small_tiles = model_tiled(source, scene_extraction(), scene_modelling(), tiling);
  std::vector<PartialModel> parts = model_in_three_groups(source);
  const ModellingResult split = merge_partial_models(parts, scene_extraction(), scene_modelling());
  expect_same_records(split.model, small_tiles.model);
  // Four pieces of each merge back into one pipe, one wall and the ground.
  EXPECT_EQ(type_counts(small_tiles.model)[QuadricType::CircularCylinder], 1);
  EXPECT_EQ(type_counts(small_tiles.model)[QuadricType::Plane], 2);

  // A missing part or one given twice is an error naming it.
  parts.pop_back();
  EXPECT_THROW(merge_partial_models(parts, scene_extraction(), scene_modelling()), Error);
  parts.push_back(parts.front());
  EXPECT_THROW(merge_partial_models(parts, scene_extraction(), scene_modelling()), Error);
}

// Without a tile edge the tiles are split by their point count: none holds more than asked for,
// the pieces still merge back into one pipe, one wall and the ground, and any split into tile
// groups gives the same model (every process counts the whole survey, so all agree on the tiles).
TEST_F(TiledModelling, TilesSplitByPointCountHoldAtMostTheTargetAndMergeBack) {
  const Eigen::Matrix3Xf points = make_scene(5);
  MatrixChunkSource source(points, "scene");
  tiling.tile_size = 0.0;
  tiling.tile_points = static_cast<std::size_t>(points.cols() / 4);  // about a quarter of the scene each
  const PartialModel part = model_tile_group(source, scene_extraction(), tiling);
  EXPECT_EQ(part.tile_points, tiling.tile_points);
  EXPECT_GE(part.tiles, 4u);
  EXPECT_LE(part.largest_tile, part.tile_points);
  EXPECT_GT(part.largest_tile, part.tile_points / 3);  // split where needed, not into slivers
  EXPECT_EQ(part.survey_points, static_cast<std::uint64_t>(points.cols()));
  EXPECT_EQ(part.group_points, part.survey_points);
  EXPECT_TRUE(std::filesystem::is_empty(folder));
  const ModellingResult merged = merge_partial_models({part}, scene_extraction(), scene_modelling());
  EXPECT_EQ(type_counts(merged.model)[QuadricType::CircularCylinder], 1);
  EXPECT_EQ(type_counts(merged.model)[QuadricType::Plane], 2);
  EXPECT_TRUE(merged.model.has_ground);
  expect_the_whole_pipe(merged.model);

  std::vector<PartialModel> parts = model_in_three_groups(source);
  for (const PartialModel& group : parts) EXPECT_EQ(group.tile_points, part.tile_points);
  const ModellingResult split = merge_partial_models(parts, scene_extraction(), scene_modelling());
  expect_same_records(split.model, merged.model);
  // Parts of a different split of the tiles do not merge with these.
  TilingOptions other = tiling;
  other.tile_points = tiling.tile_points / 2;
  other.group = 2;
  other.groups = 3;
  parts.back() = model_tile_group(source, scene_extraction(), other);
  EXPECT_THROW(merge_partial_models(parts, scene_extraction(), scene_modelling()), Error);
}

// The tiles read from a file chunk by chunk give the model the tiles read from memory give.
TEST_F(TiledModelling, StreamingFromAFileGivesTheInMemoryModel) {
  const Eigen::Matrix3Xf points = make_scene(6);
  PointCloud cloud;
  cloud.positions = points;
  const std::string path = (folder / "scene.ply").string();
  write_point_cloud(path, cloud);
  tiling.tile_size = 6.0;
  MatrixChunkSource memory(points, "scene");
  const ModellingResult in_memory = model_tiled(memory, scene_extraction(), scene_modelling(), tiling);
  FileChunkSource file({path});
  ASSERT_TRUE(file.declared_points().has_value());
  EXPECT_EQ(*file.declared_points(), static_cast<std::size_t>(points.cols()));
  const ModellingResult streamed = model_tiled(file, scene_extraction(), scene_modelling(), tiling);
  EXPECT_EQ(streamed.model.source_point_count, static_cast<std::size_t>(points.cols()));
  ASSERT_EQ(streamed.model.size(), in_memory.model.size());
  for (std::size_t i = 0; i < streamed.model.size(); ++i) {
    EXPECT_EQ(streamed.model.types[i], in_memory.model.types[i]);
    const auto a = streamed.model.records[i].to_array(), b = in_memory.model.records[i].to_array();
    for (std::size_t k = 0; k < a.size(); ++k) EXPECT_NEAR(a[k], b[k], 1e-9) << "record " << i << " value " << k;
  }
  EXPECT_EQ(type_counts(streamed.model)[QuadricType::CircularCylinder], 1);
  EXPECT_EQ(type_counts(streamed.model)[QuadricType::Plane], 2);

  // Two files, the second moved by its pose: the source serves both in one frame.
  PointCloud half_a, half_b;
  half_a.positions = points.leftCols(points.cols() / 2);
  const Eigen::Vector3d shift(100.0, -50.0, 2.0);
  half_b.positions = points.rightCols(points.cols() - points.cols() / 2).colwise() - shift.cast<float>();
  write_point_cloud((folder / "a.ply").string(), half_a);
  write_point_cloud((folder / "b.ply").string(), half_b);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = shift;
  FileChunkSource stations({(folder / "a.ply").string(), (folder / "b.ply").string()}, {Eigen::Isometry3d::Identity(), pose});
  Eigen::Matrix3Xd chunk, all(3, 0);
  for (int pass = 0; pass < 2; ++pass) {  // re-readable after rewind
    stations.rewind();
    all.resize(3, 0);
    while (stations.next_chunk(chunk, 1000)) {
      all.conservativeResize(3, all.cols() + chunk.cols());
      all.rightCols(chunk.cols()) = chunk;
    }
    ASSERT_EQ(all.cols(), points.cols());
    EXPECT_LT((all - points.cast<double>()).cwiseAbs().maxCoeff(), 1e-4);
  }
  EXPECT_THROW(FileChunkSource({(folder / "missing.ply").string()}), Error);
  EXPECT_THROW(FileChunkSource({path}, {pose, pose}), Error);
}

// A small georeferenced LAS (UTM-sized coordinates in millimetre steps): the model from the file
// is the local scene's, moved to the file's coordinates, with nothing lost to float32.
TEST_F(TiledModelling, GeoreferencedLasIsModelledInTheFilesCoordinates) {
  const Eigen::Matrix3Xf points = make_scene(7);
  testing::LasTestFile las;
  las.scale = Eigen::Vector3d::Constant(0.001);
  // Whole tiles away (12 m), so the tile borders cut the scene where they cut the local copy.
  las.offset = Eigen::Vector3d(12.0 * 41667.0, 12.0 * 333334.0, 120.0);
  Eigen::Matrix3Xf local(3, points.cols());
  for (Eigen::Index i = 0; i < points.cols(); ++i) {
    testing::LasTestPoint p;
    p.X = static_cast<std::int32_t>(std::lround(points(0, i) * 1000.0));
    p.Y = static_cast<std::int32_t>(std::lround(points(1, i) * 1000.0));
    p.Z = static_cast<std::int32_t>(std::lround(points(2, i) * 1000.0));
    local.col(i) = Eigen::Vector3f(static_cast<float>(p.X * 0.001), static_cast<float>(p.Y * 0.001), static_cast<float>(p.Z * 0.001));
    las.points.push_back(p);
  }
  const std::string path = (folder / "site.las").string();
  testing::write_bytes(path, testing::las_test_bytes(las));
  MatrixChunkSource memory(local, "scene");
  const ModellingResult in_memory = model_tiled(memory, scene_extraction(), scene_modelling(), tiling);
  ExtractionOptions georeferenced = scene_extraction();
  georeferenced.sensor_origin += las.offset;
  FileChunkSource file({path});
  const ModellingResult streamed = model_tiled(file, georeferenced, scene_modelling(), tiling);
  EXPECT_EQ(type_counts(streamed.model), type_counts(in_memory.model));
  EXPECT_EQ(type_counts(streamed.model)[QuadricType::CircularCylinder], 1);
  EXPECT_EQ(type_counts(streamed.model)[QuadricType::Plane], 2);
  // Every piece's points are in the file's coordinates: the statistical centres lie at the offset.
  for (std::size_t i = 0; i < streamed.model.augmented_begin; ++i)
    EXPECT_LT((streamed.model.records[i].full_center - las.offset).norm(), 30.0) << "record " << i;
  // Moved back to the scene's frame, the model is the local one (a quadric in ~10^6 m coordinates
  // is compared where it is well conditioned).
  const SceneModel back = translated(streamed.model, -las.offset);
  ASSERT_TRUE(back.has_ground);
  EXPECT_GT(back.ground_normal.z(), 0.999);
  EXPECT_NEAR(back.ground_offset, 0.0, 0.01);  // the floor at z = 120 m in the file
  int cylinders = 0;
  for (std::size_t i = 0; i < back.augmented_begin; ++i) {
    if (back.types[i] != QuadricType::CircularCylinder) continue;
    ++cylinders;
    const QuadricDecomposition shape = back.records[i].quadric().decompose();
    EXPECT_NEAR(shape.scale.x(), 0.5, 0.02);
    EXPECT_GT(std::abs(shape.rotation.col(2).x()), 0.999);  // along x
    EXPECT_NEAR(shape.center.y(), 6.0, 0.02);               // the pipe's axis at y = 6, z = 1.5
    EXPECT_NEAR(shape.center.z(), 1.5, 0.02);
  }
  EXPECT_EQ(cylinders, 1);
}

// Points on a cone (apex, unit axis toward the opening, half-angle), from `near` to `far` along
// the axis, over the azimuths [from, to) (radians), 2 mm noise.
Eigen::Matrix3Xd cone_points(const Eigen::Vector3d& apex, const Eigen::Vector3d& axis, double half_angle, double near, double far,
                             double from, double to, int count, std::uint64_t seed) {
  std::mt19937_64 engine(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.002);
  const Eigen::Vector3d u = axis.unitOrthogonal(), v = axis.cross(u);
  Eigen::Matrix3Xd points(3, count);
  for (int i = 0; i < count; ++i) {
    const double t = near + (far - near) * unit(engine), angle = from + (to - from) * unit(engine);
    points.col(i) = apex + t * axis + t * std::tan(half_angle) * (std::cos(angle) * u + std::sin(angle) * v) +
                    Eigen::Vector3d(noise(engine), noise(engine), noise(engine));
  }
  return points;
}

// The merge rules of pass 3 on cone pieces: two halves of one roof ring whose tiles fitted slightly
// different cones join (refitted from their own cone, where the normals of two half arcs alone
// may not pin the axis down), and a "cone" whose points are two walls meeting at a right angle
// (a 45-degree cone along their corner fits them locally) is dissolved.
TEST(TiledMerge, ConePiecesJoinAndACornerIsNoCone) {
  const ShapeDetectionOptions options = extraction_preset("monument").shapes;
  const Eigen::Vector3d apex(0.0, 0.0, 10.0), down(0.0, 0.0, -1.0);
  const double angle = 26.565 * kPi / 180.0;
  std::vector<detail::ShapePiece> pieces(3);
  for (int half = 0; half < 2; ++half) {
    detail::ShapePiece& piece = pieces[static_cast<std::size_t>(half)];
    piece.type = QuadricType::CircularCone;
    piece.points = cone_points(apex, down, angle, 6.0, 9.0, half * kPi, (half + 1) * kPi, 1000, 10 + half);
    // Each tile's cone is off by a little: 1 degree of tilt, 2 cm of apex, 0.3 degrees of angle.
    piece.axis = Eigen::AngleAxisd((half == 0 ? 1.0 : -1.0) * kPi / 180.0, Eigen::Vector3d::UnitX()) * down;
    piece.point = apex + Eigen::Vector3d(0.0, 0.02 * half, 0.0);
    piece.size = angle + (half == 0 ? 0.003 : -0.003);
    piece.weight = half == 0 ? 40000.0 : 30000.0;
  }
  // Two walls x = 20 (y in [0, 2]) and y = 0 (x in [18, 20]), 1.5 m high, taken for a cone along
  // their corner's bisector.
  detail::ShapePiece& corner = pieces[2];
  corner.type = QuadricType::CircularCone;
  corner.points.resize(3, 800);
  std::mt19937_64 engine(5);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (Eigen::Index i = 0; i < corner.points.cols(); ++i)
    corner.points.col(i) = i % 2 == 0 ? Eigen::Vector3d(20.0, 2.0 * unit(engine), 1.5 * unit(engine))
                                      : Eigen::Vector3d(18.0 + 2.0 * unit(engine), 0.0, 1.5 * unit(engine));
  corner.axis = Eigen::Vector3d(-1.0, 1.0, 0.0).normalized();
  corner.point = Eigen::Vector3d(20.0, 0.0, 0.75);
  corner.size = 0.25 * kPi;
  corner.weight = 800.0;
  const std::vector<int> joined = detail::merge_shape_pieces(pieces, options, Eigen::Vector3d::UnitZ());
  ASSERT_EQ(joined.size(), 3u);
  EXPECT_EQ(joined[0], 0);
  EXPECT_EQ(joined[1], 0);   // the second half joined the first
  EXPECT_EQ(joined[2], -1);  // the corner is dissolved
  EXPECT_NEAR(pieces[0].size, angle, 0.5 * kPi / 180.0);
  EXPECT_LT((pieces[0].point - apex).norm(), 0.05);

  // A genuine cone piece two planes cannot explain stays.
  std::vector<detail::ShapePiece> alone(1);
  alone[0] = pieces[1];
  alone[0].points = cone_points(apex, down, angle, 6.0, 9.0, 0.0, 0.5 * kPi, 1000, 12);
  EXPECT_EQ(detail::merge_shape_pieces(alone, options, Eigen::Vector3d::UnitZ()), std::vector<int>{0});
}

// A roof ring as on the monument's drum (a cone opening downward, apex 30 m up, half-angle
// 26.565 degrees, 10 to 14 m across, the monument preset) over a floor, cut by 6 m tiles into
// strips whose cones each tile pins down poorly, is one cone again after the merge, as modelled whole.
TEST_F(TiledModelling, ARoofRingCutIntoStripsByTileBordersMergesBackIntoOneCone) {
  const Eigen::Vector3d apex(1.5, 2.5, 30.0), down(0.0, 0.0, -1.0);
  const double angle = 26.565 * kPi / 180.0;
  const int ring_points = 27000;  // 40 points/m^2 over its 675 m^2
  const Eigen::Matrix3Xd ring = cone_points(apex, down, angle, 20.0, 28.0, 0.0, 2.0 * kPi, ring_points, 21);
  std::mt19937_64 engine(22);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.004);
  const int floor_points = 12000;
  Eigen::Matrix3Xf points(3, ring_points + floor_points);
  points.leftCols(ring_points) = ring.cast<float>();
  for (int i = 0; i < floor_points; ++i)
    points.col(ring_points + i) = Eigen::Vector3f(static_cast<float>(-15.0 + 33.0 * unit(engine)),
                                                  static_cast<float>(-14.0 + 33.0 * unit(engine)), static_cast<float>(noise(engine)));
  ExtractionOptions extraction = extraction_preset("monument");
  extraction.sensor_origin = Eigen::Vector3d(1.5, -40.0, 40.0);  // a station above, seeing the roof's outside

  PointCloud cloud;
  cloud.positions = points;
  const ExtractionResult whole = extract_elements(cloud, extraction);
  std::map<QuadricType, int> whole_counts;
  for (const Element& element : whole.elements) ++whole_counts[element.detected_type];
  ASSERT_EQ(whole_counts[QuadricType::CircularCone], 1);

  MatrixChunkSource source(points, "ring");
  tiling.tile_size = 6.0;  // five strips across the ring
  const PartialModel part = model_tile_group(source, extraction, tiling);
  std::size_t curved_pieces = 0;
  for (const TilePiece& piece : part.pieces) curved_pieces += piece.type != QuadricType::Plane ? 1 : 0;
  EXPECT_GE(curved_pieces, 4u);  // the tiles did cut the ring
  const ModellingResult merged = merge_partial_models({part}, extraction, scene_modelling());
  std::map<QuadricType, int> counts = type_counts(merged.model);
  EXPECT_EQ(counts[QuadricType::CircularCone], 1);
  EXPECT_EQ(counts[QuadricType::CircularCylinder], 0);
  EXPECT_EQ(counts[QuadricType::Sphere], 0);
  for (std::size_t i = 0; i < merged.model.augmented_begin; ++i) {
    if (merged.model.types[i] != QuadricType::CircularCone) continue;
    // One cone holds the ring's points from every tile, at the ring's apex.
    EXPECT_GT(merged.model.element_point_counts[i], 0.9 * ring_points);
    const QuadricDecomposition shape = merged.model.records[i].quadric().decompose();
    EXPECT_LT((shape.center - apex).norm(), 0.1) << shape.center.transpose();
    EXPECT_NEAR(shape.scale.x(), std::tan(angle), 0.01);
  }
}

// The merge rules of pass 3 that do not trust a piece's own parameters: a sliver of a roof ring
// whose tile fitted a cone tilted by 8 degrees (beyond the merge angle) joins the ring the other
// piece's cone explains; a band of the ring a tile took for a tilted cylinder joins it too; and a
// "cone" on the corner of three faces (two walls and a strip of the floor above a step, which no
// two planes explain) is dissolved.
TEST(TiledMerge, SliversAndCylinderBandsJoinTheirConeAndAThreeFaceCornerIsNoCone) {
  const ShapeDetectionOptions options = extraction_preset("monument").shapes;
  const Eigen::Vector3d apex(0.0, 0.0, 30.0), down(0.0, 0.0, -1.0);
  const double angle = 26.565 * kPi / 180.0;
  std::vector<detail::ShapePiece> pieces(4);
  // The ring's well-fitted piece (a third of it) and a 10-degree sliver with a tilted cone; the
  // sliver is the heavier piece (a dense strip in front of a station).
  pieces[0].type = QuadricType::CircularCone;
  pieces[0].points = cone_points(apex, down, angle, 20.0, 28.0, 0.0, 2.0 * kPi / 3.0, 1000, 31);
  pieces[0].axis = down;
  pieces[0].point = apex;
  pieces[0].size = angle;
  pieces[0].weight = 30000.0;
  pieces[1].type = QuadricType::CircularCone;
  pieces[1].points = cone_points(apex, down, angle, 20.0, 28.0, -0.2, -0.025, 1000, 32);
  pieces[1].axis = Eigen::AngleAxisd(8.0 * kPi / 180.0, Eigen::Vector3d::UnitY()) * down;
  pieces[1].point = apex + Eigen::Vector3d(-3.0, 0.0, -6.0);
  pieces[1].size = angle + 6.0 * kPi / 180.0;
  pieces[1].weight = 90000.0;
  // A band of the ring on the far side, as a cylinder tilted 25 degrees.
  pieces[2].type = QuadricType::CircularCylinder;
  pieces[2].points = cone_points(apex, down, angle, 22.0, 26.0, 2.2, 2.5, 600, 33);
  pieces[2].axis = Eigen::AngleAxisd(25.0 * kPi / 180.0, Eigen::Vector3d::UnitX()) * down;
  pieces[2].point = pieces[2].points.rowwise().mean() + Eigen::Vector3d(0.0, 0.0, 0.0);
  pieces[2].size = 12.0;
  pieces[2].weight = 5000.0;
  // Walls x = 40 (y in [0, 3], z in [1, 1.5]) and y = 3 (x in [40, 44], z in [0, 1.5]) and the floor
  // z = 1.5 above the step (x in [40, 41], y in [0, 3]): a 45-degree cone around the corner's bisector.
  detail::ShapePiece& corner = pieces[3];
  corner.type = QuadricType::CircularCone;
  corner.points.resize(3, 900);
  std::mt19937_64 engine(34);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (Eigen::Index i = 0; i < corner.points.cols(); ++i) {
    const int face = static_cast<int>(i % 9);
    corner.points.col(i) = face < 4   ? Eigen::Vector3d(40.0, 3.0 * unit(engine), 1.0 + 0.5 * unit(engine))
                           : face < 8 ? Eigen::Vector3d(40.0 + 4.0 * unit(engine), 3.0, 1.5 * unit(engine))
                                      : Eigen::Vector3d(40.0 + unit(engine), 3.0 * unit(engine), 1.5);
  }
  corner.axis = Eigen::Vector3d(1.0, -1.0, 0.0).normalized();
  corner.point = Eigen::Vector3d(40.0, 3.0, 1.0);
  corner.size = 0.25 * kPi;
  corner.weight = 1600.0;
  const std::vector<int> joined = detail::merge_shape_pieces(pieces, options, Eigen::Vector3d::UnitZ());
  ASSERT_EQ(joined.size(), 4u);
  EXPECT_EQ(joined[1], joined[0]);  // the sliver and the third are one ring
  EXPECT_GE(joined[0], 0);
  EXPECT_EQ(joined[2], joined[0]);  // the cylinder band joined it
  EXPECT_EQ(joined[3], -1);         // the three-face corner is dissolved
  const detail::ShapePiece& ring = pieces[static_cast<std::size_t>(joined[0])];
  EXPECT_NEAR(ring.size, angle, 0.2 * kPi / 180.0);
  EXPECT_LT((ring.point - apex).norm(), 0.05);
  EXPECT_GT(std::abs(ring.axis.z()), std::cos(0.2 * kPi / 180.0));
}

TEST_F(TiledModelling, BadInputIsAClearError) {
  int group = 0, groups = 0;
  parse_tile_group("2/5", group, groups);
  EXPECT_EQ(group, 1);
  EXPECT_EQ(groups, 5);
  for (const char* text : {"0/3", "4/3", "1/0", "a/b", "2", "1/2x"}) EXPECT_THROW(parse_tile_group(text, group, groups), Error) << text;
  const std::string path = (folder / "truncated.tiles").string();
  PartialModel part;
  part.tile_size = 10.0;
  TilePiece piece;
  piece.type = QuadricType::Plane;
  piece.point_count = 3;
  piece.sample = Eigen::Matrix3Xd::Identity(3, 3);
  part.pieces.push_back(piece);
  write_partial_model(path, part);
  EXPECT_EQ(read_partial_model(path).pieces.size(), 1u);
  std::filesystem::resize_file(path, std::filesystem::file_size(path) - 7);
  try {
    read_partial_model(path);
    FAIL() << "a truncated partial model was read";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("truncated"), std::string::npos) << error.what();
  }
  const Eigen::Matrix3Xf points = make_scene(5);
  MatrixChunkSource source(points, "scene");
  ExtractionOptions lidar = extraction_preset("vlp64");
  EXPECT_THROW(model_tile_group(source, lidar, tiling), Error);
  tiling.tile_size = 1.5;  // not wider than two margins
  EXPECT_THROW(model_tile_group(source, scene_extraction(), tiling), Error);
}

}  // namespace
}  // namespace quadrix
