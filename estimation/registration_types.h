// The registration's vocabulary: its options, what each candidate and the answer carry, the status
// and the findings behind it (decided in one place, decide_registration_status), and how answers
// are compared and moved between frames. The stages (candidate_estimation.h, verification.h,
// initial_guess.h) and the conductor (registration.h) all speak it.
#pragma once

#include "estimation/answer_quality.h"
#include "estimation/candidate_selection.h"
#include "estimation/dense_search.h"
#include "estimation/free_space.h"
#include "estimation/overlap.h"
#include "estimation/refiner.h"
#include "fitting/extraction.h"
#include "fitting/scene_model.h"
#include "fitting/scene_modelling.h"
#include "geometry/point_cloud.h"
#include "matching/compatibility_graph.h"
#include "matching/correspondences.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace quadrix {

/// Outcome of a registration.
enum class RegistrationStatus : std::uint8_t {
  Ok,          ///< a well-supported candidate won clearly
  Ambiguous,   ///< best and second-best candidates disagree strongly and score almost equally
  Degenerate,  ///< fewer than 3 inlier correspondences, or the factors do not constrain all 6 DoF
  Failed,      ///< no candidate could be estimated or scored
};

/// Lower-case status name ("ok", "ambiguous", "degenerate", "failed").
const char* registration_status_name(RegistrationStatus status);

/// Options of the estimation half (Algorithm 1, transformation candidate estimation).
struct EstimationOptions {
  std::string refiner = "ceres";              ///< Refiner registry name (LMOptimizer of Algorithm 1): "ceres" | "nlopt"
  RefinerOptions refinement;                  ///< LM, 300 iterations, tolerance 1e-8 (published defaults)
  double manhattan_tolerance_degrees = 10.0;  ///< δ_g of f_pp in refinement, degrees (published 10)
  bool augment_non_central = true;            ///< Augment(): samples on linear / planar centres (paper: yes)
  bool use_ground_constraint = true;          ///< add the ground plane-to-plane factor when both clouds have a ground
  double ground_weight = 1.0;                 ///< w of the ground factor
  double level_ground_lever_arm = 100.0;      ///< with both grounds level (grounds_level), the ground factor's tilt residual is multiplied by this, metres: a tilt then costs what lifting a ground point this far out does (1: unscaled). Over the seven tuning sets (2,100 pairs), right answers more than 2 deg off went from 22 (1 m) to 13 (100 m; 21 at 30 m), right answers from 1,875 to 1,882, and no `ok` answer was wrong (docs/registration.md, "The ground's tilt")
  std::size_t minimum_inliers = 3;            ///< a candidate needs at least this many clique correspondences (paper: 3)
  bool refine = true;                         ///< false: each candidate is its SVD estimate T^0_k (ablation "W/O trans. refinement")
  bool use_rotation_error = true;             ///< false: refinement without e_R of Eq. (quadrics distance) (ablation "W/O e_R")
  bool use_translation_error = true;          ///< false: refinement without e_t of Eq. (quadrics distance) (ablation "W/O e_t")
};

/// Thresholds of the `ambiguous` status.
struct AmbiguityOptions {
  double score_ratio = 0.85;                  ///< D_v(best) / D_v(second) above this counts as "scores close"
  double translation_disagreement = 2.0;      ///< candidates farther apart than this disagree, m (success rule: 2 m)
  double rotation_disagreement_degrees = 5.0; ///< or rotated more than this apart, degrees (success rule: 5 deg)
  std::size_t minimum_clique_for_ok = 5;      ///< a winner supported by a smaller clique is `ambiguous`: 3 or 4 mutually consistent pairs arise by chance among hundreds
  double overlap_margin = 0.0;                ///< an `ok` answer whose dense overlap (check_overlap) is below the unmoved source's by more than this fraction is `ambiguous` (0: it must beat not moving; negative: no check)
  double minimum_overlap = 0.4;               ///< an `ok` answer must land at least this fraction of the source (above its ground) within 0.3 m of the target, else `ambiguous` (0: no floor)
  double confirm_below = 0.55;                ///< an `ok` answer of the quadrics landing less than this fraction of the source is `ok` only once the dense search (with the correlation over the ground) settles on it or on a better answer. Right and wrong answers meet here: on the tuning set's 600 runs (as drawn and under random yaw) 15 right `ok` answers (2.5%) landed less than 0.55 (5th percentile 0.57), so few pairs pay for the search (0: off)
  double confirm_over_identity = 0.1;        ///< an `ok` answer of the quadrics landing less than this fraction of the source more than the unmoved source does is `ok` only once the dense search settles on it or on a better answer: an answer that moves the source without landing more of it than not moving is a local optimum as often as the truth. On the tuning set's 600 runs (as drawn and under random yaw) every right `ok` answer gained at least 0.14 (as drawn; 0.37 under random yaw), so none paid for the search (0: off)
  double isolation_cell = 0.3;                ///< the checks (overlap, half turn, correlation over the ground, dense search) leave out points with no other point in their cube of this edge or the 26 around it, m (without_isolated_points; 0: keep every point)
  int isolation_neighbours = 1;               ///< ... or with fewer than this many other points there (at least 1)
  double half_turn_margin = 0.03;             ///< an `ok` answer must put more of the source on the target than the best ICP optimum reached from its half turn (check_half_turn), by this fraction, else `ambiguous` (negative: no check)
  double half_turn_ok_margin = 0.03;         ///< an `ok` answer must also out-overlap that rival by this fraction, else `ambiguous` (the answer is kept; below half_turn_margin it has no effect)
  bool adopt_icp_optimum = true;              ///< an answer that passes the half-turn check becomes the point-to-plane ICP optimum reached from it
  std::size_t half_turn_samples = 1500;       ///< source points the half-turn check's ICP aligns (dense_search.source_samples, 3,000, is for settling): half as many cut the check from about 100 to 80 ms a KITTI pair and changed no status on the loop-closure sets or pairs.tsv (docs/registration.md)
  std::size_t half_turn_votes = 8;            ///< ICP also starts from the half-turned rotation at this many translations the quadrics vote for (the axis of the turn is not known)
  std::size_t half_turn_correlation_starts = 3;  ///< ICP also starts from the half-turned rotation at this many translations that land the most source points in space the target occupies (correlate_translations; 0: none)
  double half_turn_correlation_reach = 40.0;     ///< those translations are searched this far, m, along the ground from the turned answer's: a street's mirror image can lie anywhere along it
  double free_space_limit = 0.18;             ///< an `ok` answer may put at most this share of each scan's high points in the other sensor's free space, the two shares summed (check_free_space), else `ambiguous` (the answer is kept; negative: no check). The clouds must be in their sensors' frames (ExtractionOptions::sensor_origin); the monument preset, whose stations are merged, turns it off. The middle of the gap on the simulated tuning sets (seeds 1001-1005: HDL-64E as drawn and under random yaw, VLP-16, Livox with both passes one way: 1,200 runs, with the other `ok` margins at their defaults), where the 931 right `ok` answers summed at most 0.100 and the 41 wrong ones at least 0.254 (docs/registration.md, "Free space")
  bool free_space_screens_optima = true;       ///< the dense search and the half-turn check leave out of their best and their rivals every refined optimum the free-space check would demote (more than free_space_limit, judged on 100 points a side or more): on the tuning sets this took VLP-16 success from 210 to 263 of 300 and Livox (both passes one way) from 213 to 237, `ok` and wrong still none (docs/registration.md, "Free space")
  double ground_tilt_limit_degrees = 3.5;     ///< an `ok` answer may turn the source's ground at most this far from the target's (the angle between the moved source ground normal and the target's), else `ambiguous`, kept (negative: no check; check_ground_agreement). Under the truth the two grounds agree within 1.76 deg on the tuning sets (1,115 pairs: HDL-64E, VLP-16, Livox driven one way, HDL-64E onto VLP-16); the one `ok` and wrong answer there, an HDL-64E scan onto a VLP-16 one, tilted them 5.47 deg; 3.5 is the middle of that gap
  double free_space_height = 2.0;             ///< the free-space check tests points standing more than this above their scan's ground, m: cars and people that moved between the scans stand lower (at 0.5 m, right answers of the HDL-64E tuning set summed up to 0.63, parked cars that differ between the passes)
};

/// Every option of register_clouds; defaults are the paper's (§"Implementation Details").
struct RegistrationOptions {
  ExtractionOptions source_extraction;        ///< extraction of the source cloud (sensor preset)
  ExtractionOptions target_extraction;        ///< extraction of the target cloud (sensor preset; may differ: cross-sensor)
  ModellingOptions modelling;                 ///< K_e = 50, delta_a = 60, K_a = 10, v_a = 0.5 m
  CorrespondenceOptions correspondences;      ///< K_s = 20, augmented points by FPFH
  CompatibilityGraphOptions graphs;           ///< δ_m = [0.2, 0.4, 0.6, 0.8] m
  double clique_time_limit_ms = 2000.0;       ///< deadline of the whole graduated clique search, ms (released code: 3.6e6)
  int clique_threads = 1;                     ///< threads of the clique solver (0: hardware concurrency)
  EstimationOptions estimation;               ///< candidate estimation
  SelectionOptions selection;                 ///< Φ = 0.5 DCS, δ_g^e = 5 deg (ground normals are filled in by the pipeline)
  AmbiguityOptions ambiguity;                 ///< when the answer is reported as ambiguous
  DenseSearchOptions dense_search;            ///< the ICP search that settles an ambiguous answer (verify_registration)
  AnswerQualityOptions quality;               ///< the fitness, inlier RMSE, correspondences and information of the final answer (measure_answer_quality)
  /// A pose the caller already has (odometry, a previous answer), mapping source into target in the
  /// frame the registration works in. With `local_only` it is the only start; without, the global
  /// answer and the answer from the guess are both verified and compete (register_modelled_clouds).
  std::optional<Eigen::Isometry3d> initial_guess;
  /// Skip the quadric matching (correspondences, graphs, cliques, candidates, selection): align by
  /// point-to-plane ICP from `initial_guess` (required) and let the same verification decide `ok` or
  /// `ambiguous`. Both clouds are still modelled: the checks measure heights from their grounds.
  bool local_only = false;
  /// ICP from the initial guess first pairs points up to this far apart, m, then half as far, and so
  /// on down to dense_search.correspondence_distance: a guess 1 m and 5 degrees off moves points 30 m
  /// away by 2.6 m (at most that distance is what the first pass must reach; at or below
  /// dense_search.correspondence_distance: a single pass).
  double initial_guess_reach = 4.0;
};

/// One transformation candidate T_k (one per clique level).
struct RegistrationCandidate {
  std::size_t level = 0;                      ///< index k of the compatibility graph level
  double threshold = 0.0;                     ///< δ_m^k of that level, m
  std::size_t clique_size = 0;                ///< |I*_k|
  std::vector<RecordCorrespondence> clique;   ///< I*_k: (source record, target record) indices of the clique's correspondences
  Eigen::Isometry3d initial = Eigen::Isometry3d::Identity();    ///< T^0_k = SVD(R_x, R_y, I*_k)
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();  ///< T_k after refinement
  std::string refinement_status;              ///< refinement_status_name, or "skipped" (too few inliers / SVD degenerate)
  std::size_t factor_count = 0;               ///< factors in the refinement (correspondences + augmented + ground)
  std::size_t filtered_count = 0;             ///< clique correspondences removed by f_pp
  double refinement_cost = 0.0;               ///< final refinement cost F(T_k)
  bool valid = false;                         ///< enough inliers and all 6 DoF constrained: takes part in selection
  CandidateScore score;                       ///< D_v(T_k) and its counts (score inf when not valid)
  std::string note;                           ///< why the candidate is not valid (empty when valid)
};

/// Counts reported by a registration.
struct RegistrationCounts {
  std::size_t source_points = 0;              ///< points of the source cloud
  std::size_t target_points = 0;              ///< points of the target cloud
  std::size_t source_elements = 0;            ///< extracted elements of the source
  std::size_t target_elements = 0;            ///< extracted elements of the target
  std::size_t source_quadrics = 0;            ///< fitted quadrics kept in the source model
  std::size_t target_quadrics = 0;            ///< fitted quadrics kept in the target model
  std::size_t source_augmented_points = 0;    ///< augmented points of the source model
  std::size_t target_augmented_points = 0;    ///< augmented points of the target model
  std::size_t correspondences = 0;            ///< putative correspondences |I|
  std::size_t quadric_correspondences = 0;    ///< of which between fitted quadrics
  std::size_t augmented_correspondences = 0;  ///< of which between augmented points (FPFH)
  std::vector<std::size_t> clique_sizes;      ///< |I*_k| per level
  std::size_t source_isolated_points = 0;     ///< source points within range the checks left out as isolated (AmbiguityOptions::isolation_cell)
  std::size_t target_isolated_points = 0;     ///< target points within range the checks left out as isolated
};

/// What the stages found that bears on the status. decide_registration_status turns it into the
/// status; no stage sets a status of its own.
struct RegistrationFindings {
  std::optional<RegistrationStatus> estimation_failure;  ///< Degenerate or Failed when estimation produced no answer
  bool scores_close = false;              ///< the winner nearly ties a disagreeing candidate (AmbiguityOptions::score_ratio)
  bool weak_support = false;              ///< the winner's clique is smaller than AmbiguityOptions::minimum_clique_for_ok
  bool fits_worse_than_identity = false;  ///< the answer's overlap is below the unmoved source's by more than overlap_margin
  bool overlaps_too_little = false;       ///< the answer lands less of the source on the target than AmbiguityOptions::minimum_overlap
  bool overlap_unconfirmed = false;       ///< the answer lands less than AmbiguityOptions::confirm_below, or less than confirm_over_identity more than not moving, and no dense search has settled it
  bool settled_by_dense_search = false;   ///< the dense search replaced an unsure answer by a clear winner
  bool dense_search_unclear = false;      ///< that winner beats its best distinct optimum by less than DenseSearchOptions::ok_margin
  bool half_turn_rival = false;           ///< the answer turned half a turn about the up axis fits the points about as well (check_half_turn)
  bool half_turn_unclear = false;         ///< the answer beats that rival by less than AmbiguityOptions::half_turn_ok_margin
  bool replaced_by_half_turn = false;     ///< the half-turned rival fitted clearly better and became the answer (check_half_turn)
  bool in_free_space = false;             ///< the answer puts more points in the other sensor's free space than AmbiguityOptions::free_space_limit (check_free_space)
  bool free_space_unjudged = false;       ///< the free-space check could not judge the answer (no ground in a model, or fewer than 100 points tested a side), so it is not vouched for (check_free_space)
  bool grounds_disagree = false;          ///< the answer tilts the source's ground from the target's by more than AmbiguityOptions::ground_tilt_limit_degrees (check_ground_agreement)
  bool guess_disagrees = false;           ///< the global answer and the answer from RegistrationOptions::initial_guess were both verified `ok` and disagree (AmbiguityOptions::translation_disagreement, rotation_disagreement_degrees)
};

/// The half-turn check of an answer (check_half_turn): how well the answer and its mirror image fit.
struct HalfTurnCheck {
  Eigen::Vector3d pivot = Eigen::Vector3d::Zero();             ///< centre of the answer's overlap, on the vertical axis of the half turn (target frame)
  double answer_overlap = 0.0;                                  ///< overlap of the ICP optimum reached from the answer
  double rival_overlap = 0.0;                                   ///< overlap of the best optimum that disagrees with the answer (0 when none)
  Eigen::Isometry3d rival = Eigen::Isometry3d::Identity();      ///< that optimum
  bool has_rival = false;                                       ///< some optimum disagrees with the answer
};

/// The status of a registration from its findings, the one place a status is decided: the estimation
/// failure when there is one; otherwise `ok` when the answer is sure (no close rival and enough support,
/// or settled by the dense search), fits the points at least as well as not moving, overlaps the
/// target by at least the floor and, below AmbiguityOptions::confirm_below or within
/// confirm_over_identity of not moving, was settled by the dense search; else `ambiguous`.
RegistrationStatus decide_registration_status(const RegistrationFindings& findings);

/// Everything register_clouds returns.
struct RegistrationResult {
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();  ///< T*: maps source points into the target frame (identity unless ok/ambiguous)
  RegistrationStatus status = RegistrationStatus::Failed;       ///< see RegistrationStatus; decide_registration_status(findings)
  RegistrationFindings findings;                                ///< what the stages found, behind `status`
  std::string message;                                          ///< why, for any status but ok; a short summary otherwise
  std::size_t best_candidate = 0;                               ///< index of T* in `candidates` (candidates.size() when the answer came from the initial guess)
  std::vector<RegistrationCandidate> candidates;                ///< every candidate with its score, in level order
  double best_to_second_ratio = 0.0;                            ///< D_v(best) / D_v(second best valid); 0 with fewer than 2
  RegistrationCounts counts;                                    ///< counts of every stage
  /// Wall times in ms: "modelling_source", "modelling_target", "correspondences", "graphs", "cliques",
  /// "estimation", "selection", "overlap", "dense_search" (when it ran), and "total" (written once, by
  /// register_modelled_clouds: both modellings plus everything after them).
  std::map<std::string, double> timings_ms;
  SceneModel source_model;                                      ///< R_x
  SceneModel target_model;                                      ///< R_y
  std::optional<OverlapMeasure> overlap;                        ///< dense overlap of the answer (check_overlap: register_clouds and the benchmark)
  std::optional<DenseSearchResult> dense_search;                ///< the search along the weakest direction, when an ambiguous answer ran it
  std::vector<GroundPose> ground_correlation;                   ///< the correlation over the ground's poses, best first, which the dense search started from (empty when it did not run)
  std::optional<HalfTurnCheck> half_turn;                       ///< the last half-turn check (check_half_turn), when one ran
  std::optional<FreeSpaceMeasure> free_space;                   ///< the free-space check of the final answer (check_free_space), when it ran
  /// Where the answer comes from: false for the quadric matching, true for ICP from
  /// RegistrationOptions::initial_guess (always with local_only; with a guess and no local_only,
  /// when the guess's verified answer won).
  bool from_initial_guess = false;
  // What a back end uses (measure_answer_quality of the final answer, options.quality), filled for
  // every `ok` or `ambiguous` answer (zero / empty otherwise). Measured on the checks' points: the
  // clouds within their extraction's range limits without their isolated points (verify_registration).
  double fitness = 0.0;      ///< share of the checks' source points with a target point within quality.correspondence_distance after `transform` (Open3D's fitness), [0, 1]
  double inlier_rmse = 0.0;  ///< root mean square of those inliers' point-to-point distances, m (Open3D's inlier_rmse)
  /// The inliers, (source index, target index), indices into the clouds given to register_clouds /
  /// register_modelled_clouds (the checks' crop and filter are mapped back); every source index once.
  std::vector<PointCorrespondence> correspondences;
  /// H = J^T J of the point-to-plane cost over `correspondences` at `transform` (as small_gicp
  /// returns H): order rotation then translation, perturbation on the left in the TARGET frame,
  /// T = Exp(δ) T* (AnswerQuality::information). Symmetric positive semi-definite, growing with the
  /// inliers; a pose graph's edge information for unit-variance (metre) residuals.
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
};

/// Sets `result.status` to decide_registration_status(result.findings); an answer that is neither
/// `ok` nor `ambiguous` becomes the identity. Every stage that changes a finding calls it.
void apply_registration_status(RegistrationResult& result);

/// `cloud` (every field kept) moved by -sensor_origin, so that its sensor stands at the origin: the
/// frame the pipeline measures ranges, free space and rotations in, for a cloud given in another
/// frame (a map's) with its sensor at `sensor_origin`. The cloud's local_origin is added first (in
/// double) and the result has none. Throws quadrix::Error for a non-finite origin.
PointCloud centred_on_sensor(PointCloud cloud, const Eigen::Vector3d& sensor_origin);

/// Where and in what unit a cloud given in its file's frame is modelled: centred on its sensor and
/// in metres, the frame and unit every preset's lengths mean.
struct ModellingFrame {
  Eigen::Vector3d sensor_origin = Eigen::Vector3d::Zero();  ///< where the sensor stood, file coordinates (zero: not centred)
  double metres_per_unit = 1.0;                              ///< the file's length unit in metres (a LAS file in feet: 0.3048)
  /// Whether a cloud must be copied to be modelled (centred or scaled).
  bool moves() const { return !sensor_origin.isZero(0.0) || metres_per_unit != 1.0; }
};

/// A copy of `cloud` in `frame`: centred_on_sensor when frame.sensor_origin is not zero (then checked
/// for finite points, quadrix::Error naming `what` otherwise), positions scaled to metres.
PointCloud in_modelling_frame(const PointCloud& cloud, const ModellingFrame& frame, const std::string& what);

/// A model made in `frame` of a cloud read relative to `local_origin`, back in the file's unit and
/// coordinates: scaled by 1 / metres_per_unit, then moved by the sensor origin (or the local origin).
SceneModel in_file_frame(SceneModel model, const ModellingFrame& frame, const Eigen::Vector3d& local_origin);

/// A transform between sensor-centred clouds (centred_on_sensor) as one between the clouds' own
/// frames: Tr(target_origin) * between_sensors * Tr(-source_origin).
Eigen::Isometry3d between_cloud_frames(const Eigen::Isometry3d& between_sensors, const Eigen::Vector3d& source_origin,
                                       const Eigen::Vector3d& target_origin);

/// The inverse of between_cloud_frames: Tr(-target_origin) * between_clouds * Tr(source_origin). The
/// paper's RTE is measured between sensor frames; in a frame whose origin lies far from the sensors,
/// a small rotation error would add a large translation error.
Eigen::Isometry3d between_sensor_frames(const Eigen::Isometry3d& between_clouds, const Eigen::Vector3d& source_origin,
                                        const Eigen::Vector3d& target_origin);

/// Relative translation error ||t - t_gt||, metres (paper's RTE).
double translation_error(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& truth);
/// Relative rotation error arccos((tr(R^T R_gt) - 1) / 2), degrees (paper's RRE), accurate near 0.
double rotation_error_degrees(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& truth);
/// The paper's success rule: RTE <= 2 m and RRE <= 5 deg.
bool registration_succeeded(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& truth,
                            double max_translation = 2.0, double max_rotation_degrees = 5.0);

}  // namespace quadrix
