// `quadrix synth SCENE --seed N --sensor hdl64|vlp16|livox|tls [--poses POSE_SPEC] --out DIR`:
// simulates scans of a built-in scene and writes a self-describing folder with the ground truth;
// `quadrix synth --list` names the scenes and sensors. `quadrix synth loop-closures` writes a
// loop-closure benchmark set (loop_closure_set.h) instead of one scene's scans, and `quadrix synth drive`
// a multi-session drive through a town with drifting odometry (town_drive.h), the mapping benchmark.
#include "geometry/output_paths.h"
#include "experiments/command_line/command_registry.h"
#include "experiments/synthetic/loop_closure_set.h"
#include "experiments/synthetic/synthetic_output.h"
#include "experiments/synthetic/town_drive.h"
#include "geometry/error.h"

#include <chrono>
#include <map>
#include <cstdio>
#include <memory>
#include <optional>
#include <sstream>
#include <string>

namespace quadrix::cli {
namespace {

struct SynthCommandOptions {
  std::string scene;                   ///< scene name (street, corridor, monument)
  std::uint64_t seed = 1;              ///< layout and noise seed
  std::string sensor = "hdl64";        ///< sensor preset
  std::string poses;                   ///< POSE_SPEC; empty = the scene's defaults for the sensor
  std::string out;                     ///< output folder
  std::string format = "ply";          ///< cloud format: ply or pcd
  bool ascii = false;                  ///< ascii clouds instead of binary
  std::optional<double> noise;         ///< range noise sigma override, metres
  std::optional<double> dropout;       ///< dropout probability override
  std::string foliage = "solid";       ///< street vegetation: solid or porous (crowns and hedges)
  std::string second_pass = "opposite";  ///< loop-closures: the second drive's direction, opposite or same
  std::string source_sensor;           ///< loop-closures: the second pass's sensor (the sources'), for a cross-sensor set
  bool list = false;                   ///< list scenes and sensors, then exit
  LoopClosureSetOptions loop_set;      ///< loop-closures only: streets, pairs per bin
  std::optional<double> scan_spacing;  ///< loop-closures, drive: metres between scans (defaults 3 and 2)
  std::string sessions = "hdl64,vlp16,livox";  ///< drive only: one session per sensor, comma-separated
  TownDriveOptions drive;              ///< drive only: length, scans, drift
  std::optional<int> drive_scans;      ///< drive only: scans per session instead of --length
};

void print_listing() {
  std::printf("scenes:\n");
  for (const auto& name : scene_names()) std::printf("  %-9s %s\n", name.c_str(), scene_description(name).c_str());
  std::printf("  %-9s %s\n", "loop-closures",
              "benchmark set, not a scene: --streets street layouts from --seed on, each driven twice (the second "
              "pass the other way unless --second-pass same, with other parked cars and pedestrians), --pairs-per-bin "
              "pairs per street in each "
              "of the bins 0-10, 10-20, 20-30 m; writes pairs.tsv for quadrix bench");
  std::printf("  %-9s %s\n", "drive",
              "mapping benchmark, not a scene: a town of 2 x 2 blocks (12 streets) driven by --sessions (one sensor "
              "each) for --length m, with drifting odometry; writes SCANS.tsv, truth.tsv, scans/ and README.md");
  std::printf("sensors:\n");
  for (const auto& name : sensor_names()) {
    const SensorModel sensor = sensor_preset(name);
    std::printf("  %-9s %s\n", name.c_str(), sensor.description.c_str());
  }
}

// The sensor preset `name` with --noise and --dropout applied (checked first).
SensorModel sensor_with_overrides(const std::string& name, const SynthCommandOptions& options) {
  SensorModel sensor = sensor_preset(name);
  if (options.noise) {
    if (!(*options.noise >= 0.0)) throw Error("--noise: expected a range noise sigma >= 0 in metres");
    sensor.range_noise_sigma = *options.noise;
  }
  if (options.dropout) {
    if (!(*options.dropout >= 0.0 && *options.dropout < 1.0)) throw Error("--dropout: expected a probability in [0, 1)");
    sensor.dropout_probability = *options.dropout;
  }
  return sensor;
}

// `quadrix synth drive`: the town drive with one session per --sessions sensor.
void run_drive(const SynthCommandOptions& options) {
  if (!options.poses.empty()) throw Error("synth drive: --poses does not apply (the sessions follow the town's tour)");
  if (options.format != "ply" || options.ascii) throw Error("synth drive: writes binary PLY only (no --format pcd, no --ascii)");
  if (options.second_pass != "opposite" || !options.source_sensor.empty())
    throw Error("synth drive: --second-pass and --source-sensor apply to loop-closures only");
  TownDriveOptions drive = options.drive;
  drive.seed = options.seed;
  drive.foliage = foliage_from_name(options.foliage, "--foliage");
  if (options.scan_spacing) drive.scan_spacing = *options.scan_spacing;
  drive.scans = options.drive_scans;
  drive.sensors.clear();
  std::stringstream names(options.sessions);
  for (std::string name; std::getline(names, name, ',');) {
    if (name.empty()) throw Error("--sessions: expected sensor names separated by commas, got '" + options.sessions + "'");
    drive.sensors.push_back(sensor_with_overrides(name, options));
  }
  FolderReplacement output("--out", options.out, {"scans", "SCANS.tsv", "truth.tsv", "README.md"}, {});
  const auto start = std::chrono::steady_clock::now();
  const TownDriveSummary summary = write_town_drive(output.staging_folder(), drive);
  output.commit();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("town drive, seed %llu: %zu scans in %zu session(s), %zu points\n", static_cast<unsigned long long>(drive.seed),
              summary.plan.scans.size(), drive.sensors.size(), summary.points);
  for (std::size_t k = 0; k < drive.sensors.size(); ++k)
    std::printf("  session %zu (%s): %.0f m, odometry ATE %.2f m, end error %.2f m\n", k + 1, drive.sensors[k].name.c_str(),
                summary.plan.session_lengths[k], summary.odometry_ate[k], summary.odometry_end_error[k]);
  std::printf("revisits within 10 m: %d same direction, %d opposite; wrote %s/SCANS.tsv and truth.tsv in %.1f s\n",
              summary.same_direction_revisits, summary.opposite_direction_revisits, options.out.c_str(), seconds);
}

void run_command(const SynthCommandOptions& options) {
  if (options.list) {
    print_listing();
    return;
  }
  if (options.scene.empty()) throw Error("synth: SCENE is required (one of street, corridor, monument; see --list)");
  if (options.out.empty()) throw Error("synth: --out DIR is required");
  const SensorModel sensor = sensor_with_overrides(options.sensor, options);
  if (options.scene == "drive") {
    run_drive(options);
    return;
  }
  if (options.scene == "loop-closures") {
    // The set places its own scans and writes binary PLY: options that would be ignored are refused.
    if (!options.poses.empty()) throw Error("synth loop-closures: --poses does not apply (each pass places its own scans)");
    if (options.format != "ply" || options.ascii) throw Error("synth loop-closures: writes binary PLY only (no --format pcd, no --ascii)");
    LoopClosureSetOptions loop_set = options.loop_set;
    if (options.scan_spacing) loop_set.scan_spacing = *options.scan_spacing;
    loop_set.first_seed = options.seed;
    loop_set.street.foliage = foliage_from_name(options.foliage, "--foliage");
    if (options.second_pass != "opposite" && options.second_pass != "same")
      throw Error("--second-pass: expected opposite or same, got '" + options.second_pass + "'");
    loop_set.same_direction = options.second_pass == "same";
    loop_set.sensor = sensor;
    if (!options.source_sensor.empty()) loop_set.source_sensor = sensor_with_overrides(options.source_sensor, options);
    FolderReplacement output("--out", options.out, {"pairs.tsv", "street_*"}, {});
    const auto start = std::chrono::steady_clock::now();
    const std::vector<LoopClosureSetPair> pairs = write_loop_closure_set(output.staging_folder(), loop_set);
    output.commit();
    std::map<std::string, int> per_bin;
    for (const LoopClosureSetPair& pair : pairs) ++per_bin[pair.bin];
    std::printf("loop-closure set: %d streets from seed %llu, %zu pairs (", loop_set.streets,
                static_cast<unsigned long long>(loop_set.first_seed), pairs.size());
    for (const auto& [bin, count] : per_bin) std::printf("%s%s m: %d", bin == per_bin.begin()->first ? "" : ", ", bin.c_str(), count);
    std::printf(") in %.1f s; run it with quadrix bench --pairs %s/pairs.tsv\n",
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), options.out.c_str());
    return;
  }
  if (options.second_pass != "opposite") throw Error("--second-pass applies to loop-closures only");
  if (options.scan_spacing) throw Error("--scan-spacing applies to loop-closures and drive only");
  if (!options.source_sensor.empty()) throw Error("--source-sensor applies to loop-closures only");
  SyntheticOutputOptions output;
  if (options.format == "ply") {
    output.cloud_format = CloudFormat::Ply;
  } else if (options.format == "pcd") {
    output.cloud_format = CloudFormat::Pcd;
  } else {
    throw Error("--format: expected ply or pcd, got '" + options.format + "'");
  }
  output.binary = !options.ascii;

  FolderReplacement folder("--out", options.out, synthetic_folder_names(), {options.poses});
  const auto start = std::chrono::steady_clock::now();
  StreetOptions street;
  street.foliage = foliage_from_name(options.foliage, "--foliage");
  const Scene scene = make_scene(options.scene, options.seed, street);
  const auto poses = options.poses.empty() ? default_sensor_poses(scene, sensor) : parse_pose_spec(options.poses);
  const SyntheticRun run = run_synthetic(scene, sensor, poses, options.seed);
  const auto simulated = std::chrono::steady_clock::now();
  const auto files = write_synthetic_folder(folder.staging_folder(), run, output);
  folder.commit();
  const auto finished = std::chrono::steady_clock::now();

  std::printf("scene %s (seed %llu): %zu primitives", scene.name.c_str(),
              static_cast<unsigned long long>(options.seed), scene.primitives.size());
  for (const auto& [type, count] : count_model_types(scene)) std::printf(", %d %s", count, type.c_str());
  std::printf("\n");
  for (std::size_t i = 0; i < run.scans.size(); ++i) {
    const auto& scan = run.scans[i];
    std::printf("scan %zu: %zu points from %zu rays (%zu misses, %zu too near, %zu dropped)\n", i, scan.cloud.size(),
                scan.rays, scan.misses, scan.too_near, scan.dropped);
  }
  const auto seconds = [](auto from, auto to) { return std::chrono::duration<double>(to - from).count(); };
  std::printf("simulated in %.2f s, wrote %zu files to %s in %.2f s (see scene.json)\n", seconds(start, simulated),
              files.size(), options.out.c_str(), seconds(simulated, finished));
}

const CommandRegistration registration(20, [](CLI::App& app) {
  auto options = std::make_shared<SynthCommandOptions>();
  CLI::App* command =
      app.add_subcommand("synth", "Simulate LiDAR/TLS scans of a built-in scene and write clouds plus ground truth");
  command->add_option("scene", options->scene, "Scene: street, corridor or monument, or loop-closures or drive (see --list)");
  command->add_flag("--list", options->list, "List the scenes and sensors, then exit");
  command->add_option("--seed", options->seed, "Seed of the layout (street, corridor) and of noise/dropout")
      ->capture_default_str();
  command->add_option("--sensor", options->sensor, "Sensor preset: hdl64, vlp16, livox or tls")->capture_default_str();
  command->add_option("--poses", options->poses,
                      "Sensor->world poses: 'x,y,z,yaw_deg[,pitch_deg[,roll_deg]];...' or a file with one pose a line "
                      "(4-6 numbers, or 12/16 row-major). Default: a LiDAR registration pair, or six TLS stations");
  command->add_option("--out", options->out, "Output folder (replaced whole once everything is written; an existing one may hold only an earlier run's files)");
  command->add_option("--format", options->format, "Cloud format: ply or pcd")->capture_default_str();
  command->add_flag("--ascii", options->ascii, "Write ascii clouds instead of binary");
  command->add_option("--noise", options->noise, "Gaussian range noise sigma in metres (overrides the preset)");
  command->add_option("--dropout", options->dropout, "Probability that a return is lost (overrides the preset)");
  command->add_option("--foliage", options->foliage,
                      "street, loop-closures: solid tree crowns, or porous crowns and hedges that rays enter")
      ->capture_default_str();
  command->add_option("--streets", options->loop_set.streets, "loop-closures: number of street layouts")->capture_default_str();
  command->add_option("--pairs-per-bin", options->loop_set.pairs_per_bin, "loop-closures: pairs per street and distance bin")
      ->capture_default_str();
  command->add_option("--scan-spacing", options->scan_spacing,
                      "loop-closures, drive: metres between scans of a pass or session (default 3 and 2)");
  command->add_option("--sessions", options->sessions, "drive: one session per sensor, comma-separated (hdl64, vlp16, livox, tls)")
      ->capture_default_str();
  command->add_option("--length", options->drive.length, "drive: metres driven per session")->capture_default_str();
  command->add_option("--scans", options->drive_scans, "drive: scans per session (instead of --length)");
  command->add_option("--drift-scale", options->drive.drift.scale_error,
                      "drive: odometry scale error, fraction (sign drawn per session)")
      ->capture_default_str();
  command->add_option("--drift-yaw-bias", options->drive.drift.yaw_bias_deg_per_m,
                      "drive: odometry heading bias, degrees per metre (sign drawn per session)")
      ->capture_default_str();
  command->add_option("--drift-yaw-walk", options->drive.drift.yaw_walk_deg_per_sqrt_m,
                      "drive: odometry heading random walk, degrees per sqrt(metre)")
      ->capture_default_str();
  command->add_option("--drift-tilt-walk", options->drive.drift.tilt_walk_deg_per_sqrt_m,
                      "drive: odometry roll and pitch random walk, degrees per sqrt(metre)")
      ->capture_default_str();
  command->add_option("--drift-translation-walk", options->drive.drift.translation_walk_m_per_sqrt_m,
                      "drive: odometry position random walk, metres per sqrt(metre)")
      ->capture_default_str();
  command->add_option("--second-pass", options->second_pass,
                      "loop-closures: the second drive goes the opposite way or the same way (forward-looking sensors such as "
                      "the Livox share no view with an opposite pass)")
      ->capture_default_str();
  command->add_option("--source-sensor", options->source_sensor,
                      "loop-closures: scan the second pass (the pairs' sources) with this sensor and the first with --sensor: "
                      "a cross-sensor set (default: --sensor for both)");
  command->callback([options] { run_command(*options); });
});

}  // namespace
}  // namespace quadrix::cli
