// SceneModel: a point cloud reduced to quadric records (paper §"Quadric Modeling", Struct. 1):
// the top-K_e quadrics per semantic class plus, in sparse scenes, augmented points.
#pragma once

#include "geometry/quadric.h"
#include "geometry/quadric_record.h"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace quadrix {

/// Semantic classes of scene elements (paper §"Quadric Extraction"). Values are stable: they are
/// the `label` of QuadricRecord and are written to files.
enum class ElementClass : std::uint32_t {
  Ground = 1,      ///< the ground surface (plane)
  Plane = 2,       ///< planar structure: facade, wall, barrier (plane)
  Line = 3,        ///< pole, lamp post, sign post (line)
  Object = 4,      ///< geometry-only cluster (ellipsoid)
  Vehicle = 5,     ///< car, truck (ellipsoid), from semantic labels
  Trunk = 6,       ///< tree trunk (elliptic cylinder), from semantic labels
  Vegetation = 7,  ///< bushes and crowns (ellipsoid), from semantic labels
  Cylinder = 8,    ///< column, pillar (circular cylinder), static scans
  Sphere = 9,      ///< dome, ball (sphere), static scans
  Cone = 10,       ///< conical roof or cone (circular cone), static scans
};

/// Lower-case name of a class ("ground", "plane", ...).
std::string element_class_name(ElementClass element_class);
/// The quadric type each class is fitted as (REFERENCE.md "Class -> quadric type").
QuadricType quadric_type_for_class(ElementClass element_class);

/// Number of floats of an FPFH descriptor (PCL's 33-bin histogram).
inline constexpr int kFpfhSize = 33;

/// A scene reduced to quadrics. Records [0, augmented_begin) are fitted elements; records
/// [augmented_begin, size) are augmented points (type point, label of the element they came from).
struct SceneModel {
  std::vector<QuadricRecord> records;                       ///< paper Struct. 1, one per element or augmented point
  std::vector<QuadricType> types;                           ///< fitted type of each record
  std::vector<std::uint32_t> element_point_counts;          ///< points of the element behind each record
  std::size_t augmented_begin = 0;                          ///< index of the first augmented point
  std::vector<std::array<float, kFpfhSize>> augmented_descriptors;  ///< FPFH of each augmented point, in order
  bool has_ground = false;                                  ///< whether a ground was extracted
  Eigen::Vector3d ground_normal = Eigen::Vector3d::UnitZ(); ///< unit ground normal (pointing up), v_g of the f_pp filter
  double ground_offset = 0.0;                               ///< ground plane n . x + offset = 0
  std::size_t source_point_count = 0;                       ///< points of the cloud that was modelled
  std::map<std::string, double> timings_ms;                 ///< per-stage wall times of the modelling run

  /// Number of records.
  std::size_t size() const { return records.size(); }
  /// Number of augmented points.
  std::size_t augmented_count() const { return records.size() - augmented_begin; }
};

/// Class of a record label; throws quadrix::Error when the label is not an ElementClass value.
ElementClass element_class_from_label(std::uint32_t label);
/// Parses a name of element_class_name(); throws quadrix::Error naming the text otherwise.
ElementClass element_class_from_name(const std::string& name);
/// Every element class in ascending value order.
const std::vector<ElementClass>& all_element_classes();

/// Largest source_point_count a model may hold: 2^53; every count up to it survives the JSON
/// format's numbers (doubles) exactly.
inline constexpr std::size_t kMaxExactSourcePoints = std::size_t{1} << 53;

/// Checks the invariants (parallel vectors of equal size, augmented_begin <= size, one descriptor
/// per augmented point or none, finite numbers, known labels, source_point_count at most
/// kMaxExactSourcePoints); throws quadrix::Error naming the field.
void validate_scene_model(const SceneModel& model);

/// The model moved by `offset` (metres): every record's quadric (Q' = T^-T Q T^-1, renormalised as
/// make_quadric_record does) and full centre, and the ground plane (offset' = offset - n . t). What
/// `quadrix model --sensor-origin` does to a model of the sensor-centred cloud to put it back in the
/// file's frame. Types, classes, scales, rotations and descriptors are unchanged.
SceneModel translated(SceneModel model, const Eigen::Vector3d& offset);

/// The model with every length multiplied by `factor` (> 0) about the origin, x' = factor x: each
/// record's quadric (Q' = S^-T Q S^-1 with S = diag(factor, factor, factor, 1), renormalised),
/// full centre and full scale, and the ground plane (offset' = factor offset). Puts a model made in
/// metres back into a file's own length unit (factor = 1 / metres per unit: LAS files in feet).
/// Types, classes, rotations and descriptors (FPFH histograms, unitless) are unchanged. Throws
/// quadrix::Error for a factor that is not finite and positive.
SceneModel scaled(SceneModel model, double factor);

/// Binary scene-model format, version 1 (all little-endian, IEEE-754):
///   magic "QDXSCENE" (8 bytes), u32 version = 1,
///   u64 record count N, u64 augmented_begin, u64 source_point_count,
///   u8 has_ground, f64 ground_normal[3], f64 ground_offset,
///   N x { f64 record[21] in Struct. 1 order, u8 QuadricType, u32 element point count },
///   u64 descriptor count D (0 or N - augmented_begin), D x f32[33],
///   u32 timing count T, T x { u32 name length, name bytes (UTF-8), f64 milliseconds },
///   u32 FNV-1a checksum of every preceding byte.
inline constexpr std::uint32_t kSceneModelBinaryVersion = 1;

/// The FNV-1a checksum the binary format stores after its payload, over `size` bytes of `data`.
std::uint32_t scene_model_binary_checksum(const char* data, std::size_t size);

/// Serialised bytes of the binary format (see kSceneModelBinaryVersion).
std::string scene_model_to_binary(const SceneModel& model);
/// Parses the binary format; throws quadrix::Error naming `source_name`, the field and what was
/// expected (bad magic, unknown version, truncation, checksum mismatch, invalid record).
SceneModel scene_model_from_binary(const std::string& bytes, const std::string& source_name = "<memory>");
/// Writes the binary format atomically.
void write_scene_model_binary(const std::string& path, const SceneModel& model);
/// Reads the binary format; errors name the file.
SceneModel read_scene_model_binary(const std::string& path);

/// JSON document of a model: {"format": "quadrix-scene-model", "version": 1, "quadrics": [one
/// object per record: index, label, class, type, points, augmented, q[10], scale[3] (s_f),
/// rotation[4] (eta_f w,x,y,z), rotation_matrix[9] (row-major R_f), center[3] (t_f), record[21]],
/// "ground": {found, normal, offset}, "augmented_begin", "augmented_descriptors": [[33]...],
/// "stats": {source_points, records, augmented_points, counts_by_class, counts_by_type, timings_ms,
/// binary_bytes} plus the members of `extra_stats` (the inside of a JSON object, e.g. "\"a\": 1", or empty)}.
/// Numbers are written with 17 significant digits, so reading returns the same doubles.
std::string scene_model_to_json(const SceneModel& model, const std::string& extra_stats = "");
/// Parses scene_model_to_json output (reads records, types, point counts, ground, augmented_begin,
/// descriptors, source_points and timings_ms); throws quadrix::Error naming the field otherwise.
SceneModel scene_model_from_json(const std::string& text, const std::string& source_name = "<memory>");
/// Writes scene_model_to_json atomically.
void write_scene_model_json(const std::string& path, const SceneModel& model, const std::string& extra_stats = "");
/// Reads a JSON model; errors name the file.
SceneModel read_scene_model_json(const std::string& path);

}  // namespace quadrix
