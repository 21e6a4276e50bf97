// `quadrix fit INPUT --type T --fitter NAME`: fits one quadric to a whole point cloud (an element)
// and prints the result as JSON: the plain shape parameters ("shape": radius, axis, height, apex,
// half-angle, normal, offset... as the type has them) beside the canonical q, scale, rotation, center.
#include "experiments/command_line/command_registry.h"
#include "experiments/reports/fit_report.h"
#include "fitting/quadric_fitter.h"
#include "geometry/io.h"

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
    std::cout << fit_report_json(fit, fitter->name(), cloud.size(), 2, points) << std::endl;
  });
});

}  // namespace
}  // namespace quadrix::cli
