// Tile-by-tile modelling of large static scans (beyond the paper, whose Pantheon fits in memory):
// pass 1 bins the points into square tiles of the horizontal plane on disk (a temporary folder,
// removed afterwards, also on error) — square tiles of a given edge, or rectangles split by their
// point count so that no tile holds more than a memory budget allows; pass 2 extracts the static-scan shapes of each tile with a
// margin of overlap (paper §"Quadric Extraction", CGAL Efficient RANSAC), tiles in parallel; pass 3
// joins the pieces of one primitive cut by tile borders with the rules detect_shapes applies to
// the pieces of one shape, and fits one quadric per primitive (paper §"Quadric Fitting", Eq. (full
// attributes)). Memory grows with a tile, not with the survey. Passes 1 and 2 of one group of
// tiles give a PartialModel, so a survey can be split over processes or machines and merged.
#pragma once

#include "fitting/extraction.h"
#include "fitting/scene_model.h"
#include "fitting/scene_modelling.h"
#include "geometry/point_cloud.h"
#include "geometry/point_stream.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace quadrix {

/// A source of points read chunk by chunk (positions in the file's frame, metres).
class PointChunkSource {
 public:
  virtual ~PointChunkSource() = default;
  /// Fills `chunk` (3 x n) with the next n <= `maximum` points; false when none are left.
  virtual bool next_chunk(Eigen::Matrix3Xd& chunk, std::size_t maximum) = 0;
  /// Starts again from the first point (the tiler reads once more when it sizes tiles itself).
  virtual void rewind() = 0;
  /// What the points come from, for messages (a file name).
  virtual std::string name() const = 0;
};

/// Points already in memory as a chunk source (a cloud, or several moved into one frame).
class MatrixChunkSource : public PointChunkSource {
 public:
  /// Serves the columns of `points` plus `origin` (a cloud read relative to its local origin is
  /// served in the file's frame); `points` is kept by reference and must outlive the source.
  MatrixChunkSource(const Eigen::Matrix3Xf& points, std::string name, const Eigen::Vector3d& origin = Eigen::Vector3d::Zero());
  bool next_chunk(Eigen::Matrix3Xd& chunk, std::size_t maximum) override;
  void rewind() override { next_ = 0; }
  std::string name() const override { return name_; }

 private:
  const Eigen::Matrix3Xf& points_;
  std::string name_;
  Eigen::Vector3d origin_;
  Eigen::Index next_ = 0;
};

/// Another source's points multiplied by `factor`: a survey in feet served in metres, the unit of
/// every preset's lengths (the model is scaled back by 1 / factor before it is written).
class ScaledChunkSource : public PointChunkSource {
 public:
  /// `points` is kept by reference and must outlive the source.
  ScaledChunkSource(PointChunkSource& points, double factor) : points_(points), factor_(factor) {}
  bool next_chunk(Eigen::Matrix3Xd& chunk, std::size_t maximum) override {
    if (!points_.next_chunk(chunk, maximum)) return false;
    chunk *= factor_;
    return true;
  }
  void rewind() override { points_.rewind(); }
  std::string name() const override { return points_.name(); }

 private:
  PointChunkSource& points_;
  double factor_;
};

/// Point-cloud files read chunk by chunk (geometry/point_stream.h) in the file's coordinates
/// (double: georeferenced coordinates keep their precision), each moved by its pose into one frame
/// (TLS stations). Only one file and one chunk are held at once, so memory does not grow with the
/// files; rewind reopens the first file, so the tiler may read them as often as it needs.
class FileChunkSource : public PointChunkSource {
 public:
  /// Opens every file once to check it can be streamed (quadrix::Error naming the file otherwise);
  /// `poses` is empty (the files' own frame) or holds one sensor-to-world pose per file.
  FileChunkSource(std::vector<std::string> paths, std::vector<Eigen::Isometry3d> poses = {},
                  const PointStreamOptions& options = {});
  bool next_chunk(Eigen::Matrix3Xd& chunk, std::size_t maximum) override;
  void rewind() override;
  std::string name() const override;
  /// Records the files' headers declare, summed; nullopt when a file does not say (XYZ text).
  std::optional<std::size_t> declared_points() const { return declared_points_; }
  /// Records dropped so far because a coordinate was NaN or inf (since the last rewind).
  std::size_t non_finite_dropped() const { return dropped_ + (stream_ ? stream_->non_finite_dropped() : 0); }

 private:
  std::vector<std::string> paths_;
  std::vector<Eigen::Isometry3d> poses_;
  PointStreamOptions options_;
  std::optional<std::size_t> declared_points_;
  std::size_t file_ = 0;                 ///< index of the file being read
  std::unique_ptr<PointStream> stream_;  ///< that file, open (null before the first read or after the last)
  PointChunk chunk_;                     ///< reused read buffer
  std::size_t dropped_ = 0;              ///< non-finite records of the files already closed
};

/// Where the tiler is, for a progress display.
struct TilingProgress {
  int pass = 1;                       ///< 1 binning, 2 modelling tiles, 3 merging
  std::size_t points_done = 0;        ///< pass 1: points binned; pass 2: points of the tiles modelled
  std::size_t points_total = 0;       ///< points of the survey (pass 2: of this group's tiles; 0 when unknown)
  std::size_t tiles_done = 0;         ///< pass 2: tiles modelled
  std::size_t tiles_total = 0;        ///< pass 2: tiles of this group
  double seconds = 0.0;               ///< time since the pass began, s
};

/// Options of tiled modelling.
struct TilingOptions {
  double tile_size = 0.0;             ///< edge of a square tile in the x-y plane, m (0: tiles split by point count, see tile_points)
  std::size_t tile_points = 0;        ///< without tile_size: core points a tile holds at most (0: from memory_budget and threads, at most 2 M); a tile is split until it holds no more or is four margins wide
  double margin = 2.0;                ///< each tile is modelled with the points this far beyond its edges, m (at least cluster_epsilon, so a shape cut by the edge keeps its connected piece on both sides)
  std::size_t memory_budget = std::size_t{2} << 30;  ///< bytes the modelling may hold at once (default 2 GiB: a 2-core 24 GB machine shared with other work)
  int threads = 0;                    ///< tiles modelled at once (0: every core, within memory_budget)
  int group = 0;                      ///< this process models tile group `group` of `groups` (0-based)
  int groups = 1;                     ///< number of tile groups the survey is split into
  std::string temporary_parent;       ///< folder in which the tile folder is made (empty: the system's temporary folder)
  std::size_t sample_points = 1000;   ///< points kept per primitive piece for the merge refits and the final fit (pass 3 holds them all: at 1,000 it stays below pass 2's tiles on a 200 M-point site; the constrained fitter solves on 1,500)
  std::function<void(const TilingProgress&)> progress;  ///< called as the passes advance (may be empty)
};

/// Bytes a whole-cloud static-scan modelling holds per point (cloud, double copy, simplification,
/// element indices, CGAL's structures): the simulated monument peaked at about 130 bytes a point.
inline constexpr double kWholeModellingBytesPerPoint = 130.0;

/// Whether a survey of `points` points should be modelled tile by tile: its whole modelling would
/// exceed the memory budget.
bool tiling_needed(std::size_t points, const TilingOptions& options);

/// One primitive piece of a tile: what the merge and the final fit need. Coordinates are in the
/// file's frame; the moments and the sample hold the points of the tile's core only, so a point
/// the margins share is counted once.
struct TilePiece {
  ElementClass element_class = ElementClass::Plane;  ///< class the tile's extraction gave (ground, plane, cylinder, sphere, cone)
  QuadricType type = QuadricType::Invalid;           ///< detected shape type
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();   ///< shape parameters of the tile's detection: plane normal, cylinder or cone axis
  Eigen::Vector3d point = Eigen::Vector3d::Zero();   ///< point on a plane, axis point, sphere centre, cone apex
  double size = 0.0;                                 ///< cylinder or sphere radius (m), cone half-angle (radians)
  std::uint64_t point_count = 0;                     ///< core points of the piece
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();    ///< mean of those points
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero(); ///< sum of (p - mean)(p - mean)^T over them
  Eigen::Matrix3Xd sample;                           ///< at most TilingOptions::sample_points of them, evenly strided
};

/// Passes 1 and 2 for one group of tiles: what `quadrix model --tile i/n` writes.
struct PartialModel {
  int group = 0;                      ///< tile group modelled
  int groups = 1;                     ///< number of groups
  double tile_size = 0.0;             ///< square tiles: the tile edge used, m; tiles split by count: the edge of the grid cells they are made of, m
  std::uint64_t tile_points = 0;      ///< tiles split by count: at most this many core points each (0: square tiles of tile_size)
  double margin = 0.0;                ///< margin used, m
  std::uint64_t survey_points = 0;    ///< points of the whole survey
  std::uint64_t group_points = 0;     ///< core points of this group's tiles
  std::uint64_t tiles = 0;            ///< tiles of this group holding points
  std::uint64_t largest_tile = 0;     ///< core points of this group's largest tile
  std::vector<TilePiece> pieces;      ///< every primitive piece of those tiles
  std::map<std::string, double> timings_ms;  ///< wall time of "counting" (the tiles split by count), "binning" and "modelling" (pass 2), ms; not written to the file
};

/// Passes 1 and 2: bins `source` into tiles (square tiles of TilingOptions::tile_size, or without it
/// rectangles split by their point count, counted on a fine grid in one more read of the source:
/// every process of a split counts the whole survey, so all agree on the tiles) and extracts the static-scan shapes (extraction.static_scan must be
/// set) of the tiles of group options.group. Throws quadrix::Error on bad options or when a tile
/// file cannot be written (the temporary folder is removed either way).
PartialModel model_tile_group(PointChunkSource& source, const ExtractionOptions& extraction, const TilingOptions& options);

/// Pass 3: joins the partial models of every group (each exactly once, same tile size and margin,
/// else quadrix::Error naming the problem), merges pieces cut by tile borders, fits each primitive
/// with modelling.fitter and returns the model. No per-class cap (K_e) and no augmented points: a
/// static-scan model keeps every primitive it finds. The returned result's extraction and
/// record_elements are empty (the points are not held).
ModellingResult merge_partial_models(const std::vector<PartialModel>& parts, const ExtractionOptions& extraction,
                                     const ModellingOptions& modelling, const TilingOptions& options = {});

/// All three passes in one process.
ModellingResult model_tiled(PointChunkSource& source, const ExtractionOptions& extraction, const ModellingOptions& modelling,
                            const TilingOptions& options);

/// Writes a partial model (binary, little-endian, magic "QDXTILES" version 2) atomically.
void write_partial_model(const std::string& path, const PartialModel& part);
/// Reads a partial model; throws quadrix::Error naming the file and what is wrong.
PartialModel read_partial_model(const std::string& path);

/// A partial model as the bytes write_partial_model writes (to hand between processes).
std::string partial_model_to_bytes(const PartialModel& part);
/// Parses partial_model_to_bytes's output; throws quadrix::Error naming `name` and what is wrong.
PartialModel partial_model_from_bytes(const std::string& bytes, const std::string& name);

/// Parses "i/n" (1 <= i <= n) of `--tile` into a 0-based group and the group count; throws
/// quadrix::Error otherwise.
void parse_tile_group(const std::string& text, int& group, int& groups);

}  // namespace quadrix
