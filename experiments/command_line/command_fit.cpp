// `quadrix fit INPUT --type T --fitter NAME`: fits one quadric to a whole point cloud (an element)
// and prints the result as JSON.
#include "experiments/command_line/command_registry.h"
#include "fitting/quadric_fitter.h"
#include "geometry/io.h"

#include <nlohmann/json.hpp>

#include <iostream>
#include <memory>

namespace quadrix::cli {
namespace {

struct FitCommandOptions {
  std::string input;             ///< point-cloud file holding one element
  std::string type = "auto";     ///< requested quadric type or auto
  std::string fitter = "statistical";  ///< registry name of the fitter
  std::string format = "auto";   ///< input format override
  std::string residuals = "exact";  ///< residual evaluation: exact (every point), subsample or skip
};

nlohmann::json fit_to_json(const QuadricFit& fit, const std::string& fitter_name, std::size_t point_count) {
  nlohmann::json result;
  result["fitter"] = fitter_name;
  result["status"] = fit_status_name(fit.status);
  if (!fit.message.empty()) result["message"] = fit.message;
  result["type"] = quadric_type_name(fit.type);
  result["points"] = point_count;
  const Vector10d q = fit.quadric.normalized().parameters();
  result["q"] = std::vector<double>(q.data(), q.data() + 10);
  result["scale"] = {fit.shape.scale(0), fit.shape.scale(1), fit.shape.scale(2)};
  std::vector<double> rotation;
  for (int row = 0; row < 3; ++row)
    for (int column = 0; column < 3; ++column) rotation.push_back(fit.shape.rotation(row, column));
  result["rotation"] = rotation;
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
  return result;
}

const CommandRegistration registration(40, [](CLI::App& app) {
  auto options = std::make_shared<FitCommandOptions>();
  CLI::App* command = app.add_subcommand("fit", "Fit one quadric to all points of a file and print it as JSON");
  command->add_option("input", options->input, "Point cloud holding one element (any supported format)")->required();
  command->add_option("--type", options->type,
                      "auto, point, line, plane, sphere, ellipsoid, cylinder, elliptic_cylinder, cone, elliptic_cone")
      ->capture_default_str();
  std::string fitter_names;
  for (const auto& name : quadric_fitter_names()) fitter_names += (fitter_names.empty() ? "" : ", ") + name;
  command->add_option("--fitter", options->fitter, "Fitter: " + fitter_names)->capture_default_str();
  command->add_option("--residuals", options->residuals,
                      "Residual statistics over every point (exact), at most 2000 evenly strided points (subsample) "
                      "or none (skip)")
      ->capture_default_str();
  command->add_option("--format", options->format, "Input format override (see `quadrix info --help`)")
      ->capture_default_str();
  command->callback([options] {
    const FitTypeHint hint = fit_type_hint_from_name(options->type);
    FitEvaluationOptions evaluation;
    evaluation.residuals = residual_evaluation_from_name(options->residuals);
    const auto fitter = make_quadric_fitter(options->fitter, evaluation);
    CloudReadOptions read_options;
    read_options.format = cloud_format_from_name(options->format);
    const PointCloud cloud = read_point_cloud(options->input, read_options);
    const Eigen::Matrix3Xd points = cloud.positions.cast<double>();
    const QuadricFit fit = fitter->fit(points, Eigen::Matrix3Xd(), hint);
    std::cout << fit_to_json(fit, fitter->name(), cloud.size()).dump(2) << std::endl;
  });
});

}  // namespace
}  // namespace quadrix::cli
