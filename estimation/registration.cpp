// register_clouds: the QuadricsReg pipeline end to end (see registration.h).
#include "estimation/registration.h"

#include "estimation/svd_alignment.h"
#include "geometry/error.h"
#include "matching/max_clique.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <new>
#include <sstream>

namespace quadrix {
namespace {

using Clock = std::chrono::steady_clock;

double elapsed_ms(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Labels of the key structures f_pp applies to: planes (facades), lines (poles), trunks, and the
// static-scan cylinders and cones. Ground is the reference itself; central quadrics have no axis test.
std::vector<std::uint32_t> structure_labels() {
  return {static_cast<std::uint32_t>(ElementClass::Plane), static_cast<std::uint32_t>(ElementClass::Line),
          static_cast<std::uint32_t>(ElementClass::Trunk), static_cast<std::uint32_t>(ElementClass::Cylinder),
          static_cast<std::uint32_t>(ElementClass::Cone)};
}

std::size_t count_quadrics(const SceneModel& model) { return model.augmented_begin; }

}  // namespace

FactorBuildOptions estimation_factor_options(const SceneModel& source, const SceneModel& target,
                                             const EstimationOptions& options) {
  FactorBuildOptions factor_options;
  factor_options.augment_non_central = options.augment_non_central;
  factor_options.manhattan_tolerance_degrees = options.manhattan_tolerance_degrees;
  factor_options.structure_labels = structure_labels();
  factor_options.use_rotation_error = options.use_rotation_error;
  factor_options.use_translation_error = options.use_translation_error;
  if (source.has_ground && target.has_ground) {
    // f_pp against the estimated ground normal of each cloud (not the z axis: REFERENCE.md pitfall).
    factor_options.source_ground_normal = source.ground_normal;
    factor_options.target_ground_normal = target.ground_normal;
    if (options.use_ground_constraint) {
      factor_options.source_ground = GroundPlane{source.ground_normal, source.ground_offset};
      factor_options.target_ground = GroundPlane{target.ground_normal, target.ground_offset};
      factor_options.ground_weight = options.ground_weight;
    }
  }
  return factor_options;
}

const char* registration_status_name(RegistrationStatus status) {
  switch (status) {
    case RegistrationStatus::Ok: return "ok";
    case RegistrationStatus::Ambiguous: return "ambiguous";
    case RegistrationStatus::Degenerate: return "degenerate";
    case RegistrationStatus::Failed: return "failed";
  }
  return "failed";
}

double translation_error(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& truth) {
  return (estimate.translation() - truth.translation()).norm();
}

double rotation_error_degrees(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& truth) {
  // The angle of R^T R_gt through atan2(|axis part|, cos part): exact near 0 and 180 degrees, where
  // arccos((tr - 1) / 2) loses precision; mathematically identical to the paper's formula.
  const Eigen::Matrix3d difference = estimate.linear().transpose() * truth.linear();
  const Eigen::Vector3d skew(difference(2, 1) - difference(1, 2), difference(0, 2) - difference(2, 0),
                             difference(1, 0) - difference(0, 1));
  const double angle = std::atan2(0.5 * skew.norm(), 0.5 * (difference.trace() - 1.0));
  return std::abs(angle) * 180.0 / M_PI;
}

bool registration_succeeded(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& truth, double max_translation,
                            double max_rotation_degrees) {
  return translation_error(estimate, truth) <= max_translation &&
         rotation_error_degrees(estimate, truth) <= max_rotation_degrees;
}

RegistrationResult register_models(const SceneModel& source, const SceneModel& target, const RegistrationOptions& options) {
  const Clock::time_point start = Clock::now();
  RegistrationResult result;
  result.source_model = source;
  result.target_model = target;
  RegistrationCounts& counts = result.counts;
  counts.source_quadrics = count_quadrics(source);
  counts.target_quadrics = count_quadrics(target);
  counts.source_augmented_points = source.augmented_count();
  counts.target_augmented_points = target.augmented_count();
  make_refiner(options.estimation.refiner);  // unknown names are an Error before any work

  // Quadric correspondence initialisation (paper §"Quadric Correspondence Initialization").
  Clock::time_point stage = Clock::now();
  const CorrespondenceSet correspondence_set = establish_correspondences(source, target, options.correspondences);
  result.timings_ms["correspondences"] = elapsed_ms(stage);
  counts.correspondences = correspondence_set.correspondences.size();
  counts.quadric_correspondences = correspondence_set.quadric_matches;
  counts.augmented_correspondences = correspondence_set.augmented_matches;

  const auto finish = [&](RegistrationStatus status, const std::string& message) {
    result.status = status;
    result.message = message;
    if (status != RegistrationStatus::Ok && status != RegistrationStatus::Ambiguous)
      result.transform = Eigen::Isometry3d::Identity();
    result.timings_ms["total"] = elapsed_ms(start);
    return result;
  };
  for (const char* name : {"graphs", "cliques", "estimation", "selection"}) result.timings_ms[name] = 0.0;
  if (correspondence_set.correspondences.size() < options.estimation.minimum_inliers) {
    std::ostringstream message;
    message << "only " << correspondence_set.correspondences.size() << " putative correspondences (" << count_quadrics(source)
            << " source and " << count_quadrics(target) << " target quadrics, " << correspondence_set.shared_classes
            << " shared classes); at least " << options.estimation.minimum_inliers << " are needed";
    return finish(RegistrationStatus::Degenerate, message.str());
  }

  // Multi-level compatibility graphs (paper Eq. of d_ij) and the graduated maximum cliques.
  stage = Clock::now();
  const CompatibilityGraphs graphs = build_compatibility_graphs(correspondence_set.source_centers(source),
                                                                correspondence_set.target_centers(target), options.graphs);
  result.timings_ms["graphs"] = elapsed_ms(stage);
  stage = Clock::now();
  MaxCliqueOptions clique_options;
  clique_options.thread_count = options.clique_threads;
  clique_options.deadline = stage + std::chrono::microseconds(static_cast<long long>(options.clique_time_limit_ms * 1000.0));
  const GraduatedCliqueResult cliques = find_graduated_maximum_cliques(graphs.levels, clique_options);
  result.timings_ms["cliques"] = elapsed_ms(stage);
  for (const MaxCliqueResult& level : cliques.levels) counts.clique_sizes.push_back(level.size());

  // Algorithm 1, transformation candidate estimation: one candidate per level.
  stage = Clock::now();
  const std::vector<QuadricDecomposition> source_shapes = decompose_records(source.records);
  const std::vector<QuadricDecomposition> target_shapes = decompose_records(target.records);
  const FactorBuildOptions factor_options = estimation_factor_options(source, target, options.estimation);
  RefinerOptions refiner_options = options.estimation.refinement;
  // Without e_R or e_t some directions may be unconstrained by design: optimise what is left and keep
  // the SVD start along the rest (the paper's ablation rows), instead of refusing as degenerate.
  if (!options.estimation.use_rotation_error || !options.estimation.use_translation_error) refiner_options.check_degeneracy = false;
  const std::unique_ptr<Refiner> refiner = make_refiner(options.estimation.refiner);
  for (std::size_t level = 0; level < cliques.levels.size(); ++level) {
    const std::vector<int>& clique = cliques.levels[level].clique;
    RegistrationCandidate candidate;
    candidate.level = level;
    candidate.threshold = graphs.thresholds[level];
    candidate.clique_size = clique.size();
    // A level whose clique equals the previous level's gives the same candidate: reuse it.
    if (level > 0 && clique == cliques.levels[level - 1].clique) {
      candidate = result.candidates.back();
      candidate.level = level;
      candidate.threshold = graphs.thresholds[level];
      result.candidates.push_back(candidate);
      continue;
    }
    if (clique.size() < options.estimation.minimum_inliers) {
      candidate.refinement_status = "skipped";
      candidate.note = "clique of " + std::to_string(clique.size()) + " correspondences (< " +
                       std::to_string(options.estimation.minimum_inliers) + ")";
      result.candidates.push_back(candidate);
      continue;
    }
    std::vector<RecordCorrespondence> pairs;
    pairs.reserve(clique.size());
    for (const int vertex : clique) {
      const Correspondence& match = correspondence_set.correspondences[static_cast<std::size_t>(vertex)];
      pairs.push_back(RecordCorrespondence{match.source, match.target});
    }
    const RigidAlignment initial = align_full_centers(source.records, target.records, pairs);  // T^0 = SVD(R_x, R_y, I*)
    candidate.initial = initial.transform;
    if (initial.status != AlignmentStatus::Ok) {
      candidate.refinement_status = "skipped";
      candidate.note = "SVD initialisation degenerate: " + initial.message;
      result.candidates.push_back(candidate);
      continue;
    }
    const FactorSet factors = build_quadric_factors(source.records, source_shapes, target.records, target_shapes, pairs,
                                                    factor_options);
    candidate.factor_count = factors.factors.size();
    candidate.filtered_count = factors.filtered_count;
    if (!options.estimation.refine) {  // ablation: the SVD estimate is the candidate
      candidate.transform = initial.transform;
      candidate.refinement_status = "skipped";
      candidate.valid = true;
      candidate.note = "refinement disabled (estimation.refine = false)";
      result.candidates.push_back(candidate);
      continue;
    }
    const RefinementResult refined = refiner->refine(factors.factors, initial.transform, refiner_options);
    candidate.refinement_status = refinement_status_name(refined.status);
    candidate.refinement_cost = refined.final_cost;
    candidate.transform = refined.transform;
    switch (refined.status) {
      case RefinementStatus::Converged:
      case RefinementStatus::MaxIterations:
        candidate.valid = true;
        break;
      case RefinementStatus::Failed:
        // The backend could not run; the SVD estimate is still a candidate (scored like the others).
        candidate.transform = initial.transform;
        candidate.valid = true;
        candidate.note = "refinement failed, SVD estimate kept: " + refined.message;
        break;
      case RefinementStatus::Degenerate:
        candidate.note = "refinement degenerate (rank " + std::to_string(refined.constrained_rank) + " of 6): " + refined.message;
        break;
    }
    result.candidates.push_back(candidate);
  }
  result.timings_ms["estimation"] = elapsed_ms(stage);

  // Algorithm 1, optimal transformation selection among the valid candidates.
  stage = Clock::now();
  std::vector<std::size_t> valid_indices;
  std::vector<Eigen::Isometry3d> valid_transforms;
  for (std::size_t i = 0; i < result.candidates.size(); ++i)
    if (result.candidates[i].valid) {
      valid_indices.push_back(i);
      valid_transforms.push_back(result.candidates[i].transform);
    }
  if (valid_indices.empty()) {
    result.timings_ms["selection"] = elapsed_ms(stage);
    const std::size_t largest = counts.clique_sizes.empty() ? 0 : *std::max_element(counts.clique_sizes.begin(), counts.clique_sizes.end());
    std::string notes;
    for (const RegistrationCandidate& candidate : result.candidates)
      if (!candidate.note.empty() && notes.find(candidate.note) == std::string::npos)
        notes += (notes.empty() ? "" : "; ") + candidate.note;
    return finish(RegistrationStatus::Degenerate, "no usable candidate (largest clique " + std::to_string(largest) +
                                                      " of " + std::to_string(counts.correspondences) + " correspondences): " + notes);
  }
  SelectionOptions selection = options.selection;
  if (selection.structure_labels.empty()) selection.structure_labels = structure_labels();
  if (source.has_ground && target.has_ground) {
    selection.source_ground_normal = source.ground_normal;
    selection.target_ground_normal = target.ground_normal;
  }
  SelectionResult selected;
  try {
    selected = select_candidate(source.records, target.records, valid_transforms, selection);
  } catch (const std::bad_alloc&) {
    // SNN enumerates every same-label source/target pair; huge augmented models can exhaust memory.
    result.timings_ms["selection"] = elapsed_ms(stage);
    return finish(RegistrationStatus::Failed, "candidate selection ran out of memory (" + std::to_string(source.size()) +
                                                  " source and " + std::to_string(target.size()) + " target records)");
  }
  result.timings_ms["selection"] = elapsed_ms(stage);
  for (std::size_t k = 0; k < valid_indices.size(); ++k) {
    CandidateScore score = selected.scores[k];
    score.index = valid_indices[k];
    result.candidates[valid_indices[k]].score = score;
  }
  if (selected.status != SelectionStatus::Ok)
    return finish(RegistrationStatus::Failed, "no candidate could be scored (no shared structure after the transform)");
  result.best_candidate = valid_indices[selected.best_index];
  result.transform = result.candidates[result.best_candidate].transform;

  // Ambiguity: the best distinct rival (a candidate that disagrees with the winner) scoring nearly as well.
  const RegistrationCandidate& best = result.candidates[result.best_candidate];
  double best_rival_score = std::numeric_limits<double>::infinity();
  std::size_t rival = result.best_candidate;
  double second_score = std::numeric_limits<double>::infinity();
  for (const std::size_t index : valid_indices) {
    if (index == result.best_candidate) continue;
    const RegistrationCandidate& other = result.candidates[index];
    if (!std::isfinite(other.score.score)) continue;
    second_score = std::min(second_score, other.score.score);
    const bool disagrees = translation_error(other.transform, best.transform) > options.ambiguity.translation_disagreement ||
                           rotation_error_degrees(other.transform, best.transform) > options.ambiguity.rotation_disagreement_degrees;
    if (disagrees && other.score.score < best_rival_score) {
      best_rival_score = other.score.score;
      rival = index;
    }
  }
  if (std::isfinite(second_score) && second_score > 0.0) result.best_to_second_ratio = best.score.score / second_score;
  std::ostringstream summary;
  summary << "candidate of level " << best.level << " (delta_m " << best.threshold << " m, clique " << best.clique_size
          << ", score " << best.score.score << ")";
  if (std::isfinite(best_rival_score) && best_rival_score > 0.0 &&
      best.score.score / best_rival_score > options.ambiguity.score_ratio) {
    summary << " nearly ties with level " << result.candidates[rival].level << " (score " << best_rival_score
            << "), which differs by " << translation_error(result.candidates[rival].transform, best.transform) << " m and "
            << rotation_error_degrees(result.candidates[rival].transform, best.transform) << " deg";
    return finish(RegistrationStatus::Ambiguous, summary.str());
  }
  // Weak support: all candidates may agree and still rest on a handful of pairs that happen to be
  // mutually consistent (3DMatch under an indoor configuration: cliques of 2-3 among 19 pairs,
  // 170 deg off). Such an answer is a guess, not an `ok`.
  if (best.clique_size < options.ambiguity.minimum_clique_for_ok) {
    summary << " rests on only " << best.clique_size << " mutually consistent correspondences (fewer than "
            << options.ambiguity.minimum_clique_for_ok << ")";
    return finish(RegistrationStatus::Ambiguous, summary.str());
  }
  return finish(RegistrationStatus::Ok, summary.str());
}

void check_overlap(RegistrationResult& result, const PointCloud& source, const PointCloud& target,
                   const AmbiguityOptions& options) {
  const Clock::time_point start = Clock::now();
  std::optional<Eigen::Vector4d> source_ground;
  if (result.source_model.has_ground)
    source_ground = Eigen::Vector4d(result.source_model.ground_normal.x(), result.source_model.ground_normal.y(),
                                    result.source_model.ground_normal.z(), result.source_model.ground_offset);
  const OverlapMeasure overlap = measure_overlap(source, target, result.transform, source_ground);
  result.overlap = overlap;
  if (result.status == RegistrationStatus::Ok && options.overlap_margin >= 0.0 && overlap.sampled > 0 &&
      overlap.transformed < overlap.identity - options.overlap_margin) {
    std::ostringstream why;
    why.precision(2);
    why << "; but only " << overlap.transformed << " of the source lands within " << overlap.distance
        << " m of the target, against " << overlap.identity << " left where it is (margin " << options.overlap_margin << ")";
    result.status = RegistrationStatus::Ambiguous;
    result.message += why.str();
  }
  const double ms = elapsed_ms(start);
  result.timings_ms["overlap"] += ms;  // verify_registration may measure twice
  if (const auto total = result.timings_ms.find("total"); total != result.timings_ms.end()) total->second += ms;
}

namespace {

// The points of `cloud` within the extraction's range limits around its sensor (within_range, as extraction crops).
PointCloud crop_to_range(const PointCloud& cloud, const ExtractionOptions& extraction) {
  std::vector<Eigen::Index> kept;
  kept.reserve(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i)
    if (within_range(cloud.point(i), extraction)) kept.push_back(static_cast<Eigen::Index>(i));
  PointCloud cropped;
  cropped.positions.resize(3, static_cast<Eigen::Index>(kept.size()));
  for (std::size_t i = 0; i < kept.size(); ++i) cropped.positions.col(static_cast<Eigen::Index>(i)) = cloud.positions.col(kept[i]);
  return cropped;
}

}  // namespace

void verify_registration(RegistrationResult& result, const PointCloud& source, const PointCloud& target,
                         const RegistrationOptions& options) {
  const PointCloud cropped_source = crop_to_range(source, options.source_extraction);
  const PointCloud cropped_target = crop_to_range(target, options.target_extraction);
  // The overlap guard first: an `ok` answer that fits the points worse than not moving becomes
  // `ambiguous`, and the dense search then gets its chance too.
  check_overlap(result, cropped_source, cropped_target, options.ambiguity);
  if (result.status == RegistrationStatus::Ambiguous && options.dense_search.enabled && !cropped_source.empty() &&
      !cropped_target.empty()) {
    const Clock::time_point start = Clock::now();
    std::vector<Eigen::Isometry3d> other_starts;
    for (std::size_t i = 0; i < result.candidates.size(); ++i)
      if (result.candidates[i].valid && i != result.best_candidate) other_starts.push_back(result.candidates[i].transform);
    std::optional<Eigen::Vector3d> up;
    if (result.target_model.has_ground) up = result.target_model.ground_normal;
    std::optional<Eigen::Vector4d> source_ground;
    if (result.source_model.has_ground)
      source_ground = Eigen::Vector4d(result.source_model.ground_normal.x(), result.source_model.ground_normal.y(),
                                      result.source_model.ground_normal.z(), result.source_model.ground_offset);
    const DenseSearchResult search = search_weakest_direction(
        cropped_source, cropped_target, result.transform, other_starts, up, source_ground,
        options.ambiguity.translation_disagreement, options.ambiguity.rotation_disagreement_degrees, options.dense_search);
    const DenseOptimum& best = search.optima[search.best];
    std::ostringstream why;
    why.precision(3);
    why << "; dense search along (" << search.weakest_direction.x() << ", " << search.weakest_direction.y() << ", "
        << search.weakest_direction.z() << "): best from " << best.start << " (overlap " << best.overlap << ", "
        << translation_error(best.transform, result.transform) << " m from the quadric answer)";
    if (search.rival) {
      const DenseOptimum& rival = search.optima[*search.rival];
      why << ", best distinct optimum from " << rival.start << " at " << translation_error(rival.transform, best.transform)
          << " m (overlap " << rival.overlap << ")";
    } else {
      why << ", every start reached it";
    }
    // Settled only when the winner is clear of every distinct optimum, all close contenders were
    // refined, it lands enough of the source on the target, and it lies within the grid searched
    // around the answer. When the truth is outside the grid, the winner is a wrong local optimum:
    // KITTI answers 10-15 m off gave winners overlapping 0.23-0.33, and 3DTK answers 10-15 m off
    // gave the optimum near not moving (0.49-0.56, 1.4-3.4 m and up to 8 deg wrong) a big margin
    // over the empty grid.
    const bool settled = search.margin >= options.dense_search.decisive_margin && search.unrefined_contenders == 0 &&
                         best.overlap >= options.dense_search.minimum_overlap && search.best_in_grid;
    if (settled) {
      result.transform = best.transform;
      result.status = RegistrationStatus::Ok;
      why << ": settled (margin " << search.margin << ")";
    } else {
      // Not settled: the points do not single out an optimum either, so the quadric answer stands.
      why << ": not settled (margin " << search.margin;
      if (search.margin < options.dense_search.decisive_margin) why << " < " << options.dense_search.decisive_margin;
      if (best.overlap < options.dense_search.minimum_overlap)
        why << ", best overlap below " << options.dense_search.minimum_overlap;
      if (!search.best_in_grid) why << ", best optimum outside the grid searched around the answer";
      if (search.unrefined_contenders > 0)
        why << ", " << search.unrefined_contenders << " optima within " << options.dense_search.refine_band
            << " of the best left unrefined beyond max_refined " << options.dense_search.max_refined;
      why << "), the quadric answer stands";
    }
    result.message += why.str();
    result.dense_search = search;
    const double ms = elapsed_ms(start);
    result.timings_ms["dense_search"] = ms;
    if (const auto total = result.timings_ms.find("total"); total != result.timings_ms.end()) total->second += ms;
    // The new answer's overlap, under the same guard.
    if (settled) check_overlap(result, cropped_source, cropped_target, options.ambiguity);
  }
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

RegistrationResult register_clouds(const PointCloud& source, const PointCloud& target, const RegistrationOptions& options,
                                   const std::vector<std::uint32_t>& source_labels,
                                   const std::vector<std::uint32_t>& target_labels) {
  const Clock::time_point start = Clock::now();
  ExtractionOptions source_extraction = options.source_extraction;
  ExtractionOptions target_extraction = options.target_extraction;
  if (!source_labels.empty()) source_extraction.semantic_mode = SemanticMode::Labels;
  if (!target_labels.empty()) target_extraction.semantic_mode = SemanticMode::Labels;

  Clock::time_point stage = Clock::now();
  ModellingResult source_modelling = model_scene(source, source_extraction, options.modelling, source_labels);
  double source_ms = elapsed_ms(stage);
  stage = Clock::now();
  ModellingResult target_modelling = model_scene(target, target_extraction, options.modelling, target_labels);
  double target_ms = elapsed_ms(stage);
  // delta_a is decided per cloud, but augmented points only match augmented points: when one side
  // fell below delta_a and the other did not, augment the other too.
  if (options.correspondences.match_augmented_points) {
    stage = Clock::now();
    if (augment_other_side(source, source_modelling, target_modelling, options.modelling))
      source_ms += elapsed_ms(stage);
    else if (augment_other_side(target, target_modelling, source_modelling, options.modelling))
      target_ms += elapsed_ms(stage);
  }

  RegistrationResult result = register_models(source_modelling.model, target_modelling.model, options);
  verify_registration(result, source, target, options);
  result.timings_ms["modelling_source"] = source_ms;
  result.timings_ms["modelling_target"] = target_ms;
  result.timings_ms["total"] = elapsed_ms(start);
  result.counts.source_points = source.size();
  result.counts.target_points = target.size();
  result.counts.source_elements = source_modelling.extraction.elements.size();
  result.counts.target_elements = target_modelling.extraction.elements.size();
  if (result.status == RegistrationStatus::Degenerate || result.status == RegistrationStatus::Failed) {
    const auto describe = [](const char* side, const ModellingResult& modelling) {
      return std::string(side) + " " + extraction_status_name(modelling.extraction.status) +
             (modelling.message.empty() ? "" : " (" + modelling.message + ")");
    };
    result.message += " [modelling: " + describe("source", source_modelling) + ", " + describe("target", target_modelling) + "]";
  }
  return result;
}

}  // namespace quadrix
