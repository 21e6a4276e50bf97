// Tile-by-tile modelling of large static scans (see tiled_modelling.h).
#include "fitting/tiled_modelling.h"
#include "fitting/extraction_internal.h"
#include "fitting/quadric_fitter.h"

#include "geometry/constants.h"
#include "geometry/error.h"
#include "geometry/io.h"

#include <tbb/parallel_for.h>
#include <tbb/task_group.h>
#include <tbb/task_arena.h>

#include <stdlib.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <numeric>
#include <sstream>
#include <thread>
#include <unordered_map>

namespace quadrix {

MatrixChunkSource::MatrixChunkSource(const Eigen::Matrix3Xf& points, std::string name, const Eigen::Vector3d& origin)
    : points_(points), name_(std::move(name)), origin_(origin) {}

bool MatrixChunkSource::next_chunk(Eigen::Matrix3Xd& chunk, std::size_t maximum) {
  const Eigen::Index count = std::min<Eigen::Index>(static_cast<Eigen::Index>(maximum), points_.cols() - next_);
  if (count <= 0) return false;
  chunk = points_.middleCols(next_, count).cast<double>().colwise() + origin_;
  next_ += count;
  return true;
}

FileChunkSource::FileChunkSource(std::vector<std::string> paths, std::vector<Eigen::Isometry3d> poses,
                                 const PointStreamOptions& options)
    : paths_(std::move(paths)), poses_(std::move(poses)), options_(options) {
  if (paths_.empty()) throw Error("tiled modelling: no input file");
  if (!poses_.empty() && poses_.size() != paths_.size())
    throw Error("tiled modelling: " + std::to_string(poses_.size()) + " poses for " + std::to_string(paths_.size()) +
                " files (expected one per file)");
  std::size_t declared = 0;
  bool all_declared = true;
  for (const std::string& path : paths_) {
    const std::unique_ptr<PointStream> stream = open_point_stream(path, options_);
    if (stream->point_count()) declared += *stream->point_count();
    else all_declared = false;
  }
  if (all_declared) declared_points_ = declared;
}

bool FileChunkSource::next_chunk(Eigen::Matrix3Xd& chunk, std::size_t maximum) {
  while (file_ < paths_.size()) {
    if (!stream_) stream_ = open_point_stream(paths_[file_], options_);
    if (stream_->read(std::max<std::size_t>(1, maximum), chunk_)) {
      if (poses_.empty()) chunk.swap(chunk_.positions);
      else chunk.noalias() = poses_[file_] * chunk_.positions;  // Isometry3d * 3xN applies the rotation and translation
      return true;
    }
    dropped_ += stream_->non_finite_dropped();
    stream_.reset();
    ++file_;
  }
  return false;
}

void FileChunkSource::rewind() {
  stream_.reset();
  file_ = 0;
  dropped_ = 0;
}

std::string FileChunkSource::name() const {
  const std::string first = std::filesystem::path(paths_.front()).filename().string();
  return paths_.size() == 1 ? first : first + " + " + std::to_string(paths_.size() - 1) + " more";
}

bool tiling_needed(std::size_t points, const TilingOptions& options) {
  return static_cast<double>(points) * kWholeModellingBytesPerPoint > static_cast<double>(options.memory_budget);
}

void parse_tile_group(const std::string& text, int& group, int& groups) {
  const std::size_t slash = text.find('/');
  try {
    std::size_t used_i = 0, used_n = 0;
    if (slash == std::string::npos) throw std::invalid_argument("no slash");
    const int i = std::stoi(text.substr(0, slash), &used_i);
    const int n = std::stoi(text.substr(slash + 1), &used_n);
    if (used_i != slash || used_n != text.size() - slash - 1 || n < 1 || i < 1 || i > n) throw std::invalid_argument("range");
    group = i - 1;
    groups = n;
  } catch (const std::exception&) {
    throw Error("--tile: expected i/n with 1 <= i <= n (the i-th of n tile groups), got '" + text + "'");
  }
}

namespace {

using Clock = std::chrono::steady_clock;

// Points a tile is sized for at most: Efficient RANSAC's time grows faster than its input, and two
// tiles of this size stay within the default budget at kWholeModellingBytesPerPoint.
constexpr double kMaximumTilePoints = 2.0e6;
// Points read from the source at once.
constexpr std::size_t kChunkPoints = 1u << 20;
// Occupied grid cells the count pass holds at most (about 50 MB of hash map) before it doubles the cell.
constexpr std::size_t kMaximumCountCells = std::size_t{1} << 20;
// Bytes of tile buffers held in pass 1 before they are appended to their files.
constexpr std::size_t kBufferedBytes = std::size_t{64} << 20;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

/// Integer tile coordinates packed into one key.
std::uint64_t tile_key(std::int64_t x, std::int64_t y) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(static_cast<std::int32_t>(x))) << 32) |
         static_cast<std::uint32_t>(static_cast<std::int32_t>(y));
}
std::int64_t tile_x(std::uint64_t key) { return static_cast<std::int32_t>(static_cast<std::uint32_t>(key >> 32)); }
std::int64_t tile_y(std::uint64_t key) { return static_cast<std::int32_t>(static_cast<std::uint32_t>(key & 0xffffffffu)); }

/// The group a tile belongs to: a hash of its coordinates (splitmix64), so every process agrees
/// without knowing the other tiles.
int group_of_tile(std::uint64_t key, int groups) {
  std::uint64_t z = key + 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  z ^= z >> 31;
  return static_cast<int>(z % static_cast<std::uint64_t>(groups));
}

/// A folder of tile files under `parent`, removed with everything in it when this goes out of scope
/// (also when an exception unwinds).
class TemporaryFolder {
 public:
  explicit TemporaryFolder(const std::string& parent) {
    std::filesystem::path base = parent.empty() ? std::filesystem::temp_directory_path() : std::filesystem::path(parent);
    std::string pattern = (base / "quadrix-tiles-XXXXXX").string();
    if (mkdtemp(pattern.data()) == nullptr)
      throw Error("tiles: cannot create a temporary folder in " + base.string() + " (" + std::strerror(errno) + ")");
    path_ = pattern;
  }
  ~TemporaryFolder() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  TemporaryFolder(const TemporaryFolder&) = delete;
  TemporaryFolder& operator=(const TemporaryFolder&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

/// Floor of a / 2 for negative cell indices too.
std::int64_t half_floor(std::int64_t a) { return a >= 0 ? a / 2 : -((-a + 1) / 2); }

/// Where the tiles lie in the x-y plane: square tiles of one edge anchored at the origin, or
/// rectangles of grid cells split by their point count (a k-d split). A tile is named by the grid
/// indices of its lower corner (tile_key); its corner in metres is those indices times the cell.
class TileLayout {
 public:
  /// Square tiles of edge `size`.
  static TileLayout squares(double size) {
    TileLayout layout;
    layout.cell_ = size;
    return layout;
  }

  /// Rectangles of `cell`-sized grid cells covering the occupied cells `cells` (cell key -> points),
  /// each split in two across its longer side at the line that best halves its points while it
  /// holds more than `target` points and both halves stay at least `minimum_cells` cells wide. The
  /// split depends on the counts only, not on the order the points came in.
  static TileLayout split_by_count(const std::unordered_map<std::uint64_t, std::uint64_t>& cells, double cell,
                                   std::uint64_t target, std::int64_t minimum_cells) {
    TileLayout layout;
    layout.cell_ = cell;
    layout.target_ = std::max<std::uint64_t>(1, target);
    std::vector<Cell> list;
    list.reserve(cells.size());
    Node root;
    root.x0 = root.y0 = std::numeric_limits<std::int64_t>::max();
    root.x1 = root.y1 = std::numeric_limits<std::int64_t>::min();
    for (const auto& [key, count] : cells) {
      list.push_back({tile_x(key), tile_y(key), count});
      root.x0 = std::min(root.x0, tile_x(key)), root.x1 = std::max(root.x1, tile_x(key) + 1);
      root.y0 = std::min(root.y0, tile_y(key)), root.y1 = std::max(root.y1, tile_y(key) + 1);
    }
    if (list.empty()) root.x0 = root.y0 = 0, root.x1 = root.y1 = 1;
    layout.nodes_.push_back(root);
    layout.split(0, list, 0, list.size(), std::max<std::int64_t>(1, minimum_cells));
    return layout;
  }

  /// Calls visit(key, core) for the tile holding `p` (core true) and for every tile whose
  /// rectangle widened by `margin` holds it (core false). Square tiles need margin <= edge / 2.
  template <typename Visit>
  void visit(const Eigen::Vector3d& p, double margin, Visit&& visit) const {
    const std::int64_t cx = static_cast<std::int64_t>(std::floor(p.x() / cell_));
    const std::int64_t cy = static_cast<std::int64_t>(std::floor(p.y() / cell_));
    if (nodes_.empty()) {
      const double rx = p.x() - static_cast<double>(cx) * cell_, ry = p.y() - static_cast<double>(cy) * cell_;
      const int low_x = rx < margin ? -1 : 0, high_x = rx >= cell_ - margin ? 1 : 0;
      const int low_y = ry < margin ? -1 : 0, high_y = ry >= cell_ - margin ? 1 : 0;
      for (int dx = low_x; dx <= high_x; ++dx)
        for (int dy = low_y; dy <= high_y; ++dy) visit(tile_key(cx + dx, cy + dy), dx == 0 && dy == 0);
      return;
    }
    const Node& root = nodes_.front();
    if (cx < root.x0 || cx >= root.x1 || cy < root.y0 || cy >= root.y1)
      throw Error("tiles: a point at (" + std::to_string(p.x()) + ", " + std::to_string(p.y()) +
                  ") lies outside the tiles the first read counted (did the input change between reads?)");
    stack_.clear();
    stack_.push_back(0);
    while (!stack_.empty()) {
      const Node& node = nodes_[static_cast<std::size_t>(stack_.back())];
      stack_.pop_back();
      if (node.axis < 0) {
        if (node.count == 0) continue;  // no core point: not a tile
        visit(tile_key(node.x0, node.y0), cx >= node.x0 && cx < node.x1 && cy >= node.y0 && cy < node.y1);
        continue;
      }
      const std::int64_t index = node.axis == 0 ? cx : cy;
      const double line = static_cast<double>(node.split) * cell_, coordinate = p(node.axis);
      if (index < node.split || coordinate < line + margin) stack_.push_back(node.left);
      if (index >= node.split || coordinate >= line - margin) stack_.push_back(node.right);
    }
  }

  /// The tile's lower corner in the file's frame (z = 0).
  Eigen::Vector3d corner(std::uint64_t key) const {
    return {static_cast<double>(tile_x(key)) * cell_, static_cast<double>(tile_y(key)) * cell_, 0.0};
  }
  /// Square tiles: their edge; split tiles: the grid cell's edge, m.
  double cell() const { return cell_; }
  /// Split tiles: the points a tile holds at most unless it is at the minimum width (0: squares).
  std::uint64_t target() const { return target_; }

 private:
  struct Cell {
    std::int64_t x, y;
    std::uint64_t count;
  };
  struct Node {
    int axis = -1;            ///< 0 split across x, 1 across y, -1 a tile
    std::int64_t split = 0;   ///< cells below this index go left
    int left = -1, right = -1;
    std::int64_t x0 = 0, y0 = 0, x1 = 0, y1 = 0;  ///< cells [x0, x1) x [y0, y1)
    std::uint64_t count = 0;  ///< points of the cells inside
  };

  void split(int index, std::vector<Cell>& list, std::size_t begin, std::size_t end, std::int64_t minimum_cells) {
    std::uint64_t total = 0;
    for (std::size_t i = begin; i < end; ++i) total += list[i].count;
    nodes_[static_cast<std::size_t>(index)].count = total;
    const Node box = nodes_[static_cast<std::size_t>(index)];
    if (total <= target_) return;
    const std::int64_t width[2] = {box.x1 - box.x0, box.y1 - box.y0};
    int axis = width[0] >= width[1] ? 0 : 1;
    if (width[axis] < 2 * minimum_cells) axis = 1 - axis;
    if (width[axis] < 2 * minimum_cells) return;  // as narrow as a tile may be
    const auto coordinate = [axis](const Cell& c) { return axis == 0 ? c.x : c.y; };
    std::sort(list.begin() + static_cast<std::ptrdiff_t>(begin), list.begin() + static_cast<std::ptrdiff_t>(end),
              [&](const Cell& a, const Cell& b) {
                return coordinate(a) != coordinate(b) ? coordinate(a) < coordinate(b) : (axis == 0 ? a.y < b.y : a.x < b.x);
              });
    // The line (a cell index) where the points below come closest to half of them.
    const std::int64_t low = (axis == 0 ? box.x0 : box.y0) + minimum_cells, high = (axis == 0 ? box.x1 : box.y1) - minimum_cells;
    std::vector<std::int64_t> lines{low, high};  // where the points below can change: the cells' own lines
    for (std::size_t i = begin; i < end; ++i) lines.push_back(std::clamp(coordinate(list[i]), low, high));
    std::sort(lines.begin(), lines.end());
    lines.erase(std::unique(lines.begin(), lines.end()), lines.end());
    std::int64_t best = low;
    double best_gap = std::numeric_limits<double>::infinity();
    std::uint64_t below = 0;
    std::size_t i = begin;
    for (const std::int64_t line : lines) {
      while (i < end && coordinate(list[i]) < line) below += list[i++].count;
      const double gap = std::abs(2.0 * static_cast<double>(below) - static_cast<double>(total));
      if (gap < best_gap) best_gap = gap, best = line;
    }
    std::size_t middle = begin;
    while (middle < end && coordinate(list[middle]) < best) ++middle;
    Node left = box, right = box;
    left.axis = right.axis = -1;
    (axis == 0 ? left.x1 : left.y1) = best;
    (axis == 0 ? right.x0 : right.y0) = best;
    const int left_index = static_cast<int>(nodes_.size());
    nodes_.push_back(left);
    nodes_.push_back(right);
    Node& parent = nodes_[static_cast<std::size_t>(index)];
    parent.axis = axis;
    parent.split = best;
    parent.left = left_index;
    parent.right = left_index + 1;
    split(left_index, list, begin, middle, minimum_cells);
    split(left_index + 1, list, middle, end, minimum_cells);
  }

  double cell_ = 1.0;
  std::uint64_t target_ = 0;
  std::vector<Node> nodes_;            ///< the k-d split, root first (empty: square tiles)
  mutable std::vector<int> stack_;     ///< visit's work list (pass 1 bins from one thread)
};

/// Points of one tile: those inside it (core) and those within the margin around it.
struct TileCounts {
  std::uint64_t core = 0;    ///< points inside the tile
  std::uint64_t margin = 0;  ///< points of the margin
};

/// Pass 1 state: per-tile buffers of float coordinates relative to the tile's corner, appended to
/// "<x>_<y>.core" and "<x>_<y>.margin" files.
class TileBinner {
 public:
  TileBinner(const std::filesystem::path& folder, const TileLayout& layout, double margin, int group, int groups)
      : folder_(folder), layout_(layout), margin_(margin), group_(group), groups_(groups) {}

  void add(const Eigen::Vector3d& p) {
    layout_.visit(p, margin_, [&](std::uint64_t key, bool core) {
      TileCounts& counts = counts_[key];
      (core ? counts.core : counts.margin) += 1;
      if (groups_ > 1 && group_of_tile(key, groups_) != group_) return;
      const Eigen::Vector3d corner = layout_.corner(key);
      std::vector<float>& buffer = (core ? core_buffers_ : margin_buffers_)[key];
      buffer.push_back(static_cast<float>(p.x() - corner.x()));
      buffer.push_back(static_cast<float>(p.y() - corner.y()));
      buffer.push_back(static_cast<float>(p.z()));
      buffered_ += 3 * sizeof(float);
    });
    if (buffered_ >= kBufferedBytes) flush();
  }

  void flush() {
    for (auto* buffers : {&core_buffers_, &margin_buffers_})
      for (auto& [key, buffer] : *buffers) {
        if (buffer.empty()) continue;
        const std::filesystem::path path = file(key, buffers == &core_buffers_);
        std::ofstream out(path, std::ios::binary | std::ios::app);
        out.write(reinterpret_cast<const char*>(buffer.data()), static_cast<std::streamsize>(buffer.size() * sizeof(float)));
        out.close();
        if (!out) throw Error("tiles: writing " + path.string() + " failed (is the disk full?)");
        buffer.clear();
        buffer.shrink_to_fit();
      }
    buffered_ = 0;
  }

  std::filesystem::path file(std::uint64_t key, bool core) const {
    return folder_ / (std::to_string(tile_x(key)) + "_" + std::to_string(tile_y(key)) + (core ? ".core" : ".margin"));
  }
  const std::map<std::uint64_t, TileCounts>& counts() const { return counts_; }
  bool in_group(std::uint64_t key) const { return groups_ == 1 || group_of_tile(key, groups_) == group_; }

 private:
  std::filesystem::path folder_;
  const TileLayout& layout_;
  double margin_;
  int group_, groups_;
  std::map<std::uint64_t, TileCounts> counts_;
  std::unordered_map<std::uint64_t, std::vector<float>> core_buffers_, margin_buffers_;
  std::size_t buffered_ = 0;
};

/// Reads `count` points of a tile file into columns [first, first + count) of `points`, adding `corner`.
void read_tile_file(const std::filesystem::path& path, std::uint64_t count, const Eigen::Vector3d& corner,
                    Eigen::Matrix3Xd& points, Eigen::Index first) {
  if (count == 0) return;
  std::ifstream in(path, std::ios::binary);
  std::vector<float> values(static_cast<std::size_t>(3 * count));
  in.read(reinterpret_cast<char*>(values.data()), static_cast<std::streamsize>(values.size() * sizeof(float)));
  if (!in) throw Error("tiles: reading " + path.string() + " failed (expected " + std::to_string(count) + " points)");
  for (std::uint64_t i = 0; i < count; ++i)
    points.col(first + static_cast<Eigen::Index>(i)) =
        Eigen::Vector3d(values[3 * i], values[3 * i + 1], values[3 * i + 2]) + corner;
}

/// Tiles for the budget: the points counted on a grid of cells (cell edge the margin, at least
/// 1 m, doubled while more than kMaximumCountCells cells hold points), then split until a tile holds
/// at most as many points as `threads` tiles modelled at once may (bounded by kMaximumTilePoints)
/// or is four margins wide. Reads the source once.
TileLayout layout_for_budget(PointChunkSource& source, const TilingOptions& options, int threads) {
  double cell = std::max(options.margin, 1.0);
  std::unordered_map<std::uint64_t, std::uint64_t> cells;
  Eigen::Matrix3Xd chunk;
  source.rewind();
  while (source.next_chunk(chunk, kChunkPoints)) {
    for (Eigen::Index i = 0; i < chunk.cols(); ++i) {
      if (!chunk.col(i).allFinite()) continue;
      ++cells[tile_key(static_cast<std::int64_t>(std::floor(chunk(0, i) / cell)),
                       static_cast<std::int64_t>(std::floor(chunk(1, i) / cell)))];
    }
    while (cells.size() > kMaximumCountCells) {  // the grid at twice the edge, each cell the sum of four
      std::unordered_map<std::uint64_t, std::uint64_t> coarser;
      for (const auto& [key, count] : cells) coarser[tile_key(half_floor(tile_x(key)), half_floor(tile_y(key)))] += count;
      cells.swap(coarser);
      cell *= 2.0;
    }
  }
  source.rewind();
  const std::uint64_t target =
      options.tile_points > 0
          ? static_cast<std::uint64_t>(options.tile_points)
          : static_cast<std::uint64_t>(std::min(kMaximumTilePoints, static_cast<double>(options.memory_budget) /
                                                                        (kWholeModellingBytesPerPoint * static_cast<double>(threads))));
  const double minimum_width = std::max(4.0 * options.margin, 1.0);
  return TileLayout::split_by_count(cells, cell, target, static_cast<std::int64_t>(std::ceil(minimum_width / cell - 1e-9)));
}

/// The pieces of one tile's extraction: every shape element holding core points (columns below
/// `core_count`), in the file's frame (`corner` added back).
std::vector<TilePiece> pieces_of_tile(const Eigen::Matrix3Xd& local, std::uint64_t core_count, const Eigen::Vector3d& corner,
                                      const ExtractionResult& extraction,
                                      const std::vector<detail::ShapeParameters>& parameters, std::size_t sample_points) {
  std::vector<TilePiece> pieces;
  for (std::size_t e = 0; e < extraction.elements.size(); ++e) {
    const Element& element = extraction.elements[e];
    if (element.detected_type == QuadricType::Invalid) continue;  // tori: not quadrics
    std::vector<std::uint32_t> core;
    for (const std::uint32_t index : element.point_indices)
      if (index < core_count) core.push_back(index);
    if (core.empty()) continue;  // the neighbour owns it
    TilePiece piece;
    piece.element_class = element.element_class;
    piece.type = element.detected_type;
    piece.axis = parameters[e].axis;
    piece.point = parameters[e].point + corner;
    piece.size = parameters[e].size;
    piece.point_count = core.size();
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const std::uint32_t index : core) mean += local.col(index);
    mean /= static_cast<double>(core.size());
    for (const std::uint32_t index : core) {
      const Eigen::Vector3d d = local.col(index) - mean;
      piece.scatter.noalias() += d * d.transpose();
    }
    piece.mean = mean + corner;
    const std::size_t cap = std::max<std::size_t>(1, sample_points);
    const std::size_t stride = (core.size() + cap - 1) / cap;
    piece.sample.resize(3, static_cast<Eigen::Index>((core.size() + stride - 1) / stride));
    for (Eigen::Index k = 0; k < piece.sample.cols(); ++k)
      piece.sample.col(k) = local.col(core[static_cast<std::size_t>(k) * stride]) + corner;
    pieces.push_back(std::move(piece));
  }
  return pieces;
}

/// Admits work while the bytes it announces fit the budget (one item is always admitted).
class MemoryGate {
 public:
  explicit MemoryGate(std::size_t budget) : budget_(budget) {}
  void enter(std::size_t bytes) {
    std::unique_lock<std::mutex> lock(mutex_);
    released_.wait(lock, [&] { return in_use_ == 0 || in_use_ + bytes <= budget_; });
    in_use_ += bytes;
  }
  void leave(std::size_t bytes) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      in_use_ -= bytes;
    }
    released_.notify_all();
  }

 private:
  std::size_t budget_, in_use_ = 0;
  std::mutex mutex_;
  std::condition_variable released_;
};

/// Statistical pose (geometry/quadric_record.h) of points given by their count, mean and scatter:
/// statistical_pose of six points mean +- sqrt(3 lambda_k) v_k, which have that mean and covariance.
StatisticalPose statistical_pose_of_moments(const Eigen::Vector3d& mean, const Eigen::Matrix3d& scatter, double count) {
  const detail::Principal principal = detail::principal_axes(scatter / std::max(1.0, count));
  Eigen::Matrix3Xd six(3, 6);
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d offset = std::sqrt(3.0 * principal.values(k)) * principal.vectors.col(k);
    six.col(2 * k) = mean + offset;
    six.col(2 * k + 1) = mean - offset;
  }
  return statistical_pose(six);
}

/// One primitive after the merge.
struct MergedPrimitive {
  ElementClass element_class = ElementClass::Plane;
  QuadricType type = QuadricType::Invalid;
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  double count = 0.0;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  std::vector<Eigen::Vector3d> sample;
};

/// Adds the moments of (count b, mean b, scatter b) to a (Chan et al.'s pairwise update).
void add_moments(MergedPrimitive& a, double count_b, const Eigen::Vector3d& mean_b, const Eigen::Matrix3d& scatter_b) {
  const double total = a.count + count_b;
  if (!(total > 0.0)) return;
  const Eigen::Vector3d delta = mean_b - a.mean;
  a.scatter += scatter_b + delta * delta.transpose() * (a.count * count_b / total);
  a.mean += delta * (count_b / total);
  a.count = total;
}

ElementClass class_of_type(QuadricType type) {
  switch (type) {
    case QuadricType::CircularCylinder: return ElementClass::Cylinder;
    case QuadricType::Sphere: return ElementClass::Sphere;
    case QuadricType::CircularCone: return ElementClass::Cone;
    default: return ElementClass::Plane;
  }
}

}  // namespace

PartialModel model_tile_group(PointChunkSource& source, const ExtractionOptions& extraction, const TilingOptions& options) {
  if (!extraction.static_scan)
    throw Error("tiled modelling: the extraction must be a static scan's (--preset monument); LiDAR scans are modelled whole");
  if (options.groups < 1 || options.group < 0 || options.group >= options.groups)
    throw Error("tiled modelling: tile group " + std::to_string(options.group + 1) + " of " + std::to_string(options.groups) +
                " does not exist");
  if (!(options.margin >= 0.0) || !std::isfinite(options.margin)) throw Error("tiled modelling: the margin must be >= 0 m");
  if (!(options.tile_size >= 0.0) || !std::isfinite(options.tile_size))
    throw Error("--tile-size: expected a tile edge > 0 m (0: sized from the memory budget)");
  if (options.memory_budget == 0) throw Error("--memory-budget: expected a positive number of bytes");
  const int threads = options.threads > 0 ? options.threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  PartialModel part;
  part.group = options.group;
  part.groups = options.groups;
  part.margin = options.margin;
  if (options.tile_size > 0.0 && options.tile_size <= 2.0 * options.margin)
    throw Error("--tile-size: a tile of " + std::to_string(options.tile_size) + " m must be wider than twice the margin (" +
                std::to_string(options.margin) + " m)");
  auto start = Clock::now();
  const TileLayout layout =
      options.tile_size > 0.0 ? TileLayout::squares(options.tile_size) : layout_for_budget(source, options, threads);
  if (options.tile_size <= 0.0) part.timings_ms["counting"] = detail::elapsed_ms(start);
  part.tile_size = layout.cell();
  part.tile_points = layout.target();

  // Pass 1: binning.
  TemporaryFolder folder(options.temporary_parent);
  TileBinner binner(folder.path(), layout, options.margin, options.group, options.groups);
  start = Clock::now();
  Eigen::Matrix3Xd chunk;
  source.rewind();
  std::size_t binned = 0;
  while (source.next_chunk(chunk, kChunkPoints)) {
    for (Eigen::Index i = 0; i < chunk.cols(); ++i)
      if (chunk.col(i).allFinite()) binner.add(chunk.col(i));
    binned += static_cast<std::size_t>(chunk.cols());
    if (options.progress) options.progress({1, binned, 0, 0, 0, seconds_since(start)});
  }
  binner.flush();
  std::vector<std::uint64_t> tiles;
  for (const auto& [key, counts] : binner.counts()) {
    part.survey_points += counts.core;
    if (counts.core > 0 && binner.in_group(key)) {
      tiles.push_back(key);
      part.group_points += counts.core;
      part.largest_tile = std::max(part.largest_tile, counts.core);
    }
  }
  part.tiles = tiles.size();
  part.timings_ms["binning"] = detail::elapsed_ms(start);

  // Pass 2: each tile with its margin, as many at once as the threads and the budget allow.
  start = Clock::now();
  std::vector<std::vector<TilePiece>> tile_pieces(tiles.size());
  MemoryGate gate(options.memory_budget);
  std::mutex progress_mutex;
  std::size_t tiles_done = 0, points_done = 0;
  std::exception_ptr failure;
  std::mutex failure_mutex;
  // One tile with its margin (read from its files, extracted, its pieces kept); a failure is kept
  // for the caller and stops the tiles not yet begun.
  const auto model_tile = [&](std::size_t t) {
    {
      std::lock_guard<std::mutex> lock(failure_mutex);
      if (failure) return;
    }
    try {
      const std::uint64_t key = tiles[t];
      const TileCounts counts = binner.counts().at(key);
      const std::size_t total = static_cast<std::size_t>(counts.core + counts.margin);
      const std::size_t bytes = static_cast<std::size_t>(static_cast<double>(total) * kWholeModellingBytesPerPoint);
      gate.enter(bytes);
      struct Leave {
        MemoryGate& gate;
        std::size_t bytes;
        ~Leave() { gate.leave(bytes); }
      } leave{gate, bytes};
      // Modelled relative to the tile's corner (georeferenced coordinates keep their precision).
      const Eigen::Vector3d corner = layout.corner(key);
      Eigen::Matrix3Xd local(3, static_cast<Eigen::Index>(total));
      read_tile_file(binner.file(key, true), counts.core, Eigen::Vector3d::Zero(), local, 0);
      read_tile_file(binner.file(key, false), counts.margin, Eigen::Vector3d::Zero(), local,
                     static_cast<Eigen::Index>(counts.core));
      PointCloud cloud;
      cloud.positions = local.cast<float>();
      ExtractionOptions tile_extraction = extraction;
      tile_extraction.sensor_origin = extraction.sensor_origin - corner;
      std::vector<detail::ShapeParameters> parameters;
      // Isolated: while the extraction's own parallel loops (the normals) wait, this thread must
      // not take up another tile, or tiles pile up on its stack beyond `threads` and the memory
      // held grows with the number of tiles the survey has.
      ExtractionResult result;
      tbb::this_task_arena::isolate(
          [&] { result = detail::extract_elements_of_points(local, cloud, tile_extraction, {}, &parameters); });
      if (parameters.size() != result.elements.size())
        throw Error("tiles: shape parameters missing for tile (" + std::to_string(tile_x(key)) + ", " +
                    std::to_string(tile_y(key)) + ")");
      tile_pieces[t] = pieces_of_tile(local, counts.core, corner, result, parameters, options.sample_points);
      std::lock_guard<std::mutex> lock(progress_mutex);
      ++tiles_done;
      points_done += counts.core;
      if (options.progress)
        options.progress({2, points_done, static_cast<std::size_t>(part.group_points), tiles_done, tiles.size(),
                          seconds_since(start)});
    } catch (...) {
      std::lock_guard<std::mutex> lock(failure_mutex);
      if (!failure) failure = std::current_exception();
    }
  };
  // Largest tiles first (longest processing time first): a large tile started last would run on
  // one thread while the others idle.
  std::vector<std::size_t> order(tiles.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const TileCounts& x = binner.counts().at(tiles[a]);
    const TileCounts& y = binner.counts().at(tiles[b]);
    return x.core + x.margin > y.core + y.margin;
  });
  std::atomic<std::size_t> next_tile{0};
  tbb::task_arena arena(threads);
  arena.execute([&] {
    tbb::task_group workers;
    for (int worker = 0; worker < threads; ++worker)
      workers.run([&] {
        for (std::size_t k = next_tile++; k < order.size(); k = next_tile++) model_tile(order[k]);
      });
    workers.wait();
  });
  if (failure) std::rethrow_exception(failure);
  part.timings_ms["modelling"] = detail::elapsed_ms(start);
  for (auto& pieces : tile_pieces)
    for (TilePiece& piece : pieces) part.pieces.push_back(std::move(piece));
  return part;
}

ModellingResult merge_partial_models(const std::vector<PartialModel>& parts, const ExtractionOptions& extraction,
                                     const ModellingOptions& modelling, const TilingOptions& options) {
  const auto start = Clock::now();
  if (parts.empty()) throw Error("model merge: no partial model given");
  const int groups = parts.front().groups;
  std::vector<int> seen(static_cast<std::size_t>(std::max(1, groups)), 0);
  for (const PartialModel& part : parts) {
    if (part.groups != groups || part.group < 0 || part.group >= groups)
      throw Error("model merge: parts of different splits (" + std::to_string(part.group + 1) + "/" +
                  std::to_string(part.groups) + " beside n = " + std::to_string(groups) + ")");
    if (part.tile_size != parts.front().tile_size || part.margin != parts.front().margin ||
        part.tile_points != parts.front().tile_points)
      throw Error("model merge: parts of different tilings (tile or grid cell " + std::to_string(part.tile_size) + " m vs " +
                  std::to_string(parts.front().tile_size) + " m, margin " + std::to_string(part.margin) + " m vs " +
                  std::to_string(parts.front().margin) + " m, at most " + std::to_string(part.tile_points) + " vs " +
                  std::to_string(parts.front().tile_points) + " points a tile)");
    if (part.survey_points != parts.front().survey_points)
      throw Error("model merge: parts of different surveys (" + std::to_string(part.survey_points) + " vs " +
                  std::to_string(parts.front().survey_points) + " points)");
    if (seen[static_cast<std::size_t>(part.group)]++ > 0)
      throw Error("model merge: part " + std::to_string(part.group + 1) + "/" + std::to_string(groups) + " given twice");
  }
  for (int g = 0; g < groups; ++g)
    if (seen[static_cast<std::size_t>(g)] == 0)
      throw Error("model merge: part " + std::to_string(g + 1) + "/" + std::to_string(groups) + " is missing");

  // Every piece, in an order that does not depend on the split.
  std::vector<const TilePiece*> pieces;
  for (const PartialModel& part : parts)
    for (const TilePiece& piece : part.pieces) pieces.push_back(&piece);
  std::sort(pieces.begin(), pieces.end(), [](const TilePiece* a, const TilePiece* b) {
    if (a->point_count != b->point_count) return a->point_count > b->point_count;
    if (a->type != b->type) return a->type < b->type;
    return std::lexicographical_compare(a->mean.data(), a->mean.data() + 3, b->mean.data(), b->mean.data() + 3);
  });
  // The merge and the fits run relative to a whole-metre origin (georeferenced coordinates).
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  if (!pieces.empty()) {
    origin = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    for (const TilePiece* piece : pieces) origin = origin.cwiseMin(piece->mean);
    origin = origin.array().floor();
  }
  std::vector<detail::ShapePiece> shape_pieces(pieces.size());
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    detail::ShapePiece& shape = shape_pieces[i];
    shape.type = pieces[i]->type;
    shape.axis = pieces[i]->axis;
    shape.point = pieces[i]->point - origin;
    shape.size = pieces[i]->size;
    shape.points = pieces[i]->sample.colwise() - origin;
    shape.weight = static_cast<double>(pieces[i]->point_count);
  }
  const std::vector<int> joined = detail::merge_shape_pieces(shape_pieces, extraction.shapes, extraction.up);
  std::vector<int> primitive_of_piece(pieces.size(), -1);
  std::vector<MergedPrimitive> primitives;
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    if (joined[i] < 0) continue;  // dissolved: larger primitives explain it
    const std::size_t holder = static_cast<std::size_t>(joined[i]);
    if (primitive_of_piece[holder] < 0) {
      primitive_of_piece[holder] = static_cast<int>(primitives.size());
      primitives.emplace_back();
      primitives.back().type = pieces[holder]->type;
      primitives.back().axis = shape_pieces[holder].axis;
      primitives.back().element_class = class_of_type(pieces[holder]->type);
    }
    MergedPrimitive& primitive = primitives[static_cast<std::size_t>(primitive_of_piece[holder])];
    add_moments(primitive, static_cast<double>(pieces[i]->point_count), pieces[i]->mean - origin, pieces[i]->scatter);
    for (Eigen::Index k = 0; k < shape_pieces[i].points.cols(); ++k) primitive.sample.push_back(shape_pieces[i].points.col(k));
  }

  // A piece a tile found mostly in its margin that joined no neighbour's piece can be left with
  // fewer points than the smallest shape Efficient RANSAC reports (min_points, counted on the
  // simplified cloud, so never more than the points): it is not a primitive of the survey.
  primitives.erase(std::remove_if(primitives.begin(), primitives.end(),
                                  [&](const MergedPrimitive& primitive) {
                                    return primitive.count < static_cast<double>(extraction.shapes.minimum_points);
                                  }),
                   primitives.end());

  // The ground: the lowest of the large near-horizontal planes, as detect_shapes marks it.
  const Eigen::Vector3d up = extraction.up.normalized();
  const double cos_ten_degrees = std::cos(10.0 * kPi / 180.0);
  double largest = 0.0;
  for (const MergedPrimitive& primitive : primitives)
    if (primitive.type == QuadricType::Plane && std::abs(primitive.axis.dot(up)) >= cos_ten_degrees)
      largest = std::max(largest, primitive.count);
  int ground = -1;
  double ground_height = std::numeric_limits<double>::infinity();
  if (extraction.shapes.mark_ground)
    for (std::size_t p = 0; p < primitives.size(); ++p) {
      const MergedPrimitive& primitive = primitives[p];
      if (primitive.type != QuadricType::Plane || std::abs(primitive.axis.dot(up)) < cos_ten_degrees ||
          primitive.count * 10.0 < largest)
        continue;
      if (up.dot(primitive.mean) < ground_height) ground_height = up.dot(primitive.mean), ground = static_cast<int>(p);
    }

  ModellingResult result;
  SceneModel& model = result.model;
  if (ground >= 0) {
    MergedPrimitive& primitive = primitives[static_cast<std::size_t>(ground)];
    primitive.element_class = ElementClass::Ground;
    Eigen::Vector3d normal = detail::principal_axes(primitive.scatter).vectors.col(0);
    if (normal.dot(up) < 0.0) normal = -normal;
    model.has_ground = true;
    model.ground_normal = normal;
    model.ground_offset = -normal.dot(primitive.mean);
  }

  // One fit per primitive on an even sample of its points (ModellingOptions::maximum_fit_points,
  // as model_elements), its statistical pose from all of its points' moments (paper Eq. (full attributes)).
  const auto fit_start = Clock::now();
  const std::unique_ptr<QuadricFitter> fitter = make_quadric_fitter(modelling.fitter, FitEvaluationOptions{ResidualEvaluation::Skip});
  struct Fitted {
    bool ok = false;
    QuadricRecord record;
    QuadricType type = QuadricType::Invalid;
    double size = 0.0;
  };
  std::vector<Fitted> fitted(primitives.size());
  tbb::parallel_for(std::size_t(0), primitives.size(), [&](std::size_t p) {
    const MergedPrimitive& primitive = primitives[p];
    if (primitive.count < static_cast<double>(minimum_points_for_type(primitive.type)) || primitive.sample.empty()) return;
    const std::size_t cap = modelling.maximum_fit_points > 0 ? static_cast<std::size_t>(modelling.maximum_fit_points)
                                                             : primitive.sample.size();
    const std::size_t stride = (primitive.sample.size() + cap - 1) / cap;
    Eigen::Matrix3Xd sample(3, static_cast<Eigen::Index>((primitive.sample.size() + stride - 1) / stride));
    for (Eigen::Index k = 0; k < sample.cols(); ++k) sample.col(k) = primitive.sample[static_cast<std::size_t>(k) * stride];
    const QuadricFit fit = fitter->fit(sample, Eigen::Matrix3Xd(), primitive.type);
    if (fit.status != FitStatus::Ok || !fit.quadric.matrix().allFinite()) return;
    Fitted& out = fitted[p];
    out.record = make_quadric_record(static_cast<std::uint32_t>(primitive.element_class), fit.quadric,
                                     statistical_pose_of_moments(primitive.mean, primitive.scatter, primitive.count));
    bool finite = true;
    for (const double value : out.record.to_array()) finite = finite && std::isfinite(value);
    if (!finite) return;
    out.type = fit.type;
    out.size = record_size(out.record, fit.type);
    out.ok = true;
  });
  // Records grouped by class, largest V_a first, as model_elements orders them.
  std::map<std::uint32_t, std::vector<std::size_t>> by_class;
  for (std::size_t p = 0; p < primitives.size(); ++p) {
    if (fitted[p].ok)
      by_class[static_cast<std::uint32_t>(primitives[p].element_class)].push_back(p), ++result.elements_fitted;
    else
      ++result.elements_failed;
  }
  for (auto& [label, members] : by_class) {
    std::stable_sort(members.begin(), members.end(), [&](std::size_t a, std::size_t b) { return fitted[a].size > fitted[b].size; });
    for (const std::size_t p : members) {
      model.records.push_back(fitted[p].record);
      model.types.push_back(fitted[p].type);
      model.element_point_counts.push_back(static_cast<std::uint32_t>(std::min(primitives[p].count, 4294967295.0)));
    }
  }
  model.augmented_begin = model.records.size();
  for (const PartialModel& part : parts) model.source_point_count = static_cast<std::size_t>(part.survey_points);
  model.timings_ms["fitting"] = detail::elapsed_ms(fit_start);
  model = translated(std::move(model), origin);
  model.timings_ms["merge"] = detail::elapsed_ms(start);
  if (model.augmented_begin == 0) {
    result.status = ModellingStatus::Empty;
    result.message = pieces.empty() ? "no shape was found in any tile" : "no primitive could be fitted";
  }
  if (result.elements_failed > 0)
    result.message += (result.message.empty() ? "" : "; ") + std::to_string(result.elements_failed) + " primitive(s) not fitted";
  (void)options;
  return result;
}

ModellingResult model_tiled(PointChunkSource& source, const ExtractionOptions& extraction, const ModellingOptions& modelling,
                            const TilingOptions& options) {
  const auto start = Clock::now();
  TilingOptions whole = options;
  whole.group = 0;
  whole.groups = 1;
  const PartialModel part = model_tile_group(source, extraction, whole);
  const double tiles_ms = detail::elapsed_ms(start);
  if (options.progress) options.progress({3, 0, 0, part.tiles, part.tiles, 0.0});
  ModellingResult result = merge_partial_models({part}, extraction, modelling, options);
  result.model.timings_ms["tiles"] = tiles_ms;
  result.model.timings_ms.insert(part.timings_ms.begin(), part.timings_ms.end());
  result.model.timings_ms["total"] = detail::elapsed_ms(start);
  return result;
}

namespace {

constexpr char kPartialMagic[8] = {'Q', 'D', 'X', 'T', 'I', 'L', 'E', 'S'};
constexpr std::uint32_t kPartialVersion = 2;

template <typename T>
void put(std::ostream& out, const T& value) {
  out.write(reinterpret_cast<const char*>(&value), sizeof(T));
}

/// Reads binary values of a partial model, naming the file and the field on a short read.
class PartialReader {
 public:
  PartialReader(std::istream& in, std::string path) : in_(in), path_(std::move(path)) {}
  template <typename T>
  T get(const char* field) {
    T value;
    in_.read(reinterpret_cast<char*>(&value), sizeof(T));
    if (!in_) throw Error("partial model " + path_ + ": truncated at " + field);
    return value;
  }
  double finite(const char* field) {
    const double value = get<double>(field);
    if (!std::isfinite(value)) throw Error("partial model " + path_ + ": " + field + " is not finite");
    return value;
  }
  const std::string& path() const { return path_; }

 private:
  std::istream& in_;
  std::string path_;
};

}  // namespace

namespace {

void write_partial_stream(std::ostream& out, const PartialModel& part) {
  {
    out.write(kPartialMagic, sizeof kPartialMagic);
    put(out, kPartialVersion);
    put(out, static_cast<std::int32_t>(part.group));
    put(out, static_cast<std::int32_t>(part.groups));
    put(out, part.tile_size);
    put(out, part.margin);
    put(out, part.survey_points);
    put(out, part.group_points);
    put(out, part.tiles);
    put(out, part.tile_points);
    put(out, part.largest_tile);
    put(out, static_cast<std::uint64_t>(part.pieces.size()));
    for (const TilePiece& piece : part.pieces) {
      put(out, static_cast<std::uint32_t>(piece.element_class));
      put(out, static_cast<std::uint8_t>(piece.type));
      for (int k = 0; k < 3; ++k) put(out, piece.axis(k));
      for (int k = 0; k < 3; ++k) put(out, piece.point(k));
      put(out, piece.size);
      put(out, piece.point_count);
      for (int k = 0; k < 3; ++k) put(out, piece.mean(k));
      for (int k = 0; k < 9; ++k) put(out, piece.scatter.data()[k]);
      put(out, static_cast<std::uint64_t>(piece.sample.cols()));
      for (Eigen::Index k = 0; k < piece.sample.size(); ++k) put(out, piece.sample.data()[k]);
    }
  }
}

PartialModel read_partial_stream(std::istream& in, const std::string& path) {
  PartialReader reader(in, path);
  char magic[8];
  in.read(magic, sizeof magic);
  if (!in || std::memcmp(magic, kPartialMagic, sizeof magic) != 0)
    throw Error("partial model " + path + ": not a partial model (expected the magic QDXTILES of `quadrix model --tile`)");
  const auto version = reader.get<std::uint32_t>("version");
  if (version != kPartialVersion)
    throw Error("partial model " + path + ": version " + std::to_string(version) + " (expected " +
                std::to_string(kPartialVersion) + ")");
  PartialModel part;
  part.group = reader.get<std::int32_t>("group");
  part.groups = reader.get<std::int32_t>("groups");
  if (part.groups < 1 || part.group < 0 || part.group >= part.groups)
    throw Error("partial model " + path + ": group " + std::to_string(part.group + 1) + " of " + std::to_string(part.groups) +
                " (expected 1 <= i <= n)");
  part.tile_size = reader.finite("tile_size");
  part.margin = reader.finite("margin");
  if (!(part.tile_size > 0.0) || part.margin < 0.0) throw Error("partial model " + path + ": tile_size must be > 0 and margin >= 0");
  part.survey_points = reader.get<std::uint64_t>("survey_points");
  part.group_points = reader.get<std::uint64_t>("group_points");
  part.tiles = reader.get<std::uint64_t>("tiles");
  part.tile_points = reader.get<std::uint64_t>("tile_points");
  part.largest_tile = reader.get<std::uint64_t>("largest_tile");
  const auto count = reader.get<std::uint64_t>("piece count");
  for (std::uint64_t p = 0; p < count; ++p) {
    TilePiece piece;
    const auto label = reader.get<std::uint32_t>("piece class");
    piece.element_class = element_class_from_label(label);
    const auto type = reader.get<std::uint8_t>("piece type");
    piece.type = static_cast<QuadricType>(type);
    if (piece.type != QuadricType::Plane && piece.type != QuadricType::CircularCylinder && piece.type != QuadricType::Sphere &&
        piece.type != QuadricType::CircularCone)
      throw Error("partial model " + path + ": piece " + std::to_string(p) + " has type " + std::to_string(type) +
                  " (expected a plane, circular cylinder, sphere or circular cone)");
    for (int k = 0; k < 3; ++k) piece.axis(k) = reader.finite("piece axis");
    for (int k = 0; k < 3; ++k) piece.point(k) = reader.finite("piece point");
    piece.size = reader.finite("piece size");
    piece.point_count = reader.get<std::uint64_t>("piece point count");
    for (int k = 0; k < 3; ++k) piece.mean(k) = reader.finite("piece mean");
    for (int k = 0; k < 9; ++k) piece.scatter.data()[k] = reader.finite("piece scatter");
    const auto samples = reader.get<std::uint64_t>("piece sample count");
    if (samples == 0 || samples > piece.point_count || samples > (std::uint64_t{1} << 26))
      throw Error("partial model " + path + ": piece " + std::to_string(p) + " has " + std::to_string(samples) +
                  " sample points for " + std::to_string(piece.point_count) + " points");
    piece.sample.resize(3, static_cast<Eigen::Index>(samples));
    for (Eigen::Index k = 0; k < piece.sample.size(); ++k) piece.sample.data()[k] = reader.finite("piece sample");
    part.pieces.push_back(std::move(piece));
  }
  if (in.peek() != std::char_traits<char>::eof())
    throw Error("partial model " + path + ": bytes after the last of its " + std::to_string(count) + " pieces");
  return part;
}

}  // namespace

void write_partial_model(const std::string& path, const PartialModel& part) {
  write_file_atomically(path, [&](std::ostream& out) { write_partial_stream(out, part); });
}

PartialModel read_partial_model(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("partial model " + path + ": cannot open");
  return read_partial_stream(in, path);
}

std::string partial_model_to_bytes(const PartialModel& part) {
  std::ostringstream out(std::ios::binary);
  write_partial_stream(out, part);
  return out.str();
}

PartialModel partial_model_from_bytes(const std::string& bytes, const std::string& name) {
  std::istringstream in(bytes, std::ios::binary);
  return read_partial_stream(in, name);
}

}  // namespace quadrix
