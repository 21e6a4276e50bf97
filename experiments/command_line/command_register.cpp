// `quadrix register SOURCE TARGET [--preset vlp64|vlp16|mid360|avia|monument|auto] [--config FILE.yaml]
// [--source-preset P --target-preset P] [--source-origin X,Y,Z --target-origin X,Y,Z]
// [--labels-source F --labels-target F [--label-classes C,...]] [--gt FILE] [--initial-guess FILE [--local]]
// [--out DIR]`:
// global registration of two clouds with quadrics (paper Fig. overview, Algorithm 1). Prints the 4x4
// transform mapping SOURCE points into the TARGET frame and a one-line summary; with --gt also RTE,
// RRE and success (2 m / 5 deg, between the sensors' frames); --source-origin/--target-origin give
// where each sensor stood in its file's frame (the clouds are registered centred there); --initial-guess
// gives a pose to start from (competing with the global answer; with --local, the only start: ICP,
// no quadric matching); with --out writes report.json, merged.ply, bev.png, both models
// (source_model.json, target_model.json) and the interactive page view.html (unless --no-page).
// The exit status is 0 whenever a registration ran (its status says ok / ambiguous / degenerate /
// failed); 2 on bad input (unreadable file, unknown preset or config key).
#include "geometry/output_paths.h"
#include "experiments/command_line/command_registry.h"
#include "experiments/command_line/terminal_text.h"
#include "estimation/registration_config.h"
#include "experiments/reports/interactive_page.h"
#include "experiments/reports/registration_report.h"
#include "geometry/error.h"
#include "geometry/io.h"
#include "geometry/las.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace quadrix::cli {
namespace {

struct RegisterCommandOptions {
  std::string source;          ///< source cloud file
  std::string target;          ///< target cloud file
  std::string preset = "auto"; ///< preset of both sides, or auto
  std::string source_preset;   ///< overrides --preset for the source
  std::string target_preset;   ///< overrides --preset for the target
  std::vector<double> source_origin{0.0, 0.0, 0.0};  ///< where the source's sensor stood in the source file's frame
  std::vector<double> target_origin{0.0, 0.0, 0.0};  ///< where the target's sensor stood in the target file's frame
  std::string config;          ///< YAML overrides applied after the presets
  std::string labels_source;   ///< SemanticKITTI labels of the source
  std::string labels_target;   ///< SemanticKITTI labels of the target
  std::string label_classes;   ///< take only these classes from the labels (comma-separated), the rest from geometry
  std::string ground_truth;    ///< 4x4 T_gt (source -> target) for RTE/RRE
  std::string initial_guess;   ///< 4x4 or 3x4 pose (source -> target) to start from
  bool local = false;          ///< ICP from the initial guess only (RegistrationOptions::local_only)
  std::string out;             ///< output folder
  std::string refiner;         ///< refiner override (ceres | nlopt)
  bool no_page = false;        ///< skip view.html in the output folder
  bool verbose = false;        ///< print the whole status message, auto's measurements and the stage timings
};

// The terminal summary: the transform and a few one-line facts; the whole status message, auto's
// measurements and the stage timings with --verbose (and in report.json).
void print_register_summary(const RegisterCommandOptions& options, const RegistrationOptions& registration,
                            const std::string& notes, const RegistrationResult& result, const Eigen::Vector3d& source_origin,
                            const Eigen::Vector3d& target_origin, const std::optional<Eigen::Isometry3d>& ground_truth,
                            double load_ms, double preset_ms, double total_ms) {
  const bool verbose = options.verbose;
  const std::string details = options.out.empty() ? "--verbose" : "--verbose, report.json";
  std::printf("quadrix register %s -> %s\n", options.source.c_str(), options.target.c_str());
  const std::string source_preset = options.source_preset.empty() ? options.preset : options.source_preset;
  const std::string target_preset = options.target_preset.empty() ? options.preset : options.target_preset;
  const std::string& source_used = registration.source_extraction.preset;
  const std::string& target_used = registration.target_extraction.preset;
  if (source_preset == target_preset && source_used == target_used)
    std::printf("%s\n", preset_summary_line(source_preset, source_used, notes, verbose, details).c_str());
  else
    std::printf("source %s\ntarget %s\n", preset_summary_line(source_preset, source_used, notes, verbose, details).c_str(),
                preset_summary_line(target_preset, target_used, verbose ? "" : notes, false, details).c_str());
  for (const std::string& check : switched_off_checks(registration)) std::printf("note: %s\n", check.c_str());
  const Eigen::Matrix4d matrix = between_cloud_frames(result.transform, source_origin, target_origin).matrix();
  for (int r = 0; r < 4; ++r)
    std::printf("%12.6f %12.6f %12.6f %12.6f\n", matrix(r, 0), matrix(r, 1), matrix(r, 2), matrix(r, 3));
  std::printf("status %s\n",
              status_summary_line(registration_status_name(result.status), result.message, verbose, details).c_str());
  const RegistrationCounts& c = result.counts;
  std::string cliques;
  for (const std::size_t size : c.clique_sizes) cliques += (cliques.empty() ? "" : "/") + std::to_string(size);
  const OverlapMeasure& overlap = *result.overlap;  // register_clouds measured it (check_overlap)
  std::printf("quadrics %zu/%zu, correspondences %zu, cliques %s | overlap %.2f (unmoved %.2f)", c.source_quadrics,
              c.target_quadrics, c.correspondences, cliques.empty() ? "-" : cliques.c_str(), overlap.transformed,
              overlap.identity);
  if (result.status == RegistrationStatus::Ok || result.status == RegistrationStatus::Ambiguous)
    std::printf(" | fitness %.2f, RMSE %.3f m%s", result.fitness, result.inlier_rmse,
                result.from_initial_guess ? ", from the guess" : "");
  std::printf(" | %.0f ms\n", total_ms);
  if (verbose) {
    // A stage that did not run (a local registration matches no quadrics) took 0 ms.
    const auto ms = [&](const char* stage) {
      const auto found = result.timings_ms.find(stage);
      return found == result.timings_ms.end() ? 0.0 : found->second;
    };
    std::printf("timings (ms, 2 shared cores): load %.0f, preset %.0f, model %.0f + %.0f, match %.0f, estimate %.0f, select %.0f\n",
                load_ms, preset_ms, ms("modelling_source"), ms("modelling_target"),
                ms("correspondences") + ms("graphs") + ms("cliques"), ms("estimation"), ms("selection"));
    std::printf("overlap measured at %.1f m", overlap.distance);
    if (c.source_isolated_points + c.target_isolated_points > 0)
      std::printf("; %zu + %zu isolated points left out", c.source_isolated_points, c.target_isolated_points);
    std::printf("\n");
  }
  if (ground_truth) {
    const double rte = translation_error(result.transform, *ground_truth);
    const double rre = rotation_error_degrees(result.transform, *ground_truth);
    std::printf("RTE %.3f m, RRE %.3f deg -> %s\n", rte, rre,
                registration_succeeded(result.transform, *ground_truth) ? "SUCCESS" : "FAILURE");
  }
}

void run(const RegisterCommandOptions& options) {
  using Clock = std::chrono::steady_clock;
  if (!options.config.empty() && !std::filesystem::exists(options.config))
    throw file_error(options.config, "configuration file does not exist");
  // Clouds in another frame than their sensors' (a map's) are registered centred on their sensors,
  // where ranges, free space and rotations mean what the pipeline assumes; the answer printed and
  // the ground truth compared are between the files' own frames.
  const Eigen::Vector3d source_origin(options.source_origin.data());
  const Eigen::Vector3d target_origin(options.target_origin.data());
  if (!source_origin.allFinite()) throw Error("--source-origin: expected three finite numbers X,Y,Z in metres");
  if (!target_origin.allFinite()) throw Error("--target-origin: expected three finite numbers X,Y,Z in metres");
  // The output folder is checked before the work, and replaced at once after it.
  const std::vector<std::string> inputs = {options.source,        options.target,        options.config,
                                           options.ground_truth,  options.labels_source, options.labels_target};
  std::optional<FolderReplacement> output_folder;
  if (!options.out.empty())
    output_folder.emplace("--out", options.out,
                          std::vector<std::string>{"report.json", "merged.ply", "bev.png", "source_model.json",
                                                   "target_model.json", "view.html"},
                          inputs);
  std::optional<Eigen::Isometry3d> ground_truth;
  if (!options.ground_truth.empty())
    ground_truth = between_sensor_frames(read_pose_matrix(options.ground_truth), source_origin, target_origin);
  if (options.local && options.initial_guess.empty()) throw Error("--local needs --initial-guess FILE (the pose to start from)");
  std::optional<Eigen::Isometry3d> initial_guess;
  if (!options.initial_guess.empty())
    initial_guess = between_sensor_frames(read_pose_matrix(options.initial_guess), source_origin, target_origin);

  const Clock::time_point start = Clock::now();
  // Read relative to a local origin (large coordinates stay exact) and centred in double.
  CloudReadOptions read_options;
  read_options.local_origin = LocalOrigin::Auto;
  require_metres(coordinate_units(options.source), options.source, "registration");
  require_metres(coordinate_units(options.target), options.target, "registration");
  const PointCloud source = centred_on_sensor(read_point_cloud(options.source, read_options), source_origin);
  const PointCloud target = centred_on_sensor(read_point_cloud(options.target, read_options), target_origin);
  require_finite_points(source, "--source-origin moved " + options.source);
  require_finite_points(target, "--target-origin moved " + options.target);
  std::vector<std::uint32_t> source_labels;
  std::vector<std::uint32_t> target_labels;
  if (!options.labels_source.empty()) source_labels = read_semantic_kitti_labels(options.labels_source, source.size());
  if (!options.labels_target.empty()) target_labels = read_semantic_kitti_labels(options.labels_target, target.size());
  const double load_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();

  std::string notes;
  const Clock::time_point resolve_start = Clock::now();
  RegistrationOptions registration = resolve_registration_options(
      options.source_preset.empty() ? options.preset : options.source_preset, source,
      options.target_preset.empty() ? options.preset : options.target_preset, target, &notes);
  const double preset_ms = std::chrono::duration<double, std::milli>(Clock::now() - resolve_start).count();
  if (!options.config.empty()) apply_registration_config(options.config, registration);
  if (!options.refiner.empty()) {
    make_refiner(options.refiner);
    registration.estimation.refiner = options.refiner;
  }

  if (!options.label_classes.empty()) {
    if (source_labels.empty() && target_labels.empty())
      throw Error("--label-classes needs --labels-source and/or --labels-target");
    registration.source_extraction.label_classes = registration.target_extraction.label_classes =
        parse_label_classes(options.label_classes);
  }
  registration.initial_guess = initial_guess;
  registration.local_only = options.local;
  const RegistrationResult result = register_clouds(source, target, registration, source_labels, target_labels);
  const double total_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();

  print_register_summary(options, registration, notes, result, source_origin, target_origin, ground_truth, load_ms, preset_ms,
                         total_ms);
  if (output_folder) {
    RegistrationReportContext context;
    context.source_path = options.source;
    context.target_path = options.target;
    context.source_preset = registration.source_extraction.preset;
    context.target_preset = registration.target_extraction.preset;
    context.preset_notes = notes;
    context.load_ms = load_ms;
    context.total_ms = total_ms;
    context.ground_truth = ground_truth;
    context.overlap = *result.overlap;  // register_clouds measured it (check_overlap)
    context.source_sensor_origin = source_origin;
    context.target_sensor_origin = target_origin;
    FolderReplacement& folder = *output_folder;
    write_registration_report(folder.path("report.json"), result, context);
    // merged.ply in the target file's frame; the picture, the models and the page stay sensor-centred.
    write_point_cloud(folder.path("merged.ply"),
                      centred_on_sensor(merge_aligned_clouds(source, target, result.transform), -target_origin));
    BirdsEyeOptions picture;
    picture.status = registration_status_name(result.status);
    picture.title = std::filesystem::path(options.source).filename().string() + " -> " +
                    std::filesystem::path(options.target).filename().string();
    write_birds_eye_png(folder.path("bev.png"), source, target, result.transform, picture);
    // The models, so `quadrix view DIR` can draw the clique's correspondences between record centres.
    write_scene_model_json(folder.path("source_model.json"), result.source_model);
    write_scene_model_json(folder.path("target_model.json"), result.target_model);
    std::string page;
    if (!options.no_page) {
      RegistrationPageInput page_input;
      page_input.report_json = registration_report_json(result, context);
      page_input.source_model = result.source_model;
      page_input.target_model = result.target_model;
      page_input.source = source;
      page_input.target = target;
      // The registration's own outputs are written: a page that cannot be built (libjs-three
      // missing) is a warning, not a failed run.
      try {
        write_page(folder.path("view.html"), registration_page_html(page_input));
        page = ", view.html";
      } catch (const Error& error) {
        std::fprintf(stderr, "quadrix: warning: view.html not written: %s (--no-page skips it)\n", error.what());
      }
    }
    folder.commit();
    std::printf("wrote %s/{report.json, merged.ply, bev.png, source_model.json, target_model.json%s}\n", options.out.c_str(),
                page.c_str());
  }
}

const CommandRegistration registration(60, [](CLI::App& app) {
  auto options = std::make_shared<RegisterCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "register", "Globally register SOURCE onto TARGET with quadrics; prints the 4x4 transform (source -> target frame)");
  command->add_option("source", options->source, "Source point cloud (any supported format)")->required();
  command->add_option("target", options->target, "Target point cloud")->required();
  std::string presets;
  for (const auto& name : registration_preset_names()) presets += name + "|";
  command->add_option("--preset", options->preset,
                      "Sensor preset of both sides: " + presets + "auto (chosen from the cloud: field of view, rings, size)")
      ->capture_default_str();
  command->add_option("--source-preset", options->source_preset, "Preset of the source only (cross-sensor pairs)");
  command->add_option("--target-preset", options->target_preset, "Preset of the target only (cross-sensor pairs)");
  command->add_option("--source-origin", options->source_origin,
                      "Where the source's sensor stood in the source file's frame, X,Y,Z in metres (default: the origin). "
                      "For clouds in a map's frame: they are registered centred on their sensors, and the transform "
                      "printed maps the source file's frame into the target file's")
      ->expected(3)
      ->delimiter(',');
  command->add_option("--target-origin", options->target_origin,
                      "Where the target's sensor stood in the target file's frame, X,Y,Z in metres (default: the origin)")
      ->expected(3)
      ->delimiter(',');
  command->add_option("--config", options->config, "YAML overrides (keys: quadrix config --schema); unknown keys are errors");
  command->add_option("--labels-source", options->labels_source, "SemanticKITTI .label file of the source");
  command->add_option("--labels-target", options->labels_target, "SemanticKITTI .label file of the target");
  command->add_option("--label-classes", options->label_classes,
                      "Take only these classes from the labels, comma-separated (line, vehicle, trunk, vegetation); "
                      "every other point is modelled from geometry");
  command->add_option("--gt", options->ground_truth, "Ground-truth 4x4 (maps source into target): print RTE/RRE/success");
  command->add_option("--refiner", options->refiner, "Refiner backend override: ceres | nlopt");
  command->add_option("--initial-guess", options->initial_guess,
                      "A pose to start from, 4x4 or 3x4 text (maps source into target, files' frames, as --gt): its "
                      "ICP answer is verified beside the global one and the better wins");
  command->add_flag("--local", options->local,
                    "With --initial-guess: skip the global quadric matching, ICP from the guess only (verified as usual)");
  command->add_option("--out", options->out,
                      "Folder for report.json, merged.ply, bev.png, source_model.json, target_model.json and view.html");
  command->add_flag("--no-page", options->no_page, "With --out: do not write the interactive page view.html");
  command->add_flag("-v,--verbose", options->verbose,
                    "Also print the whole status message, auto's measurements and the stage timings (all are in report.json)");
  command->callback([options] { run(*options); });
});

}  // namespace
}  // namespace quadrix::cli
