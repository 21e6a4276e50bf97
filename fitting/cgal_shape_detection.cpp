// Every heavy CGAL template of extraction lives here (CGAL 5.5 API, doc.cgal.org/5.5):
//  - Efficient RANSAC (Schnabel et al. 2007) for static scans: planes, cylinders, spheres, cones
//    (and optionally tori), every Parameters field set explicitly; normals by CGAL jet fitting,
//    oriented toward the scanner;
//  - Shape_detection region growing of planes on a point set (the alternative plane method of
//    paper §"Quadric Extraction" step 1(b)).
#include "fitting/extraction.h"
#include "fitting/extraction_internal.h"

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
#include <new>
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

using RansacTraits = CGAL::Shape_detection::Efficient_RANSAC_traits<Kernel, PointWithNormalVector, PointMap, NormalMap>;
using EfficientRansac = CGAL::Shape_detection::Efficient_RANSAC<RansacTraits>;
using RansacPlane = CGAL::Shape_detection::Plane<RansacTraits>;
using RansacCylinder = CGAL::Shape_detection::Cylinder<RansacTraits>;
using RansacSphere = CGAL::Shape_detection::Sphere<RansacTraits>;
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
  const double angle_deg = std::acos(std::clamp(options.normal_cosine, -1.0, 1.0)) * 180.0 / 3.14159265358979323846;
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

ExtractionResult detect_shapes(const Eigen::Matrix3Xd& points, const Eigen::Matrix3Xd& normals,
                               const ExtractionOptions& options) {
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

  // Grid simplification: one representative per voxel; every point follows its representative.
  std::vector<std::uint32_t> representative_of_point(count);
  std::vector<std::uint32_t> representatives;
  if (shape_options.simplification_voxel > 0.0) {
    std::unordered_map<std::uint64_t, std::uint32_t> voxel_representative;
    voxel_representative.reserve(count / 4 + 16);
    const double inverse = 1.0 / shape_options.simplification_voxel;
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
  PointWithNormalVector input;
  input.reserve(representatives.size());
  for (const std::uint32_t index : representatives) {
    const Eigen::Vector3d n = have_normals ? Eigen::Vector3d(normals.col(index)) : Eigen::Vector3d::UnitZ();
    input.emplace_back(to_point(points.col(index)), Vector3(n.x(), n.y(), n.z()));
  }
  result.timings_ms["simplification"] = detail::elapsed_ms(start);

  auto stage = std::chrono::steady_clock::now();
  if (!have_normals && input.size() >= 3) {
    CGAL::jet_estimate_normals<CGAL::Parallel_if_available_tag>(
        input, static_cast<unsigned>(std::max(3, shape_options.normal_neighbours)),
        CGAL::parameters::point_map(PointMap()).normal_map(NormalMap()));
  }
  // Orient estimated normals toward the scanner (a TLS station sees the outside of each surface);
  // normals that came with the cloud are kept as given.
  for (PointWithNormal& item : input) {
    if (have_normals) break;
    const Eigen::Vector3d p(item.first.x(), item.first.y(), item.first.z());
    const Eigen::Vector3d n(item.second.x(), item.second.y(), item.second.z());
    if (n.dot(options.sensor_origin - p) < 0.0) item.second = -item.second;
  }
  result.timings_ms["normals"] = detail::elapsed_ms(stage);

  stage = std::chrono::steady_clock::now();
  std::vector<int> shape_of_representative(input.size(), -1);
  struct DetectedShape {
    ElementClass element_class;
    QuadricType type;
    Eigen::Vector3d normal;                              // planes: normal; cylinders, cones: axis (unit)
    Eigen::Vector3d point = Eigen::Vector3d::Zero();     // planes: foot of the origin; cylinders: axis point; spheres: centre; cones: apex
    double size = 0.0;                                   // cylinders, spheres: radius; cones: half-angle (radians)
  };
  std::vector<DetectedShape> shapes;
  if (input.size() >= static_cast<std::size_t>(std::max(3, shape_options.minimum_points))) {
    CGAL::get_default_random() = CGAL::Random(shape_options.seed);
    EfficientRansac ransac;
    ransac.set_input(input, PointMap(), NormalMap());
    if (shape_options.detect_planes) ransac.add_shape_factory<RansacPlane>();
    if (shape_options.detect_cylinders) ransac.add_shape_factory<RansacCylinder>();
    if (shape_options.detect_spheres) ransac.add_shape_factory<RansacSphere>();
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
      result.status = ExtractionStatus::NoElements;
      result.message = "Efficient RANSAC ran out of memory on " + std::to_string(input.size()) +
                       " simplified points (raise simplification_voxel or cluster_epsilon)";
      result.timings_ms["shape_detection"] = detail::elapsed_ms(stage);
      return result;
    }
    for (const auto& shape : ransac.shapes()) {
      DetectedShape detected{ElementClass::Object, QuadricType::Invalid, Eigen::Vector3d::Zero()};
      const auto vector = [](const Vector3& v) { return Eigen::Vector3d(v.x(), v.y(), v.z()); };
      const auto point = [](const Point3& p) { return Eigen::Vector3d(p.x(), p.y(), p.z()); };
      if (const auto* plane = dynamic_cast<const RansacPlane*>(shape.get())) {
        const Eigen::Vector3d n = vector(plane->plane_normal());
        // CGAL's plane: n . x + d = 0 with n possibly not unit.
        detected = {ElementClass::Plane, QuadricType::Plane, n.normalized(), -plane->d() / n.squaredNorm() * n, 0.0};
      } else if (const auto* cylinder = dynamic_cast<const RansacCylinder*>(shape.get())) {
        const auto axis = cylinder->axis();
        detected = {ElementClass::Cylinder, QuadricType::CircularCylinder, vector(axis.to_vector()).normalized(),
                    point(axis.point(0)), cylinder->radius()};
      } else if (const auto* sphere = dynamic_cast<const RansacSphere*>(shape.get())) {
        detected = {ElementClass::Sphere, QuadricType::Sphere, Eigen::Vector3d::Zero(), point(sphere->center()),
                    sphere->radius()};
      } else if (const auto* cone = dynamic_cast<const RansacCone*>(shape.get())) {
        detected = {ElementClass::Cone, QuadricType::CircularCone, vector(cone->axis()).normalized(), point(cone->apex()),
                    cone->angle()};
      }  // tori stay Object (not quadrics; fitted as ellipsoids)
      // A curved shape whose points are flat within epsilon is a plane: Efficient RANSAC otherwise
      // returns strips of a large floor as cylinders (or cones) of huge radius.
      if (detected.type != QuadricType::Plane && detected.element_class != ElementClass::Object) {
        detail::Moments moments;
        for (const std::size_t i : shape->indices_of_assigned_points())
          moments.add(Eigen::Vector3d(input[i].first.x(), input[i].first.y(), input[i].first.z()));
        const detail::Principal axes = detail::principal_axes(moments.covariance());
        if (std::sqrt(axes.values(0)) <= shape_options.epsilon)
          detected = {ElementClass::Plane, QuadricType::Plane, axes.vectors.col(0), moments.mean(), 0.0};
      }
      const int id = static_cast<int>(shapes.size());
      shapes.push_back(detected);
      for (const std::size_t i : shape->indices_of_assigned_points()) shape_of_representative[i] = id;
    }
  }
  result.timings_ms["shape_detection"] = detail::elapsed_ms(stage);

  // Efficient RANSAC keeps the largest connected piece of each candidate, so one surface cut by
  // occlusion shadows (a plaza behind columns) returns as several shapes with equal parameters:
  // those are merged into the first (largest) of them.
  if (shape_options.merge_equal_shapes && shapes.size() > 1) {
    const double cos_angle = std::cos(shape_options.merge_angle_deg * 3.14159265358979323846 / 180.0);
    const double distance = shape_options.merge_distance;
    const auto line_distance = [](const Eigen::Vector3d& point, const Eigen::Vector3d& on_line, const Eigen::Vector3d& axis) {
      const Eigen::Vector3d d = point - on_line;
      return (d - d.dot(axis) * axis).norm();
    };
    const auto equal = [&](const DetectedShape& a, const DetectedShape& b) {
      if (a.type != b.type || a.element_class != b.element_class) return false;
      const bool parallel = std::abs(a.normal.dot(b.normal)) >= cos_angle;
      const bool same_size = std::abs(a.size - b.size) <= shape_options.merge_radius_fraction * std::max(a.size, b.size);
      switch (a.type) {
        case QuadricType::Plane: return parallel && std::abs(a.normal.dot(b.point - a.point)) <= distance;
        case QuadricType::CircularCylinder: return parallel && same_size && line_distance(b.point, a.point, a.normal) <= distance;
        case QuadricType::Sphere: return same_size && (a.point - b.point).norm() <= distance;
        case QuadricType::CircularCone:
          return a.normal.dot(b.normal) >= cos_angle && (a.point - b.point).norm() <= distance &&
                 std::abs(a.size - b.size) <= shape_options.merge_angle_deg * 3.14159265358979323846 / 180.0;
        default: return false;
      }
    };
    std::vector<int> merged_into(shapes.size());
    for (std::size_t id = 0; id < shapes.size(); ++id) {
      merged_into[id] = static_cast<int>(id);
      for (std::size_t earlier = 0; earlier < id; ++earlier)
        if (merged_into[earlier] == static_cast<int>(earlier) && equal(shapes[earlier], shapes[id])) {
          merged_into[id] = static_cast<int>(earlier);
          break;
        }
    }
    for (int& id : shape_of_representative)
      if (id >= 0) id = merged_into[static_cast<std::size_t>(id)];
  }

  std::vector<Element> elements(shapes.size());
  for (std::size_t id = 0; id < shapes.size(); ++id) {
    elements[id].element_class = shapes[id].element_class;
    elements[id].detected_type = shapes[id].type;
  }
  for (std::uint32_t i = 0; i < count; ++i) {
    const int id = shape_of_representative[representative_of_point[i]];
    if (id >= 0) elements[static_cast<std::size_t>(id)].point_indices.push_back(i);
  }

  // Ground: the lowest of the large near-horizontal planes.
  if (shape_options.mark_ground) {
    const Eigen::Vector3d up = options.up.normalized();
    const double cos_ten_degrees = std::cos(10.0 * 3.14159265358979323846 / 180.0);
    std::size_t largest = 0;
    for (std::size_t id = 0; id < shapes.size(); ++id)
      if (shapes[id].type == QuadricType::Plane && std::abs(shapes[id].normal.dot(up)) >= cos_ten_degrees)
        largest = std::max(largest, elements[id].point_indices.size());
    int ground = -1;
    double ground_height = 1e300;
    for (std::size_t id = 0; id < shapes.size(); ++id) {
      if (shapes[id].type != QuadricType::Plane || std::abs(shapes[id].normal.dot(up)) < cos_ten_degrees) continue;
      if (elements[id].point_indices.size() * 10 < largest) continue;
      double height = 0.0;
      for (const std::uint32_t index : elements[id].point_indices) height += up.dot(points.col(index));
      height /= static_cast<double>(elements[id].point_indices.size());
      if (height < ground_height) {
        ground_height = height;
        ground = static_cast<int>(id);
      }
    }
    if (ground >= 0) {
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
    }
  }
  elements.erase(std::remove_if(elements.begin(), elements.end(), [](const Element& e) { return e.point_indices.empty(); }),
                 elements.end());
  result.elements = std::move(elements);
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

}  // namespace quadrix
