// Transformation candidate estimation and selection, Algorithm 1 (see candidate_estimation.h).
#include "estimation/candidate_estimation.h"

#include "estimation/svd_alignment.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <new>
#include <sstream>

namespace quadrix {
namespace {

// Labels of the key structures f_pp applies to: planes (facades), lines (poles), trunks, and the
// static-scan cylinders and cones. Ground is the reference itself; central quadrics have no axis test.
std::vector<std::uint32_t> structure_labels() {
  return {static_cast<std::uint32_t>(ElementClass::Plane), static_cast<std::uint32_t>(ElementClass::Line),
          static_cast<std::uint32_t>(ElementClass::Trunk), static_cast<std::uint32_t>(ElementClass::Cylinder),
          static_cast<std::uint32_t>(ElementClass::Cone)};
}

}  // namespace

FactorBuildOptions estimation_factor_options(const SceneModel& source, const SceneModel& target,
                                             const EstimationOptions& options, bool grounds_level) {
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
      if (grounds_level) factor_options.ground_tilt_lever_arm = options.level_ground_lever_arm;
    }
  }
  return factor_options;
}

RegistrationResult& fail_estimation(RegistrationResult& result, RegistrationStatus failure, const std::string& message) {
  result.findings.estimation_failure = failure;
  result.message = message;
  apply_registration_status(result);
  return result;
}

namespace {

// The clique's correspondences as record pairs.
std::vector<RecordCorrespondence> clique_pairs(const CorrespondenceSet& correspondence_set, const std::vector<int>& clique) {
  std::vector<RecordCorrespondence> pairs;
  pairs.reserve(clique.size());
  for (const int vertex : clique) {
    const Correspondence& match = correspondence_set.correspondences[static_cast<std::size_t>(vertex)];
    pairs.push_back(RecordCorrespondence{match.source, match.target});
  }
  return pairs;
}

// What candidate estimation of every level shares.
struct CandidateContext {
  const SceneModel* source = nullptr;
  const SceneModel* target = nullptr;
  std::vector<QuadricDecomposition> source_shapes;
  std::vector<QuadricDecomposition> target_shapes;
  FactorBuildOptions factor_options;
  RefinerOptions refiner_options;
  std::unique_ptr<Refiner> refiner;
  const EstimationOptions* options = nullptr;
};

// Algorithm 1 for one clique: T^0 = SVD(R_x, R_y, I*) (Eq. of the full-centre alignment), then the
// refinement of the quadric distance (Eq. quadrics distance) with f_pp and Augment().
void estimate_candidate(const CandidateContext& context, const std::vector<RecordCorrespondence>& pairs,
                        RegistrationCandidate& candidate) {
  const RigidAlignment initial = align_full_centers(context.source->records, context.target->records, pairs);
  candidate.initial = initial.transform;
  if (initial.status != AlignmentStatus::Ok) {
    candidate.refinement_status = "skipped";
    candidate.note = "SVD initialisation degenerate: " + initial.message;
    return;
  }
  const FactorSet factors = build_quadric_factors(context.source->records, context.source_shapes, context.target->records,
                                                  context.target_shapes, pairs, context.factor_options);
  candidate.factor_count = factors.factors.size();
  candidate.filtered_count = factors.filtered_count;
  if (!context.options->refine) {  // ablation: the SVD estimate is the candidate
    candidate.transform = initial.transform;
    candidate.refinement_status = "skipped";
    candidate.valid = true;
    candidate.note = "refinement disabled (estimation.refine = false)";
    return;
  }
  const RefinementResult refined = context.refiner->refine(factors.factors, initial.transform, context.refiner_options);
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
}

}  // namespace

std::vector<RegistrationCandidate> estimate_candidates(const SceneModel& source, const SceneModel& target,
                                                       const CorrespondenceSet& correspondence_set,
                                                       const CompatibilityGraphs& graphs,
                                                       const GraduatedCliqueResult& cliques,
                                                       const EstimationOptions& options, bool grounds_level) {
  CandidateContext context;
  context.source = &source;
  context.target = &target;
  context.source_shapes = decompose_records(source.records);
  context.target_shapes = decompose_records(target.records);
  context.factor_options = estimation_factor_options(source, target, options, grounds_level);
  context.refiner_options = options.refinement;
  // Without e_R or e_t some directions may be unconstrained by design: optimise what is left and keep
  // the SVD start along the rest (the paper's ablation rows), instead of refusing as degenerate.
  if (!options.use_rotation_error || !options.use_translation_error) context.refiner_options.check_degeneracy = false;
  context.refiner = make_refiner(options.refiner);
  context.options = &options;

  std::vector<RegistrationCandidate> candidates;
  for (std::size_t level = 0; level < cliques.levels.size(); ++level) {
    const std::vector<int>& clique = cliques.levels[level].clique;
    // A level whose clique equals the previous level's gives the same candidate: reuse it.
    const bool reused = level > 0 && clique == cliques.levels[level - 1].clique;
    RegistrationCandidate candidate = reused ? candidates.back() : RegistrationCandidate{};
    candidate.level = level;
    candidate.threshold = graphs.thresholds[level];
    candidate.clique_size = clique.size();
    if (!reused) {
      candidate.clique = clique_pairs(correspondence_set, clique);
      if (clique.size() < options.minimum_inliers) {
        candidate.refinement_status = "skipped";
        candidate.note = "clique of " + std::to_string(clique.size()) + " correspondences (< " +
                         std::to_string(options.minimum_inliers) + ")";
      } else {
        estimate_candidate(context, candidate.clique, candidate);
      }
    }
    candidates.push_back(candidate);
  }
  return candidates;
}

namespace {

// The reason no candidate is usable: the largest clique and every distinct candidate note.
std::string describe_no_usable_candidate(const RegistrationResult& result) {
  const std::vector<std::size_t>& sizes = result.counts.clique_sizes;
  const std::size_t largest = sizes.empty() ? 0 : *std::max_element(sizes.begin(), sizes.end());
  std::string notes;
  for (const RegistrationCandidate& candidate : result.candidates)
    if (!candidate.note.empty() && notes.find(candidate.note) == std::string::npos)
      notes += (notes.empty() ? "" : "; ") + candidate.note;
  return "no usable candidate (largest clique " + std::to_string(largest) + " of " +
         std::to_string(result.counts.correspondences) + " correspondences): " + notes;
}

// Ambiguity of the selected winner (findings.scores_close, findings.weak_support) and the summary message.
void judge_winner(RegistrationResult& result, const std::vector<std::size_t>& valid_indices, const AmbiguityOptions& options) {
  const RegistrationCandidate& best = result.candidates[result.best_candidate];
  // The best distinct rival: a candidate that disagrees with the winner, scoring nearly as well.
  double best_rival_score = std::numeric_limits<double>::infinity();
  std::size_t rival = result.best_candidate;
  double second_score = std::numeric_limits<double>::infinity();
  for (const std::size_t index : valid_indices) {
    if (index == result.best_candidate) continue;
    const RegistrationCandidate& other = result.candidates[index];
    if (!std::isfinite(other.score.score)) continue;
    second_score = std::min(second_score, other.score.score);
    const bool disagrees = translation_error(other.transform, best.transform) > options.translation_disagreement ||
                           rotation_error_degrees(other.transform, best.transform) > options.rotation_disagreement_degrees;
    if (disagrees && other.score.score < best_rival_score) {
      best_rival_score = other.score.score;
      rival = index;
    }
  }
  if (std::isfinite(second_score) && second_score > 0.0) result.best_to_second_ratio = best.score.score / second_score;
  std::ostringstream summary;
  summary << "candidate of level " << best.level << " (delta_m " << best.threshold << " m, clique " << best.clique_size
          << ", score " << best.score.score << ")";
  result.findings.scores_close = std::isfinite(best_rival_score) && best_rival_score > 0.0 &&
                                 best.score.score / best_rival_score > options.score_ratio;
  if (result.findings.scores_close) {
    summary << " nearly ties with level " << result.candidates[rival].level << " (score " << best_rival_score
            << "), which differs by " << translation_error(result.candidates[rival].transform, best.transform) << " m and "
            << rotation_error_degrees(result.candidates[rival].transform, best.transform) << " deg";
  } else if (best.clique_size < options.minimum_clique_for_ok) {
    // Weak support: all candidates may agree and still rest on a handful of pairs that happen to be
    // mutually consistent (3 or 4 consistent pairs arise by chance among hundreds). A guess, not `ok`.
    result.findings.weak_support = true;
    summary << " rests on only " << best.clique_size << " mutually consistent correspondences (fewer than "
            << options.minimum_clique_for_ok << ")";
  }
  result.message = summary.str();
}

}  // namespace

void select_answer(RegistrationResult& result, const RegistrationOptions& options) {
  const SceneModel& source = result.source_model;
  const SceneModel& target = result.target_model;
  std::vector<std::size_t> valid_indices;
  std::vector<Eigen::Isometry3d> valid_transforms;
  for (std::size_t i = 0; i < result.candidates.size(); ++i)
    if (result.candidates[i].valid) {
      valid_indices.push_back(i);
      valid_transforms.push_back(result.candidates[i].transform);
    }
  if (valid_indices.empty()) {
    fail_estimation(result, RegistrationStatus::Degenerate, describe_no_usable_candidate(result));
    return;
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
    fail_estimation(result, RegistrationStatus::Failed, "candidate selection ran out of memory (" +
                                                            std::to_string(source.size()) + " source and " +
                                                            std::to_string(target.size()) + " target records)");
    return;
  }
  for (std::size_t k = 0; k < valid_indices.size(); ++k) {
    CandidateScore score = selected.scores[k];
    score.index = valid_indices[k];
    result.candidates[valid_indices[k]].score = score;
  }
  if (selected.status != SelectionStatus::Ok) {
    fail_estimation(result, RegistrationStatus::Failed, "no candidate could be scored (no shared structure after the transform)");
    return;
  }
  result.best_candidate = valid_indices[selected.best_index];
  result.transform = result.candidates[result.best_candidate].transform;
  judge_winner(result, valid_indices, options.ambiguity);
  apply_registration_status(result);
}

}  // namespace quadrix
