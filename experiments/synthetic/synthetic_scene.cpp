// Synthetic scenes: label table, primitive helpers, the street / corridor / monument layouts and
// the ground truth (quadrics and 21-number records) of every primitive.
#include "experiments/synthetic/synthetic_scene.h"

#include "geometry/constants.h"
#include "geometry/error.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

namespace quadrix {

// ---------------------------------------------------------------------------------------------
// Labels

const std::vector<SemanticLabelInfo>& semantic_label_table() {
  static const std::vector<SemanticLabelInfo> table = {
      {SemanticLabel::Unlabelled, "unlabelled", "no primitive"},
      {SemanticLabel::Car, "car", "parked car body, ellipsoid"},
      {SemanticLabel::Person, "person", "pedestrian, upright ellipsoid"},
      {SemanticLabel::Road, "road", "drivable road surface, plane"},
      {SemanticLabel::Sidewalk, "sidewalk", "raised pavement beside the road, plane"},
      {SemanticLabel::Ground, "ground", "plaza, verge or other ground, plane"},
      {SemanticLabel::Facade, "facade", "building facade, recess back walls, jambs and soffits, plane"},
      {SemanticLabel::Barrier, "barrier", "road barrier or noise wall, plane"},
      {SemanticLabel::Vegetation, "vegetation", "tree crown, ellipsoid"},
      {SemanticLabel::Trunk, "trunk", "tree trunk, cylinder"},
      {SemanticLabel::Pole, "pole", "lamp post, sign post or lamp arm, thin cylinder modelled as a line"},
      {SemanticLabel::Kerb, "kerb", "vertical kerb face between road and sidewalk, plane"},
      {SemanticLabel::Bollard, "bollard", "spherical stone bollard, sphere"},
      {SemanticLabel::TrafficCone, "traffic_cone", "traffic cone, cone"},
      {SemanticLabel::Column, "column", "architectural column, cylinder"},
      {SemanticLabel::Wall, "wall", "monument wall or rotunda drum, plane or cylinder"},
      {SemanticLabel::Floor, "floor", "floor, podium top, step tread or ceiling, plane"},
      {SemanticLabel::Dome, "dome", "dome with an oculus, clipped sphere"},
      {SemanticLabel::Roof, "roof", "roof slope or conical roof ring, plane or cone"},
      {SemanticLabel::Step, "step", "step riser or podium side, plane"},
      {SemanticLabel::Pediment, "pediment", "pediment or entablature face, plane"},
      {SemanticLabel::Ornament, "ornament", "spherical finial or ornament, sphere"},
  };
  return table;
}

std::string semantic_label_name(SemanticLabel label) {
  for (const auto& row : semantic_label_table())
    if (row.label == label) return row.name;
  throw Error("semantic label: id " + std::to_string(static_cast<std::uint32_t>(label)) +
              " is not in the synthetic label table");
}

SemanticLabel semantic_label_from_name(const std::string& name) {
  for (const auto& row : semantic_label_table())
    if (row.name == name) return row.label;
  throw Error("semantic label: unknown name '" + name + "' (expected a name of the synthetic label table)");
}

// ---------------------------------------------------------------------------------------------
// Portable randomness

double PortableRandom::uniform(double minimum, double maximum) {
  return minimum + (maximum - minimum) * unit_interval_from_bits(engine_());
}

int PortableRandom::uniform_integer(int minimum, int maximum) {
  if (maximum < minimum) throw Error("PortableRandom::uniform_integer: maximum must not be below minimum");
  const std::uint64_t span = static_cast<std::uint64_t>(static_cast<std::int64_t>(maximum) - minimum) + 1;
  return static_cast<int>(minimum + static_cast<std::int64_t>(engine_() % span));
}

bool PortableRandom::bernoulli(double probability) { return unit_interval_from_bits(engine_()) < probability; }

double PortableRandom::normal(double mean, double standard_deviation) {
  // Box-Muller; 1 - u keeps the logarithm finite.
  const double u1 = 1.0 - unit_interval_from_bits(engine_());
  const double u2 = unit_interval_from_bits(engine_());
  return mean + standard_deviation * std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
}

std::uint64_t mix_bits(std::uint64_t value) {
  value += 0x9E3779B97F4A7C15ULL;
  value = (value ^ (value >> 30)) * 0xBF58476D1CE4E5B9ULL;
  value = (value ^ (value >> 27)) * 0x94D049BB133111EBULL;
  return value ^ (value >> 31);
}

double unit_interval_from_bits(std::uint64_t bits) { return static_cast<double>(bits >> 11) * 0x1.0p-53; }

// ---------------------------------------------------------------------------------------------
// Primitive geometry

namespace {

double degrees(double value) { return value * kPi / 180.0; }

/// Orthonormal right-handed basis whose third column is `axis`.
Eigen::Matrix3d basis_with_third_axis(const Eigen::Vector3d& axis) {
  const Eigen::Vector3d c = axis.normalized();
  const Eigen::Vector3d helper = std::abs(c.z()) < 0.9 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX();
  const Eigen::Vector3d a = helper.cross(c).normalized();
  const Eigen::Vector3d b = c.cross(a);
  Eigen::Matrix3d rotation;
  rotation << a, b, c;
  return rotation;
}

Eigen::Isometry3d make_pose(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = rotation;
  pose.translation() = translation;
  return pose;
}

bool is_plane(const ScenePrimitive& primitive) { return primitive.surface_type == QuadricType::Plane; }
bool is_cylinder(QuadricType type) {
  return type == QuadricType::CircularCylinder || type == QuadricType::EllipticCylinder;
}
bool is_cone(QuadricType type) { return type == QuadricType::CircularCone || type == QuadricType::EllipticCone; }
bool is_ellipsoid(QuadricType type) { return type == QuadricType::Sphere || type == QuadricType::Ellipsoid; }

/// Ramanujan's approximation of an ellipse perimeter.
double ellipse_perimeter(double a, double b) {
  return kPi * (3.0 * (a + b) - std::sqrt((3.0 * a + b) * (a + 3.0 * b)));
}

/// Area of a full ellipsoid (Knud Thomsen's approximation, exact for spheres).
double ellipsoid_area(const Eigen::Vector3d& s) {
  const double p = 1.6075;
  const double ab = std::pow(s.x() * s.y(), p), ac = std::pow(s.x() * s.z(), p), bc = std::pow(s.y() * s.z(), p);
  return 4.0 * kPi * std::pow((ab + ac + bc) / 3.0, 1.0 / p);
}

double polygon_area(const std::vector<Eigen::Vector2d>& polygon) {
  double twice = 0.0;
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const auto& p = polygon[i];
    const auto& q = polygon[(i + 1) % polygon.size()];
    twice += p.x() * q.y() - q.x() * p.y();
  }
  return 0.5 * std::abs(twice);
}

/// Unit-sphere Fibonacci points (deterministic, nearly uniform).
Eigen::Vector3d fibonacci_direction(int index, int count) {
  const double golden_angle = kPi * (3.0 - std::sqrt(5.0));
  const double z = 1.0 - (2.0 * index + 1.0) / count;
  const double radius = std::sqrt(std::max(0.0, 1.0 - z * z));
  const double angle = golden_angle * index;
  return {radius * std::cos(angle), radius * std::sin(angle), z};
}

/// Local (canonical-frame) samples of the bounded surface, about `spacing` apart.
std::vector<Eigen::Vector3d> local_samples(const ScenePrimitive& primitive, double spacing) {
  std::vector<Eigen::Vector3d> points;
  const LocalExtent& e = primitive.extent;
  const Eigen::Vector3d& s = primitive.scale;
  const QuadricType type = primitive.surface_type;
  if (type == QuadricType::Plane) {
    const int nb = std::max(1, static_cast<int>(std::ceil((e.maximum.y() - e.minimum.y()) / spacing)));
    const int nc = std::max(1, static_cast<int>(std::ceil((e.maximum.z() - e.minimum.z()) / spacing)));
    for (int i = 0; i < nb; ++i)
      for (int j = 0; j < nc; ++j) {
        const Eigen::Vector3d p(0.0, e.minimum.y() + (i + 0.5) * (e.maximum.y() - e.minimum.y()) / nb,
                                e.minimum.z() + (j + 0.5) * (e.maximum.z() - e.minimum.z()) / nc);
        if (inside_primitive_bounds(primitive, p)) points.push_back(p);
      }
  } else if (is_cylinder(type)) {
    const int nt = std::max(8, static_cast<int>(std::ceil(ellipse_perimeter(s.x(), s.y()) / spacing)));
    const int nc = std::max(1, static_cast<int>(std::ceil((e.maximum.z() - e.minimum.z()) / spacing)));
    for (int i = 0; i < nt; ++i) {
      const double angle = 2.0 * kPi * (i + 0.5) / nt;
      for (int j = 0; j < nc; ++j) {
        const Eigen::Vector3d p(s.x() * std::cos(angle), s.y() * std::sin(angle),
                                e.minimum.z() + (j + 0.5) * (e.maximum.z() - e.minimum.z()) / nc);
        if (inside_primitive_bounds(primitive, p)) points.push_back(p);
      }
    }
  } else if (is_ellipsoid(type)) {
    const int count = std::max(32, static_cast<int>(std::ceil(ellipsoid_area(s) / (spacing * spacing))));
    for (int i = 0; i < count; ++i) {
      const Eigen::Vector3d p = fibonacci_direction(i, count).cwiseProduct(s);
      if (inside_primitive_bounds(primitive, p)) points.push_back(p);
    }
  } else if (is_cone(type)) {
    // x^2/sa^2 + y^2/sb^2 = c^2: rows of constant c, each ring spaced by arc length.
    const double c0 = e.minimum.z(), c1 = e.maximum.z();
    const double mean_slope = std::sqrt(1.0 + 0.25 * (s.x() + s.y()) * (s.x() + s.y()));
    const int rows = std::max(1, static_cast<int>(std::ceil((c1 - c0) * mean_slope / spacing)));
    for (int j = 0; j < rows; ++j) {
      const double c = c0 + (j + 0.5) * (c1 - c0) / rows;
      const double perimeter = ellipse_perimeter(s.x() * std::abs(c), s.y() * std::abs(c));
      const int nt = std::max(6, static_cast<int>(std::ceil(perimeter / spacing)));
      for (int i = 0; i < nt; ++i) {
        const double angle = 2.0 * kPi * (i + 0.5) / nt;
        const Eigen::Vector3d p(s.x() * std::abs(c) * std::cos(angle), s.y() * std::abs(c) * std::sin(angle), c);
        if (inside_primitive_bounds(primitive, p)) points.push_back(p);
      }
    }
  } else {
    throw Error("primitive '" + primitive.name + "': surface_type " + quadric_type_name(type) +
                " is not simulated (expected plane, sphere, ellipsoid, cylinder or cone)");
  }
  return points;
}

}  // namespace

bool inside_primitive_bounds(const ScenePrimitive& primitive, const Eigen::Vector3d& local_point, double tolerance) {
  const LocalExtent& e = primitive.extent;
  const int first_axis = is_plane(primitive) ? 1 : 0;  // a plane's points have a = 0 by construction
  for (int axis = first_axis; axis < 3; ++axis)
    if (local_point[axis] < e.minimum[axis] - tolerance || local_point[axis] > e.maximum[axis] + tolerance) return false;
  const auto& polygon = primitive.polygon;
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const Eigen::Vector2d& p = polygon[i];
    const Eigen::Vector2d& q = polygon[(i + 1) % polygon.size()];
    const Eigen::Vector2d edge = q - p;
    const Eigen::Vector2d offset(local_point.y() - p.x(), local_point.z() - p.y());
    const double cross = edge.x() * offset.y() - edge.y() * offset.x();
    if (cross < -tolerance * edge.norm()) return false;  // right of a counter-clockwise edge = outside
  }
  return true;
}

Quadric surface_quadric(const ScenePrimitive& primitive) {
  return Quadric::from_canonical(primitive.surface_type, primitive.scale, primitive.pose);
}

Quadric model_quadric(const ScenePrimitive& primitive) {
  return Quadric::from_canonical(primitive.model_type, primitive.scale, primitive.pose);
}

QuadricDecomposition primitive_shape(const ScenePrimitive& primitive) {
  QuadricDecomposition shape;
  shape.type = primitive.surface_type;
  shape.scale = primitive.scale;
  shape.rotation = primitive.pose.linear();
  shape.center = primitive.pose.translation();
  shape.indicators = degeneracy_indicators(primitive.surface_type);
  const QuadricType type = primitive.surface_type;
  if (type == QuadricType::Plane) {
    shape.center_kind = CenterKind::PlanarCenter;
    shape.rank_q33 = 1;
  } else if (is_cylinder(type)) {
    shape.center_kind = CenterKind::LinearCenter;
    shape.rank_q33 = 2;
  } else {
    shape.center_kind = CenterKind::Central;
    shape.rank_q33 = 3;
  }
  const Eigen::Vector3d& s = primitive.scale;
  if (type == QuadricType::Plane) {
    shape.eigenvalues = Eigen::Vector3d(1.0 / (s.x() * s.x()), 0.0, 0.0);
    shape.constant = 0.0;
  } else if (is_cylinder(type)) {
    shape.eigenvalues = Eigen::Vector3d(1.0 / (s.x() * s.x()), 1.0 / (s.y() * s.y()), 0.0);
    shape.constant = -1.0;
  } else if (is_cone(type)) {
    shape.eigenvalues = Eigen::Vector3d(1.0 / (s.x() * s.x()), 1.0 / (s.y() * s.y()), -1.0);
    shape.constant = 0.0;
  } else {
    shape.eigenvalues = s.cwiseProduct(s).cwiseInverse();
    shape.constant = -1.0;
  }
  shape.rank_q = shape.rank_q33 + (shape.constant != 0.0 ? 1 : 0);
  return shape;
}

Eigen::Matrix3Xd sample_primitive_surface(const ScenePrimitive& primitive, double spacing) {
  if (!(spacing > 0.0)) throw Error("sample_primitive_surface: spacing must be positive, got " + std::to_string(spacing));
  const auto local = local_samples(primitive, spacing);
  Eigen::Matrix3Xd world(3, static_cast<Eigen::Index>(local.size()));
  for (std::size_t i = 0; i < local.size(); ++i) world.col(static_cast<Eigen::Index>(i)) = primitive.pose * local[i];
  return world;
}

double primitive_surface_area(const ScenePrimitive& primitive) {
  const LocalExtent& e = primitive.extent;
  const Eigen::Vector3d& s = primitive.scale;
  const QuadricType type = primitive.surface_type;
  if (type == QuadricType::Plane) {
    const double rectangle = (e.maximum.y() - e.minimum.y()) * (e.maximum.z() - e.minimum.z());
    return primitive.polygon.empty() ? rectangle : std::min(rectangle, polygon_area(primitive.polygon));
  }
  if (is_cylinder(type)) return ellipse_perimeter(s.x(), s.y()) * (e.maximum.z() - e.minimum.z());
  if (is_cone(type)) {
    const double mean_slope = std::sqrt(1.0 + 0.25 * (s.x() + s.y()) * (s.x() + s.y()));
    const double c0 = e.minimum.z(), c1 = e.maximum.z();
    return 0.5 * ellipse_perimeter(s.x(), s.y()) * mean_slope * std::abs(c1 * std::abs(c1) - c0 * std::abs(c0));
  }
  // Ellipsoids: full area times the fraction of Fibonacci samples inside the extent.
  const int count = 4096;
  int inside = 0;
  for (int i = 0; i < count; ++i)
    if (inside_primitive_bounds(primitive, fibonacci_direction(i, count).cwiseProduct(s))) ++inside;
  return ellipsoid_area(s) * inside / count;
}

QuadricRecord ground_truth_record(const ScenePrimitive& primitive, int sample_count) {
  const double area = std::max(primitive_surface_area(primitive), 1e-6);
  const double spacing = std::sqrt(area / std::max(16, sample_count));
  const Eigen::Matrix3Xd samples = sample_primitive_surface(primitive, spacing);
  return make_quadric_record(static_cast<std::uint32_t>(primitive.label), model_quadric(primitive),
                             statistical_pose(samples));
}

std::vector<std::pair<std::string, int>> count_model_types(const Scene& scene) {
  std::map<std::string, int> counts;
  for (const auto& primitive : scene.primitives) ++counts[quadric_type_name(primitive.model_type)];
  return {counts.begin(), counts.end()};
}

// ---------------------------------------------------------------------------------------------
// Scene builder helpers

namespace {

/// Appends primitives with consecutive ids and unique names.
class SceneBuilder {
 public:
  explicit SceneBuilder(Scene& scene) : scene_(scene) {}

  /// Appends a primitive of another scene under the next id.
  void copy(const ScenePrimitive& primitive) {
    ScenePrimitive copied = primitive;
    copied.id = static_cast<std::uint32_t>(scene_.primitives.size());
    add(copied);
  }

  /// Rectangle spanned from `corner` by the perpendicular edges `edge_b` and `edge_c`.
  void rectangle(const std::string& name, SemanticLabel label, const Eigen::Vector3d& corner,
                 const Eigen::Vector3d& edge_b, const Eigen::Vector3d& edge_c) {
    polygon_plane(name, label, corner, edge_b, edge_c, {});
  }

  /// Plane region inside the rectangle (corner, edge_b, edge_c) and a convex polygon in (b, c) metres.
  void polygon_plane(const std::string& name, SemanticLabel label, const Eigen::Vector3d& corner,
                     const Eigen::Vector3d& edge_b, const Eigen::Vector3d& edge_c, std::vector<Eigen::Vector2d> polygon) {
    const Eigen::Vector3d b = edge_b.normalized();
    const Eigen::Vector3d a = edge_b.cross(edge_c).normalized();
    const Eigen::Vector3d c = a.cross(b);
    Eigen::Matrix3d rotation;
    rotation << a, b, c;
    ScenePrimitive primitive = base(name, label, QuadricType::Plane, QuadricType::Plane);
    primitive.scale = Eigen::Vector3d::Ones();
    primitive.pose = make_pose(rotation, corner);
    primitive.extent.minimum = Eigen::Vector3d(0.0, 0.0, 0.0);
    primitive.extent.maximum = Eigen::Vector3d(0.0, edge_b.norm(), std::abs(edge_c.dot(c)));
    primitive.polygon = std::move(polygon);
    add(primitive);
  }

  /// Circular cylinder of `radius` from `base_center` along `axis` for `length` metres.
  void cylinder(const std::string& name, SemanticLabel label, QuadricType model_type, const Eigen::Vector3d& base_center,
                const Eigen::Vector3d& axis, double radius, double length) {
    ScenePrimitive primitive = base(name, label, QuadricType::CircularCylinder, model_type);
    primitive.scale = Eigen::Vector3d(radius, radius, radius);
    primitive.pose = make_pose(basis_with_third_axis(axis), base_center);
    primitive.extent.minimum = Eigen::Vector3d(-radius, -radius, 0.0);
    primitive.extent.maximum = Eigen::Vector3d(radius, radius, length);
    add(primitive);
  }

  /// Sphere or ellipsoid with semi-axes `radii` along the columns of `rotation`, keeping local
  /// c in [c_minimum, c_maximum] (clipped bottoms, domes).
  void ellipsoid(const std::string& name, SemanticLabel label, const Eigen::Vector3d& center,
                 const Eigen::Matrix3d& rotation, const Eigen::Vector3d& radii, double c_minimum, double c_maximum) {
    const bool sphere = radii.x() == radii.y() && radii.y() == radii.z();
    const QuadricType type = sphere ? QuadricType::Sphere : QuadricType::Ellipsoid;
    ScenePrimitive primitive = base(name, label, type, type);
    primitive.scale = radii;
    primitive.pose = make_pose(rotation, center);
    primitive.extent.minimum = Eigen::Vector3d(-radii.x(), -radii.y(), std::max(-radii.z(), c_minimum));
    primitive.extent.maximum = Eigen::Vector3d(radii.x(), radii.y(), std::min(radii.z(), c_maximum));
    add(primitive);
  }

  /// Circular cone with apex `apex`, axis `axis` (local +c), tan of the half-angle `tan_half_angle`,
  /// keeping local c in [c_minimum, c_maximum] (negative c = the nappe opposite the axis).
  void cone(const std::string& name, SemanticLabel label, const Eigen::Vector3d& apex, const Eigen::Vector3d& axis,
            double tan_half_angle, double c_minimum, double c_maximum) {
    ScenePrimitive primitive = base(name, label, QuadricType::CircularCone, QuadricType::CircularCone);
    primitive.scale = Eigen::Vector3d(tan_half_angle, tan_half_angle, 1.0);
    primitive.pose = make_pose(basis_with_third_axis(axis), apex);
    const double radius = tan_half_angle * std::max(std::abs(c_minimum), std::abs(c_maximum));
    primitive.extent.minimum = Eigen::Vector3d(-radius, -radius, c_minimum);
    primitive.extent.maximum = Eigen::Vector3d(radius, radius, c_maximum);
    add(primitive);
  }

 private:
  ScenePrimitive base(const std::string& name, SemanticLabel label, QuadricType surface, QuadricType model) const {
    ScenePrimitive primitive;
    primitive.id = static_cast<std::uint32_t>(scene_.primitives.size());
    primitive.name = name;
    primitive.label = label;
    primitive.surface_type = surface;
    primitive.model_type = model;
    return primitive;
  }
  void add(const ScenePrimitive& primitive) { scene_.primitives.push_back(primitive); }

  Scene& scene_;
};

std::string numbered(const std::string& stem, int index) {
  char buffer[16];
  std::snprintf(buffer, sizeof(buffer), "_%02d", index);
  return stem + buffer;
}

Eigen::Matrix3d yaw_rotation(double yaw_radians) {
  return Eigen::AngleAxisd(yaw_radians, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

/// Sensor pose on a road that rises along x with gradient `gradient` (sensor z = road normal).
Eigen::Isometry3d vehicle_pose(double x, double y, double height, double yaw_radians, double gradient) {
  const Eigen::Matrix3d pitch = Eigen::AngleAxisd(-std::atan(gradient), Eigen::Vector3d::UnitY()).toRotationMatrix();
  return make_pose(pitch * yaw_rotation(yaw_radians), Eigen::Vector3d(x, y, gradient * x + height));
}

/// A registration pair on a road: a few metres and tens of degrees apart.
std::vector<Eigen::Isometry3d> vehicle_pair(PortableRandom& random, double gradient, double lateral_limit,
                                            double lateral_center) {
  const double x0 = random.uniform(-6.0, 6.0);
  const double y0 = lateral_center + random.uniform(-lateral_limit, lateral_limit);
  const double yaw0 = degrees(random.uniform(-10.0, 10.0));
  const double distance = random.uniform(3.0, 8.0);
  const double direction = random.bernoulli(0.5) ? 1.0 : -1.0;
  const double x1 = x0 + direction * distance;
  const double y1 = lateral_center + random.uniform(-lateral_limit, lateral_limit);
  const double yaw1 = yaw0 + (random.bernoulli(0.5) ? 1.0 : -1.0) * degrees(random.uniform(15.0, 45.0));
  return {vehicle_pose(x0, y0, 1.73, yaw0, gradient), vehicle_pose(x1, y1, 1.73, yaw1, gradient)};
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Scenes

std::vector<std::string> scene_names() { return {"street", "corridor", "monument"}; }

std::string scene_description(const std::string& name) {
  if (name == "street")
    return "KITTI-like urban block, random layout per seed: sloped road, kerbs, sidewalks, recessed facades, "
           "lamp posts, trees (trunk + crown), parked cars, spherical bollards, traffic cones";
  if (name == "corridor")
    return "long straight highway between barriers and noise walls with evenly spaced median lamp posts and "
           "no end walls: translation along the road is degenerate";
  if (name == "monument")
    return "Pantheon-like monument: 33 cylinders (portico, interior columns, drum), 25 planes, 3 spheres "
           "(dome, two finials), 1 cone (stepped roof ring)";
  throw Error("scene: unknown name '" + name + "' (expected street, corridor or monument)");
}

Foliage foliage_from_name(const std::string& name, const std::string& context) {
  if (name == "solid") return Foliage::Solid;
  if (name == "porous") return Foliage::Porous;
  throw Error(context + ": expected solid or porous, got '" + name + "'");
}

Scene make_scene(const std::string& name, std::uint64_t seed, const StreetOptions& street) {
  if (name == "street") return make_street_scene(seed, street);
  if (street.foliage != Foliage::Solid) throw Error("scene '" + name + "': only the street has foliage to make porous");
  if (name == "corridor") return make_corridor_scene(seed);
  if (name == "monument") return make_monument_scene(seed);
  throw Error("scene: unknown name '" + name + "' (expected street, corridor or monument)");
}

Scene make_street_scene(std::uint64_t seed, const StreetOptions& options) {
  Scene scene;
  scene.name = "street";
  scene.seed = seed;
  scene.description = scene_description("street");
  SceneBuilder builder(scene);
  PortableRandom random(seed);

  const double half_length = 72.0;  // x in [-72, 72], closed by cross facades
  const double drawn_gradient = (random.bernoulli(0.5) ? 1.0 : -1.0) * random.uniform(0.005, 0.03);
  const double gradient = options.level ? 0.0 : drawn_gradient;
  const double road_half_width = random.uniform(3.8, 5.0);
  const double sidewalk_width = random.uniform(2.5, 4.0);
  const double kerb_height = random.uniform(0.12, 0.18);
  const double facade_line = road_half_width + sidewalk_width;  // facade y before its setback
  const auto ground_height = [gradient](double x) { return gradient * x; };
  const Eigen::Vector3d along(2.0 * half_length, 0.0, 2.0 * half_length * gradient);

  builder.rectangle("road", SemanticLabel::Road, Eigen::Vector3d(-half_length, -road_half_width, ground_height(-half_length)),
                    along, Eigen::Vector3d(0.0, 2.0 * road_half_width, 0.0));
  for (int side_index = 0; side_index < 2; ++side_index) {
    const double side = side_index == 0 ? -1.0 : 1.0;
    const std::string side_name = side < 0 ? "right" : "left";
    const double y_kerb = side * road_half_width;
    // Sidewalk from the kerb to beyond the deepest setback plus recess (hidden under the buildings).
    const double y_outer = side * (facade_line + 4.0);
    const double y_low = std::min(y_kerb, y_outer);
    builder.rectangle("sidewalk_" + side_name, SemanticLabel::Sidewalk,
                      Eigen::Vector3d(-half_length, y_low, ground_height(-half_length) + kerb_height), along,
                      Eigen::Vector3d(0.0, std::abs(y_outer - y_kerb), 0.0));
    builder.rectangle("kerb_" + side_name, SemanticLabel::Kerb,
                      Eigen::Vector3d(-half_length, y_kerb, ground_height(-half_length)), along,
                      Eigen::Vector3d(0.0, 0.0, kerb_height));

    // Facades: a row of buildings with random widths, heights, setbacks and recessed entrances.
    double x = -half_length;
    int building = 0;
    double previous_setback = 0.0, previous_top = 0.0;
    while (x < half_length - 1e-9) {
      double width = random.uniform(10.0, 24.0);
      if (half_length - (x + width) < 8.0) width = half_length - x;
      const double setback = random.uniform(0.0, 1.5);
      const double height = random.uniform(8.0, 24.0);
      const double y_facade = side * (facade_line + setback);
      const double bottom = std::min(ground_height(x), ground_height(x + width)) - 1.0;
      const double top = std::max(ground_height(x), ground_height(x + width)) + height;
      const std::string stem = numbered("facade_" + side_name, building);
      const Eigen::Vector3d up(0.0, 0.0, 1.0);
      if (building > 0 && std::abs(setback - previous_setback) > 1e-9) {
        // Side wall of whichever building stands nearer the street, at the boundary.
        const double near = side * (facade_line + std::min(setback, previous_setback));
        const double far = side * (facade_line + std::max(setback, previous_setback));
        const double wall_top = setback < previous_setback ? top : previous_top;
        builder.rectangle(stem + "_side", SemanticLabel::Facade, Eigen::Vector3d(x, std::min(near, far), bottom),
                          Eigen::Vector3d(0.0, std::abs(far - near), 0.0), up * (wall_top - bottom));
      }
      if (width >= 12.0 && random.bernoulli(0.5)) {
        const double recess_width = random.uniform(2.5, 5.0);
        const double recess_depth = random.uniform(0.8, 2.0);
        const double recess_height = random.uniform(3.5, 6.0);
        const double start = x + random.uniform(2.0, width - recess_width - 2.0);
        const double end = start + recess_width;
        const double recess_top = std::max(ground_height(start), ground_height(end)) + kerb_height + recess_height;
        const double y_back = y_facade + side * recess_depth;
        builder.rectangle(stem + "_left_part", SemanticLabel::Facade, Eigen::Vector3d(x, y_facade, bottom),
                          Eigen::Vector3d(start - x, 0.0, 0.0), up * (top - bottom));
        builder.rectangle(stem + "_right_part", SemanticLabel::Facade, Eigen::Vector3d(end, y_facade, bottom),
                          Eigen::Vector3d(x + width - end, 0.0, 0.0), up * (top - bottom));
        builder.rectangle(stem + "_above_recess", SemanticLabel::Facade, Eigen::Vector3d(start, y_facade, recess_top),
                          Eigen::Vector3d(recess_width, 0.0, 0.0), up * (top - recess_top));
        builder.rectangle(stem + "_recess_back", SemanticLabel::Facade, Eigen::Vector3d(start, y_back, bottom),
                          Eigen::Vector3d(recess_width, 0.0, 0.0), up * (recess_top - bottom));
        const double y_low_recess = std::min(y_facade, y_back);
        builder.rectangle(stem + "_recess_jamb_a", SemanticLabel::Facade, Eigen::Vector3d(start, y_low_recess, bottom),
                          Eigen::Vector3d(0.0, recess_depth, 0.0), up * (recess_top - bottom));
        builder.rectangle(stem + "_recess_jamb_b", SemanticLabel::Facade, Eigen::Vector3d(end, y_low_recess, bottom),
                          Eigen::Vector3d(0.0, recess_depth, 0.0), up * (recess_top - bottom));
        builder.rectangle(stem + "_recess_soffit", SemanticLabel::Facade, Eigen::Vector3d(start, y_low_recess, recess_top),
                          Eigen::Vector3d(recess_width, 0.0, 0.0), Eigen::Vector3d(0.0, recess_depth, 0.0));
      } else {
        builder.rectangle(stem, SemanticLabel::Facade, Eigen::Vector3d(x, y_facade, bottom),
                          Eigen::Vector3d(width, 0.0, 0.0), up * (top - bottom));
      }
      previous_setback = setback;
      previous_top = top;
      x += width;
      ++building;
    }
  }
  // Cross facades closing both ends of the block.
  for (int end_index = 0; end_index < 2; ++end_index) {
    const double x_end = end_index == 0 ? -half_length : half_length;
    const double height = random.uniform(12.0, 25.0);
    const double half_width = facade_line + 2.5;
    builder.rectangle(end_index == 0 ? "facade_end_west" : "facade_end_east", SemanticLabel::Facade,
                      Eigen::Vector3d(x_end, -half_width, ground_height(x_end) - 1.0),
                      Eigen::Vector3d(0.0, 2.0 * half_width, 0.0), Eigen::Vector3d(0.0, 0.0, height + 1.0));
  }
  // Street furniture per side: lamp posts with arms, trees between them, bollards.
  int pole_count = 0, tree_count = 0;
  for (int side_index = 0; side_index < 2; ++side_index) {
    const double side = side_index == 0 ? -1.0 : 1.0;
    const double pole_y = side * (road_half_width + 0.45);
    double x = -half_length + random.uniform(4.0, 12.0);
    while (x < half_length - 6.0) {
      const double base = ground_height(x) + kerb_height - 0.05;
      const double height = random.uniform(5.5, 9.0);
      const double radius = random.uniform(0.06, 0.10);
      builder.cylinder(numbered("lamp_post", pole_count), SemanticLabel::Pole, QuadricType::Line,
                       Eigen::Vector3d(x, pole_y, base), Eigen::Vector3d::UnitZ(), radius, height);
      if (random.bernoulli(0.6)) {
        builder.cylinder(numbered("lamp_arm", pole_count), SemanticLabel::Pole, QuadricType::Line,
                         Eigen::Vector3d(x, pole_y, base + height - 0.25), Eigen::Vector3d(0.0, -side, 0.0), 0.05,
                         random.uniform(1.2, 2.2));
      }
      ++pole_count;
      const double spacing = random.uniform(14.0, 24.0);
      const double tree_x = x + 0.5 * spacing;
      if (tree_x < half_length - 4.0 && random.bernoulli(0.7)) {
        const double tree_y = side * (road_half_width + random.uniform(1.0, 1.6));
        const double tree_base = ground_height(tree_x) + kerb_height - 0.05;
        const double trunk_height = random.uniform(2.2, 3.5);
        const double trunk_radius = random.uniform(0.12, 0.25);
        const double room = sidewalk_width - 0.8;
        const Eigen::Vector3d crown_radii(std::min(room, random.uniform(1.3, 2.3)), std::min(room, random.uniform(1.3, 2.3)),
                                          random.uniform(1.5, 3.0));
        const double crown_center = tree_base + trunk_height + 0.6 * crown_radii.z();
        builder.cylinder(numbered("tree_trunk", tree_count), SemanticLabel::Trunk, QuadricType::CircularCylinder,
                         Eigen::Vector3d(tree_x, tree_y, tree_base), Eigen::Vector3d::UnitZ(), trunk_radius,
                         crown_center - tree_base);
        builder.ellipsoid(numbered("tree_crown", tree_count), SemanticLabel::Vegetation,
                          Eigen::Vector3d(tree_x, tree_y, crown_center), yaw_rotation(random.uniform(0.0, kPi)),
                          crown_radii, -crown_radii.z(), crown_radii.z());
        ++tree_count;
      }
      x += spacing;
    }
  }
  // Parked cars in both parking lanes.
  int car_count = 0;
  for (int side_index = 0; side_index < 2; ++side_index) {
    const double side = side_index == 0 ? -1.0 : 1.0;
    double x = -half_length + random.uniform(2.0, 8.0);
    while (x < half_length - 6.0) {
      if (random.bernoulli(0.55)) {
        const Eigen::Vector3d radii(random.uniform(2.0, 2.4), random.uniform(0.85, 0.95), random.uniform(0.7, 0.8));
        const double center_x = x + radii.x();
        const double yaw = degrees(random.uniform(-3.0, 3.0));
        const Eigen::Matrix3d rotation =
            Eigen::AngleAxisd(-std::atan(gradient), Eigen::Vector3d::UnitY()).toRotationMatrix() * yaw_rotation(yaw);
        const Eigen::Vector3d center(center_x, side * (road_half_width - 1.15),
                                     ground_height(center_x) + 0.25 + 0.7 * radii.z());
        builder.ellipsoid(numbered("car", car_count), SemanticLabel::Car, center, rotation, radii, -0.7 * radii.z(),
                          radii.z());
        ++car_count;
        x += 2.0 * radii.x() + random.uniform(0.8, 3.0);
      } else {
        x += random.uniform(3.0, 10.0);
      }
    }
  }
  // A row of spherical bollards on one sidewalk and traffic cones (road works) on the road.
  {
    const double side = random.bernoulli(0.5) ? 1.0 : -1.0;
    const double start = random.uniform(-60.0, -20.0);
    const int count = random.uniform_integer(3, 5);
    for (int i = 0; i < count; ++i) {
      const double bx = start + 1.6 * i;
      const double radius = random.uniform(0.2, 0.3);
      builder.ellipsoid(numbered("bollard", i), SemanticLabel::Bollard,
                        Eigen::Vector3d(bx, side * (road_half_width + 0.3), ground_height(bx) + kerb_height + 0.8 * radius),
                        Eigen::Matrix3d::Identity(), Eigen::Vector3d::Constant(radius), -0.8 * radius, radius);
    }
  }
  {
    const double side = random.bernoulli(0.5) ? 1.0 : -1.0;
    const double start = random.uniform(20.0, 45.0);
    const int count = random.uniform_integer(3, 5);
    for (int i = 0; i < count; ++i) {
      const double cx = start + 2.5 * i;
      const double height = random.uniform(0.5, 0.75);
      const double tan_half_angle = random.uniform(0.25, 0.32);
      const Eigen::Vector3d apex(cx, side * (road_half_width - 2.4), ground_height(cx) + height);
      builder.cone(numbered("traffic_cone", i), SemanticLabel::TrafficCone, apex, Eigen::Vector3d::UnitZ(),
                   tan_half_angle, -height, -0.05);
    }
  }

  scene.default_lidar_poses = vehicle_pair(random, gradient, 1.0, 0.0);
  for (int station = 0; station < 6; ++station) {
    const double x = -45.0 + 18.0 * station;
    scene.default_tls_stations.push_back(
        make_pose(Eigen::Matrix3d::Identity(), Eigen::Vector3d(x, station % 2 == 0 ? -1.0 : 1.0, ground_height(x) + 1.8)));
  }
  if (options.foliage == Foliage::Porous) {
    // Foliage a LiDAR sees into: crowns and hedges stop a ray at an exponential depth inside them. A
    // mean free path of 0.4 m spreads a crown's returns through its outer metre, as leaves do. The
    // hedges are drawn from their own stream, so the rest of the layout is that of solid foliage.
    constexpr double kFoliageMeanFreePath = 0.4;
    for (ScenePrimitive& primitive : scene.primitives)
      if (primitive.label == SemanticLabel::Vegetation) primitive.mean_free_path = kFoliageMeanFreePath;
    PortableRandom hedge_random(mix_bits(seed ^ 0x4ED6E5ULL));
    int hedge_count = 0;
    for (int side_index = 0; side_index < 2; ++side_index) {
      const double side = side_index == 0 ? -1.0 : 1.0;
      double x = -half_length + hedge_random.uniform(1.0, 6.0);
      while (x < half_length - 3.0) {
        const double length = std::min(hedge_random.uniform(2.0, 9.0), half_length - 1.0 - x);
        if (length > 1.5 && hedge_random.bernoulli(0.8)) {
          // An ellipsoid along the facade, its lower part cut below the sidewalk (hidden under it).
          const double half_width = hedge_random.uniform(0.4, 0.8), height = hedge_random.uniform(0.8, 2.0);
          const double center_x = x + 0.5 * length;
          const Eigen::Vector3d center(center_x, side * (facade_line - half_width - 0.1),
                                       ground_height(center_x) + kerb_height + 0.1 * height);
          builder.ellipsoid(numbered("hedge", hedge_count++), SemanticLabel::Vegetation, center,
                            Eigen::AngleAxisd(std::atan(gradient), -Eigen::Vector3d::UnitY()).toRotationMatrix(),
                            Eigen::Vector3d(0.5 * length, half_width, 0.9 * height), -0.3 * height, 0.9 * height);
          scene.primitives.back().mean_free_path = kFoliageMeanFreePath;
        }
        x += length + hedge_random.uniform(0.5, 4.0);
      }
    }
  }
  return scene;
}

namespace {

// The measures of a street that a second pass needs, read back from make_street_scene's primitives.
struct StreetMeasures {
  double gradient = 0.0;         // road rise per metre along x
  double road_half_width = 0.0;  // m
  double kerb_height = 0.0;      // m
};

StreetMeasures measure_street(const Scene& street) {
  StreetMeasures measures;
  for (const ScenePrimitive& primitive : street.primitives) {
    if (primitive.name == "road") {
      const Eigen::Vector3d along = primitive.pose.linear().col(1);  // the rectangle's edge_b: the road's length
      measures.gradient = along.z() / along.x();
      measures.road_half_width = 0.5 * primitive.extent.maximum.z();
    } else if (primitive.name == "kerb_right") {
      measures.kerb_height = primitive.extent.maximum.z();
    }
  }
  if (!(measures.road_half_width > 0.0 && measures.kerb_height > 0.0))
    throw Error("make_street_pass: the street has no road or kerb primitive");
  return measures;
}

// A parked car as make_street_scene draws one: an ellipsoid of `radii` centred over x in the parking lane.
void add_parked_car(SceneBuilder& builder, const std::string& name, const StreetMeasures& street, double side,
                    double center_x, const Eigen::Vector3d& radii, double yaw) {
  const Eigen::Matrix3d rotation =
      Eigen::AngleAxisd(-std::atan(street.gradient), Eigen::Vector3d::UnitY()).toRotationMatrix() * yaw_rotation(yaw);
  const Eigen::Vector3d center(center_x, side * (street.road_half_width - 1.15),
                               street.gradient * center_x + 0.25 + 0.7 * radii.z());
  builder.ellipsoid(name, SemanticLabel::Car, center, rotation, radii, -0.7 * radii.z(), radii.z());
}

// New parked cars in the free kerb space of both lanes: `occupied` holds each lane's taken x intervals.
void park_new_cars(SceneBuilder& builder, PortableRandom& random, const StreetMeasures& street, int pass,
                   std::vector<std::pair<double, double>> occupied[2]) {
  int count = 0;
  for (int side_index = 0; side_index < 2; ++side_index) {
    const double side = side_index == 0 ? -1.0 : 1.0;
    const int wanted = random.uniform_integer(2, 6);
    for (int attempt = 0, added = 0; attempt < 40 && added < wanted; ++attempt) {
      const Eigen::Vector3d radii(random.uniform(2.0, 2.4), random.uniform(0.85, 0.95), random.uniform(0.7, 0.8));
      const double center_x = random.uniform(-64.0, 64.0);
      const double yaw = degrees(random.uniform(-3.0, 3.0));
      const double low = center_x - radii.x() - 0.5, high = center_x + radii.x() + 0.5;
      bool free = true;
      for (const auto& interval : occupied[side_index]) free = free && (high < interval.first || low > interval.second);
      if (!free) continue;
      occupied[side_index].emplace_back(low, high);
      add_parked_car(builder, numbered("car_pass" + std::to_string(pass), count++), street, side, center_x, radii, yaw);
      ++added;
    }
  }
}

// Pedestrians: most on the sidewalks, some crossing the road.
void add_pedestrians(SceneBuilder& builder, PortableRandom& random, const StreetMeasures& street, int pass) {
  const int count = random.uniform_integer(6, 14);
  for (int i = 0; i < count; ++i) {
    const double x = random.uniform(-64.0, 64.0);
    const bool crossing = random.bernoulli(0.2);
    const double side = random.bernoulli(0.5) ? 1.0 : -1.0;
    const double y = crossing ? random.uniform(-street.road_half_width + 0.5, street.road_half_width - 0.5)
                              : side * (street.road_half_width + random.uniform(0.6, 2.2));
    const Eigen::Vector3d radii(random.uniform(0.22, 0.3), random.uniform(0.15, 0.22), random.uniform(0.8, 0.9));
    const double base = street.gradient * x + (crossing ? 0.0 : street.kerb_height);
    builder.ellipsoid(numbered("pedestrian_pass" + std::to_string(pass), i), SemanticLabel::Person,
                      Eigen::Vector3d(x, y, base + radii.z()), yaw_rotation(random.uniform(0.0, 2.0 * kPi)), radii,
                      -radii.z(), radii.z());
  }
}

}  // namespace

StreetPass make_street_pass(std::uint64_t seed, int pass, double scan_spacing, const StreetOptions& options) {
  if (pass < 1) throw Error("make_street_pass: pass must be at least 1, got " + std::to_string(pass));
  if (!(scan_spacing > 0.0)) throw Error("make_street_pass: scan_spacing must be positive, got " + std::to_string(scan_spacing));
  const Scene street = make_street_scene(seed, options);
  const StreetMeasures measures = measure_street(street);
  PortableRandom random(mix_bits(seed * 1000003ULL + static_cast<std::uint64_t>(pass)));
  StreetPass result;
  Scene& scene = result.scene;
  scene.name = street.name;
  scene.seed = seed;
  scene.description = street.description + "; pass " + std::to_string(pass) + ": parked cars re-drawn, pedestrians added";
  scene.default_lidar_poses = street.default_lidar_poses;
  scene.default_tls_stations = street.default_tls_stations;
  SceneBuilder builder(scene);
  std::vector<std::pair<double, double>> occupied[2];
  for (const ScenePrimitive& primitive : street.primitives) {
    if (primitive.label != SemanticLabel::Car) {
      builder.copy(primitive);
      continue;
    }
    if (!random.bernoulli(0.5)) continue;  // this car has left
    builder.copy(primitive);
    const double center_x = primitive.pose.translation().x();
    occupied[primitive.pose.translation().y() < 0.0 ? 0 : 1].emplace_back(center_x - primitive.scale.x() - 0.5,
                                                                           center_x + primitive.scale.x() + 0.5);
  }
  park_new_cars(builder, random, measures, pass, occupied);
  add_pedestrians(builder, random, measures, pass);

  const bool forward = pass % 2 == 1;
  const double lane = (forward ? -0.5 : 0.5) * measures.road_half_width;
  // Every pass after the first starts half a spacing later, so no scan repeats a first-pass position.
  for (double along = -48.0 + (pass == 1 ? 0.0 : 0.5 * scan_spacing); along <= 48.0 + 1e-9; along += scan_spacing) {
    const double x = forward ? along : -along;
    const double yaw = (forward ? 0.0 : kPi) + degrees(random.uniform(-4.0, 4.0));
    result.poses.push_back(vehicle_pose(x, lane + random.uniform(-0.5, 0.5), 1.73, yaw, measures.gradient));
  }
  return result;
}

Scene make_corridor_scene(std::uint64_t seed) {
  Scene scene;
  scene.name = "corridor";
  scene.seed = seed;
  scene.description = scene_description("corridor");
  SceneBuilder builder(scene);
  PortableRandom random(seed);

  const double half_length = 160.0;  // longer than every sensor's range: the ends are never seen
  const double gradient = random.uniform(-0.01, 0.01);
  const double half_width = random.uniform(7.0, 9.0);  // edge of the carriageway
  const double verge_width = random.uniform(2.0, 3.0);
  const double barrier_height = random.uniform(0.8, 1.0);
  const double wall_height = random.uniform(3.5, 5.0);
  const double pole_spacing = random.uniform(25.0, 40.0);
  const double pole_phase = random.uniform(0.0, pole_spacing);
  const auto ground_height = [gradient](double x) { return gradient * x; };
  const Eigen::Vector3d along(2.0 * half_length, 0.0, 2.0 * half_length * gradient);
  const Eigen::Vector3d start_point(-half_length, 0.0, ground_height(-half_length));
  const Eigen::Vector3d up(0.0, 0.0, 1.0);

  builder.rectangle("road", SemanticLabel::Road, start_point + Eigen::Vector3d(0.0, -half_width, 0.0), along,
                    Eigen::Vector3d(0.0, 2.0 * half_width, 0.0));
  builder.rectangle("median_barrier_right_face", SemanticLabel::Barrier, start_point + Eigen::Vector3d(0.0, -0.3, 0.0),
                    along, up * 0.9);
  builder.rectangle("median_barrier_left_face", SemanticLabel::Barrier, start_point + Eigen::Vector3d(0.0, 0.3, 0.0),
                    along, up * 0.9);
  for (int side_index = 0; side_index < 2; ++side_index) {
    const double side = side_index == 0 ? -1.0 : 1.0;
    const std::string side_name = side < 0 ? "right" : "left";
    builder.rectangle("shoulder_barrier_" + side_name, SemanticLabel::Barrier,
                      start_point + Eigen::Vector3d(0.0, side * half_width, 0.0), along, up * barrier_height);
    const double y_low = side < 0 ? -(half_width + verge_width) : half_width;
    builder.rectangle("verge_" + side_name, SemanticLabel::Ground, start_point + Eigen::Vector3d(0.0, y_low, 0.0), along,
                      Eigen::Vector3d(0.0, verge_width, 0.0));
    builder.rectangle("noise_wall_" + side_name, SemanticLabel::Barrier,
                      start_point + Eigen::Vector3d(0.0, side * (half_width + verge_width), -0.5), along,
                      up * (wall_height + 0.5));
  }
  // Evenly spaced median lamp posts with an arm over each carriageway: repetitive by design.
  int pole = 0;
  for (double x = -half_length + pole_phase; x < half_length; x += pole_spacing) {
    const double base = ground_height(x) + 0.9;  // standing on the median barrier
    builder.cylinder(numbered("median_lamp_post", pole), SemanticLabel::Pole, QuadricType::Line,
                     Eigen::Vector3d(x, 0.0, base - 0.2), Eigen::Vector3d::UnitZ(), 0.1, 10.2);
    builder.cylinder(numbered("median_lamp_arm_right", pole), SemanticLabel::Pole, QuadricType::Line,
                     Eigen::Vector3d(x, 0.0, base + 9.5), -Eigen::Vector3d::UnitY(), 0.06, 2.5);
    builder.cylinder(numbered("median_lamp_arm_left", pole), SemanticLabel::Pole, QuadricType::Line,
                     Eigen::Vector3d(x, 0.0, base + 9.5), Eigen::Vector3d::UnitY(), 0.06, 2.5);
    ++pole;
  }
  scene.default_lidar_poses = vehicle_pair(random, gradient, 0.8, -0.5 * half_width);
  for (int station = 0; station < 6; ++station) {
    const double x = -50.0 + 20.0 * station;
    scene.default_tls_stations.push_back(
        make_pose(Eigen::Matrix3d::Identity(), Eigen::Vector3d(x, -0.5 * half_width, ground_height(x) + 1.8)));
  }
  return scene;
}

Scene make_monument_scene(std::uint64_t seed) {
  Scene scene;
  scene.name = "monument";
  scene.seed = seed;
  scene.description = scene_description("monument");
  SceneBuilder builder(scene);
  PortableRandom random(seed);
  const Eigen::Vector3d up(0.0, 0.0, 1.0), ex(1.0, 0.0, 0.0), ey(0.0, 1.0, 0.0);

  // Dimensions (metres), after the Pantheon: rotunda of radius 21.65 centred at the origin, the
  // portico towards -x, the intermediate block between them.
  const double drum_radius = 21.65;
  const double springing = 21.65;      // height of the dome's centre
  const double drum_top = springing + 8.0;  // the outer drum hides the dome's lower part
  const double podium = 1.5;           // portico floor height
  const double portico_front = -40.0;  // front column row
  const double portico_half_width = 16.5;
  const double entablature_front = portico_front - 1.0;
  const double column_top = 13.5;
  const double entablature_top = 16.0;
  const double pediment_top = 23.0;
  const double block_front = -26.0;
  const double block_half_width = 20.0;
  const double block_top = 30.0;
  const double block_back = -std::sqrt(drum_radius * drum_radius - block_half_width * block_half_width);
  const double door_half_width = 3.0;
  // The door (and its soffit) stops 2 m under the portico ceiling, so the soffit is its own plane
  // and the recessed panel over the door shows between them.
  const double door_top = column_top - 2.0;
  const double door_back = -std::sqrt(drum_radius * drum_radius - door_half_width * door_half_width);
  const double floor_end = -drum_radius - 0.05;

  // --- 25 planes ---------------------------------------------------------------------------
  builder.rectangle("plaza_ground", SemanticLabel::Ground, Eigen::Vector3d(-90.0, -70.0, 0.0), ex * 160.0, ey * 140.0);
  const double step_depth = 1.0, step_height = 0.5;
  const double first_riser = entablature_front - 3.0 * step_depth;
  for (int step = 0; step < 3; ++step) {
    const double x = first_riser + step * step_depth;
    builder.rectangle(numbered("step_riser", step), SemanticLabel::Step,
                      Eigen::Vector3d(x, -portico_half_width, step * step_height), ey * (2.0 * portico_half_width),
                      up * step_height);
    if (step < 2)
      builder.rectangle(numbered("step_tread", step), SemanticLabel::Floor,
                        Eigen::Vector3d(x, -portico_half_width, (step + 1) * step_height), ex * step_depth,
                        ey * (2.0 * portico_half_width));
  }
  const double floor_start = first_riser + 2.0 * step_depth;
  builder.rectangle("portico_floor", SemanticLabel::Floor, Eigen::Vector3d(floor_start, -portico_half_width, podium),
                    ex * (floor_end - floor_start), ey * (2.0 * portico_half_width));
  for (int side = 0; side < 2; ++side) {
    const double y = side == 0 ? -portico_half_width : portico_half_width;
    builder.rectangle(side == 0 ? "podium_side_right" : "podium_side_left", SemanticLabel::Step,
                      Eigen::Vector3d(floor_start, y, 0.0), ex * (block_front - floor_start), up * podium);
  }
  builder.rectangle("portico_ceiling", SemanticLabel::Floor,
                    Eigen::Vector3d(entablature_front, -portico_half_width, column_top), ex * (block_front - entablature_front),
                    ey * (2.0 * portico_half_width));
  builder.rectangle("entablature_front", SemanticLabel::Pediment,
                    Eigen::Vector3d(entablature_front, -portico_half_width, column_top), ey * (2.0 * portico_half_width),
                    up * (entablature_top - column_top));
  for (int side = 0; side < 2; ++side) {
    const double y = side == 0 ? -portico_half_width : portico_half_width;
    builder.rectangle(side == 0 ? "entablature_side_right" : "entablature_side_left", SemanticLabel::Pediment,
                      Eigen::Vector3d(entablature_front, y, column_top), ex * (block_front - entablature_front),
                      up * (entablature_top - column_top));
  }
  {
    const double base = 2.0 * portico_half_width, rise = pediment_top - entablature_top;
    // The tympanum is set back behind the cornice, as on the Pantheon, so it is not the
    // entablature's plane continued.
    const double tympanum_recess = 0.6;
    builder.polygon_plane("pediment", SemanticLabel::Pediment,
                          Eigen::Vector3d(entablature_front + tympanum_recess, -portico_half_width, entablature_top),
                          ey * base, up * rise,
                          {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(base, 0.0), Eigen::Vector2d(0.5 * base, rise)});
    const Eigen::Vector3d slope_right(0.0, portico_half_width, rise);
    builder.rectangle("portico_roof_right", SemanticLabel::Roof,
                      Eigen::Vector3d(entablature_front, -portico_half_width, entablature_top),
                      ex * (block_front - entablature_front), slope_right);
    const Eigen::Vector3d slope_left(0.0, -portico_half_width, rise);
    builder.rectangle("portico_roof_left", SemanticLabel::Roof,
                      Eigen::Vector3d(entablature_front, portico_half_width, entablature_top),
                      ex * (block_front - entablature_front), slope_left);
  }
  builder.rectangle("block_front_right", SemanticLabel::Wall, Eigen::Vector3d(block_front, -block_half_width, 0.0),
                    ey * (block_half_width - door_half_width), up * block_top);
  builder.rectangle("block_front_left", SemanticLabel::Wall, Eigen::Vector3d(block_front, door_half_width, 0.0),
                    ey * (block_half_width - door_half_width), up * block_top);
  // A panel recessed over the door: otherwise the wall over it is the two front walls' plane.
  const double door_panel_recess = 0.5;
  builder.rectangle("block_front_over_door", SemanticLabel::Wall,
                    Eigen::Vector3d(block_front + door_panel_recess, -door_half_width, door_top),
                    ey * (2.0 * door_half_width), up * (block_top - door_top));
  for (int side = 0; side < 2; ++side) {
    const double y = side == 0 ? -door_half_width : door_half_width;
    builder.rectangle(side == 0 ? "door_jamb_right" : "door_jamb_left", SemanticLabel::Wall,
                      Eigen::Vector3d(block_front, y, podium), ex * (door_back - block_front), up * (door_top - podium));
  }
  builder.rectangle("door_soffit", SemanticLabel::Wall, Eigen::Vector3d(block_front, -door_half_width, door_top),
                    ex * (door_back - block_front), ey * (2.0 * door_half_width));
  for (int side = 0; side < 2; ++side) {
    const double y = side == 0 ? -block_half_width : block_half_width;
    builder.rectangle(side == 0 ? "block_side_right" : "block_side_left", SemanticLabel::Wall,
                      Eigen::Vector3d(block_front, y, 0.0), ex * (block_back - block_front), up * block_top);
  }
  builder.rectangle("block_roof", SemanticLabel::Roof, Eigen::Vector3d(block_front, -block_half_width, block_top),
                    ex * (floor_end - block_front), ey * (2.0 * block_half_width));

  // --- 33 cylinders -------------------------------------------------------------------------
  builder.cylinder("rotunda_drum", SemanticLabel::Wall, QuadricType::CircularCylinder, Eigen::Vector3d::Zero(), up,
                   drum_radius, drum_top);
  const double column_radius = 0.75;
  int column = 0;
  for (int i = 0; i < 8; ++i) {  // front row of eight
    const double y = -14.0 + 4.0 * i;
    builder.cylinder(numbered("portico_column", column++), SemanticLabel::Column, QuadricType::CircularCylinder,
                     Eigen::Vector3d(portico_front, y, podium), up, column_radius, column_top - podium);
  }
  for (double x : {portico_front + 5.0, portico_front + 10.0})  // two rows of four behind
    for (double y : {-10.0, -6.0, 6.0, 10.0})
      builder.cylinder(numbered("portico_column", column++), SemanticLabel::Column, QuadricType::CircularCylinder,
                       Eigen::Vector3d(x, y, podium), up, column_radius, column_top - podium);
  for (int i = 0; i < 16; ++i) {  // interior ring, clear of the door axis
    const double angle = (i + 0.5) * 2.0 * kPi / 16.0;
    builder.cylinder(numbered("interior_column", i), SemanticLabel::Column, QuadricType::CircularCylinder,
                     Eigen::Vector3d(19.0 * std::cos(angle), 19.0 * std::sin(angle), 0.0), up, 0.55, 12.0);
  }

  // --- 3 spheres and 1 cone -------------------------------------------------------------------
  const double oculus_radius = 4.5;
  builder.ellipsoid("dome", SemanticLabel::Dome, Eigen::Vector3d(0.0, 0.0, springing), Eigen::Matrix3d::Identity(),
                    Eigen::Vector3d::Constant(drum_radius), 0.0,
                    std::sqrt(drum_radius * drum_radius - oculus_radius * oculus_radius));
  for (int side = 0; side < 2; ++side) {
    const double radius = 0.8;
    builder.ellipsoid(side == 0 ? "finial_right" : "finial_left", SemanticLabel::Ornament,
                      Eigen::Vector3d(first_riser - 3.0, side == 0 ? -12.0 : 12.0, 0.95 * radius),
                      Eigen::Matrix3d::Identity(), Eigen::Vector3d::Constant(radius), -0.95 * radius, radius);
  }
  {
    // Stepped ring on the drum: a frustum from the drum top inwards, staying outside the dome.
    // tan 0.5: radius 21.65 -> 17.65 over 8 m while the dome shrinks 20.1 -> 14.6; steep enough to be
    // seen from the plaza beyond ~36 m from the axis.
    const double tan_half_angle = 0.5;
    const double apex_height = drum_top + drum_radius / tan_half_angle;
    builder.cone("roof_ring", SemanticLabel::Roof, Eigen::Vector3d(0.0, 0.0, apex_height), up, tan_half_angle,
                 -(apex_height - drum_top), -(apex_height - (springing + 16.0)));
  }

  // Sensors: a LiDAR pair on the plaza facing the portico; TLS stations (below).
  const double yaw0 = degrees(random.uniform(-10.0, 10.0));
  const double yaw1 = yaw0 + degrees(random.uniform(20.0, 35.0));
  scene.default_lidar_poses = {make_pose(yaw_rotation(yaw0), Eigen::Vector3d(-72.0, -5.0, 1.8)),
                               make_pose(yaw_rotation(yaw1), Eigen::Vector3d(-66.0, 3.0, 1.8))};
  // A survey that sees every face, as a heritage TLS campaign is planned: two stations on the plaza
  // diagonals (steps, portico front and sides), one in the portico, one behind on the right (drum,
  // roof ring, block side), two inside (dome, interior columns) and one on the intermediate block's
  // roof (block roof, portico roof slopes), where ground stations cannot see.
  const std::vector<Eigen::Vector3d> stations = {
      {-60.0, -26.0, 1.6}, {-60.0, 26.0, 1.6}, {-33.0, 0.0, podium + 1.6}, {12.0, -50.0, 1.6},
      {7.0, 6.0, 1.6},     {-8.0, -7.0, 1.6},  {block_front + 2.2, 0.0, block_top + 1.6}};
  for (std::size_t i = 0; i < stations.size(); ++i)
    scene.default_tls_stations.push_back(make_pose(yaw_rotation(degrees(30.0 * static_cast<double>(i))), stations[i]));
  return scene;
}

}  // namespace quadrix
