// The benchmark harness behind `quadrix bench`: runs Quadrix and the baselines (each baseline call in
// a quadrix-baselines child process, baseline_process.h) on the same pairs, with optional random yaw / translation trials, ablations, parallel
// jobs and shards; computes the paper's metrics (§"Evaluation Metrics": success = RTE <= 2 m and
// RRE <= 5 deg, RTE/RRE of successes, inlier ratio and correspondence recall, time per stage, model
// bytes per frame) and writes them (pairs.csv, summary.md, SVG plots). A summary is computed from the
// per-pair rows alone, so shards merged with merge_bench_outputs give exactly the summary of one run.
#pragma once

#include "estimation/registration.h"
#include "experiments/baselines/baseline_protocol.h"
#include "experiments/benchmark/bench_pairs.h"
#include "experiments/benchmark/fault_injection.h"
#include "fitting/scene_model.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace quadrix {

/// Names accepted by --ablation, one per row of the paper's ablation table (Table "Ablation study").
std::vector<std::string> bench_ablation_names();

/// The paper's ablation-table row of ablation `name` as "module|setting" (the `module` and
/// `setting` columns of papers/quadricsreg/tables/ablation.csv), "default|Default" for "" or
/// "default"; throws quadrix::Error for an unknown name.
std::string bench_ablation_paper_row(const std::string& name);

/// Applies the option part of ablation `name` to `options` (K_e, K_s, δ_m sets, augmentation,
/// no e_R / e_t, no refinement). Model-level ablations (no semantics, no central / linear-centre /
/// planar-centre quadrics) change nothing here: see apply_model_ablation. Throws quadrix::Error
/// listing the names for an unknown one; "" and "default" leave the options unchanged.
void apply_ablation(const std::string& name, RegistrationOptions& options);

/// Applies the model part of ablation `name` to a scene model: "no-semantics" gives every record
/// one label (Object: classes are no longer told apart), "no-central" / "no-linear-center" /
/// "no-planar-center" drop the fitted records whose centre is a point / a line / a plane (paper
/// §"Quadric Decomposition", I_t with 3 / 2 / 1 ones). Other names leave the model unchanged.
SceneModel apply_model_ablation(const std::string& name, const SceneModel& model);

/// Everything a benchmark run needs beside the pairs.
struct BenchOptions {
  std::vector<std::string> methods{"quadrix"};  ///< "quadrix" and/or baseline names (baseline_method_names())
  std::string preset = "auto";                  ///< Quadrix preset of both sides, or auto (chosen per cloud as `quadrix register` does)
  std::string config;                           ///< YAML overrides applied after the presets (apply_registration_config)
  std::string refiner;                          ///< refiner override ("" keeps the preset's)
  std::string ablation;                         ///< bench_ablation_names() entry, or "" for the defaults
  double yaw_range_degrees = 0.0;               ///< trials rotate the source by a yaw uniform in [-range, range] about the up axis
  double translation_range = 0.0;               ///< and translate it uniformly within a horizontal disc of this radius, m
  double tilt_range_degrees = 0.0;              ///< and tilt it about a random horizontal axis through the sensor by up to this angle (auto then finds the up axis itself)
  std::string corruption;                       ///< fault injected into every source cloud (parse_corruption name; "" none)
  bool labels = false;                          ///< Quadrix in the labels semantic mode: per-point classes from each pair's label files, else from the clouds' own label field (simulated scans)
  std::vector<ElementClass> label_classes;      ///< with `labels`: take only these classes from the labels, the rest from geometry (ExtractionOptions::label_classes; empty: all)
  int trials = 1;                               ///< random perturbations per pair (1 with both ranges 0: the pair as given)
  std::uint64_t seed = 1;                       ///< seed of the perturbations; task k uses seed * 1000003 + k (recorded per row)
  int jobs = 1;                                 ///< tasks run in parallel
  int shard_index = 1;                          ///< this shard, 1..shard_count: runs tasks k with k % shard_count == shard_index - 1
  int shard_count = 1;                          ///< number of shards
  bool progress = true;                         ///< print a progress line to stderr
  BaselineOptions baseline;                     ///< parameters of every baseline
};

/// One (pair, trial, method) result: a line of pairs.csv.
struct BenchRow {
  std::size_t task = 0;            ///< task index: pair index * trials + trial (global, shard-independent)
  std::string pair_id;             ///< BenchPair::id
  int trial = 0;                   ///< trial index
  std::string method;              ///< method name
  std::string difficulty;          ///< BenchPair::difficulty
  std::string kind;                ///< BenchPair::kind
  bool has_ground_truth = false;   ///< false: reported as "no ground truth", never counted as success or failure
  std::string status;              ///< quadrix: ok|ambiguous|degenerate|failed; baselines: solved|unsolved; "error" on an exception
  bool success = false;            ///< RTE <= 2 m and RRE <= 5 deg (only meaningful with ground truth)
  double rte = 0.0;                ///< RTE, m (0 without ground truth)
  double rre = 0.0;                ///< RRE, degrees (0 without ground truth)
  double yaw_degrees = 0.0;        ///< yaw applied to the source in this trial
  double tilt_degrees = 0.0;       ///< angle between the source's up axis before and after the perturbation
  double shift_x = 0.0;            ///< x translation applied to the source, m
  double shift_y = 0.0;            ///< y translation applied to the source, m
  std::uint64_t seed = 0;          ///< seed of this task's perturbation
  long long correspondences = -1;  ///< putative correspondences (quadrix; -1 otherwise)
  long long inliers = -1;          ///< of which inliers under the ground truth, 0.5 m (quadrix with ground truth; -1 otherwise)
  int recalled = -1;               ///< >= 3 inliers: 1 / 0 (quadrix with ground truth; -1 otherwise)
  long long true_partners = -1;    ///< fitted source quadrics with a true partner in the target model (count_true_partners: what matching could find; quadrix with ground truth)
  long long quadric_inliers = -1;  ///< true correspondences among the putative quadric correspondences (augmented points left out; quadrix with ground truth)
  long long best_clique_inliers = -1;  ///< most true quadric correspondences in one level's maximum clique (quadrix with ground truth)
  long long clique_inliers = -1;   ///< true quadric correspondences in the chosen candidate's clique (quadrix with ground truth)
  long long source_model_bytes = -1;  ///< binary model size of the source frame (quadrix; -1 otherwise)
  long long target_model_bytes = -1;  ///< binary model size of the target frame (quadrix; -1 otherwise)
  double overlap = -1.0;            ///< fraction of the source landing on the target under the answer (quadrix; -1 otherwise)
  double identity_overlap = -1.0;   ///< the same without moving the source (quadrix; -1 otherwise)
  std::map<std::string, double> timings_ms;  ///< per stage and "total" (cloud in memory -> transform), ms
  std::string message;             ///< status message
};

/// A method run on one task: what the runner needs from it.
struct BenchMethodInput {
  const BenchPair* pair = nullptr;                ///< the pair
  const PointCloud* source = nullptr;             ///< source cloud, already perturbed
  const PointCloud* target = nullptr;             ///< target cloud
  Eigen::Isometry3d perturbation = Eigen::Isometry3d::Identity();  ///< applied to the source (identity when none)
};

/// A method's answer on one task.
struct BenchMethodOutput {
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();  ///< maps the (perturbed) source into the target frame
  std::string status;                          ///< method status word
  std::string message;                         ///< why / summary
  std::map<std::string, double> timings_ms;    ///< per stage and "total", ms
};

/// An extra method for tests and studies: called per task instead of Quadrix / a baseline.
using BenchMethod = std::function<BenchMethodOutput(const BenchMethodInput& input)>;

/// Registers `method` under `name` for run_benchmark (replaces an existing extra of that name).
void register_bench_method(const std::string& name, BenchMethod method);

/// Called after every finished task: (tasks done, tasks of this shard, rows so far).
using BenchProgress = std::function<void(std::size_t done, std::size_t total, const std::vector<BenchRow>& rows)>;

/// Runs every task of this shard with every method. Clouds are read once per file and models of
/// unperturbed frames are built once (kept while tasks still need them); each row's modelling time
/// is the time that model took, so totals are per pair as if nothing were cached. Rows come back
/// sorted by (task, method order). Throws quadrix::Error for an unknown method, preset, ablation or
/// an unreadable file (naming it).
std::vector<BenchRow> run_benchmark(const std::vector<BenchPair>& pairs, const BenchOptions& options,
                                    const BenchProgress& progress = {});

/// How many rows of one status were right (success) and how many wrong, among rows with ground truth.
struct StatusOutcome {
  std::size_t right = 0;  ///< rows that met the success rule
  std::size_t wrong = 0;  ///< rows that did not
};

/// True quadric correspondences left after each stage, one entry per row with ground truth (BenchRow's
/// true_partners, quadric_inliers, best_clique_inliers, clique_inliers).
struct TrueCorrespondenceStages {
  std::vector<double> modelled;       ///< source records with a true partner in the target model
  std::vector<double> matched;        ///< true putative correspondences
  std::vector<double> best_clique;    ///< most true correspondences in one level's maximum clique
  std::vector<double> chosen_clique;  ///< true correspondences in the chosen candidate's clique
};

/// Per-method summary of rows.
struct MethodSummary {
  std::string method;                      ///< method name
  std::size_t tasks = 0;                   ///< rows
  std::size_t with_ground_truth = 0;       ///< rows with ground truth
  std::size_t successes = 0;               ///< of which successes
  std::size_t without_ground_truth = 0;    ///< rows reported as "no ground truth"
  std::map<std::string, std::size_t> statuses;  ///< rows per status word
  std::map<std::string, std::pair<std::size_t, std::size_t>> by_difficulty;  ///< difficulty -> (successes, with ground truth)
  std::map<std::string, std::map<std::string, StatusOutcome>> outcomes_by_kind;  ///< pair kind -> status -> right / wrong (ground truth only)
  std::size_t ok_and_wrong = 0;            ///< rows with status ok that failed the success rule: the error `ok` must never make
  std::map<std::string, TrueCorrespondenceStages> stages_by_difficulty;  ///< difficulty -> true correspondences per stage (quadrix rows with ground truth)
  double median_rte = 0.0;                 ///< median RTE of successes, m
  double median_rre = 0.0;                 ///< median RRE of successes, degrees
  double mean_rte = 0.0;                   ///< mean RTE of successes, m
  double mean_rre = 0.0;                   ///< mean RRE of successes, degrees
  double mean_inlier_ratio = -1.0;         ///< mean inliers / correspondences over rows with ground truth (-1: not measured)
  double correspondence_recall = -1.0;     ///< fraction of rows with >= 3 inliers (-1: not measured)
  double mean_correspondences = -1.0;      ///< mean putative correspondences (-1: not measured)
  std::map<std::string, std::pair<double, double>> stage_ms;  ///< stage -> (median, p90), ms, over every row
  double median_total_ms = 0.0;            ///< median of "total", ms
  double p90_total_ms = 0.0;               ///< 90th percentile of "total", ms
  double time_ratio_to_quadrix = 0.0;      ///< median_total_ms / Quadrix's (0 when Quadrix did not run)
  double median_model_bytes = -1.0;          ///< median binary model bytes per frame (-1: not a model-based method)
  std::vector<double> rte_values;          ///< RTE of every row with ground truth (for CDFs)
  std::vector<double> rre_values;          ///< RRE of every row with ground truth (for CDFs)

  /// successes / with_ground_truth (0 without ground truth).
  double success_rate() const { return with_ground_truth ? double(successes) / double(with_ground_truth) : 0.0; }
};

/// Summaries of `rows`, one per method in `methods` order (methods without rows are left out).
std::vector<MethodSummary> summarize_bench(const std::vector<BenchRow>& rows, const std::vector<std::string>& methods);

/// The Markdown summary: one table per method line (success, RTE/RRE, IR/CR, median/p90 time,
/// ratio to Quadrix, bytes per frame), success per difficulty, each status right / wrong per pair
/// kind (the confusion table), time per stage, statuses.
std::string bench_summary_markdown(const std::vector<MethodSummary>& summaries, const std::string& title);
/// Its "Success per difficulty" section, under a heading of `heading` ("##", "####").
std::string bench_success_by_difficulty_markdown(const std::vector<MethodSummary>& summaries, const std::string& heading);
/// Its "Status against ground truth" section (each status right / wrong per pair kind), under `heading`.
std::string bench_status_outcomes_markdown(const std::vector<MethodSummary>& summaries, const std::string& heading);
/// Its "Where the true correspondences are lost" section (TrueCorrespondenceStages per difficulty;
/// empty when no row counted them), under `heading`.
std::string bench_true_correspondence_stages_markdown(const std::vector<MethodSummary>& summaries,
                                                      const std::string& heading);

/// Short plain-text summary for the terminal: per method success on pairs with ground truth,
/// median time and its ratio to Quadrix.
std::string bench_summary_text(const std::vector<MethodSummary>& summaries);

/// Splits one CSV line into fields (RFC 4180 quoting: "a,b" and "" for a quote inside quotes).
std::vector<std::string> parse_csv_fields(const std::string& line);

/// Writes rows as CSV (header + one row each; numbers with 17 significant digits), atomically.
void write_bench_rows_csv(const std::string& path, const std::vector<BenchRow>& rows);
/// Reads write_bench_rows_csv output (also files written before the overlap columns existed, whose
/// rows get overlap -1); throws quadrix::Error naming the file and line.
std::vector<BenchRow> read_bench_rows_csv(const std::string& path);

/// Description of a run stored beside its rows (run.json): what merge needs to check and rebuild.
struct BenchRunInfo {
  std::string title;                  ///< title of the summary page
  std::vector<std::string> methods;   ///< method order
  std::size_t task_count = 0;         ///< tasks of the whole run (all shards)
  int shard_index = 1;                ///< shard of this output
  int shard_count = 1;                ///< shards of the run
  std::string options_text;           ///< options that must agree between shards (everything but the shard)
};

/// Writes every output of a run (or shard) into `folder`: pairs.csv, run.json, summary.md,
/// success_by_difficulty.svg, error_cdf.svg, time_per_stage.svg. Returns the summaries.
std::vector<MethodSummary> write_bench_outputs(const std::string& folder, const std::vector<BenchRow>& rows,
                                               const BenchRunInfo& info);

/// Reads run.json of an output folder; throws quadrix::Error naming the file.
BenchRunInfo read_bench_run_info(const std::string& folder);

/// Merges shard folders, and runs of different methods over the same tasks (options equal but for
/// --method; e.g. the slow baselines once, Quadrix again after a change): checks that every task of
/// every method is present exactly once, then writes the outputs of the whole run into `out_folder`
/// (shard 1/1, methods in first-seen order). Throws quadrix::Error naming the folder that disagrees
/// or the missing tasks.
std::vector<MethodSummary> merge_bench_outputs(const std::vector<std::string>& folders, const std::string& out_folder);

/// The SVG plots of write_bench_outputs, for reuse: success rate per difficulty bin and method.
std::string bench_success_svg(const std::vector<MethodSummary>& summaries);
/// RTE and RRE cumulative distributions per method (rows with ground truth).
std::string bench_error_cdf_svg(const std::vector<MethodSummary>& summaries);
/// Median time per stage and method (horizontal stacked bars).
std::string bench_time_svg(const std::vector<MethodSummary>& summaries);

}  // namespace quadrix
