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

}  // namespace quadrix
