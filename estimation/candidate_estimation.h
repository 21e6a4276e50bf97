// Transformation candidate estimation and selection (paper Algorithm 1, §"Quadric-based 6-DoF
// Transformation Estimation"): one candidate per clique level, T^0_k by SVD of the full centres,
// refined on the degeneracy-aware quadric distance with f_pp and Augment(); then T* by the robust
// quadric distance D_v, and the ambiguity of the winner (a disagreeing candidate scoring nearly as
// well, or too small a clique).
#pragma once

#include "estimation/registration_types.h"
#include "matching/max_clique.h"

#include <cstddef>
#include <string>
#include <vector>

namespace quadrix {

/// The factor options of candidate estimation between two models (Algorithm 1): Augment(), f_pp over
/// the key-structure labels against each cloud's estimated ground normal, the ground factor when both
/// clouds have a ground (its tilt weighed by `options.level_ground_lever_arm` when `grounds_level`),
/// and the e_R / e_t switches. register_models and the studies share it.
FactorBuildOptions estimation_factor_options(const SceneModel& source, const SceneModel& target,
                                             const EstimationOptions& options, bool grounds_level);

/// Algorithm 1, transformation candidate estimation: one candidate per level of `cliques` (a level
/// whose clique equals the previous one's reuses its candidate); a clique smaller than
/// `options.minimum_inliers`, a degenerate SVD or a degenerate refinement leaves it not valid, with
/// a note. `grounds_level` weighs the ground factor's tilt (estimation_factor_options).
std::vector<RegistrationCandidate> estimate_candidates(const SceneModel& source, const SceneModel& target,
                                                       const CorrespondenceSet& correspondence_set,
                                                       const CompatibilityGraphs& graphs,
                                                       const GraduatedCliqueResult& cliques,
                                                       const EstimationOptions& options, bool grounds_level);

/// Algorithm 1, optimal transformation selection among the valid candidates of `result` (D_v with
/// the DCS kernel, select_candidate on result.source_model and result.target_model), then the
/// ambiguity of the winner (findings.scores_close, findings.weak_support) and the summary message.
/// Fills the scores, best_candidate, the answer, and the status; degenerate when no candidate is valid.
void select_answer(RegistrationResult& result, const RegistrationOptions& options);

/// Ends estimation without an answer: `failure` (Degenerate or Failed) with its reason.
RegistrationResult& fail_estimation(RegistrationResult& result, RegistrationStatus failure, const std::string& message);

}  // namespace quadrix
