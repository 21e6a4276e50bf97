// Plain shape parameters of a fitted quadric: what a user of a fitting library expects to read
// (plane: normal and offset; sphere: center and radius; cylinder: axis, a point on it, radius and
// height; cone: apex, axis and half-angle; ...) instead of the canonical scale, rotation and center
// of paper Eq. (Q=PCP), from which they are read.
#pragma once

#include "fitting/scene_model.h"
#include "geometry/quadric.h"
#include "geometry/quadric_record.h"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace quadrix {

/// One named parameter: a number (`values` of size 1, `is_vector` false) or a vector.
struct ShapeParameter {
  std::string name;            ///< e.g. "radius", "axis", "half_angle_deg"
  std::vector<double> values;  ///< the number, or the vector's components
  bool is_vector = false;      ///< written as an array (a direction, a point, radii)
};

/// The plain parameters of a quadric of type `type` decomposed as `shape` (paper Eq. (Q=PCP)):
///   point: position; line: point (on the line), direction;
///   plane: normal, offset (normal . x + offset = 0);
///   sphere: center, radius; ellipsoid: center, radii (along axes), axes (3x3 row-major, columns);
///   circular cylinder: point (on the axis), axis, radius; elliptic cylinder: point, axis, radii (2);
///   circular cone: apex, axis, half_angle_deg; elliptic cone: apex, axis, half_angles_deg (2).
/// Other types give their center. The point of a line or cylinder is the one nearest `reference`
/// (the element's center, so it sits among the points). When `points` is non-empty, lines,
/// cylinders and cones also get extent ([min, max] of the points along the axis, from the point or
/// apex) and height (max - min), metres.
std::vector<ShapeParameter> shape_parameters(QuadricType type, const QuadricDecomposition& shape,
                                             const Eigen::Vector3d& reference,
                                             const Eigen::Matrix3Xd& points = Eigen::Matrix3Xd());

/// The plain parameters of one model record fitted as `type`: shape_parameters of its quadric q,
/// referenced to its full center t_f (a point record: its position t_f). No extent: a record keeps
/// no points.
std::vector<ShapeParameter> record_shape_parameters(const QuadricRecord& record, QuadricType type);

/// `parameters` as a JSON object text: numbers, arrays for vectors (non-finite numbers null).
std::string shape_parameters_json(const std::vector<ShapeParameter>& parameters);

/// A JSON array text of one record_shape_parameters object per record of `model`, in record order
/// (the "shape" members of scene_model_to_json).
std::string scene_model_shapes_json(const SceneModel& model);

}  // namespace quadrix
