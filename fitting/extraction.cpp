// Whole extraction pipeline (paper §"Quadric Extraction"), sensor presets (REFERENCE.md table of
// the released configs) and the SemanticKITTI label mapping of the `labels` semantic mode.
#include "fitting/extraction.h"
#include "fitting/extraction_internal.h"

#include "geometry/error.h"
#include "geometry/voxel_cells.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iterator>
#include <limits>
#include <map>
#include <sstream>
#include <string>

namespace quadrix {

std::string extraction_status_name(ExtractionStatus status) {
  switch (status) {
    case ExtractionStatus::Ok: return "ok";
    case ExtractionStatus::EmptyCloud: return "empty_cloud";
    case ExtractionStatus::NoGround: return "no_ground";
    case ExtractionStatus::NoElements: return "no_elements";
  }
  return "unknown";
}

std::vector<std::string> extraction_preset_names() { return {"vlp64", "vlp16", "mid360", "avia", "monument", "airborne"}; }

ExtractionOptions extraction_preset(const std::string& name) {
  ExtractionOptions options;  // HDL-64E values (range 2-80 m, voxel 1.0 m, merge 0.20 m, cos 0.95, ratio 30, 20 pts)
  options.preset = name;
  if (name == "vlp64") return options;
  // The other sensors: the table gives voxel, merge distance, normal cosine and eigenvalue ratio;
  // values it leaves open keep the HDL-64E ones.
  if (name == "vlp16") {
    options.planes.voxel_size = 1.4;
    options.planes.merge_distance = 0.28;
    options.planes.eigenvalue_ratio = 16.0;
    return options;
  }
  // Non-repetitive scanners see a wall as a dense patch, not the narrow band of beams a spinning
  // head leaves, so walls inside a cluster take the full plane size tests (with the smaller ones
  // the 3DTK pair 2->1, which `auto` gives this preset, fails). The trunk rule is tuned for spinning
  // heads only; on the Avia demo pair it turns the answer wrong, so it stays off.
  const auto full_cluster_wall_tests = [](ExtractionOptions& non_repetitive) {
    non_repetitive.planes.cluster_plane_width = non_repetitive.planes.minimum_plane_width;
    non_repetitive.planes.cluster_plane_area = non_repetitive.planes.minimum_plane_area;
    non_repetitive.trunks.enabled = false;
    non_repetitive.stems.enabled = false;
  };
  if (name == "mid360") {
    options.planes.voxel_size = 1.2;
    options.planes.merge_distance = 0.25;
    options.planes.eigenvalue_ratio = 18.0;
    options.minimum_range = 0.5;  // solid-state, no ego-vehicle ring to remove
    full_cluster_wall_tests(options);
    return options;
  }
  if (name == "avia") {
    options.planes.voxel_size = 1.0;
    options.planes.merge_distance = 0.22;
    options.planes.eigenvalue_ratio = 20.0;
    options.minimum_range = 0.5;
    full_cluster_wall_tests(options);
    return options;
  }
  if (name == "monument") {
    options.static_scan = true;  // CGAL Efficient RANSAC shapes (paper Fig. "quadric modeling of Pantheon")
    options.minimum_range = 0.0;
    options.maximum_range = 0.0;
    // Scaled for a ~160 m monument of several TLS stations (~6 M points): 0.2 m simplification and
    // a 0.6 m cluster epsilon keep Efficient RANSAC within memory (its connectivity bitmap covers
    // each candidate's parameter domain at cluster_epsilon resolution) and time; the tolerances
    // follow the simplified spacing. Small dense scenes want ShapeDetectionOptions' defaults.
    options.shapes.simplification_voxel = 0.2;
    options.shapes.epsilon = 0.05;
    options.shapes.cluster_epsilon = 0.6;
    options.shapes.minimum_points = 60;
    return options;
  }
  if (name == "airborne") {
    // Nadir airborne laser scans at 0.5-2 points/m^2 (the USGS Lidar Base Specification's quality
    // level 2, at least 2 points/m^2 with RMSEz <= 10 cm, and sparser legacy flights): roofs and the
    // ground seen from above. The values follow from that spacing (0.7-1.4 m) and accuracy, not from
    // a tuned data set. No sensor position: no range limits.
    options.static_scan = true;
    options.minimum_range = 0.0;
    options.maximum_range = 0.0;
    options.ground_class = 2;  // ASPRS class 2 (ground), where the file classifies its points
    // A lone return (bird, multipath) has no other point in its 7.5 m block of cells; a surface at
    // 0.5 points/m^2 puts about 28 there.
    options.isolation_cell = 2.5;
    // A 0.5 m grid, finer than the spacing, keeps nearly every surface point and thins only where
    // flight strips overlap.
    options.shapes.simplification_voxel = 0.5;
    options.shapes.normal_neighbours = 12;  // about 2 m around a point at 1 point/m^2: inside one roof facet
    options.shapes.epsilon = 0.2;           // twice the 10 cm RMSEz of quality level 2
    options.shapes.cluster_epsilon = 2.5;   // 1.8 times the 1.4 m spacing at 0.5 points/m^2: a facet's points connect, roofs across a lane do not
    options.shapes.minimum_points = 40;     // a 20 m^2 facet at 2 points/m^2, 80 m^2 at 0.5
    // Seen from above, walls and columns get almost no points and a curved roof of 10 m gets a few
    // dozen, too few to tell a sphere or cone from facets, while tree crowns offer curved
    // candidates everywhere: planes only.
    options.shapes.detect_cylinders = false;
    options.shapes.detect_spheres = false;
    options.shapes.detect_cones = false;
    return options;
  }
  std::string valid;
  for (const auto& preset : extraction_preset_names()) valid += (valid.empty() ? "" : ", ") + preset;
  throw Error("unknown extraction preset '" + name + "' (expected one of: " + valid + ")");
}

namespace {

// Throws unless `element_class` is one the labels can give alone (ExtractionOptions::label_classes).
void check_label_class(ElementClass element_class) {
  if (element_class != ElementClass::Line && element_class != ElementClass::Vehicle && element_class != ElementClass::Trunk &&
      element_class != ElementClass::Vegetation)
    throw Error("label classes: '" + element_class_name(element_class) +
                "' cannot be taken from labels alone (expected line, vehicle, trunk or vegetation)");
}

}  // namespace

std::vector<ElementClass> parse_label_classes(const std::string& names) {
  std::vector<ElementClass> classes;
  std::size_t start = 0;
  while (start <= names.size()) {
    const std::size_t end = std::min(names.find(',', start), names.size());
    const std::string name = names.substr(start, end - start);
    ElementClass element_class;
    try {
      element_class = element_class_from_name(name);
    } catch (const Error&) {
      throw Error("label classes: unknown class '" + name + "' (expected line, vehicle, trunk or vegetation)");
    }
    check_label_class(element_class);
    if (std::find(classes.begin(), classes.end(), element_class) == classes.end()) classes.push_back(element_class);
    start = end + 1;
  }
  return classes;
}

bool element_class_for_semantic_kitti_label(std::uint32_t label, ElementClass& element_class) {
  switch (label & 0xFFFFu) {
    case 10: case 11: case 13: case 15: case 18: case 20:   // car, bicycle, bus, motorcycle, truck, other-vehicle
    case 252: case 253: case 254: case 255: case 256: case 257: case 258: case 259:  // moving variants
      element_class = ElementClass::Vehicle;
      return true;
    case 40: case 44: case 48: case 49: case 72:  // road, parking, sidewalk, other-ground, terrain
      element_class = ElementClass::Ground;
      return true;
    case 50: case 51: case 52:  // building, fence, other-structure
      element_class = ElementClass::Plane;
      return true;
    case 70:
      element_class = ElementClass::Vegetation;
      return true;
    case 71:
      element_class = ElementClass::Trunk;
      return true;
    case 80: case 81:  // pole, traffic-sign
      element_class = ElementClass::Line;
      return true;
    default:
      return false;
  }
}

namespace {

using Clock = std::chrono::steady_clock;

// Clusters that are too wide or do not rise above the ground are clutter, not objects.
bool keep_cluster(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& cluster,
                  const std::vector<float>& height_of_point, const ClusterOptions& options) {
  Eigen::Vector3d lower = Eigen::Vector3d::Constant(1e300), upper = Eigen::Vector3d::Constant(-1e300);
  float top = -1e30f;
  for (const std::uint32_t index : cluster) {
    lower = lower.cwiseMin(points.col(index));
    upper = upper.cwiseMax(points.col(index));
    if (!height_of_point.empty()) top = std::max(top, height_of_point[index]);
  }
  if ((upper - lower).norm() > options.maximum_extent) return false;
  return height_of_point.empty() || top >= options.minimum_height_above_ground;
}

void set_ground(ExtractionResult& result, const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& ground,
                const Eigen::Vector3d& up, const GroundSegmentation* segmentation) {
  if (ground.size() < 3) return;
  Element element;
  element.element_class = ElementClass::Ground;
  element.point_indices = ground;
  result.elements.insert(result.elements.begin(), std::move(element));
  result.has_ground = true;
  if (segmentation != nullptr) {
    result.ground_normal = segmentation->normal;
    result.ground_offset = segmentation->offset;
    return;
  }
  detail::Moments moments;
  for (const std::uint32_t index : ground) moments.add(points.col(index));
  Eigen::Vector3d normal = detail::principal_axes(moments.covariance()).vectors.col(0);
  if (normal.dot(up) < 0) normal = -normal;
  result.ground_normal = normal;
  result.ground_offset = -normal.dot(moments.mean());
}

// Trunks and crowns, lines, walls and objects from the clusters (paper step 1(c) and the
// geometry-only key objects): a tree gives its trunk and crown; otherwise RANSAC lines (poles, or
// trunks when thicker than a pole and cut by the top of the view);
// a cluster without a pole that is mostly planes gives those planes (walls the voxels missed);
// what is left of a cluster is an object.
void lines_and_objects(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& in_range,
                       const std::vector<std::vector<std::uint32_t>>& clusters, const ExtractionOptions& options,
                       const Eigen::Vector3d& up, std::vector<Element>& lines, std::vector<Element>& objects) {
  std::vector<std::vector<Element>> elements_per_cluster(clusters.size());
  tbb::parallel_for(std::size_t(0), clusters.size(), [&](std::size_t c) {
    std::vector<Element>& found = elements_per_cluster[c];
    const auto add = [&](ElementClass element_class, std::vector<std::uint32_t>&& indices) {
      Element element;
      element.element_class = element_class;
      element.point_indices = std::move(indices);
      found.push_back(std::move(element));
    };
    std::vector<std::uint32_t> trunk, crown;
    if (options.trunks.enabled && separate_trunk(points, clusters[c], options.trunks, up, trunk, crown)) {
      add(ElementClass::Trunk, std::move(trunk));
      add(ElementClass::Vegetation, std::move(crown));
      return;
    }
    std::vector<std::uint32_t> rest;
    found = extract_lines(points, clusters[c], options.lines, up, rest);
    // A trunk whose crown is above the top beam: its stem is thicker than a pole's and runs out of
    // the top of the view.
    if (options.trunks.enabled && options.trunks.crownless_minimum_radius > 0.0)
      for (Element& line : found)
        if (stem_radius_across_view(points, line.point_indices, options.trunks, options.sensor_origin) >=
                options.trunks.crownless_minimum_radius &&
            stem_reaches_top_of_view(points, line.point_indices, in_range, options.trunks, up, options.sensor_origin))
          line.element_class = ElementClass::Trunk;
    if (found.empty()) {
      // Stems standing inside the cluster: a trunk in a hedge, a pole beside a car. They are Line
      // elements whatever their thickness: the crownless trunk rule's radius, applied to them, gave
      // fewer successes on the synthetic tuning set (docs/modelling.md), since a stem measured from
      // two places can fall on both sides of it.
      for (std::vector<std::uint32_t>& stem : find_stems(points, rest, options.stems, up)) {
        std::vector<std::uint32_t> left;
        std::set_difference(rest.begin(), rest.end(), stem.begin(), stem.end(), std::back_inserter(left));
        rest = std::move(left);
        add(ElementClass::Line, std::move(stem));
      }
      for (std::vector<std::uint32_t>& plane : cluster_planes(points, rest, options.planes, up)) {
        std::vector<std::uint32_t> left;
        std::set_difference(rest.begin(), rest.end(), plane.begin(), plane.end(), std::back_inserter(left));
        rest = std::move(left);
        add(ElementClass::Plane, std::move(plane));
      }
    }
    if (static_cast<int>(rest.size()) >= options.clusters.minimum_points) add(ElementClass::Object, std::move(rest));
  });
  for (std::vector<Element>& found : elements_per_cluster)
    for (Element& element : found) (element.element_class == ElementClass::Line ? lines : objects).push_back(std::move(element));
}

}  // namespace

bool within_range(const Eigen::Vector3d& point, const ExtractionOptions& options) {
  const double squared = (point - options.sensor_origin).squaredNorm();
  return squared >= options.minimum_range * options.minimum_range &&
         (options.maximum_range <= 0.0 || squared <= options.maximum_range * options.maximum_range);
}

ExtractionResult extract_elements(const PointCloud& cloud, const ExtractionOptions& options,
                                  const std::vector<std::uint32_t>& labels) {
  return detail::extract_elements_of_points(cloud.positions.cast<double>(), cloud, options, labels);
}

namespace detail {

namespace {

// Static scans: CGAL Efficient RANSAC shapes on the points in range (detect_shapes), with the
// cloud's own normals when it carries nx, ny, nz.
ExtractionResult extract_static_scan(const Eigen::Matrix3Xd& points, const PointCloud& cloud,
                                     const std::vector<std::uint32_t>& in_range, const ExtractionOptions& options,
                                     std::vector<ShapeParameters>* shape_parameters) {
  Eigen::Matrix3Xd normals;
  const auto nx = cloud.extra_fields.find("nx"), ny = cloud.extra_fields.find("ny"), nz = cloud.extra_fields.find("nz");
  if (nx != cloud.extra_fields.end() && ny != cloud.extra_fields.end() && nz != cloud.extra_fields.end()) {
    normals.resize(3, static_cast<Eigen::Index>(in_range.size()));
    for (std::size_t i = 0; i < in_range.size(); ++i)
      normals.col(static_cast<Eigen::Index>(i)) =
          Eigen::Vector3d(nx->second[in_range[i]], ny->second[in_range[i]], nz->second[in_range[i]]);
  }
  // The file's own ground classification, where it has one (ExtractionOptions::ground_class).
  std::vector<std::uint32_t> classified_ground, others;
  if (options.ground_class >= 0 && cloud.labels.size() == cloud.size())
    for (const std::uint32_t index : in_range)
      (cloud.labels[index] == static_cast<std::uint32_t>(options.ground_class) ? classified_ground : others).push_back(index);
  const bool ground_from_classes = classified_ground.size() >= 3 && !others.empty() &&
                                   classified_ground.size() >= static_cast<std::size_t>(options.shapes.minimum_points);
  if (!ground_from_classes) {
    ExtractionResult shapes = detect_shapes_with_parameters(detail::gather_points(points, in_range), normals, options, shape_parameters);
    for (Element& element : shapes.elements)
      for (std::uint32_t& index : element.point_indices) index = in_range[index];
    shapes.points_in_range = in_range.size();
    if (shapes.has_ground) shapes.ground_source = "geometry";
    return shapes;
  }
  // Shapes among the other points; the classified points are the ground, its plane their PCA plane.
  Eigen::Matrix3Xd other_normals;
  if (normals.cols() > 0) {
    other_normals.resize(3, static_cast<Eigen::Index>(others.size()));
    for (std::size_t i = 0, j = 0; i < in_range.size(); ++i)
      if (cloud.labels[in_range[i]] != static_cast<std::uint32_t>(options.ground_class))
        other_normals.col(static_cast<Eigen::Index>(j++)) = normals.col(static_cast<Eigen::Index>(i));
  }
  ExtractionOptions without_ground = options;
  without_ground.shapes.mark_ground = false;
  std::vector<ShapeParameters> other_parameters;
  ExtractionResult shapes = detect_shapes_with_parameters(detail::gather_points(points, others), other_normals, without_ground,
                                                          shape_parameters != nullptr ? &other_parameters : nullptr);
  for (Element& element : shapes.elements)
    for (std::uint32_t& index : element.point_indices) index = others[index];
  Moments moments;
  for (const std::uint32_t index : classified_ground) moments.add(points.col(index));
  const Eigen::Vector3d up = options.up.normalized();
  Eigen::Vector3d normal = principal_axes(moments.covariance()).vectors.col(0);
  if (normal.dot(up) < 0.0) normal = -normal;
  Element ground;
  ground.element_class = ElementClass::Ground;
  ground.detected_type = QuadricType::Plane;
  ground.point_indices = std::move(classified_ground);
  shapes.elements.insert(shapes.elements.begin(), std::move(ground));
  if (shape_parameters != nullptr) {
    shape_parameters->push_back({normal, moments.mean(), 0.0});
    shape_parameters->insert(shape_parameters->end(), other_parameters.begin(), other_parameters.end());
  }
  shapes.has_ground = true;
  shapes.ground_normal = normal;
  shapes.ground_offset = -normal.dot(moments.mean());
  shapes.ground_source = "classification";
  shapes.status = ExtractionStatus::Ok;  // the ground alone is a model: no shape among the rest is not a failure
  shapes.message.clear();
  shapes.points_in_range = in_range.size();
  return shapes;
}

// The elements extracted so far, by group.
struct ElementGroups {
  std::vector<Element> planes, lines, objects;
};

// Each Euclidean cluster of `members`, all of one labelled class, as an element of that class.
void add_class_clusters(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& members,
                        ElementClass element_class, const ClusterOptions& options, ElementGroups& groups) {
  for (auto& cluster : euclidean_clusters(points, members, options)) {
    Element element;
    element.element_class = element_class;
    element.point_indices = std::move(cluster);
    (element_class == ElementClass::Line ? groups.lines : groups.objects).push_back(std::move(element));
  }
}

// Labels semantic mode: the given per-point classes decide; ground is the ground class, planes are
// extracted among the plane class, and each Euclidean cluster of a labelled class is one element.
ElementGroups extract_with_labels(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& in_range,
                                  const std::vector<std::uint32_t>& labels, const ExtractionOptions& options,
                                  const Eigen::Vector3d& up, ExtractionResult& result) {
  ElementGroups groups;
  auto stage = Clock::now();
  std::vector<std::uint32_t> ground;
  std::vector<std::uint32_t> per_class[11];
  for (const std::uint32_t index : in_range) {
    ElementClass element_class;
    if (!element_class_for_semantic_kitti_label(labels[index], element_class)) continue;
    if (element_class == ElementClass::Ground)
      ground.push_back(index);
    else
      per_class[static_cast<int>(element_class)].push_back(index);
  }
  set_ground(result, points, ground, up, nullptr);
  result.timings_ms["ground"] = detail::elapsed_ms(stage);
  stage = Clock::now();
  std::vector<std::uint32_t> remaining;
  groups.planes = extract_planes(points, per_class[static_cast<int>(ElementClass::Plane)], options.planes, remaining);
  result.timings_ms["planes"] = detail::elapsed_ms(stage);
  stage = Clock::now();
  for (const ElementClass element_class :
       {ElementClass::Line, ElementClass::Vehicle, ElementClass::Trunk, ElementClass::Vegetation})
    add_class_clusters(points, per_class[static_cast<int>(element_class)], element_class, options.clusters, groups);
  result.timings_ms["clusters"] = detail::elapsed_ms(stage);
  return groups;
}

// Geometry-only mode (paper §"Quadric Extraction", step 1): ground segmentation, planes by voxel
// region growing, Euclidean clusters kept by size and height above the ground, then lines (poles,
// trunks) and objects among them.
ElementGroups extract_geometric(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& in_range,
                                const ExtractionOptions& options, const Eigen::Vector3d& up, ExtractionResult& result) {
  ElementGroups groups;
  auto stage = Clock::now();
  const GroundSegmentation ground = segment_ground(points, in_range, options.ground, options.sensor_origin, up);
  if (ground.found) set_ground(result, points, ground.ground_indices, up, &ground);
  result.timings_ms["ground"] = detail::elapsed_ms(stage);
  std::vector<float> height_of_point;  // per cloud point, when a ground was found (else no height test)
  if (ground.found) {
    height_of_point.assign(static_cast<std::size_t>(points.cols()), 1e9f);
    for (std::size_t i = 0; i < ground.other_indices.size(); ++i) height_of_point[ground.other_indices[i]] = ground.other_heights[i];
  }

  stage = Clock::now();
  std::vector<std::uint32_t> remaining;
  groups.planes = extract_planes(points, ground.other_indices, options.planes, remaining);
  result.timings_ms["planes"] = detail::elapsed_ms(stage);

  stage = Clock::now();
  std::vector<std::vector<std::uint32_t>> clusters = euclidean_clusters(points, remaining, options.clusters);
  clusters.erase(std::remove_if(clusters.begin(), clusters.end(),
                                [&](const auto& cluster) { return !keep_cluster(points, cluster, height_of_point, options.clusters); }),
                 clusters.end());
  result.timings_ms["clusters"] = detail::elapsed_ms(stage);
  stage = Clock::now();
  lines_and_objects(points, in_range, clusters, options, up, groups.lines, groups.objects);
  result.timings_ms["lines"] = detail::elapsed_ms(stage);
  return groups;
}

// Labels mode for some classes only (ExtractionOptions::label_classes): points whose label maps to
// one of them form that class's Euclidean clusters; every other point goes through the geometry-only
// pipeline, which never sees the given ones (a car kept out of the walls and the clusters).
ElementGroups extract_partially_labelled(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& in_range,
                                         const std::vector<std::uint32_t>& labels, const ExtractionOptions& options,
                                         const Eigen::Vector3d& up, ExtractionResult& result) {
  std::map<ElementClass, std::vector<std::uint32_t>> given;
  std::vector<std::uint32_t> unlabelled;
  for (const std::uint32_t index : in_range) {
    ElementClass element_class;
    if (element_class_for_semantic_kitti_label(labels[index], element_class) &&
        std::find(options.label_classes.begin(), options.label_classes.end(), element_class) != options.label_classes.end())
      given[element_class].push_back(index);
    else
      unlabelled.push_back(index);
  }
  ElementGroups groups = extract_geometric(points, unlabelled, options, up, result);
  const auto stage = Clock::now();
  for (const auto& [element_class, members] : given) add_class_clusters(points, members, element_class, options.clusters, groups);
  result.timings_ms["labelled_clusters"] = detail::elapsed_ms(stage);
  return groups;
}

// The extraction's status and message from what was found among `points_in_range` points.
void describe_extraction(ExtractionResult& result, std::size_t points_in_range) {
  if (result.elements.empty()) {
    result.status = ExtractionStatus::NoElements;
    result.message = "no ground, plane, line or cluster passed the size tests among " + std::to_string(points_in_range) +
                     " points in range";
  } else if (!result.has_ground) {
    result.status = ExtractionStatus::NoGround;
    result.message = "no ground found; planes, lines and objects were still extracted";
  } else if (result.elements.size() == 1) {
    result.message = "only the ground was found: no plane, line or cluster passed the size tests among the " +
                     std::to_string(points_in_range - result.elements.front().point_indices.size()) + " other points";
  }
}

// Why nothing is in range, with the nearest and farthest point's distance from the sensor: a cloud
// whose points all lie beyond the maximum range is most often in another frame than its sensor's
// (a map's), where the range limits measure from a point the sensor never stood at, or in
// millimetres.
std::string no_point_in_range_message(const Eigen::Matrix3Xd& points, const ExtractionOptions& options) {
  double nearest = std::numeric_limits<double>::infinity();
  double farthest = 0.0;
  for (Eigen::Index i = 0; i < points.cols(); ++i) {
    const double distance = (points.col(i) - options.sensor_origin).norm();
    if (!std::isfinite(distance)) continue;
    nearest = std::min(nearest, distance);
    farthest = std::max(farthest, distance);
  }
  std::ostringstream message;
  message.precision(4);
  message << "no point within the range limits (" << options.minimum_range << " to " << options.maximum_range
          << " m from the sensor at (" << options.sensor_origin.x() << ", " << options.sensor_origin.y() << ", "
          << options.sensor_origin.z() << "))";
  if (std::isfinite(nearest)) message << "; the points lie " << nearest << " to " << farthest << " m from it";
  if (std::isfinite(nearest) && options.maximum_range > 0.0 && nearest > options.maximum_range)
    message << ": is the cloud in metres, and in its sensor's frame with the sensor at the origin? (A cloud in a "
               "map's frame needs its sensor's position: --sensor-origin, --source-origin, --target-origin)";
  return message.str();
}

}  // namespace

ExtractionResult extract_elements_of_points(const Eigen::Matrix3Xd& points, const PointCloud& cloud,
                                            const ExtractionOptions& options, const std::vector<std::uint32_t>& labels,
                                            std::vector<ShapeParameters>* shape_parameters) {
  const auto start = Clock::now();
  if (options.semantic_mode == SemanticMode::Labels && labels.size() != cloud.size())
    throw Error("labels semantic mode: " + std::to_string(labels.size()) + " labels for " +
                std::to_string(cloud.size()) + " points (expected one label per point)");
  if (!(options.up.norm() > 0.0) || !options.up.allFinite())
    throw Error("extraction option 'up' must be a finite non-zero vector");
  if (!(options.isolation_cell >= 0.0 && std::isfinite(options.isolation_cell)))
    throw Error("extraction option 'isolation_cell' must be a length >= 0 in metres, got " + std::to_string(options.isolation_cell));
  if (options.isolation_neighbours < 1)
    throw Error("extraction option 'isolation_neighbours' must be at least 1, got " + std::to_string(options.isolation_neighbours));
  for (const ElementClass element_class : options.label_classes) check_label_class(element_class);
  const Eigen::Vector3d up = options.up.normalized();

  ExtractionResult result;
  // Range limits around the sensor (REFERENCE.md: HDL-64E 2-80 m).
  std::vector<std::uint32_t> in_range;
  in_range.reserve(cloud.size());
  for (std::uint32_t i = 0; i < cloud.size(); ++i)
    if (within_range(points.col(i), options)) in_range.push_back(i);
  result.points_in_range = in_range.size();
  // Spurious returns (dust, rain, multipath echoes) stand alone: left in, those dense enough to reach
  // a patch or a cluster join the ground and the clusters. Under 30-50% uniform outliers, leaving
  // them out here kept 84 of 84 KITTI registrations right against 81 (three draws a pair), and
  // changed no status on 1,500 undamaged synthetic runs (docs/registration.md, "Isolated points").
  result.timings_ms["crop"] = detail::elapsed_ms(start);
  if (options.isolation_cell > 0.0 && !in_range.empty()) {
    const auto isolation_start = Clock::now();
    in_range = accompanied_points(points, in_range, options.isolation_cell, options.isolation_neighbours);
    result.isolated_points = result.points_in_range - in_range.size();
    result.timings_ms["isolated_points"] = detail::elapsed_ms(isolation_start);
  }
  result.measured.indices = in_range;
  result.measured.cloud_size = cloud.size();
  result.measured.sensor_origin = options.sensor_origin;
  result.measured.minimum_range = options.minimum_range;
  result.measured.maximum_range = options.maximum_range;
  result.measured.isolation_cell = options.isolation_cell;
  result.measured.isolation_neighbours = options.isolation_neighbours;
  if (in_range.empty()) {
    result.status = ExtractionStatus::EmptyCloud;
    result.message = cloud.empty() ? "the cloud has no points"
                     : result.points_in_range == 0
                         ? no_point_in_range_message(points, options)
                         : "every one of the " + std::to_string(result.points_in_range) +
                               " points in range is isolated (no other point within its cube of " +
                               std::to_string(options.isolation_cell) + " m or the 26 around)";
    return result;
  }
  if (options.static_scan) {
    ExtractionResult shapes = extract_static_scan(points, cloud, in_range, options, shape_parameters);
    shapes.timings_ms.insert(result.timings_ms.begin(), result.timings_ms.end());
    shapes.points_in_range = result.points_in_range;
    shapes.isolated_points = result.isolated_points;
    shapes.measured = std::move(result.measured);
    return shapes;
  }
  ElementGroups groups = options.semantic_mode != SemanticMode::Labels ? extract_geometric(points, in_range, options, up, result)
                         : options.label_classes.empty() ? extract_with_labels(points, in_range, labels, options, up, result)
                                                         : extract_partially_labelled(points, in_range, labels, options, up, result);
  for (auto* group : {&groups.planes, &groups.lines, &groups.objects})
    for (Element& element : *group) result.elements.push_back(std::move(element));
  describe_extraction(result, in_range.size());
  result.timings_ms["extraction"] = detail::elapsed_ms(start);
  return result;
}

}  // namespace detail
}  // namespace quadrix
