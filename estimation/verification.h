// Verification of an answer (beyond the paper, which stops at selection): it needs the clouds, not
// only the models. The checks' points are prepared once (range crop, isolated points left out, the
// target hashed, both clouds prepared for ICP, each sensor's range image); then the overlap guard,
// ICP refinement and the free-space check, the half-turn check against a street's mirror image,
// the dense search that settles an `ambiguous` answer, the grounds' agreement, and last the
// measures a back end uses (fitness, inlier RMSE, correspondences, information). Each check records
// findings; apply_registration_status turns them into the status.
#pragma once

#include "estimation/registration_types.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

namespace quadrix {

/// Measures the answer's dense overlap into `result.overlap` (measure_overlap at 0.3 m, points near
/// the source model's ground skipped) and demotes an `ok` answer to `ambiguous` when it overlaps
/// less than leaving the source in place by more than `options.overlap_margin`: a transform that
/// fits the points worse than not moving is not a confident answer (findings.fits_worse_than_identity).
/// Adds to the "overlap" timing. verify_registration calls it.
void check_overlap(RegistrationResult& result, const PointCloud& source, const PointCloud& target,
                   const AmbiguityOptions& options);

/// Checks an answer against its mirror image (beyond the paper): two scans of a street taken from
/// its two ends look alike under a half turn about a vertical axis through the stretch both see,
/// and the quadrics can support the turned answer as strongly as the true one. The answer's
/// rotation is turned by 180 degrees about the up axis (the target's ground normal); point-to-plane
/// ICP then runs from that rotation turned about the centre of the source points the answer lands
/// on the target, from the same rotation at the `half_turn_votes` translations most same-class
/// quadric pairs vote for (the axis of the turn is not known), at the
/// `half_turn_correlation_starts` translations within `half_turn_correlation_reach` that land the
/// most source points in space the target occupies, and from the answer itself. An `ok`
/// answer whose own optimum beats the best disagreeing optimum by less than
/// `options.ambiguity.half_turn_margin` is demoted to `ambiguous` (findings.half_turn_rival); one
/// that passes becomes its ICP optimum when `adopt_icp_optimum`, and is still `ambiguous` when it
/// beats the rival by less than `half_turn_ok_margin` (findings.half_turn_unclear). When `may_replace`, an `ok` or
/// `ambiguous` answer that the rival beats by the margin, with at least
/// dense_search.minimum_overlap of the source on the target, is replaced by it
/// (findings.replaced_by_half_turn) and left `ambiguous` with the old answer as its rival, for
/// the dense search to settle. The pivot comes from `result.overlap` when set, so check_overlap must
/// have measured the current answer (verify_registration keeps that order). `prepared`, when given,
/// holds `source` and `target` already prepared with `options.dense_search` (verify_registration
/// shares one between its checks); else they are prepared here. An optimum `screen` rules out is
/// never the rival (verify_registration passes the free-space check's rule when
/// `ambiguity.free_space_screens_optima`). Adds the "half_turn" timing; verify_registration calls it.
void check_half_turn(RegistrationResult& result, const PointCloud& source, const PointCloud& target,
                     const RegistrationOptions& options, bool may_replace = true, const DenseSearchPair* prepared = nullptr,
                     const OptimumScreen& screen = {});

/// Checks an `ok` answer against what each sensor saw as empty (beyond the paper): measure_free_space
/// of the answer, with each scan's range image around its extraction's sensor_origin and the points
/// higher than `options.ambiguity.free_space_height` above each model's ground. An answer whose two
/// shares sum to more than `free_space_limit` is `ambiguous` (findings.in_free_space), and is kept.
/// Where a street's mirror image or a shift along it lands as much of the source as the truth, it
/// still puts façades where the other sensor saw through. Runs only on an `ok` answer. Without a
/// ground in both models, or with fewer than 100 points tested a side, it cannot judge, and the
/// answer is `ambiguous` too (findings.free_space_unjudged): `ok` is what every check vouched for.
/// Adds the "free_space" timing; verify_registration calls it last.
void check_free_space(RegistrationResult& result, const PointCloud& source, const PointCloud& target,
                      const RangeImage& source_image, const RangeImage& target_image, const AmbiguityOptions& options);

/// A ground whose normal lies within this of its extraction's up axis is level enough for
/// check_ground_agreement and for the refinement's weighed tilt (grounds_level), degrees. The
/// grounds of the tuning sets lie within 0.91 deg of the up axis `auto` measured (every tenth pair
/// of each of the five sets, 300 scans); a 3DTK scan's ground region, a ramp, 8.9 deg off it.
inline constexpr double kLevelGroundDegrees = 3.0;

/// Whether both models have a ground within kLevelGroundDegrees of their extraction's up axis
/// (`options.source_extraction.up`, `options.target_extraction.up`): two scanners standing on level
/// ground, whose grounds agree under the truth.
bool grounds_level(const SceneModel& source, const SceneModel& target, const RegistrationOptions& options);

/// Checks that an `ok` answer lays the source's ground on the target's (beyond the paper): both
/// scanners stood on the same ground, so under the truth two level grounds agree. An answer that
/// turns them apart by more than `options.ambiguity.ground_tilt_limit_degrees` is tilted, and
/// `ambiguous` (findings.grounds_disagree); it is kept. Runs only on an `ok` answer whose two models
/// both have a ground within kLevelGroundDegrees of their extraction's up axis: a ground region that
/// is a ramp or a bank (a 3DTK scan's leans 9 deg off its up axis) says nothing about the tilt.
/// verify_registration calls it after check_free_space.
void check_ground_agreement(RegistrationResult& result, const RegistrationOptions& options);

/// Verification after selection (register_clouds and the benchmark): crops both clouds to their
/// extraction's range limits around the sensor (the platform's own hits are not scene), leaves out
/// their isolated points (without_isolated_points, `options.ambiguity.isolation_cell`; counted in
/// result.counts), hashes the target once for every overlap, prepares both clouds once for every
/// ICP search (DenseSearchPair, when the answer is `ok` or `ambiguous`), and runs check_overlap.
/// An `ok` answer is then refined by ICP (refine_answer, when `adopt_icp_optimum`) and checked by
/// check_free_space first (each cloud's range image is made with the checks' points): one it
/// clears is done. Otherwise check_half_turn runs, then an `ambiguous` answer is settled with
/// search_weakest_direction when `options.dense_search.enabled`, started also from the poses of
/// correlate_over_ground when both models have a ground: when the best optimum beats every
/// distinct optimum's overlap by `decisive_margin` it becomes the answer, `ok`, and check_overlap
/// and check_half_turn run again on it (a half-turned rival that fits clearly better replaces it,
/// `ambiguous`); otherwise the quadric answer stands, `ambiguous`. Both searches leave out the
/// optima check_free_space would demote when `ambiguity.free_space_screens_optima`. Last,
/// check_free_space on an `ok` answer it has not judged. Adds "check_inputs", "overlap",
/// "dense_preparation", and, when they ran, "answer_refinement", "half_turn",
/// "ground_correlation", "dense_search" and "free_space" timings. `source_extraction` and `target_extraction`, when given, are the
/// extractions of the two clouds: the points they worked on (ExtractionResult::measured) are
/// taken as the checks' points when they were chosen by the checks' own range limits and
/// isolated-point rule (else the clouds are cropped and filtered here). Last, measure_answer_quality of
/// the answer on the checks' points fills fitness, inlier_rmse, correspondences (indices into
/// `source` and `target`) and information ("quality" timing).
void verify_registration(RegistrationResult& result, const PointCloud& source, const PointCloud& target,
                         const RegistrationOptions& options, const ExtractionResult* source_extraction = nullptr,
                         const ExtractionResult* target_extraction = nullptr);

/// A model's ground plane as (n, d) with n . x + d = 0, when the model has one (the form
/// measure_overlap and the searches take).
std::optional<Eigen::Vector4d> ground_plane_of(const SceneModel& model);

/// What every check of an answer measures, prepared before the answer is known: it depends on the
/// clouds and the options only (prepare_verification).
struct VerificationInputs {
  PointCloud source, target;               ///< within the extraction's range, isolated points left out
  std::vector<std::uint32_t> source_indices, target_indices;  ///< the cloud index of each of their points
  std::optional<TargetCoverage> coverage;  ///< the target hashed at measure_overlap's distance
  std::optional<DenseSearchPair> prepared; ///< both prepared for the ICP searches, when one may run
  std::optional<RangeImage> source_image, target_image;  ///< what each sensor saw, when the free-space check may run
  std::size_t source_isolated_points = 0, target_isolated_points = 0;  ///< points left out as isolated
  double inputs_ms = 0.0, preparation_ms = 0.0;  ///< time taken by the points, and by the pair and the images, ms
};

/// The checks' points (the extractions' own when chosen by the same rule), the target's hash and,
/// when `may_answer` (an `ok` or `ambiguous` answer is possible), the pair every ICP search shares
/// (DenseSearchPair, when a search or an initial guess may run) and the range images of the
/// free-space check (when it is on). The conductor makes them while the quadrics are matched.
VerificationInputs prepare_verification(const PointCloud& source, const PointCloud& target, const RegistrationOptions& options,
                                        const ExtractionResult* source_extraction, const ExtractionResult* target_extraction,
                                        bool may_answer);

/// verify_registration on inputs prepare_verification made for these clouds and options: the
/// checks, then the free-space check on the answer they leave (unless it judged that answer
/// already), then the grounds' agreement. Does not measure the answer's quality (measure_final_answer).
void verify_prepared_answer(RegistrationResult& result, const VerificationInputs& inputs, const RegistrationOptions& options);

/// Fills fitness, inlier_rmse, correspondences (indices mapped back to the clouds the inputs were
/// prepared from) and information of an `ok` or `ambiguous` answer: measure_answer_quality on the
/// checks' points with `options.quality` ("quality" timing). Other statuses leave them zero / empty.
void measure_final_answer(RegistrationResult& result, const VerificationInputs& inputs, const RegistrationOptions& options);

}  // namespace quadrix
