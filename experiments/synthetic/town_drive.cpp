// The town drive (see town_drive.h): layout, tour, routes, drift, per-leg scenes and the output folder.
#include "experiments/synthetic/town_drive.h"

#include "experiments/synthetic/synthetic_output.h"
#include "geometry/constants.h"
#include "geometry/error.h"
#include "geometry/io.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <sstream>

namespace quadrix {
namespace {

constexpr double kStreetHalfLength = 72.0;        // make_street_scene's block: x in [-72, 72]
constexpr double kIntersectionHalfWidth = 14.0;   // > the widest street (facade line + 4 m sidewalk <= 13 m)
constexpr double kPitch = 2.0 * (kStreetHalfLength + kIntersectionHalfWidth);  // metres between intersections
constexpr int kNodesPerSide = 3;                  // 3 x 3 intersections, 2 x 2 blocks, 12 streets
constexpr double kTurnRadius = 8.0;               // centreline radius of a turn at an intersection, m
// Lane centre right of the street's centreline, m: parked cars reach 1.7 m from it on the narrowest
// road (road half width 3.8 m, car centre 1.15 m inside the kerb, 0.95 m half width), so a sensor at
// 1 +- 0.3 m stays at least 0.4 m clear of them.
constexpr double kLaneOffset = 1.0;
constexpr double kLaneWander = 0.3;               // most the driver wanders from the lane centre, m
constexpr double kPathStep = 0.05;                // resolution of the dense path, m
constexpr double kClosingWallHeight = 16.0;       // walls closing the grid's outer ends, m
constexpr double kCornerWallHeight = 12.0;        // walls closing a building row at an intersection, m

double radians(double degrees) { return degrees * kPi / 180.0; }

// The closed tour over the grid's intersections (x, y): 22 legs, no U-turn, every street at least
// once, ten streets both ways; it ends heading south at (0, 0) and turns left into its first leg.
const std::vector<std::array<int, 2>>& tour_nodes() {
  static const std::vector<std::array<int, 2>> nodes{
      {0, 0}, {1, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 0}, {0, 0}, {0, 1}, {1, 1}, {2, 1}, {2, 2}, {1, 2},
      {0, 2}, {0, 1}, {1, 1}, {1, 2}, {2, 2}, {2, 1}, {2, 0}, {1, 0}, {1, 1}, {0, 1}, {0, 0}};
  return nodes;
}

Eigen::Vector2d node_position(const std::array<int, 2>& node) { return Eigen::Vector2d(node[0], node[1]) * kPitch; }

// Street (grid edge) index: east-west edges 0-5 (y row * 2 + x), north-south edges 6-11.
int street_index(const std::array<int, 2>& a, const std::array<int, 2>& b) {
  if (a[1] == b[1]) return a[1] * 2 + std::min(a[0], b[0]);
  return 6 + a[0] * 2 + std::min(a[1], b[1]);
}
constexpr int kStreetCount = 12;

// Street s's placement in the town: the street scene's x axis along the edge, its centre at the edge's middle.
Eigen::Isometry3d street_placement(int street) {
  Eigen::Isometry3d placement = Eigen::Isometry3d::Identity();
  if (street < 6) {
    placement.translation() = Eigen::Vector3d((street % 2 + 0.5) * kPitch, (street / 2) * kPitch, 0.0);
  } else {
    const int edge = street - 6;
    placement.linear() = Eigen::AngleAxisd(0.5 * kPi, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    placement.translation() = Eigen::Vector3d((edge / 2) * kPitch, (edge % 2 + 0.5) * kPitch, 0.0);
  }
  return placement;
}

std::uint64_t street_seed(std::uint64_t seed, int street) { return seed * 64 + static_cast<std::uint64_t>(street); }

// A plane rectangle spanned from `corner` by perpendicular edges, as make_street_scene builds them.
ScenePrimitive rectangle(const std::string& name, SemanticLabel label, const Eigen::Vector3d& corner,
                         const Eigen::Vector3d& edge_b, const Eigen::Vector3d& edge_c) {
  const Eigen::Vector3d b = edge_b.normalized();
  const Eigen::Vector3d a = edge_b.cross(edge_c).normalized();
  const Eigen::Vector3d c = a.cross(b);
  ScenePrimitive primitive;
  primitive.name = name;
  primitive.label = label;
  primitive.surface_type = primitive.model_type = QuadricType::Plane;
  primitive.pose.linear() << a, b, c;
  primitive.pose.translation() = corner;
  primitive.extent.minimum = Eigen::Vector3d::Zero();
  primitive.extent.maximum = Eigen::Vector3d(0.0, edge_b.norm(), std::abs(edge_c.dot(c)));
  return primitive;
}

void append(Scene& scene, ScenePrimitive primitive) {
  primitive.id = static_cast<std::uint32_t>(scene.primitives.size());
  scene.primitives.push_back(std::move(primitive));
}

// One sample of the dense centreline path of a tour.
struct PathSample {
  Eigen::Vector2d position;  // lane centre, town frame
  double heading = 0.0;      // radians
  int tour_leg = 0;          // leg of the tour (0..21) the sample belongs to
};

// The tour driven forwards or backwards, sampled every kPathStep metres along the lane, with rounded
// turns; `centreline_length` receives the tour's centreline length.
std::vector<PathSample> dense_tour(bool reverse, double& centreline_length) {
  std::vector<std::array<int, 2>> nodes = tour_nodes();
  if (reverse) std::reverse(nodes.begin(), nodes.end());
  const int legs = static_cast<int>(nodes.size()) - 1;
  std::vector<Eigen::Vector2d> direction(legs);
  for (int k = 0; k < legs; ++k) direction[k] = (node_position(nodes[k + 1]) - node_position(nodes[k])).normalized();
  const auto turns_at_start = [&](int k) { return (direction[(k + legs - 1) % legs] - direction[k]).norm() > 1e-9; };
  std::vector<PathSample> centreline;
  centreline_length = 0.0;
  for (int k = 0; k < legs; ++k) {
    const Eigen::Vector2d a = node_position(nodes[k]), b = node_position(nodes[k + 1]);
    const double begin = turns_at_start(k) ? kTurnRadius : 0.0;
    const double end = kPitch - (turns_at_start((k + 1) % legs) ? kTurnRadius : 0.0);
    const double heading = std::atan2(direction[k].y(), direction[k].x());
    for (double s = begin; s < end; s += kPathStep) centreline.push_back({a + s * direction[k], heading, k});
    centreline_length += end - begin;
    if (turns_at_start((k + 1) % legs)) {
      // Quarter arc from b - r d_k to b + r d_next around c = b - r d_k + r d_next.
      const Eigen::Vector2d& next = direction[(k + 1) % legs];
      const Eigen::Vector2d centre = b - kTurnRadius * direction[k] + kTurnRadius * next;
      const double arc = 0.5 * kPi * kTurnRadius;
      for (double s = 0.0; s < arc; s += kPathStep) {
        const double phi = s / kTurnRadius;
        const Eigen::Vector2d point = centre - kTurnRadius * std::cos(phi) * next + kTurnRadius * std::sin(phi) * direction[k];
        const Eigen::Vector2d tangent = std::sin(phi) * next + std::cos(phi) * direction[k];
        centreline.push_back({point, std::atan2(tangent.y(), tangent.x()), k});
      }
      centreline_length += arc;
    }
  }
  // The lane: right of the centreline (right-hand traffic).
  for (PathSample& sample : centreline)
    sample.position += kLaneOffset * Eigen::Vector2d(std::sin(sample.heading), -std::cos(sample.heading));
  return centreline;
}

// Tour leg -> street, for the tour in the given direction.
int tour_leg_street(bool reverse, int leg) {
  std::vector<std::array<int, 2>> nodes = tour_nodes();
  if (reverse) std::reverse(nodes.begin(), nodes.end());
  return street_index(nodes[leg], nodes[leg + 1]);
}

Eigen::Matrix3d rotation_zyx(double yaw, double pitch, double roll) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

void check_options(const TownDriveOptions& options) {
  if (options.sensors.empty()) throw Error("town drive: at least one session (sensor) is required");
  if (!(options.scan_spacing > 0.0))
    throw Error("town drive: --scan-spacing must be positive, got " + std::to_string(options.scan_spacing));
  if (options.scans && *options.scans < 2)
    throw Error("town drive: --scans must be at least 2 per session, got " + std::to_string(*options.scans));
  if (!options.scans && !(options.length >= options.scan_spacing))
    throw Error("town drive: --length (" + std::to_string(options.length) + " m) must cover at least one --scan-spacing (" +
                std::to_string(options.scan_spacing) + " m), so that a session has 2 scans");
  const DriftModel& d = options.drift;
  const std::pair<const char*, double> drift[] = {{"--drift-scale", d.scale_error},
                                                  {"--drift-yaw-bias", d.yaw_bias_deg_per_m},
                                                  {"--drift-yaw-walk", d.yaw_walk_deg_per_sqrt_m},
                                                  {"--drift-tilt-walk", d.tilt_walk_deg_per_sqrt_m},
                                                  {"--drift-translation-walk", d.translation_walk_m_per_sqrt_m}};
  for (const auto& [name, value] : drift)
    if (!(value >= 0.0 && std::isfinite(value)))
      throw Error(std::string("town drive: ") + name + " must be a finite value >= 0, got " + std::to_string(value));
  if (!(d.scale_error < 0.5)) throw Error("town drive: --drift-scale must be below 0.5");
}

std::string pose_numbers(const Eigen::Isometry3d& pose, char separator) {
  std::string text;
  char buffer[32];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) {
      std::snprintf(buffer, sizeof(buffer), "%.10g", pose.matrix()(r, c));
      if (!text.empty()) text += separator;
      text += buffer;
    }
  return text;
}

std::string four_digits(int index) {
  char buffer[16];
  std::snprintf(buffer, sizeof(buffer), "%04d", index);
  return buffer;
}

}  // namespace

TownDrivePlan plan_town_drive(const TownDriveOptions& options) {
  check_options(options);
  TownDrivePlan plan;
  const int sessions = static_cast<int>(options.sensors.size());
  const DriftModel& drift = options.drift;
  for (int session = 1; session <= sessions; ++session) {
    // Odd sessions drive the tour forwards, even ones backwards; session k starts (k-1)/sessions of the way round.
    const bool reverse = session % 2 == 0;
    const std::vector<PathSample> path = dense_tour(reverse, plan.tour_length);
    const std::size_t start = static_cast<std::size_t>(std::floor(static_cast<double>(path.size()) * (session - 1) / sessions));
    const int wanted = options.scans ? *options.scans : static_cast<int>(std::floor(options.length / options.scan_spacing + 1e-9)) + 1;
    PortableRandom route_random(mix_bits(options.seed * 7919ULL + static_cast<std::uint64_t>(session)));
    PortableRandom drift_random(mix_bits((options.seed ^ 0xD81F7000ULL) * 104729ULL + static_cast<std::uint64_t>(session)));
    const double yaw_bias_sign = drift_random.bernoulli(0.5) ? 1.0 : -1.0;
    const double scale_sign = drift_random.bernoulli(0.5) ? 1.0 : -1.0;
    // Different vehicles carry their sensors at different heights.
    const double sensor_height = 1.73 + 0.12 * ((session - 1) % 3);
    double travelled = 0.0, next_scan = 0.0, lateral = 0.0;
    int tour_leg = -1, global_leg = static_cast<int>(plan.leg_streets.size()) - 1;
    Eigen::Vector2d previous = path[start].position;
    const std::size_t first_scan = plan.scans.size();
    for (std::size_t step = 0; static_cast<int>(plan.scans.size() - first_scan) < wanted; ++step) {
      const PathSample& sample = path[(start + step) % path.size()];
      travelled += (sample.position - previous).norm();
      previous = sample.position;
      if (sample.tour_leg != tour_leg) {
        tour_leg = sample.tour_leg;
        plan.leg_streets.push_back(tour_leg_street(reverse, tour_leg));
        global_leg = static_cast<int>(plan.leg_streets.size()) - 1;
      }
      if (travelled + 1e-9 < next_scan) continue;
      next_scan += options.scan_spacing;
      // A driver wanders in the lane (first-order autoregressive) and the body yaws, pitches and rolls a little.
      lateral = std::clamp(0.7 * lateral + route_random.normal(0.0, 0.1), -kLaneWander, kLaneWander);
      const double yaw = sample.heading + radians(route_random.normal(0.0, 1.5));
      const double pitch = radians(route_random.normal(0.0, 0.3)), roll = radians(route_random.normal(0.0, 0.3));
      const Eigen::Vector2d right(std::sin(sample.heading), -std::cos(sample.heading));
      const Eigen::Vector2d position = sample.position + lateral * right;
      TownDriveScan scan;
      scan.session = session;
      scan.index = static_cast<int>(plan.scans.size() - first_scan);
      scan.file = "scans/s" + std::to_string(session) + "_" + four_digits(scan.index) + ".ply";
      scan.world.linear() = rotation_zyx(yaw, pitch, roll);
      scan.world.translation() = Eigen::Vector3d(position.x(), position.y(), sensor_height);
      scan.street = plan.leg_streets[static_cast<std::size_t>(global_leg)];
      scan.leg = global_leg;
      scan.street_visit = 1;
      for (int leg = 0; leg < global_leg; ++leg) scan.street_visit += plan.leg_streets[static_cast<std::size_t>(leg)] == scan.street;
      if (scan.index > 0) {
        // Drifted odometry: the previous odometry pose times the true step with the errors of DriftModel.
        const TownDriveScan& before = plan.scans.back();
        const Eigen::Isometry3d step_motion = before.world.inverse() * scan.world;
        const double distance = step_motion.translation().norm(), root = std::sqrt(distance);
        Eigen::Isometry3d measured = step_motion;
        measured.translation() = (1.0 + scale_sign * drift.scale_error) * step_motion.translation() +
                                 Eigen::Vector3d(drift_random.normal(0.0, drift.translation_walk_m_per_sqrt_m * root),
                                                 drift_random.normal(0.0, drift.translation_walk_m_per_sqrt_m * root),
                                                 drift_random.normal(0.0, drift.translation_walk_m_per_sqrt_m * root));
        const double yaw_error = yaw_bias_sign * radians(drift.yaw_bias_deg_per_m) * distance +
                                 radians(drift_random.normal(0.0, drift.yaw_walk_deg_per_sqrt_m * root));
        const double pitch_error = radians(drift_random.normal(0.0, drift.tilt_walk_deg_per_sqrt_m * root));
        const double roll_error = radians(drift_random.normal(0.0, drift.tilt_walk_deg_per_sqrt_m * root));
        measured.linear() = step_motion.linear() * rotation_zyx(yaw_error, pitch_error, roll_error);
        scan.odometry = before.odometry * measured;
      }
      plan.scans.push_back(scan);
    }
    plan.session_lengths.push_back(travelled);
  }
  // The map frame is session 1's odometry frame: its first true pose is the identity.
  const Eigen::Isometry3d map_from_town = plan.scans.front().world.inverse();
  for (TownDriveScan& scan : plan.scans) scan.truth = map_from_town * scan.world;
  return plan;
}

Scene town_scene(const TownDriveOptions& options, const TownDrivePlan& plan, int leg) {
  if (leg < 0 || leg >= static_cast<int>(plan.leg_streets.size()))
    throw Error("town_scene: leg " + std::to_string(leg) + " outside the plan's " + std::to_string(plan.leg_streets.size()) + " legs");
  Scene scene;
  scene.name = "town";
  scene.seed = options.seed;
  scene.description = "town of 2 x 2 blocks: 12 level street scenes joined by open intersections; parked cars and "
                      "pedestrians of each street re-drawn after every visit";
  StreetOptions street_options;
  street_options.foliage = options.foliage;
  street_options.level = true;
  for (int street = 0; street < kStreetCount; ++street) {
    int visit = 1;  // a street changes its dynamic objects after each completed visit
    for (int earlier = 0; earlier < leg; ++earlier) visit += plan.leg_streets[static_cast<std::size_t>(earlier)] == street;
    const StreetPass pass = make_street_pass(street_seed(options.seed, street), visit, 10.0, street_options);
    const Eigen::Isometry3d placement = street_placement(street);
    const std::string prefix = "street" + std::to_string(street) + "_";
    double road_half_width = 0.0, sidewalk_extent = 0.0;
    for (const ScenePrimitive& primitive : pass.scene.primitives) {
      if (primitive.name == "facade_end_west" || primitive.name == "facade_end_east") continue;  // open to the intersection
      if (primitive.name == "road") road_half_width = 0.5 * primitive.extent.maximum.z();
      if (primitive.name == "sidewalk_left") sidewalk_extent = primitive.extent.maximum.z();
      ScenePrimitive placed = primitive;
      placed.name = prefix + primitive.name;
      placed.pose = placement * primitive.pose;
      append(scene, placed);
    }
    // The sidewalk reaches 4 m past the facade line (make_street_scene): close each building row at both ends.
    const double facade_line = road_half_width + sidewalk_extent - 4.0;
    for (const double end : {-kStreetHalfLength, kStreetHalfLength})
      for (const double side : {-1.0, 1.0}) {
        const Eigen::Vector3d corner(end, side * facade_line, -1.0);
        append(scene, rectangle(prefix + (end < 0 ? "west" : "east") + (side < 0 ? "_right" : "_left") + "_corner_wall",
                                SemanticLabel::Facade, placement * corner, placement.linear() * Eigen::Vector3d(0.0, side * 4.0, 0.0),
                                Eigen::Vector3d(0.0, 0.0, kCornerWallHeight + 1.0)));
      }
  }
  for (int x = 0; x < kNodesPerSide; ++x)
    for (int y = 0; y < kNodesPerSide; ++y) {
      const Eigen::Vector3d node(x * kPitch, y * kPitch, 0.0);
      const std::string name = "intersection_" + std::to_string(x) + "_" + std::to_string(y);
      const double g = kIntersectionHalfWidth;
      append(scene, rectangle(name, SemanticLabel::Road, node + Eigen::Vector3d(-g, -g, 0.0), Eigen::Vector3d(2.0 * g, 0.0, 0.0),
                              Eigen::Vector3d(0.0, 2.0 * g, 0.0)));
      // A wall across every side of the intersection that no street leaves from (the grid's outer edge).
      const std::array<std::array<int, 2>, 4> sides{{{1, 0}, {-1, 0}, {0, 1}, {0, -1}}};
      for (const auto& side : sides) {
        const int nx = x + side[0], ny = y + side[1];
        if (nx >= 0 && nx < kNodesPerSide && ny >= 0 && ny < kNodesPerSide) continue;
        const Eigen::Vector3d outward(side[0], side[1], 0.0), across(-side[1], side[0], 0.0);
        append(scene, rectangle(name + "_wall_" + std::to_string(side[0]) + std::to_string(side[1]), SemanticLabel::Facade,
                                node + g * outward - g * across + Eigen::Vector3d(0.0, 0.0, -1.0), 2.0 * g * across,
                                Eigen::Vector3d(0.0, 0.0, kClosingWallHeight + 1.0)));
      }
    }
  return scene;
}

std::pair<int, int> count_revisits(const TownDrivePlan& plan, double radius) {
  int same = 0, opposite = 0;
  for (std::size_t i = 0; i < plan.scans.size(); ++i)
    for (std::size_t j = i + 1; j < plan.scans.size(); ++j) {
      const TownDriveScan& a = plan.scans[i];
      const TownDriveScan& b = plan.scans[j];
      if (a.leg == b.leg) continue;
      if ((a.world.translation() - b.world.translation()).head<2>().norm() > radius) continue;
      const Eigen::Vector3d ha = a.world.linear().col(0), hb = b.world.linear().col(0);
      const double angle = std::acos(std::clamp(ha.head<2>().normalized().dot(hb.head<2>().normalized()), -1.0, 1.0)) * 180.0 / kPi;
      same += angle < 45.0;
      opposite += angle > 135.0;
    }
  return {same, opposite};
}

double aligned_position_rmse(const std::vector<Eigen::Isometry3d>& estimate, const std::vector<Eigen::Isometry3d>& truth) {
  if (estimate.size() != truth.size() || estimate.size() < 3)
    throw Error("aligned_position_rmse: expected two pose lists of the same length >= 3, got " +
                std::to_string(estimate.size()) + " and " + std::to_string(truth.size()));
  Eigen::Matrix3Xd from(3, estimate.size()), to(3, truth.size());
  for (std::size_t i = 0; i < estimate.size(); ++i) {
    from.col(static_cast<Eigen::Index>(i)) = estimate[i].translation();
    to.col(static_cast<Eigen::Index>(i)) = truth[i].translation();
  }
  const Eigen::Matrix4d alignment = Eigen::umeyama(from, to, false);
  const Eigen::Matrix3Xd moved = (alignment.topLeftCorner<3, 3>() * from).colwise() + alignment.topRightCorner<3, 1>();
  return std::sqrt((moved - to).colwise().squaredNorm().mean());
}

TownDriveSummary write_town_drive(const std::string& directory, const TownDriveOptions& options) {
  TownDriveSummary summary;
  summary.plan = plan_town_drive(options);
  const TownDrivePlan& plan = summary.plan;
  const std::filesystem::path root(directory);
  std::filesystem::create_directories(root / "scans");
  const auto start = std::chrono::steady_clock::now();
  std::unique_ptr<Scene> scene;
  std::unique_ptr<RayCaster> caster;
  int scene_leg = -1;
  for (const TownDriveScan& scan : plan.scans) {
    if (scan.leg != scene_leg) {  // scans come in time order: one scene per leg
      caster.reset();
      scene = std::make_unique<Scene>(town_scene(options, plan, scan.leg));
      caster = std::make_unique<RayCaster>(*scene);
      scene_leg = scan.leg;
    }
    const SensorModel& sensor = options.sensors[static_cast<std::size_t>(scan.session - 1)];
    SimulatedScan simulated = simulate_scan(*scene, *caster, sensor, scan.world,
                                            mix_bits(options.seed * 31ULL + static_cast<std::uint64_t>(scan.session)),
                                            static_cast<std::uint32_t>(scan.index));
    simulated.cloud.extra_fields.clear();  // primitive ids differ between legs' scenes: not ground truth of the drive
    summary.points += simulated.cloud.size();
    write_point_cloud((root / scan.file).string(), simulated.cloud);
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  const int sessions = static_cast<int>(options.sensors.size());
  for (int session = 1; session <= sessions; ++session) {
    std::vector<Eigen::Isometry3d> odometry, truth;
    for (const TownDriveScan& scan : plan.scans)
      if (scan.session == session) {
        odometry.push_back(scan.odometry);
        truth.push_back(scan.truth);
      }
    summary.odometry_ate.push_back(odometry.size() >= 3 ? aligned_position_rmse(odometry, truth) : 0.0);
    const Eigen::Isometry3d aligned_end = truth.front() * odometry.back();
    summary.odometry_end_error.push_back((aligned_end.translation() - truth.back().translation()).norm());
  }
  std::tie(summary.same_direction_revisits, summary.opposite_direction_revisits) = count_revisits(plan);

  write_file_atomically((root / "SCANS.tsv").string(), [&](std::ostream& out) {
    out << "session\tscan\todometry\n";
    for (const TownDriveScan& scan : plan.scans) out << scan.session << '\t' << scan.file << '\t' << pose_numbers(scan.odometry, ' ') << '\n';
  });
  write_file_atomically((root / "truth.tsv").string(), [&](std::ostream& out) {
    out << "session\tscan";
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) out << "\tt" << r << c;
    out << '\n';
    for (const TownDriveScan& scan : plan.scans) out << scan.session << '\t' << scan.file << '\t' << pose_numbers(scan.truth, '\t') << '\n';
  });
  write_file_atomically((root / "README.md").string(), [&](std::ostream& out) {
    const DriftModel& d = options.drift;
    out << "# Simulated town drive (quadrix synth drive)\n\n"
        << "Seed " << options.seed << ", " << sessions << " session(s), scan spacing " << options.scan_spacing << " m, "
        << plan.scans.size() << " scans, " << summary.points << " points, simulated and written in "
        << decimal_text(seconds, 1) << " s.\n\n"
        << "Town: 2 x 2 blocks, 12 streets of 144 m (street scenes of seeds " << street_seed(options.seed, 0) << "-"
        << street_seed(options.seed, kStreetCount - 1) << ", level roads) joined by 28 m intersections, "
        << kPitch << " m apart. The closed tour has 22 legs, " << decimal_text(plan.tour_length, 0)
        << " m; odd sessions drive it forwards, even ones backwards, session k starting (k-1)/" << sessions
        << " of the way round. Parked cars and pedestrians of a street are re-drawn after each visit.\n\n"
        << "| session | sensor | scans | driven (m) | direction | odometry ATE (m) | odometry end error (m) |\n"
        << "|---|---|---|---|---|---|---|\n";
    for (int session = 1; session <= sessions; ++session) {
      const auto count = std::count_if(plan.scans.begin(), plan.scans.end(), [&](const TownDriveScan& s) { return s.session == session; });
      out << "| " << session << " | " << options.sensors[static_cast<std::size_t>(session - 1)].name << " | " << count << " | "
          << decimal_text(plan.session_lengths[static_cast<std::size_t>(session - 1)], 0) << " | "
          << (session % 2 == 0 ? "backwards" : "forwards") << " | " << decimal_text(summary.odometry_ate[static_cast<std::size_t>(session - 1)], 2)
          << " | " << decimal_text(summary.odometry_end_error[static_cast<std::size_t>(session - 1)], 2) << " |\n";
    }
    out << "\nRevisits (scan pairs of different legs within 10 m): " << summary.same_direction_revisits
        << " in the same direction (heading within 45 deg), " << summary.opposite_direction_revisits
        << " in the opposite one (more than 135 deg apart).\n\n"
        << "Odometry drift per step of d m: scale error +-" << d.scale_error << ", yaw bias +-" << d.yaw_bias_deg_per_m
        << " deg/m (signs drawn per session), yaw walk " << d.yaw_walk_deg_per_sqrt_m << " deg/sqrt(m), roll/pitch walk "
        << d.tilt_walk_deg_per_sqrt_m << " deg/sqrt(m), position walk " << d.translation_walk_m_per_sqrt_m << " m/sqrt(m).\n\n"
        << "Files:\n"
        << "- `SCANS.tsv`: session, scan (cloud path relative to this folder), odometry (12 numbers, row-major 3x4 "
           "sensor pose in the session's odometry frame, whose origin is the session's first scan).\n"
        << "- `truth.tsv`: session, scan, t00..t23: the true sensor pose in the map frame, which is session 1's "
           "odometry frame (its first true pose is the identity).\n"
        << "- `scans/s<session>_<NNNN>.ply`: binary PLY in the sensor frame (x forward, z up), semantic labels.\n";
  });
  return summary;
}

}  // namespace quadrix
