// The JSON of one quadric fit (fit_report.h): what `quadrix fit` prints and quadrix.fit returns.
#include "experiments/reports/fit_report.h"

#include "fitting/shape_parameters.h"
#include "geometry/quadric.h"

#include <Eigen/Geometry>

#include <nlohmann/json.hpp>

#include <vector>

namespace quadrix {

std::string fit_report_json(const QuadricFit& fit, const std::string& fitter_name, std::size_t point_count, int indent,
                            const Eigen::Matrix3Xd& points) {
  nlohmann::json result;
  result["fitter"] = fitter_name;
  result["status"] = fit_status_name(fit.status);
  if (!fit.message.empty()) result["message"] = fit.message;
  result["type"] = quadric_type_name(fit.type);
  result["points"] = point_count;
  result["shape"] = nlohmann::json::parse(shape_parameters_json(shape_parameters(fit.type, fit.shape, fit.statistics.center, points)));
  const Vector10d q = fit.quadric.normalized().parameters();
  result["q"] = std::vector<double>(q.data(), q.data() + 10);
  result["scale"] = {fit.shape.scale(0), fit.shape.scale(1), fit.shape.scale(2)};
  const Eigen::Quaterniond quaternion(fit.shape.rotation);
  result["rotation"] = {quaternion.w(), quaternion.x(), quaternion.y(), quaternion.z()};
  std::vector<double> rotation_matrix;
  for (int row = 0; row < 3; ++row)
    for (int column = 0; column < 3; ++column) rotation_matrix.push_back(fit.shape.rotation(row, column));
  result["rotation_matrix"] = rotation_matrix;
  result["center"] = {fit.shape.center(0), fit.shape.center(1), fit.shape.center(2)};
  result["degeneracy"] = {
      {"scale", {fit.shape.indicators.scale(0), fit.shape.indicators.scale(1), fit.shape.indicators.scale(2)}},
      {"rotation", {fit.shape.indicators.rotation(0), fit.shape.indicators.rotation(1), fit.shape.indicators.rotation(2)}},
      {"translation",
       {fit.shape.indicators.translation(0), fit.shape.indicators.translation(1), fit.shape.indicators.translation(2)}}};
  result["statistical_scale"] = {fit.statistics.scale(0), fit.statistics.scale(1), fit.statistics.scale(2)};
  result["statistical_center"] = {fit.statistics.center(0), fit.statistics.center(1), fit.statistics.center(2)};
  result["residual_rms"] = fit.residual_rms;
  result["residual_max"] = fit.residual_max;
  result["f_p2s"] = fit.algebraic_distance;
  result["time_ms"] = fit.time_ms;
  result["residual_evaluation"] = residual_evaluation_name(fit.residual_evaluation);
  result["residual_points"] = fit.residual_points;
  result["evaluation_ms"] = fit.evaluation_ms;
  return result.dump(indent);
}

}  // namespace quadrix
