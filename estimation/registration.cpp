// register_clouds: the QuadricsReg pipeline end to end, as the data flow of DESIGN.md §1 (see
// registration.h): model -> correspond -> graphs -> cliques -> SVD + refine -> select (estimation
// in candidate_estimation.cpp) -> verify (verification.cpp), or ICP from an initial guess
// (initial_guess.cpp) -> verify.
#include "estimation/registration.h"

#include "estimation/stage_timing.h"
#include "geometry/error.h"
#include "matching/max_clique.h"

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <chrono>
#include <optional>
#include <sstream>
#include <string>

namespace quadrix {
namespace {

using stage_timing::Clock;
using stage_timing::elapsed_ms;
using stage_timing::timed;

std::size_t count_quadrics(const SceneModel& model) { return model.augmented_begin; }

// Points a side keeps when either cloud lies on one plane (register_clouds): enough for the pipeline
// to model and check the pair, and no more, since no number of points on one plane fixes the three
// motions it leaves free.
constexpr std::size_t kOnePlaneRegistrationPoints = 50000;

// Every ceil(N / cap)-th point of `cloud` with every per-point field (all of them when N <= cap).
PointCloud strided_points(const PointCloud& cloud, std::size_t cap) {
  const std::size_t count = cloud.size();
  if (count <= cap) return cloud;
  const std::size_t stride = (count + cap - 1) / cap;
  std::vector<Eigen::Index> kept;
  for (std::size_t i = 0; i < count; i += stride) kept.push_back(static_cast<Eigen::Index>(i));
  PointCloud sample;
  sample.local_origin = cloud.local_origin;
  sample.positions = cloud.positions(Eigen::all, kept);
  const auto take = [&](const auto& values) {
    std::decay_t<decltype(values)> picked;
    if (values.size() != count) return picked;
    picked.reserve(kept.size());
    for (const Eigen::Index i : kept) picked.push_back(values[static_cast<std::size_t>(i)]);
    return picked;
  };
  sample.intensity = take(cloud.intensity);
  sample.labels = take(cloud.labels);
  sample.colors = take(cloud.colors);
  for (const auto& [name, values] : cloud.extra_fields) sample.extra_fields[name] = take(values);
  return sample;
}

// The labels of the points strided_points kept.
std::vector<std::uint32_t> strided_labels(const std::vector<std::uint32_t>& labels, std::size_t count, std::size_t cap) {
  if (labels.empty() || count <= cap) return labels;
  const std::size_t stride = (count + cap - 1) / cap;
  std::vector<std::uint32_t> kept;
  for (std::size_t i = 0; i < count && i < labels.size(); i += stride) kept.push_back(labels[i]);
  return kept;
}

}  // namespace

RegistrationResult register_models(const SceneModel& source, const SceneModel& target, const RegistrationOptions& options) {
  RegistrationResult result;
  result.source_model = source;
  result.target_model = target;
  RegistrationCounts& counts = result.counts;
  counts.source_quadrics = count_quadrics(source);
  counts.target_quadrics = count_quadrics(target);
  counts.source_augmented_points = source.augmented_count();
  counts.target_augmented_points = target.augmented_count();
  make_refiner(options.estimation.refiner);  // unknown names are an Error before any work
  for (const char* name : {"correspondences", "graphs", "cliques", "estimation", "selection"}) result.timings_ms[name] = 0.0;

  // Quadric correspondence initialisation (paper §"Quadric Correspondence Initialization").
  const CorrespondenceSet correspondence_set =
      timed(result, "correspondences", [&] { return establish_correspondences(source, target, options.correspondences); });
  counts.correspondences = correspondence_set.correspondences.size();
  counts.quadric_correspondences = correspondence_set.quadric_matches;
  counts.augmented_correspondences = correspondence_set.augmented_matches;
  if (correspondence_set.correspondences.size() < options.estimation.minimum_inliers) {
    std::ostringstream message;
    message << "only " << correspondence_set.correspondences.size() << " putative correspondences (" << count_quadrics(source)
            << " source and " << count_quadrics(target) << " target quadrics, " << correspondence_set.shared_classes
            << " shared classes); at least " << options.estimation.minimum_inliers << " are needed";
    return fail_estimation(result, RegistrationStatus::Degenerate, message.str());
  }

  // Multi-level compatibility graphs (paper Eq. of d_ij) and the graduated maximum cliques.
  const CompatibilityGraphs graphs = timed(result, "graphs", [&] {
    return build_compatibility_graphs(correspondence_set.source_centers(source), correspondence_set.target_centers(target),
                                      options.graphs);
  });
  const GraduatedCliqueResult cliques = timed(result, "cliques", [&] {
    MaxCliqueOptions clique_options;
    clique_options.thread_count = options.clique_threads;
    clique_options.deadline =
        Clock::now() + std::chrono::microseconds(static_cast<long long>(options.clique_time_limit_ms * 1000.0));
    return find_graduated_maximum_cliques(graphs.levels, clique_options);
  });
  for (const MaxCliqueResult& level : cliques.levels) counts.clique_sizes.push_back(level.size());

  result.candidates = timed(result, "estimation", [&] {
    return estimate_candidates(source, target, correspondence_set, graphs, cliques, options.estimation,
                               grounds_level(source, target, options));
  });
  timed(result, "selection", [&] { select_answer(result, options); });
  return result;
}

bool lacks_augmentation_of(const SceneModel& model, const SceneModel& other) {
  return model.augmented_count() == 0 && other.augmented_count() > 0;
}

bool augment_other_side(const PointCloud& cloud, ModellingResult& modelling, const ModellingResult& other,
                        const ModellingOptions& options) {
  if (!lacks_augmentation_of(modelling.model, other.model)) return false;
  augment_scene_model(cloud.positions.cast<double>(), modelling, options);
  return modelling.model.augmented_count() > 0;
}

RegistrationResult register_modelled_clouds(const ModelledCloud& source, const ModelledCloud& target,
                                            const RegistrationOptions& options, const ModelAdjustment& adjust_models) {
  const Clock::time_point start = Clock::now();
  if (options.local_only && !options.initial_guess)
    throw Error("local registration (local_only) needs an initial guess (RegistrationOptions::initial_guess)");
  if (options.initial_guess && !options.initial_guess->matrix().allFinite())
    throw Error("the initial guess must be a finite rigid transform");
  if (options.initial_guess && !(options.initial_guess_reach > 0.0))
    throw Error("option 'initial_guess_reach' must be positive, got " + std::to_string(options.initial_guess_reach));
  validate_answer_quality_options(options.quality);
  const ModellingResult* source_modelling = source.modelling;
  const ModellingResult* target_modelling = target.modelling;
  double source_ms = source.modelling_ms;
  double target_ms = target.modelling_ms;
  // delta_a is decided per cloud, but augmented points only match augmented points: when one side
  // fell below delta_a and the other did not, augment the other too (on a copy: the caller's model stays).
  std::optional<ModellingResult> augmented;
  if (options.correspondences.match_augmented_points && !options.local_only) {
    const auto augment = [&](const ModelledCloud& side, const ModellingResult& other, double& side_ms) {
      if (!lacks_augmentation_of(side.modelling->model, other.model)) return false;
      const Clock::time_point stage = Clock::now();
      augmented = *side.modelling;
      const bool added = augment_other_side(*side.cloud, *augmented, other, options.modelling);
      if (added) side_ms += elapsed_ms(stage);
      else augmented.reset();
      return added;
    };
    if (augment(source, *target.modelling, source_ms)) source_modelling = &*augmented;
    else if (augment(target, *source.modelling, target_ms)) target_modelling = &*augmented;
  }

  // The checks' inputs and the searches' preparation depend on the clouds only, so they are made
  // while the quadrics are matched (~25 ms beside ~10 on a KITTI pair; docs/registration.md, "Time").
  // They are wasted when no answer comes out, which costs the difference.
  // Local registration matches no quadrics: the models serve the checks only.
  RegistrationResult result;
  std::optional<VerificationInputs> inputs;
  const auto model_of = [&](const ModellingResult& modelling) {
    return adjust_models ? adjust_models(modelling.model) : modelling.model;
  };
  tbb::parallel_invoke(
      [&] {
        if (!options.local_only) result = register_models(model_of(*source_modelling), model_of(*target_modelling), options);
      },
      [&] {
        inputs = prepare_verification(*source.cloud, *target.cloud, options, &source_modelling->extraction,
                                &target_modelling->extraction, true);
      });
  if (options.local_only) {
    result = align_from_guess(model_of(*source_modelling), model_of(*target_modelling), *inputs, options);
    verify_prepared_answer(result, *inputs, options);
  } else {
    verify_prepared_answer(result, *inputs, options);
    if (options.initial_guess) {
      RegistrationResult guessed = align_from_guess(result.source_model, result.target_model, *inputs, options);
      verify_prepared_answer(guessed, *inputs, options);
      result = compete_with_guess(std::move(result), std::move(guessed), options);
    }
  }
  measure_final_answer(result, *inputs, options);
  result.timings_ms["modelling_source"] = source_ms;
  result.timings_ms["modelling_target"] = target_ms;
  const bool concurrent = source.modelled_concurrently && target.modelled_concurrently;
  result.timings_ms["total"] = (concurrent ? std::max(source.modelling_ms, target.modelling_ms)
                                           : source.modelling_ms + target.modelling_ms) +
                               elapsed_ms(start);
  result.counts.source_points = source.cloud->size();
  result.counts.target_points = target.cloud->size();
  result.counts.source_elements = source_modelling->extraction.elements.size();
  result.counts.target_elements = target_modelling->extraction.elements.size();
  if (result.status == RegistrationStatus::Degenerate || result.status == RegistrationStatus::Failed) {
    const auto describe = [](const char* side, const ModellingResult& modelling) {
      return std::string(side) + " " + extraction_status_name(modelling.extraction.status) +
             (modelling.message.empty() ? "" : " (" + modelling.message + ")");
    };
    result.message += " [modelling: " + describe("source", *source_modelling) + ", " + describe("target", *target_modelling) + "]";
  }
  return result;
}

RegistrationResult register_clouds(const PointCloud& source, const PointCloud& target, const RegistrationOptions& options,
                                   const std::vector<std::uint32_t>& source_labels,
                                   const std::vector<std::uint32_t>& target_labels) {
  // A cloud on one plane leaves three motions free, so the pair is degenerate whatever the pipeline
  // finds, and every point past a few more costs time without telling more: modelling a 3 M-point
  // plane took ~50 s a side (normals of the static-scan preset; docs/reliability.md). The pair is then
  // registered from evenly strided points of both clouds, for the same status and checks.
  const auto one_plane = [&](const PointCloud& cloud) {
    return cloud.size() > kOnePlaneRegistrationPoints && lies_on_one_plane(cloud, options.modelling);
  };
  bool source_flat = false, target_flat = false;
  tbb::parallel_invoke([&] { source_flat = one_plane(source); }, [&] { target_flat = one_plane(target); });
  if (source_flat || target_flat) {
    const std::size_t cap = kOnePlaneRegistrationPoints;
    RegistrationResult result =
        register_clouds(strided_points(source, cap), strided_points(target, cap), options,
                        strided_labels(source_labels, source.size(), cap), strided_labels(target_labels, target.size(), cap));
    const std::string flat = std::string("the ") +
                             (source_flat && target_flat ? "source and target clouds lie"
                              : source_flat              ? "source cloud lies"
                                                         : "target cloud lies") +
                             " on one plane, which leaves three motions free";
    // Whatever the strided pair gave, no answer is determined: never `ok` or `ambiguous` here.
    if (result.status == RegistrationStatus::Ok || result.status == RegistrationStatus::Ambiguous)
      fail_estimation(result, RegistrationStatus::Degenerate, flat + " (the pipeline's answer: " + result.message + ")");
    result.message += " [" + flat + "; registered from at most " + std::to_string(cap) + " evenly strided points a side, of " +
                      std::to_string(source.size()) + " and " + std::to_string(target.size()) + "]";
    result.counts.source_points = source.size();
    result.counts.target_points = target.size();
    return result;
  }
  ExtractionOptions source_extraction = options.source_extraction;
  ExtractionOptions target_extraction = options.target_extraction;
  if (!source_labels.empty()) source_extraction.semantic_mode = SemanticMode::Labels;
  if (!target_labels.empty()) target_extraction.semantic_mode = SemanticMode::Labels;
  // The two clouds are modelled independently, so at the same time: on two cores this saves about the
  // shorter of the two modelling times (measured in docs/registration.md, "Time").
  ModellingResult source_modelling, target_modelling;
  double source_ms = 0.0, target_ms = 0.0;
  tbb::parallel_invoke(
      [&] {
        const Clock::time_point start = Clock::now();
        source_modelling = model_scene(source, source_extraction, options.modelling, source_labels);
        source_ms = elapsed_ms(start);
      },
      [&] {
        const Clock::time_point start = Clock::now();
        target_modelling = model_scene(target, target_extraction, options.modelling, target_labels);
        target_ms = elapsed_ms(start);
      });
  return register_modelled_clouds({&source, &source_modelling, source_ms, true}, {&target, &target_modelling, target_ms, true},
                                  options);
}

}  // namespace quadrix
