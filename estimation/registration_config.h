// Registration presets and YAML configuration (DESIGN.md §6): the C++ option structs hold the
// defaults (the paper's values); a preset is those defaults plus what differs for one sensor
// (extraction_preset(name) on both sides and the few registration fields listed in
// registration_preset); a YAML file (--config FILE) then overrides fields. One table of keys
// (registration_config_keys) drives reading, writing and the printed schema. Unknown keys are an
// Error naming the key and the file. `auto` chooses a preset from measurable properties of the cloud.
#pragma once

#include "estimation/registration.h"
#include "geometry/point_cloud.h"

#include <Eigen/Core>

#include <cstddef>
#include <string>
#include <variant>
#include <vector>

namespace quadrix {

/// Names accepted by registration_preset: vlp64, vlp16, mid360, avia, monument, airborne.
std::vector<std::string> registration_preset_names();

/// The paper's defaults plus what the preset `name` changes: its sensor's extraction
/// (extraction_preset) on both sides and its registration fields (monument and airborne have them: the
/// constrained fitter). Throws quadrix::Error listing the valid names otherwise.
RegistrationOptions registration_preset(const std::string& name);

/// Which side's extraction a per-side configuration key reaches.
enum class ConfigSide { Source, Target };

/// The member of RegistrationOptions one configuration key reads and writes (its type decides the
/// YAML form: bool, integer, non-negative integer, number, string, list of numbers, [x, y, z]).
using RegistrationConfigMember =
    std::variant<bool*, int*, std::size_t*, double*, std::string*, std::vector<double>*, Eigen::Vector3d*>;

/// One key of the YAML configuration: a row of the table behind apply_registration_config,
/// registration_config_yaml and registration_config_schema.
struct RegistrationConfigKey {
  std::string path;         ///< dotted YAML path, e.g. "extraction.planes.voxel_size"
  std::string description;  ///< what it sets, one line with its unit
  bool per_side = false;    ///< an extraction key: set on the source, the target or both (`side` of apply_registration_config)
  RegistrationConfigMember (*member)(RegistrationOptions& options, ConfigSide side) = nullptr;  ///< the member it reaches (`side` used by per-side keys)
  std::vector<std::string> (*choices)() = nullptr;  ///< the valid names of a string key (nullptr: any string)
  double minimum = 0.0;   ///< smallest valid value of a number, an integer or each list entry (valid_range_text says why)
  double maximum = 0.0;   ///< largest valid value of a number, an integer or each list entry; bounds every amount of work
  bool zero_allowed = false;  ///< 0 is also valid (the key's documented "0: off") though below `minimum`
  bool ranged = false;    ///< a number, an integer or a list of numbers: minimum..maximum apply (bools, names and [x, y, z] have none)
};

/// "[minimum, maximum]" of a ranged key (with "or 0" when zero_allowed); empty for other keys.
std::string valid_range_text(const RegistrationConfigKey& key);

/// Most entries of a list key (matching.thresholds: one clique search per entry).
inline constexpr std::size_t kMaxConfigListEntries = 8;

/// Largest configuration file read, bytes: a full configuration is about 6 kB, and a bigger file is
/// refused before it is parsed (a 100 MB YAML list would take gigabytes to hold as nodes).
inline constexpr std::size_t kMaxConfigFileBytes = 1 << 20;

/// Every key of the YAML configuration, in the order registration_config_yaml writes them
/// (`sensor` first: reading it restarts the extraction from that preset before the other keys).
const std::vector<RegistrationConfigKey>& registration_config_keys();

/// The key of registration_config_keys at the dotted `path` ("extraction.planes.voxel_size"), or nullptr.
const RegistrationConfigKey* find_registration_config_key(const std::string& path);

/// The names directly below the section `prefix` ("" for the top level), in table order:
/// "extraction" gives minimum_range, ..., planes, ...; empty when `prefix` is no section.
std::vector<std::string> registration_config_names_below(const std::string& prefix);

/// The schema of the YAML configuration as text: one line per key of registration_config_keys with
/// its type (and valid names) and description, plus how `sensor`, `up` and lists are read.
std::string registration_config_schema();

/// Applies the YAML file `path` to `options`: every key of registration_config_keys is optional;
/// per-side keys (`sensor`, `extraction.*`) go to both sides' extraction unless `side` is "source"
/// or "target". `sensor` restarts that extraction from extraction_preset first; `extraction.up`
/// is normalised (non-zero); `matching.thresholds` is a non-empty, non-negative, strictly ascending
/// list; string keys with choices must name one of them; the dense_search block must pass
/// validate_dense_search_options; every number, integer and list entry must lie in its key's range
/// (RegistrationConfigKey::minimum..maximum, printed by registration_config_schema). Throws
/// quadrix::Error naming the file and the key for unknown keys, wrong types, out-of-range values,
/// unreadable files, files that are not regular files (a FIFO would block) or larger than
/// kMaxConfigFileBytes; quoted values are cut to a few dozen characters.
void apply_registration_config(const std::string& path, RegistrationOptions& options, const std::string& side = "both");

/// The checks of the `ok` verification that `options` switch off through their documented off
/// values (a negative margin or limit, a zero floor), one line each naming the key, e.g.
/// "ambiguity.free_space_limit -1 (< 0): the free-space check is off"; empty when every check runs.
std::vector<std::string> switched_off_checks(const RegistrationOptions& options);

/// Every key of registration_config_keys with its value in `options` (per-side keys from `side`:
/// "source" or "target") as YAML a user can save, edit and pass back with --config; applying it
/// reproduces every value it lists. Throws quadrix::Error for another side.
std::string registration_config_yaml(const RegistrationOptions& options, const std::string& side = "source");

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

/// Chooses among the presets by the cloud itself: a cloud that covers its x-y extent evenly and is
/// flat against it (a nadir view; thresholds beside the rule, docs/registration.md) -> airborne;
/// narrow horizontal field of view (< 50% azimuth
/// coverage) -> avia; more than 1.5 M points -> monument (static scan); an elevation span (1st..99th
/// percentile beyond 10 m) under 35 deg is a spinning multi-beam scanner -> vlp64 when dense (>= 60 k
/// points or >= 48 rings), else vlp16; a taller span -> mid360. Angles are measured in the cloud's
/// own frame (a sensor head's rings stay horizontal there even when it is mounted tilted); the up
/// axis is estimated separately (estimate_up_direction) for the extraction. The origin is assumed
/// to be the sensor (not estimated). More than 10% of the points within 1.5 m of it are
/// the platform's own body: auto then crops everything nearer than 2 m. Angles, ranges and the up
/// axis are measured without isolated points (without_isolated_points), which would widen the span;
/// point_count counts every point.
SensorGuess guess_sensor_preset(const PointCloud& cloud);

/// The options one cloud's preset gives (both extractions set alike): `preset` by name
/// (registration_preset), or "auto" (guess_sensor_preset, whose estimated up axis and platform crop
/// are set on the extractions). The reasons of an auto choice are appended to `notes` when given,
/// after `side` ("source", "target"). Throws quadrix::Error for an unknown preset name.
RegistrationOptions resolve_registration_side(const std::string& preset, const PointCloud& cloud, const std::string& side,
                                              std::string* notes = nullptr);

/// Registration options for a pair: each side's preset by name (registration_preset), or "auto"
/// (guess_sensor_preset, whose estimated up axis is also set on that side's extraction); the two
/// sides are resolved concurrently (resolve_registration_side). The reasons of every auto choice are
/// appended to `notes` when given. Throws quadrix::Error for an unknown preset name.
RegistrationOptions resolve_registration_options(const std::string& source_preset, const PointCloud& source,
                                                 const std::string& target_preset, const PointCloud& target,
                                                 std::string* notes = nullptr);

}  // namespace quadrix
