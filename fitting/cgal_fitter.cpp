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
  QuadricFit fit_points(const Eigen::Matrix3Xd& points, const Eigen::Matrix3Xd& normals, FitTypeHint hint) const {
    QuadricFit result;
    if (normals.cols() != 0 && normals.cols() != points.cols())
      throw Error("cgal fitter: " + std::to_string(normals.cols()) + " normals given for " +
                  std::to_string(points.cols()) + " points (pass none or one per point)");
    if (!points.allFinite()) throw Error("cgal fitter: the points contain NaN or infinite coordinates");
    const QuadricType requested = hint.value_or(QuadricType::Invalid);
    result.type = requested;
    if (hint) {
      const auto types = cgal_fitter_types();
      if (std::find(types.begin(), types.end(), requested) == types.end()) {
        result.status = FitStatus::Failed;
        result.message = "CGAL shape detection has no " + quadric_type_name(requested) +
                         " primitive (it detects planes, spheres, circular cylinders and circular cones)";
        return result;
      }
    }
    const std::size_t needed = hint ? std::max<std::size_t>(minimum_points_for_type(requested), 3) : 9;
    if (static_cast<std::size_t>(points.cols()) < needed) {
      result.status = FitStatus::TooFewPoints;
      result.message = "CGAL fitting needs at least " + std::to_string(needed) + " points, got " +
                       std::to_string(points.cols());
      return result;
    }
    result.statistics = statistical_pose(points);
    std::vector<Point3> cgal_points;
    cgal_points.reserve(static_cast<std::size_t>(points.cols()));
    for (Eigen::Index i = 0; i < points.cols(); ++i) cgal_points.emplace_back(points(0, i), points(1, i), points(2, i));

    if (hint && (requested == QuadricType::Point || requested == QuadricType::Line)) {
      const Point3 centroid = CGAL::centroid(cgal_points.begin(), cgal_points.end());
      if (requested == QuadricType::Point) {
        result.quadric = Quadric::from_canonical(QuadricType::Point, Eigen::Vector3d::Ones(),
                                                 make_pose(Eigen::Matrix3d::Identity(), to_eigen(centroid)));
      } else {
        if (result.statistics.scale(0) <= 0.0) {
          result.status = FitStatus::Degenerate;
          result.message = "all points coincide; a line is not determined";
          return result;
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
      return result;
    }

    ShapeChoice choice;
    choice.plane = !hint || requested == QuadricType::Plane;
    choice.sphere = !hint || requested == QuadricType::Sphere;
    choice.cylinder = !hint || requested == QuadricType::CircularCylinder;
    choice.cone = !hint || requested == QuadricType::CircularCone;

    // Points with normals: the caller's, else CGAL's jet estimate.
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
    const Eigen::Vector3d lower = points.rowwise().minCoeff();
    const Eigen::Vector3d upper = points.rowwise().maxCoeff();
    const double diagonal = (upper - lower).norm();
    if (!(diagonal > 0.0)) {
      result.status = FitStatus::Degenerate;
      result.message = "all points coincide";
      return result;
    }

    // Detection with increasing epsilon until a shape covers minimum_coverage of the points.
    const std::size_t minimum_points = std::max<std::size_t>(
        needed, static_cast<std::size_t>(std::ceil(options_.minimum_coverage * static_cast<double>(points.cols()))));
    for (const double multiplier : options_.epsilon_multipliers) {
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
      parameters.epsilon = options_.epsilon_fraction * multiplier * diagonal;
      parameters.cluster_epsilon = options_.cluster_epsilon_fraction * diagonal;
      parameters.normal_threshold = options_.normal_threshold;
      ransac.preprocess();
      if (!ransac.detect(parameters)) continue;
      Detected best;
      for (const auto& shape : ransac.shapes()) {
        const std::size_t inliers = shape->indices_of_assigned_points().size();
        if (inliers < minimum_points || inliers <= best.inliers) continue;
        Detected detected = convert(shape, with_normals);
        if (detected.type == QuadricType::Invalid) continue;
        best = std::move(detected);
      }
      if (best.type == QuadricType::Invalid) continue;
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
                           ? "epsilon " + std::to_string(parameters.epsilon) + " m, " + std::to_string(best.inliers) + " of " +
                                 std::to_string(points.cols()) + " points on the shape"
                           : result.message;
      return result;
    }
    result.status = FitStatus::Degenerate;
    result.message = std::string("CGAL shape detection found no ") + (hint ? quadric_type_name(requested) : "shape") +
                     " covering " + std::to_string(minimum_points) + " of " + std::to_string(points.cols()) +
                     " points (epsilon up to " +
                     std::to_string(options_.epsilon_fraction * options_.epsilon_multipliers.back() * diagonal) + " m)";
    return result;
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
