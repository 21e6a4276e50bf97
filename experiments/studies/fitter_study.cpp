// The fitter study (see fitter_study.h): synthetic grid + real segments, per-fit metrics, and the
// CSV / Markdown / SVG writers.
#include "experiments/studies/fitter_study.h"

#include "experiments/studies/study_report.h"
#include "experiments/synthetic/scan_segments.h"
#include "fitting/extraction.h"
#include "fitting/learned_fitter.h"
#include "geometry/constants.h"
#include "geometry/error.h"
#include "geometry/io.h"

#include <nlohmann/json.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <ostream>
#include <random>
#include <set>
#include <sstream>
#include <unordered_map>

namespace quadrix {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// splitmix64: derives independent seeds from the base seed and a cell's coordinates.
std::uint64_t mix_seed(std::uint64_t value) {
  value += 0x9e3779b97f4a7c15ULL;
  value = (value ^ (value >> 30)) * 0xbf58476d1ce4e5b9ULL;
  value = (value ^ (value >> 27)) * 0x94d049bb133111ebULL;
  return value ^ (value >> 31);
}

Eigen::Isometry3d random_pose(std::mt19937_64& random) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::Quaterniond rotation(normal(random), normal(random), normal(random), normal(random));
  rotation.normalize();
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = rotation.toRotationMatrix();
  pose.translation() = Eigen::Vector3d(normal(random), normal(random), normal(random)) * 10.0;
  return pose;
}

// Extents of the generated surfaces (metres, canonical frame).
constexpr double kPlaneWidth = 4.0;      // along b
constexpr double kPlaneHeight = 3.0;     // along c
constexpr double kLineLength = 6.0;
constexpr double kCylinderLength = 3.0;
constexpr double kConeNearHeight = 0.5;  // distance of the cone segment from its apex along the axis
constexpr double kConeFarHeight = 2.5;

/// A local (canonical-frame) point of the surface; `visible` limits the part sampled.
Eigen::Vector3d canonical_sample(QuadricType type, const Eigen::Vector3d& scale, double visible, std::mt19937_64& random) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double angle = 2.0 * kPi * visible * unit(random);
  switch (type) {
    case QuadricType::Plane:
      return {0.0, kPlaneWidth * (visible * unit(random) - 0.5), kPlaneHeight * (unit(random) - 0.5)};
    case QuadricType::Line:
      return {0.0, 0.0, kLineLength * (visible * unit(random) - 0.5)};
    case QuadricType::Sphere:
    case QuadricType::Ellipsoid: {
      // Uniform on the unit sphere's cap z >= 1 - 2 visible (its area is `visible` of the sphere).
      const double z = 1.0 - 2.0 * visible * unit(random);
      const double ring = std::sqrt(std::max(0.0, 1.0 - z * z));
      const double azimuth = 2.0 * kPi * unit(random);
      return Eigen::Vector3d(ring * std::cos(azimuth), ring * std::sin(azimuth), z).cwiseProduct(scale);
    }
    case QuadricType::CircularCylinder:
    case QuadricType::EllipticCylinder:
      return {scale(0) * std::cos(angle), scale(1) * std::sin(angle), kCylinderLength * (unit(random) - 0.5)};
    case QuadricType::CircularCone:
    case QuadricType::EllipticCone: {
      const double height = kConeNearHeight + (kConeFarHeight - kConeNearHeight) * unit(random);
      return {height * scale(0) * std::cos(angle), height * scale(1) * std::sin(angle), height};
    }
    default:
      throw Error("synthetic segment: unsupported type " + quadric_type_name(type));
  }
}

Eigen::Vector3d random_scale(QuadricType type, std::mt19937_64& random) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  switch (type) {
    case QuadricType::Plane: return {1.0, kPlaneWidth, kPlaneHeight};
    case QuadricType::Line: return {1.0, 1.0, kLineLength};
    case QuadricType::Sphere: return Eigen::Vector3d::Constant(0.3 + 1.7 * unit(random));
    case QuadricType::Ellipsoid: {
      const double a = 0.4 + 0.8 * unit(random);
      const double b = a * (1.25 + 0.35 * unit(random));
      return {a, b, b * (1.25 + 0.35 * unit(random))};
    }
    case QuadricType::CircularCylinder: { const double r = 0.1 + 0.9 * unit(random); return {r, r, 1.0}; }
    case QuadricType::EllipticCylinder: {
      const double a = 0.3 + 0.7 * unit(random);
      return {a, a * (1.3 + 0.7 * unit(random)), 1.0};
    }
    case QuadricType::CircularCone: { const double t = 0.25 + 0.75 * unit(random); return {t, t, 1.0}; }
    case QuadricType::EllipticCone: {
      const double t = 0.25 + 0.5 * unit(random);
      return {t, t * (1.3 + 0.5 * unit(random)), 1.0};
    }
    default: throw Error("synthetic segment: unsupported type " + quadric_type_name(type));
  }
}

int family(QuadricType type) {
  switch (type) {
    case QuadricType::Sphere: case QuadricType::Ellipsoid: return 1;
    case QuadricType::CircularCylinder: case QuadricType::EllipticCylinder: return 2;
    case QuadricType::CircularCone: case QuadricType::EllipticCone: return 3;
    default: return 100 + static_cast<int>(type);
  }
}

double angle_degrees(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::min(1.0, std::abs(a.normalized().dot(b.normalized())))) * 180.0 / kPi;
}

/// Fills the error columns of a synthetic row from the truth and the fit.
void measure_synthetic(const SyntheticSegment& segment, const QuadricFit& fit, FitterStudyRow& row) {
  row.scale_error = row.axis_error_deg = row.centre_error = row.surface_rms = kNaN;
  const QuadricDecomposition& shape = fit.shape;
  const bool usable = (fit.status == FitStatus::Ok || fit.status == FitStatus::NotConverged ||
                       fit.status == FitStatus::TypeMismatch) &&
                      shape.type != QuadricType::Invalid && shape.type != QuadricType::Imaginary;
  if (!usable) return;
  double sum = 0.0;
  for (Eigen::Index i = 0; i < segment.full_surface.cols(); ++i) {
    const double distance = orthogonal_distance(shape, segment.full_surface.col(i));
    sum += distance * distance;
  }
  row.surface_rms = std::sqrt(sum / static_cast<double>(std::max<Eigen::Index>(1, segment.full_surface.cols())));
  if (!std::isfinite(row.surface_rms)) row.surface_rms = kNaN;
  const QuadricType type = segment.type;
  if (family(shape.type) != family(type)) return;
  const Eigen::Matrix3d& truth_axes = segment.pose.linear();
  int defined = 2;
  if (type == QuadricType::Sphere || type == QuadricType::Ellipsoid) defined = 3;
  if (type == QuadricType::Plane || type == QuadricType::Line) defined = 0;
  if (defined > 0) {
    Eigen::Vector3d truth = segment.scale, found = shape.scale;
    std::sort(truth.data(), truth.data() + defined);
    std::sort(found.data(), found.data() + defined);
    row.scale_error = (truth - found).head(defined).cwiseQuotient(truth.head(defined)).cwiseAbs().maxCoeff();
  }
  const Eigen::Vector3d offset = shape.center - segment.pose.translation();
  switch (type) {
    case QuadricType::Plane:
      row.axis_error_deg = angle_degrees(shape.rotation.col(0), truth_axes.col(0));
      row.centre_error = std::abs(offset.dot(truth_axes.col(0)));
      break;
    case QuadricType::Sphere:
      row.centre_error = offset.norm();
      break;
    case QuadricType::Ellipsoid: {
      row.centre_error = offset.norm();
      if (shape.type == QuadricType::Ellipsoid) {  // pair axes by ascending scale
        std::array<int, 3> truth_order{0, 1, 2}, found_order{0, 1, 2};
        std::sort(truth_order.begin(), truth_order.end(), [&](int a, int b) { return segment.scale(a) < segment.scale(b); });
        std::sort(found_order.begin(), found_order.end(), [&](int a, int b) { return shape.scale(a) < shape.scale(b); });
        double worst = 0.0;
        for (int k = 0; k < 3; ++k)
          worst = std::max(worst, angle_degrees(shape.rotation.col(found_order[k]), truth_axes.col(truth_order[k])));
        row.axis_error_deg = worst;
      }
      break;
    }
    case QuadricType::CircularCone:
    case QuadricType::EllipticCone:
      row.axis_error_deg = angle_degrees(shape.rotation.col(2), truth_axes.col(2));
      row.centre_error = offset.norm();
      break;
    default: {  // line, cylinders: distance of the fitted centre from the true axis
      row.axis_error_deg = angle_degrees(shape.rotation.col(2), truth_axes.col(2));
      const Eigen::Vector3d axis = truth_axes.col(2);
      row.centre_error = (offset - offset.dot(axis) * axis).norm();
      break;
    }
  }
}

FitterStudyRow base_row(const std::string& fitter, const std::string& mode, const QuadricFit& fit, QuadricType true_type,
                        int points) {
  FitterStudyRow row;
  row.fitter = fitter;
  row.mode = mode;
  row.true_type = true_type;
  row.points = points;
  row.status = fit.status;
  const bool returned = fit.status == FitStatus::Ok || fit.status == FitStatus::NotConverged || fit.status == FitStatus::TypeMismatch;
  row.fitted_type = returned ? fit.shape.type : QuadricType::Invalid;
  row.type_correct = (fit.status == FitStatus::Ok || fit.status == FitStatus::NotConverged) && row.fitted_type == true_type;
  row.residual_rms = returned ? fit.residual_rms : kNaN;
  row.fitted_scale = returned ? fit.shape.scale : Eigen::Vector3d::Constant(kNaN);
  row.time_ms = fit.time_ms;
  return row;
}

// ---- Real segments -----------------------------------------------------------------------------

/// Every k-th column so that at most max_points remain.
Eigen::Matrix3Xd thin(const Eigen::Matrix3Xd& points, int max_points) {
  if (max_points <= 0 || points.cols() <= max_points) return points;
  const Eigen::Index step = (points.cols() + max_points - 1) / max_points;
  Eigen::Matrix3Xd kept(3, (points.cols() + step - 1) / step);
  for (Eigen::Index i = 0, j = 0; i < points.cols(); i += step, ++j) kept.col(j) = points.col(i);
  return kept;
}

Eigen::Matrix3Xd select(const Eigen::Matrix3Xd& points, const std::vector<Eigen::Index>& indices) {
  Eigen::Matrix3Xd selected(3, static_cast<Eigen::Index>(indices.size()));
  for (std::size_t i = 0; i < indices.size(); ++i) selected.col(static_cast<Eigen::Index>(i)) = points.col(indices[i]);
  return selected;
}

/// Deterministic RANSAC plane (fixed seed): unit normal n and offset d with n.x + d = 0.
std::pair<Eigen::Vector3d, double> ransac_plane(const Eigen::Matrix3Xd& points, double threshold, int iterations,
                                                std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::uniform_int_distribution<Eigen::Index> pick(0, points.cols() - 1);
  const Eigen::Index stride = std::max<Eigen::Index>(1, points.cols() / 5000);  // score on a thinned set
  std::size_t best_count = 0;
  std::pair<Eigen::Vector3d, double> best{Eigen::Vector3d::UnitZ(), 0.0};
  for (int iteration = 0; iteration < iterations; ++iteration) {
    const Eigen::Vector3d a = points.col(pick(random)), b = points.col(pick(random)), c = points.col(pick(random));
    Eigen::Vector3d normal = (b - a).cross(c - a);
    if (!(normal.norm() > 1e-12)) continue;
    normal.normalize();
    const double offset = -normal.dot(a);
    std::size_t count = 0;
    for (Eigen::Index i = 0; i < points.cols(); i += stride) count += std::abs(normal.dot(points.col(i)) + offset) < threshold;
    if (count > best_count) {
      best_count = count;
      best = {normal, offset};
    }
  }
  return best;
}

/// Largest 26-connected component of the occupied cells of a voxel grid.
std::vector<Eigen::Index> largest_voxel_component(const Eigen::Matrix3Xd& points, double cell) {
  struct KeyHash {
    std::size_t operator()(const std::array<long long, 3>& k) const {
      return static_cast<std::size_t>(mix_seed(static_cast<std::uint64_t>(k[0]) * 73856093ULL ^
                                               static_cast<std::uint64_t>(k[1]) * 19349663ULL ^
                                               static_cast<std::uint64_t>(k[2]) * 83492791ULL));
    }
  };
  std::unordered_map<std::array<long long, 3>, std::vector<Eigen::Index>, KeyHash> cells;
  for (Eigen::Index i = 0; i < points.cols(); ++i) {
    const std::array<long long, 3> key{static_cast<long long>(std::floor(points(0, i) / cell)),
                                       static_cast<long long>(std::floor(points(1, i) / cell)),
                                       static_cast<long long>(std::floor(points(2, i) / cell))};
    cells[key].push_back(i);
  }
  std::set<std::array<long long, 3>> seen;
  std::vector<Eigen::Index> best;
  // Visit cells in sorted order so ties resolve the same way on every machine.
  std::vector<std::array<long long, 3>> keys;
  keys.reserve(cells.size());
  for (const auto& entry : cells) keys.push_back(entry.first);
  std::sort(keys.begin(), keys.end());
  for (const auto& start : keys) {
    if (seen.count(start)) continue;
    std::vector<std::array<long long, 3>> stack{start};
    seen.insert(start);
    std::vector<Eigen::Index> component;
    while (!stack.empty()) {
      const auto key = stack.back();
      stack.pop_back();
      const auto& members = cells.at(key);
      component.insert(component.end(), members.begin(), members.end());
      for (long long dx = -1; dx <= 1; ++dx)
        for (long long dy = -1; dy <= 1; ++dy)
          for (long long dz = -1; dz <= 1; ++dz) {
            const std::array<long long, 3> next{key[0] + dx, key[1] + dy, key[2] + dz};
            if (cells.count(next) && !seen.count(next)) {
              seen.insert(next);
              stack.push_back(next);
            }
          }
    }
    if (component.size() > best.size()) best = std::move(component);
  }
  std::sort(best.begin(), best.end());
  return best;
}

/// The held-apart scan segments: per type an even stride of at most `per_type` of them, in order.
std::vector<SyntheticSegment> held_apart_scan_segments(const FitterStudyOptions& options, std::vector<ScanSegment>& kept) {
  ScanSegmentOptions generation;
  generation.seed = options.scan_seed;
  generation.scans = options.scan_scene_scans;
  generation.object_scans = options.scan_object_scans;
  generation.max_points = options.scan_segment_max_points;
  const std::vector<ScanSegment> all = make_scan_segments(generation);
  std::vector<SyntheticSegment> segments;
  for (const QuadricType type : generation.types) {
    std::vector<const ScanSegment*> of_type;
    for (const ScanSegment& segment : all)
      if (segment.type == type) of_type.push_back(&segment);
    const std::size_t limit = static_cast<std::size_t>(std::max(options.scan_segments_per_type, 1));
    const std::size_t step = std::max<std::size_t>(1, (of_type.size() + limit - 1) / limit);
    for (std::size_t i = 0; i < of_type.size(); i += step) {
      const ScanSegment& scan = *of_type[i];
      SyntheticSegment segment;
      segment.type = scan.type;
      segment.scale = scan.scale;
      segment.pose = scan.pose;
      segment.points = scan.points;
      segment.full_surface = scan.full_surface;
      segments.push_back(std::move(segment));
      kept.push_back(scan);
    }
  }
  return segments;
}

/// Angle between a fit's defining axis (plane normal; line, cylinder, cone axis) and the segment's
/// physical reference, or its departure from perpendicular; NaN without a reference or a usable fit.
double reference_deviation_degrees(const QuadricFit& fit, const RealSegment& segment) {
  if (segment.reference_axis.isZero() || (fit.status != FitStatus::Ok && fit.status != FitStatus::NotConverged)) return kNaN;
  const QuadricType type = fit.shape.type;
  Eigen::Vector3d axis;
  if (type == QuadricType::Plane) axis = fit.shape.rotation.col(0);
  else if (type == QuadricType::Line || family(type) == family(QuadricType::CircularCylinder) ||
           family(type) == family(QuadricType::CircularCone))
    axis = fit.shape.rotation.col(2);
  else return kNaN;
  const double angle = angle_degrees(axis, segment.reference_axis);
  return segment.reference_is_perpendicular ? 90.0 - angle : angle;
}

}  // namespace

std::vector<QuadricType> synthetic_segment_types() {
  return {QuadricType::Plane,           QuadricType::Line,           QuadricType::Sphere,
          QuadricType::Ellipsoid,       QuadricType::CircularCylinder, QuadricType::EllipticCylinder,
          QuadricType::CircularCone,    QuadricType::EllipticCone};
}

SyntheticSegment make_synthetic_segment(const SyntheticSegmentSpec& spec) {
  const auto types = synthetic_segment_types();
  if (std::find(types.begin(), types.end(), spec.type) == types.end())
    throw Error("synthetic segment: unsupported type " + quadric_type_name(spec.type));
  if (!(spec.visible_fraction > 0.0 && spec.visible_fraction <= 1.0))
    throw Error("synthetic segment: visible fraction must be in (0, 1], got " + std::to_string(spec.visible_fraction));
  if (!(spec.outlier_fraction >= 0.0 && spec.outlier_fraction < 1.0))
    throw Error("synthetic segment: outlier fraction must be in [0, 1), got " + std::to_string(spec.outlier_fraction));
  if (!(spec.noise >= 0.0)) throw Error("synthetic segment: noise must be >= 0, got " + std::to_string(spec.noise));
  if (spec.points < 1) throw Error("synthetic segment: points must be >= 1, got " + std::to_string(spec.points));
  // Separate streams: shape and pose, surface samples, noise, outliers, full-surface samples. Shape,
  // pose and sample positions therefore do not depend on the noise or outlier level (common random numbers).
  std::mt19937_64 shape_random(mix_seed(spec.seed));
  std::mt19937_64 sample_random(mix_seed(spec.seed ^ 0x5151ULL));
  std::mt19937_64 noise_random(mix_seed(spec.seed ^ 0xa0a0ULL));
  std::mt19937_64 outlier_random(mix_seed(spec.seed ^ 0x0f0fULL));
  std::mt19937_64 full_random(mix_seed(spec.seed ^ 0x7777ULL));
  SyntheticSegment segment;
  segment.type = spec.type;
  segment.scale = random_scale(spec.type, shape_random);
  segment.pose = random_pose(shape_random);
  segment.points.resize(3, spec.points);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (int i = 0; i < spec.points; ++i) {
    const Eigen::Vector3d local = canonical_sample(spec.type, segment.scale, spec.visible_fraction, sample_random);
    const Eigen::Vector3d jitter(noise(noise_random), noise(noise_random), noise(noise_random));
    segment.points.col(i) = segment.pose * local + spec.noise * jitter;
  }
  segment.outlier_count = static_cast<int>(std::round(spec.outlier_fraction * spec.points));
  if (segment.outlier_count > 0) {
    const Eigen::Vector3d lower = segment.points.rowwise().minCoeff();
    const Eigen::Vector3d upper = segment.points.rowwise().maxCoeff();
    const double margin = 0.1 * (upper - lower).norm();
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int i = 0; i < segment.outlier_count; ++i)
      for (int k = 0; k < 3; ++k)
        segment.points(k, i) = lower(k) - margin + (upper(k) - lower(k) + 2.0 * margin) * unit(outlier_random);
  }
  const int full_count = 300;
  segment.full_surface.resize(3, full_count);
  for (int i = 0; i < full_count; ++i)
    segment.full_surface.col(i) = segment.pose * canonical_sample(spec.type, segment.scale, 1.0, full_random);
  return segment;
}

std::vector<RealSegment> real_fitter_segments(const std::string& data_root, int max_points, std::vector<std::string>& notes) {
  std::vector<RealSegment> segments;
  const std::filesystem::path root(data_root);
  const std::filesystem::path table_path = root / "single_scans" / "table_scene_mug_stereo_textured.pcd";
  if (std::filesystem::exists(table_path)) {
    const PointCloud cloud = read_point_cloud(table_path.string());
    const Eigen::Matrix3Xd all = cloud.positions.cast<double>();
    std::vector<Eigen::Index> near;
    for (Eigen::Index i = 0; i < all.cols(); ++i)
      if (all(2, i) < 1.6) near.push_back(i);
    const Eigen::Matrix3Xd cropped = select(all, near);
    const auto [normal, offset] = ransac_plane(cropped, 0.01, 300, 7);
    std::vector<Eigen::Index> table, above;
    // The camera is on the side of the plane where n.x + d has the sign of d (origin = camera).
    const double camera_side = offset >= 0.0 ? 1.0 : -1.0;
    for (Eigen::Index i = 0; i < cropped.cols(); ++i) {
      const double signed_distance = (normal.dot(cropped.col(i)) + offset) * camera_side;
      if (std::abs(signed_distance) < 0.01) table.push_back(i);
      else if (signed_distance > 0.01 && signed_distance < 0.2) above.push_back(i);
    }
    RealSegment plane;
    plane.name = "table_plane";
    plane.type = QuadricType::Plane;
    plane.points = thin(select(cropped, table), max_points);
    plane.reference_axis = normal;  // the RANSAC normal: a plane fit should agree with it
    plane.how = "table scene: points with z < 1.6 m; RANSAC plane (300 draws, seed 7, 1 cm threshold); its " +
                std::to_string(table.size()) + " inliers thinned to " + std::to_string(plane.points.cols());
    segments.push_back(plane);
    const Eigen::Matrix3Xd objects = select(cropped, above);
    const std::vector<Eigen::Index> mug_indices = largest_voxel_component(objects, 0.01);
    RealSegment mug;
    mug.name = "mug";
    mug.type = QuadricType::CircularCylinder;
    mug.points = thin(select(objects, mug_indices), max_points);
    mug.reference_axis = normal;  // a mug stands on the table: its axis is the table's normal
    mug.how = "table scene: points 1-20 cm above that plane on the camera side, largest 26-connected component of "
              "1 cm voxels (" + std::to_string(mug_indices.size()) + " points incl. the handle) thinned to " +
              std::to_string(mug.points.cols()) + ", fitted as a circular cylinder";
    segments.push_back(mug);
  } else {
    notes.push_back("skipped the table scene: " + table_path.string() + " is absent");
  }
  const std::filesystem::path lamppost_path = root / "single_scans" / "lamppost.pcd";
  if (std::filesystem::exists(lamppost_path)) {
    const PointCloud cloud = read_point_cloud(lamppost_path.string());
    const Eigen::Matrix3Xd all = cloud.positions.cast<double>();
    // Pole: below z = -0.5 m (under the lamp arm); per 0.5 m height slice, points within 12 cm
    // horizontally of the slice's median (x, y) (drops the sign/bracket around z = -3 m).
    std::map<long long, std::vector<Eigen::Index>> slices;
    for (Eigen::Index i = 0; i < all.cols(); ++i)
      if (all(2, i) < -0.5) slices[static_cast<long long>(std::floor(all(2, i) / 0.5))].push_back(i);
    std::vector<Eigen::Index> pole;
    for (const auto& [slice, members] : slices) {
      std::vector<double> xs, ys;
      for (const Eigen::Index i : members) {
        xs.push_back(all(0, i));
        ys.push_back(all(1, i));
      }
      std::nth_element(xs.begin(), xs.begin() + xs.size() / 2, xs.end());
      std::nth_element(ys.begin(), ys.begin() + ys.size() / 2, ys.end());
      const Eigen::Vector2d median(xs[xs.size() / 2], ys[ys.size() / 2]);
      for (const Eigen::Index i : members)
        if ((all.col(i).head<2>() - median).norm() < 0.12) pole.push_back(i);
    }
    std::sort(pole.begin(), pole.end());
    const std::string how = "lamppost: points below z = -0.5 m within 12 cm horizontally of their 0.5 m slice's median (x, y) (" +
                            std::to_string(pole.size()) + " points)";
    RealSegment cylinder{"lamppost_pole", QuadricType::CircularCylinder, thin(select(all, pole), max_points),
                         how + ", fitted as a circular cylinder"};
    cylinder.reference_axis = Eigen::Vector3d::UnitZ();  // the slicing above assumes z is up: the pole is vertical
    RealSegment line{"lamppost_pole_line", QuadricType::Line, cylinder.points, how + ", fitted as a line",
                     Eigen::Vector3d::UnitZ()};
    segments.push_back(cylinder);
    segments.push_back(line);
  } else {
    notes.push_back("skipped the lamppost: " + lamppost_path.string() + " is absent");
  }
  return segments;
}

std::vector<RealSegment> kitti_fitter_segments(const std::string& data_root, int max_points, int facades, int poles,
                                               std::vector<std::string>& notes) {
  std::vector<RealSegment> segments;
  const std::filesystem::path path = std::filesystem::path(data_root) / "kitti00" / "velodyne" / "000000.bin";
  if (!std::filesystem::exists(path)) {
    notes.push_back("skipped the KITTI segments: " + path.string() + " is absent");
    return segments;
  }
  const PointCloud cloud = read_point_cloud(path.string());
  const ExtractionResult extraction = extract_elements(cloud, extraction_preset("vlp64"));
  const Eigen::Matrix3Xd all = cloud.positions.cast<double>();
  // Largest elements of a class first (ties by extraction order, which is deterministic).
  const auto largest = [&](ElementClass element_class, int count) {
    std::vector<const Element*> found;
    for (const Element& element : extraction.elements)
      if (element.element_class == element_class) found.push_back(&element);
    std::stable_sort(found.begin(), found.end(),
                     [](const Element* a, const Element* b) { return a->point_indices.size() > b->point_indices.size(); });
    if (static_cast<int>(found.size()) > count) found.resize(static_cast<std::size_t>(std::max(count, 0)));
    return found;
  };
  const auto points_of = [&](const Element& element) {
    const std::vector<Eigen::Index> indices(element.point_indices.begin(), element.point_indices.end());
    return thin(select(all, indices), max_points);
  };
  const std::string source = "KITTI 00 frame 0, extract_elements with preset vlp64 (geometry-only classes)";
  int rank = 0;
  for (const Element* element : largest(ElementClass::Plane, facades)) {
    ++rank;
    // KITTI's Velodyne is mounted level: a facade's normal is horizontal (perpendicular to z).
    RealSegment facade{"kitti_facade_" + std::to_string(rank), QuadricType::Plane, points_of(*element), "",
                       Eigen::Vector3d::UnitZ(), true};
    facade.how = source + ": plane element #" + std::to_string(rank) + " by size (" +
                 std::to_string(element->point_indices.size()) + " points, thinned to " +
                 std::to_string(facade.points.cols()) + "), fitted as a plane";
    segments.push_back(std::move(facade));
  }
  rank = 0;
  for (const Element* element : largest(ElementClass::Line, poles)) {
    ++rank;
    const std::string name = "kitti_pole_" + std::to_string(rank);
    const std::string how = source + ": line element #" + std::to_string(rank) + " by size (" +
                            std::to_string(element->point_indices.size()) +
                            " points; a pole or a tree trunk, the data has no labels to tell them apart)";
    const Eigen::Matrix3Xd points = points_of(*element);
    // Poles and trunks stand upright in the level sensor's frame: their axis is z.
    segments.push_back({name, QuadricType::CircularCylinder, points, how + ", fitted as a circular cylinder", Eigen::Vector3d::UnitZ()});
    segments.push_back({name + "_line", QuadricType::Line, points, how + ", fitted as a line", Eigen::Vector3d::UnitZ()});
  }
  if (segments.empty())
    notes.push_back("the KITTI extraction (" + extraction_status_name(extraction.status) + ") gave no plane or line element");
  return segments;
}

namespace {

/// One segment of the synthetic grid; its index fixes the slots of its rows, so output is independent of scheduling.
struct GridCell {
  QuadricType type;
  double noise, visible, outliers;
  int trial;
};

using Fitters = std::vector<std::unique_ptr<QuadricFitter>>;

/// Counts finished fits across the worker threads and passes the running count to the caller's progress callback.
class FitCounter {
 public:
  FitCounter(const StudyProgress& progress, std::size_t total) : progress_(progress), total_(total) {}
  void add(std::size_t count) {
    const std::size_t now = done_.fetch_add(count) + count;
    if (progress_) {
      std::lock_guard<std::mutex> lock(mutex_);
      progress_(now, total_);
    }
  }

 private:
  const StudyProgress& progress_;
  std::size_t total_;
  std::atomic<std::size_t> done_{0};
  std::mutex mutex_;
};

/// Rejects ungeneratable types and out-of-range grid values before any segment is made or fitted.
void check_study_options(const FitterStudyOptions& options) {
  const auto supported = synthetic_segment_types();
  for (const QuadricType type : options.types)
    if (std::find(supported.begin(), supported.end(), type) == supported.end())
      throw Error("--types: the study cannot generate a " + quadric_type_name(type));
  for (const double noise : options.noise_levels)
    if (!(noise >= 0.0)) throw Error("--noise: values must be >= 0 metres, got " + std::to_string(noise));
  for (const double visible : options.visible_fractions)
    if (!(visible > 0.0 && visible <= 1.0)) throw Error("--partiality: values must be in (0, 1], got " + std::to_string(visible));
  for (const double outliers : options.outlier_fractions)
    if (!(outliers >= 0.0 && outliers < 1.0)) throw Error("--outliers: values must be in [0, 1), got " + std::to_string(outliers));
  if (options.trials < 1) throw Error("--trials must be >= 1");
  if (options.points_per_segment < 10) throw Error("--points must be >= 10");
  if (options.threads < 1) throw Error("--threads must be >= 1");
}

/// Lists the synthetic grid in its fixed order (type, trial, visible fraction, outliers, noise): the row order of the CSV.
std::vector<GridCell> grid_cells(const FitterStudyOptions& options) {
  std::vector<GridCell> cells;
  for (const QuadricType type : options.types)
    for (int trial = 0; trial < options.trials; ++trial)
      for (const double visible : options.visible_fractions)
        for (const double outliers : options.outlier_fractions)
          for (const double noise : options.noise_levels) cells.push_back({type, noise, visible, outliers, trial});
  return cells;
}

/// Fits per grid segment and fitter: hinted, plus one unhinted (auto) fit when the type accuracy is measured.
std::size_t fit_modes(const FitterStudyOptions& options) { return options.automatic_type ? 2 : 1; }

/// Cuts the real segments (data folder, then KITTI) and records in result.real_notes how each was cut or why none was.
std::vector<RealSegment> load_real_segments(const FitterStudyOptions& options, FitterStudyResult& result) {
  std::vector<std::string> notes;
  std::vector<RealSegment> real;
  if (options.real_data) {
    if (std::filesystem::exists(options.data_root)) {
      real = real_fitter_segments(options.data_root, options.real_segment_max_points, notes);
      for (RealSegment& segment : kitti_fitter_segments(options.data_root, options.real_segment_max_points,
                                                        options.kitti_facades, options.kitti_poles, notes))
        real.push_back(std::move(segment));
    } else notes.push_back("skipped the real segments: data folder " + options.data_root + " is absent");
  }
  result.real_notes = notes;
  for (const auto& segment : real) result.real_notes.push_back(segment.name + " - " + segment.how);
  return real;
}

/// Generates each grid segment and fits it with every fitter and mode, in parallel, into the rows' fixed slots.
void run_grid(const FitterStudyOptions& options, const std::vector<GridCell>& cells, const Fitters& fitters,
              tbb::task_arena& arena, FitCounter& counter, FitterStudyResult& result) {
  const std::size_t modes = fit_modes(options);
  const std::size_t per_segment = fitters.size() * modes;
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cells.size(), 1), [&](const tbb::blocked_range<std::size_t>& range) {
      for (std::size_t c = range.begin(); c != range.end(); ++c) {
        const GridCell& cell = cells[c];
        SyntheticSegmentSpec spec;
        spec.type = cell.type;
        spec.noise = cell.noise;
        spec.visible_fraction = cell.visible;
        spec.outlier_fraction = cell.outliers;
        spec.points = options.points_per_segment;
        // The seed depends on type and trial only: every noise / visibility / outlier level of a trial
        // shares its surface, pose and sample stream.
        spec.seed = mix_seed(options.seed ^ (static_cast<std::uint64_t>(cell.type) << 32) ^ static_cast<std::uint64_t>(cell.trial));
        const SyntheticSegment segment = make_synthetic_segment(spec);
        for (std::size_t f = 0; f < fitters.size(); ++f)
          for (std::size_t m = 0; m < modes; ++m) {
            const FitTypeHint hint = m == 0 ? FitTypeHint(cell.type) : std::nullopt;
            const QuadricFit fit = fitters[f]->fit(segment.points, Eigen::Matrix3Xd(), hint);
            FitterStudyRow row = base_row(result.fitters[f], m == 0 ? "hint" : "auto", fit, cell.type,
                                          static_cast<int>(segment.points.cols()));
            row.source = "synthetic";
            row.noise = cell.noise;
            row.visible_fraction = cell.visible;
            row.outlier_fraction = cell.outliers;
            row.trial = cell.trial;
            measure_synthetic(segment, fit, row);
            result.rows[c * per_segment + f * modes + m] = std::move(row);
          }
        counter.add(per_segment);
      }
    });
  });
}

/// Fits the held-apart scan segments, hinted only (no fitter here classifies types from scans), into rows from `offset`.
void run_scan_segments(const std::vector<SyntheticSegment>& scans, const std::vector<ScanSegment>& scan_truth,
                       const Fitters& fitters, tbb::task_arena& arena, FitCounter& counter, std::size_t offset,
                       FitterStudyResult& result) {
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, scans.size(), 1), [&](const tbb::blocked_range<std::size_t>& range) {
      for (std::size_t s = range.begin(); s != range.end(); ++s)
        for (std::size_t f = 0; f < fitters.size(); ++f) {
          const QuadricFit fit = fitters[f]->fit(scans[s].points, Eigen::Matrix3Xd(), scans[s].type);
          FitterStudyRow row = base_row(result.fitters[f], "hint", fit, scans[s].type, static_cast<int>(scans[s].points.cols()));
          row.source = "scan";
          row.noise = scan_truth[s].noise;
          row.visible_fraction = scan_truth[s].visible_fraction;
          row.outlier_fraction = static_cast<double>(scan_truth[s].leaked_points) / static_cast<double>(scans[s].points.cols());
          row.trial = static_cast<int>(s);
          measure_synthetic(scans[s], fit, row);
          result.rows[offset + s * fitters.size() + f] = std::move(row);
          counter.add(1);
        }
    });
  });
}

/// Fits the real segments, hinted, one after another; without ground truth only the reference deviation is measured.
void run_real_segments(const std::vector<RealSegment>& real, const Fitters& fitters, FitCounter& counter, std::size_t offset,
                       FitterStudyResult& result) {
  for (std::size_t s = 0; s < real.size(); ++s)
    for (std::size_t f = 0; f < fitters.size(); ++f) {
      const QuadricFit fit = fitters[f]->fit(real[s].points, Eigen::Matrix3Xd(), real[s].type);
      FitterStudyRow row = base_row(result.fitters[f], "hint", fit, real[s].type, static_cast<int>(real[s].points.cols()));
      row.source = real[s].name;
      row.scale_error = row.centre_error = row.surface_rms = kNaN;
      row.axis_error_deg = reference_deviation_degrees(fit, real[s]);
      result.rows[offset + s * fitters.size() + f] = std::move(row);
      counter.add(1);
    }
}

}  // namespace

FitterStudyResult run_fitter_study(const FitterStudyOptions& options, const StudyProgress& progress) {
  const auto start = std::chrono::steady_clock::now();
  FitterStudyResult result;
  result.fitters = options.fitters.empty() ? quadric_fitter_names() : options.fitters;
  Fitters fitters;
  for (const auto& name : result.fitters) fitters.push_back(make_quadric_fitter(name));  // throws for unknown names
  check_study_options(options);

  // Rows have fixed slots: the grid, then the scan segments, then the real segments.
  const std::vector<GridCell> cells = grid_cells(options);
  const std::size_t per_segment = fitters.size() * fit_modes(options);
  const std::vector<RealSegment> real = load_real_segments(options, result);
  std::vector<ScanSegment> scan_truth;
  const std::vector<SyntheticSegment> scans =
      options.scan_segments ? held_apart_scan_segments(options, scan_truth) : std::vector<SyntheticSegment>{};
  const std::size_t total = cells.size() * per_segment + real.size() * fitters.size() + scans.size() * fitters.size();
  result.rows.resize(total);
  FitCounter counter(progress, total);

  tbb::task_arena arena(options.threads);
  run_grid(options, cells, fitters, arena, counter, result);
  const std::size_t scan_offset = cells.size() * per_segment;
  run_scan_segments(scans, scan_truth, fitters, arena, counter, scan_offset, result);
  run_real_segments(real, fitters, counter, scan_offset + scans.size() * fitters.size(), result);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

// ---- Writers -----------------------------------------------------------------------------------

namespace {

using report::fixed;
using report::median;
using report::number;
using report::percentile;

/// Hinted fit returned a quadric of the requested family.
bool family_ok(const FitterStudyRow& row) {
  return (row.status == FitStatus::Ok || row.status == FitStatus::NotConverged) &&
         family(row.fitted_type) == family(row.true_type);
}

template <typename Predicate>
std::vector<const FitterStudyRow*> rows_where(const FitterStudyResult& result, Predicate predicate) {
  std::vector<const FitterStudyRow*> selected;
  for (const auto& row : result.rows)
    if (predicate(row)) selected.push_back(&row);
  return selected;
}

template <typename Field>
std::vector<double> column(const std::vector<const FitterStudyRow*>& rows, Field field) {
  std::vector<double> values;
  values.reserve(rows.size());
  for (const auto* row : rows) values.push_back(field(*row));
  return values;
}

double share(const std::vector<const FitterStudyRow*>& rows, const std::function<bool(const FitterStudyRow&)>& test) {
  if (rows.empty()) return kNaN;
  std::size_t count = 0;
  for (const auto* row : rows) count += test(*row) ? 1 : 0;
  return 100.0 * static_cast<double>(count) / static_cast<double>(rows.size());
}

std::vector<double> distinct(const FitterStudyResult& result, double FitterStudyRow::*field) {
  std::set<double> values;
  for (const auto& row : result.rows)
    if (row.source == "synthetic") values.insert(row.*field);
  return {values.begin(), values.end()};
}

/// "median (n)" of a metric over the family-ok rows, scaled for display.
std::string median_cell(const std::vector<const FitterStudyRow*>& rows, double FitterStudyRow::*field, double display_scale,
                        int decimals) {
  std::vector<const FitterStudyRow*> good;
  for (const auto* row : rows)
    if (family_ok(*row)) good.push_back(row);
  return fixed(display_scale * median(column(good, [field](const FitterStudyRow& r) { return r.*field; })), decimals);
}

/// Visible-fraction and noise bins of the scan-segment tables.
struct Bin {
  std::string name;
  double low, high;  // low < value <= high
};

/// One table per type: rows fitters, columns bins of `field`; cells "axis° / centre cm (n)".
void write_binned_tables(std::ostream& out, const FitterStudyResult& result, const std::vector<QuadricType>& types,
                         double FitterStudyRow::*field, const std::vector<Bin>& bins) {
  for (const QuadricType type : types) {
    out << "\n**" << quadric_type_name(type) << "** (median axis error / median centre error; n = segments in the bin)\n\n| fitter |";
    for (const Bin& bin : bins) {
      const auto rows = rows_where(result, [&](const FitterStudyRow& r) {
        return r.source == "scan" && r.fitter == result.fitters.front() && r.true_type == type && r.*field > bin.low &&
               r.*field <= bin.high;
      });
      out << ' ' << bin.name << " (n " << rows.size() << ") |";
    }
    out << "\n|---|";
    for (std::size_t i = 0; i < bins.size(); ++i) out << "---:|";
    out << '\n';
    for (const auto& fitter : result.fitters) {
      out << "| " << fitter << " |";
      for (const Bin& bin : bins) {
        const auto rows = rows_where(result, [&](const FitterStudyRow& r) {
          return r.source == "scan" && r.fitter == fitter && r.true_type == type && r.*field > bin.low && r.*field <= bin.high;
        });
        out << ' ' << median_cell(rows, &FitterStudyRow::axis_error_deg, 1.0, 1) << "° / "
            << median_cell(rows, &FitterStudyRow::centre_error, 100.0, 0) << " cm |";
      }
      out << '\n';
    }
  }
}

/// Rows of the held-apart scan segments that pass `test`.
std::vector<const FitterStudyRow*> scan_rows(const FitterStudyResult& result,
                                             const std::function<bool(const FitterStudyRow&)>& test) {
  return rows_where(result, [&](const FitterStudyRow& r) { return r.source == "scan" && test(r); });
}

/// "Held-apart scan segments": how they were cut, and the per fitter and type table of medians.
void write_scan_overview(std::ostream& out, const FitterStudyResult& result, const FitterStudyOptions& options,
                         const std::vector<QuadricType>& types, std::size_t segments) {
  out << "\n## Held-apart scan segments\n\n" << segments << " segments cut from simulated scans (`make_scan_segments`, "
      << "experiments/synthetic/scan_segments.h, seed " << options.scan_seed << ": " << options.scan_scene_scans
      << " scans of the street, corridor and monument scenes and " << options.scan_object_scans
      << " scans of single objects on the ground, sensors hdl64, vlp16, livox and tls in turn, segment centroids 2-80 m "
         "from the sensor, half the scans with a range noise sigma drawn in 0-5 cm; at most "
      << options.scan_segments_per_type << " per type, thinned to " << options.scan_segment_max_points
      << " points). The learned fitter was trained on seed 101 of the same generator: other street layouts, objects, "
         "sensor places and noise. A segment is what one scan saw of one primitive: one side of a pole, a band of a "
         "column, a patch of a dome or a facade, with neighbours' points within 0-30 cm leaking in. Poles count twice: "
         "as lines and as the thin cylinders they are. Hinted fits; metrics as above (visible fraction = measured "
         "share of the surface seen; the `leaked` column is the median share of neighbours' points).\n\n"
      << "| fitter | type | n | ok | scale err | axis err | centre err | residual | surface | leaked | time/fit |\n"
      << "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const auto& fitter : result.fitters)
    for (const QuadricType type : types) {
      const auto rows = scan_rows(result, [&](const FitterStudyRow& r) { return r.fitter == fitter && r.true_type == type; });
      out << "| " << fitter << " | " << quadric_type_name(type) << " | " << rows.size() << " | "
          << fixed(share(rows, family_ok), 0) << "% | " << median_cell(rows, &FitterStudyRow::scale_error, 100.0, 1) << "% | "
          << median_cell(rows, &FitterStudyRow::axis_error_deg, 1.0, 2) << "° | "
          << median_cell(rows, &FitterStudyRow::centre_error, 100.0, 1) << " cm | "
          << median_cell(rows, &FitterStudyRow::residual_rms, 100.0, 2) << " cm | "
          << median_cell(rows, &FitterStudyRow::surface_rms, 100.0, 1) << " cm | "
          << fixed(100.0 * median(column(rows, [](const FitterStudyRow& r) { return r.outlier_fraction; })), 1) << "% | "
          << fixed(median(column(rows, [](const FitterStudyRow& r) { return r.time_ms; })), 3) << " ms |\n";
    }
}

/// "Partial views": axis, centre and ok share on the scan segments with at most half the surface seen.
void write_partial_views(std::ostream& out, const FitterStudyResult& result, const std::vector<QuadricType>& partial_types) {
  out << "\n### Partial views: at most 50% of the surface seen\n\nMedian axis and centre error of the hinted fits on the "
         "held-apart scan segments with a visible fraction <= 50% (spheres have no axis), and the share of fits that "
         "returned the requested family.\n\n| type | metric |";
  for (const auto& fitter : result.fitters) out << ' ' << fitter << " |";
  out << "\n|---|---|";
  for (std::size_t i = 0; i < result.fitters.size(); ++i) out << "---:|";
  out << '\n';
  for (const QuadricType type : partial_types) {
    const auto partial = [&](const std::string& fitter) {
      return scan_rows(result, [&](const FitterStudyRow& r) {
        return r.fitter == fitter && r.true_type == type && r.visible_fraction <= 0.5;
      });
    };
    if (partial(result.fitters.front()).empty()) continue;
    const std::string name = quadric_type_name(type) + " (n " + std::to_string(partial(result.fitters.front()).size()) + ")";
    if (type != QuadricType::Sphere) {
      out << "| " << name << " | axis |";
      for (const auto& fitter : result.fitters) out << ' ' << median_cell(partial(fitter), &FitterStudyRow::axis_error_deg, 1.0, 2) << "° |";
      out << '\n';
    }
    out << "| " << name << " | centre |";
    for (const auto& fitter : result.fitters) out << ' ' << median_cell(partial(fitter), &FitterStudyRow::centre_error, 100.0, 1) << " cm |";
    out << "\n| " << name << " | ok |";
    for (const auto& fitter : result.fitters) out << ' ' << fixed(share(partial(fitter), family_ok), 0) << "% |";
    out << '\n';
  }
}

/// "By visible fraction" and "By noise": the scan-segment errors binned by each factor, one table per type.
void write_scan_bins(std::ostream& out, const FitterStudyResult& result, const std::vector<QuadricType>& partial_types) {
  out << "\n### By visible fraction (scan segments)\n";
  write_binned_tables(out, result, partial_types, &FitterStudyRow::visible_fraction,
                      {{"<= 25%", -1.0, 0.25}, {"25-50%", 0.25, 0.5}, {"50-75%", 0.5, 0.75}, {"> 75%", 0.75, 2.0}});
  out << "\n### By noise (scan segments; sigma of the scan's range noise)\n";
  write_binned_tables(out, result, partial_types, &FitterStudyRow::noise,
                      {{"<= 1 cm", -1.0, 0.01}, {"1-3 cm", 0.01, 0.03}, {"> 3 cm", 0.03, 1.0}});
}

/// "Where each fitter wins": per type and metric, the best and runner-up among the fitters that are reliably ok.
void write_scan_winners(std::ostream& out, const FitterStudyResult& result, const std::vector<QuadricType>& types) {
  out << "\n### Where each fitter wins (scan segments)\n\nPer type and metric, the fitter with the lowest median among "
         "those that returned the requested family for at least 90% of the segments, then the runner-up.\n\n"
         "| type | metric | best | runner-up |\n|---|---|---|---|\n";
  struct Metric {
    std::string name, unit;
    double FitterStudyRow::*field;
    double display_scale;
  };
  const std::vector<Metric> metrics = {{"axis error", "°", &FitterStudyRow::axis_error_deg, 1.0},
                                       {"centre error", " cm", &FitterStudyRow::centre_error, 100.0},
                                       {"scale error", "%", &FitterStudyRow::scale_error, 100.0},
                                       {"surface distance", " cm", &FitterStudyRow::surface_rms, 100.0}};
  for (const QuadricType type : types)
    for (const Metric& metric : metrics) {
      std::vector<std::pair<double, std::string>> ranking;
      for (const auto& fitter : result.fitters) {
        const auto rows = scan_rows(result, [&](const FitterStudyRow& r) { return r.fitter == fitter && r.true_type == type; });
        std::vector<const FitterStudyRow*> good;
        for (const auto* row : rows)
          if (family_ok(*row)) good.push_back(row);
        const double value = median(column(good, [&](const FitterStudyRow& r) { return r.*(metric.field); }));
        if (share(rows, family_ok) >= 90.0 && std::isfinite(value)) ranking.emplace_back(value, fitter);
      }
      if (ranking.empty()) continue;
      std::sort(ranking.begin(), ranking.end());
      const auto cell = [&](std::size_t i) {
        return i < ranking.size() ? "`" + ranking[i].second + "` " + fixed(metric.display_scale * ranking[i].first, 2) + metric.unit
                                  : std::string("–");
      };
      out << "| " << quadric_type_name(type) << " | " << metric.name << " | " << cell(0) << " | " << cell(1) << " |\n";
    }
}

/// The held-apart scan-segment sections: per fitter and type, the partial-view comparison, tables by
/// visible fraction and by noise, and where each fitter wins.
void write_scan_sections(std::ostream& out, const FitterStudyResult& result, const FitterStudyOptions& options) {
  const auto segments = scan_rows(result, [&](const FitterStudyRow& r) { return r.fitter == result.fitters.front(); });
  if (segments.empty()) return;
  std::set<QuadricType> type_set;
  for (const auto* row : segments) type_set.insert(row->true_type);
  const std::vector<QuadricType> types(type_set.begin(), type_set.end());
  const std::vector<QuadricType> partial_types = {QuadricType::CircularCylinder, QuadricType::CircularCone, QuadricType::Sphere};
  write_scan_overview(out, result, options, types, segments.size());
  write_partial_views(out, result, partial_types);
  write_scan_bins(out, result, partial_types);
  write_scan_winners(out, result, types);
}

/// The learned fitter's training record (manifest.json): segments, epochs, validation loss and time per type.
void write_learned_fitter_training_summary(std::ostream& out, const std::string& directory) {
  std::ifstream stream(directory + "/manifest.json");
  nlohmann::json manifest;
  try {
    stream >> manifest;
  } catch (const nlohmann::json::exception&) {
    return;
  }
  if (!manifest.contains("training") || !manifest["training"].contains("per_type")) return;
  const nlohmann::json& training = manifest["training"];
  out << "\n## Learned fitter training\n\nFrom `fitting/models/learned_fitter/manifest.json` (`make train-fitter`; "
         "loss curves: [learned_fitter_training.svg](learned_fitter_training.svg)). "
      << training.value("threads", 1) << " torch thread(s), " << fixed(training.value("total_seconds", kNaN) / 60.0, 1)
      << " min wall and " << fixed(training.value("total_cpu_seconds", kNaN) / 60.0, 1)
      << " CPU-min in all on the shared 2-core machine. Validation: a held-out share of the training pool (scan and "
         "analytic segments); training stops after " << training.value("patience", 0)
      << " epochs without a better validation loss and keeps the best epoch. The last column is the network's "
         "floor: its median axis error on clean, complete analytic segments of its type (no noise, nothing hidden), "
         "where the largest-variance axis of an elongated segment, the statistical fitter's, is exact.\n\n"
      << "| type | scan segments | analytic segments | epochs run | kept epoch | best validation loss | CPU time | "
         "axis error, clean and complete |\n"
      << "|---|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const auto& [type, record] : training["per_type"].items()) {
    const nlohmann::json* clean_axis = nullptr;
    if (record.contains("held_out_clean_full") && record["held_out_clean_full"].contains("axis_deg"))
      clean_axis = &record["held_out_clean_full"]["axis_deg"];
    out << "| " << type << " | " << record.value("scan_segments", 0) << " | " << record.value("analytic_segments", 0) << " | "
        << record.value("epochs_run", 0) << " | " << record.value("best_epoch", 0) << " | "
        << fixed(record.value("best_validation_loss", kNaN), 4) << " | " << fixed(record.value("training_cpu_seconds", kNaN), 0)
        << " s | " << (clean_axis ? fixed(clean_axis->value("median", kNaN), 2) + "°" : std::string("–")) << " |\n";
  }
}

/// Types of the synthetic grid, in enum order: the rows and columns of the per-type tables.
std::vector<QuadricType> synthetic_types(const FitterStudyResult& result) {
  std::set<QuadricType> type_set;
  for (const auto& row : result.rows)
    if (row.source == "synthetic") type_set.insert(row.true_type);
  return {type_set.begin(), type_set.end()};
}

/// The page's opening: the command and run, the grid, how segments are made and what each metric measures.
void write_introduction(std::ostream& out, const FitterStudyResult& result, const FitterStudyOptions& options,
                        const std::string& command_line) {
  std::size_t synthetic_segments = 0;
  for (const auto& row : result.rows)
    if (row.source == "synthetic" && row.mode == "hint" && row.fitter == result.fitters.front()) ++synthetic_segments;
  out << "# Fitter study\n\n"
      << "Generated by `" << command_line << "` (" << result.rows.size() << " fits, " << fixed(result.seconds, 1)
      << " s wall time on this machine, " << options.threads << " worker threads; times are per fit, measured while "
      << options.threads << " fits ran concurrently on 2 shared cores). Raw rows: the CSV beside this file; plot: the SVG.\n\n"
      << "Fitters: ";
  for (std::size_t f = 0; f < result.fitters.size(); ++f) out << (f ? ", " : "") << '`' << result.fitters[f] << '`';
  out << ". Synthetic grid: " << synthetic_segments << " segments of " << options.points_per_segment
      << " points = types x noise sigma {";
  for (std::size_t i = 0; i < options.noise_levels.size(); ++i) out << (i ? ", " : "") << fixed(100.0 * options.noise_levels[i], 0) << " cm";
  out << "} x visible fraction {";
  for (std::size_t i = 0; i < options.visible_fractions.size(); ++i) out << (i ? ", " : "") << fixed(100.0 * options.visible_fractions[i], 0) << "%";
  out << "} x outliers {";
  for (std::size_t i = 0; i < options.outlier_fractions.size(); ++i) out << (i ? ", " : "") << fixed(100.0 * options.outlier_fractions[i], 0) << "%";
  out << "} x " << options.trials << " trials (seed " << options.seed << "). Each segment is fitted with its type as the hint"
      << (options.automatic_type ? " and once without a hint (auto)" : "") << ".\n\n"
      << "How segments are made: a random size (spheres r 0.3-2 m; ellipsoids semi-axes 0.4-3 m, distinct; cylinders r 0.1-1 m, "
         "3 m long; elliptic cylinders a 0.3-1 m, b 1.3-2 a; cones tan 0.25-1 between 0.5 and 2.5 m from the apex; planes 4 x 3 m; "
         "lines 6 m) and a random pose; the visible part is an angular sector (cylinders, cones), a spherical cap "
         "(spheres, ellipsoids) or a sub-extent (planes, lines) of that fraction; isotropic Gaussian noise; outliers replace "
         "points with uniform samples of the bounding box enlarged by 10% of its diagonal. Shape, pose and sample stream depend "
         "on type and trial only, so every noise/visibility/outlier level sees the same surfaces.\n\n"
      << "Metrics (medians over the hinted fits that returned the requested family; `ok` is the share that did): "
         "scale error = largest relative error of the defined scales (radii, semi-axes, cone tangents; none for planes and lines); "
         "axis error = angle of the plane normal / line, cylinder or cone axis (ellipsoids: worst axis); centre error = distance "
         "of the centre (central types), of the centre from the true axis (lines, cylinders), or offset along the normal (planes); "
         "residual = RMS orthogonal distance of the fitted points (noise and outliers included); surface = RMS distance from the "
         "noise-free WHOLE generating surface to the fit (how well a partial view is completed).\n\n";
}

/// "Per fitter and type (hinted)": the headline medians over the whole synthetic grid.
void write_per_type_table(std::ostream& out, const FitterStudyResult& result, const std::vector<QuadricType>& types) {
  out << "## Per fitter and type (hinted)\n\n| fitter | type | ok | scale err | axis err | centre err | residual | surface | time/fit |\n"
      << "|---|---|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const auto& fitter : result.fitters)
    for (const QuadricType type : types) {
      const auto rows = rows_where(result, [&](const FitterStudyRow& r) {
        return r.source == "synthetic" && r.mode == "hint" && r.fitter == fitter && r.true_type == type;
      });
      if (rows.empty()) continue;
      std::vector<const FitterStudyRow*> good;
      for (const auto* row : rows)
        if (family_ok(*row)) good.push_back(row);
      out << "| " << fitter << " | " << quadric_type_name(type) << " | " << fixed(share(rows, family_ok), 0) << "% | "
          << fixed(100.0 * median(column(good, [](const FitterStudyRow& r) { return r.scale_error; })), 2) << "% | "
          << fixed(median(column(good, [](const FitterStudyRow& r) { return r.axis_error_deg; })), 2) << "° | "
          << fixed(100.0 * median(column(good, [](const FitterStudyRow& r) { return r.centre_error; })), 1) << " cm | "
          << fixed(100.0 * median(column(good, [](const FitterStudyRow& r) { return r.residual_rms; })), 2) << " cm | "
          << fixed(100.0 * median(column(good, [](const FitterStudyRow& r) { return r.surface_rms; })), 2) << " cm | "
          << fixed(median(column(rows, [](const FitterStudyRow& r) { return r.time_ms; })), 3) << " ms |\n";
    }
}

/// One grid-factor table: rows fitters, columns the levels of `field`, over the hinted synthetic fits passing `filter`.
void write_factor_table(std::ostream& out, const FitterStudyResult& result, const std::string& title,
                        double FitterStudyRow::*field, double display_scale, const std::string& unit,
                        const std::string& filter_text, const std::function<bool(const FitterStudyRow&)>& filter) {
  const std::vector<double> levels = distinct(result, field);
  out << "\n## " << title << "\n\n" << filter_text << " Cells: median scale error / median surface distance / ok share.\n\n| fitter |";
  for (const double level : levels) out << ' ' << fixed(display_scale * level, 0) << unit << " |";
  out << "\n|---|";
  for (std::size_t i = 0; i < levels.size(); ++i) out << "---:|";
  out << '\n';
  for (const auto& fitter : result.fitters) {
    out << "| " << fitter << " |";
    for (const double level : levels) {
      const auto rows = rows_where(result, [&](const FitterStudyRow& r) {
        return r.source == "synthetic" && r.mode == "hint" && r.fitter == fitter && r.*field == level && filter(r);
      });
      std::vector<const FitterStudyRow*> good;
      for (const auto* row : rows)
        if (family_ok(*row)) good.push_back(row);
      out << ' ' << fixed(100.0 * median(column(good, [](const FitterStudyRow& r) { return r.scale_error; })), 1) << "% / "
          << fixed(100.0 * median(column(good, [](const FitterStudyRow& r) { return r.surface_rms; })), 1) << " cm / "
          << fixed(share(rows, family_ok), 0) << "% |";
    }
    out << '\n';
  }
}

/// "Noise", "Visible fraction" and "Outliers": how each grid factor moves the errors with the others held mild.
void write_factor_tables(std::ostream& out, const FitterStudyResult& result) {
  write_factor_table(out, result, "Noise", &FitterStudyRow::noise, 100.0, " cm",
                     "Hinted fits without outliers, every type and visible fraction.",
                     [](const FitterStudyRow& r) { return r.outlier_fraction == 0.0; });
  write_factor_table(out, result, "Visible fraction", &FitterStudyRow::visible_fraction, 100.0, "%",
                     "Hinted fits without outliers, noise <= 2 cm, every type.",
                     [](const FitterStudyRow& r) { return r.outlier_fraction == 0.0 && r.noise <= 0.02 + 1e-12; });
  write_factor_table(out, result, "Outliers", &FitterStudyRow::outlier_fraction, 100.0, "%",
                     "Hinted fits with noise <= 2 cm, every type and visible fraction.",
                     [](const FitterStudyRow& r) { return r.noise <= 0.02 + 1e-12; });
}

/// "Type accuracy without a hint": per fitter and type, the share of auto fits that returned the generating type.
void write_type_accuracy(std::ostream& out, const FitterStudyResult& result, const std::vector<QuadricType>& types) {
  out << "\n## Type accuracy without a hint\n\nShare of auto fits whose returned type equals the generating type "
         "(the statistical fitter always answers ellipsoid without a hint, by the paper's rule).\n\n| fitter |";
  for (const QuadricType type : types) out << ' ' << quadric_type_name(type) << " |";
  out << " all |\n|---|";
  for (std::size_t i = 0; i <= types.size(); ++i) out << "---:|";
  out << '\n';
  for (const auto& fitter : result.fitters) {
    out << "| " << fitter << " |";
    for (const QuadricType type : types) {
      const auto rows = rows_where(result, [&](const FitterStudyRow& r) {
        return r.source == "synthetic" && r.mode == "auto" && r.fitter == fitter && r.true_type == type;
      });
      out << ' ' << fixed(share(rows, [](const FitterStudyRow& r) { return r.type_correct; }), 0) << "% |";
    }
    const auto all = rows_where(result, [&](const FitterStudyRow& r) { return r.source == "synthetic" && r.mode == "auto" && r.fitter == fitter; });
    out << ' ' << fixed(share(all, [](const FitterStudyRow& r) { return r.type_correct; }), 0) << "% |\n";
  }
}

/// "Time per fit": median and 90th percentile per fitter over the hinted synthetic fits.
void write_time_per_fit(std::ostream& out, const FitterStudyResult& result, const FitterStudyOptions& options) {
  out << "\n## Time per fit\n\nHinted synthetic fits (" << options.points_per_segment
      << " points), milliseconds, including the exact residual evaluation on every point (microbenchmark_fitters times the fit "
         "alone); 2 shared cores, " << options.threads << " fits at a time.\n\n| fitter | median | 90th percentile |\n|---|---:|---:|\n";
  for (const auto& fitter : result.fitters) {
    const auto rows = rows_where(result, [&](const FitterStudyRow& r) {
      return r.source == "synthetic" && r.mode == "hint" && r.fitter == fitter;
    });
    const auto times = column(rows, [](const FitterStudyRow& r) { return r.time_ms; });
    out << "| " << fitter << " | " << fixed(median(times), 3) << " | " << fixed(percentile(times, 0.9), 3) << " |\n";
  }
}

/// "Real segments": how each was cut and, lacking ground truth, each fit's deviation from a physical reference.
void write_real_segments(std::ostream& out, const FitterStudyResult& result) {
  out << "\n## Real segments\n\nNo ground truth: the table and the KITTI facades are fitted as planes; the mug, the "
         "lamppost's pole and the KITTI poles/trunks as circular cylinders (radius shown) and the poles also as lines. "
         "Residuals are exact orthogonal distances over every fitted point. How each segment was cut:\n\n";
  for (const auto& note : result.real_notes) out << "- " << note << '\n';
  const auto real_rows =
      rows_where(result, [](const FitterStudyRow& r) { return r.source != "synthetic" && r.source != "scan"; });
  if (real_rows.empty()) return;
  out << "\nAxis dev. = angle between the fitted axis (plane normal; line, cylinder or cone axis) and the physical "
         "reference: vertical (z) for the KITTI poles, trunks and the lamppost, the RANSAC table normal for the mug and "
         "the table, and for KITTI facades the departure of the normal from horizontal (the sensor is mounted level). "
         "Centre errors need a reference these segments do not have; the radius shows which fits are believable.\n";
  out << "\n| segment | points | fitter | status | type | axis dev. | radius | residual | time/fit |\n"
         "|---|---:|---|---|---|---:|---:|---:|---:|\n";
  for (const auto* row : real_rows) {
    const bool cylinder = row->fitted_type == QuadricType::CircularCylinder || row->fitted_type == QuadricType::EllipticCylinder;
    out << "| " << row->source << " | " << row->points << " | " << row->fitter << " | " << fit_status_name(row->status) << " | "
        << quadric_type_name(row->fitted_type) << " | " << fixed(row->axis_error_deg, 2) << "° | "
        << (cylinder ? fixed(100.0 * row->fitted_scale.head<2>().mean(), 2) + " cm" : std::string("–")) << " | "
        << fixed(100.0 * row->residual_rms, 2) << " cm | " << fixed(row->time_ms, 3) << " ms |\n";
  }
}


}  // namespace

void write_fitter_study_csv(const std::string& path, const FitterStudyResult& result) {
  write_file_atomically(path, [&](std::ostream& out) {
    out << "source,fitter,mode,true_type,noise_m,visible_fraction,outlier_fraction,trial,points,status,fitted_type,"
           "type_correct,scale_error,axis_error_deg,centre_error_m,residual_rms_m,surface_rms_m,fitted_scale_a,"
           "fitted_scale_b,fitted_scale_c,time_ms\n";
    for (const auto& row : result.rows) {
      out << row.source << ',' << row.fitter << ',' << row.mode << ',' << quadric_type_name(row.true_type) << ','
          << number(row.noise) << ',' << number(row.visible_fraction) << ',' << number(row.outlier_fraction) << ','
          << row.trial << ',' << row.points << ',' << fit_status_name(row.status) << ','
          << quadric_type_name(row.fitted_type) << ',' << (row.type_correct ? 1 : 0) << ',' << number(row.scale_error)
          << ',' << number(row.axis_error_deg) << ',' << number(row.centre_error) << ',' << number(row.residual_rms)
          << ',' << number(row.surface_rms) << ',' << number(row.fitted_scale(0)) << ',' << number(row.fitted_scale(1))
          << ',' << number(row.fitted_scale(2)) << ',' << number(row.time_ms, 4) << '\n';
    }
  });
}

void write_fitter_study_markdown(const std::string& path, const FitterStudyResult& result,
                                 const FitterStudyOptions& options, const std::string& command_line) {
  const std::vector<QuadricType> types = synthetic_types(result);
  write_file_atomically(path, [&](std::ostream& out) {
    write_introduction(out, result, options, command_line);
    write_per_type_table(out, result, types);
    write_factor_tables(out, result);
    if (options.automatic_type) write_type_accuracy(out, result, types);
    write_time_per_fit(out, result, options);
    write_real_segments(out, result);
    write_scan_sections(out, result, options);
    write_learned_fitter_training_summary(out, default_learned_fitter_directory());
  });
}

void write_fitter_study_svg(const std::string& path, const FitterStudyResult& result) {
  // Median scale error (log axis, %) of the hinted synthetic fits against each grid factor, and the
  // median time per fit per type, one line per fitter (report::write_line_panels_svg).
  struct Factor {
    std::string title, x_label, unit;
    double FitterStudyRow::*field;
    std::function<bool(const FitterStudyRow&)> filter;
  };
  const std::vector<Factor> factors = {
      {"median scale error vs noise (no outliers)", "noise sigma", " cm", &FitterStudyRow::noise,
       [](const FitterStudyRow& r) { return r.outlier_fraction == 0.0; }},
      {"median scale error vs visible fraction (noise ≤ 2 cm, no outliers)", "visible fraction", "%",
       &FitterStudyRow::visible_fraction, [](const FitterStudyRow& r) { return r.outlier_fraction == 0.0 && r.noise <= 0.02 + 1e-12; }},
      {"median scale error vs outliers (noise ≤ 2 cm)", "outlier fraction", "%", &FitterStudyRow::outlier_fraction,
       [](const FitterStudyRow& r) { return r.noise <= 0.02 + 1e-12; }},
  };
  const auto synthetic_hint = [&](const std::string& fitter, const std::function<bool(const FitterStudyRow&)>& test) {
    return rows_where(result, [&](const FitterStudyRow& r) {
      return r.source == "synthetic" && r.mode == "hint" && r.fitter == fitter && test(r);
    });
  };
  std::vector<report::PlotPanel> panels;
  for (const Factor& factor : factors) {
    report::PlotPanel panel;
    panel.title = factor.title;
    panel.x_label = factor.x_label;
    panel.y_label = "%";
    panel.log_y = true;
    panel.y_low = 1e-3;
    panel.y_high = 1e2;
    const std::vector<double> levels = distinct(result, factor.field);
    for (const double level : levels) panel.x_ticks.push_back(fixed(100.0 * level, 0) + factor.unit);
    for (const auto& fitter : result.fitters) {
      report::PlotSeries series{fitter, {}};
      for (const double level : levels) {
        const auto rows = synthetic_hint(fitter, [&](const FitterStudyRow& r) {
          return r.*(factor.field) == level && factor.filter(r) && family_ok(r);
        });
        series.values.push_back(100.0 * median(column(rows, [](const FitterStudyRow& r) { return r.scale_error; })));
      }
      panel.series.push_back(std::move(series));
    }
    panels.push_back(std::move(panel));
  }
  std::set<QuadricType> type_set;
  for (const auto& row : result.rows)
    if (row.source == "synthetic") type_set.insert(row.true_type);
  report::PlotPanel timing;
  timing.title = "median time per fit (exact residuals included)";
  timing.x_label = "type";
  timing.y_label = " ms";
  timing.log_y = true;
  timing.y_low = 1e-3;
  timing.y_high = 1e4;
  for (const QuadricType type : type_set) timing.x_ticks.push_back(quadric_type_name(type));
  for (const auto& fitter : result.fitters) {
    report::PlotSeries series{fitter, {}};
    for (const QuadricType type : type_set)
      series.values.push_back(median(column(synthetic_hint(fitter, [&](const FitterStudyRow& r) { return r.true_type == type; }),
                                            [](const FitterStudyRow& r) { return r.time_ms; })));
    timing.series.push_back(std::move(series));
  }
  panels.push_back(std::move(timing));
  report::write_line_panels_svg(path, panels, 2);
}

}  // namespace quadrix
