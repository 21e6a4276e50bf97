// Running a benchmark: tasks, perturbations, cached clouds and models, methods, ablations (see benchmark_runner.h).
#include "experiments/benchmark/benchmark_runner.h"

#include "estimation/registration_config.h"
#include "experiments/benchmark/baseline_process.h"
#include "fitting/scene_modelling.h"
#include "geometry/error.h"
#include "geometry/io.h"
#include "matching/correspondences.h"

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <future>
#include <iterator>
#include <memory>
#include <mutex>
#include <random>
#include <thread>

namespace quadrix {
namespace {

using Clock = std::chrono::steady_clock;

double elapsed_ms(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

std::map<std::string, BenchMethod>& extra_methods() {
  static std::map<std::string, BenchMethod> methods;
  return methods;
}
std::mutex& extra_methods_mutex() {
  static std::mutex mutex;
  return mutex;
}

// Centre kind of a quadric type by its translation indicator I_t: 3 ones central, 2 linear, 1 planar.
int center_dimension(QuadricType type) {
  return static_cast<int>(degeneracy_indicators(type).translation.sum() + 0.5);
}

SceneModel drop_fitted_records(const SceneModel& model, int translation_ones) {
  SceneModel kept = model;
  kept.records.clear();
  kept.types.clear();
  kept.element_point_counts.clear();
  for (std::size_t i = 0; i < model.records.size(); ++i) {
    const bool fitted = i < model.augmented_begin;
    if (fitted && center_dimension(model.types[i]) == translation_ones) continue;
    kept.records.push_back(model.records[i]);
    kept.types.push_back(model.types[i]);
    kept.element_point_counts.push_back(model.element_point_counts[i]);
  }
  kept.augmented_begin = model.augmented_begin - (model.records.size() - kept.records.size());
  return kept;
}

// A cloud or model shared by the tasks that need it; released when the last one is done.
template <typename Value>
class SharedCache {
 public:
  // Announces one future use of `key`.
  void expect(const std::string& key) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++uses_[key];
  }
  // The value of `key`, made by `make` on first use (other callers wait for it).
  std::shared_ptr<const Value> get(const std::string& key, const std::function<Value()>& make) {
    std::shared_future<std::shared_ptr<const Value>> future;
    std::promise<std::shared_ptr<const Value>> promise;
    bool maker = false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      const auto found = values_.find(key);
      if (found != values_.end()) {
        future = found->second;
      } else {
        future = promise.get_future().share();
        values_[key] = future;
        maker = true;
      }
    }
    if (maker) {
      try {
        promise.set_value(std::make_shared<const Value>(make()));
      } catch (...) {
        promise.set_exception(std::current_exception());
      }
    }
    return future.get();
  }
  // One use of `key` is over; the value is dropped after the last announced use.
  void release(const std::string& key) {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto found = uses_.find(key);
    if (found == uses_.end()) return;
    if (--found->second == 0) {
      uses_.erase(found);
      values_.erase(key);
    }
  }

 private:
  std::mutex mutex_;
  std::map<std::string, std::size_t> uses_;
  std::map<std::string, std::shared_future<std::shared_ptr<const Value>>> values_;
};

struct BuiltModel {
  ModellingResult modelling;  // the model with its elements (augment_other_side needs them)
  double modelling_ms = 0.0;
};

struct Task {
  std::size_t index = 0;
  std::size_t pair = 0;
  int trial = 0;
};

// Whether trials move the source at all (else each pair runs as given).
bool perturbs(const BenchOptions& options) {
  return options.yaw_range_degrees > 0.0 || options.translation_range > 0.0 || options.tilt_range_degrees > 0.0;
}

// The trial's motion of the source: a tilt about a random horizontal axis through the sensor (uniform
// angle in [0, tilt range]) after a yaw about the up axis, then a horizontal shift. The yaw and shift
// are drawn first, so a run without tilt draws exactly what it drew before tilt existed.
Eigen::Isometry3d perturbation_of(const BenchOptions& options, std::uint64_t seed) {
  Eigen::Isometry3d perturbation = Eigen::Isometry3d::Identity();
  if (!perturbs(options)) return perturbation;
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const double yaw = options.yaw_range_degrees * unit(random);
  double x = 0.0;
  double y = 0.0;
  if (options.translation_range > 0.0) {  // uniform in the disc: rejection sampling in the square
    do {
      x = unit(random);
      y = unit(random);
    } while (x * x + y * y > 1.0);
    x *= options.translation_range;
    y *= options.translation_range;
  }
  Eigen::Matrix3d tilt = Eigen::Matrix3d::Identity();
  if (options.tilt_range_degrees > 0.0) {
    const double axis_heading = M_PI * unit(random);
    const double angle = options.tilt_range_degrees * 0.5 * (unit(random) + 1.0);
    const Eigen::Vector3d axis(std::cos(axis_heading), std::sin(axis_heading), 0.0);
    tilt = Eigen::AngleAxisd(angle * M_PI / 180.0, axis).toRotationMatrix();
  }
  perturbation.linear() = tilt * Eigen::AngleAxisd(yaw * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  perturbation.translation() = Eigen::Vector3d(x, y, 0.0);
  return perturbation;
}

PointCloud transformed(const PointCloud& cloud, const Eigen::Isometry3d& transform) {
  PointCloud moved = cloud;
  const Eigen::Matrix3f rotation = transform.linear().cast<float>();
  const Eigen::Vector3f translation = transform.translation().cast<float>();
  moved.positions = (rotation * cloud.positions).colwise() + translation;
  return moved;
}

// Everything shared by the workers of one run.
struct RunContext {
  const std::vector<BenchPair>* pairs = nullptr;
  const BenchOptions* options = nullptr;
  RegistrationOptions base;   // preset-independent part: config + ablation applied per preset in options_for
  SharedCache<PointCloud> clouds;
  std::mutex preset_mutex;
  // One side's options as `quadrix register` resolves them, and how long that took (auto measures the
  // cloud: sensor, up axis, crop).
  struct ResolvedSide {
    RegistrationOptions options;
    double milliseconds = 0.0;
  };
  std::map<std::string, ResolvedSide> resolved;  // cloud path (and corruption) -> its options, resolved once

  // The options `quadrix register` would use for this cloud on either side (resolve_registration_side).
  ResolvedSide resolve(const PointCloud& cloud) const {
    const Clock::time_point start = Clock::now();
    ResolvedSide side{resolve_registration_side(options->preset, cloud, "either")};
    side.milliseconds = elapsed_ms(start);
    return side;
  }

  // resolve(cloud), once per key: a file is resolved once for all its pairs, and each pair is charged
  // the time it took, as each `quadrix register` call would pay it.
  ResolvedSide options_of(const std::string& key, const PointCloud& cloud) {
    std::lock_guard<std::mutex> lock(preset_mutex);
    auto found = resolved.find(key);
    if (found == resolved.end()) found = resolved.emplace(key, resolve(cloud)).first;
    return found->second;
  }

  // RegistrationOptions as `quadrix register` builds them, then the ablation.
  RegistrationOptions options_for(const RegistrationOptions& source_side, const RegistrationOptions& target_side) const {
    RegistrationOptions registration = source_side;
    registration.target_extraction = target_side.target_extraction;
    if (!options->config.empty()) apply_registration_config(options->config, registration);
    if (!options->refiner.empty()) registration.estimation.refiner = options->refiner;
    apply_ablation(options->ablation, registration);
    return registration;
  }
};

// `unmoved_source` is the source before any perturbation (damaged when a corruption is set): the
// options are resolved on it, as `quadrix register` would resolve them on the file it is given.
BenchMethodOutput run_quadrix(RunContext& context, const BenchMethodInput& input, const PointCloud& unmoved_source,
                              std::uint64_t seed, BenchRow& row) {
  const BenchPair& pair = *input.pair;
  if (context.options->labels && (input.source->labels.empty() || input.target->labels.empty()))
    throw Error("pair '" + pair.id + "': --labels needs per-point labels for both clouds (pairs.tsv columns " +
                "source_labels / target_labels, or a label field in the cloud files)");
  const std::string& corruption = context.options->corruption;
  // A tilted source is resolved as given, tilted, for this trial only (auto measures its up axis, as
  // `quadrix register` would on a tilted scan); otherwise on the unmoved source, whose up axis the yaw
  // leaves alone, once per file (and damage).
  const bool tilted = context.options->tilt_range_degrees > 0.0;
  const std::string source_key = corruption.empty() ? pair.source : pair.source + "|" + corruption + "|" + std::to_string(seed);
  const RunContext::ResolvedSide source_side =
      tilted ? context.resolve(*input.source) : context.options_of(source_key, unmoved_source);
  const RunContext::ResolvedSide target_side = context.options_of(pair.target, *input.target);
  const RegistrationOptions registration = context.options_for(source_side.options, target_side.options);
  const bool perturbed = perturbs(*context.options);
  const bool labelled = context.options->labels;
  const std::vector<ElementClass>& label_classes = context.options->label_classes;
  const auto build = [&](const PointCloud& cloud, ExtractionOptions extraction, const ModellingOptions& modelling,
                         BuiltModel& built) {
    if (labelled) {
      extraction.semantic_mode = SemanticMode::Labels;
      extraction.label_classes = label_classes;
    }
    const Clock::time_point start = Clock::now();
    built.modelling = model_scene(cloud, extraction, modelling, labelled ? cloud.labels : std::vector<std::uint32_t>());
    built.modelling_ms = elapsed_ms(start);
  };
  // The perturbed sensor sits at the perturbation's origin with its up axis rotated: tell extraction.
  ExtractionOptions source_extraction = registration.source_extraction;
  if (perturbed) {
    source_extraction.sensor_origin = input.perturbation * source_extraction.sensor_origin;
    if (!tilted) source_extraction.up = input.perturbation.linear() * source_extraction.up;
  }
  // Both clouds are modelled for every task, at the same time, as register_clouds does, so the row's
  // times are those of `quadrix register` with both clouds in memory (no model is reused across pairs).
  BuiltModel source_model, target_model;
  tbb::parallel_invoke([&] { build(*input.source, source_extraction, registration.modelling, source_model); },
                       [&] { build(*input.target, registration.target_extraction, registration.modelling, target_model); });
  // The same pipeline as register_clouds from here on. A perturbed source's sensor sits at the
  // perturbation's origin: its range crop in the verification follows it.
  RegistrationOptions pipeline = registration;
  pipeline.source_extraction.sensor_origin = source_extraction.sensor_origin;
  pipeline.source_extraction.up = source_extraction.up;  // the ground agreement judges the turned scan's ground against it
  const std::string& ablation = context.options->ablation;
  const RegistrationResult result = register_modelled_clouds(
      {input.source, &source_model.modelling, source_model.modelling_ms, true},
      {input.target, &target_model.modelling, target_model.modelling_ms, true}, pipeline,
      [&ablation](const SceneModel& model) { return apply_model_ablation(ablation, model); });
  BenchMethodOutput output;
  output.transform = result.transform;
  output.status = registration_status_name(result.status);
  output.message = result.message;
  output.timings_ms = result.timings_ms;
  // `quadrix register` resolves both presets first, the two sides at the same time (auto measures
  // each cloud): the longer of the two.
  output.timings_ms["preset"] = std::max(source_side.milliseconds, target_side.milliseconds);
  output.timings_ms["total"] += output.timings_ms["preset"];
  // Bytes of the models as registered (after augmentation and any model-level ablation).
  row.source_model_bytes = static_cast<long long>(scene_model_to_binary(result.source_model).size());
  row.target_model_bytes = static_cast<long long>(scene_model_to_binary(result.target_model).size());
  row.correspondences = static_cast<long long>(result.counts.correspondences);
  if (result.overlap) {
    row.overlap = result.overlap->transformed;
    row.identity_overlap = result.overlap->identity;
  }
  if (pair.ground_truth) {
    const Eigen::Isometry3d truth = *pair.ground_truth * input.perturbation.inverse();
    const CorrespondenceSet set =
        establish_correspondences(result.source_model, result.target_model, registration.correspondences);
    const CorrespondenceQuality quality =
        evaluate_correspondences(result.source_model, result.target_model, set.correspondences, truth);
    row.inliers = static_cast<long long>(quality.inliers);
    row.recalled = quality.recalled ? 1 : 0;
    // Where the true quadric correspondences are lost: modelled in both scans, matched, kept in a
    // level's maximum clique, kept in the chosen candidate's clique (augmented points left out).
    row.true_partners = static_cast<long long>(count_true_partners(result.source_model, result.target_model, truth));
    std::vector<Correspondence> quadric_matches;
    std::copy_if(set.correspondences.begin(), set.correspondences.end(), std::back_inserter(quadric_matches),
                 [](const Correspondence& correspondence) { return !correspondence.augmented; });
    row.quadric_inliers = static_cast<long long>(
        evaluate_correspondences(result.source_model, result.target_model, quadric_matches, truth).inliers);
    const auto true_in_clique = [&](const RegistrationCandidate& candidate) {
      std::vector<Correspondence> clique;
      for (const RecordCorrespondence& pair_in_clique : candidate.clique) {
        if (pair_in_clique.source_index >= result.source_model.augmented_begin) continue;
        Correspondence correspondence;
        correspondence.source = static_cast<std::uint32_t>(pair_in_clique.source_index);
        correspondence.target = static_cast<std::uint32_t>(pair_in_clique.target_index);
        clique.push_back(correspondence);
      }
      return static_cast<long long>(evaluate_correspondences(result.source_model, result.target_model, clique, truth).inliers);
    };
    row.best_clique_inliers = 0;
    for (const RegistrationCandidate& candidate : result.candidates)
      row.best_clique_inliers = std::max(row.best_clique_inliers, true_in_clique(candidate));
    row.clique_inliers = result.candidates.empty() ? 0 : true_in_clique(result.candidates[result.best_candidate]);
  }
  return output;
}

BenchMethodOutput run_baseline_method(const std::string& method, const BenchMethodInput& input, const BaselineOptions& options) {
  const BaselineResult result = run_baseline_process(method, *input.source, *input.target, options);
  BenchMethodOutput output;
  output.transform = result.transform;
  output.status = result.solved ? "solved" : "unsolved";
  output.message = result.message;
  output.timings_ms = result.timings_ms;
  return output;
}

std::vector<BenchRow> run_task(RunContext& context, const Task& task) {
  const BenchOptions& options = *context.options;
  const BenchPair& pair = (*context.pairs)[task.pair];
  // With --labels, a cloud carries the pair's label file (else its own label field, checked in run_quadrix).
  const auto read = [&](const std::string& path, const std::string& labels) {
    PointCloud cloud = read_point_cloud(path);
    if (options.labels && !labels.empty()) cloud.labels = read_semantic_kitti_labels(labels, cloud.size());
    return cloud;
  };
  const std::shared_ptr<const PointCloud> source =
      context.clouds.get(pair.source, [&] { return read(pair.source, pair.source_labels); });
  const std::shared_ptr<const PointCloud> target =
      context.clouds.get(pair.target, [&] { return read(pair.target, pair.target_labels); });
  const std::uint64_t seed = options.seed * 1000003ULL + task.index;
  const Eigen::Isometry3d perturbation = perturbation_of(options, seed);
  const bool perturbed = perturbs(options);
  const Corruption corruption = parse_corruption(options.corruption);
  // The source is damaged in its own frame (the sensor at the origin), then moved.
  const PointCloud corrupted_source =
      corruption.kind == CorruptionKind::None ? PointCloud() : corrupt_cloud(*source, corruption, seed);
  const PointCloud& damaged_source = corruption.kind == CorruptionKind::None ? *source : corrupted_source;
  const PointCloud moved_source = perturbed ? transformed(damaged_source, perturbation) : PointCloud();
  BenchMethodInput input;
  input.pair = &pair;
  input.source = perturbed ? &moved_source : &damaged_source;
  input.target = target.get();
  input.perturbation = perturbation;

  std::vector<BenchRow> rows;
  for (const std::string& method : options.methods) {
    BenchRow row;
    row.task = task.index;
    row.pair_id = pair.id;
    row.trial = task.trial;
    row.method = method;
    row.difficulty = pair.difficulty;
    row.kind = pair.kind;
    row.has_ground_truth = pair.ground_truth.has_value();
    row.seed = seed;
    row.yaw_degrees = std::atan2(perturbation.linear()(1, 0), perturbation.linear()(0, 0)) * 180.0 / M_PI;
    row.tilt_degrees =
        std::acos(std::clamp((perturbation.linear() * Eigen::Vector3d::UnitZ()).z(), -1.0, 1.0)) * 180.0 / M_PI;
    row.shift_x = perturbation.translation().x();
    row.shift_y = perturbation.translation().y();
    BenchMethodOutput output;
    try {
      BenchMethod extra;
      {
        std::lock_guard<std::mutex> lock(extra_methods_mutex());
        const auto found = extra_methods().find(method);
        if (found != extra_methods().end()) extra = found->second;
      }
      if (extra) {
        output = extra(input);
      } else if (method == "quadrix") {
        output = run_quadrix(context, input, damaged_source, seed, row);
      } else {
        output = run_baseline_method(method, input, options.baseline);
      }
    } catch (const std::exception& error) {  // a method that throws on this pair fails it; the run goes on
      output.status = "error";
      output.message = error.what();
      output.transform = Eigen::Isometry3d::Identity();
    }
    row.status = output.status;
    row.message = output.message;
    row.timings_ms = output.timings_ms;
    if (pair.ground_truth) {
      const Eigen::Isometry3d truth = *pair.ground_truth * perturbation.inverse();  // maps the moved source into the target
      row.rte = translation_error(output.transform, truth);
      row.rre = rotation_error_degrees(output.transform, truth);
      row.success = output.status != "error" && registration_succeeded(output.transform, truth);
    }
    rows.push_back(std::move(row));
  }
  context.clouds.release(pair.source);
  context.clouds.release(pair.target);
  return rows;
}

void check_methods(const std::vector<std::string>& methods) {
  if (methods.empty()) throw Error("--method: no method given");
  const std::vector<std::string> baselines = baseline_method_names();
  for (const std::string& method : methods) {
    bool known = method == "quadrix" || std::find(baselines.begin(), baselines.end(), method) != baselines.end();
    {
      std::lock_guard<std::mutex> lock(extra_methods_mutex());
      known = known || extra_methods().count(method) > 0;
    }
    if (!known) {
      std::string names = "quadrix";
      for (const std::string& name : baselines) names += ", " + name;
      throw Error("--method: unknown method '" + method + "' (known: " + names + ")");
    }
  }
}

}  // namespace

std::vector<std::string> bench_ablation_names() {
  return {"no-semantics", "no-central",  "no-linear-center", "no-planar-center", "no-augmented-points",
          "ke30",         "ke40",        "ke60",             "ks15",             "ks25",
          "dm-0.2",       "dm-0.8",      "dm-0.2-0.8",       "dm-0.2-0.6-0.8",   "dm-0.2-0.4-0.6-0.8-1.0",
          "no-er",        "no-et",       "no-augmented-factors", "no-refinement"};
}

std::string bench_ablation_paper_row(const std::string& name) {
  static const std::map<std::string, std::string> rows{
      {"", "default|Default"},
      {"default", "default|Default"},
      {"no-semantics", "representation|W/O semantics-aided"},
      {"no-central", "representation|W/O central quadrics"},
      {"no-linear-center", "representation|W/O linear-center quadrics"},
      {"no-planar-center", "representation|W/O planar-center quadrics"},
      {"no-augmented-points", "representation|W/O augmented points"},
      {"ke30", "representation|K_e=30"},
      {"ke40", "representation|K_e=40"},
      {"ke60", "representation|K_e=60"},
      {"ks15", "correspondence establishment|K_s=15"},
      {"ks25", "correspondence establishment|K_s=25"},
      {"dm-0.2", "correspondence establishment|delta_m: [0.2]"},
      {"dm-0.8", "correspondence establishment|delta_m: [0.8]"},
      {"dm-0.2-0.8", "correspondence establishment|delta_m: [0.2,0.8]"},
      {"dm-0.2-0.6-0.8", "correspondence establishment|delta_m: [0.2,0.6,0.8]"},
      {"dm-0.2-0.4-0.6-0.8-1.0", "correspondence establishment|delta_m: [0.2,0.4,0.6,0.8,1.0]"},
      {"no-er", "transformation estimation|W/O e_R"},
      {"no-et", "transformation estimation|W/O e_t"},
      {"no-augmented-factors", "transformation estimation|W/O augmented points"},
      {"no-refinement", "transformation estimation|W/O trans. refinement"}};
  const auto found = rows.find(name);
  if (found == rows.end()) {
    RegistrationOptions probe;
    apply_ablation(name, probe);  // throws the error listing the names
  }
  return found->second;
}

void apply_ablation(const std::string& name, RegistrationOptions& options) {
  if (name.empty() || name == "default") return;
  const std::vector<std::string> names = bench_ablation_names();
  if (std::find(names.begin(), names.end(), name) == names.end()) {
    std::string known;
    for (const std::string& entry : names) known += (known.empty() ? "" : ", ") + entry;
    throw Error("--ablation: unknown ablation '" + name + "' (known: " + known + ")");
  }
  if (name == "no-augmented-points") options.modelling.augmentation_threshold = 0;  // never augment (delta_a = 0)
  if (name == "ke30") options.modelling.quadrics_per_class = 30;
  if (name == "ke40") options.modelling.quadrics_per_class = 40;
  if (name == "ke60") options.modelling.quadrics_per_class = 60;
  if (name == "ks15") options.correspondences.top_k_similar = 15;
  if (name == "ks25") options.correspondences.top_k_similar = 25;
  if (name == "dm-0.2") options.graphs.thresholds = {0.2};
  if (name == "dm-0.8") options.graphs.thresholds = {0.8};
  if (name == "dm-0.2-0.8") options.graphs.thresholds = {0.2, 0.8};
  if (name == "dm-0.2-0.6-0.8") options.graphs.thresholds = {0.2, 0.6, 0.8};
  if (name == "dm-0.2-0.4-0.6-0.8-1.0") options.graphs.thresholds = {0.2, 0.4, 0.6, 0.8, 1.0};
  if (name == "no-er") options.estimation.use_rotation_error = false;
  if (name == "no-et") options.estimation.use_translation_error = false;
  if (name == "no-augmented-factors") options.estimation.augment_non_central = false;
  if (name == "no-refinement") options.estimation.refine = false;
}

SceneModel apply_model_ablation(const std::string& name, const SceneModel& model) {
  if (name == "no-central") return drop_fitted_records(model, 3);
  if (name == "no-linear-center") return drop_fitted_records(model, 2);
  if (name == "no-planar-center") return drop_fitted_records(model, 1);
  if (name == "no-semantics") {
    SceneModel unlabelled = model;
    for (QuadricRecord& record : unlabelled.records) record.label = static_cast<std::uint32_t>(ElementClass::Object);
    return unlabelled;
  }
  return model;
}

void register_bench_method(const std::string& name, BenchMethod method) {
  std::lock_guard<std::mutex> lock(extra_methods_mutex());
  extra_methods()[name] = std::move(method);
}

std::vector<BenchRow> run_benchmark(const std::vector<BenchPair>& pairs, const BenchOptions& options,
                                    const BenchProgress& progress) {
  check_methods(options.methods);
  if (options.trials < 1) throw Error("--trials must be at least 1, got " + std::to_string(options.trials));
  if (options.shard_count < 1 || options.shard_index < 1 || options.shard_index > options.shard_count)
    throw Error("--shard " + std::to_string(options.shard_index) + "/" + std::to_string(options.shard_count) +
                ": expected i/n with 1 <= i <= n");
  if (options.jobs < 1) throw Error("--jobs must be at least 1, got " + std::to_string(options.jobs));
  if (!(options.tilt_range_degrees >= 0.0 && options.tilt_range_degrees <= 90.0))
    throw Error("--tilt must be an angle in [0, 90] degrees, got " + std::to_string(options.tilt_range_degrees));
  if (options.preset != "auto") registration_preset(options.preset);  // unknown names are an Error listing them
  if (!options.config.empty()) {
    RegistrationOptions probe;
    apply_registration_config(options.config, probe);  // bad files fail before any work
  }
  if (!options.refiner.empty()) make_refiner(options.refiner);
  parse_corruption(options.corruption);  // an unknown name is an Error listing the forms
  RegistrationOptions probe;
  apply_ablation(options.ablation, probe);

  RunContext context;
  context.pairs = &pairs;
  context.options = &options;
  std::vector<Task> tasks;
  for (std::size_t p = 0; p < pairs.size(); ++p)
    for (int trial = 0; trial < options.trials; ++trial) {
      const std::size_t index = p * static_cast<std::size_t>(options.trials) + static_cast<std::size_t>(trial);
      if (index % static_cast<std::size_t>(options.shard_count) != static_cast<std::size_t>(options.shard_index - 1)) continue;
      tasks.push_back(Task{index, p, trial});
      context.clouds.expect(pairs[p].source);
      context.clouds.expect(pairs[p].target);
    }

  std::vector<std::vector<BenchRow>> results(tasks.size());
  std::vector<BenchRow> finished;
  std::mutex finished_mutex;
  std::atomic<std::size_t> next{0};
  std::exception_ptr failure;
  const auto worker = [&] {
    while (true) {
      const std::size_t k = next.fetch_add(1);
      if (k >= tasks.size()) return;
      {
        std::lock_guard<std::mutex> lock(finished_mutex);
        if (failure) return;
      }
      try {
        results[k] = run_task(context, tasks[k]);
        std::lock_guard<std::mutex> lock(finished_mutex);
        finished.insert(finished.end(), results[k].begin(), results[k].end());
        if (progress) progress(finished.size() / options.methods.size(), tasks.size(), finished);
      } catch (...) {
        std::lock_guard<std::mutex> lock(finished_mutex);
        if (!failure) failure = std::current_exception();
        return;
      }
    }
  };
  const int threads = std::min<int>(options.jobs, static_cast<int>(std::max<std::size_t>(tasks.size(), 1)));
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& thread : pool) thread.join();
  if (failure) std::rethrow_exception(failure);
  std::vector<BenchRow> rows;
  for (std::vector<BenchRow>& task_rows : results)
    for (BenchRow& row : task_rows) rows.push_back(std::move(row));
  return rows;
}

}  // namespace quadrix
