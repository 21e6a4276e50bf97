// CGAL 5.5 shape detection as a quadric fitter (see cgal_fitter.h). All CGAL templates of the
// fitter live in this file.
#include "fitting/cgal_fitter.h"

#include "geometry/error.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Random.h>
#include <CGAL/centroid.h>
#include <CGAL/Shape_detection/Efficient_RANSAC.h>
#include <CGAL/jet_estimate_normals.h>
#include <CGAL/linear_least_squares_fitting_3.h>
#include <CGAL/property_map.h>

#include <boost/shared_ptr.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace quadrix {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point3 = Kernel::Point_3;
using Vector3 = Kernel::Vector_3;
using PointWithNormal = std::pair<Point3, Vector3>;
using PointList = std::vector<PointWithNormal>;
using PointMap = CGAL::First_of_pair_property_map<PointWithNormal>;
using NormalMap = CGAL::Second_of_pair_property_map<PointWithNormal>;
using Traits = CGAL::Shape_detection::Efficient_RANSAC_traits<Kernel, PointList, PointMap, NormalMap>;
using EfficientRansac = CGAL::Shape_detection::Efficient_RANSAC<Traits>;
using RansacPlane = CGAL::Shape_detection::Plane<Traits>;
using RansacSphere = CGAL::Shape_detection::Sphere<Traits>;
using RansacCylinder = CGAL::Shape_detection::Cylinder<Traits>;
using RansacCone = CGAL::Shape_detection::Cone<Traits>;

Eigen::Vector3d to_eigen(const Point3& p) { return {p.x(), p.y(), p.z()}; }
Eigen::Vector3d to_eigen(const Vector3& v) { return {v.x(), v.y(), v.z()}; }

/// A right-handed frame whose column `axis` is `direction` (unit).
Eigen::Matrix3d frame_with_axis(const Eigen::Vector3d& direction, int axis) {
  const Eigen::Vector3d n = direction.normalized();
  const Eigen::Vector3d helper = std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d u = (helper - helper.dot(n) * n).normalized();
  const Eigen::Vector3d v = n.cross(u);
  Eigen::Matrix3d frame;
  if (axis == 0) frame << n, u, v;  // det(n, u, n x u) = +1
  else frame << u, v, n;            // axis c
  return frame;
}

Eigen::Isometry3d make_pose(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = rotation;
  pose.translation() = translation;
  return pose;
}

/// The shape types Efficient RANSAC searches for a request (auto: all four).
struct ShapeChoice {
  bool plane = false, sphere = false, cylinder = false, cone = false;
};

/// One detected primitive converted to its quadric.
struct Detected {
  QuadricType type = QuadricType::Invalid;
  Quadric quadric;
  std::size_t inliers = 0;
};

/// Throws when the normals do not match the points one to one or a coordinate is NaN or infinite.
void validate_input(const Eigen::Matrix3Xd& points, const Eigen::Matrix3Xd& normals) {
  if (normals.cols() != 0 && normals.cols() != points.cols())
    throw Error("cgal fitter: " + std::to_string(normals.cols()) + " normals given for " +
                std::to_string(points.cols()) + " points (pass none or one per point)");
  if (!points.allFinite()) throw Error("cgal fitter: the points contain NaN or infinite coordinates");
}

/// The fewest points a request can be fitted from (without a hint: 9, enough for any shape).
std::size_t points_needed(FitTypeHint hint) {
  return hint ? std::max<std::size_t>(minimum_points_for_type(*hint), 3) : 9;
}

/// Marks `result` when CGAL has no primitive for the requested type or there are too few points.
bool accept_request(const Eigen::Matrix3Xd& points, FitTypeHint hint, QuadricFit& result) {
  if (hint) {
    const auto types = cgal_fitter_types();
    if (std::find(types.begin(), types.end(), *hint) == types.end()) {
      result.status = FitStatus::Failed;
      result.message = "CGAL shape detection has no " + quadric_type_name(*hint) +
                       " primitive (it detects planes, spheres, circular cylinders and circular cones)";
      return false;
    }
  }
  const std::size_t needed = points_needed(hint);
  if (static_cast<std::size_t>(points.cols()) < needed) {
    result.status = FitStatus::TooFewPoints;
    result.message = "CGAL fitting needs at least " + std::to_string(needed) + " points, got " +
                     std::to_string(points.cols());
    return false;
  }
  return true;
}

/// Copies the points into CGAL's kernel.
std::vector<Point3> to_cgal_points(const Eigen::Matrix3Xd& points) {
  std::vector<Point3> cgal_points;
  cgal_points.reserve(static_cast<std::size_t>(points.cols()));
  for (Eigen::Index i = 0; i < points.cols(); ++i) cgal_points.emplace_back(points(0, i), points(1, i), points(2, i));
  return cgal_points;
}

/// Chooses the shape factories for a request: the hinted type's, or all four without a hint.
ShapeChoice choose_shapes(FitTypeHint hint) {
  const QuadricType requested = hint.value_or(QuadricType::Invalid);
  ShapeChoice choice;
  choice.plane = !hint || requested == QuadricType::Plane;
  choice.sphere = !hint || requested == QuadricType::Sphere;
  choice.cylinder = !hint || requested == QuadricType::CircularCylinder;
  choice.cone = !hint || requested == QuadricType::CircularCone;
  return choice;
}

class CgalFitter final : public QuadricFitter {
 public:
  explicit CgalFitter(const CgalFitterOptions& options) : options_(options) {
    if (!(options_.epsilon_fraction > 0.0) || options_.epsilon_multipliers.empty())
      throw Error("cgal fitter: epsilon_fraction must be > 0 and epsilon_multipliers non-empty");
    if (!(options_.minimum_coverage > 0.0 && options_.minimum_coverage <= 1.0))
      throw Error("cgal fitter: minimum_coverage must be in (0, 1], got " + std::to_string(options_.minimum_coverage));
    if (options_.normal_neighbours < 3)
      throw Error("cgal fitter: normal_neighbours must be >= 3, got " + std::to_string(options_.normal_neighbours));
  }

  std::string name() const override { return "cgal"; }

  QuadricFit fit(const Eigen::Matrix3Xd& points, const Eigen::Matrix3Xd& normals, FitTypeHint hint) const override {
    const auto start = std::chrono::steady_clock::now();
    QuadricFit result = fit_points(points, normals, hint);
    result.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return result;
  }

 private:
  /// Fits with CGAL: a point or line by least squares, every other type by Efficient RANSAC with growing epsilon.
  QuadricFit fit_points(const Eigen::Matrix3Xd& points, const Eigen::Matrix3Xd& normals, FitTypeHint hint) const {
    QuadricFit result;
    validate_input(points, normals);
    const QuadricType requested = hint.value_or(QuadricType::Invalid);
    result.type = requested;
    if (!accept_request(points, hint, result)) return result;
    result.statistics = statistical_pose(points);
    const std::vector<Point3> cgal_points = to_cgal_points(points);
    if (hint && (requested == QuadricType::Point || requested == QuadricType::Line)) {
      fit_by_least_squares(points, cgal_points, requested, result);
      return result;
    }
    PointList with_normals = attach_normals(cgal_points, normals);
    const Eigen::Vector3d lower = points.rowwise().minCoeff();
    const Eigen::Vector3d upper = points.rowwise().maxCoeff();
    const double diagonal = (upper - lower).norm();
    if (!(diagonal > 0.0)) {
      result.status = FitStatus::Degenerate;
      result.message = "all points coincide";
      return result;
    }
    detect_with_growing_epsilon(points, with_normals, hint, diagonal, result);
    return result;
  }

  /// Fits a point (the centroid) or a line (CGAL's least squares) and evaluates it.
  void fit_by_least_squares(const Eigen::Matrix3Xd& points, const std::vector<Point3>& cgal_points,
                            QuadricType requested, QuadricFit& result) const {
    const Point3 centroid = CGAL::centroid(cgal_points.begin(), cgal_points.end());
    if (requested == QuadricType::Point) {
      result.quadric = Quadric::from_canonical(QuadricType::Point, Eigen::Vector3d::Ones(),
                                               make_pose(Eigen::Matrix3d::Identity(), to_eigen(centroid)));
    } else {
      if (result.statistics.scale(0) <= 0.0) {
        result.status = FitStatus::Degenerate;
        result.message = "all points coincide; a line is not determined";
        return;
      }
      Kernel::Line_3 line;
      Point3 line_centroid;
      CGAL::linear_least_squares_fitting_3(cgal_points.begin(), cgal_points.end(), line, line_centroid,
                                           CGAL::Dimension_tag<0>());
      result.quadric = Quadric::from_canonical(QuadricType::Line, Eigen::Vector3d::Ones(),
                                               make_pose(frame_with_axis(to_eigen(line.to_vector()), 2), to_eigen(line_centroid)));
    }
    result.status = FitStatus::Ok;
    evaluate_fit(points, result, {}, options_.evaluation);
  }

  /// Pairs each point with a normal: the caller's, else CGAL's jet estimate.
  PointList attach_normals(const std::vector<Point3>& cgal_points, const Eigen::Matrix3Xd& normals) const {
    PointList with_normals;
    with_normals.reserve(cgal_points.size());
    for (std::size_t i = 0; i < cgal_points.size(); ++i) {
      Vector3 normal(0.0, 0.0, 1.0);
      if (normals.cols() != 0) {
        const Eigen::Vector3d n = normals.col(static_cast<Eigen::Index>(i)).normalized();
        normal = Vector3(n.x(), n.y(), n.z());
      }
      with_normals.emplace_back(cgal_points[i], normal);
    }
    if (normals.cols() == 0) {
      const unsigned neighbours =
          static_cast<unsigned>(std::min<std::size_t>(static_cast<std::size_t>(options_.normal_neighbours), cgal_points.size() - 1));
      CGAL::jet_estimate_normals<CGAL::Sequential_tag>(
          with_normals, neighbours, CGAL::parameters::point_map(PointMap()).normal_map(NormalMap()));
    }
    return with_normals;
  }

  /// Detects with increasing epsilon until a shape covers minimum_coverage of the points; Degenerate when none does.
  void detect_with_growing_epsilon(const Eigen::Matrix3Xd& points, PointList& with_normals, FitTypeHint hint,
                                   double diagonal, QuadricFit& result) const {
    const std::size_t minimum_points = std::max<std::size_t>(
        points_needed(hint),
        static_cast<std::size_t>(std::ceil(options_.minimum_coverage * static_cast<double>(points.cols()))));
    const ShapeChoice choice = choose_shapes(hint);
    for (const double multiplier : options_.epsilon_multipliers) {
      const double epsilon = options_.epsilon_fraction * multiplier * diagonal;
      const Detected best = detect_largest_shape(with_normals, choice, minimum_points, epsilon, diagonal);
      if (best.type == QuadricType::Invalid) continue;
      record_detection(points, best, hint, epsilon, result);
      return;
    }
    result.status = FitStatus::Degenerate;
    result.message = std::string("CGAL shape detection found no ") + (hint ? quadric_type_name(*hint) : "shape") +
                     " covering " + std::to_string(minimum_points) + " of " + std::to_string(points.cols()) +
                     " points (epsilon up to " +
                     std::to_string(options_.epsilon_fraction * options_.epsilon_multipliers.back() * diagonal) + " m)";
  }

  /// Runs Efficient RANSAC once and keeps the usable shape with the most inliers (Invalid type when there is none).
  Detected detect_largest_shape(PointList& with_normals, const ShapeChoice& choice, std::size_t minimum_points,
                                double epsilon, double diagonal) const {
    CGAL::get_default_random() = CGAL::Random(options_.seed);  // thread-local: reproducible, thread-safe
    EfficientRansac ransac;
    ransac.set_input(with_normals);
    if (choice.plane) ransac.add_shape_factory<RansacPlane>();
    if (choice.sphere) ransac.add_shape_factory<RansacSphere>();
    if (choice.cylinder) ransac.add_shape_factory<RansacCylinder>();
    if (choice.cone) ransac.add_shape_factory<RansacCone>();
    EfficientRansac::Parameters parameters;  // every parameter set explicitly (DESIGN.md §5)
    parameters.probability = options_.probability;
    parameters.min_points = minimum_points;
    parameters.epsilon = epsilon;
    parameters.cluster_epsilon = options_.cluster_epsilon_fraction * diagonal;
    parameters.normal_threshold = options_.normal_threshold;
    ransac.preprocess();
    Detected best;
    if (!ransac.detect(parameters)) return best;
    for (const auto& shape : ransac.shapes()) {
      const std::size_t inliers = shape->indices_of_assigned_points().size();
      if (inliers < minimum_points || inliers <= best.inliers) continue;
      Detected detected = convert(shape, with_normals);
      if (detected.type == QuadricType::Invalid) continue;
      best = std::move(detected);
    }
    return best;
  }

  /// Stores the detected quadric, evaluates it and says how it was found; flags a type the rebuilt Q did not keep.
  void record_detection(const Eigen::Matrix3Xd& points, const Detected& best, FitTypeHint hint, double epsilon,
                        QuadricFit& result) const {
    const QuadricType requested = hint.value_or(QuadricType::Invalid);
    result.quadric = best.quadric;
    result.status = FitStatus::Ok;
    evaluate_fit(points, result, {}, options_.evaluation);
    if (result.status == FitStatus::Ok && hint && result.type != requested &&
        !(requested == QuadricType::CircularCylinder && result.type == QuadricType::EllipticCylinder)) {
      // Only possible through rounding of the rebuilt Q; report it rather than hide it.
      result.status = FitStatus::TypeMismatch;
      result.message = "asked for a " + quadric_type_name(requested) + ", the rebuilt quadric is a " +
                       quadric_type_name(result.type);
    }
    result.message = result.message.empty()
                         ? "epsilon " + std::to_string(epsilon) + " m, " + std::to_string(best.inliers) + " of " +
                               std::to_string(points.cols()) + " points on the shape"
                         : result.message;
  }

  /// Converts one detected primitive to its quadric (Invalid type when its parameters are unusable).
  template <typename ShapePointer>
  static Detected convert(const ShapePointer& shape, const PointList& with_normals) {
    Detected detected;
    const std::vector<std::size_t>& indices = shape->indices_of_assigned_points();
    detected.inliers = indices.size();
    std::vector<Point3> inliers;
    inliers.reserve(indices.size());
    for (const std::size_t index : indices) inliers.push_back(with_normals[index].first);
    const Eigen::Vector3d inlier_centroid = to_eigen(CGAL::centroid(inliers.begin(), inliers.end()));
    if (const auto plane = boost::dynamic_pointer_cast<RansacPlane>(shape)) {
      // CGAL's linear least squares on the inliers (RANSAC's plane comes from a minimal sample).
      Kernel::Plane_3 fitted;
      Point3 centroid;
      CGAL::linear_least_squares_fitting_3(inliers.begin(), inliers.end(), fitted, centroid, CGAL::Dimension_tag<0>());
      const Eigen::Vector3d normal = to_eigen(fitted.orthogonal_vector());
      if (!(normal.norm() > 0.0)) return detected;
      detected.type = QuadricType::Plane;
      detected.quadric = Quadric::from_canonical(QuadricType::Plane, Eigen::Vector3d::Ones(),
                                                 make_pose(frame_with_axis(normal, 0), to_eigen(centroid)));
    } else if (const auto sphere = boost::dynamic_pointer_cast<RansacSphere>(shape)) {
      const double radius = sphere->radius();
      if (!(radius > 0.0) || !std::isfinite(radius)) return detected;
      detected.type = QuadricType::Sphere;
      detected.quadric = Quadric::from_canonical(QuadricType::Sphere, Eigen::Vector3d::Constant(radius),
                                                 make_pose(Eigen::Matrix3d::Identity(), to_eigen(sphere->center())));
    } else if (const auto cylinder = boost::dynamic_pointer_cast<RansacCylinder>(shape)) {
      const double radius = cylinder->radius();
      const Eigen::Vector3d direction = to_eigen(cylinder->axis().to_vector());
      if (!(radius > 0.0) || !std::isfinite(radius) || !(direction.norm() > 0.0)) return detected;
      const Eigen::Vector3d axis = direction.normalized();
      const Eigen::Vector3d on_axis = to_eigen(cylinder->axis().point(0));
      // Centre: the foot of the inliers' centroid on the axis.
      const Eigen::Vector3d center = on_axis + (inlier_centroid - on_axis).dot(axis) * axis;
      detected.type = QuadricType::CircularCylinder;
      detected.quadric = Quadric::from_canonical(QuadricType::CircularCylinder, Eigen::Vector3d(radius, radius, 1.0),
                                                 make_pose(frame_with_axis(axis, 2), center));
    } else if (const auto cone = boost::dynamic_pointer_cast<RansacCone>(shape)) {
      const double half_angle = cone->angle();
      const Eigen::Vector3d axis = to_eigen(cone->axis());
      if (!(half_angle > 0.0) || !(half_angle < 1.5707963267948966) || !(axis.norm() > 0.0)) return detected;
      const double tangent = std::tan(half_angle);
      detected.type = QuadricType::CircularCone;
      detected.quadric = Quadric::from_canonical(QuadricType::CircularCone, Eigen::Vector3d(tangent, tangent, 1.0),
                                                 make_pose(frame_with_axis(axis, 2), to_eigen(cone->apex())));
    }
    return detected;
  }

  CgalFitterOptions options_;
};

}  // namespace

std::vector<QuadricType> cgal_fitter_types() {
  return {QuadricType::Point, QuadricType::Line, QuadricType::Plane, QuadricType::Sphere, QuadricType::CircularCylinder,
          QuadricType::CircularCone};
}

std::unique_ptr<QuadricFitter> make_cgal_fitter(const CgalFitterOptions& options) {
  return std::make_unique<CgalFitter>(options);
}

}  // namespace quadrix
