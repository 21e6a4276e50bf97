// Plain shape parameters read from a quadric's decomposition (shape_parameters.h).
#include "fitting/shape_parameters.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace quadrix {
namespace {

constexpr double kDegrees = 57.29577951308232;

ShapeParameter vector_parameter(const std::string& name, const Eigen::Vector3d& value) {
  return {name, {value.x(), value.y(), value.z()}, true};
}

ShapeParameter number_parameter(const std::string& name, double value) { return {name, {value}, false}; }

// [min, max] of the points along `axis` from `origin`, and their difference.
void append_extent(std::vector<ShapeParameter>& parameters, const Eigen::Vector3d& origin, const Eigen::Vector3d& axis,
                   const Eigen::Matrix3Xd& points) {
  if (points.cols() == 0) return;
  double low = std::numeric_limits<double>::infinity(), high = -low;
  for (Eigen::Index i = 0; i < points.cols(); ++i) {
    const double along = (points.col(i) - origin).dot(axis);
    low = std::min(low, along);
    high = std::max(high, along);
  }
  parameters.push_back({"extent", {low, high}, true});
  parameters.push_back(number_parameter("height", high - low));
}

}  // namespace

std::vector<ShapeParameter> shape_parameters(QuadricType type, const QuadricDecomposition& shape,
                                             const Eigen::Vector3d& reference, const Eigen::Matrix3Xd& points) {
  std::vector<ShapeParameter> parameters;
  const Eigen::Vector3d axis = shape.rotation.col(2);
  // The point of the axis (a line of centres) nearest the reference.
  const Eigen::Vector3d on_axis = shape.center + (reference - shape.center).dot(axis) * axis;
  switch (type) {
    case QuadricType::Point:
      parameters.push_back(vector_parameter("position", shape.center));
      break;
    case QuadricType::Line:
      parameters.push_back(vector_parameter("point", on_axis));
      parameters.push_back(vector_parameter("direction", axis));
      append_extent(parameters, on_axis, axis, points);
      break;
    case QuadricType::Plane: {
      const Eigen::Vector3d normal = shape.rotation.col(0);
      parameters.push_back(vector_parameter("normal", normal));
      parameters.push_back(number_parameter("offset", -normal.dot(shape.center)));
      break;
    }
    case QuadricType::Sphere:
      parameters.push_back(vector_parameter("center", shape.center));
      parameters.push_back(number_parameter("radius", shape.scale(0)));
      break;
    case QuadricType::Ellipsoid: {
      parameters.push_back(vector_parameter("center", shape.center));
      parameters.push_back(vector_parameter("radii", shape.scale));
      std::vector<double> axes;
      for (int row = 0; row < 3; ++row)
        for (int column = 0; column < 3; ++column) axes.push_back(shape.rotation(row, column));
      parameters.push_back({"axes", axes, true});
      break;
    }
    case QuadricType::CircularCylinder:
    case QuadricType::EllipticCylinder:
      parameters.push_back(vector_parameter("point", on_axis));
      parameters.push_back(vector_parameter("axis", axis));
      if (type == QuadricType::CircularCylinder)
        parameters.push_back(number_parameter("radius", shape.scale(0)));
      else
        parameters.push_back({"radii", {shape.scale(0), shape.scale(1)}, true});
      append_extent(parameters, on_axis, axis, points);
      break;
    case QuadricType::CircularCone:
    case QuadricType::EllipticCone: {
      // The axis points into the nappe holding the points (a fitted cone is one nappe of the pair).
      double along = 0.0;
      for (Eigen::Index i = 0; i < points.cols(); ++i) along += (points.col(i) - shape.center).dot(axis);
      const Eigen::Vector3d into = along < 0.0 ? Eigen::Vector3d(-axis) : axis;
      parameters.push_back(vector_parameter("apex", shape.center));
      parameters.push_back(vector_parameter("axis", into));
      if (type == QuadricType::CircularCone)
        parameters.push_back(number_parameter("half_angle_deg", std::atan(shape.scale(0)) * kDegrees));
      else
        parameters.push_back(
            {"half_angles_deg", {std::atan(shape.scale(0)) * kDegrees, std::atan(shape.scale(1)) * kDegrees}, true});
      append_extent(parameters, shape.center, into, points);
      break;
    }
    default:
      parameters.push_back(vector_parameter("center", shape.center));
      break;
  }
  return parameters;
}

std::vector<ShapeParameter> record_shape_parameters(const QuadricRecord& record, QuadricType type) {
  if (type == QuadricType::Point) return {vector_parameter("position", record.full_center)};
  return shape_parameters(type, record.quadric().decompose(), record.full_center);
}

std::string shape_parameters_json(const std::vector<ShapeParameter>& parameters) {
  nlohmann::json shape = nlohmann::json::object();
  for (const ShapeParameter& parameter : parameters)
    shape[parameter.name] = parameter.is_vector ? nlohmann::json(parameter.values) : nlohmann::json(parameter.values.front());
  return shape.dump();
}

std::string scene_model_shapes_json(const SceneModel& model) {
  std::string text = "[";
  for (std::size_t i = 0; i < model.records.size(); ++i)
    text += (i == 0 ? "" : ", ") + shape_parameters_json(record_shape_parameters(model.records[i], model.types[i]));
  return text + "]";
}

}  // namespace quadrix
