// Scanner simulator: spinning LiDARs (HDL-64E, VLP-16), a Livox-like non-repetitive
// rosette, and a terrestrial laser scanner, ray-cast exactly against the bounded quadric primitives
// of a synthetic scene (ray-plane, ray-cylinder, ray-ellipsoid, ray-cone in each primitive's
// canonical frame) with a bounding-volume hierarchy as broad phase. Rays run in parallel (TBB);
// noise and dropout are drawn per ray from a counter-based hash, so a scan is identical for any
// number of threads.
#pragma once

#include "experiments/synthetic/synthetic_scene.h"
#include "geometry/point_cloud.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace quadrix {

/// How a sensor's beams sweep.
enum class ScanPattern {
  Spinning,  ///< fixed beam elevations, uniform azimuth steps over 360 degrees (Velodyne)
  Rosette,   ///< two counter-rotating prisms: a non-repetitive rosette in a narrow cone around +x (Livox)
  Dome,      ///< terrestrial laser scanner: uniform elevation x azimuth grid over the full dome
};

/// Geometry and error model of a simulated sensor. Angles in degrees, ranges in metres. The sensor
/// frame is x forward, y left, z up; every output point is in this frame.
struct SensorModel {
  std::string name;                           ///< preset name ("hdl64", "vlp16", "livox", "tls")
  std::string description;                    ///< one line for listings and scene.json
  ScanPattern pattern = ScanPattern::Spinning;  ///< beam sweep
  std::vector<double> beam_elevations_deg;    ///< Spinning: elevation of every beam (laser ring order)
  int azimuth_steps = 2000;                   ///< Spinning: firings per revolution
  int rosette_samples = 24000;                ///< Rosette: samples per frame (all beams together)
  int rosette_beams = 6;                      ///< Rosette: beams sharing the prisms, evenly phase-shifted
  double rosette_field_of_view_deg = 70.4;    ///< Rosette: full cone angle of the pattern
  double rosette_prism_frequency_1_hz = 121.6;  ///< Rosette: rate of the first prism
  double rosette_prism_frequency_2_hz = -77.7;  ///< Rosette: rate of the second prism (opposite sense, incommensurate)
  double rosette_frame_seconds = 0.1;         ///< Rosette: integration time of one frame
  double dome_angular_step_deg = 0.2;         ///< Dome: step in azimuth and in elevation
  double dome_min_elevation_deg = -60.0;      ///< Dome: lowest elevation (tripod shadow below)
  double dome_max_elevation_deg = 90.0;       ///< Dome: highest elevation
  double min_range = 1.0;                     ///< returns nearer than this are discarded
  double max_range = 120.0;                   ///< returns farther than this are discarded
  double range_noise_sigma = 0.02;            ///< standard deviation of Gaussian noise along the ray
  double dropout_probability = 0.0;           ///< probability that a return is lost

  /// Number of rays of one scan.
  std::size_t ray_count() const;
};

/// Names of the presets, in listing order: hdl64, vlp16, livox, tls.
std::vector<std::string> sensor_names();
/// A preset by name: hdl64 (Velodyne HDL-64E: 64 beams +2.0..-24.8 deg, 2000 azimuth steps,
/// 0.9-120 m, 2 cm noise, 1 % dropout), vlp16 (16 beams +-15 deg, 0.2 deg azimuth, 0.5-100 m,
/// 3 cm), livox (Avia-like rosette, 70.4 deg cone, 6 beams, 24000 samples a frame, 1-190 m, 2 cm),
/// tls (dome -60..90 deg, 0.2 deg steps, 0.6-300 m, 2 mm). Throws quadrix::Error for other names.
SensorModel sensor_preset(const std::string& name);
/// Unit ray directions of one scan in the sensor frame, in firing order (deterministic).
std::vector<Eigen::Vector3d> sensor_ray_directions(const SensorModel& sensor);
/// Checks ranges, probabilities and counts; throws quadrix::Error naming the field otherwise.
void validate_sensor(const SensorModel& sensor);

/// One ray-surface intersection.
struct RayHit {
  double range = 0.0;           ///< distance from the origin along the unit direction, metres
  std::int32_t primitive = -1;  ///< id of the primitive hit, -1 for no hit
  /// True when something was hit.
  bool hit() const { return primitive >= 0; }
};

/// Exact nearest-hit ray casting against a scene's bounded primitives with a bounding-volume
/// hierarchy over their world boxes. Immutable after construction; safe to share between threads.
class RayCaster {
 public:
  /// Prepares world-to-local transforms, world boxes and the hierarchy. Throws quadrix::Error for
  /// primitives with unsupported surface types or non-positive scales.
  explicit RayCaster(const Scene& scene);
  /// Releases the hierarchy.
  ~RayCaster();
  /// Not copyable (owns the hierarchy); movable.
  RayCaster(const RayCaster&) = delete;
  /// Not copyable.
  RayCaster& operator=(const RayCaster&) = delete;
  /// Moves the hierarchy.
  RayCaster(RayCaster&&) noexcept;
  /// Moves the hierarchy.
  RayCaster& operator=(RayCaster&&) noexcept;

  /// Nearest hit with range in (min_range, max_range] along a unit direction, through the hierarchy.
  RayHit cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& unit_direction, double min_range,
              double max_range) const;
  /// The same answer by testing every primitive (no broad phase): the reference for tests.
  RayHit cast_brute_force(const Eigen::Vector3d& origin, const Eigen::Vector3d& unit_direction, double min_range,
                          double max_range) const;
  /// Every intersection of the ray with one primitive's bounded surface with range in
  /// (min_range, max_range], ascending (at most two).
  std::vector<double> intersect_primitive(std::size_t primitive, const Eigen::Vector3d& origin,
                                          const Eigen::Vector3d& unit_direction, double min_range,
                                          double max_range) const;
  /// Number of primitives.
  std::size_t primitive_count() const;
  /// Number of nodes of the bounding-volume hierarchy.
  std::size_t hierarchy_node_count() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// One simulated scan and its bookkeeping.
struct SimulatedScan {
  PointCloud cloud;                                        ///< points in the SENSOR frame; labels = semantic label; extra field "primitive_id"
  Eigen::Isometry3d sensor_pose = Eigen::Isometry3d::Identity();  ///< sensor -> world
  std::vector<std::size_t> points_per_primitive;           ///< returned points of each primitive id
  std::size_t rays = 0;                                    ///< rays cast
  std::size_t misses = 0;                                  ///< rays that hit nothing within max_range (sky)
  std::size_t too_near = 0;                                ///< hits discarded by min_range
  std::size_t dropped = 0;                                 ///< returns lost to dropout
};

/// Scans the scene from `sensor_pose` (sensor -> world). `seed` and `scan_index` select the noise
/// and dropout draws (same inputs -> identical scan for any thread count). The range noise may
/// move a point past max_range; such points are kept (a real sensor reports them too).
SimulatedScan simulate_scan(const Scene& scene, const RayCaster& caster, const SensorModel& sensor,
                            const Eigen::Isometry3d& sensor_pose, std::uint64_t seed, std::uint32_t scan_index);

}  // namespace quadrix
