// The refiner study (see refiner_study.h): synthetic problems from the monument and street ground
// truth, real problems from the KITTI loop closures, every configuration refined from the same
// perturbed starts and from the ground truth (the reference), and the CSV / Markdown / SVG writers.
#include "experiments/studies/refiner_study.h"

#include "estimation/refiner.h"
#include "estimation/registration.h"
#include "estimation/registration_config.h"
#include "experiments/studies/study_report.h"
#include "experiments/synthetic/synthetic_scene.h"
#include "fitting/scene_modelling.h"
#include "geometry/constants.h"
#include "geometry/error.h"
#include "geometry/io.h"
#include "matching/max_clique.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <numeric>
#include <ostream>
#include <set>
#include <sstream>

#include <time.h>

namespace quadrix {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInlierDistance = 0.5;  // correspondence inlier under the ground truth (paper: 0.5 m)

/// A fixed set of factors with its ground truth, refined by every configuration from the same starts.
struct Problem {
  std::string source;                 // scene name or pair id
  std::string correspondence_set;     // "synthetic", "gt_inliers", "clique"
  double noise = 0.0;                 // synthetic centre sigma
  double outlier_fraction = 0.0;      // asked for (synthetic) or measured (real)
  bool exact = false;                 // noise-free synthetic without wrong correspondences: criterion = truth
  int first_trial = 0;                // trial index of starts[0]
  std::size_t correspondences = 0;
  std::size_t wrong_correspondences = 0;
  std::vector<QuadricFactor> factors;
  Eigen::Isometry3d truth = Eigen::Isometry3d::Identity();
  std::vector<Eigen::Isometry3d> starts;
};

Eigen::Vector3d unit_vector(PortableRandom& random) {
  Eigen::Vector3d v(random.normal(0.0, 1.0), random.normal(0.0, 1.0), random.normal(0.0, 1.0));
  while (v.norm() < 1e-9) v = Eigen::Vector3d(random.normal(0.0, 1.0), random.normal(0.0, 1.0), random.normal(0.0, 1.0));
  return v.normalized();
}

/// A start whose RTE and RRE against `truth` are exactly the drawn magnitudes (default 0.5-5 m, 2-20 deg).
Eigen::Isometry3d perturbed_start(const Eigen::Isometry3d& truth, const RefinerStudyOptions& options, PortableRandom& random) {
  const double translation = random.uniform(options.minimum_translation, options.maximum_translation);
  const double angle = random.uniform(options.minimum_rotation_degrees, options.maximum_rotation_degrees) * kPi / 180.0;
  const Eigen::Vector3d direction = unit_vector(random);
  const Eigen::Vector3d axis = unit_vector(random);
  Eigen::Isometry3d start = truth;
  start.linear() = Eigen::AngleAxisd(angle, axis).toRotationMatrix() * truth.linear();
  start.translation() = truth.translation() + translation * direction;
  return start;
}

/// A rigid motion of `angle_sigma` radians (per axis) about `anchor` plus `shift_sigma` metres (per axis).
Eigen::Isometry3d jitter_about(const Eigen::Vector3d& anchor, const Eigen::Vector3d& rotation_draw,
                               const Eigen::Vector3d& shift_draw, double angle_sigma, double shift_sigma) {
  Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d axis_angle = angle_sigma * rotation_draw;
  if (axis_angle.norm() > 0.0) motion.linear() = Eigen::AngleAxisd(axis_angle.norm(), axis_angle.normalized()).toRotationMatrix();
  motion.translation() = anchor - motion.linear() * anchor + shift_sigma * shift_draw;
  return motion;
}

/// A scene's primitives with their statistical poses, computed once (ground_truth_record's sampling).
struct SceneTruth {
  Scene scene;
  std::vector<StatisticalPose> statistics;
};

SceneTruth scene_truth(const std::string& name) {
  SceneTruth truth;
  truth.scene = make_scene(name, 1);
  for (const ScenePrimitive& primitive : truth.scene.primitives) {
    const double area = std::max(primitive_surface_area(primitive), 1e-6);
    truth.statistics.push_back(statistical_pose(sample_primitive_surface(primitive, std::sqrt(area / 4000.0))));
  }
  return truth;
}

/// The seed of one scene and trial: the base seed mixed with a hash of the scene's name and the trial.
std::uint64_t synthetic_problem_seed(const std::string& name, int trial, const RefinerStudyOptions& options) {
  std::uint64_t scene_hash = 1469598103934665603ULL;
  for (const char c : name) scene_hash = (scene_hash ^ static_cast<unsigned char>(c)) * 1099511628211ULL;
  return mix_bits(options.seed ^ scene_hash ^ (static_cast<std::uint64_t>(trial) << 40));
}

/// A ground-truth pose of the kind a loop closure has: any heading, a slight tilt, tens of metres of translation.
Eigen::Isometry3d draw_truth_pose(PortableRandom& random) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = (Eigen::AngleAxisd(random.uniform(0.0, 2.0 * kPi), Eigen::Vector3d::UnitZ()) *
                   Eigen::AngleAxisd(random.uniform(-3.0, 3.0) * kPi / 180.0, Eigen::Vector3d::UnitX()) *
                   Eigen::AngleAxisd(random.uniform(-3.0, 3.0) * kPi / 180.0, Eigen::Vector3d::UnitY()))
                      .toRotationMatrix();
  pose.translation() = Eigen::Vector3d(random.uniform(-20.0, 20.0), random.uniform(-20.0, 20.0), random.uniform(-1.0, 1.0));
  return pose;
}

/// The primitives used as elements, in scene order: all, or a random `cap` of them so problems stay small.
std::vector<std::size_t> choose_elements(std::size_t primitive_count, std::size_t cap, PortableRandom& random) {
  std::vector<std::size_t> chosen(primitive_count);
  std::iota(chosen.begin(), chosen.end(), std::size_t{0});
  if (chosen.size() > cap) {
    for (std::size_t i = chosen.size() - 1; i > 0; --i)
      std::swap(chosen[i], chosen[static_cast<std::size_t>(random.uniform_integer(0, static_cast<int>(i)))]);
    chosen.resize(cap);
    std::sort(chosen.begin(), chosen.end());
  }
  return chosen;
}

/// Per-element draws that every noise level and outlier fraction of a trial share (common random numbers).
struct ElementDraws {
  std::vector<Eigen::Vector3d> rotation, shift;  // unit-variance noise directions
  std::vector<double> scale;                     // unit-variance scale noise
  std::vector<std::size_t> wrong_order;          // the order in which correspondences turn wrong
  std::vector<std::size_t> wrong_partner;        // each element's wrong target
};

/// Each element's wrong partner: one of the same semantic label when there is one (plausible mistakes), else any.
std::vector<std::size_t> draw_wrong_partners(const std::vector<ScenePrimitive>& primitives, const std::vector<std::size_t>& chosen,
                                             PortableRandom& random) {
  const std::size_t count = chosen.size();
  std::vector<std::size_t> wrong_partner(count);
  for (std::size_t k = 0; k < count; ++k) {
    std::vector<std::size_t> same_label;
    for (std::size_t j = 0; j < count; ++j)
      if (j != k && primitives[chosen[j]].label == primitives[chosen[k]].label) same_label.push_back(j);
    if (!same_label.empty()) {
      wrong_partner[k] = same_label[static_cast<std::size_t>(random.uniform_integer(0, static_cast<int>(same_label.size()) - 1))];
    } else {
      const auto other = static_cast<std::size_t>(random.uniform_integer(0, static_cast<int>(count) - 2));
      wrong_partner[k] = other >= k ? other + 1 : other;
    }
  }
  return wrong_partner;
}

/// Draws noise, then the order correspondences turn wrong, then wrong partners: the seeded rows rely on this order.
ElementDraws draw_elements(const std::vector<ScenePrimitive>& primitives, const std::vector<std::size_t>& chosen,
                           PortableRandom& random) {
  const std::size_t count = chosen.size();
  ElementDraws draws;
  draws.rotation.resize(count);
  draws.shift.resize(count);
  draws.scale.resize(count);
  for (std::size_t k = 0; k < count; ++k) {
    draws.rotation[k] = Eigen::Vector3d(random.normal(0.0, 1.0), random.normal(0.0, 1.0), random.normal(0.0, 1.0));
    draws.shift[k] = Eigen::Vector3d(random.normal(0.0, 1.0), random.normal(0.0, 1.0), random.normal(0.0, 1.0));
    draws.scale[k] = random.normal(0.0, 1.0);
  }
  draws.wrong_order.resize(count);
  std::iota(draws.wrong_order.begin(), draws.wrong_order.end(), std::size_t{0});
  for (std::size_t i = count - 1; i > 0; --i)
    std::swap(draws.wrong_order[i], draws.wrong_order[static_cast<std::size_t>(random.uniform_integer(0, static_cast<int>(i)))]);
  draws.wrong_partner = draw_wrong_partners(primitives, chosen, random);
  return draws;
}

/// Target records at one noise level: each primitive moved by the pose, jittered about its centre and scaled.
std::vector<QuadricRecord> noisy_target_records(const SceneTruth& truth, const std::vector<std::size_t>& chosen,
                                                const Eigen::Isometry3d& pose, const ElementDraws& draws,
                                                const AttributeNoise& noise) {
  std::vector<QuadricRecord> target;
  for (std::size_t k = 0; k < chosen.size(); ++k) {
    const ScenePrimitive& primitive = truth.scene.primitives[chosen[k]];
    const Eigen::Isometry3d jitter = jitter_about(pose * primitive.pose.translation(), draws.rotation[k], draws.shift[k],
                                                  noise.axis_degrees * kPi / 180.0, noise.centre);
    const Eigen::Isometry3d motion = jitter * pose;
    const double scale_factor = std::max(0.2, 1.0 + noise.scale * draws.scale[k]);
    ScenePrimitive moved = primitive;
    moved.pose = motion * primitive.pose;
    moved.scale = primitive.scale * scale_factor;
    StatisticalPose statistics = truth.statistics[chosen[k]];
    statistics.scale *= scale_factor;
    statistics.rotation = motion.linear() * statistics.rotation;
    statistics.center = motion * statistics.center;
    target.push_back(make_quadric_record(static_cast<std::uint32_t>(primitive.label), model_quadric(moved), statistics));
  }
  return target;
}

/// Correspondences k -> k, the first `wrong` of the wrong order sent to their partners (nested wrong sets).
std::vector<RecordCorrespondence> synthetic_correspondences(std::size_t count, std::size_t wrong, const ElementDraws& draws) {
  std::vector<RecordCorrespondence> pairs(count);
  for (std::size_t k = 0; k < count; ++k) pairs[k] = {k, k};
  for (std::size_t w = 0; w < wrong; ++w) pairs[draws.wrong_order[w]].target_index = draws.wrong_partner[draws.wrong_order[w]];
  return pairs;
}

/// The synthetic problems of one scene and trial: every noise level x outlier fraction shares the
/// truth pose, the element subset, the noise draws, the wrong partners and the start (common random numbers).
std::vector<Problem> synthetic_problems(const std::string& name, const SceneTruth& truth, int trial,
                                        const RefinerStudyOptions& options) {
  PortableRandom random(synthetic_problem_seed(name, trial, options));
  const std::vector<ScenePrimitive>& primitives = truth.scene.primitives;
  const Eigen::Isometry3d pose = draw_truth_pose(random);
  const std::vector<std::size_t> chosen = choose_elements(primitives.size(), options.max_synthetic_elements, random);
  const std::size_t count = chosen.size();
  const ElementDraws draws = draw_elements(primitives, chosen, random);
  const Eigen::Isometry3d start = perturbed_start(pose, options, random);

  std::vector<QuadricRecord> source;
  for (const std::size_t index : chosen)
    source.push_back(make_quadric_record(static_cast<std::uint32_t>(primitives[index].label), model_quadric(primitives[index]),
                                         truth.statistics[index]));
  const std::vector<QuadricDecomposition> source_shapes = decompose_records(source);
  FactorBuildOptions factor_options;
  factor_options.augment_non_central = options.augment_non_central;

  std::vector<Problem> problems;
  for (const AttributeNoise& noise : options.noise_levels) {
    const std::vector<QuadricRecord> target = noisy_target_records(truth, chosen, pose, draws, noise);
    const std::vector<QuadricDecomposition> target_shapes = decompose_records(target);
    for (const double fraction : options.outlier_fractions) {
      const auto wrong = static_cast<std::size_t>(std::llround(fraction * static_cast<double>(count)));
      const std::vector<RecordCorrespondence> pairs = synthetic_correspondences(count, wrong, draws);
      Problem problem;
      problem.source = name;
      problem.correspondence_set = "synthetic";
      problem.noise = noise.centre;
      problem.outlier_fraction = fraction;
      problem.exact = noise.centre == 0.0 && noise.axis_degrees == 0.0 && noise.scale == 0.0 && wrong == 0;
      problem.first_trial = trial;
      problem.correspondences = count;
      problem.wrong_correspondences = wrong;
      problem.factors = build_quadric_factors(source, source_shapes, target, target_shapes, pairs, factor_options).factors;
      problem.truth = pose;
      problem.starts = {start};
      problems.push_back(std::move(problem));
    }
  }
  return problems;
}

// ---- Real pairs ----------------------------------------------------------------------------------

/// One row of pairs.tsv.
struct PairRow {
  std::string id, source, target, ground_truth, quality, kind;
};

std::vector<PairRow> read_pairs_table(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot open the pairs table");
  std::vector<PairRow> rows;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (number == 1 || line.empty() || line[0] == '#') continue;  // header
    std::vector<std::string> fields;
    std::stringstream stream(line);
    for (std::string field; std::getline(stream, field, '\t');) fields.push_back(field);
    if (fields.size() < 7)
      throw Error(path + ":" + std::to_string(number) + ": expected 9 tab-separated columns (id source target gt gt_quality "
                  "sensor kind t_m rot_deg), got " + std::to_string(fields.size()));
    rows.push_back({fields[0], fields[1], fields[2], fields[3], fields[4], fields[6]});
  }
  return rows;
}

/// The real problems of one loop-closure pair: its ground-truth inliers and the pipeline's clique.
std::vector<Problem> real_problems(const PairRow& pair, std::size_t pair_index, const RegistrationOptions& registration,
                                   std::map<std::string, SceneModel>& models, const RefinerStudyOptions& options,
                                   std::vector<std::string>& notes) {
  const std::filesystem::path root(options.data_root);
  for (const std::string* file : {&pair.source, &pair.target, &pair.ground_truth})
    if (!std::filesystem::exists(root / *file)) {
      notes.push_back(pair.id + ": skipped, " + (root / *file).string() + " is absent");
      return {};
    }
  for (const std::string* file : {&pair.source, &pair.target})
    if (!models.count(*file))
      models[*file] = model_scene(read_point_cloud((root / *file).string()), registration.source_extraction, registration.modelling).model;
  const SceneModel& source = models.at(pair.source);
  const SceneModel& target = models.at(pair.target);
  const Eigen::Isometry3d truth = read_pose_matrix((root / pair.ground_truth).string());

  const CorrespondenceSet putative = establish_correspondences(source, target, registration.correspondences);
  std::vector<RecordCorrespondence> inliers;
  const auto is_inlier = [&](const RecordCorrespondence& c) {
    return (truth * source.records[c.source_index].full_center - target.records[c.target_index].full_center).norm() <= kInlierDistance;
  };
  for (const Correspondence& c : putative.correspondences) {
    const RecordCorrespondence pair_of_records{c.source, c.target};
    if (is_inlier(pair_of_records)) inliers.push_back(pair_of_records);
  }

  // The clique of the level register_models selects (same options, so the same graphs and cliques).
  const RegistrationResult registered = register_models(source, target, registration);
  std::vector<RecordCorrespondence> clique_pairs;
  std::string clique_note;
  if (registered.status == RegistrationStatus::Ok || registered.status == RegistrationStatus::Ambiguous) {
    const CompatibilityGraphs graphs = build_compatibility_graphs(putative.source_centers(source), putative.target_centers(target),
                                                                  registration.graphs);
    MaxCliqueOptions clique_options;
    clique_options.thread_count = 1;
    const GraduatedCliqueResult cliques = find_graduated_maximum_cliques(graphs.levels, clique_options);
    const std::size_t level = registered.candidates[registered.best_candidate].level;
    for (const int vertex : cliques.levels[level].clique) {
      const Correspondence& c = putative.correspondences[static_cast<std::size_t>(vertex)];
      clique_pairs.push_back({c.source, c.target});
    }
    clique_note = "clique of level " + std::to_string(level) + " (delta_m " + report::fixed(graphs.thresholds[level], 1) +
                  " m, chosen by the pipeline, registration " + registration_status_name(registered.status) + ")";
  } else {
    clique_note = std::string("no clique set: registration ") + registration_status_name(registered.status) + " (" +
                  registered.message + ")";
  }

  const FactorBuildOptions factor_options = estimation_factor_options(source, target, registration.estimation,
                                                                          grounds_level(source, target, registration));
  const std::vector<QuadricDecomposition> source_shapes = decompose_records(source.records);
  const std::vector<QuadricDecomposition> target_shapes = decompose_records(target.records);

  std::vector<Problem> problems;
  const auto add = [&](const std::string& set, const std::vector<RecordCorrespondence>& pairs) {
    Problem problem;
    problem.source = pair.id;
    problem.correspondence_set = set;
    problem.correspondences = pairs.size();
    problem.wrong_correspondences = static_cast<std::size_t>(
        std::count_if(pairs.begin(), pairs.end(), [&](const RecordCorrespondence& c) { return !is_inlier(c); }));
    problem.outlier_fraction =
        pairs.empty() ? 0.0 : static_cast<double>(problem.wrong_correspondences) / static_cast<double>(pairs.size());
    problem.factors = build_quadric_factors(source.records, source_shapes, target.records, target_shapes, pairs, factor_options).factors;
    problem.truth = truth;
    PortableRandom random(mix_bits(options.seed ^ 0x7265616cULL ^ (static_cast<std::uint64_t>(pair_index) << 32)));
    for (int trial = 0; trial < options.trials; ++trial) problem.starts.push_back(perturbed_start(truth, options, random));
    problems.push_back(std::move(problem));
  };
  if (inliers.size() >= 3) add("gt_inliers", inliers);
  const std::size_t clique_wrong = static_cast<std::size_t>(
      std::count_if(clique_pairs.begin(), clique_pairs.end(), [&](const RecordCorrespondence& c) { return !is_inlier(c); }));
  if (clique_pairs.size() >= 3) add("clique", clique_pairs);
  std::ostringstream note;
  note << pair.id << ": " << source.size() << " source / " << target.size() << " target records, " << putative.correspondences.size()
       << " putative correspondences, " << inliers.size() << " within " << kInlierDistance << " m under the ground truth; "
       << clique_note << ", " << clique_pairs.size() << " correspondences";
  if (!clique_pairs.empty()) note << " of which " << clique_wrong << " farther than " << kInlierDistance << " m";
  notes.push_back(note.str());
  return problems;
}

/// CPU time consumed by the calling thread, milliseconds.
double thread_cpu_ms() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return 1e3 * static_cast<double>(now.tv_sec) + 1e-6 * static_cast<double>(now.tv_nsec);
}

/// Pose gap (metres, degrees) between two poses.
std::pair<double, double> pose_gap(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& reference) {
  return {translation_error(estimate, reference), rotation_error_degrees(estimate, reference)};
}

}  // namespace

std::vector<std::string> refiner_study_algorithms(const std::string& backend) {
  if (backend == "ceres") return {"levenberg_marquardt", "dogleg"};
  if (backend == "nlopt") return {"lbfgs", "slsqp", "bobyqa"};
  return {""};
}

std::vector<RefinerConfiguration> refiner_study_configurations(const std::vector<std::string>& backends,
                                                              const std::vector<RobustLoss>& losses) {
  const std::vector<std::string> names = backends.empty() ? refiner_names() : backends;
  std::vector<RefinerConfiguration> configurations;
  for (const std::string& backend : names) {
    make_refiner(backend);  // unknown names are an Error listing the known ones
    for (const std::string& algorithm : refiner_study_algorithms(backend))
      for (const RobustLoss loss : losses) configurations.push_back({backend, algorithm, loss});
  }
  return configurations;
}

std::string refiner_configuration_name(const RefinerConfiguration& configuration) {
  return configuration.algorithm.empty() ? configuration.backend : configuration.backend + "/" + configuration.algorithm;
}

namespace {

// Throws quadrix::Error naming the option when `options` cannot run.
void validate_refiner_study_options(const RefinerStudyOptions& options) {
  if (options.losses.empty()) throw Error("refiner study: at least one robust loss is needed");
  const std::vector<std::string> known_scenes = scene_names();
  for (const std::string& scene : options.scenes)
    if (std::find(known_scenes.begin(), known_scenes.end(), scene) == known_scenes.end())
      throw Error("--scenes: unknown scene '" + scene + "' (known: monument, street, corridor)");
  for (const double fraction : options.outlier_fractions)
    if (!(fraction >= 0.0 && fraction < 1.0)) throw Error("--outlier-fractions: values must be in [0, 1), got " + std::to_string(fraction));
  for (const AttributeNoise& noise : options.noise_levels)
    if (!(noise.centre >= 0.0 && noise.axis_degrees >= 0.0 && noise.scale >= 0.0 && noise.scale < 1.0))
      throw Error("--noise: noise levels must be >= 0 (relative scale noise < 1)");
  if (options.trials < 1) throw Error("--trials must be >= 1, got " + std::to_string(options.trials));
  if (options.threads < 1) throw Error("--threads must be >= 1, got " + std::to_string(options.threads));
  if (!(options.minimum_translation >= 0.0 && options.maximum_translation >= options.minimum_translation &&
        options.minimum_rotation_degrees >= 0.0 && options.maximum_rotation_degrees >= options.minimum_rotation_degrees &&
        options.maximum_rotation_degrees < 180.0))
    throw Error("refiner study: perturbation ranges must satisfy 0 <= min <= max (rotation below 180 degrees)");
  if (!(options.loss_scale > 0.0)) throw Error("refiner study: loss_scale must be > 0");
  if (options.max_synthetic_elements < 3) throw Error("refiner study: max_synthetic_elements must be >= 3");
}

// Every problem of the study: the synthetic scenes' trials, then the shared KITTI loop closures
// (exact ground truth) when options.real_data and pairs.tsv is there (a note says when it is not).
std::vector<Problem> refiner_study_problems(const RefinerStudyOptions& options, std::vector<std::string>& notes) {
  std::vector<Problem> problems;
  for (const std::string& scene : options.scenes) {
    const SceneTruth truth = scene_truth(scene);
    for (int trial = 0; trial < options.trials; ++trial)
      for (Problem& problem : synthetic_problems(scene, truth, trial, options)) problems.push_back(std::move(problem));
  }
  if (!options.real_data) return problems;
  const std::filesystem::path table = std::filesystem::path(options.data_root) / "pairs.tsv";
  if (!std::filesystem::exists(table)) {
    notes.push_back("real pairs skipped: " + table.string() + " is absent");
    return problems;
  }
  const RegistrationOptions registration = registration_preset(options.real_preset);
  std::map<std::string, SceneModel> models;
  std::size_t used = 0;
  const std::vector<PairRow> rows = read_pairs_table(table.string());
  for (std::size_t index = 0; index < rows.size(); ++index) {
    const PairRow& pair = rows[index];
    if (pair.kind != "loop_closure" || pair.quality != "exact" || pair.id.rfind("kitti", 0) != 0) continue;
    if (options.max_real_pairs > 0 && used >= options.max_real_pairs) break;
    ++used;
    for (Problem& problem : real_problems(pair, index, registration, models, options, notes)) problems.push_back(std::move(problem));
  }
  return problems;
}

// One row: `configuration` refined from start `s` of `problem`, judged against the truth (exact
// problems) or against `reference`, the same configuration started at the ground truth.
RefinerStudyRow refine_from_start(const Problem& problem, std::size_t s, const RefinerConfiguration& configuration,
                                  Refiner& refiner, const RefinerOptions& refiner_options,
                                  const RefinementResult& reference, const RefinerStudyOptions& options) {
  const auto [reference_rte, reference_rre] = pose_gap(reference.transform, problem.truth);
  const double cpu_before = thread_cpu_ms();
  const RefinementResult refined = refiner.refine(problem.factors, problem.starts[s], refiner_options);
  const double cpu_after = thread_cpu_ms();
  RefinerStudyRow row;
  row.source = problem.source;
  row.correspondence_set = problem.correspondence_set;
  row.backend = configuration.backend;
  row.algorithm = refined.algorithm;
  row.loss = robust_loss_name(configuration.loss);
  row.noise = problem.noise;
  row.outlier_fraction = problem.outlier_fraction;
  row.trial = problem.first_trial + static_cast<int>(s);
  std::tie(row.start_translation, row.start_rotation_degrees) = pose_gap(problem.starts[s], problem.truth);
  row.correspondences = problem.correspondences;
  row.wrong_correspondences = problem.wrong_correspondences;
  row.factors = problem.factors.size();
  row.status = refinement_status_name(refined.status);
  std::tie(row.rte, row.rre_degrees) = pose_gap(refined.transform, problem.truth);
  row.criterion = problem.exact ? "truth" : "reference";
  row.reference_rte = reference_rte;
  row.reference_rre_degrees = reference_rre;
  std::tie(row.gap_translation, row.gap_rotation_degrees) =
      problem.exact ? std::make_pair(row.rte, row.rre_degrees) : pose_gap(refined.transform, reference.transform);
  row.converged = refined.status != RefinementStatus::Failed && refined.status != RefinementStatus::Degenerate &&
                  row.gap_translation < options.converged_translation &&
                  row.gap_rotation_degrees < options.converged_rotation_degrees;
  row.iterations = refined.iterations;
  row.evaluations = refined.evaluations;
  row.initial_cost = refined.initial_cost;
  row.final_cost = refined.final_cost;
  row.time_ms = 1000.0 * refined.seconds;
  row.cpu_ms = cpu_after - cpu_before;
  return row;
}

}  // namespace

RefinerStudyResult run_refiner_study(const RefinerStudyOptions& options, const RefinerStudyProgress& progress) {
  const auto start_time = std::chrono::steady_clock::now();
  RefinerStudyResult result;
  validate_refiner_study_options(options);
  result.configurations = refiner_study_configurations(options.backends, options.losses);
  const std::vector<Problem> problems = refiner_study_problems(options, result.notes);

  // Fixed row slots: problem-major, then configuration, then start.
  const std::size_t configurations = result.configurations.size();
  std::vector<std::size_t> offsets(problems.size() + 1, 0);
  for (std::size_t p = 0; p < problems.size(); ++p) offsets[p + 1] = offsets[p] + configurations * problems[p].starts.size();
  const std::size_t total = offsets.back();
  result.rows.resize(total);
  std::atomic<std::size_t> done{0};
  std::mutex progress_mutex;
  tbb::task_arena arena(options.threads);
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, problems.size() * configurations, 1), [&](const tbb::blocked_range<std::size_t>& range) {
      for (std::size_t task = range.begin(); task != range.end(); ++task) {
        const Problem& problem = problems[task / configurations];
        const std::size_t c = task % configurations;
        const RefinerConfiguration& configuration = result.configurations[c];
        const auto refiner = make_refiner(configuration.backend);
        RefinerOptions refiner_options;
        refiner_options.algorithm = configuration.algorithm;
        refiner_options.loss = configuration.loss;
        refiner_options.loss_scale = options.loss_scale;
        const RefinementResult reference = refiner->refine(problem.factors, problem.truth, refiner_options);
        for (std::size_t s = 0; s < problem.starts.size(); ++s)
          result.rows[offsets[task / configurations] + c * problem.starts.size() + s] =
              refine_from_start(problem, s, configuration, *refiner, refiner_options, reference, options);
        const std::size_t now = done.fetch_add(problem.starts.size()) + problem.starts.size();
        if (progress) {
          std::lock_guard<std::mutex> lock(progress_mutex);
          progress(now, total);
        }
      }
    });
  });
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
  return result;
}

// ---- Writers -------------------------------------------------------------------------------------

namespace {

using namespace report;  // number, fixed, median, percentile of the shared study helpers

using RowFilter = std::function<bool(const RefinerStudyRow&)>;

std::vector<const RefinerStudyRow*> rows_where(const RefinerStudyResult& result, const RowFilter& keep) {
  std::vector<const RefinerStudyRow*> rows;
  for (const RefinerStudyRow& row : result.rows)
    if (keep(row)) rows.push_back(&row);
  return rows;
}

bool same_configuration(const RefinerStudyRow& row, const RefinerConfiguration& configuration) {
  return row.backend == configuration.backend && (configuration.algorithm.empty() || row.algorithm == configuration.algorithm) &&
         row.loss == robust_loss_name(configuration.loss);
}

double convergence_percent(const std::vector<const RefinerStudyRow*>& rows) {
  if (rows.empty()) return kNaN;
  const auto converged = std::count_if(rows.begin(), rows.end(), [](const RefinerStudyRow* r) { return r->converged; });
  return 100.0 * static_cast<double>(converged) / static_cast<double>(rows.size());
}

std::vector<double> column(const std::vector<const RefinerStudyRow*>& rows, double RefinerStudyRow::*field) {
  std::vector<double> values;
  for (const RefinerStudyRow* row : rows) values.push_back(row->*field);
  return values;
}

std::vector<double> int_column(const std::vector<const RefinerStudyRow*>& rows, int RefinerStudyRow::*field) {
  std::vector<double> values;
  for (const RefinerStudyRow* row : rows) values.push_back(static_cast<double>(row->*field));
  return values;
}

std::vector<double> synthetic_levels(const RefinerStudyResult& result, double RefinerStudyRow::*field) {
  std::set<double> levels;
  for (const RefinerStudyRow& row : result.rows)
    if (row.correspondence_set == "synthetic") levels.insert(row.*field);
  return {levels.begin(), levels.end()};
}

std::string percent_label(double fraction) { return fixed(100.0 * fraction, 0) + "%"; }

/// The distinct backend/algorithm pairs of the study, in configuration order (loss of the first one).
std::vector<RefinerConfiguration> distinct_methods(const RefinerStudyResult& result) {
  std::vector<RefinerConfiguration> methods;
  for (const RefinerConfiguration& configuration : result.configurations)
    if (std::none_of(methods.begin(), methods.end(), [&](const RefinerConfiguration& m) {
          return m.backend == configuration.backend && m.algorithm == configuration.algorithm;
        }))
      methods.push_back(configuration);
  return methods;
}

}  // namespace

void write_refiner_study_csv(const std::string& path, const RefinerStudyResult& result) {
  write_file_atomically(path, [&](std::ostream& out) {
    out << "source,correspondence_set,backend,algorithm,loss,noise_m,outlier_fraction,trial,start_translation_m,"
           "start_rotation_deg,correspondences,wrong_correspondences,factors,status,rte_m,rre_deg,criterion,reference_rte_m,"
           "reference_rre_deg,gap_translation_m,gap_rotation_deg,converged,iterations,evaluations,initial_cost,final_cost,time_ms,"
           "cpu_ms\n";
    for (const RefinerStudyRow& row : result.rows)
      out << row.source << ',' << row.correspondence_set << ',' << row.backend << ',' << row.algorithm << ',' << row.loss << ','
          << number(row.noise) << ',' << number(row.outlier_fraction) << ',' << row.trial << ',' << number(row.start_translation)
          << ',' << number(row.start_rotation_degrees) << ',' << row.correspondences << ',' << row.wrong_correspondences << ','
          << row.factors << ',' << row.status << ',' << number(row.rte) << ',' << number(row.rre_degrees) << ',' << row.criterion
          << ',' << number(row.reference_rte) << ',' << number(row.reference_rre_degrees) << ',' << number(row.gap_translation)
          << ',' << number(row.gap_rotation_degrees) << ',' << (row.converged ? 1 : 0) << ',' << row.iterations << ','
          << row.evaluations << ',' << number(row.initial_cost) << ',' << number(row.final_cost) << ',' << number(row.time_ms, 4)
          << ',' << number(row.cpu_ms, 4) << '\n';
  });
}

namespace {

/// The synthetic rows of one configuration (backend, algorithm and loss) that `keep` accepts.
std::vector<const RefinerStudyRow*> synthetic_rows(const RefinerStudyResult& result, const RefinerConfiguration& configuration,
                                                   const RowFilter& keep) {
  return rows_where(result, [&](const RefinerStudyRow& r) {
    return r.correspondence_set == "synthetic" && same_configuration(r, configuration) && keep(r);
  });
}

/// The rows of one backend/algorithm, every loss pooled, that `keep` accepts.
std::vector<const RefinerStudyRow*> method_rows(const RefinerStudyResult& result, const RefinerConfiguration& method,
                                                const RowFilter& keep) {
  return rows_where(result, [&](const RefinerStudyRow& r) {
    return r.backend == method.backend && (method.algorithm.empty() || r.algorithm == method.algorithm) && keep(r);
  });
}

/// Title and prose (run, objective, problems, starts, "converged") from the run's options, so text matches numbers.
void write_study_introduction(std::ostream& out, const RefinerStudyResult& result, const RefinerStudyOptions& options,
                              const std::string& command_line) {
  out << "# Refiner study: Ceres vs NLopt\n\n"
      << "Generated by `" << command_line << "` (" << result.rows.size() << " refinements plus one reference refinement per "
      << "problem and configuration, " << fixed(result.seconds, 1) << " s wall time, " << options.threads
      << " worker thread(s) on 2 shared, loaded cores). Raw rows: `refiners.csv` beside this file; plot: `refiners.svg`. "
      << "Seeds are fixed (base seed " << options.seed << "): a rerun gives the same rows except the times.\n\n"
      << "Every configuration minimises the same objective, F(T) = 1/2 sum rho(w ||e(T)||^2) with e the degeneracy-aware "
         "quadric distance of paper Eq. (quadrics distance) (Algorithm 1, LMOptimizer; `estimation/refiner.h`), with the "
         "backends' default budgets and tolerances. Robust kernels use scale "
      << fixed(options.loss_scale, 2) << " (a of Huber/Cauchy, Phi of DCS).\n\n"
      << "## Problems\n\n"
      << "- **Synthetic** (`" ;
  for (std::size_t i = 0; i < options.scenes.size(); ++i) out << (i ? "`, `" : "") << options.scenes[i];
  out << "`): the ground-truth records of the scene's primitives (layout seed 1; at most " << options.max_synthetic_elements
      << " primitives, a random subset per trial) are the source; the target is every primitive moved by a random pose (any "
         "heading, up to 3 deg tilt, up to 20 m) and, at the noisy level, by its own rigid jitter about its centre (centre sigma, "
         "axis-rotation sigma per axis) with its scales multiplied by 1 + sigma_s N(0,1). Noise levels (centre / axes / scale): ";
  for (std::size_t i = 0; i < options.noise_levels.size(); ++i)
    out << (i ? ", " : "") << fixed(100.0 * options.noise_levels[i].centre, 0) << " cm / " << fixed(options.noise_levels[i].axis_degrees, 1)
        << " deg / " << fixed(100.0 * options.noise_levels[i].scale, 0) << "%";
  out << ". Wrong correspondences: a share of {";
  for (std::size_t i = 0; i < options.outlier_fractions.size(); ++i) out << (i ? ", " : "") << percent_label(options.outlier_fractions[i]);
  out << "} of the pairs point to another primitive of the same semantic label (nested sets, common random numbers). Factors "
         "are built as Algorithm 1 does (augmentation of lines and planes"
      << (options.augment_non_central ? "" : " disabled") << "; no f_pp filter and no ground factor: synthetic records have no "
         "estimated ground). " << options.trials << " trials per scene, each with one start.\n"
      << "- **Real** (KITTI loop closures of `pairs.tsv`, exact ground truth): both clouds modelled with the `" << options.real_preset
      << "` preset as `quadrix register` does; correspondence sets `gt_inliers` (putative correspondences within "
      << fixed(kInlierDistance, 1) << " m under the ground truth) and `clique` (the maximum clique of the level the pipeline selects, "
         "which may hold wrong pairs); factors with f_pp against the estimated ground normals, augmentation and the ground factor, "
         "as the pipeline builds them. "
      << options.trials << " starts per set.\n"
      << "- **Starts**: the ground truth perturbed by exactly " << fixed(options.minimum_translation, 1) << "-"
      << fixed(options.maximum_translation, 1) << " m (uniform, random direction) and " << fixed(options.minimum_rotation_degrees, 0)
      << "-" << fixed(options.maximum_rotation_degrees, 0) << " deg (uniform, random axis).\n\n"
      << "**Converged** means: on noise-free synthetic problems without wrong correspondences (criterion `truth`), RTE < "
      << fixed(100.0 * options.converged_translation, 0) << " cm and RRE < " << number(options.converged_rotation_degrees)
      << " deg against the ground truth; everywhere else (criterion `reference`), the final pose within "
      << fixed(100.0 * options.converged_translation, 0) << " cm / " << number(options.converged_rotation_degrees)
      << " deg of the **reference**, i.e. the same configuration started at the ground truth: the minimum the optimiser should "
         "find. Whether that minimum is accurate is a property of the loss, shown by the reference's own RTE/RRE. A degenerate "
         "or failed refinement never counts as converged.\n\n";
}

/// Headline: each backend/algorithm pooled over losses, noise levels and scenes, to compare backends at a glance.
void write_headline_table(std::ostream& out, const RefinerStudyResult& result, const std::vector<double>& outlier_levels) {
  out << "## Headline\n\nConverged share per backend/algorithm, pooled over every loss, noise level and scene (synthetic) or "
         "pair and correspondence set (real); median CPU and wall time per synthetic refinement.\n\n| backend/algorithm |";
  for (const double level : outlier_levels) out << " synthetic, " << percent_label(level) << " wrong |";
  out << " real KITTI | median CPU time | median wall time |\n|---|";
  for (std::size_t i = 0; i < outlier_levels.size() + 3; ++i) out << "---:|";
  out << '\n';
  for (const RefinerConfiguration& method : distinct_methods(result)) {
    out << "| " << refiner_configuration_name(method) << " |";
    for (const double level : outlier_levels)
      out << ' ' << fixed(convergence_percent(method_rows(result, method, [&](const RefinerStudyRow& r) {
            return r.correspondence_set == "synthetic" && r.outlier_fraction == level;
          })), 0) << "% |";
    const auto synthetic = method_rows(result, method, [](const RefinerStudyRow& r) { return r.correspondence_set == "synthetic"; });
    out << ' ' << fixed(convergence_percent(method_rows(result, method, [](const RefinerStudyRow& r) { return r.correspondence_set != "synthetic"; })), 0)
        << "% | " << fixed(median(column(synthetic, &RefinerStudyRow::cpu_ms)), 2) << " ms | "
        << fixed(median(column(synthetic, &RefinerStudyRow::time_ms)), 2) << " ms |\n";
  }
  out << '\n';
}

/// One synthetic noise level: every configuration's convergence, RTE and RRE by share of wrong correspondences.
void write_wrong_share_table(std::ostream& out, const RefinerStudyResult& result, double noise,
                             const std::vector<double>& outlier_levels) {
  out << "## Synthetic, centre noise " << fixed(100.0 * noise, 0) << " cm: convergence by wrong-correspondence share\n\n"
      << "Cells: converged share / median RTE / median RRE (RTE and RRE against the ground truth), both scenes.\n\n| configuration | loss |";
  for (const double level : outlier_levels) out << ' ' << percent_label(level) << " wrong |";
  out << "\n|---|---|";
  for (std::size_t i = 0; i < outlier_levels.size(); ++i) out << "---:|";
  out << '\n';
  for (const RefinerConfiguration& configuration : result.configurations) {
    out << "| " << refiner_configuration_name(configuration) << " | " << robust_loss_name(configuration.loss) << " |";
    for (const double level : outlier_levels) {
      const auto rows =
          synthetic_rows(result, configuration, [&](const RefinerStudyRow& r) { return r.noise == noise && r.outlier_fraction == level; });
      out << ' ' << fixed(convergence_percent(rows), 0) << "% / " << fixed(100.0 * median(column(rows, &RefinerStudyRow::rte)), 2)
          << " cm / " << fixed(median(column(rows, &RefinerStudyRow::rre_degrees)), 3) << "° |";
    }
    out << '\n';
  }
  out << '\n';
}

/// Convergence and RTE per scene and noise level without wrong correspondences, to show which scene is harder.
void write_per_scene_table(std::ostream& out, const RefinerStudyResult& result, const RefinerStudyOptions& options,
                           const std::vector<double>& noise_levels) {
  out << "## Per scene (synthetic, no wrong correspondences)\n\nCells: converged share / median RTE, per noise level.\n\n| configuration | loss |";
  std::vector<std::pair<std::string, double>> scene_columns;
  for (const std::string& scene : options.scenes)
    for (const double noise : noise_levels) scene_columns.emplace_back(scene, noise);
  for (const auto& [scene, noise] : scene_columns) out << ' ' << scene << ", " << fixed(100.0 * noise, 0) << " cm |";
  out << "\n|---|---|";
  for (std::size_t i = 0; i < scene_columns.size(); ++i) out << "---:|";
  out << '\n';
  for (const RefinerConfiguration& configuration : result.configurations) {
    out << "| " << refiner_configuration_name(configuration) << " | " << robust_loss_name(configuration.loss) << " |";
    for (const auto& [scene, noise] : scene_columns) {
      const auto rows = synthetic_rows(result, configuration, [&, s = scene, n = noise](const RefinerStudyRow& r) {
        return r.source == s && r.noise == n && r.outlier_fraction == 0.0;
      });
      out << ' ' << fixed(convergence_percent(rows), 0) << "% / " << fixed(100.0 * median(column(rows, &RefinerStudyRow::rte)), 2) << " cm |";
    }
    out << '\n';
  }
}

/// Iterations, evaluations, CPU and wall time per refinement over every synthetic problem.
void write_cost_table(std::ostream& out, const RefinerStudyResult& result) {
  out << "\n## Cost per refinement (every synthetic problem)\n\nIterations: Ceres minimiser iterations; NLopt evaluations that "
         "improved the best cost. Evaluations: objective evaluations. CPU time is the refining thread's; wall time is "
         "RefinementResult::seconds, inflated by the other work on 2 shared, loaded cores.\n\n"
      << "| configuration | loss | median iterations | median evaluations | median CPU time | 90th pct CPU time | median wall time | median factors |\n"
      << "|---|---|---:|---:|---:|---:|---:|---:|\n";
  for (const RefinerConfiguration& configuration : result.configurations) {
    const auto rows = synthetic_rows(result, configuration, [](const RefinerStudyRow&) { return true; });
    std::vector<double> factors;
    for (const RefinerStudyRow* row : rows) factors.push_back(static_cast<double>(row->factors));
    out << "| " << refiner_configuration_name(configuration) << " | " << robust_loss_name(configuration.loss) << " | "
        << fixed(median(int_column(rows, &RefinerStudyRow::iterations)), 0) << " | "
        << fixed(median(int_column(rows, &RefinerStudyRow::evaluations)), 0) << " | "
        << fixed(median(column(rows, &RefinerStudyRow::cpu_ms)), 2) << " ms | "
        << fixed(percentile(column(rows, &RefinerStudyRow::cpu_ms), 0.9), 2) << " ms | "
        << fixed(median(column(rows, &RefinerStudyRow::time_ms)), 2) << " ms | " << fixed(median(factors), 0) << " |\n";
  }
}

/// KITTI: each pair's notes, then every configuration on ground-truth inliers and the clique, beside the reference.
void write_real_pairs_table(std::ostream& out, const RefinerStudyResult& result) {
  const auto real = rows_where(result, [](const RefinerStudyRow& r) { return r.correspondence_set != "synthetic"; });
  out << "\n## Real KITTI loop closures\n\n";
  for (const std::string& note : result.notes) out << "- " << note << '\n';
  if (real.empty()) return;
  out << "\nCells: converged share (criterion `reference`) / median RTE / median RRE of the refinements from perturbed starts / "
         "RTE and RRE of the reference; CPU time = median per refinement.\n\n"
      << "| configuration | loss | gt_inliers | clique | CPU time |\n|---|---|---:|---:|---:|\n";
  for (const RefinerConfiguration& configuration : result.configurations) {
    out << "| " << refiner_configuration_name(configuration) << " | " << robust_loss_name(configuration.loss) << " |";
    for (const char* set : {"gt_inliers", "clique"}) {
      const auto rows = rows_where(result, [&](const RefinerStudyRow& r) {
        return r.correspondence_set == set && same_configuration(r, configuration);
      });
      out << ' ' << fixed(convergence_percent(rows), 0) << "% / " << fixed(100.0 * median(column(rows, &RefinerStudyRow::rte)), 1)
          << " cm / " << fixed(median(column(rows, &RefinerStudyRow::rre_degrees)), 2) << "° / ref "
          << fixed(100.0 * median(column(rows, &RefinerStudyRow::reference_rte)), 1) << " cm, "
          << fixed(median(column(rows, &RefinerStudyRow::reference_rre_degrees)), 2) << "° |";
    }
    const auto rows = rows_where(result, [&](const RefinerStudyRow& r) {
      return r.correspondence_set != "synthetic" && same_configuration(r, configuration);
    });
    out << ' ' << fixed(median(column(rows, &RefinerStudyRow::cpu_ms)), 2) << " ms |\n";
  }
}

}  // namespace

void write_refiner_study_markdown(const std::string& path, const RefinerStudyResult& result, const RefinerStudyOptions& options,
                                  const std::string& command_line) {
  const std::vector<double> outlier_levels = synthetic_levels(result, &RefinerStudyRow::outlier_fraction);
  const std::vector<double> noise_levels = synthetic_levels(result, &RefinerStudyRow::noise);
  write_file_atomically(path, [&](std::ostream& out) {
    write_study_introduction(out, result, options, command_line);
    write_headline_table(out, result, outlier_levels);
    for (const double noise : noise_levels) write_wrong_share_table(out, result, noise, outlier_levels);
    write_per_scene_table(out, result, options, noise_levels);
    write_cost_table(out, result);
    write_real_pairs_table(out, result);
  });
}

void write_refiner_study_svg(const std::string& path, const RefinerStudyResult& result) {
  const std::vector<double> outlier_levels = synthetic_levels(result, &RefinerStudyRow::outlier_fraction);
  std::vector<std::string> ticks;
  for (const double level : outlier_levels) ticks.push_back(percent_label(level));
  // Backend/algorithm pairs in configuration order; one panel per loss, then the time panel.
  const std::vector<RefinerConfiguration> methods = distinct_methods(result);
  std::vector<RobustLoss> losses;
  for (const RefinerConfiguration& configuration : result.configurations)
    if (std::find(losses.begin(), losses.end(), configuration.loss) == losses.end()) losses.push_back(configuration.loss);
  const auto series_of = [&](RobustLoss loss, const std::function<double(const std::vector<const RefinerStudyRow*>&)>& statistic) {
    std::vector<report::PlotSeries> series;
    for (RefinerConfiguration method : methods) {
      method.loss = loss;
      report::PlotSeries line{refiner_configuration_name(method), {}};
      for (const double level : outlier_levels)
        line.values.push_back(statistic(rows_where(result, [&](const RefinerStudyRow& r) {
          return r.correspondence_set == "synthetic" && same_configuration(r, method) && r.outlier_fraction == level;
        })));
      series.push_back(std::move(line));
    }
    return series;
  };
  std::vector<report::PlotPanel> panels;
  for (const RobustLoss loss : losses) {
    report::PlotPanel panel;
    panel.title = std::string("converged, loss ") + robust_loss_name(loss) + " (synthetic, all noise)";
    panel.x_label = "wrong correspondences";
    panel.y_label = "%";
    panel.x_ticks = ticks;
    panel.series = series_of(loss, convergence_percent);
    panels.push_back(std::move(panel));
  }
  report::PlotPanel time_panel;
  time_panel.title = std::string("median CPU time per refinement, loss ") + robust_loss_name(losses.front());
  time_panel.x_label = "wrong correspondences";
  time_panel.y_label = " ms";
  time_panel.x_ticks = ticks;
  time_panel.log_y = true;
  time_panel.y_low = 0.1;
  time_panel.y_high = 1000.0;
  time_panel.series = series_of(losses.front(), [](const std::vector<const RefinerStudyRow*>& rows) {
    return median(column(rows, &RefinerStudyRow::cpu_ms));
  });
  panels.push_back(std::move(time_panel));
  report::write_line_panels_svg(path, panels, 2);
}

}  // namespace quadrix
