// Registration presets and YAML configuration (DESIGN.md §6): the C++ option structs hold the
// defaults (paper values); a preset is extraction_preset(name) plus those defaults; YAML files
// (estimation/presets/<name>.yaml, or --config FILE) override fields. Unknown keys are an Error
// naming the key and the file. `auto` chooses a preset from measurable properties of the cloud.
#pragma once

#include "estimation/registration.h"
#include "geometry/point_cloud.h"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace quadrix {

/// Names accepted by registration_preset: vlp64, vlp16, mid360, avia, monument.
std::vector<std::string> registration_preset_names();

/// Paper defaults with the extraction preset `name` on both sides (C++ values only, no file read).
/// Throws quadrix::Error listing the valid names otherwise.
RegistrationOptions registration_preset(const std::string& name);

/// Folder of the preset YAML files: $QUADRIX_PRESETS_DIR if set, else estimation/presets of the source tree.
std::string registration_presets_directory();

/// Applies the YAML file `path` to `options` (both sides' extraction unless `side` is "source" or
/// "target"). Schema (every key optional):
///   sensor: vlp64|vlp16|mid360|avia|monument   (restarts the extraction from that preset)
///   extraction: {minimum_range, maximum_range, static_scan, up: [x,y,z],
///                ground: {inlier_distance, max_slope_deg, max_step_height},
///                planes: {voxel_size, merge_distance, normal_cosine, eigenvalue_ratio, minimum_plane_points},
///                clusters: {radius, minimum_points, maximum_points, maximum_extent},
///                lines: {inlier_distance, minimum_points, minimum_length},
///                shapes: {simplification_voxel, epsilon, cluster_epsilon, minimum_points, normal_threshold}}
///   modelling: {fitter, quadrics_per_class, augmentation_threshold, augmented_elements_per_class, augmentation_voxel}
///   matching: {top_k_similar, match_augmented_points, thresholds: [..], clique_time_limit_ms, clique_threads}
///   estimation: {refiner, max_iterations, function_tolerance, manhattan_tolerance_degrees,
///                augment_non_central, use_ground_constraint, ground_weight, minimum_inliers}
///   selection: {dcs_phi, manhattan_tolerance_degrees}
///   ambiguity: {score_ratio, translation_disagreement, rotation_disagreement_degrees, minimum_clique_for_ok, overlap_margin}
///   dense_search: {enabled, voxel_size, source_samples, normal_neighbours, correspondence_distance, iterations,
///                  step, range, across_step, across_range, refine_band, max_refined,
///                  minimum_overlap, decisive_margin}
/// Throws quadrix::Error naming the file and the key for unknown keys, wrong types or unreadable files.
void apply_registration_config(const std::string& path, RegistrationOptions& options, const std::string& side = "both");

/// The options in the schema of apply_registration_config (every key it accepts, `extraction` from
/// `side`: "source" or "target"), as YAML a user can save, edit and pass back with --config;
/// applying it reproduces every value it lists. Throws quadrix::Error for another side.
std::string registration_config_yaml(const RegistrationOptions& options, const std::string& side = "source");

/// The preset `name` as the user sees it: registration_preset(name), then its YAML file from
/// registration_presets_directory() when present (its values mirror the C++ ones; edits take effect).
RegistrationOptions load_registration_preset(const std::string& name);

/// The up axis of a cloud measured from its planar structure (the `auto` preset's levelling).
struct UpDirectionEstimate {
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();  ///< unit up axis in the cloud's frame (+z when nothing was found)
  bool found = false;                 ///< a planar mode supported the estimate (else +z is assumed)
  double support = 0.0;               ///< fraction of the planar-voxel points whose normal is within 10 deg of `up`
  double tilt_degrees = 0.0;          ///< angle between `up` and +z, degrees
  std::string reason;                 ///< one line: what was measured and chosen
};

/// Estimates the up axis from the dominant horizontal structure: PCA normals of planar voxels
/// (voxel = median range / 15, clamped to 0.1..1 m), the best-supported normal direction within
/// 45 deg of +z (ground and ceilings of a sensor tilted by less than 45 deg; walls are then at
/// least 45 deg away), refined as the mean of the normals within 10 deg of it and oriented
/// toward +z. Without such a mode, the best-supported direction overall, oriented so that most
/// of its planar points lie below the origin (the sensor stands above the ground).
UpDirectionEstimate estimate_up_direction(const PointCloud& cloud);

/// Measured properties of a cloud behind the `auto` preset.
struct SensorGuess {
  std::string preset;                 ///< chosen preset name
  std::string reason;                 ///< one line: the measurements and the rule that chose it
  std::size_t point_count = 0;        ///< points of the cloud
  double azimuth_coverage = 0.0;      ///< fraction of 1-degree azimuth bins (around the origin) holding points
  int ring_count = 0;                 ///< separated elevation bands (0.05 deg bins, >= ~20 points each on average; occupied above half the mean) of points beyond 10 m: the laser rings
  double elevation_span_degrees = 0.0;///< 1st..99th percentile of the elevation angle, degrees
  double median_range = 0.0;          ///< median distance from the origin, m
  UpDirectionEstimate up;             ///< the measured up axis (for the extraction; the preset rule does not use it)
  double near_field_fraction = 0.0;   ///< fraction of points within 1.5 m of the origin (a robot's or vehicle's own body)
  double minimum_range = 0.0;         ///< crop radius auto sets, m: 2 m when near_field_fraction > 10% (self-hits), else the preset's
};

/// Chooses among the presets by the cloud itself: narrow horizontal field of view (< 50% azimuth
/// coverage) -> avia; more than 1.5 M points -> monument (static scan); an elevation span (1st..99th
/// percentile beyond 10 m) under 35 deg is a spinning multi-beam scanner -> vlp64 when dense (>= 60 k
/// points or >= 48 rings), else vlp16; a taller span -> mid360. Angles are measured in the cloud's
/// own frame (a sensor head's rings stay horizontal there even when it is mounted tilted); the up
/// axis is estimated separately (estimate_up_direction) for the extraction. The origin is assumed
/// to be the sensor (not estimated). More than 10% of the points within 1.5 m of it are
/// the platform's own body: auto then crops everything nearer than 2 m.
SensorGuess guess_sensor_preset(const PointCloud& cloud);

/// Registration options for a pair: each side's preset by name, or "auto" (guess_sensor_preset,
/// whose estimated up axis is also set on that side's extraction). Presets load their YAML files
/// (load_registration_preset). The reasons of every auto choice are appended to `notes` when given.
/// Throws quadrix::Error for an unknown preset name.
RegistrationOptions resolve_registration_options(const std::string& source_preset, const PointCloud& source,
                                                 const std::string& target_preset, const PointCloud& target,
                                                 std::string* notes = nullptr);

}  // namespace quadrix
