// Line extraction (paper §"Quadric Extraction", step 1(c)): RANSAC on each cluster left after
// ground and planes; a line must dominate its cluster, be long enough, and (by default) stand
// roughly upright like a pole. Hypotheses are refined by PCA of their inliers. Before the lines, a
// cluster standing on a narrow upright stem under a round crown is split into the paper's trunk
// (elliptic cylinder) and vegetation (ellipsoid) key objects; a line whose stem is wider than a
// pole's and runs out of the top of the scanner's view is a trunk whose crown was not seen.
#include "fitting/extraction.h"
#include "fitting/extraction_internal.h"
#include "geometry/constants.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

namespace quadrix {
namespace {

constexpr double kRadiansPerDegree = kPi / 180.0;

struct LineModel {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
};

double distance_to_line(const LineModel& line, const Eigen::Vector3d& x) {
  const Eigen::Vector3d d = x - line.point;
  return (d - d.dot(line.direction) * line.direction).norm();
}

}  // namespace

std::vector<Element> extract_lines(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& cluster,
                                   const LineOptions& options, const Eigen::Vector3d& up_axis,
                                   std::vector<std::uint32_t>& remaining) {
  std::vector<Element> lines;
  remaining = cluster;
  const Eigen::Vector3d up = up_axis.normalized();
  const double cos_tilt = std::cos(std::min(options.max_tilt_deg, 90.0) * kRadiansPerDegree);
  // Deterministic per cluster: the seed mixes in the first index, so the result does not depend on
  // the order clusters are processed in (they run in parallel).
  std::mt19937_64 engine(options.seed ^ (cluster.empty() ? 0u : 0x9E3779B97F4A7C15ull * (cluster.front() + 1)));
  for (int line_number = 0; line_number < options.maximum_lines_per_cluster; ++line_number) {
    const std::size_t count = remaining.size();
    if (static_cast<int>(count) < std::max(options.minimum_points, 2)) break;
    std::uniform_int_distribution<std::size_t> pick(0, count - 1);
    LineModel best;
    std::size_t best_inliers = 0;
    for (int iteration = 0; iteration < options.iterations; ++iteration) {
      const std::size_t a = pick(engine), b = pick(engine);
      if (a == b) continue;
      const Eigen::Vector3d pa = points.col(remaining[a]), pb = points.col(remaining[b]);
      const double length = (pb - pa).norm();
      if (length < 1e-6) continue;
      LineModel model{pa, (pb - pa) / length};
      if (std::abs(model.direction.dot(up)) < cos_tilt) continue;
      std::size_t inliers = 0;
      for (const std::uint32_t index : remaining)
        inliers += distance_to_line(model, points.col(index)) <= options.inlier_distance;
      if (inliers > best_inliers) {
        best_inliers = inliers;
        best = model;
      }
    }
    if (static_cast<int>(best_inliers) < options.minimum_points) break;
    // Refine: PCA line of the inliers, then the final inlier set of the refined line.
    for (int refinement = 0; refinement < 2; ++refinement) {
      detail::Moments moments;
      for (const std::uint32_t index : remaining)
        if (distance_to_line(best, points.col(index)) <= options.inlier_distance) moments.add(points.col(index));
      if (moments.count < 2) break;
      const detail::Principal axes = detail::principal_axes(moments.covariance());
      best.point = moments.mean();
      best.direction = axes.vectors.col(2);
    }
    std::vector<std::uint32_t> on_line, off_line;
    double lowest = 1e300, highest = -1e300;
    const double membership = std::max(options.inlier_distance, options.membership_distance);
    for (const std::uint32_t index : remaining) {
      const Eigen::Vector3d x = points.col(index);
      if (distance_to_line(best, x) <= membership) {
        on_line.push_back(index);
        const double s = (x - best.point).dot(best.direction);
        lowest = std::min(lowest, s);
        highest = std::max(highest, s);
      } else {
        off_line.push_back(index);
      }
    }
    const bool upright = std::abs(best.direction.dot(up)) >= cos_tilt;
    const bool dominant = static_cast<double>(on_line.size()) >= options.minimum_inlier_fraction * static_cast<double>(count);
    if (!upright || !dominant || static_cast<int>(on_line.size()) < options.minimum_points ||
        highest - lowest < options.minimum_length)
      break;
    Element line;
    line.element_class = ElementClass::Line;
    line.point_indices = std::move(on_line);
    lines.push_back(std::move(line));
    remaining = std::move(off_line);
  }
  return lines;
}

bool separate_trunk(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& cluster,
                    const TrunkOptions& options, const Eigen::Vector3d& up_axis, std::vector<std::uint32_t>& trunk,
                    std::vector<std::uint32_t>& crown) {
  trunk.clear();
  crown.clear();
  if (static_cast<int>(cluster.size()) < options.minimum_points + options.minimum_crown_points ||
      !(options.slice_height > 0.0))
    return false;
  // Height along the up axis and horizontal coordinates in the plane across it.
  const Eigen::Vector3d up = up_axis.normalized();
  const Eigen::Vector3d across = (std::abs(up.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY()).cross(up).normalized();
  const Eigen::Vector3d across_too = up.cross(across);
  std::vector<double> height(cluster.size());
  std::vector<Eigen::Vector2d> horizontal(cluster.size());
  for (std::size_t i = 0; i < cluster.size(); ++i) {
    const Eigen::Vector3d p = points.col(cluster[i]);
    height[i] = p.dot(up);
    horizontal[i] = Eigen::Vector2d(p.dot(across), p.dot(across_too));
  }
  std::vector<std::size_t> order(cluster.size());
  std::iota(order.begin(), order.end(), std::size_t(0));
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return height[a] < height[b]; });
  // Grow the stem slice by slice from the foot: a slice joins while all its points lie within
  // maximum_radius of the stem's centre line (the mean of the stem so far, else of the slice).
  const double foot = height[order.front()];
  Eigen::Vector2d stem_sum = Eigen::Vector2d::Zero();
  std::size_t stem_count = 0, next = 0;
  double stem_top = foot;
  const double radius_squared = options.maximum_radius * options.maximum_radius;
  while (next < order.size()) {
    const double slice_top = stem_top + options.slice_height;
    std::size_t end = next;
    Eigen::Vector2d slice_sum = Eigen::Vector2d::Zero();
    while (end < order.size() && height[order[end]] < slice_top) slice_sum += horizontal[order[end++]];
    if (end > next) {
      const Eigen::Vector2d centre = stem_count > 0 ? Eigen::Vector2d(stem_sum / static_cast<double>(stem_count))
                                                    : Eigen::Vector2d(slice_sum / static_cast<double>(end - next));
      bool narrow = true;
      for (std::size_t k = next; k < end && narrow; ++k) narrow = (horizontal[order[k]] - centre).squaredNorm() <= radius_squared;
      if (!narrow) break;
      stem_sum += slice_sum;
      stem_count += end - next;
    }
    next = end;
    stem_top = slice_top;
  }
  if (next >= order.size() || stem_top - foot < options.minimum_height || static_cast<int>(stem_count) < options.minimum_points ||
      static_cast<int>(order.size() - next) < options.minimum_crown_points)
    return false;
  // The crown spreads in both horizontal directions (an arm or a sign does not).
  detail::Moments crown_moments;
  for (std::size_t k = next; k < order.size(); ++k)
    crown_moments.add(Eigen::Vector3d(horizontal[order[k]].x(), horizontal[order[k]].y(), 0.0));
  const Eigen::Matrix2d spread = crown_moments.covariance().topLeftCorner<2, 2>();
  const double smaller_variance = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(spread, Eigen::EigenvaluesOnly).eigenvalues()(0);
  if (smaller_variance < options.minimum_crown_spread * options.minimum_crown_spread) return false;
  for (std::size_t k = 0; k < order.size(); ++k) (k < next ? trunk : crown).push_back(cluster[order[k]]);
  std::sort(trunk.begin(), trunk.end());
  std::sort(crown.begin(), crown.end());
  return true;
}

double stem_radius_across_view(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& stem,
                               const TrunkOptions& options, const Eigen::Vector3d& sensor_origin) {
  if (stem.size() < 2 || !(options.slice_height > 0.0)) return -1.0;
  detail::Moments moments;
  for (const std::uint32_t index : stem) moments.add(points.col(index));
  const Eigen::Vector3d centre = moments.mean();
  const Eigen::Vector3d axis = detail::principal_axes(moments.covariance()).vectors.col(2);
  // Across the line of sight: perpendicular to the stem and to the view direction.
  Eigen::Vector3d view = centre - sensor_origin;
  view -= view.dot(axis) * axis;
  if (!(view.norm() > 1e-6)) return -1.0;
  const Eigen::Vector3d across = axis.cross(view).normalized();
  std::vector<std::pair<long, double>> slice_and_offset;
  slice_and_offset.reserve(stem.size());
  for (const std::uint32_t index : stem) {
    const Eigen::Vector3d d = points.col(index) - centre;
    // Clamped before the cast: a slice index beyond a long would be undefined behaviour.
    const double slice = std::clamp(std::floor(d.dot(axis) / options.slice_height), -1e15, 1e15);
    slice_and_offset.emplace_back(static_cast<long>(slice), d.dot(across));
  }
  std::sort(slice_and_offset.begin(), slice_and_offset.end());
  std::vector<double> half_widths;
  for (std::size_t begin = 0; begin < slice_and_offset.size();) {
    std::size_t end = begin;
    double lowest = 1e300, highest = -1e300;
    for (; end < slice_and_offset.size() && slice_and_offset[end].first == slice_and_offset[begin].first; ++end) {
      lowest = std::min(lowest, slice_and_offset[end].second);
      highest = std::max(highest, slice_and_offset[end].second);
    }
    if (static_cast<int>(end - begin) >= options.crownless_slice_points) half_widths.push_back(0.5 * (highest - lowest));
    begin = end;
  }
  // Compared as doubles: a minimum height of 5e18 m asks for more slices than a size_t holds.
  const double needed = std::max(1.0, std::ceil(options.minimum_height / options.slice_height - 1e-9));
  if (!(static_cast<double>(half_widths.size()) >= needed)) return -1.0;
  std::sort(half_widths.begin(), half_widths.end());
  return half_widths[half_widths.size() / 4];
}

bool stem_reaches_top_of_view(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& stem,
                              const std::vector<std::uint32_t>& cloud, const TrunkOptions& options,
                              const Eigen::Vector3d& up_axis, const Eigen::Vector3d& sensor_origin) {
  if (stem.empty()) return false;
  const Eigen::Vector3d up = up_axis.normalized();
  // Horizontal direction of the stem from the sensor, and its azimuth span as the smallest cosine
  // between that direction and any stem point's horizontal direction.
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const std::uint32_t index : stem) centre += points.col(index) - sensor_origin;
  centre -= centre.dot(up) * up;
  if (!(centre.norm() > 1e-9)) return false;
  const Eigen::Vector3d direction = centre.normalized();
  double span_cosine = 1.0, top_tangent = -1e300;
  for (const std::uint32_t index : stem) {
    const Eigen::Vector3d d = points.col(index) - sensor_origin;
    const Eigen::Vector3d horizontal = d - d.dot(up) * up;
    const double length = horizontal.norm();
    if (!(length > 1e-9)) return false;  // a stem through the sensor has no azimuth
    span_cosine = std::min(span_cosine, horizontal.dot(direction) / length);
    top_tangent = std::max(top_tangent, d.dot(up) / length);
  }
  // Elevation angles compared through their tangents (tan is increasing below 90 degrees).
  // Elevations are capped just below 90 degrees, where the tangent stays finite.
  const double tolerance = options.crownless_top_tolerance_deg * kRadiansPerDegree;
  const double limit_tangent = std::tan(std::min(std::atan(top_tangent) + tolerance, 0.5 * kPi - 1e-7));
  for (const std::uint32_t index : cloud) {
    const Eigen::Vector3d d = points.col(index) - sensor_origin;
    const double height = d.dot(up);
    const Eigen::Vector3d horizontal = d - height * up;
    const double length = horizontal.norm();
    if (!(length > 1e-9) || horizontal.dot(direction) < span_cosine * length) continue;
    if (height > limit_tangent * length) return false;
  }
  return true;
}

}  // namespace quadrix
