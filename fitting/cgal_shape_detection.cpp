// Every heavy CGAL template of extraction lives here (CGAL 5.5 API, doc.cgal.org/5.5):
//  - Efficient RANSAC (Schnabel et al. 2007) for static scans: planes, cylinders, spheres, cones
//    (and optionally tori), every Parameters field set explicitly; normals by CGAL jet fitting,
//    oriented toward the scanner;
//  - Shape_detection region growing of planes on a point set (the alternative plane method of
//    paper §"Quadric Extraction" step 1(b)).
#include "fitting/extraction.h"
#include "fitting/extraction_internal.h"
#include "geometry/constants.h"

#include <CGAL/Eigen_matrix.h>
#include <CGAL/Eigen_vector.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Random.h>
#include <CGAL/Shape_detection/Efficient_RANSAC.h>
#include <CGAL/Shape_detection/Region_growing/Region_growing.h>
#include <CGAL/Shape_detection/Region_growing/Region_growing_on_point_set.h>
#include <CGAL/jet_estimate_normals.h>
#include <CGAL/pca_estimate_normals.h>
#include <CGAL/property_map.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <new>
#include <numeric>
#include <random>
#include <tuple>
#include <unordered_map>

namespace quadrix {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point3 = Kernel::Point_3;
using Vector3 = Kernel::Vector_3;
using PointWithNormal = std::pair<Point3, Vector3>;
using PointWithNormalVector = std::vector<PointWithNormal>;
using PointMap = CGAL::First_of_pair_property_map<PointWithNormal>;
using NormalMap = CGAL::Second_of_pair_property_map<PointWithNormal>;

// Efficient RANSAC reorders its input (it moves random subsets to the end for its octrees), so each
// point carries the index of the simplified point it came from.
using RansacPoint = std::tuple<Point3, Vector3, std::uint32_t>;
using RansacPointVector = std::vector<RansacPoint>;
using RansacPointMap = CGAL::Nth_of_tuple_property_map<0, RansacPoint>;

// CGAL 5.5's Sphere::create_shape accepts three sampled points only when their normals point away
// from the proposed centre (planes, cylinders and cones compare |cos|), so a dome whose normals face
// a station inside it, or a ball whose normals face the wrong station, is never proposed. While this
// flag is set the normal map hands out reversed normals, so a sphere proposal can try both sides.
thread_local bool reverse_normals_for_sphere_proposal = false;

/// Normal of a RansacPoint as a readable property map (reversed while a sphere proposal asks).
struct RansacNormalMap {
  using key_type = RansacPoint;
  using value_type = Vector3;
  using reference = Vector3;
  using category = boost::readable_property_map_tag;
  friend Vector3 get(const RansacNormalMap&, const RansacPoint& item) {
    return reverse_normals_for_sphere_proposal ? -std::get<1>(item) : std::get<1>(item);
  }
};

using RansacTraits = CGAL::Shape_detection::Efficient_RANSAC_traits<Kernel, RansacPointVector, RansacPointMap, RansacNormalMap>;
using EfficientRansac = CGAL::Shape_detection::Efficient_RANSAC<RansacTraits>;
using RansacPlane = CGAL::Shape_detection::Plane<RansacTraits>;
using RansacCylinder = CGAL::Shape_detection::Cylinder<RansacTraits>;
using RansacSphere = CGAL::Shape_detection::Sphere<RansacTraits>;

/// CGAL's sphere with orientation-free proposals: when the sampled normals point toward the centre
/// (a surface scanned from inside), the proposal is repeated with the normals reversed.
class TwoSidedSphere : public RansacSphere {
 protected:
  void create_shape(const std::vector<std::size_t>& indices) override {
    RansacSphere::create_shape(indices);
    if (this->m_is_valid) return;
    reverse_normals_for_sphere_proposal = true;
    RansacSphere::create_shape(indices);
    reverse_normals_for_sphere_proposal = false;
  }
};
using RansacCone = CGAL::Shape_detection::Cone<RansacTraits>;
using RansacTorus = CGAL::Shape_detection::Torus<RansacTraits>;

Point3 to_point(const Eigen::Vector3d& p) { return Point3(p.x(), p.y(), p.z()); }

}  // namespace

namespace detail {

std::vector<std::vector<std::uint32_t>> cgal_region_growing_planes(const Eigen::Matrix3Xd& points,
                                                                   const std::vector<std::uint32_t>& candidates,
                                                                   const PlaneOptions& options) {
  if (candidates.size() < 3) return {};
  PointWithNormalVector input;
  input.reserve(candidates.size());
  for (const std::uint32_t index : candidates) input.emplace_back(to_point(points.col(index)), Vector3(0, 0, 1));
  const unsigned neighbours = static_cast<unsigned>(std::max(3, options.cgal_neighbours));
  CGAL::pca_estimate_normals<CGAL::Parallel_if_available_tag>(
      input, neighbours, CGAL::parameters::point_map(PointMap()).normal_map(NormalMap()));

  using NeighborQuery = CGAL::Shape_detection::Point_set::K_neighbor_query<Kernel, PointWithNormalVector, PointMap>;
  using RegionType =
      CGAL::Shape_detection::Point_set::Least_squares_plane_fit_region<Kernel, PointWithNormalVector, PointMap, NormalMap>;
  using Sorting = CGAL::Shape_detection::Point_set::Least_squares_plane_fit_sorting<Kernel, PointWithNormalVector,
                                                                                     NeighborQuery, PointMap>;
  using RegionGrowing = CGAL::Shape_detection::Region_growing<PointWithNormalVector, NeighborQuery, RegionType,
                                                              typename Sorting::Seed_map>;
  NeighborQuery neighbor_query(input, neighbours, PointMap());
  const double angle_deg = std::acos(std::clamp(options.normal_cosine, -1.0, 1.0)) * 180.0 / kPi;
  RegionType region_type(input, options.merge_distance, angle_deg,
                         static_cast<std::size_t>(std::max(3, options.minimum_plane_points)), PointMap(), NormalMap());
  Sorting sorting(input, neighbor_query, PointMap());
  sorting.sort();
  RegionGrowing region_growing(input, neighbor_query, region_type, sorting.seed_map());
  std::vector<std::vector<std::size_t>> regions;
  region_growing.detect(std::back_inserter(regions));
  std::vector<std::vector<std::uint32_t>> result;
  result.reserve(regions.size());
  for (const auto& region : regions) {
    result.emplace_back();
    for (const std::size_t i : region) result.back().push_back(candidates[i]);
  }
  return result;
}

}  // namespace detail

namespace {


/// One Efficient RANSAC shape in Eigen terms with the simplified points it holds.
struct DetectedShape {
  ElementClass element_class = ElementClass::Object;  ///< class the element gets
  QuadricType type = QuadricType::Invalid;            ///< plane, circular cylinder, sphere, circular cone (Invalid: torus)
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();    ///< planes: unit normal; cylinders, cones: unit axis (cones: opening side)
  Eigen::Vector3d point = Eigen::Vector3d::Zero();    ///< planes: a point on it; cylinders: an axis point; spheres: centre; cones: apex
  double size = 0.0;                                  ///< cylinders, spheres: radius, m; cones: half-angle, radians
  std::vector<std::uint32_t> members;                 ///< indices into the simplified points
  Eigen::Vector3d lower = Eigen::Vector3d::Zero();    ///< bounding box of the members
  Eigen::Vector3d upper = Eigen::Vector3d::Zero();    ///< bounding box of the members
};

/// Distance from p to the surface of a shape (planes, cylinders, spheres: exact; cones: to the nappe
/// on the axis side, the CGAL cone's).
double surface_distance(const DetectedShape& shape, const Eigen::Vector3d& p) {
  const Eigen::Vector3d d = p - shape.point;
  switch (shape.type) {
    case QuadricType::Plane: return std::abs(shape.axis.dot(d));
    case QuadricType::CircularCylinder: return std::abs((d - d.dot(shape.axis) * shape.axis).norm() - shape.size);
    case QuadricType::Sphere: return std::abs(d.norm() - shape.size);
    case QuadricType::CircularCone: {
      const double along = d.dot(shape.axis), across = (d - along * shape.axis).norm();
      return std::abs(across * std::cos(shape.size) - along * std::sin(shape.size));
    }
    default: return std::numeric_limits<double>::infinity();
  }
}

/// How well a shape explains points: RMS distance and the fraction within epsilon.
struct Agreement {
  double rms = std::numeric_limits<double>::infinity();  ///< root mean square surface distance, m
  double inside_fraction = 0.0;                          ///< fraction of the points within epsilon
};

Agreement agreement(const DetectedShape& shape, const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& members,
                    double epsilon) {
  Agreement result;
  if (members.empty()) return result;
  double squares = 0.0;
  std::size_t inside = 0;
  for (const std::uint32_t i : members) {
    const double distance = surface_distance(shape, points.col(i));
    squares += distance * distance;
    if (distance <= epsilon) ++inside;
  }
  result.rms = std::sqrt(squares / static_cast<double>(members.size()));
  result.inside_fraction = static_cast<double>(inside) / static_cast<double>(members.size());
  return result;
}

/// Least-squares plane (PCA) of the members.
DetectedShape fit_plane(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& members) {
  detail::Moments moments;
  for (const std::uint32_t i : members) moments.add(points.col(i));
  DetectedShape plane;
  plane.element_class = ElementClass::Plane;
  plane.type = QuadricType::Plane;
  plane.axis = detail::principal_axes(moments.covariance()).vectors.col(0);
  plane.point = moments.mean();
  return plane;
}

/// Least-squares circle (D = 2) or sphere (D = 3) through points given relative to their centroid:
/// Kasa's algebraic fit (|q|^2 = 2 c . q + k), then Gauss-Newton on the geometric distance |q - c| - r.
/// False when the points define none.
template <int D>
bool fit_round(const std::vector<Eigen::Matrix<double, D, 1>>& relative, Eigen::Matrix<double, D, 1>& centre, double& radius) {
  using Row = Eigen::Matrix<double, D + 1, 1>;
  using Square = Eigen::Matrix<double, D + 1, D + 1>;
  if (relative.size() < static_cast<std::size_t>(D + 1)) return false;
  Square normal_matrix = Square::Zero();
  Row right_side = Row::Zero();
  for (const auto& q : relative) {
    Row row;
    row << q, 1.0;
    normal_matrix.noalias() += row * row.transpose();
    right_side += row * q.squaredNorm();
  }
  const Row solution = normal_matrix.ldlt().solve(right_side);
  centre = 0.5 * solution.template head<D>();
  const double radius_squared = solution(D) + centre.squaredNorm();
  if (!solution.allFinite() || !(radius_squared > 0.0)) return false;
  radius = std::sqrt(radius_squared);
  for (int iteration = 0; iteration < 10; ++iteration) {
    Square jtj = Square::Zero();
    Row jtr = Row::Zero();
    for (const auto& q : relative) {
      const Eigen::Matrix<double, D, 1> d = q - centre;
      const double length = d.norm();
      if (!(length > 1e-12)) continue;
      Row jacobian;
      jacobian << -d / length, -1.0;
      jtj.noalias() += jacobian * jacobian.transpose();
      jtr += jacobian * (length - radius);
    }
    const Row step = jtj.ldlt().solve(-jtr);
    if (!step.allFinite()) return false;
    centre += step.template head<D>();
    radius += step(D);
    if (step.norm() < 1e-7) break;
  }
  return radius > 0.0 && std::isfinite(radius);
}

Eigen::Vector3d centroid_of(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& members) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const std::uint32_t i : members) sum += points.col(i);
  return sum / static_cast<double>(std::max<std::size_t>(1, members.size()));
}

/// Least-squares circular cylinder of the members with a given unit axis: a circle fit in the
/// plane across the axis. False when the points do not define a circle.
bool fit_cylinder(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& members, const Eigen::Vector3d& axis,
                  DetectedShape& cylinder) {
  const Eigen::Vector3d helper = std::abs(axis.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d u = axis.cross(helper).normalized(), v = axis.cross(u);
  const Eigen::Vector3d origin = centroid_of(points, members);
  std::vector<Eigen::Vector2d> planar;
  planar.reserve(members.size());
  for (const std::uint32_t i : members) {
    const Eigen::Vector3d d = points.col(i) - origin;
    planar.emplace_back(d.dot(u), d.dot(v));
  }
  Eigen::Vector2d centre;
  double radius = 0.0;
  if (!fit_round<2>(planar, centre, radius)) return false;
  cylinder.element_class = ElementClass::Cylinder;
  cylinder.type = QuadricType::CircularCylinder;
  cylinder.axis = axis;
  cylinder.point = origin + centre.x() * u + centre.y() * v;
  cylinder.size = radius;
  return true;
}

/// Least-squares sphere of the members. False when the points do not define one.
bool fit_sphere(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& members, DetectedShape& sphere) {
  const Eigen::Vector3d origin = centroid_of(points, members);
  std::vector<Eigen::Vector3d> relative;
  relative.reserve(members.size());
  for (const std::uint32_t i : members) relative.emplace_back(points.col(i) - origin);
  Eigen::Vector3d centre;
  double radius = 0.0;
  if (!fit_round<3>(relative, centre, radius)) return false;
  sphere.element_class = ElementClass::Sphere;
  sphere.type = QuadricType::Sphere;
  sphere.point = origin + centre;
  sphere.size = radius;
  return true;
}

/// Every k-th member, k chosen so that about 2000 remain (the cone fits' cost bound).
std::vector<std::uint32_t> cone_fit_sample(const std::vector<std::uint32_t>& members) {
  const std::size_t stride = std::max<std::size_t>(1, members.size() / 2000);
  std::vector<std::uint32_t> sample;
  for (std::size_t k = 0; k < members.size(); k += stride) sample.push_back(members[k]);
  return sample;
}

/// Levenberg-Marquardt on the point-to-cone distances of (a sample of) the members, from the
/// apex, axis and half-angle `cone` holds: 6 parameters (apex 3, axis tilt 2, half-angle 1) with a
/// numeric Jacobian. False (cone untouched) when the result is not a proper cone.
bool refine_cone(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& members, DetectedShape& cone) {
  if (members.size() < 6) return false;
  const std::vector<std::uint32_t> sample = cone_fit_sample(members);
  Eigen::Vector3d apex = cone.point, axis = cone.axis;
  double angle = cone.size;
  using Vector6 = Eigen::Matrix<double, 6, 1>;
  const auto residuals = [&](const Vector6& delta, const Eigen::Vector3d& a0, const Eigen::Vector3d& p0, double alpha0,
                             Eigen::VectorXd& out) {
    const Eigen::Vector3d helper = std::abs(a0.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    const Eigen::Vector3d t1 = a0.cross(helper).normalized(), t2 = a0.cross(t1);
    DetectedShape trial;
    trial.type = QuadricType::CircularCone;
    trial.point = p0 + delta.head<3>();
    trial.axis = (a0 + delta(3) * t1 + delta(4) * t2).normalized();
    trial.size = alpha0 + delta(5);
    out.resize(static_cast<Eigen::Index>(sample.size()));
    const double cosine = std::cos(trial.size), sine = std::sin(trial.size);
    for (std::size_t k = 0; k < sample.size(); ++k) {
      const Eigen::Vector3d d = points.col(sample[k]) - trial.point;
      const double along = d.dot(trial.axis), across = (d - along * trial.axis).norm();
      out(static_cast<Eigen::Index>(k)) = across * cosine - along * sine;
    }
    return trial;
  };
  double damping = 1e-3;
  Eigen::VectorXd current, trial_values;
  residuals(Vector6::Zero(), axis, apex, angle, current);
  for (int iteration = 0; iteration < 30; ++iteration) {
    Eigen::MatrixXd jacobian(current.size(), 6);
    for (int p = 0; p < 6; ++p) {
      Vector6 h = Vector6::Zero();
      h(p) = 1e-6 * (p < 3 ? std::max(1.0, apex.norm()) : 1.0);
      Eigen::VectorXd shifted;
      residuals(h, axis, apex, angle, shifted);
      jacobian.col(p) = (shifted - current) / h(p);
    }
    const Eigen::Matrix<double, 6, 6> jtj = jacobian.transpose() * jacobian;
    const Vector6 jtr = jacobian.transpose() * current;
    bool improved = false;
    for (int attempt = 0; attempt < 8 && !improved; ++attempt) {
      Eigen::Matrix<double, 6, 6> damped = jtj;
      damped.diagonal() += damping * jtj.diagonal().cwiseMax(1e-12);
      const Vector6 step = damped.ldlt().solve(-jtr);
      if (!step.allFinite()) return false;
      const DetectedShape moved = residuals(step, axis, apex, angle, trial_values);
      if (trial_values.squaredNorm() < current.squaredNorm()) {
        apex = moved.point, axis = moved.axis, angle = moved.size;
        current = trial_values;
        damping = std::max(1e-9, damping * 0.3);
        improved = true;
        if (step.norm() < 1e-9) iteration = 30;
      } else {
        damping *= 10.0;
      }
    }
    if (!improved) break;
  }
  if (!(angle > 0.0 && angle < 0.5 * kPi) || !apex.allFinite()) return false;
  cone.point = apex;
  cone.axis = axis;
  cone.size = angle;
  return true;
}

/// Circular cone of the members from their normals (paper §"Quadric Extraction", static scans): the
/// normals of a cone make one angle with its axis, so the axis is the direction in which the
/// (consistently oriented) normals vary least and the apex is the least-squares meet of the tangent
/// planes; Levenberg-Marquardt on the point-to-cone distances then refines apex, axis and half-angle.
/// False when the normals do not pin a cone down (a flat or nearly parallel set).
bool fit_cone(const Eigen::Matrix3Xd& points, const Eigen::Matrix3Xd& normals, const std::vector<std::uint32_t>& members,
              DetectedShape& cone) {
  if (members.size() < 6) return false;
  const std::vector<std::uint32_t> sample = cone_fit_sample(members);
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const std::uint32_t i : sample) scatter.noalias() += normals.col(i) * normals.col(i).transpose();
  const Eigen::Vector3d reference = detail::principal_axes(scatter).vectors.col(2);
  detail::Moments oriented;
  Eigen::Matrix3d plane_normal_sum = Eigen::Matrix3d::Zero();
  Eigen::Vector3d plane_offset_sum = Eigen::Vector3d::Zero();
  for (const std::uint32_t i : sample) {
    const Eigen::Vector3d n = normals.col(i).dot(reference) < 0.0 ? Eigen::Vector3d(-normals.col(i)) : Eigen::Vector3d(normals.col(i));
    oriented.add(n);
    plane_normal_sum.noalias() += n * n.transpose();
    plane_offset_sum += n * n.dot(points.col(i));
  }
  const detail::Principal spread = detail::principal_axes(oriented.covariance());
  if (!(spread.values(1) > 1e-6)) return false;  // normals on one line or a point: no axis
  Eigen::Vector3d axis = spread.vectors.col(0);
  const Eigen::FullPivLU<Eigen::Matrix3d> solver(plane_normal_sum);
  if (!solver.isInvertible()) return false;
  Eigen::Vector3d apex = solver.solve(plane_offset_sum);
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const std::uint32_t i : sample) centroid += points.col(i);
  centroid /= static_cast<double>(sample.size());
  if (axis.dot(centroid - apex) < 0.0) axis = -axis;
  double angle = 0.0;
  for (const std::uint32_t i : sample) angle += std::acos(std::clamp(axis.dot((points.col(i) - apex).normalized()), -1.0, 1.0));
  angle /= static_cast<double>(sample.size());
  if (!apex.allFinite() || !std::isfinite(angle)) return false;
  cone = DetectedShape();
  cone.element_class = ElementClass::Cone;
  cone.type = QuadricType::CircularCone;
  cone.point = apex;
  cone.axis = axis;
  cone.size = angle;
  return refine_cone(points, members, cone);
}

void update_bounds(const Eigen::Matrix3Xd& points, DetectedShape& shape) {
  shape.lower = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  shape.upper = -shape.lower;
  for (const std::uint32_t i : shape.members) {
    shape.lower = shape.lower.cwiseMin(points.col(i));
    shape.upper = shape.upper.cwiseMax(points.col(i));
  }
}

/// Whether the bounding boxes of `a` and `b` lie within `gap` of each other on every axis.
bool boxes_within(const DetectedShape& a, const DetectedShape& b, double gap) {
  return !((b.lower - a.upper).array() > gap).any() && !((a.lower - b.upper).array() > gap).any();
}

/// Whether some point of `b` lies within `gap` of a point of `a` (points hashed in cells of `gap`).
/// gap <= 0: always true.
bool pieces_within(const Eigen::Matrix3Xd& points, const DetectedShape& a, const DetectedShape& b, double gap) {
  if (!(gap > 0.0)) return true;
  if (!boxes_within(a, b, gap)) return false;
  const DetectedShape& indexed = a.members.size() <= b.members.size() ? a : b;
  const DetectedShape& queried = a.members.size() <= b.members.size() ? b : a;
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> cells;
  const auto cell = [&](std::uint32_t i) { return Eigen::Vector3i((points.col(i) / gap).array().floor().cast<int>()); };
  for (const std::uint32_t i : indexed.members) {
    const Eigen::Vector3i c = cell(i);
    cells[detail::voxel_key(c.x(), c.y(), c.z())].push_back(i);
  }
  const double gap_squared = gap * gap;
  for (const std::uint32_t i : queried.members) {
    const Eigen::Vector3i c = cell(i);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto found = cells.find(detail::voxel_key(c.x() + dx, c.y() + dy, c.z() + dz));
          if (found == cells.end()) continue;
          for (const std::uint32_t j : found->second)
            if ((points.col(i) - points.col(j)).squaredNorm() <= gap_squared) return true;
        }
  }
  return false;
}

bool explains(const DetectedShape& candidate, const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& members,
              const ShapeDetectionOptions& shape_options);

/// The same shape refitted to `members` (planes, cylinders with the given axis, spheres, cones
/// from the shape's parameters, else from the normals). False when the fit fails.
bool refit(const Eigen::Matrix3Xd& points, const Eigen::Matrix3Xd& normals, const std::vector<std::uint32_t>& members,
           const DetectedShape& shape, const ShapeDetectionOptions& shape_options, DetectedShape& refitted) {
  refitted = shape;
  switch (shape.type) {
    case QuadricType::Plane: refitted = fit_plane(points, members); break;
    case QuadricType::CircularCylinder: if (!fit_cylinder(points, members, shape.axis, refitted)) return false; break;
    case QuadricType::Sphere: if (!fit_sphere(points, members, refitted)) return false; break;
    case QuadricType::CircularCone:
      // From the shape's own apex, axis and angle first: the normals of two partial arcs can pin
      // the axis down worse than either piece's cone (two quarters of a roof ring), then from the
      // normals alone.
      if (!refine_cone(points, members, refitted) || !explains(refitted, points, members, shape_options)) {
        refitted = shape;
        if (!fit_cone(points, normals, members, refitted)) return false;
      }
      break;
    default: return false;
  }
  refitted.members = members;
  return true;
}

/// Whether `candidate` explains the points `members`: RMS distance and the fraction within epsilon
/// inside the explained_rms / explained_fraction bounds of the options.
bool explains(const DetectedShape& candidate, const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& members,
              const ShapeDetectionOptions& shape_options) {
  const double epsilon = shape_options.epsilon;
  const Agreement fit = agreement(candidate, points, members, epsilon);
  return fit.rms <= shape_options.explained_rms * epsilon && fit.inside_fraction >= shape_options.explained_fraction;
}

/// The smallest cone half-angle that is not a cylinder in disguise, radians.
double minimum_cone_angle(const ShapeDetectionOptions& shape_options) {
  return shape_options.minimum_cone_angle_deg * kPi / 180.0;
}

/// Grid simplification: one representative per voxel of edge `voxel` (voxel <= 0: every point is
/// its own); every point follows its representative (`representative_of_point` indexes `representatives`).
void simplify_on_grid(const Eigen::Matrix3Xd& points, double voxel, std::vector<std::uint32_t>& representative_of_point,
                      std::vector<std::uint32_t>& representatives) {
  const std::size_t count = static_cast<std::size_t>(points.cols());
  representative_of_point.assign(count, 0);
  representatives.clear();
  if (voxel > 0.0) {
    std::unordered_map<std::uint64_t, std::uint32_t> voxel_representative;
    voxel_representative.reserve(count / 4 + 16);
    const double inverse = 1.0 / voxel;
    for (std::uint32_t i = 0; i < count; ++i) {
      const Eigen::Vector3i c((points.col(i) * inverse).array().floor().cast<int>());
      auto [it, inserted] = voxel_representative.try_emplace(detail::voxel_key(c.x(), c.y(), c.z()),
                                                             static_cast<std::uint32_t>(representatives.size()));
      if (inserted) representatives.push_back(i);
      representative_of_point[i] = it->second;
    }
  } else {
    representatives.resize(count);
    for (std::uint32_t i = 0; i < count; ++i) representatives[i] = representative_of_point[i] = i;
  }
}

/// The representatives as CGAL points with normals: the cloud's own normals when it has them, else
/// +z as the initial value that detect_shapes always overwrites with estimate_oriented_normals.
PointWithNormalVector representatives_with_normals(const Eigen::Matrix3Xd& points, const Eigen::Matrix3Xd& normals,
                                                   bool have_normals, const std::vector<std::uint32_t>& representatives) {
  PointWithNormalVector input;
  input.reserve(representatives.size());
  for (const std::uint32_t index : representatives) {
    const Eigen::Vector3d n = have_normals ? Eigen::Vector3d(normals.col(index)) : Eigen::Vector3d::UnitZ();
    input.emplace_back(to_point(points.col(index)), Vector3(n.x(), n.y(), n.z()));
  }
  return input;
}

/// The least-squares solver of CGAL's jet fitting (its SvdTraits concept, as CGAL::Eigen_svd): a
/// complete orthogonal decomposition (column-pivoted QR, then QR of R's transpose) gives the same
/// minimum-norm least-squares solution as Eigen_svd's Jacobi SVD, which took about 19% of a tiled
/// survey's modelling CPU (`perf`, the 24.9 M-point site) for the 18 x 6 systems of a degree-2 jet.
/// The condition number is estimated from the pivoted R's diagonal (jet normals do not read it).
struct OrthogonalDecompositionSolver {
  typedef double FT;
  typedef CGAL::Eigen_vector<FT> Vector;
  typedef CGAL::Eigen_matrix<FT> Matrix;
  static FT solve(const Matrix& m, Vector& b) {
    const Eigen::CompleteOrthogonalDecomposition<Matrix::EigenType> decomposition(m.eigen_object());
    b.eigen_object() = decomposition.solve(Vector::EigenType(b.eigen_object()));
    const auto diagonal = decomposition.matrixQTZ().diagonal().cwiseAbs();
    return diagonal.minCoeff() > 0.0 ? diagonal.maxCoeff() / diagonal.minCoeff() : std::numeric_limits<FT>::infinity();
  }
};

/// Normals by CGAL jet fitting over `neighbours` neighbours, oriented toward the scanner (a TLS
/// station sees the outside of each surface).
void estimate_oriented_normals(PointWithNormalVector& input, int neighbours, const Eigen::Vector3d& sensor_origin) {
  if (input.size() >= 3) {
    CGAL::jet_estimate_normals<CGAL::Parallel_if_available_tag>(
        input, static_cast<unsigned>(std::max(3, neighbours)),
        CGAL::parameters::point_map(PointMap()).normal_map(NormalMap()).svd_traits(OrthogonalDecompositionSolver()));
  }
  for (PointWithNormal& item : input) {
    const Eigen::Vector3d p(item.first.x(), item.first.y(), item.first.z());
    const Eigen::Vector3d n(item.second.x(), item.second.y(), item.second.z());
    if (n.dot(sensor_origin - p) < 0.0) item.second = -item.second;
  }
}

/// A shape found by Efficient RANSAC in Eigen terms, holding the simplified points it was assigned.
/// Planes are refitted by least squares (CGAL's plane from its last refit may be off on far, sparse
/// pieces); tori stay Object (not quadrics; fitted as ellipsoids).
DetectedShape detected_shape_of(const EfficientRansac::Shape& shape, const RansacPointVector& ransac_input,
                                const Eigen::Matrix3Xd& simplified) {
  const auto vector = [](const Vector3& v) { return Eigen::Vector3d(v.x(), v.y(), v.z()); };
  const auto point = [](const Point3& p) { return Eigen::Vector3d(p.x(), p.y(), p.z()); };
  DetectedShape detected;
  for (const std::size_t i : shape.indices_of_assigned_points()) detected.members.push_back(std::get<2>(ransac_input[i]));
  if (dynamic_cast<const RansacPlane*>(&shape) != nullptr) {
    detected = fit_plane(simplified, detected.members);
    for (const std::size_t i : shape.indices_of_assigned_points()) detected.members.push_back(std::get<2>(ransac_input[i]));
  } else if (const auto* cylinder = dynamic_cast<const RansacCylinder*>(&shape)) {
    const auto axis = cylinder->axis();
    detected.element_class = ElementClass::Cylinder;
    detected.type = QuadricType::CircularCylinder;
    detected.axis = vector(axis.to_vector()).normalized();
    detected.point = point(axis.point(0));
    detected.size = cylinder->radius();
  } else if (const auto* sphere = dynamic_cast<const RansacSphere*>(&shape)) {
    detected.element_class = ElementClass::Sphere;
    detected.type = QuadricType::Sphere;
    detected.point = point(sphere->center());
    detected.size = sphere->radius();
  } else if (const auto* cone = dynamic_cast<const RansacCone*>(&shape)) {
    detected.element_class = ElementClass::Cone;
    detected.type = QuadricType::CircularCone;
    detected.axis = vector(cone->axis()).normalized();
    detected.point = point(cone->apex());
    detected.size = cone->angle();
  }
  update_bounds(simplified, detected);
  return detected;
}

/// Efficient RANSAC on the simplified points with every Parameters field from the options (seeded
/// for deterministic runs), appending the shapes found to `shapes`. Nothing runs on fewer than
/// minimum_points points. False when Efficient RANSAC ran out of memory.
bool detect_ransac_shapes(const PointWithNormalVector& input, const Eigen::Matrix3Xd& simplified,
                          const ShapeDetectionOptions& shape_options, std::vector<DetectedShape>& shapes) {
  if (input.size() < static_cast<std::size_t>(std::max(3, shape_options.minimum_points))) return true;
  CGAL::get_default_random() = CGAL::Random(shape_options.seed);
  RansacPointVector ransac_input;
  ransac_input.reserve(input.size());
  for (std::uint32_t i = 0; i < input.size(); ++i) ransac_input.emplace_back(input[i].first, input[i].second, i);
  EfficientRansac ransac;
  ransac.set_input(ransac_input, RansacPointMap(), RansacNormalMap());
  if (shape_options.detect_planes) ransac.add_shape_factory<RansacPlane>();
  if (shape_options.detect_cylinders) ransac.add_shape_factory<RansacCylinder>();
  if (shape_options.detect_spheres) ransac.add_shape_factory<TwoSidedSphere>();
  if (shape_options.detect_cones) ransac.add_shape_factory<RansacCone>();
  if (shape_options.detect_tori) ransac.add_shape_factory<RansacTorus>();
  EfficientRansac::Parameters parameters;
  parameters.probability = shape_options.probability;
  parameters.min_points = static_cast<std::size_t>(std::max(1, shape_options.minimum_points));
  parameters.epsilon = shape_options.epsilon;
  parameters.cluster_epsilon = shape_options.cluster_epsilon;
  parameters.normal_threshold = shape_options.normal_threshold;
  try {
    ransac.preprocess();
    ransac.detect(parameters);
  } catch (const std::bad_alloc&) {
    return false;
  }
  for (const auto& shape : ransac.shapes()) shapes.push_back(detected_shape_of(*shape, ransac_input, simplified));
  return true;
}

/// The simplest quadric that explains a shape's points replaces it: Efficient RANSAC returns strips
/// of a large floor as cylinders of huge radius, and columns as cones of a tiny angle.
void replace_by_simplest_quadrics(std::vector<DetectedShape>& shapes, const Eigen::Matrix3Xd& simplified,
                                  const Eigen::Matrix3Xd& simplified_normals, const ShapeDetectionOptions& shape_options) {
  const double epsilon = shape_options.epsilon;
  const double minimum_angle = minimum_cone_angle(shape_options);
  for (DetectedShape& shape : shapes) {
    if (shape.type == QuadricType::Plane || shape.type == QuadricType::Invalid) continue;
    DetectedShape simpler = fit_plane(simplified, shape.members);
    simpler.members = shape.members;
    if (explains(simpler, simplified, shape.members, shape_options)) {
      simpler.lower = shape.lower, simpler.upper = shape.upper;
      shape = std::move(simpler);
      continue;
    }
    // A cone narrower than minimum_cone_angle_deg is a cylinder (a column piece) even where its
    // few extra parameters fit the noise a little better.
    if (shape.type == QuadricType::CircularCone && fit_cylinder(simplified, shape.members, shape.axis, simpler) &&
        (shape.size < minimum_angle || explains(simpler, simplified, shape.members, shape_options))) {
      simpler.lower = shape.lower, simpler.upper = shape.upper;
      shape = std::move(simpler);
      continue;
    }
    // The other way round: a piece of a wide cone seen from afar (noisy normals, so Efficient RANSAC
    // never proposes the cone) comes back as a cylinder; a cone fitted from its normals that halves
    // the distances of a cylinder on the same points replaces it.
    DetectedShape cone, cylinder;
    if (shape.type == QuadricType::CircularCylinder && fit_cylinder(simplified, shape.members, shape.axis, cylinder) &&
        fit_cone(simplified, simplified_normals, shape.members, cone) &&
        cone.size >= minimum_angle && explains(cone, simplified, shape.members, shape_options) &&
        agreement(cone, simplified, shape.members, epsilon).rms <=
            0.5 * agreement(cylinder, simplified, shape.members, epsilon).rms) {
      cone.members = std::move(shape.members);
      cone.lower = shape.lower, cone.upper = shape.upper;
      shape = std::move(cone);
    }
  }
}

/// Joins `piece` to `cone` when the cone, refined on the points of both from its own parameters,
/// stays at least `minimum_angle` wide and explains them all: `cone` then holds both pieces' points
/// and box and `piece` is left empty. Returns whether it joined.
bool join_into_cone(DetectedShape& cone, DetectedShape& piece, const Eigen::Matrix3Xd& points,
                    const ShapeDetectionOptions& options, double minimum_angle) {
  std::vector<std::uint32_t> united = cone.members;
  united.insert(united.end(), piece.members.begin(), piece.members.end());
  DetectedShape joined = cone;
  if (!refine_cone(points, united, joined) || joined.size < minimum_angle || !explains(joined, points, united, options))
    return false;
  joined.members = std::move(united);
  joined.lower = cone.lower.cwiseMin(piece.lower);
  joined.upper = cone.upper.cwiseMax(piece.upper);
  cone = std::move(joined);
  piece.members.clear();
  return true;
}

/// A band of a wide cone close to a station can come back as a tilted cylinder whose own cone fit
/// (from noisy normals) goes astray, while a smaller patch of the same cone is found as a cone
/// (whose angle a small patch pins down poorly). When the cone, refined on the points of both from
/// its own parameters, explains them all, the piece joins it (and is left empty).
/// Cones narrower than minimum_cone_angle_deg are cylinders in disguise (a column) and take no part.
void join_cylinder_pieces_to_cones(std::vector<DetectedShape>& shapes, const Eigen::Matrix3Xd& simplified,
                                   const ShapeDetectionOptions& shape_options) {
  const double minimum_angle = minimum_cone_angle(shape_options);
  for (DetectedShape& cone : shapes) {
    if (cone.type != QuadricType::CircularCone || cone.size < minimum_angle) continue;
    for (DetectedShape& piece : shapes) {
      if (piece.type != QuadricType::CircularCylinder || piece.members.empty()) continue;
      join_into_cone(cone, piece, simplified, shape_options, minimum_angle);
    }
  }
}

/// Efficient RANSAC keeps the largest connected piece of each candidate, so one surface cut by
/// occlusion shadows (a plaza behind columns) or seen in arcs from several stations (a column)
/// returns as several shapes of similar parameters. A smaller shape joins a larger one of its type
/// (shapes sorted by decreasing size) when their parameters are close and one refitted shape
/// explains the points of both; the smaller one is left empty.
void merge_similar_shapes(std::vector<DetectedShape>& shapes, const Eigen::Matrix3Xd& simplified,
                          const Eigen::Matrix3Xd& simplified_normals, const ShapeDetectionOptions& shape_options,
                          const Eigen::Vector3d& up_direction) {
  const double cos_angle = std::cos(shape_options.merge_angle_deg * kPi / 180.0);
  const double cos_ten_degrees = std::cos(10.0 * kPi / 180.0);
  const Eigen::Vector3d up = up_direction.normalized();
  const double distance = shape_options.merge_distance;
  const DetectedShape* ground_candidate = nullptr;
  for (const DetectedShape& shape : shapes)
    if (ground_candidate == nullptr && shape.type == QuadricType::Plane && std::abs(shape.axis.dot(up)) >= cos_ten_degrees)
      ground_candidate = &shape;
  const auto similar_size = [&](double a, double b) {
    return std::abs(a - b) <= shape_options.merge_radius_fraction * std::max(a, b);
  };
  const auto close = [&](const DetectedShape& a, const DetectedShape& b) {
    if (a.type != b.type) return false;
    const Eigen::Vector3d offset = b.point - a.point;
    switch (a.type) {
      case QuadricType::Plane:
        // Coplanar faces far apart stay apart (a podium and an entablature in one plane), except on
        // the largest near-horizontal plane: the ground, shadowed by everything on it.
        return std::abs(a.axis.dot(b.axis)) >= cos_angle && std::abs(a.axis.dot(offset)) <= distance &&
               (&a == ground_candidate ||
                pieces_within(simplified, a, b, shape_options.merge_plane_gap));
      case QuadricType::CircularCylinder:
        return std::abs(a.axis.dot(b.axis)) >= cos_angle && similar_size(a.size, b.size) &&
               (offset - offset.dot(a.axis) * a.axis).norm() <= distance + std::max(a.size, b.size) * shape_options.merge_radius_fraction;
      case QuadricType::Sphere:
        return similar_size(a.size, b.size) && offset.norm() <= distance + std::max(a.size, b.size) * shape_options.merge_radius_fraction;
      case QuadricType::CircularCone:
        // Apexes of wide cones fitted to pieces lie far from the points: axes and angles gate, and
        // the pieces' boxes lie no farther apart than the larger box is across (or merge_plane_gap):
        // two arcs of one roof ring may be apart by a third arc that a tile found as another shape,
        // while the equal roof rings of a survey's buildings are not refitted pair by pair. A
        // narrow strip of a wide cone (a tile's sliver of a roof ring) pins its axis and angle down
        // poorly, so a piece also joins when the other's cone explains its points.
        if (!boxes_within(a, b, std::max({shape_options.merge_plane_gap, (a.upper - a.lower).norm(), (b.upper - b.lower).norm()})))
          return false;
        return (a.axis.dot(b.axis) >= cos_angle && std::abs(a.size - b.size) <= shape_options.merge_angle_deg * kPi / 180.0) ||
               explains(a, simplified, b.members, shape_options) || explains(b, simplified, a.members, shape_options);
      default: return false;
    }
  };
  // The refit of two pieces starts from the larger's parameters, and for cones also from the
  // smaller's: the better-determined piece is not always the larger one.
  const auto joint_refit = [&](const DetectedShape& a, const DetectedShape& b, const std::vector<std::uint32_t>& united,
                               DetectedShape& candidate) {
    if (refit(simplified, simplified_normals, united, a, shape_options, candidate) &&
        explains(candidate, simplified, united, shape_options))
      return true;
    return a.type == QuadricType::CircularCone && refine_cone(simplified, united, candidate = b) &&
           explains(candidate, simplified, united, shape_options);
  };
  for (std::size_t b = 1; b < shapes.size(); ++b) {
    for (std::size_t a = 0; a < b; ++a) {
      if (shapes[a].members.empty() || !close(shapes[a], shapes[b])) continue;
      std::vector<std::uint32_t> united = shapes[a].members;
      united.insert(united.end(), shapes[b].members.begin(), shapes[b].members.end());
      DetectedShape candidate;
      if (!joint_refit(shapes[a], shapes[b], united, candidate)) continue;
      candidate.members = united;
      candidate.lower = shapes[a].lower.cwiseMin(shapes[b].lower);
      candidate.upper = shapes[a].upper.cwiseMax(shapes[b].upper);
      shapes[a] = std::move(candidate);
      shapes[b].members.clear();
      break;
    }
  }
}

/// A shape whose points larger shapes already explain (a strip of a column taken for a plane, a
/// band of a dome, the seam where two walls meet) adds nothing: when at least absorb_fraction of its
/// points lie within epsilon of larger shapes, each goes to the nearest of them, the rest are left
/// out, and the shape is left empty. Shapes are sorted by decreasing size.
void absorb_explained_shapes(std::vector<DetectedShape>& shapes, const Eigen::Matrix3Xd& simplified,
                             const ShapeDetectionOptions& shape_options) {
  const double epsilon = shape_options.epsilon;
  const double reach = shape_options.cluster_epsilon;
  for (std::size_t s = shapes.size(); s-- > 1;) {
    DetectedShape& small = shapes[s];
    if (small.members.empty()) continue;
    std::vector<int> explainer(small.members.size(), -1);
    std::size_t explained = 0;
    for (std::size_t k = 0; k < small.members.size(); ++k) {
      const Eigen::Vector3d p = simplified.col(small.members[k]);
      double best = epsilon;
      for (std::size_t l = 0; l < s; ++l) {
        const DetectedShape& large = shapes[l];
        if (large.members.empty() || (p.array() < large.lower.array() - reach).any() ||
            (p.array() > large.upper.array() + reach).any())
          continue;
        const double d = surface_distance(large, p);
        if (d <= best) best = d, explainer[k] = static_cast<int>(l);
      }
      if (explainer[k] >= 0) ++explained;
    }
    if (static_cast<double>(explained) < shape_options.absorb_fraction * static_cast<double>(small.members.size())) continue;
    for (std::size_t k = 0; k < small.members.size(); ++k) {
      if (explainer[k] < 0) continue;
      DetectedShape& large = shapes[static_cast<std::size_t>(explainer[k])];
      large.members.push_back(small.members[k]);
      large.lower = large.lower.cwiseMin(simplified.col(small.members[k]));
      large.upper = large.upper.cwiseMax(simplified.col(small.members[k]));
    }
    small.members.clear();
  }
}

/// One element per shape, holding every original point whose representative the shape holds.
std::vector<Element> elements_of_shapes(const std::vector<DetectedShape>& shapes, std::size_t representative_count,
                                        const std::vector<std::uint32_t>& representative_of_point) {
  std::vector<int> shape_of_representative(representative_count, -1);
  for (std::size_t id = 0; id < shapes.size(); ++id)
    for (const std::uint32_t i : shapes[id].members) shape_of_representative[i] = static_cast<int>(id);
  std::vector<Element> elements(shapes.size());
  for (std::size_t id = 0; id < shapes.size(); ++id) {
    elements[id].element_class = shapes[id].element_class;
    elements[id].detected_type = shapes[id].type;
  }
  for (std::uint32_t i = 0; i < representative_of_point.size(); ++i) {
    const int id = shape_of_representative[representative_of_point[i]];
    if (id >= 0) elements[static_cast<std::size_t>(id)].point_indices.push_back(i);
  }
  return elements;
}

/// Ground: the lowest of the large near-horizontal planes (within 10 deg of `up_direction`, at least
/// a tenth of the largest one's points) becomes the Ground element, moved to the front, and its PCA
/// plane fills the result's ground fields.
void mark_ground_element(const std::vector<DetectedShape>& shapes, const Eigen::Matrix3Xd& points,
                         const Eigen::Vector3d& up_direction, std::vector<Element>& elements,
                         std::vector<detail::ShapeParameters>& parameters, ExtractionResult& result) {
  const Eigen::Vector3d up = up_direction.normalized();
  const double cos_ten_degrees = std::cos(10.0 * kPi / 180.0);
  std::size_t largest = 0;
  for (std::size_t id = 0; id < shapes.size(); ++id)
    if (shapes[id].type == QuadricType::Plane && std::abs(shapes[id].axis.dot(up)) >= cos_ten_degrees)
      largest = std::max(largest, elements[id].point_indices.size());
  int ground = -1;
  double ground_height = 1e300;
  for (std::size_t id = 0; id < shapes.size(); ++id) {
    if (shapes[id].type != QuadricType::Plane || std::abs(shapes[id].axis.dot(up)) < cos_ten_degrees) continue;
    if (elements[id].point_indices.size() * 10 < largest) continue;
    double height = 0.0;
    for (const std::uint32_t index : elements[id].point_indices) height += up.dot(points.col(index));
    height /= static_cast<double>(elements[id].point_indices.size());
    if (height < ground_height) {
      ground_height = height;
      ground = static_cast<int>(id);
    }
  }
  if (ground < 0) return;
  Element& element = elements[static_cast<std::size_t>(ground)];
  element.element_class = ElementClass::Ground;
  detail::Moments moments;
  for (const std::uint32_t index : element.point_indices) moments.add(points.col(index));
  Eigen::Vector3d normal = detail::principal_axes(moments.covariance()).vectors.col(0);
  if (normal.dot(up) < 0) normal = -normal;
  result.has_ground = true;
  result.ground_normal = normal;
  result.ground_offset = -normal.dot(moments.mean());
  std::rotate(elements.begin(), elements.begin() + ground, elements.begin() + ground + 1);
  std::rotate(parameters.begin(), parameters.begin() + ground, parameters.begin() + ground + 1);
}

}  // namespace

namespace {

/// Unit surface normal of a shape at p (the side does not matter to the refits).
Eigen::Vector3d surface_normal(const DetectedShape& shape, const Eigen::Vector3d& p) {
  const Eigen::Vector3d d = p - shape.point;
  const Eigen::Vector3d radial = d - d.dot(shape.axis) * shape.axis;
  Eigen::Vector3d normal = shape.axis;
  switch (shape.type) {
    case QuadricType::CircularCylinder: normal = radial; break;
    case QuadricType::Sphere: normal = d; break;
    case QuadricType::CircularCone:
      if (radial.norm() > 1e-12) normal = std::cos(shape.size) * radial.normalized() - std::sin(shape.size) * shape.axis;
      break;
    default: break;
  }
  return normal.norm() > 1e-12 ? Eigen::Vector3d(normal.normalized()) : Eigen::Vector3d(shape.axis);
}

}  // namespace

namespace {

/// Whether at most three planes explain `members` as well as a shape must (explained_rms,
/// explained_fraction): the seam of two faces meeting at an angle, which a cone of half the angle
/// between their normals fits locally (two walls at a right angle: a 45-degree cone along their
/// corner), or the corner where a third face meets them (the step at the end of a podium's side
/// wall, with a strip of the floor above it). Each plane is the best of 256 planes through three
/// of the members its predecessors leave, drawn with the options' seed (deterministic), refitted
/// to its inliers. A cone's arc needs more than three chords within epsilon unless it is shorter
/// than about 3 * sqrt(8 r epsilon) (8.5 m of a 20 m-radius ring at 0.05 m), so only such a short
/// piece of a true cone that joined no other piece is dissolved with the seams.
bool few_planes_explain(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& members,
                        const ShapeDetectionOptions& options) {
  if (members.size() < 6) return false;
  const double epsilon = options.epsilon;
  std::mt19937 random(options.seed);
  const auto best_plane = [&](const std::vector<std::uint32_t>& pool, DetectedShape& plane) {
    if (pool.size() < 3) return false;
    std::uniform_int_distribution<std::size_t> pick(0, pool.size() - 1);
    std::size_t best_count = 0;
    Eigen::Vector3d best_normal = Eigen::Vector3d::UnitZ(), best_point = Eigen::Vector3d::Zero();
    for (int draw = 0; draw < 256; ++draw) {
      const Eigen::Vector3d a = points.col(pool[pick(random)]), b = points.col(pool[pick(random)]), c = points.col(pool[pick(random)]);
      const Eigen::Vector3d normal = (b - a).cross(c - a);
      if (!(normal.norm() > 1e-9)) continue;
      const Eigen::Vector3d unit = normal.normalized();
      std::size_t count = 0;
      for (const std::uint32_t i : pool) count += std::abs(unit.dot(points.col(i) - a)) <= epsilon ? 1 : 0;
      if (count > best_count) best_count = count, best_normal = unit, best_point = a;
    }
    if (best_count < 3) return false;
    std::vector<std::uint32_t> inliers;
    for (const std::uint32_t i : pool)
      if (std::abs(best_normal.dot(points.col(i) - best_point)) <= epsilon) inliers.push_back(i);
    plane = fit_plane(points, inliers);
    return true;
  };
  std::vector<DetectedShape> planes;
  std::vector<std::uint32_t> rest = members;
  const double count = static_cast<double>(members.size());
  for (int plane_count = 1; plane_count <= 3 && !rest.empty(); ++plane_count) {
    DetectedShape plane;
    if (!best_plane(rest, plane)) break;
    planes.push_back(plane);
    std::vector<std::uint32_t> left;
    for (const std::uint32_t i : rest)
      if (surface_distance(plane, points.col(i)) > epsilon) left.push_back(i);
    rest.swap(left);
    double squares = 0.0;
    std::size_t inside = 0;
    for (const std::uint32_t i : members) {
      double d = std::numeric_limits<double>::infinity();
      for (const DetectedShape& face : planes) d = std::min(d, surface_distance(face, points.col(i)));
      squares += d * d;
      inside += d <= epsilon ? 1 : 0;
    }
    if (plane_count >= 2 && std::sqrt(squares / count) <= options.explained_rms * epsilon &&
        static_cast<double>(inside) >= options.explained_fraction * count)
      return true;
  }
  return false;
}

}  // namespace

namespace detail {

std::vector<int> merge_shape_pieces(std::vector<ShapePiece>& pieces, const ShapeDetectionOptions& options,
                                    const Eigen::Vector3d& up) {
  std::vector<int> order(pieces.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return pieces[a].weight > pieces[b].weight; });
  Eigen::Index total = 0;
  for (const ShapePiece& piece : pieces) total += piece.points.cols();
  Eigen::Matrix3Xd points(3, total), normals(3, total);
  std::vector<DetectedShape> shapes(pieces.size());
  std::vector<int> piece_of_point(static_cast<std::size_t>(total));
  Eigen::Index column = 0;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const ShapePiece& piece = pieces[static_cast<std::size_t>(order[k])];
    DetectedShape& shape = shapes[k];
    shape.type = piece.type;
    shape.element_class = piece.type == QuadricType::Plane              ? ElementClass::Plane
                          : piece.type == QuadricType::CircularCylinder ? ElementClass::Cylinder
                          : piece.type == QuadricType::Sphere           ? ElementClass::Sphere
                                                                        : ElementClass::Cone;
    shape.axis = piece.axis.normalized();
    shape.point = piece.point;
    shape.size = piece.size;
    for (Eigen::Index i = 0; i < piece.points.cols(); ++i, ++column) {
      points.col(column) = piece.points.col(i);
      normals.col(column) = surface_normal(shape, piece.points.col(i));
      shape.members.push_back(static_cast<std::uint32_t>(column));
      piece_of_point[static_cast<std::size_t>(column)] = static_cast<int>(k);
    }
    update_bounds(points, shape);
  }
  // Two pieces of one primitive may touch only through a third that comes later in the order (a
  // wall cut by tiles of different sizes: its far piece meets the joined shape only once the piece
  // between them has joined), so the pass runs again until no piece joins.
  const auto held_shapes = [&] {
    return std::count_if(shapes.begin(), shapes.end(), [](const DetectedShape& shape) { return !shape.members.empty(); });
  };
  for (auto held = held_shapes(); shapes.size() > 1;) {
    merge_similar_shapes(shapes, points, normals, options, up);
    const auto now = held_shapes();
    if (now == held) break;
    held = now;
  }
  // A band of a wide cone that a tile took for a tilted cylinder (join_cylinder_pieces_to_cones
  // within one cloud) joins the cone when the cone already explains its points and, refined on
  // both, explains them all; the cone's own pieces are joined by now, so its parameters are those
  // of the whole surface.
  const double minimum_angle = minimum_cone_angle(options);
  for (DetectedShape& cone : shapes) {
    if (cone.type != QuadricType::CircularCone || cone.members.empty() || cone.size < minimum_angle) continue;
    for (DetectedShape& piece : shapes) {
      if (piece.type != QuadricType::CircularCylinder || piece.members.empty() || !boxes_within(cone, piece, options.cluster_epsilon) ||
          !explains(cone, points, piece.members, options))
        continue;
      join_into_cone(cone, piece, points, options, minimum_angle);
    }
  }
  // Joined pieces: each sorted piece's first point tells which kept shape now holds it.
  std::vector<int> holder_of_point(static_cast<std::size_t>(total), -1);
  for (std::size_t k = 0; k < shapes.size(); ++k)
    for (const std::uint32_t i : shapes[k].members) holder_of_point[i] = static_cast<int>(k);
  std::vector<int> holder_of_piece(shapes.size());
  column = 0;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const ShapePiece& piece = pieces[static_cast<std::size_t>(order[k])];
    holder_of_piece[k] = piece.points.cols() > 0 && holder_of_point[static_cast<std::size_t>(column)] >= 0
                             ? holder_of_point[static_cast<std::size_t>(column)]
                             : static_cast<int>(k);
    column += piece.points.cols();
  }
  // A primitive the larger ones explain is dissolved, as detect_shapes dissolves such a shape within
  // one cloud (the seam of two walls a tile took for a 45-degree cone, with the walls' pieces in
  // its neighbours): its pieces are left out, since their points cannot be split between the
  // larger primitives any more. Larger is judged by the joined primitives' points, not by their
  // largest pieces': a tile's cone along the corner of a podium holds more points than that tile's
  // pieces of the podium's faces, but not than the faces joined over their tiles.
  std::vector<bool> dissolved(shapes.size(), false);
  if (options.absorb_fraction <= 1.0) {
    std::vector<double> joined_weight(shapes.size(), 0.0);
    for (std::size_t k = 0; k < order.size(); ++k)
      joined_weight[static_cast<std::size_t>(holder_of_piece[k])] += pieces[static_cast<std::size_t>(order[k])].weight;
    std::vector<std::size_t> by_weight(shapes.size());
    std::iota(by_weight.begin(), by_weight.end(), std::size_t{0});
    std::stable_sort(by_weight.begin(), by_weight.end(),
                     [&](std::size_t a, std::size_t b) { return joined_weight[a] > joined_weight[b]; });
    std::vector<DetectedShape> sorted(shapes.size());
    for (std::size_t k = 0; k < by_weight.size(); ++k) sorted[k] = shapes[by_weight[k]];
    absorb_explained_shapes(sorted, points, options);
    for (std::size_t k = 0; k < by_weight.size(); ++k)
      dissolved[by_weight[k]] = !shapes[by_weight[k]].members.empty() && sorted[k].members.empty();
  }
  // A cone that two or three planes explain is the seam or corner of faces whose larger pieces lie
  // in other tiles (or that the cone took whole in its tile).
  for (std::size_t k = 0; k < shapes.size(); ++k)
    if (shapes[k].type == QuadricType::CircularCone && !shapes[k].members.empty() &&
        few_planes_explain(points, shapes[k].members, options)) {
      shapes[k].members.clear();
      dissolved[k] = true;
    }
  std::vector<int> joined(pieces.size());
  for (std::size_t k = 0; k < order.size(); ++k) {
    const int holder = holder_of_piece[k];
    joined[static_cast<std::size_t>(order[k])] = dissolved[static_cast<std::size_t>(holder)] ? -1 : order[static_cast<std::size_t>(holder)];
  }
  for (std::size_t k = 0; k < shapes.size(); ++k) {
    if (shapes[k].members.empty()) continue;
    ShapePiece& piece = pieces[static_cast<std::size_t>(order[k])];
    piece.axis = shapes[k].axis;
    piece.point = shapes[k].point;
    piece.size = shapes[k].size;
  }
  return joined;
}

}  // namespace detail

ExtractionResult detect_shapes(const Eigen::Matrix3Xd& points, const Eigen::Matrix3Xd& normals,
                               const ExtractionOptions& options) {
  return detail::detect_shapes_with_parameters(points, normals, options, nullptr);
}

namespace detail {

ExtractionResult detect_shapes_with_parameters(const Eigen::Matrix3Xd& points, const Eigen::Matrix3Xd& normals,
                                               const ExtractionOptions& options, std::vector<ShapeParameters>* parameters) {
  ExtractionResult result;
  const ShapeDetectionOptions& shape_options = options.shapes;
  const auto start = std::chrono::steady_clock::now();
  const std::size_t count = static_cast<std::size_t>(points.cols());
  result.points_in_range = count;
  if (count == 0) {
    result.status = ExtractionStatus::EmptyCloud;
    result.message = "no points to detect shapes in";
    return result;
  }
  const bool have_normals = normals.cols() == points.cols() && normals.allFinite();

  std::vector<std::uint32_t> representative_of_point;
  std::vector<std::uint32_t> representatives;
  simplify_on_grid(points, shape_options.simplification_voxel, representative_of_point, representatives);
  PointWithNormalVector input = representatives_with_normals(points, normals, have_normals, representatives);
  result.timings_ms["simplification"] = detail::elapsed_ms(start);

  // Normals that came with the cloud are kept as given.
  auto stage = std::chrono::steady_clock::now();
  if (!have_normals) estimate_oriented_normals(input, shape_options.normal_neighbours, options.sensor_origin);
  result.timings_ms["normals"] = detail::elapsed_ms(stage);

  stage = std::chrono::steady_clock::now();
  Eigen::Matrix3Xd simplified(3, static_cast<Eigen::Index>(input.size()));
  for (std::size_t i = 0; i < input.size(); ++i)
    simplified.col(static_cast<Eigen::Index>(i)) = Eigen::Vector3d(input[i].first.x(), input[i].first.y(), input[i].first.z());
  Eigen::Matrix3Xd simplified_normals(3, static_cast<Eigen::Index>(input.size()));
  for (std::size_t i = 0; i < input.size(); ++i)
    simplified_normals.col(static_cast<Eigen::Index>(i)) =
        Eigen::Vector3d(input[i].second.x(), input[i].second.y(), input[i].second.z()).normalized();
  std::vector<DetectedShape> shapes;
  if (!detect_ransac_shapes(input, simplified, shape_options, shapes)) {
    result.status = ExtractionStatus::NoElements;
    result.message = "Efficient RANSAC ran out of memory on " + std::to_string(input.size()) +
                     " simplified points (raise simplification_voxel or cluster_epsilon)";
    result.timings_ms["shape_detection"] = detail::elapsed_ms(stage);
    return result;
  }
  result.timings_ms["shape_detection"] = detail::elapsed_ms(stage);

  stage = std::chrono::steady_clock::now();
  replace_by_simplest_quadrics(shapes, simplified, simplified_normals, shape_options);
  join_cylinder_pieces_to_cones(shapes, simplified, shape_options);
  std::stable_sort(shapes.begin(), shapes.end(),
                   [](const DetectedShape& a, const DetectedShape& b) { return a.members.size() > b.members.size(); });
  if (shape_options.merge_equal_shapes && shapes.size() > 1)
    merge_similar_shapes(shapes, simplified, simplified_normals, shape_options, options.up);
  if (shape_options.absorb_fraction <= 1.0) absorb_explained_shapes(shapes, simplified, shape_options);
  result.timings_ms["shape_refinement"] = detail::elapsed_ms(stage);

  std::vector<Element> elements = elements_of_shapes(shapes, input.size(), representative_of_point);
  std::vector<ShapeParameters> shape_parameters;
  for (const DetectedShape& shape : shapes) shape_parameters.push_back({shape.axis, shape.point, shape.size});
  if (shape_options.mark_ground) mark_ground_element(shapes, points, options.up, elements, shape_parameters, result);
  for (std::size_t id = 0; id < elements.size(); ++id) {
    if (elements[id].point_indices.empty()) continue;
    result.elements.push_back(std::move(elements[id]));
    if (parameters != nullptr) parameters->push_back(shape_parameters[id]);
  }
  if (result.elements.empty()) {
    result.status = ExtractionStatus::NoElements;
    result.message = "Efficient RANSAC found no shape with at least " + std::to_string(shape_options.minimum_points) +
                     " points";
  } else if (!result.has_ground && shape_options.mark_ground) {
    result.status = ExtractionStatus::NoGround;
    result.message = "no near-horizontal plane found for the ground";
  }
  return result;
}

}  // namespace detail
}  // namespace quadrix
