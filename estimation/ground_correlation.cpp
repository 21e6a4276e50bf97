// Correlation of the bird's-eye occupancy of two ground-levelled scans over yaw and translation (see
// ground_correlation.h).
#include "estimation/ground_correlation.h"

#include "geometry/constants.h"
#include "geometry/error.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>
#include <utility>

namespace quadrix {

namespace {

constexpr double kFarthest = 1e6;                           // m; levelled points beyond are dropped
constexpr std::size_t kMaximumCells = std::size_t(1) << 26;  // 64 MB of target grid: a scan 8 km across at 1 m

// A scan seen from above: its points in the band above its ground, in a frame whose z is the
// ground normal, projected onto the ground.
struct LevelledScan {
  Eigen::Matrix3d levelling = Eigen::Matrix3d::Identity();  // rotation taking the ground normal to +z
  double ground_offset = 0.0;                               // d of n . x + d = 0
  std::vector<Eigen::Vector2d> points;                      // (x, y) of the levelled points in the band
};

LevelledScan level(const PointCloud& cloud, const Eigen::Vector4d& ground, const GroundCorrelationOptions& options) {
  LevelledScan scan;
  const Eigen::Vector3d normal = ground.head<3>().normalized();
  scan.levelling = Eigen::Quaterniond::FromTwoVectors(normal, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  scan.ground_offset = ground(3) / ground.head<3>().norm();
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d point = cloud.point(i);
    if (!point.allFinite()) continue;
    const double height = normal.dot(point) + scan.ground_offset;
    if (height < options.minimum_height || height > options.maximum_height) continue;
    const Eigen::Vector2d levelled = (scan.levelling * point).head<2>();
    // Farther than any scanner reaches: a stray value, whose cell index would overflow an int.
    if (levelled.cwiseAbs().maxCoeff() > kFarthest) continue;
    scan.points.push_back(levelled);
  }
  return scan;
}

// The integer cell of a levelled point.
Eigen::Vector2i cell_of(const Eigen::Vector2d& point, double cell) {
  return (point / cell).array().floor().cast<int>();
}

// The cells the points occupy, each once. (Keeping only cells with two or more points, against
// stray returns, changed no result on the tuning set's hard bin, clean or with 10% outliers.)
std::vector<Eigen::Vector2i> occupied_cells(const std::vector<Eigen::Vector2d>& points, double cell) {
  std::vector<std::pair<int, int>> cells;
  cells.reserve(points.size());
  for (const Eigen::Vector2d& point : points) {
    const Eigen::Vector2i index = cell_of(point, cell);
    cells.emplace_back(index.x(), index.y());
  }
  std::sort(cells.begin(), cells.end());
  cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
  std::vector<Eigen::Vector2i> kept;
  kept.reserve(cells.size());
  for (const auto& [x, y] : cells) kept.emplace_back(x, y);
  return kept;
}

// Centres of the cells.
std::vector<Eigen::Vector2d> centres_of(const std::vector<Eigen::Vector2i>& cells, double cell) {
  std::vector<Eigen::Vector2d> centres;
  centres.reserve(cells.size());
  for (const Eigen::Vector2i& index : cells) centres.push_back((index.cast<double>().array() + 0.5) * cell);
  return centres;
}

// The target's occupied cells as a dense byte grid over their box (a byte, not a bit, so that a
// row of it adds to a row of scores in one vectorised loop).
struct OccupancyGrid {
  double cell = 1.0;
  Eigen::Vector2i low = Eigen::Vector2i::Zero();  // integer cell of the grid's first row and column
  int width = 0, height = 0;                       // cells along x and y
  std::vector<std::uint8_t> occupied;              // width x height, row-major in x

  OccupancyGrid(const std::vector<Eigen::Vector2i>& cells, double cell_edge) : cell(cell_edge) {
    if (cells.empty()) return;
    Eigen::Vector2i high = cells.front();
    low = cells.front();
    for (const Eigen::Vector2i& index : cells) {
      low = low.cwiseMin(index);
      high = high.cwiseMax(index);
    }
    const std::size_t size = (static_cast<std::size_t>(high.x() - low.x()) + 1) * (static_cast<std::size_t>(high.y() - low.y()) + 1);
    if (size > kMaximumCells) return;  // too large to hold: an empty grid, which no pose lands on
    width = high.x() - low.x() + 1;
    height = high.y() - low.y() + 1;
    occupied.assign(size, 0);
    for (const Eigen::Vector2i& index : cells) occupied[offset(index - low)] = 1;
  }
  std::size_t offset(const Eigen::Vector2i& local) const {
    return static_cast<std::size_t>(local.x()) * static_cast<std::size_t>(height) + static_cast<std::size_t>(local.y());
  }
  bool holds(const Eigen::Vector2d& point) const {
    const Eigen::Vector2i local = cell_of(point, cell) - low;
    return local.x() >= 0 && local.y() >= 0 && local.x() < width && local.y() < height && occupied[offset(local)] != 0;
  }
};

Eigen::Matrix2d yaw_rotation(double degrees) {
  const double radians = degrees * kPi / 180.0;
  Eigen::Matrix2d rotation;
  rotation << std::cos(radians), -std::sin(radians), std::sin(radians), std::cos(radians);
  return rotation;
}

double yaw_difference(double a, double b) {
  return std::abs(std::remainder(a - b, 360.0));
}

// A scored pose in the levelled frames: yaw and translation along the ground.
struct PlanarPose {
  double score = 0.0;
  double yaw_degrees = 0.0;
  Eigen::Vector2d translation = Eigen::Vector2d::Zero();
};

// Keeps the best poses that are not within both separations of a better one kept before, at most `count`.
std::vector<PlanarPose> keep_distinct(std::vector<PlanarPose> poses, std::size_t count, const GroundCorrelationOptions& options) {
  std::stable_sort(poses.begin(), poses.end(), [](const PlanarPose& a, const PlanarPose& b) { return a.score > b.score; });
  std::vector<PlanarPose> kept;
  for (const PlanarPose& pose : poses) {
    if (kept.size() >= count || pose.score <= 0.0) break;
    const bool near_better = std::any_of(kept.begin(), kept.end(), [&](const PlanarPose& other) {
      return (pose.translation - other.translation).norm() < options.separation &&
             yaw_difference(pose.yaw_degrees, other.yaw_degrees) < options.separation_degrees;
    });
    if (!near_better) kept.push_back(pose);
  }
  return kept;
}

// First pass: every yaw, and every translation that is a whole number of coarse cells within
// reach. Such a translation moves every rotated source cell by whole target cells, so the scores of
// all translations are the sum, over the source cells, of the target grid's window at each cell: a
// row-by-row addition instead of a lookup per cell and translation.
std::vector<PlanarPose> coarse_pass(const std::vector<Eigen::Vector2d>& source_centres, const OccupancyGrid& target,
                                    const GroundCorrelationOptions& options, std::size_t count) {
  const int steps = static_cast<int>(std::floor(options.reach / target.cell + 1e-9));
  const int side = 2 * steps + 1;
  const int yaws = std::max(1, static_cast<int>(std::lround(360.0 / options.yaw_step_degrees)));
  std::vector<std::vector<PlanarPose>> best_per_yaw(static_cast<std::size_t>(yaws));
  tbb::parallel_for(0, yaws, [&](int k) {
    const double yaw = -180.0 + k * 360.0 / yaws;
    const Eigen::Matrix2d rotation = yaw_rotation(yaw);
    // The rotated source cells, each counted once.
    std::vector<std::pair<int, int>> cells;
    cells.reserve(source_centres.size());
    for (const Eigen::Vector2d& centre : source_centres) {
      const Eigen::Vector2i index = cell_of(rotation * centre, target.cell) - target.low;
      cells.emplace_back(index.x(), index.y());
    }
    std::sort(cells.begin(), cells.end());
    cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
    // scores(i, j): source cells landing on target cells under the translation ((i, j) - steps) cells.
    std::vector<std::uint32_t> scores(static_cast<std::size_t>(side) * static_cast<std::size_t>(side), 0);
    for (const auto& [x, y] : cells) {
      const int first_i = std::max(0, -(x - steps)), last_i = std::min(side, target.width - (x - steps));
      const int first_j = std::max(0, -(y - steps)), last_j = std::min(side, target.height - (y - steps));
      if (first_j >= last_j) continue;
      for (int i = first_i; i < last_i; ++i) {
        // The target's cells (x - steps + i, y - steps + j) for j from first_j on, all inside the grid.
        const std::uint8_t* row = &target.occupied[target.offset(Eigen::Vector2i(x - steps + i, y - steps + first_j))];
        std::uint32_t* sum = &scores[static_cast<std::size_t>(i) * static_cast<std::size_t>(side) + static_cast<std::size_t>(first_j)];
        for (int j = 0; j < last_j - first_j; ++j) sum[j] += row[j];
      }
    }
    std::vector<PlanarPose> poses;
    for (int i = 0; i < side; ++i)
      for (int j = 0; j < side; ++j) {
        const Eigen::Vector2d translation = Eigen::Vector2d(i - steps, j - steps) * target.cell;
        const std::uint32_t score = scores[static_cast<std::size_t>(i) * static_cast<std::size_t>(side) + static_cast<std::size_t>(j)];
        if (score > 0 && translation.norm() <= options.reach) poses.push_back({static_cast<double>(score), yaw, translation});
      }
    best_per_yaw[static_cast<std::size_t>(k)] = keep_distinct(std::move(poses), count, options);
  });
  std::vector<PlanarPose> all;
  for (auto& poses : best_per_yaw) all.insert(all.end(), poses.begin(), poses.end());
  return keep_distinct(std::move(all), count, options);
}

// Second pass around one coarse pose: yaws a quarter step apart within half a step, translations
// half a fine cell apart within one coarse cell, on the fine grids. Scores become shares of the
// source's fine cells.
PlanarPose refine(const PlanarPose& coarse, const std::vector<Eigen::Vector2d>& source_centres, const OccupancyGrid& target,
                  const GroundCorrelationOptions& options) {
  PlanarPose best = coarse;
  best.score = -1.0;
  const double translation_step = 0.5 * options.fine_cell;
  const int reach = static_cast<int>(std::ceil(options.coarse_cell / translation_step));
  for (int y = -2; y <= 2; ++y) {
    const double yaw = coarse.yaw_degrees + y * 0.25 * options.yaw_step_degrees;
    const Eigen::Matrix2d rotation = yaw_rotation(yaw);
    std::vector<Eigen::Vector2d> rotated;
    rotated.reserve(source_centres.size());
    for (const Eigen::Vector2d& centre : source_centres) rotated.push_back(rotation * centre);
    for (int i = -reach; i <= reach; ++i)
      for (int j = -reach; j <= reach; ++j) {
        const Eigen::Vector2d translation = coarse.translation + Eigen::Vector2d(i, j) * translation_step;
        std::size_t hits = 0;
        for (const Eigen::Vector2d& point : rotated) hits += target.holds(point + translation);
        const double share = static_cast<double>(hits) / static_cast<double>(source_centres.size());
        if (share > best.score) best = {share, yaw, translation};
      }
  }
  return best;
}

}  // namespace

void validate_ground_correlation_options(const GroundCorrelationOptions& options) {
  const auto fail = [](const std::string& key, const std::string& expected, double value) {
    std::ostringstream message;
    message << "option 'dense_search.correlation." << key << "' must be " << expected << ", got " << value;
    throw Error(message.str());
  };
  if (!(options.reach > 0.0)) fail("reach", "positive", options.reach);
  if (!(options.yaw_step_degrees > 0.0 && options.yaw_step_degrees <= 180.0))
    fail("yaw_step_degrees", "in (0, 180]", options.yaw_step_degrees);
  // Finer than 5 cm is below any scanner's noise, and would put a cell index of a far point beyond an int.
  if (!(options.coarse_cell >= 0.05)) fail("coarse_cell", "at least 0.05", options.coarse_cell);
  if (!(options.fine_cell >= 0.05)) fail("fine_cell", "at least 0.05", options.fine_cell);
  if (!(options.maximum_height > options.minimum_height))
    fail("maximum_height", "above minimum_height " + std::to_string(options.minimum_height), options.maximum_height);
  if (!(options.separation >= 0.0)) fail("separation", "non-negative", options.separation);
  if (!(options.separation_degrees >= 0.0)) fail("separation_degrees", "non-negative", options.separation_degrees);
}

std::vector<GroundPose> correlate_over_ground(const PointCloud& source, const PointCloud& target,
                                              const Eigen::Vector4d& source_ground, const Eigen::Vector4d& target_ground,
                                              const GroundCorrelationOptions& options) {
  validate_ground_correlation_options(options);
  if (options.poses == 0) return {};
  const LevelledScan levelled_source = level(source, source_ground, options);
  const LevelledScan levelled_target = level(target, target_ground, options);
  if (levelled_source.points.empty() || levelled_target.points.empty()) return {};
  // Three times as many coarse poses as asked for go to the second pass, since the finer grid
  // reorders close coarse scores. The truth's rank in a one-pass 1 m correlation (a prototype,
  // docs/registration.md "Correlation over the ground") was first on 88 and within the first 4 on
  // 99 of the tuning set's 100 hard-bin pairs.
  const std::vector<PlanarPose> coarse =
      coarse_pass(centres_of(occupied_cells(levelled_source.points, options.coarse_cell), options.coarse_cell),
                  OccupancyGrid(occupied_cells(levelled_target.points, options.coarse_cell), options.coarse_cell), options,
                  3 * options.poses);
  const std::vector<Eigen::Vector2d> fine_source =
      centres_of(occupied_cells(levelled_source.points, options.fine_cell), options.fine_cell);
  if (fine_source.empty()) return {};
  const OccupancyGrid fine_target(occupied_cells(levelled_target.points, options.fine_cell), options.fine_cell);
  std::vector<PlanarPose> refined(coarse.size());
  tbb::parallel_for(std::size_t(0), coarse.size(),
                    [&](std::size_t k) { refined[k] = refine(coarse[k], fine_source, fine_target, options); });
  std::vector<GroundPose> poses;
  for (const PlanarPose& pose : keep_distinct(std::move(refined), options.poses, options)) {
    // x_target = L_t^-1 (M (L_s x_source)): M turns by the yaw about the levelled z, moves along the
    // ground, and lifts by d_s - d_t, which puts the height above ground n . x + d of every point
    // where it was (the levelled z of a point is n . x).
    Eigen::Isometry3d planar = Eigen::Isometry3d::Identity();
    planar.linear().topLeftCorner<2, 2>() = yaw_rotation(pose.yaw_degrees);
    planar.translation() << pose.translation, levelled_source.ground_offset - levelled_target.ground_offset;
    Eigen::Isometry3d source_levelling = Eigen::Isometry3d::Identity(), target_levelling = Eigen::Isometry3d::Identity();
    source_levelling.linear() = levelled_source.levelling;
    target_levelling.linear() = levelled_target.levelling;
    poses.push_back({target_levelling.inverse() * planar * source_levelling, pose.score, pose.yaw_degrees});
  }
  return poses;
}

}  // namespace quadrix
