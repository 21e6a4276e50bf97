// The registration conductor: the whole pipeline (paper §"Registration overview", §"Quadric Matching",
// §"Quadric-based 6-DoF Transformation Estimation", Algorithm 1): model both clouds with quadrics,
// establish putative correspondences, build the multi-level compatibility graphs, find the graduated
// maximum cliques I*_1..K_g, estimate one candidate per level (SVD initialisation, then refinement of
// the degeneracy-aware quadric distance with the f_pp filter against the estimated ground normal and
// correspondence augmentation), and select T* by the robust quadric distance D_v.
//
// A wrong or unsure answer is a status, never a silent transform: `degenerate` when no candidate has
// at least 3 inlier correspondences that constrain all 6 DoF, `ambiguous` when the best and the
// second-best candidates disagree strongly while their scores are close, `failed` when nothing could
// be scored.
#pragma once

#include "estimation/candidate_estimation.h"
#include "estimation/initial_guess.h"
#include "estimation/registration_types.h"
#include "estimation/verification.h"
#include "fitting/scene_modelling.h"
#include "geometry/point_cloud.h"

#include <cstdint>
#include <functional>
#include <vector>

namespace quadrix {

/// Registers two already-modelled scenes (everything after modelling: correspondences, graphs,
/// cliques, Algorithm 1). `counts` source/target points and elements are left 0; timings have no
/// modelling entries and no "total". The models are copied into the result.
RegistrationResult register_models(const SceneModel& source, const SceneModel& target,
                                   const RegistrationOptions& options = {});

/// Whether `model` has no augmented points while `other` has some (augment_other_side's condition).
bool lacks_augmentation_of(const SceneModel& model, const SceneModel& other);

/// Gives `modelling` (of `cloud`) augmented points when `other` has some and it has none
/// (augment_scene_model): delta_a is decided per cloud, augmented points match only augmented
/// points. Returns whether points were added. register_clouds and the benchmark use it.
bool augment_other_side(const PointCloud& cloud, ModellingResult& modelling, const ModellingResult& other,
                        const ModellingOptions& options);

/// Registers `source` onto `target` (paper Fig. overview): model_scene on both clouds with their
/// extraction options, the two at the same time, then register_modelled_clouds. Optional per-point SemanticKITTI labels switch
/// that side to the labels semantic mode. Degenerate input (empty clouds, one wall) gives a status.
RegistrationResult register_clouds(const PointCloud& source, const PointCloud& target,
                                   const RegistrationOptions& options = {},
                                   const std::vector<std::uint32_t>& source_labels = {},
                                   const std::vector<std::uint32_t>& target_labels = {});

/// A cloud with its scene model built beforehand, so a caller that registers one cloud in many pairs
/// (the benchmark) models it once.
struct ModelledCloud {
  const PointCloud* cloud = nullptr;           ///< the cloud, in the frame the registration works in
  const ModellingResult* modelling = nullptr;  ///< model_scene of that cloud with its side's extraction options
  double modelling_ms = 0.0;                   ///< wall time that modelling took, ms (reported as the side's modelling time)
  /// Both sides were modelled at the same time (register_clouds does): "total" then counts the longer
  /// of the two modelling times, not their sum. Set on both sides or on neither.
  bool modelled_concurrently = false;
};

/// A change applied to both models after augmentation and before matching (model-level ablations).
using ModelAdjustment = std::function<SceneModel(const SceneModel&)>;

/// The pipeline after modelling, shared by register_clouds and the benchmark: the other side augmented
/// when only one side was (augment_other_side, on a copy), `adjust_models` when given, register_models,
/// then verify_registration on the clouds; the checks' inputs and the searches' preparation, which
/// need no answer, are made while register_models runs. Fills the counts of points and elements, the
/// modelling timings and "total" (both modelling_ms, or the longer when modelled_concurrently, plus this call).
/// With `options.local_only`, no quadric is matched: the answer is point-to-plane ICP from
/// `options.initial_guess` (coarse to fine from `initial_guess_reach`), verified by the same checks
/// (candidates empty, result.from_initial_guess). With an initial guess and not local_only, that
/// answer is verified beside the global one and they compete: the better status wins, then, for
/// answers that disagree, the larger overlap (the global answer on ties and when they agree); two `ok` answers that disagree leave the winner
/// `ambiguous` (findings.guess_disagrees). Last, measure_answer_quality of the answer fills fitness,
/// inlier_rmse, correspondences and information ("quality" timing). Throws quadrix::Error for
/// local_only without a guess, a non-finite guess, a reach that is not positive or quality options
/// out of range.
RegistrationResult register_modelled_clouds(const ModelledCloud& source, const ModelledCloud& target,
                                            const RegistrationOptions& options = {},
                                            const ModelAdjustment& adjust_models = {});

}  // namespace quadrix
