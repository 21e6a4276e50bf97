// `quadrix bench`: the benchmark harness. Pairs come from a pairs.tsv file (--pairs), a
// KITTI-layout sequence by the paper's loop-closure or odometry rule (--kitti ROOT --seq SS --mode
// lc|odo), or the published lists (--list FILE, clouds under --kitti ROOT). Every pair is run with
// every --method in this process, optionally under random yaw / translation trials and an
// --ablation; results go to --out DIR (pairs.csv, summary.md, SVG plots, run.json) and a summary is
// printed. `quadrix bench merge DIR... --out DIR` merges shard folders into the summary of one run.
#include "experiments/benchmark/bench_pairs.h"
#include "experiments/benchmark/benchmark_runner.h"
#include "geometry/output_paths.h"
#include "experiments/command_line/command_registry.h"
#include "estimation/registration_config.h"
#include "geometry/error.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace quadrix::cli {
namespace {

struct BenchCommandOptions {
  std::string pairs_file;              ///< --pairs FILE.tsv
  std::vector<std::string> kinds;      ///< --kind: keep only pairs of these kinds
  std::string ids;                     ///< --ids: keep only pairs whose id matches this regular expression
  std::string kitti_root;              ///< --kitti ROOT
  std::string sequence = "00";         ///< --seq
  std::string mode = "lc";             ///< --mode lc | odo
  std::string bins = "0-10,10-20,20-30";  ///< --bins (lc)
  std::string distances = "1..10";     ///< --distance (odo)
  std::string calibration;             ///< --calib FILE
  std::vector<std::string> lists;      ///< --list FILE (repeatable)
  LoopClosureOptions loop_closure;     ///< t_lc, sampling
  OdometryOptions odometry;            ///< tolerance, sampling
  std::string methods = "quadrix";     ///< --method a,b,c
  std::string shard = "1/1";           ///< --shard i/n
  std::string out;                     ///< --out DIR
  std::string title;                   ///< --title
  bool print_pairs = false;            ///< --print-pairs: list the pairs and stop
  bool quiet = false;                  ///< --no-progress
  std::string label_classes;           ///< --label-classes a,b (with --labels)
  BenchOptions bench;                  ///< everything else
};

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream stream(text);
  for (std::string item; std::getline(stream, item, ',');)
    if (!item.empty()) items.push_back(item);
  return items;
}

std::vector<BenchPair> collect_pairs(const BenchCommandOptions& options, std::string& description) {
  const int sources = !options.pairs_file.empty() + !options.lists.empty() + (options.lists.empty() && !options.kitti_root.empty());
  if (sources != 1)
    throw Error("give exactly one pair source: --pairs FILE.tsv, --kitti ROOT (with --mode lc|odo), or --list FILE... (clouds under --kitti ROOT)");
  std::vector<BenchPair> pairs;
  std::ostringstream text;
  if (!options.pairs_file.empty()) {
    pairs = read_pairs_tsv(options.pairs_file);
    text << "--pairs " << options.pairs_file;
  } else if (!options.lists.empty()) {
    for (const std::string& list : options.lists) {
      const std::vector<BenchPair> listed = listed_pairs_to_bench(read_pair_list(list), list, options.kitti_root);
      pairs.insert(pairs.end(), listed.begin(), listed.end());
      text << "--list " << list << " ";
    }
    text << "--kitti " << options.kitti_root;
  } else {
    const KittiSequence sequence = load_kitti_sequence(options.kitti_root, options.sequence, options.calibration);
    text << "--kitti " << options.kitti_root << " --seq "
         << options.sequence << " --mode " << options.mode;
    if (options.mode == "lc") {
      pairs = generate_loop_closure_pairs(sequence, parse_distance_bins(options.bins), options.loop_closure);
      text << " --bins " << options.bins << " --t-lc " << options.loop_closure.minimum_frame_gap << " --pairs-per-bin "
           << options.loop_closure.pairs_per_bin;
    } else if (options.mode == "odo") {
      pairs = generate_odometry_pairs(sequence, parse_odometry_distances(options.distances), options.odometry);
      text << " --distance " << options.distances << " --pairs-per-bin " << options.odometry.pairs_per_distance;
    } else {
      throw Error("--mode '" + options.mode + "': expected lc (loop closure) or odo (odometry)");
    }
  }
  if (!options.kinds.empty()) {
    std::vector<BenchPair> kept;
    for (BenchPair& pair : pairs)
      if (std::find(options.kinds.begin(), options.kinds.end(), pair.kind) != options.kinds.end()) kept.push_back(std::move(pair));
    pairs = std::move(kept);
    text << " --kind";
    for (const std::string& kind : options.kinds) text << " " << kind;
  }
  if (!options.ids.empty()) {
    std::regex pattern;
    try {
      pattern = std::regex(options.ids);
    } catch (const std::regex_error& error) {
      throw Error("--ids '" + options.ids + "': not a regular expression (" + error.what() + ")");
    }
    std::vector<BenchPair> kept;
    for (BenchPair& pair : pairs)
      if (std::regex_search(pair.id, pattern)) kept.push_back(std::move(pair));
    pairs = std::move(kept);
    text << " --ids '" << options.ids << "'";
  }
  if (pairs.empty()) throw Error("no pair to run (" + text.str() + ")");
  for (const BenchPair& pair : pairs)
    if (!options.print_pairs && (pair.source.empty() || pair.target.empty()))
      throw Error("pair " + pair.id + " has no cloud files: give --kitti ROOT holding sequences/SS/velodyne");
  description = text.str();
  return pairs;
}

std::string format_duration(double seconds) {
  char text[32];
  if (seconds >= 3600.0)
    std::snprintf(text, sizeof(text), "%dh%02dm", static_cast<int>(seconds / 3600.0), static_cast<int>(seconds / 60.0) % 60);
  else if (seconds >= 60.0)
    std::snprintf(text, sizeof(text), "%dm%02ds", static_cast<int>(seconds / 60.0), static_cast<int>(seconds) % 60);
  else
    std::snprintf(text, sizeof(text), "%.0fs", seconds);
  return text;
}

// The files write_bench_outputs puts in a folder (the only ones an existing --out folder may hold).
std::vector<std::string> bench_output_names() {
  return {"pairs.csv", "run.json", "summary.md", "success_by_difficulty.svg", "error_cdf.svg", "time_per_stage.svg"};
}

void run(BenchCommandOptions& options) {
  std::string description;
  const std::vector<BenchPair> pairs = collect_pairs(options, description);
  // The output folder is checked before the benchmark and replaced at once after it.
  std::optional<FolderReplacement> output;
  if (!options.out.empty() && !options.print_pairs) {
    std::vector<std::string> inputs = {options.pairs_file, options.kitti_root, options.calibration, options.bench.config};
    inputs.insert(inputs.end(), options.lists.begin(), options.lists.end());
    for (const BenchPair& pair : pairs) {
      inputs.push_back(pair.source);
      inputs.push_back(pair.target);
    }
    output.emplace("--out", options.out, bench_output_names(), inputs);
  }
  if (options.print_pairs) {
    std::printf("id\tsource\ttarget\tdifficulty\tdistance_m\tgt\n");
    for (const BenchPair& pair : pairs) {
      std::string gt = "-";
      if (pair.ground_truth) {
        const Eigen::Matrix4d m = pair.ground_truth->matrix();
        std::ostringstream values;
        for (int k = 0; k < 12; ++k) values << (k ? " " : "") << m(k / 4, k % 4);
        gt = values.str();
      }
      std::printf("%s\t%s\t%s\t%s\t%.3f\t%s\n", pair.id.c_str(), pair.source.c_str(), pair.target.c_str(),
                  pair.difficulty.c_str(), pair.distance, gt.c_str());
    }
    return;
  }
  BenchOptions& bench = options.bench;
  bench.methods = split_list(options.methods);
  if (std::sscanf(options.shard.c_str(), "%d/%d", &bench.shard_index, &bench.shard_count) != 2)
    throw Error("--shard '" + options.shard + "': expected i/n, e.g. 2/3");
  bench.progress = !options.quiet;
  if (!options.label_classes.empty()) {
    if (!bench.labels) throw Error("--label-classes needs --labels");
    bench.label_classes = parse_label_classes(options.label_classes);
  }
  const std::size_t task_count = pairs.size() * static_cast<std::size_t>(std::max(bench.trials, 1));

  const auto start = std::chrono::steady_clock::now();
  std::mutex print_mutex;
  BenchProgress progress;
  if (bench.progress)
    progress = [&](std::size_t done, std::size_t total, const std::vector<BenchRow>& rows) {
      std::size_t successes = 0;
      std::size_t judged = 0;
      for (const BenchRow& row : rows)
        if (row.method == bench.methods.front() && row.has_ground_truth) {
          ++judged;
          successes += row.success ? 1 : 0;
        }
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      const double left = done ? elapsed / static_cast<double>(done) * static_cast<double>(total - done) : 0.0;
      std::lock_guard<std::mutex> lock(print_mutex);
      std::fprintf(stderr, "\rbench: %zu/%zu pairs done, %s success %zu/%zu, %s elapsed, ~%s left   ", done, total,
                   bench.methods.front().c_str(), successes, judged, format_duration(elapsed).c_str(),
                   format_duration(left).c_str());
      if (done == total) std::fprintf(stderr, "\n");
      std::fflush(stderr);
    };
  const std::vector<BenchRow> rows = run_benchmark(pairs, bench, progress);

  std::ostringstream options_text;
  options_text << description << " --method " << options.methods << " --preset " << bench.preset;
  if (!bench.config.empty()) options_text << " --config " << bench.config;
  if (!bench.refiner.empty()) options_text << " --refiner " << bench.refiner;
  if (!bench.ablation.empty()) options_text << " --ablation " << bench.ablation;
  if (!bench.corruption.empty()) options_text << " --corrupt " << bench.corruption;
  if (bench.labels) options_text << " --labels";
  if (!options.label_classes.empty()) options_text << " --label-classes " << options.label_classes;
  options_text << " --yaw-range " << bench.yaw_range_degrees << " --translation-range " << bench.translation_range
               << " --tilt " << bench.tilt_range_degrees
               << " --trials " << bench.trials << " --seed " << bench.seed << " --baseline-voxel " << bench.baseline.voxel_size;
  BenchRunInfo info;
  info.title = options.title.empty() ? "quadrix bench" + std::string(bench.ablation.empty() ? "" : " (ablation " + bench.ablation + ")")
                                     : options.title;
  info.methods = bench.methods;
  info.task_count = task_count;
  info.shard_index = bench.shard_index;
  info.shard_count = bench.shard_count;
  info.options_text = options_text.str();
  const std::vector<MethodSummary> summaries =
      output ? write_bench_outputs(output->staging_folder(), rows, info) : summarize_bench(rows, bench.methods);
  if (output) output->commit();
  std::printf("quadrix bench: %zu pairs x %d trial(s)%s, %zu tasks in this shard (%d/%d)\n", pairs.size(), bench.trials,
              bench.ablation.empty() ? "" : (", ablation " + bench.ablation).c_str(), rows.size() / bench.methods.size(),
              bench.shard_index, bench.shard_count);
  std::printf("%s", bench_summary_text(summaries).c_str());
  if (!options.out.empty())
    std::printf("wrote %s/{pairs.csv, summary.md, run.json, success_by_difficulty.svg, error_cdf.svg, time_per_stage.svg}\n",
                options.out.c_str());
}

const CommandRegistration registration(70, [](CLI::App& app) {
  auto options = std::make_shared<BenchCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "bench", "Benchmark Quadrix and the baselines on many pairs (success, RTE/RRE, IR/CR, time per stage, model bytes)");
  command->add_option("--pairs", options->pairs_file, "Pairs file in the format of ../shared/data/pairs.tsv (paths relative to it)");
  command->add_option("--kind", options->kinds, "Keep only pairs of these kinds (pairs.tsv `kind`, e.g. loop_closure)")->delimiter(',');
  command->add_option("--ids", options->ids, "Keep only pairs whose id matches this regular expression (e.g. '^kitti00_lc')");
  command->add_option("--kitti", options->kitti_root, "KITTI-layout root: sequences/SS/velodyne/NNNNNN.bin and poses/SS.txt");
  command->add_option("--seq", options->sequence, "KITTI sequence")->capture_default_str();
  command->add_option("--mode", options->mode, "lc: loop-closure pairs (paper Eq. loop pair gen); odo: odometry pairs")
      ->capture_default_str();
  command->add_option("--bins", options->bins, "Loop-closure distance bins d_min-d_max, m")->capture_default_str();
  command->add_option("--distance", options->distances, "Odometry distances d_odo, m: 1..10 or 1,5,10")->capture_default_str();
  command->add_option("--calib", options->calibration,
                      "Velodyne->camera calibration (KITTI calib.txt or ../shared/data/kitti_poses/calib_Tr_velo_to_cam.txt); "
                      "default ROOT/sequences/SS/calib.txt");
  command->add_option("--t-lc", options->loop_closure.minimum_frame_gap, "t_lc: minimum |i - j| of a loop pair, frames")
      ->capture_default_str();
  command->add_option("--pairs-per-bin", options->loop_closure.pairs_per_bin,
                      "Uniform spatial sampling keeps at most this many pairs per bin (lc)")->capture_default_str();
  command->add_option("--pairs-per-distance", options->odometry.pairs_per_distance,
                      "Uniform spatial sampling keeps at most this many pairs per distance (odo)")->capture_default_str();
  command->add_option("--odo-tolerance", options->odometry.tolerance, "Odometry pairs must be within this of d_odo, m")
      ->capture_default_str();
  command->add_option("--list", options->lists, "Published pair list(s) (lc_sample/*/test_A_B.txt); clouds under --kitti ROOT");
  command->add_flag("--print-pairs", options->print_pairs, "Print the pairs (id, files, bin, distance, ground truth) and stop");
  command->add_option("--method", options->methods, "Comma-separated: quadrix,open3d-ransac,open3d-fgr,pcl-prerejective")
      ->capture_default_str();
  std::string presets;
  for (const auto& name : registration_preset_names()) presets += name + "|";
  command->add_option("--preset", options->bench.preset, "Quadrix preset: " + presets + "auto (per cloud, as quadrix register)")
      ->capture_default_str();
  command->add_option("--config", options->bench.config, "Quadrix YAML overrides (as quadrix register --config)");
  command->add_option("--refiner", options->bench.refiner, "Quadrix refiner override: ceres | nlopt");
  std::string ablations;
  for (const auto& name : bench_ablation_names()) ablations += (ablations.empty() ? "" : ", ") + name;
  command->add_option("--ablation", options->bench.ablation, "One row of the paper's ablation table: " + ablations);
  command->add_option("--yaw-range", options->bench.yaw_range_degrees,
                      "Random yaw of the source about the up axis, uniform in [-DEG, DEG]")->capture_default_str();
  command->add_option("--translation-range", options->bench.translation_range,
                      "Random horizontal translation of the source, uniform in a disc of this radius, m")->capture_default_str();
  command->add_option("--tilt", options->bench.tilt_range_degrees,
                      "Random tilt of the source about a horizontal axis through the sensor, uniform in [0, DEG]; "
                      "auto then measures the tilted cloud's up axis")->capture_default_str();
  command->add_flag("--labels", options->bench.labels,
                    "Quadrix with per-point classes given (labels semantic mode): each pair's source_labels / "
                    "target_labels files of pairs.tsv, else the clouds' own label field (simulated scans)");
  command->add_option("--label-classes", options->label_classes,
                      "With --labels: take only these classes from the labels, comma-separated (line, vehicle, trunk, "
                      "vegetation); every other point is modelled from geometry");
  std::string corruptions;
  for (const auto& name : standard_corruption_names()) corruptions += (corruptions.empty() ? "" : ", ") + name;
  command->add_option("--corrupt", options->bench.corruption,
                      "Damage every source cloud (seeded per task): drop-P, sector-D, outliers-P, noise-S (20% of points), "
                      "duplicate, scale-F; e.g. " + corruptions);
  command->add_option("--trials", options->bench.trials, "Random perturbations per pair")->capture_default_str();
  command->add_option("--seed", options->bench.seed, "Seed of the perturbations (task k uses seed * 1000003 + k)")->capture_default_str();
  command->add_option("--jobs", options->bench.jobs, "Pairs run in parallel")->capture_default_str();
  command->add_option("--shard", options->shard, "Run shard i of n (tasks k with k mod n = i - 1); merge with `bench merge`")
      ->capture_default_str();
  command->add_option("--baseline-voxel", options->bench.baseline.voxel_size, "Baselines' voxel size, m")->capture_default_str();
  command->add_option("--baseline-iterations", options->bench.baseline.ransac_iterations, "Baselines' RANSAC iterations")
      ->capture_default_str();
  command->add_option("--out", options->out, "Output folder: pairs.csv, summary.md, run.json and SVG plots");
  command->add_option("--title", options->title, "Title of summary.md");
  command->add_flag("--no-progress", options->quiet, "No progress line on stderr");

  auto merge_folders = std::make_shared<std::vector<std::string>>();
  auto merge_out = std::make_shared<std::string>();
  CLI::App* merge = command->add_subcommand("merge", "Merge shard output folders into the outputs and summary of one run");
  merge->add_option("folders", *merge_folders, "Shard output folders (each from `quadrix bench --shard i/n --out DIR`)")->required();
  merge->add_option("--out", *merge_out, "Folder for the merged outputs")->required();
  merge->callback([merge_folders, merge_out] {
    FolderReplacement output("--out", *merge_out, bench_output_names(), *merge_folders);
    const std::vector<MethodSummary> summaries = merge_bench_outputs(*merge_folders, output.staging_folder());
    output.commit();
    std::printf("quadrix bench merge: %zu folders -> %s\n%s", merge_folders->size(), merge_out->c_str(),
                bench_summary_text(summaries).c_str());
  });
  command->callback([options, merge] {
    if (merge->parsed()) return;
    run(*options);
  });
});

}  // namespace
}  // namespace quadrix::cli
