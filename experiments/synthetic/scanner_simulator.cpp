// Scanner simulator: sensor presets, ray patterns, exact ray-primitive intersection, a bounding
// volume hierarchy, and the parallel scan loop.
#include "experiments/synthetic/scanner_simulator.h"

#include "geometry/constants.h"
#include "geometry/error.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>

namespace quadrix {

// ---------------------------------------------------------------------------------------------
// Sensors

namespace {

std::vector<double> linear_spacing(double first, double last, int count) {
  std::vector<double> values(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) values[static_cast<std::size_t>(i)] = first + (last - first) * i / (count - 1);
  return values;
}

int dome_rows(const SensorModel& sensor) {
  return static_cast<int>(std::lround((sensor.dome_max_elevation_deg - sensor.dome_min_elevation_deg) /
                                      sensor.dome_angular_step_deg)) + 1;
}
int dome_columns(const SensorModel& sensor) {
  return static_cast<int>(std::lround(360.0 / sensor.dome_angular_step_deg));
}

Eigen::Vector3d direction_from_angles(double azimuth_deg, double elevation_deg) {
  const double azimuth = azimuth_deg * kPi / 180.0, elevation = elevation_deg * kPi / 180.0;
  return {std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth), std::sin(elevation)};
}

}  // namespace

std::size_t SensorModel::ray_count() const {
  switch (pattern) {
    case ScanPattern::Spinning:
      return beam_elevations_deg.size() * static_cast<std::size_t>(std::max(azimuth_steps, 0));
    case ScanPattern::Rosette:
      return static_cast<std::size_t>(std::max(rosette_samples, 0));
    case ScanPattern::Dome:
      return static_cast<std::size_t>(std::max(dome_rows(*this), 0)) *
             static_cast<std::size_t>(std::max(dome_columns(*this), 0));
  }
  return 0;
}

std::vector<std::string> sensor_names() { return {"hdl64", "vlp16", "livox", "tls"}; }

SensorModel sensor_preset(const std::string& name) {
  SensorModel sensor;
  sensor.name = name;
  if (name == "hdl64") {
    sensor.description = "Velodyne HDL-64E: 64 beams +2.0..-24.8 deg (upper block 1/3 deg, lower ~1/2 deg), "
                         "2000 azimuth steps, 0.9-120 m, 2 cm noise, 1% dropout";
    sensor.pattern = ScanPattern::Spinning;
    sensor.beam_elevations_deg = linear_spacing(2.0, -8.33, 32);
    const auto lower = linear_spacing(-8.83, -24.8, 32);
    sensor.beam_elevations_deg.insert(sensor.beam_elevations_deg.end(), lower.begin(), lower.end());
    sensor.azimuth_steps = 2000;
    sensor.min_range = 0.9;
    sensor.max_range = 120.0;
    sensor.range_noise_sigma = 0.02;
    sensor.dropout_probability = 0.01;
  } else if (name == "vlp16") {
    sensor.description = "Velodyne VLP-16: 16 beams -15..+15 deg every 2 deg, 0.2 deg azimuth, 0.5-100 m, 3 cm noise";
    sensor.pattern = ScanPattern::Spinning;
    sensor.beam_elevations_deg = linear_spacing(-15.0, 15.0, 16);
    sensor.azimuth_steps = 1800;
    sensor.min_range = 0.5;
    sensor.max_range = 100.0;
    sensor.range_noise_sigma = 0.03;
  } else if (name == "livox") {
    sensor.description = "Livox Avia-like: non-repetitive rosette in a 70.4 deg cone around +x, 6 beams, "
                         "24000 samples per 0.1 s frame, 1-190 m, 2 cm noise";
    sensor.pattern = ScanPattern::Rosette;
    sensor.min_range = 1.0;
    sensor.max_range = 190.0;
    sensor.range_noise_sigma = 0.02;
  } else if (name == "tls") {
    sensor.description = "terrestrial laser scanner: full dome -60..+90 deg elevation, 0.2 deg steps "
                         "(1.35 M rays a station), 0.6-300 m, 2 mm noise";
    sensor.pattern = ScanPattern::Dome;
    sensor.min_range = 0.6;
    sensor.max_range = 300.0;
    sensor.range_noise_sigma = 0.002;
  } else {
    throw Error("sensor: unknown name '" + name + "' (expected hdl64, vlp16, livox or tls)");
  }
  return sensor;
}

void validate_sensor(const SensorModel& sensor) {
  const std::string where = "sensor '" + sensor.name + "': ";
  if (!(sensor.min_range >= 0.0) || !(sensor.max_range > sensor.min_range))
    throw Error(where + "min_range/max_range must satisfy 0 <= min_range < max_range");
  if (!(sensor.range_noise_sigma >= 0.0) || !std::isfinite(sensor.range_noise_sigma))
    throw Error(where + "range_noise_sigma must be a finite number >= 0");
  if (!(sensor.dropout_probability >= 0.0 && sensor.dropout_probability < 1.0))
    throw Error(where + "dropout_probability must be in [0, 1)");
  switch (sensor.pattern) {
    case ScanPattern::Spinning:
      if (sensor.beam_elevations_deg.empty()) throw Error(where + "beam_elevations_deg must not be empty");
      if (sensor.azimuth_steps < 1) throw Error(where + "azimuth_steps must be >= 1");
      break;
    case ScanPattern::Rosette:
      if (sensor.rosette_samples < 1 || sensor.rosette_beams < 1)
        throw Error(where + "rosette_samples and rosette_beams must be >= 1");
      if (!(sensor.rosette_field_of_view_deg > 0.0 && sensor.rosette_field_of_view_deg < 180.0))
        throw Error(where + "rosette_field_of_view_deg must be in (0, 180)");
      if (!(sensor.rosette_frame_seconds > 0.0)) throw Error(where + "rosette_frame_seconds must be positive");
      break;
    case ScanPattern::Dome:
      if (!(sensor.dome_angular_step_deg > 0.0)) throw Error(where + "dome_angular_step_deg must be positive");
      if (!(sensor.dome_min_elevation_deg >= -90.0 && sensor.dome_max_elevation_deg <= 90.0 &&
            sensor.dome_min_elevation_deg < sensor.dome_max_elevation_deg))
        throw Error(where + "dome elevations must satisfy -90 <= min < max <= 90");
      break;
  }
}

std::vector<Eigen::Vector3d> sensor_ray_directions(const SensorModel& sensor) {
  validate_sensor(sensor);
  std::vector<Eigen::Vector3d> directions;
  directions.reserve(sensor.ray_count());
  switch (sensor.pattern) {
    case ScanPattern::Spinning:
      // All beams fire at each azimuth step (column-major like a range image).
      for (int step = 0; step < sensor.azimuth_steps; ++step) {
        const double azimuth = 360.0 * step / sensor.azimuth_steps;
        for (double elevation : sensor.beam_elevations_deg) directions.push_back(direction_from_angles(azimuth, elevation));
      }
      break;
    case ScanPattern::Rosette: {
      // Two prisms deflect the beam by FOV/4 each; their sum sweeps a rosette of radius FOV/2.
      const double half_deflection = 0.25 * sensor.rosette_field_of_view_deg;
      const int per_beam = (sensor.rosette_samples + sensor.rosette_beams - 1) / sensor.rosette_beams;
      for (int sample = 0; sample < sensor.rosette_samples; ++sample) {
        const int beam = sample % sensor.rosette_beams;
        const double time = sensor.rosette_frame_seconds * (sample / sensor.rosette_beams) / per_beam;
        const double phase1 = 2.0 * kPi * (sensor.rosette_prism_frequency_1_hz * time +
                                            static_cast<double>(beam) / sensor.rosette_beams);
        const double phase2 = 2.0 * kPi * sensor.rosette_prism_frequency_2_hz * time;
        const double azimuth = half_deflection * (std::cos(phase1) + std::cos(phase2));
        const double elevation = half_deflection * (std::sin(phase1) + std::sin(phase2));
        directions.push_back(direction_from_angles(azimuth, elevation));
      }
      break;
    }
    case ScanPattern::Dome: {
      const int rows = dome_rows(sensor), columns = dome_columns(sensor);
      for (int column = 0; column < columns; ++column) {
        const double azimuth = 360.0 * column / columns;
        for (int row = 0; row < rows; ++row) {
          const double elevation =
              std::min(sensor.dome_max_elevation_deg, sensor.dome_min_elevation_deg + row * sensor.dome_angular_step_deg);
          directions.push_back(direction_from_angles(azimuth, elevation));
        }
      }
      break;
    }
  }
  return directions;
}

// ---------------------------------------------------------------------------------------------
// Ray casting

namespace {

/// A primitive prepared for intersection: f(x) = w . x^2 + w0 in its canonical frame, or a plane a = 0.
struct PreparedPrimitive {
  Eigen::Matrix3d world_to_local = Eigen::Matrix3d::Identity();  // R^T
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();              // pose translation
  bool plane = false;
  Eigen::Vector3d weights = Eigen::Vector3d::Zero();
  double constant = 0.0;
  const ScenePrimitive* source = nullptr;
  Eigen::AlignedBox3d world_box;
};

/// Axis-aligned box test; returns the entry distance or +inf when the ray misses within [0, limit].
struct RayBoxTester {
  Eigen::Vector3d origin, inverse;
  std::array<bool, 3> parallel{};
  RayBoxTester(const Eigen::Vector3d& o, const Eigen::Vector3d& d) : origin(o) {
    for (int axis = 0; axis < 3; ++axis) {
      parallel[static_cast<std::size_t>(axis)] = d[axis] == 0.0;
      inverse[axis] = d[axis] == 0.0 ? 0.0 : 1.0 / d[axis];
    }
  }
  double entry(const Eigen::AlignedBox3d& box, double limit) const {
    double near = 0.0, far = limit;
    for (int axis = 0; axis < 3; ++axis) {
      if (parallel[static_cast<std::size_t>(axis)]) {
        if (origin[axis] < box.min()[axis] || origin[axis] > box.max()[axis]) return std::numeric_limits<double>::infinity();
        continue;
      }
      double t0 = (box.min()[axis] - origin[axis]) * inverse[axis];
      double t1 = (box.max()[axis] - origin[axis]) * inverse[axis];
      if (t0 > t1) std::swap(t0, t1);
      near = std::max(near, t0);
      far = std::min(far, t1);
      if (near > far) return std::numeric_limits<double>::infinity();
    }
    return near;
  }
};

struct HierarchyNode {
  Eigen::AlignedBox3d box;
  int left = -1, right = -1;  // children, or -1 for a leaf
  int first = 0, count = 0;   // leaf: range in the ordered primitive list
};

constexpr double kBoundsTolerance = 1e-9;
constexpr int kLeafSize = 2;

/// Up to two intersections (ascending) of the ray with the primitive's bounded surface in (t_min, t_max].
int intersect_prepared(const PreparedPrimitive& primitive, const Eigen::Vector3d& origin,
                       const Eigen::Vector3d& direction, double t_min, double t_max, std::array<double, 2>& hits) {
  const Eigen::Vector3d o = primitive.world_to_local * (origin - primitive.origin);
  const Eigen::Vector3d d = primitive.world_to_local * direction;
  std::array<double, 2> roots{};
  int root_count = 0;
  if (primitive.plane) {
    if (d.x() == 0.0) return 0;
    roots[0] = -o.x() / d.x();
    root_count = 1;
  } else {
    const Eigen::Vector3d& w = primitive.weights;
    const double a = w.dot(d.cwiseProduct(d));
    const double b = 2.0 * w.dot(o.cwiseProduct(d));
    const double c = w.dot(o.cwiseProduct(o)) + primitive.constant;
    const double scale = w.cwiseAbs().maxCoeff();
    if (std::abs(a) <= 1e-14 * scale) {
      if (b == 0.0) return 0;
      roots[0] = -c / b;
      root_count = 1;
    } else {
      const double discriminant = b * b - 4.0 * a * c;
      if (discriminant < 0.0) return 0;
      const double root = std::sqrt(discriminant);
      const double q = -0.5 * (b + (b >= 0.0 ? root : -root));  // numerically stable pair
      roots[0] = q / a;
      roots[1] = q != 0.0 ? c / q : roots[0];
      if (roots[0] > roots[1]) std::swap(roots[0], roots[1]);
      root_count = 2;
    }
  }
  int count = 0;
  for (int i = 0; i < root_count; ++i) {
    const double t = roots[static_cast<std::size_t>(i)];
    if (!(t > t_min && t <= t_max)) continue;
    if (!inside_primitive_bounds(*primitive.source, o + t * d, kBoundsTolerance)) continue;
    if (count == 1 && t == hits[0]) continue;
    hits[static_cast<std::size_t>(count++)] = t;
  }
  return count;
}

/// Where the ray stops on `primitive` within (t_min, t_max], or +inf where it does not. A solid
/// surface stops it at its first intersection. A porous volume (ScenePrimitive::mean_free_path) lets
/// it travel an exponentially distributed depth past its entry (Beer-Lambert attenuation), drawn from
/// the ray and the primitive, so one ray always stops at one place: it stops there when that is
/// before its exit, else passes through. A ray that meets the volume's surface once leaves it through
/// its cut (a hedge's, under the sidewalk) and is not limited by an exit.
double stopping_range(const PreparedPrimitive& primitive, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                      double t_min, double t_max) {
  constexpr double kNone = std::numeric_limits<double>::infinity();
  std::array<double, 2> hits{};
  const double free_path = primitive.source->mean_free_path;
  if (!(free_path > 0.0)) return intersect_prepared(primitive, origin, direction, t_min, t_max, hits) > 0 ? hits[0] : kNone;
  const int count = intersect_prepared(primitive, origin, direction, t_min, kNone, hits);
  if (count == 0) return kNone;
  std::uint64_t key = mix_bits(0xF011A6EULL + primitive.source->id);
  for (const double value : {origin.x(), origin.y(), origin.z(), direction.x(), direction.y(), direction.z()}) {
    std::uint64_t bits = 0;
    std::memcpy(&bits, &value, sizeof bits);
    key = mix_bits(key ^ bits);
  }
  const double range = hits[0] - free_path * std::log(1.0 - unit_interval_from_bits(key));
  const double exit = count == 2 ? hits[1] : kNone;
  return range < exit && range <= t_max ? range : kNone;
}

PreparedPrimitive prepare(const ScenePrimitive& primitive) {
  PreparedPrimitive prepared;
  prepared.source = &primitive;
  const std::string where = "primitive " + std::to_string(primitive.id) + " '" + primitive.name + "': ";
  const Eigen::Matrix3d rotation = primitive.pose.linear();
  if (!rotation.allFinite() || std::abs(rotation.determinant() - 1.0) > 1e-6 ||
      !(rotation.transpose() * rotation).isApprox(Eigen::Matrix3d::Identity(), 1e-6))
    throw Error(where + "pose rotation must be a proper rotation matrix");
  prepared.world_to_local = rotation.transpose();
  prepared.origin = primitive.pose.translation();
  const Eigen::Vector3d& s = primitive.scale;
  const LocalExtent& e = primitive.extent;
  if (!(e.minimum.array() <= e.maximum.array()).all()) throw Error(where + "extent minimum must not exceed maximum");
  Eigen::Vector3d low = e.minimum, high = e.maximum;
  switch (primitive.surface_type) {
    case QuadricType::Plane:
      prepared.plane = true;
      low.x() = high.x() = 0.0;
      break;
    case QuadricType::Sphere:
    case QuadricType::Ellipsoid:
      if (!(s.array() > 0.0).all()) throw Error(where + "scale must be positive for an ellipsoid");
      prepared.weights = s.cwiseProduct(s).cwiseInverse();
      prepared.constant = -1.0;
      low = low.cwiseMax(-s);
      high = high.cwiseMin(s);
      break;
    case QuadricType::CircularCylinder:
    case QuadricType::EllipticCylinder:
      if (!(s.x() > 0.0 && s.y() > 0.0)) throw Error(where + "scale a and b must be positive for a cylinder");
      prepared.weights = Eigen::Vector3d(1.0 / (s.x() * s.x()), 1.0 / (s.y() * s.y()), 0.0);
      prepared.constant = -1.0;
      low.head<2>() = low.head<2>().cwiseMax(-s.head<2>());
      high.head<2>() = high.head<2>().cwiseMin(s.head<2>());
      break;
    case QuadricType::CircularCone:
    case QuadricType::EllipticCone: {
      if (!(s.x() > 0.0 && s.y() > 0.0)) throw Error(where + "scale a and b (tan of half-angles) must be positive for a cone");
      prepared.weights = Eigen::Vector3d(1.0 / (s.x() * s.x()), 1.0 / (s.y() * s.y()), -1.0);
      prepared.constant = 0.0;
      const double reach = std::max(std::abs(low.z()), std::abs(high.z()));
      low.head<2>() = low.head<2>().cwiseMax(-reach * s.head<2>());
      high.head<2>() = high.head<2>().cwiseMin(reach * s.head<2>());
      break;
    }
    default:
      throw Error(where + "surface_type " + quadric_type_name(primitive.surface_type) +
                  " cannot be ray-cast (expected plane, sphere, ellipsoid, cylinder or cone)");
  }
  if (!(low.array() <= high.array()).all()) throw Error(where + "extent does not overlap the surface");
  prepared.world_box.setEmpty();
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d local((corner & 1) ? high.x() : low.x(), (corner & 2) ? high.y() : low.y(),
                                (corner & 4) ? high.z() : low.z());
    prepared.world_box.extend(primitive.pose * local);
  }
  const Eigen::Vector3d pad = Eigen::Vector3d::Constant(1e-6);
  prepared.world_box = Eigen::AlignedBox3d(prepared.world_box.min() - pad, prepared.world_box.max() + pad);
  return prepared;
}

}  // namespace

struct RayCaster::Impl {
  std::vector<ScenePrimitive> primitives;   // own copy: prepared entries point into it
  std::vector<PreparedPrimitive> prepared;  // in hierarchy leaf order
  std::vector<HierarchyNode> nodes;

  int build(std::vector<PreparedPrimitive>& items, int first, int count) {
    HierarchyNode node;
    node.box.setEmpty();
    for (int i = first; i < first + count; ++i) node.box.extend(items[static_cast<std::size_t>(i)].world_box);
    const int index = static_cast<int>(nodes.size());
    nodes.push_back(node);
    if (count <= kLeafSize) {
      nodes[static_cast<std::size_t>(index)].first = first;
      nodes[static_cast<std::size_t>(index)].count = count;
      return index;
    }
    Eigen::AlignedBox3d centers;
    centers.setEmpty();
    for (int i = first; i < first + count; ++i) centers.extend(items[static_cast<std::size_t>(i)].world_box.center());
    int axis = 0;
    centers.sizes().maxCoeff(&axis);
    const int middle = first + count / 2;
    // Median split; ties broken by primitive id so the tree is identical on every run.
    std::nth_element(items.begin() + first, items.begin() + middle, items.begin() + first + count,
                     [axis](const PreparedPrimitive& left, const PreparedPrimitive& right) {
                       const double a = left.world_box.center()[axis], b = right.world_box.center()[axis];
                       return a < b || (a == b && left.source->id < right.source->id);
                     });
    const int left = build(items, first, middle - first);
    const int right = build(items, middle, first + count - middle);
    nodes[static_cast<std::size_t>(index)].left = left;
    nodes[static_cast<std::size_t>(index)].right = right;
    return index;
  }

  void nearest_in_leaf(const HierarchyNode& node, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                       double t_min, RayHit& best, double& limit) const {
    for (int i = node.first; i < node.first + node.count; ++i) {
      const PreparedPrimitive& primitive = prepared[static_cast<std::size_t>(i)];
      const double range = stopping_range(primitive, origin, direction, t_min, limit);
      // Equal ranges (shared edges) resolve to the lower id for determinism.
      if (range < limit || (range == limit && static_cast<std::int32_t>(primitive.source->id) < best.primitive)) {
        limit = range;
        best.range = range;
        best.primitive = static_cast<std::int32_t>(primitive.source->id);
      }
    }
  }
};

RayCaster::RayCaster(const Scene& scene) : impl_(std::make_unique<Impl>()) {
  impl_->primitives = scene.primitives;
  for (std::size_t i = 0; i < impl_->primitives.size(); ++i)
    if (impl_->primitives[i].id != i)
      throw Error("scene '" + scene.name + "': primitive " + std::to_string(i) + " has id " +
                  std::to_string(impl_->primitives[i].id) + " (ids must equal indices)");
  impl_->prepared.reserve(impl_->primitives.size());
  for (const auto& primitive : impl_->primitives) impl_->prepared.push_back(prepare(primitive));
  if (!impl_->prepared.empty()) impl_->build(impl_->prepared, 0, static_cast<int>(impl_->prepared.size()));
}

RayCaster::~RayCaster() = default;
RayCaster::RayCaster(RayCaster&&) noexcept = default;
RayCaster& RayCaster::operator=(RayCaster&&) noexcept = default;

std::size_t RayCaster::primitive_count() const { return impl_->primitives.size(); }
std::size_t RayCaster::hierarchy_node_count() const { return impl_->nodes.size(); }

RayHit RayCaster::cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& unit_direction, double min_range,
                       double max_range) const {
  RayHit best;
  if (impl_->nodes.empty()) return best;
  const RayBoxTester tester(origin, unit_direction);
  double limit = max_range;
  std::array<int, 128> stack{};
  int top = 0;
  if (tester.entry(impl_->nodes[0].box, limit) <= limit) stack[static_cast<std::size_t>(top++)] = 0;
  while (top > 0) {
    const HierarchyNode& node = impl_->nodes[static_cast<std::size_t>(stack[static_cast<std::size_t>(--top)])];
    if (tester.entry(node.box, limit) > limit) continue;  // a nearer hit was found since it was pushed
    if (node.left < 0) {
      impl_->nearest_in_leaf(node, origin, unit_direction, min_range, best, limit);
      continue;
    }
    const double left = tester.entry(impl_->nodes[static_cast<std::size_t>(node.left)].box, limit);
    const double right = tester.entry(impl_->nodes[static_cast<std::size_t>(node.right)].box, limit);
    // Push the farther child first so the nearer one is visited first.
    const bool left_first = left <= right;
    const double far_entry = left_first ? right : left, near_entry = left_first ? left : right;
    const int far_child = left_first ? node.right : node.left, near_child = left_first ? node.left : node.right;
    if (far_entry <= limit) stack[static_cast<std::size_t>(top++)] = far_child;
    if (near_entry <= limit) stack[static_cast<std::size_t>(top++)] = near_child;
  }
  return best;
}

RayHit RayCaster::cast_brute_force(const Eigen::Vector3d& origin, const Eigen::Vector3d& unit_direction,
                                   double min_range, double max_range) const {
  RayHit best;
  double limit = max_range;
  // Visit in id order so ties resolve to the lower id, as the hierarchy does.
  std::vector<const PreparedPrimitive*> by_id(impl_->prepared.size());
  for (const auto& prepared : impl_->prepared) by_id[prepared.source->id] = &prepared;
  for (const PreparedPrimitive* primitive : by_id) {
    const double range = stopping_range(*primitive, origin, unit_direction, min_range, limit);
    if (range < limit) {
      limit = range;
      best.range = range;
      best.primitive = static_cast<std::int32_t>(primitive->source->id);
    }
  }
  return best;
}

std::vector<double> RayCaster::intersect_primitive(std::size_t primitive, const Eigen::Vector3d& origin,
                                                   const Eigen::Vector3d& unit_direction, double min_range,
                                                   double max_range) const {
  if (primitive >= impl_->primitives.size())
    throw Error("RayCaster::intersect_primitive: primitive " + std::to_string(primitive) + " out of range (scene has " +
                std::to_string(impl_->primitives.size()) + ")");
  for (const auto& prepared : impl_->prepared) {
    if (prepared.source->id != primitive) continue;
    std::array<double, 2> hits{};
    const int count = intersect_prepared(prepared, origin, unit_direction, min_range, max_range, hits);
    return std::vector<double>(hits.begin(), hits.begin() + count);
  }
  return {};
}

// ---------------------------------------------------------------------------------------------
// Scanning

namespace {

enum class RayOutcome : std::uint8_t { Return, Miss, TooNear, Dropped };

struct RayResult {
  double range = 0.0;
  std::int32_t primitive = -1;
  RayOutcome outcome = RayOutcome::Miss;
};

}  // namespace

SimulatedScan simulate_scan(const Scene& scene, const RayCaster& caster, const SensorModel& sensor,
                            const Eigen::Isometry3d& sensor_pose, std::uint64_t seed, std::uint32_t scan_index) {
  validate_sensor(sensor);
  if (caster.primitive_count() != scene.primitives.size())
    throw Error("simulate_scan: the ray caster was built for a different scene (" +
                std::to_string(caster.primitive_count()) + " primitives, scene '" + scene.name + "' has " +
                std::to_string(scene.primitives.size()) + ")");
  const std::vector<Eigen::Vector3d> directions = sensor_ray_directions(sensor);
  const std::size_t ray_count = directions.size();
  std::vector<RayResult> results(ray_count);
  const Eigen::Matrix3d rotation = sensor_pose.linear();
  const Eigen::Vector3d origin = sensor_pose.translation();
  const std::uint64_t stream = mix_bits(seed ^ mix_bits(0x5CA17E5ULL + scan_index));

  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, ray_count, 2048), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t ray = range.begin(); ray != range.end(); ++ray) {
      RayResult& result = results[ray];
      const RayHit hit = caster.cast(origin, rotation * directions[ray], 0.0, sensor.max_range);
      if (!hit.hit()) {
        result.outcome = RayOutcome::Miss;
        continue;
      }
      if (hit.range < sensor.min_range) {
        result.outcome = RayOutcome::TooNear;
        continue;
      }
      const std::uint64_t key = stream + 3ULL * ray;
      if (sensor.dropout_probability > 0.0 && unit_interval_from_bits(mix_bits(key)) < sensor.dropout_probability) {
        result.outcome = RayOutcome::Dropped;
        continue;
      }
      double noise = 0.0;
      if (sensor.range_noise_sigma > 0.0) {
        const double u1 = 1.0 - unit_interval_from_bits(mix_bits(key + 1));
        const double u2 = unit_interval_from_bits(mix_bits(key + 2));
        noise = sensor.range_noise_sigma * std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
      }
      result.outcome = RayOutcome::Return;
      result.primitive = hit.primitive;
      result.range = hit.range + noise;
    }
  });

  SimulatedScan scan;
  scan.sensor_pose = sensor_pose;
  scan.rays = ray_count;
  scan.points_per_primitive.assign(scene.primitives.size(), 0);
  std::size_t returns = 0;
  for (const RayResult& result : results) {
    switch (result.outcome) {
      case RayOutcome::Return: ++returns; break;
      case RayOutcome::Miss: ++scan.misses; break;
      case RayOutcome::TooNear: ++scan.too_near; break;
      case RayOutcome::Dropped: ++scan.dropped; break;
    }
  }
  PointCloud& cloud = scan.cloud;
  cloud.positions.resize(3, static_cast<Eigen::Index>(returns));
  cloud.labels.resize(returns);
  std::vector<float>& ids = cloud.extra_fields["primitive_id"];
  ids.resize(returns);
  std::size_t index = 0;
  for (std::size_t ray = 0; ray < ray_count; ++ray) {
    const RayResult& result = results[ray];
    if (result.outcome != RayOutcome::Return) continue;
    cloud.positions.col(static_cast<Eigen::Index>(index)) = (directions[ray] * result.range).cast<float>();
    cloud.labels[index] = static_cast<std::uint32_t>(scene.primitives[static_cast<std::size_t>(result.primitive)].label);
    ids[index] = static_cast<float>(result.primitive);
    ++scan.points_per_primitive[static_cast<std::size_t>(result.primitive)];
    ++index;
  }
  return scan;
}

}  // namespace quadrix
