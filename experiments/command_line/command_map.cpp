// `quadrix map SCANS.tsv --out DIR [--gt TRUTH.tsv] [--preset P] [--no-ambiguous-edges]` (or
// `quadrix map --kitti VELODYNE_FOLDER [--kitti-poses FILE --kitti-calib FILE] --out DIR`): one map
// from many scans (paper §"Real-World Applications"): every scan modelled once, odometry given or
// registered scan to scan, loop candidates by radius search within sessions and by a place
// descriptor across them, loop edges from the registration pipeline, a pose graph. Writes
// poses.tsv, edges.csv, report.json, map.ply, map_model.qsm and models/ into DIR (all or nothing).
// With --gt also the ATE, RPE and the loop edges' precision and recall. Exit 2 on bad input.
#include "geometry/output_paths.h"
#include "experiments/command_line/command_registry.h"
#include "estimation/mapping.h"
#include "experiments/reports/map_page.h"
#include "geometry/error.h"

#include <chrono>
#include <filesystem>
#include <cstdio>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <unistd.h>
#include <sys/wait.h>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <vector>

namespace quadrix::cli {
namespace {

struct MapCommandOptions {
  std::string scans;             ///< SCANS.tsv
  std::string kitti;             ///< a KITTI velodyne folder instead
  std::string kitti_poses;       ///< its poses file
  std::string kitti_calibration; ///< its calibration (Tr), to turn camera poses into LiDAR poses
  std::string out;               ///< output folder
  std::string truth;             ///< poses.tsv of the true poses
  std::string scheduler;         ///< a Dask scheduler address (Python only)
  MapOptions map;                ///< every option of the run
};

/// `quadrix map ... --scheduler ADDRESS`: the Dask path lives in the Python package, so the same
/// arguments go to `python3 -m quadrix map` (the package of this build tree, else of the install) and
/// its exit code becomes ours. QUADRIX_PYTHON overrides the interpreter.
int run_on_scheduler(const MapCommandOptions& options) {
  if (!options.kitti.empty()) throw Error("--scheduler: takes SCANS.tsv (write the KITTI folder's list as SCANS.tsv first), not --kitti");
  if (options.scans.empty()) throw Error("give SCANS.tsv");
  if (options.map.registration_options) throw Error("--scheduler: fixed registration options are not passed on");
  const char* override_python = std::getenv("QUADRIX_PYTHON");
  const std::string python = override_python != nullptr && *override_python != '\0' ? override_python : QUADRIX_MAP_PYTHON;
  std::error_code error;
  const std::filesystem::path self = std::filesystem::canonical("/proc/self/exe", error);
  const std::filesystem::path tree = std::filesystem::weakly_canonical(QUADRIX_BUILD_TREE, error);
  const bool in_tree = !self.empty() && self.string().rfind(tree.string() + "/", 0) == 0;
  std::string python_path = in_tree ? QUADRIX_BUILD_PYTHON_PATH : QUADRIX_INSTALL_PYTHON_PATH;
  if (const char* existing = std::getenv("PYTHONPATH"); existing != nullptr && *existing != '\0') python_path += std::string(":") + existing;
  auto number = [](double value) {
    char text[64];
    std::snprintf(text, sizeof text, "%.17g", value);
    return std::string(text);
  };
  std::vector<std::string> arguments = {python, "-m", "quadrix", "map", options.scans, "--out", options.out, "--scheduler", options.scheduler,
                                        "--preset", options.map.preset, "--loop-radius", number(options.map.loop_radius),
                                        "--loop-radius-growth", number(options.map.loop_radius_growth), "--minimum-loop-travel",
                                        number(options.map.minimum_loop_travel), "--candidates-per-scan",
                                        std::to_string(options.map.candidates_per_scan), "--place-candidates",
                                        std::to_string(options.map.place_candidates_per_scan), "--map-voxel", number(options.map.map_voxel)};
  if (!options.truth.empty()) arguments.insert(arguments.end(), {"--gt", options.truth});
  arguments.insert(arguments.end(), {"--maximum-loop-radius", number(options.map.maximum_loop_radius), "--candidate-spacing",
                                     number(options.map.minimum_candidate_spacing), "--information-scale",
                                     number(options.map.loop_information_scale), "--odometry-gate",
                                     number(options.map.odometry_gate_sigmas), "--joint-rounds", std::to_string(options.map.joint_rounds),
                                     "--joint-radius", number(options.map.joint_radius), "--ambiguous-gate-translation",
                                     number(options.map.ambiguous_gate_translation), "--ambiguous-gate-rotation",
                                     number(options.map.ambiguous_gate_rotation_degrees), "--information-rounds",
                                     std::to_string(options.map.information_rounds), "--outlier-threshold",
                                     number(options.map.outlier_threshold), "--place-vote",
                                     std::to_string(options.map.place_vote_minimum)});
  if (!options.map.use_ambiguous_joint_edges) arguments.push_back("--no-ambiguous-joint-edges");
  if (!options.map.use_ambiguous_edges) arguments.push_back("--no-ambiguous-edges");
  if (options.map.use_ambiguous_edges_across_sessions) arguments.push_back("--ambiguous-edges-across-sessions");
  if (options.map.loop_information_from_registration) arguments.push_back("--registration-information");
  std::vector<char*> argv;
  for (std::string& argument : arguments) argv.push_back(argument.data());
  argv.push_back(nullptr);
  std::fflush(stdout);
  std::fflush(stderr);
  const pid_t child = fork();
  if (child < 0) throw Error("--scheduler: cannot start " + python + ": " + std::strerror(errno));
  if (child == 0) {
    ::setenv("PYTHONPATH", python_path.c_str(), 1);
    ::execvp(argv[0], argv.data());
    std::fprintf(stderr, "error: --scheduler runs the Python package quadrix, but %s cannot be started: %s (set QUADRIX_PYTHON)\n",
                 python.c_str(), std::strerror(errno));
    std::_Exit(2);
  }
  int status = 0;
  while (waitpid(child, &status, 0) < 0)
    if (errno != EINTR) throw Error(std::string("--scheduler: waiting for python: ") + std::strerror(errno));
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return 1;
}

void run(const MapCommandOptions& options) {
  if (!options.scheduler.empty()) {
    const int code = run_on_scheduler(options);
    if (code != 0) std::exit(code);
    return;
  }
  if (options.scans.empty() == options.kitti.empty()) throw Error("give either SCANS.tsv or --kitti VELODYNE_FOLDER");
  const ScanList list = options.kitti.empty() ? read_scan_list(options.scans)
                                              : read_kitti_scan_list(options.kitti, options.kitti_poses, options.kitti_calibration);
  std::vector<PoseRow> truth;
  if (!options.truth.empty()) truth = read_pose_table(options.truth);
  // The output folder is checked before the work and replaced at once after it, page included.
  std::vector<std::string> inputs = {options.scans, options.kitti, options.kitti_poses, options.kitti_calibration, options.truth};
  for (const ScanEntry& scan : list.scans) inputs.push_back(scan.path);
  FolderReplacement output("--out", options.out, map_folder_names(), inputs);

  const bool terminal = isatty(fileno(stderr)) != 0;
  const auto start = std::chrono::steady_clock::now();
  std::mutex mutex;
  MapProgress progress;
  if (terminal)
    progress = [&](const std::string& stage, std::size_t done, std::size_t total) {
      std::lock_guard<std::mutex> lock(mutex);
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (total > 0 && done > 0)
        std::fprintf(stderr, "\r%s: %zu / %zu (%.0f s, about %.0f s left in this stage)   ", stage.c_str(), done, total, seconds,
                     seconds * (static_cast<double>(total) / done - 1.0));
      else
        std::fprintf(stderr, "\r%s: %zu (%.0f s)   ", stage.c_str(), done, seconds);
      std::fflush(stderr);
    };
  const MapResult result = map_scans(list, options.map, progress);
  if (terminal) std::fprintf(stderr, "\n");

  std::string evaluation_json;
  std::optional<MapEvaluation> evaluation;
  if (!truth.empty()) {
    evaluation = evaluate_map(result, truth, 30.0, options.map.minimum_loop_travel);
    evaluation_json = map_evaluation_json(*evaluation);
  }
  write_map(output.staging_folder(), result, options.map, evaluation_json);
  // The 3-D page of the folder just written (trajectories, loop edges by status, the map).
  const std::string page = write_map_page(output.staging_folder());
  output.commit();

  std::size_t loops = 0, ok = 0, used = 0, within = 0;
  for (const MapEdge& edge : result.edges) {
    if (edge.kind != MapEdgeKind::Loop) continue;
    ++loops;
    ok += edge.status == "ok";
    used += edge.used;
    within += !edge.across_sessions;
  }
  std::size_t alone = 0;
  for (bool joined : result.in_map_frame) alone += !joined;
  std::printf("map: %zu scans in %zu sessions, %zu loop candidates registered (%zu within sessions), %zu ok, %zu in the graph\n",
              list.scans.size(), list.sessions.size(), loops, within, ok, used);
  std::printf("graph: cost %.4g -> %.4g in %d iterations (%s)\n", result.graph.initial_cost, result.graph.final_cost,
              result.graph.iterations, result.graph.converged ? "converged" : "not converged");
  if (!result.information_groups.empty()) {
    std::printf("information (variance factors after %zu rounds%s, rotation / translation):", result.calibration_costs.size(),
                result.calibration_converged ? "" : ", not settled");
    for (const InformationGroup& group : result.information_groups)
      if (group.edges > 0)
        std::printf(" %s %.3g / %.3g%s;", group.name.c_str(), group.rotation_factor, group.translation_factor,
                    !group.measured ? " (unmeasured)" : group.pooled ? " (pooled)" : "");
    std::printf("\n");
  }
  if (result.outlier_edges > 0)
    std::printf("outlier test: %zu loop edges left the graph (edges.csv notes their statistic)%s\n", result.outlier_edges,
                result.outlier_test_exhausted ? "; stopped at the most it may remove with more above the threshold" : "");
  if (!result.calibration_note.empty()) std::printf("warning: %s\n", result.calibration_note.c_str());
  if (alone > 0) std::printf("warning: %zu scans belong to sessions joined to no other: left in their own frames (frame = own)\n", alone);
  std::printf("time: %.1f s, %.0f ms a scan (modelling %.0f ms, registration %.0f ms, graph %.0f ms in all)\n",
              result.timings_ms.at("total") / 1000.0, result.timings_ms.at("total") / list.scans.size(),
              result.timings_ms.at("modelling"), result.timings_ms.at("registration"), result.timings_ms.at("graph"));
  if (evaluation) {
    std::printf("ATE %.3f m (odometry alone %.3f m) over %s\n", evaluation->ate, evaluation->ate_odometry, evaluation->scope.c_str());
    std::printf("RPE %.2f %% and %.2f deg/100 m (odometry %.2f %%, %.2f deg/100 m) over %zu sub-sequences of %s\n",
                evaluation->rpe_translation_percent, evaluation->rpe_rotation_deg_per_100m, evaluation->rpe_odometry_translation_percent,
                evaluation->rpe_odometry_rotation_deg_per_100m, evaluation->rpe_segments, evaluation->rpe_lengths.c_str());
    std::printf("loop edges: %zu used, %zu wrong (precision %.3f); %zu ok, %zu wrong; recall %zu / %zu revisits within 30 m (%.3f)\n",
                evaluation->used_loop_edges, evaluation->wrong_used_loop_edges, evaluation->precision, evaluation->ok_loop_edges,
                evaluation->wrong_ok_loop_edges, evaluation->closed_revisits, evaluation->true_revisits, evaluation->recall);
    std::printf("returns (an earlier scan within 30 m after the path left 30 m, or another session's): %zu / %zu closed by a right ok loop edge\n",
                evaluation->closed_returns, evaluation->returns);
    if (evaluation->place_queries > 0)
      std::printf("place recognition: %zu / %zu scans revisiting another session had a true match (10 m) among their candidates"
                  "; with the joint-frame search %zu / %zu\n",
                  evaluation->place_hits, evaluation->place_queries, evaluation->joint_place_hits, evaluation->joint_place_queries);
  }
  std::printf("wrote %s (poses.tsv, edges.csv, report.json, map.ply, map_model.qsm, %s)\n", options.out.c_str(),
              std::filesystem::path(page).filename().string().c_str());
}

const CommandRegistration registration(75, [](CLI::App& app) {
  auto options = std::make_shared<MapCommandOptions>();
  CLI::App* command = app.add_subcommand("map", "One map from many scans: loop closure and multi-session mapping with a pose graph");
  command->add_option("scans", options->scans, "SCANS.tsv: header, then session<TAB>scan<TAB>odometry (12 numbers or -)");
  command->add_option("--kitti", options->kitti, "A KITTI velodyne folder (*.bin) instead of SCANS.tsv");
  command->add_option("--kitti-poses", options->kitti_poses, "Its poses file (12 numbers a line; none: registered scan to scan)");
  command->add_option("--kitti-calib", options->kitti_calibration, "Its calib file: camera poses become LiDAR poses Tr^-1 P Tr");
  command->add_option("--out", options->out, "Output folder (replaced only once everything is written)")->required();
  command->add_option("--gt", options->truth, "True poses (poses.tsv format): ATE, RPE, loop-edge precision and recall");
  command->add_option("--scheduler", options->scheduler, "Dask scheduler address: model and register on its workers (runs python3 -m quadrix map; needs python3-distributed)");
  command->add_option("--preset", options->map.preset, "Registration preset of every scan: vlp64|vlp16|mid360|avia|monument|auto");
  command->add_option("--loop-radius", options->map.loop_radius, "Radius of the loop search right after a loop, m");
  command->add_option("--loop-radius-growth", options->map.loop_radius_growth, "Radius growth per metre travelled since the last loop");
  command->add_option("--minimum-loop-travel", options->map.minimum_loop_travel, "A loop candidate lies at least this far back along the path, m");
  command->add_option("--maximum-loop-radius", options->map.maximum_loop_radius, "The loop search radius never exceeds this, m");
  command->add_option("--candidate-spacing", options->map.minimum_candidate_spacing, "Loop candidates of one scan lie at least this far apart along the path, m");
  command->add_flag("--registration-information", options->map.loop_information_from_registration,
                    "Loop edges carry the registration's information (H / inliers x --information-scale) instead of fixed sigmas (0.1 m, 0.5 deg)");
  command->add_option("--information-scale", options->map.loop_information_scale, "Scale of the registration's information per inlier, 1/m^2")
      ->check(CLI::PositiveNumber);
  command->add_option("--candidates-per-scan", options->map.candidates_per_scan, "Loop candidates registered per scan within a session");
  command->add_option("--place-candidates", options->map.place_candidates_per_scan, "Candidates per scan across sessions (place descriptor)");
  command->add_flag("!--no-ambiguous-edges", options->map.use_ambiguous_edges,
                    "Leave ambiguous loop edges within a session out of the graph (default: in when they pass the odometry gate and agree with the map of the sure edges, under Huber)");
  command->add_flag("--ambiguous-edges-across-sessions", options->map.use_ambiguous_edges_across_sessions,
                    "Let ambiguous loop edges between sessions into the graph too (default: out; no odometry arbitrates them)");
  command->add_option("--odometry-gate", options->map.odometry_gate_sigmas,
                      "Loop edges within a session departing from the odometry by more than this many drift sigmas stay out (0: no gate)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  command->add_option("--joint-rounds", options->map.joint_rounds,
                      "Rounds of loop candidates across sessions by radius search in the joint map frame once placed (0: none)")
      ->capture_default_str();
  command->add_option("--joint-radius", options->map.joint_radius, "Radius of that search around each scan's map position, m")
      ->capture_default_str();
  command->add_flag("!--no-ambiguous-joint-edges", options->map.use_ambiguous_joint_edges,
                    "Leave ambiguous edges of the joint-frame rounds out of the graph (default: in within the ambiguous gate, under Huber)");
  command->add_option("--ambiguous-gate-translation", options->map.ambiguous_gate_translation,
                      "An ambiguous loop edge (within a session, or of the joint-frame rounds) enters the graph only within this "
                      "many metres of the map solved without it")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  command->add_option("--ambiguous-gate-rotation", options->map.ambiguous_gate_rotation_degrees,
                      "and within this many degrees")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  command->add_option("--information-rounds", options->map.information_rounds,
                      "At most this many rounds of variance component estimation after the last solve: each group of edges (odometry per "
                      "session, loop edges per pair of sessions) is weighted by what its residuals measured (0: the information as given)")
      ->check(CLI::Range(std::size_t{0}, kMaximumInformationRounds))
      ->capture_default_str();
  command->add_option("--place-vote", options->map.place_vote_minimum,
                      "Ambiguous place edges between two sessions enter the graph when at least this many place edges agree on the "
                      "sessions' relative pose (3 deg, 10 m) and twice as many as on any contradicting pose (0: never)")
      ->capture_default_str();
  command->add_option("--outlier-threshold", options->map.outlier_threshold,
                      "After the calibration, loop edges leave the graph one at a time while the largest chi-square over redundancy "
                      "(Baarda's outlier statistic) exceeds this (0: no test)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  command->add_option("--map-voxel", options->map.map_voxel, "map.ply keeps one point per cube of this edge, m");
  command->callback([options] { run(*options); });
});

}  // namespace
}  // namespace quadrix::cli
