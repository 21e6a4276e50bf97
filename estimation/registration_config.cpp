// Registration presets, the table of YAML configuration keys and the `auto` preset (see
// registration_config.h).
#include "estimation/registration_config.h"

#include "fitting/quadric_fitter.h"
#include "geometry/constants.h"
#include "geometry/error.h"
#include "geometry/voxel_cells.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <tbb/parallel_invoke.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <iterator>
#include <stdexcept>
#include <sstream>
#include <tuple>
#include <type_traits>
#include <unordered_map>

namespace quadrix {
namespace {

// The registration fields a preset sets beyond its sensor's extraction, only where they differ
// from the paper's defaults. The extraction differences (the released per-sensor parameters of
// REFERENCE.md "Extraction parameters per sensor", range limits, static-scan shape detection) are
// extraction_preset's, beside ExtractionOptions in fitting/extraction.cpp.
void apply_registration_differences(const std::string& preset, RegistrationOptions& options) {
  if (preset == "monument") {
    // Static scans model CGAL-detected shapes of a known type: the constrained fitter keeps that
    // type and fits all its points (the monument's drum: radius 21.65 m), where the statistical
    // fitter's moments of a partial arc are far off (16.1 m).
    options.modelling.fitter = "constrained";
    // Its stations are merged into one cloud: no single sensor saw it, so it has no free space of
    // one sensor to check.
    options.ambiguity.free_space_limit = -1.0;
  }
  if (preset == "airborne") {
    // As for the monument: CGAL-detected planes fitted whole by the constrained fitter, and flight
    // strips merged into one cloud with no single sensor position.
    options.modelling.fitter = "constrained";
    options.ambiguity.free_space_limit = -1.0;
  }
  // vlp64, vlp16, mid360, avia: the paper's registration defaults. The sparse and forward-looking
  // sensors' wrong answers (a street's mirror image, a shift along it) that once needed their own
  // margins are the free-space check's (AmbiguityOptions::free_space_limit).
}

// The extraction of `side`.
ExtractionOptions& extraction_of(RegistrationOptions& options, ConfigSide side) {
  return side == ConfigSide::Source ? options.source_extraction : options.target_extraction;
}

// The member options.*chain[0].*chain[1]... of a chain of pointers to members.
template <auto... chain>
RegistrationConfigMember shared_member(RegistrationOptions& options, ConfigSide /*side*/) {
  return &(options .* ... .* chain);
}

// The member extraction_of(options, side).*chain[0].*chain[1]...
template <auto... chain>
RegistrationConfigMember extraction_member(RegistrationOptions& options, ConfigSide side) {
  return &(extraction_of(options, side) .* ... .* chain);
}

// A key of a member shared by both sides (modelling, matching, estimation ...).
template <auto... chain>
RegistrationConfigKey shared_key(const char* path, const char* description,
                                 std::vector<std::string> (*choices)() = nullptr) {
  return {path, description, false, &shared_member<chain...>, choices};
}

// A key of a member of each side's extraction.
template <auto... chain>
RegistrationConfigKey extraction_key(const char* path, const char* description,
                                     std::vector<std::string> (*choices)() = nullptr) {
  return {path, description, true, &extraction_member<chain...>, choices};
}

constexpr const char* kSensorKey = "sensor";  // restarts the extraction from that preset before the other keys

std::vector<RegistrationConfigKey> make_registration_config_keys() {
  using G = GroundCorrelationOptions;
  using E = ExtractionOptions;
  using R = RegistrationOptions;
  return {
      extraction_key<&E::preset>(kSensorKey, "sensor preset the extraction restarts from before the other keys apply",
                                 registration_preset_names),
      // extraction (per side)
      extraction_key<&E::minimum_range>("extraction.minimum_range", "points nearer the sensor are dropped, m"),
      extraction_key<&E::maximum_range>("extraction.maximum_range", "points farther away are dropped, m (0: unlimited)"),
      extraction_key<&E::isolation_cell>("extraction.isolation_cell", "points in range with no other point in their cube of this edge or the 26 around are left out before modelling, m (0: every point kept)"),
      extraction_key<&E::isolation_neighbours>("extraction.isolation_neighbours", "a point in range is left out before modelling when fewer than this many other points lie in its isolation cube or the 26 around (at least 1)"),
      extraction_key<&E::ground_class>("extraction.ground_class", "static scans: points of this class (a LAS file's ASPRS classification, 2: ground) are the ground, where the file has them (-1: the lowest large horizontal plane always)"),
      extraction_key<&E::static_scan>("extraction.static_scan", "CGAL Efficient RANSAC shapes instead of the LiDAR pipeline (static scans)"),
      extraction_key<&E::up>("extraction.up", "up axis of the cloud, unitless (normalised when read)"),
      extraction_key<&E::ground, &GroundOptions::inlier_distance>("extraction.ground.inlier_distance", "point-to-patch-plane distance of ground points, m"),
      extraction_key<&E::ground, &GroundOptions::max_slope_deg>("extraction.ground.max_slope_deg", "ground patch normal at most this far from up, degrees"),
      extraction_key<&E::ground, &GroundOptions::max_step_height>("extraction.ground.max_step_height", "height jump allowed between neighbouring ground patches, m"),
      extraction_key<&E::planes, &PlaneOptions::voxel_size>("extraction.planes.voxel_size", "plane voxel edge, m"),
      extraction_key<&E::planes, &PlaneOptions::merge_distance>("extraction.planes.merge_distance", "centroid-to-plane distance for merging planar voxels, m"),
      extraction_key<&E::planes, &PlaneOptions::normal_cosine>("extraction.planes.normal_cosine", "|cos| between the normals of merged voxels, unitless"),
      extraction_key<&E::planes, &PlaneOptions::eigenvalue_ratio>("extraction.planes.eigenvalue_ratio", "lambda_2 / lambda_1 above which a voxel is planar, unitless"),
      extraction_key<&E::planes, &PlaneOptions::minimum_plane_points>("extraction.planes.minimum_plane_points", "planes with fewer points go back to clustering, points"),
      extraction_key<&E::planes, &PlaneOptions::cluster_plane_width>("extraction.planes.cluster_plane_width", "minimum width of a wall found inside a cluster, m"),
      extraction_key<&E::planes, &PlaneOptions::cluster_plane_area>("extraction.planes.cluster_plane_area", "minimum area of a wall found inside a cluster, m^2"),
      extraction_key<&E::trunks, &TrunkOptions::enabled>("extraction.trunks.enabled", "separate trunks from their crowns in every cluster"),
      extraction_key<&E::trunks, &TrunkOptions::maximum_radius>("extraction.trunks.maximum_radius", "stem points lie within this horizontal distance of its centre line, m"),
      extraction_key<&E::trunks, &TrunkOptions::minimum_height>("extraction.trunks.minimum_height", "a stem is at least this tall, m"),
      extraction_key<&E::trunks, &TrunkOptions::crownless_minimum_radius>("extraction.trunks.crownless_minimum_radius", "an upright line at least this thick across the view is a trunk without a crown, m (0: off)"),
      extraction_key<&E::trunks, &TrunkOptions::crownless_slice_points>("extraction.trunks.crownless_slice_points", "a stem slice is measured only with at least this many points, points"),
      extraction_key<&E::trunks, &TrunkOptions::crownless_top_tolerance_deg>("extraction.trunks.crownless_top_tolerance_deg", "a crownless stem's top lies within this elevation of the top of the view, degrees"),
      extraction_key<&E::stems, &StemOptions::enabled>("extraction.stems.enabled", "look for trunks and poles standing inside clusters"),
      extraction_key<&E::stems, &StemOptions::slice_height>("extraction.stems.slice_height", "height of a stem-search slice, m"),
      extraction_key<&E::stems, &StemOptions::maximum_radius>("extraction.stems.maximum_radius", "a stem section's points lie within this of its centre, m"),
      extraction_key<&E::stems, &StemOptions::isolation_radius>("extraction.stems.isolation_radius", "a stem section has at most one other slice point within this, m"),
      extraction_key<&E::stems, &StemOptions::minimum_span>("extraction.stems.minimum_span", "a stem spans at least this height, m"),
      extraction_key<&E::stems, &StemOptions::minimum_top>("extraction.stems.minimum_top", "a stem reaches at least this high above its cluster's foot, m"),
      extraction_key<&E::stems, &StemOptions::minimum_sections>("extraction.stems.minimum_sections", "a stem has at least this many sections, sections"),
      extraction_key<&E::clusters, &ClusterOptions::radius>("extraction.clusters.radius", "points closer than this join one cluster, m"),
      extraction_key<&E::clusters, &ClusterOptions::minimum_points>("extraction.clusters.minimum_points", "smaller clusters are dropped, points"),
      extraction_key<&E::clusters, &ClusterOptions::maximum_points>("extraction.clusters.maximum_points", "larger clusters are dropped, points"),
      extraction_key<&E::clusters, &ClusterOptions::maximum_extent>("extraction.clusters.maximum_extent", "clusters with a larger bounding-box diagonal are dropped, m"),
      extraction_key<&E::lines, &LineOptions::inlier_distance>("extraction.lines.inlier_distance", "point-to-line distance of RANSAC inliers, m"),
      extraction_key<&E::lines, &LineOptions::minimum_points>("extraction.lines.minimum_points", "inliers a line needs, points"),
      extraction_key<&E::lines, &LineOptions::minimum_length>("extraction.lines.minimum_length", "extent of the inliers along the line, m"),
      extraction_key<&E::shapes, &ShapeDetectionOptions::simplification_voxel>("extraction.shapes.simplification_voxel", "grid simplification before normals (static scans), m (0: off)"),
      extraction_key<&E::shapes, &ShapeDetectionOptions::epsilon>("extraction.shapes.epsilon", "maximum point-to-shape distance, m"),
      extraction_key<&E::shapes, &ShapeDetectionOptions::cluster_epsilon>("extraction.shapes.cluster_epsilon", "maximum distance between connected points of a shape, m"),
      extraction_key<&E::shapes, &ShapeDetectionOptions::minimum_points>("extraction.shapes.minimum_points", "smallest shape, points"),
      extraction_key<&E::shapes, &ShapeDetectionOptions::normal_threshold>("extraction.shapes.normal_threshold", "minimum |cos| between a point's normal and its shape's, unitless"),
      // modelling
      shared_key<&R::modelling, &ModellingOptions::fitter>("modelling.fitter", "QuadricFitter registry name", quadric_fitter_names),
      shared_key<&R::modelling, &ModellingOptions::quadrics_per_class>("modelling.quadrics_per_class", "K_e: quadrics kept per semantic class, quadrics (paper 50)"),
      shared_key<&R::modelling, &ModellingOptions::augmentation_threshold>("modelling.augmentation_threshold", "delta_a: augment below this many quadrics, quadrics (paper 60)"),
      shared_key<&R::modelling, &ModellingOptions::augmented_elements_per_class>("modelling.augmented_elements_per_class", "K_a: largest elements per class down-sampled into points, elements (paper 10)"),
      shared_key<&R::modelling, &ModellingOptions::augmentation_voxel>("modelling.augmentation_voxel", "v_a: voxel of the augmentation down-sampling, m (paper 0.5)"),
      shared_key<&R::modelling, &ModellingOptions::maximum_augmented_points>("modelling.maximum_augmented_points", "cap on augmented points, evenly strided, points (0: none)"),
      // matching
      shared_key<&R::correspondences, &CorrespondenceOptions::top_k_similar>("matching.top_k_similar", "K_s: candidates kept per element in each direction, candidates (paper 20)"),
      shared_key<&R::correspondences, &CorrespondenceOptions::match_augmented_points>("matching.match_augmented_points", "match augmented points by FPFH"),
      shared_key<&R::graphs, &CompatibilityGraphOptions::thresholds>("matching.thresholds", "delta_m of each compatibility-graph level, non-negative and strictly ascending, m"),
      shared_key<&R::clique_time_limit_ms>("matching.clique_time_limit_ms", "deadline of the whole graduated clique search, ms"),
      shared_key<&R::clique_threads>("matching.clique_threads", "threads of the clique solver, threads (0: hardware concurrency)"),
      // estimation
      shared_key<&R::estimation, &EstimationOptions::refiner>("estimation.refiner", "refiner backend (LMOptimizer of Algorithm 1)", refiner_names),
      shared_key<&R::estimation, &EstimationOptions::refinement, &RefinerOptions::max_iterations>("estimation.max_iterations", "LM iterations, iterations (published 300)"),
      shared_key<&R::estimation, &EstimationOptions::refinement, &RefinerOptions::function_tolerance>("estimation.function_tolerance", "stop when |dF| / F is below this, unitless (published 1e-8)"),
      shared_key<&R::estimation, &EstimationOptions::manhattan_tolerance_degrees>("estimation.manhattan_tolerance_degrees", "delta_g of f_pp in refinement, degrees (published 10)"),
      shared_key<&R::estimation, &EstimationOptions::augment_non_central>("estimation.augment_non_central", "Augment() of Algorithm 1: samples on linear and planar centres"),
      shared_key<&R::estimation, &EstimationOptions::use_ground_constraint>("estimation.use_ground_constraint", "add the ground plane-to-plane factor when both clouds have a ground"),
      shared_key<&R::estimation, &EstimationOptions::ground_weight>("estimation.ground_weight", "weight of the ground factor, unitless"),
      shared_key<&R::estimation, &EstimationOptions::level_ground_lever_arm>("estimation.level_ground_lever_arm_m", "with both grounds level, the ground factor's tilt residual is multiplied by this: a tilt costs what lifting a ground point this far out does, metres (1: unscaled)"),
      shared_key<&R::estimation, &EstimationOptions::minimum_inliers>("estimation.minimum_inliers", "a candidate needs at least this many clique correspondences, correspondences (paper 3)"),
      // selection
      shared_key<&R::selection, &SelectionOptions::dcs_phi>("selection.dcs_phi", "Phi of the DCS kernel of the candidate score, unitless (published 0.5)"),
      shared_key<&R::selection, &SelectionOptions::manhattan_tolerance_degrees>("selection.manhattan_tolerance_degrees", "delta_g^e of f_pp in selection, degrees (published 5)"),
      // ambiguity
      shared_key<&R::ambiguity, &AmbiguityOptions::score_ratio>("ambiguity.score_ratio", "best / second-best score above this counts as close, unitless"),
      shared_key<&R::ambiguity, &AmbiguityOptions::translation_disagreement>("ambiguity.translation_disagreement", "candidates farther apart than this disagree, m"),
      shared_key<&R::ambiguity, &AmbiguityOptions::rotation_disagreement_degrees>("ambiguity.rotation_disagreement_degrees", "or rotated more than this apart, degrees"),
      shared_key<&R::ambiguity, &AmbiguityOptions::minimum_clique_for_ok>("ambiguity.minimum_clique_for_ok", "a winner supported by a smaller clique is ambiguous, correspondences"),
      shared_key<&R::ambiguity, &AmbiguityOptions::overlap_margin>("ambiguity.overlap_margin", "an ok answer overlapping less than the unmoved source by more than this is ambiguous, fraction (0: it must beat not moving; negative: no check)"),
      shared_key<&R::ambiguity, &AmbiguityOptions::minimum_overlap>("ambiguity.minimum_overlap", "an ok answer landing less than this fraction of the source within 0.3 m of the target is ambiguous, fraction (0: no floor)"),
      shared_key<&R::ambiguity, &AmbiguityOptions::isolation_cell>("ambiguity.isolation_cell", "the checks leave out points with no other point in their cube of this edge or the 26 around it, m (0: keep every point)"),
      shared_key<&R::ambiguity, &AmbiguityOptions::isolation_neighbours>("ambiguity.isolation_neighbours", "the checks leave out points with fewer than this many other points in their isolation cube or the 26 around (at least 1)"),
      shared_key<&R::ambiguity, &AmbiguityOptions::confirm_below>("ambiguity.confirm_below", "an ok answer landing less than this fraction of the source is ok only once the dense search settles it, fraction (0: off)"),
      shared_key<&R::ambiguity, &AmbiguityOptions::confirm_over_identity>("ambiguity.confirm_over_identity", "an ok answer landing less than this fraction of the source more than the unmoved source is ok only once the dense search settles it (0: off)"),
      shared_key<&R::ambiguity, &AmbiguityOptions::half_turn_margin>("ambiguity.half_turn_margin", "an ok answer must out-overlap the best optimum reached from its half turn about the up axis by this, fraction (negative: no check)"),
      shared_key<&R::ambiguity, &AmbiguityOptions::half_turn_ok_margin>("ambiguity.half_turn_ok_margin", "an ok answer must also out-overlap its half turn's best rival by this, else ambiguous (the answer is kept), fraction"),
      shared_key<&R::ambiguity, &AmbiguityOptions::adopt_icp_optimum>("ambiguity.adopt_icp_optimum", "an answer that passes the half-turn check becomes the point-to-plane ICP optimum reached from it"),
      shared_key<&R::ambiguity, &AmbiguityOptions::half_turn_samples>("ambiguity.half_turn_samples", "source points the half-turn check's ICP aligns, points (>= 6)"),
      shared_key<&R::ambiguity, &AmbiguityOptions::half_turn_votes>("ambiguity.half_turn_votes", "ICP also starts from the turned rotation at this many translations the quadrics vote for, starts"),
      shared_key<&R::ambiguity, &AmbiguityOptions::half_turn_correlation_starts>("ambiguity.half_turn_correlation_starts", "ICP also starts from the turned rotation at this many translations that land the most source points in occupied target space, starts"),
      shared_key<&R::ambiguity, &AmbiguityOptions::half_turn_correlation_reach>("ambiguity.half_turn_correlation_reach", "how far along the ground those translations are searched from the turned answer's, m"),
      shared_key<&R::ambiguity, &AmbiguityOptions::free_space_limit>("ambiguity.free_space_limit", "an ok answer may put at most this share of each scan's high points in the other sensor's free space, both shares summed, else ambiguous (the answer is kept; negative: no check; clouds in their sensors' frames)"),
      shared_key<&R::ambiguity, &AmbiguityOptions::free_space_screens_optima>("ambiguity.free_space_screens_optima", "the dense search and the half-turn check leave out of their best and their rivals every refined optimum the free-space check would demote"),
      shared_key<&R::ambiguity, &AmbiguityOptions::free_space_height>("ambiguity.free_space_height", "the free-space check tests points standing more than this above their scan's ground, m (>= 0)"),
      shared_key<&R::ambiguity, &AmbiguityOptions::ground_tilt_limit_degrees>("ambiguity.ground_tilt_limit_deg", "an ok answer may turn the source's ground at most this far from the target's, else ambiguous (the answer is kept; negative: no check), degrees"),
      // dense_search
      shared_key<&R::dense_search, &DenseSearchOptions::enabled>("dense_search.enabled", "settle ambiguous answers with the dense search along the weakest direction"),
      shared_key<&R::dense_search, &DenseSearchOptions::voxel_size>("dense_search.voxel_size", "both clouds thinned to one point per cube of this edge, m (> 0)"),
      shared_key<&R::dense_search, &DenseSearchOptions::source_samples>("dense_search.source_samples", "source points ICP aligns, points (>= 6)"),
      shared_key<&R::dense_search, &DenseSearchOptions::normal_neighbours>("dense_search.normal_neighbours", "target neighbours of each normal's plane fit, points (>= 3)"),
      shared_key<&R::dense_search, &DenseSearchOptions::correspondence_distance>("dense_search.correspondence_distance", "ICP drops pairs farther apart than this, m (> 0)"),
      shared_key<&R::dense_search, &DenseSearchOptions::iterations>("dense_search.iterations", "point-to-plane Gauss-Newton iterations per start, iterations"),
      shared_key<&R::dense_search, &DenseSearchOptions::step>("dense_search.step", "spacing of the starts along the weakest direction, m (> 0)"),
      shared_key<&R::dense_search, &DenseSearchOptions::range>("dense_search.range", "the starts reach this far either side of the answer along it, m (>= 0)"),
      shared_key<&R::dense_search, &DenseSearchOptions::across_step>("dense_search.across_step", "spacing of the starts across the weakest direction, m (> 0)"),
      shared_key<&R::dense_search, &DenseSearchOptions::across_range>("dense_search.across_range", "the starts reach this far either side of the answer across it, m (>= 0)"),
      shared_key<&R::dense_search, &DenseSearchOptions::range_with_correlation>("dense_search.range_with_correlation", "when the correlation over the ground gave poses, the starts reach only this far along the weakest direction, m (>= 0)"),
      shared_key<&R::dense_search, &DenseSearchOptions::step_with_correlation>("dense_search.step_with_correlation", "when the correlation over the ground gave poses, spacing of the starts along the weakest direction, m (> 0)"),
      shared_key<&R::dense_search, &DenseSearchOptions::across_range_with_correlation>("dense_search.across_range_with_correlation", "when the correlation over the ground gave poses, the starts reach this far either side of the answer across it, m (>= 0)"),
      shared_key<&R::dense_search, &DenseSearchOptions::refine_band>("dense_search.refine_band", "optima within this overlap of the best are refined on all samples, fraction (>= 0)"),
      shared_key<&R::dense_search, &DenseSearchOptions::max_refined>("dense_search.max_refined", "at most this many optima refined, optima (>= 1)"),
      shared_key<&R::dense_search, &DenseSearchOptions::minimum_overlap>("dense_search.minimum_overlap", "a settled answer puts at least this fraction of the source on the target, fraction (0..1)"),
      shared_key<&R::dense_search, &DenseSearchOptions::decisive_margin>("dense_search.decisive_margin", "the winner's overlap beats every distinct optimum's by this, fraction (>= 0)"),
      shared_key<&R::dense_search, &DenseSearchOptions::ok_margin>("dense_search.ok_margin", "a settled winner beats every distinct optimum by this to be ok, else ambiguous (the answer is kept), fraction (>= 0)"),
      shared_key<&R::dense_search, &DenseSearchOptions::correlation, &G::poses>("dense_search.correlation.poses", "ICP also starts from this many poses of the correlation over yaw and ground translation, poses (0: none)"),
      shared_key<&R::dense_search, &DenseSearchOptions::correlation, &G::reach>("dense_search.correlation.reach", "translations searched within this of not moving, along the ground, m (> 0)"),
      shared_key<&R::dense_search, &DenseSearchOptions::correlation, &G::yaw_step_degrees>("dense_search.correlation.yaw_step_degrees", "spacing of the yaws searched over a full turn, degrees (0..180]"),
      shared_key<&R::dense_search, &DenseSearchOptions::correlation, &G::coarse_cell>("dense_search.correlation.coarse_cell", "cell edge of the first pass over every yaw and translation, m (> 0)"),
      shared_key<&R::dense_search, &DenseSearchOptions::correlation, &G::fine_cell>("dense_search.correlation.fine_cell", "cell edge of the second pass around the best coarse poses, m (> 0)"),
      shared_key<&R::dense_search, &DenseSearchOptions::correlation, &G::minimum_height>("dense_search.correlation.minimum_height", "points lower than this above their ground are left out, m"),
      shared_key<&R::dense_search, &DenseSearchOptions::correlation, &G::maximum_height>("dense_search.correlation.maximum_height", "points higher than this above their ground are left out, m (> minimum_height)"),
      shared_key<&R::dense_search, &DenseSearchOptions::correlation, &G::separation>("dense_search.correlation.separation", "poses closer than this in translation to a better one (and within separation_degrees) are not reported, m (>= 0)"),
      shared_key<&R::dense_search, &DenseSearchOptions::correlation, &G::separation_degrees>("dense_search.correlation.separation_degrees", "poses closer than this in yaw to a better one (and within separation) are not reported, degrees (>= 0)"),
      shared_key<&R::quality, &AnswerQualityOptions::correspondence_distance>("quality.correspondence_distance", "a source point with a target point within this after the answer is an inlier (fitness, inlier RMSE, correspondences, information), m (> 0)"),
      shared_key<&R::quality, &AnswerQualityOptions::normal_neighbours>("quality.normal_neighbours", "target points of each inlier's normal fit (information), points (>= 3)"),
      shared_key<&R::initial_guess_reach>("initial_guess_reach", "ICP from an initial guess first pairs points up to this far apart, then halves it down to dense_search.correspondence_distance, m (> 0)"),
  };
}

// The valid range of every number, integer and list key: [minimum, maximum], and whether 0 (the
// key's documented "off") is also valid. Three kinds of bound:
//  - sense: a length, angle or fraction outside what the quantity can mean (angles beyond 90 deg
//    from up, fractions beyond 1, lengths beyond a kilometre of scene) or a positive length so small
//    (below 1-5 cm, under any scanner's noise) that a far point's cell index leaves the range of the
//    integers the voxel hashes use;
//  - work: every value that sets an amount of work (neighbours, iterations, samples, starts, poses,
//    reaches over cell sizes, list lengths) is capped near ten times its default, so a run stays
//    within minutes whatever the file says (dense_search.normal_neighbours 10,000 took over 120 s,
//    dense_search.iterations 2^31 over 18 minutes; half_turn_samples 2^63 asked for 2^63 points);
//  - verification: a threshold of the checks that decide `ok` cannot be set where it silently stops
//    checking. The documented off values (a negative margin or limit, a zero floor) stay valid, and
//    `quadrix register` names every check they switch off; values beyond them that would switch a
//    check off without saying so are refused. The translation and rotation beyond which two answers
//    disagree are capped at the success rule (2 m, 5 deg): two answers farther apart cannot both be
//    right, so counting them as agreeing hides a rival. A winning clique keeps its floor of 5: 3 or 4
//    mutually consistent pairs arise by chance among hundreds, and 3 is every candidate. The dense search's ICP pairs at most 1 m
//    apart: at 2 m an optimum's basin swallowed its rivals and a 3DTK pair came out `ok` 1.46 m
//    and 6.7 deg off (docs/reliability.md). Its settled answer keeps a floor of 0.35 and a margin of
//    0.01 (wrong settles measured 0.23-0.33 of the source on the target, right ones 0.44-0.79; a
//    margin of 0 lets a tie settle). The best/second score ratio stays below 1: the best score is the
//    lowest, so a ratio of 1 or more can never be exceeded and the close-scores finding would vanish.
struct KeyRange {
  const char* path;
  double minimum;
  double maximum;
  bool zero_allowed;
};

constexpr double kIntLimit = 2147483647.0;  // integers only need to fit an int (options that count points)

constexpr KeyRange kKeyRanges[] = {
    {"extraction.minimum_range", 0.0, 1000.0, false},
    {"extraction.maximum_range", 0.1, 1e5, true},
    {"extraction.isolation_cell", 0.01, 100.0, true},
    {"extraction.isolation_neighbours", 1.0, 1000.0, false},
    {"extraction.ground_class", -1.0, 255.0, false},  // ASPRS classes are 0..255; -1 is off
    {"extraction.ground.inlier_distance", 0.001, 10.0, false},
    {"extraction.ground.max_slope_deg", 0.0, 90.0, false},
    {"extraction.ground.max_step_height", 0.0, 100.0, false},
    {"extraction.planes.voxel_size", 0.05, 100.0, false},
    {"extraction.planes.merge_distance", 0.0, 100.0, false},
    {"extraction.planes.normal_cosine", 0.0, 1.0, false},
    {"extraction.planes.eigenvalue_ratio", 1.0, 1e9, false},
    {"extraction.planes.minimum_plane_points", 1.0, kIntLimit, false},
    {"extraction.planes.cluster_plane_width", 0.0, 1000.0, false},
    {"extraction.planes.cluster_plane_area", 0.0, 1e6, false},
    {"extraction.trunks.maximum_radius", 0.01, 100.0, false},
    {"extraction.trunks.minimum_height", 0.0, 1000.0, false},
    {"extraction.trunks.crownless_minimum_radius", 0.0, 100.0, false},
    {"extraction.trunks.crownless_slice_points", 1.0, 1e6, false},
    {"extraction.trunks.crownless_top_tolerance_deg", 0.0, 90.0, false},
    {"extraction.stems.slice_height", 0.05, 100.0, false},
    {"extraction.stems.maximum_radius", 0.01, 100.0, false},
    {"extraction.stems.isolation_radius", 0.0, 100.0, false},
    {"extraction.stems.minimum_span", 0.0, 1000.0, false},
    {"extraction.stems.minimum_top", 0.0, 1000.0, false},
    {"extraction.stems.minimum_sections", 1.0, 1e6, false},
    {"extraction.clusters.radius", 0.05, 100.0, false},
    {"extraction.clusters.minimum_points", 1.0, kIntLimit, false},
    {"extraction.clusters.maximum_points", 1.0, kIntLimit, false},
    {"extraction.clusters.maximum_extent", 0.01, 1e5, false},
    {"extraction.lines.inlier_distance", 0.001, 10.0, false},
    {"extraction.lines.minimum_points", 2.0, kIntLimit, false},
    {"extraction.lines.minimum_length", 0.0, 1e4, false},
    {"extraction.shapes.simplification_voxel", 0.001, 10.0, true},
    {"extraction.shapes.epsilon", 0.001, 10.0, false},
    {"extraction.shapes.cluster_epsilon", 0.001, 100.0, false},
    {"extraction.shapes.minimum_points", 10.0, kIntLimit, false},
    {"extraction.shapes.normal_threshold", 0.0, 1.0, false},
    {"modelling.quadrics_per_class", 0.0, 1000.0, false},
    {"modelling.augmentation_threshold", 0.0, 100000.0, false},
    {"modelling.augmented_elements_per_class", 0.0, 1000.0, false},
    {"modelling.augmentation_voxel", 0.05, 100.0, false},
    {"modelling.maximum_augmented_points", 1.0, 20000.0, false},
    {"matching.top_k_similar", 1.0, 100.0, false},
    {"matching.thresholds", 0.0, 10.0, false},
    {"matching.clique_time_limit_ms", 1.0, 600000.0, false},
    {"matching.clique_threads", 0.0, 64.0, false},
    {"estimation.max_iterations", 1.0, 10000.0, false},
    {"estimation.function_tolerance", 0.0, 1.0, false},
    {"estimation.manhattan_tolerance_degrees", 0.0, 90.0, false},
    {"estimation.ground_weight", 0.0, 1e6, false},
    {"estimation.level_ground_lever_arm_m", 0.001, 1e6, false},
    {"estimation.minimum_inliers", 3.0, 1000.0, false},
    {"selection.dcs_phi", 1e-6, 1e6, false},
    {"selection.manhattan_tolerance_degrees", 0.0, 90.0, false},
    {"ambiguity.score_ratio", 0.0, 0.99, false},
    {"ambiguity.translation_disagreement", 0.01, 2.0, false},
    {"ambiguity.rotation_disagreement_degrees", 0.01, 5.0, false},
    {"ambiguity.minimum_clique_for_ok", 5.0, 10000.0, false},
    {"ambiguity.overlap_margin", -1.0, 1.0, false},
    {"ambiguity.minimum_overlap", 0.0, 1.0, false},
    {"ambiguity.isolation_cell", 0.01, 100.0, true},
    {"ambiguity.isolation_neighbours", 1.0, 1000.0, false},
    {"ambiguity.confirm_below", 0.0, 1.0, false},
    {"ambiguity.confirm_over_identity", 0.0, 1.0, false},
    {"ambiguity.half_turn_margin", -1.0, 1.0, false},
    {"ambiguity.half_turn_ok_margin", -1.0, 1.0, false},
    {"ambiguity.half_turn_samples", 6.0, 20000.0, false},
    {"ambiguity.half_turn_votes", 0.0, 64.0, false},
    {"ambiguity.half_turn_correlation_starts", 0.0, 64.0, false},
    {"ambiguity.half_turn_correlation_reach", 0.0, 100.0, false},
    {"ambiguity.free_space_limit", -1.0, 1.0, false},
    {"ambiguity.free_space_height", 0.0, 100.0, false},
    {"ambiguity.ground_tilt_limit_deg", -1.0, 45.0, false},
    {"dense_search.voxel_size", 0.02, 10.0, false},
    {"dense_search.source_samples", 6.0, 20000.0, false},
    {"dense_search.normal_neighbours", 3.0, 50.0, false},
    {"dense_search.correspondence_distance", 0.05, 1.0, false},
    // The back end's measures of an answer (no status depends on them): a pairing distance within a
    // scene's size, and the normal fit's neighbours capped like the dense search's (work).
    {"quality.correspondence_distance", 0.01, 10.0, false},
    {"quality.normal_neighbours", 3.0, 50.0, false},
    // ICP from an initial guess halves its pairing distance from here down to the dense search's:
    // at most 100 m (a dozen halvings), at least 5 cm (under it no pair is found).
    {"initial_guess_reach", 0.05, 100.0, false},
    {"dense_search.iterations", 1.0, 100.0, false},
    {"dense_search.step", 0.05, 100.0, false},
    {"dense_search.range", 0.0, 100.0, false},
    {"dense_search.across_step", 0.05, 100.0, false},
    {"dense_search.across_range", 0.0, 100.0, false},
    {"dense_search.range_with_correlation", 0.0, 100.0, false},
    {"dense_search.step_with_correlation", 0.05, 100.0, false},
    {"dense_search.across_range_with_correlation", 0.0, 100.0, false},
    {"dense_search.refine_band", 0.0, 1.0, false},
    {"dense_search.max_refined", 1.0, 64.0, false},
    {"dense_search.minimum_overlap", 0.35, 1.0, false},
    {"dense_search.decisive_margin", 0.01, 1.0, false},
    {"dense_search.ok_margin", 0.0, 1.0, false},
    {"dense_search.correlation.poses", 0.0, 32.0, false},
    {"dense_search.correlation.reach", 1.0, 100.0, false},
    {"dense_search.correlation.yaw_step_degrees", 1.0, 180.0, false},
    {"dense_search.correlation.coarse_cell", 0.5, 20.0, false},
    {"dense_search.correlation.fine_cell", 0.1, 20.0, false},
    {"dense_search.correlation.minimum_height", -10.0, 100.0, false},
    {"dense_search.correlation.maximum_height", -10.0, 1000.0, false},
    {"dense_search.correlation.separation", 0.0, 100.0, false},
    {"dense_search.correlation.separation_degrees", 0.0, 180.0, false},
};

std::string number_text(double value);

// A value quoted in an error message: at most `shown` characters of it (a 100 MB string is not echoed).
std::string excerpt(const std::string& text, std::size_t shown = 40) {
  if (text.size() <= shown) return text;
  return text.substr(0, shown) + "... (" + std::to_string(text.size()) + " characters)";
}

// The number a ranged member holds, for the range check.
bool outside_range(const RegistrationConfigKey& key, double value) {
  if (key.zero_allowed && value == 0.0) return false;
  return !(value >= key.minimum && value <= key.maximum);
}

// Reads one scalar of type T at `key`, naming the file and key on a type error. Numbers must be
// finite: YAML's .inf and .nan mean nothing to any option (and would not be written back as YAML).
template <typename T>
T scalar(const YAML::Node& node, const std::string& file, const std::string& key) {
  if (!node.IsScalar()) throw file_error(file, "key '" + key + "' must be a scalar");
  T value;
  try {
    value = node.as<T>();
  } catch (const YAML::Exception&) {
    throw file_error(file, "key '" + key + "' has an invalid value '" + excerpt(node.Scalar()) + "'");
  }
  if constexpr (std::is_floating_point_v<T>) {
    if (!std::isfinite(value))
      throw file_error(file, "key '" + key + "' must be a finite number, got '" + excerpt(node.Scalar()) + "'");
  }
  return value;
}

// The names in `names`, comma separated.
std::string joined(const std::vector<std::string>& names, const char* separator = ", ") {
  std::string text;
  for (const std::string& name : names) text += (text.empty() ? "" : separator) + name;
  return text;
}

// Reads `node` into the member of `key` (the YAML form its type decides; see registration_config_schema).
void read_member(const YAML::Node& node, const RegistrationConfigKey& key, const RegistrationConfigMember& member,
                 const std::string& file) {
  std::visit(
      [&](auto* target) {
        using T = std::remove_pointer_t<decltype(target)>;
        if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
          if (!node.IsSequence() || node.size() != 3) throw file_error(file, "key '" + key.path + "' must be a list of 3 numbers");
          Eigen::Vector3d value;
          for (int i = 0; i < 3; ++i) value[i] = scalar<double>(node[i], file, key.path);
          const double largest = value.cwiseAbs().maxCoeff();
          if (!(largest > 0.0)) throw file_error(file, "key '" + key.path + "' must not be the zero vector");
          // A unit vector is kept bit for bit; others are scaled by their largest entry first, so the
          // squared norm neither overflows (1e308) nor underflows (1e-300).
          if (std::abs(value.norm() - 1.0) > 1e-12) value = (value / largest).normalized();
          *target = value;
        } else if constexpr (std::is_same_v<T, std::vector<double>>) {
          if (!node.IsSequence() || node.size() == 0)
            throw file_error(file, "key '" + key.path + "' must be a non-empty list of numbers");
          if (node.size() > kMaxConfigListEntries)
            throw file_error(file, "key '" + key.path + "' lists " + std::to_string(node.size()) + " numbers, at most " +
                                       std::to_string(kMaxConfigListEntries) + " are allowed");
          std::vector<double> values;
          for (const auto& item : node) {
            values.push_back(scalar<double>(item, file, key.path));
            if (outside_range(key, values.back()))
              throw file_error(file, "key '" + key.path + "': entry " + number_text(values.back()) + " is outside its range " +
                                         valid_range_text(key));
          }
          for (std::size_t i = 0; i < values.size(); ++i)
            if (!(values[i] >= 0.0) || (i > 0 && values[i] <= values[i - 1]))
              throw file_error(file, "key '" + key.path + "' must be non-negative and strictly ascending");
          *target = values;
        } else {
          const T value = scalar<T>(node, file, key.path);
          if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>) {
            if (outside_range(key, static_cast<double>(value)))
              throw file_error(file, "key '" + key.path + "' must lie in " + valid_range_text(key) + ", got " +
                                         excerpt(node.Scalar()));
          }
          if constexpr (std::is_same_v<T, std::string>) {
            if (key.choices != nullptr) {
              const std::vector<std::string> valid = key.choices();
              if (std::find(valid.begin(), valid.end(), value) == valid.end())
                throw file_error(file, "key '" + key.path + "': unknown name '" + excerpt(value) + "' (expected one of: " + joined(valid) + ")");
            }
          }
          *target = value;
        }
      },
      member);
}

// The YAML text of a number: doubles as their shortest exact decimal (std::to_chars), so "0.15"
// reads back as the same double.
std::string number_text(double value) {
  std::array<char, 32> buffer{};
  const auto end = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value).ptr;
  return std::string(buffer.data(), end);
}

// Writes the value of `member` in the YAML form read_member reads.
void write_member(YAML::Emitter& out, const RegistrationConfigMember& member) {
  std::visit(
      [&out](auto* value) {
        using T = std::remove_pointer_t<decltype(value)>;
        if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
          out << YAML::Flow << YAML::BeginSeq << number_text(value->x()) << number_text(value->y())
              << number_text(value->z()) << YAML::EndSeq;
        } else if constexpr (std::is_same_v<T, std::vector<double>>) {
          out << YAML::Flow << YAML::BeginSeq;
          for (const double item : *value) out << number_text(item);
          out << YAML::EndSeq;
        } else if constexpr (std::is_same_v<T, double>) {
          out << number_text(*value);
        } else {
          out << *value;
        }
      },
      member);
}

// The type of a key as the schema prints it.
std::string type_name(const RegistrationConfigKey& key) {
  RegistrationOptions options;
  return std::visit(
      [&key](auto* value) -> std::string {
        using T = std::remove_pointer_t<decltype(value)>;
        if constexpr (std::is_same_v<T, bool>) {
          return "bool";
        } else if constexpr (std::is_same_v<T, int>) {
          return "integer";
        } else if constexpr (std::is_same_v<T, std::size_t>) {
          return "integer >= 0";
        } else if constexpr (std::is_same_v<T, double>) {
          return "number";
        } else if constexpr (std::is_same_v<T, std::string>) {
          return key.choices != nullptr ? "name" : "string";
        } else if constexpr (std::is_same_v<T, std::vector<double>>) {
          return "[number, ...]";
        } else {
          static_assert(std::is_same_v<T, Eigen::Vector3d>);
          return "[x, y, z]";
        }
      },
      key.member(options, ConfigSide::Source));
}


// Collects the keys set by the mapping `node` of the section `prefix` with their values; every name
// must be a key of the table or a section holding some (else an Error naming the key and the file).
void collect_keys(const YAML::Node& node, const std::string& prefix, const std::string& file,
                  std::vector<std::pair<const RegistrationConfigKey*, YAML::Node>>& found) {
  if (!node.IsMap()) throw file_error(file, "'" + prefix + "' must be a mapping");
  for (const auto& entry : node) {
    if (!entry.first.IsScalar()) {
      const YAML::Mark mark = entry.first.Mark();
      throw file_error(file, (mark.is_null() ? std::string() : "line " + std::to_string(mark.line + 1) + ": ") + "a key " +
                                 (prefix.empty() ? std::string("at the top level") : "in '" + prefix + "'") +
                                 " is a list, a mapping or empty; keys are names");
    }
    const std::string name = entry.first.Scalar();
    const std::string path = prefix.empty() ? name : prefix + "." + name;
    if (const RegistrationConfigKey* key = find_registration_config_key(path)) {
      found.emplace_back(key, entry.second);
    } else if (!registration_config_names_below(path).empty()) {
      collect_keys(entry.second, path, file, found);
    } else {
      throw file_error(file, "unknown key '" + excerpt(path, 80) + "' (known here: " + joined(registration_config_names_below(prefix)) + ")");
    }
  }
}

}  // namespace

std::vector<std::string> registration_preset_names() { return extraction_preset_names(); }

RegistrationOptions registration_preset(const std::string& name) {
  RegistrationOptions options;
  options.source_extraction = extraction_preset(name);  // throws for unknown names, listing the valid ones
  options.target_extraction = options.source_extraction;
  apply_registration_differences(name, options);
  return options;
}

const RegistrationConfigKey* find_registration_config_key(const std::string& path) {
  for (const RegistrationConfigKey& key : registration_config_keys())
    if (key.path == path) return &key;
  return nullptr;
}

std::vector<std::string> registration_config_names_below(const std::string& prefix) {
  std::vector<std::string> names;
  for (const RegistrationConfigKey& key : registration_config_keys()) {
    if (!prefix.empty() && key.path.rfind(prefix + ".", 0) != 0) continue;
    const std::string rest = prefix.empty() ? key.path : key.path.substr(prefix.size() + 1);
    const std::string name = rest.substr(0, rest.find('.'));
    if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
  }
  return names;
}

const std::vector<RegistrationConfigKey>& registration_config_keys() {
  static const std::vector<RegistrationConfigKey> keys = [] {
    std::vector<RegistrationConfigKey> table = make_registration_config_keys();
    RegistrationOptions options;
    for (RegistrationConfigKey& key : table) {
      key.ranged = std::visit(
          [](auto* member) {
            using T = std::remove_pointer_t<decltype(member)>;
            return std::is_same_v<T, int> || std::is_same_v<T, std::size_t> || std::is_same_v<T, double> ||
                   std::is_same_v<T, std::vector<double>>;
          },
          key.member(options, ConfigSide::Source));
      if (!key.ranged) continue;
      const auto range = std::find_if(std::begin(kKeyRanges), std::end(kKeyRanges),
                                      [&key](const KeyRange& entry) { return key.path == entry.path; });
      // Every number has a range: a key added without one is a programming error caught by any use.
      if (range == std::end(kKeyRanges)) throw std::logic_error("configuration key '" + key.path + "' has no valid range");
      key.minimum = range->minimum;
      key.maximum = range->maximum;
      key.zero_allowed = range->zero_allowed;
    }
    return table;
  }();
  return keys;
}

std::string valid_range_text(const RegistrationConfigKey& key) {
  if (!key.ranged) return {};
  return "[" + number_text(key.minimum) + ", " + number_text(key.maximum) + "]" + (key.zero_allowed ? " or 0" : "");
}

std::string registration_config_schema() {
  std::size_t path_width = 0, type_width = 0;
  for (const RegistrationConfigKey& key : registration_config_keys()) {
    path_width = std::max(path_width, key.path.size());
    type_width = std::max(type_width, type_name(key).size());
  }
  std::ostringstream text;
  text << "# Keys of the registration configuration (--config FILE.yaml), every one optional. A dotted\n"
          "# path is nested YAML: extraction.planes.voxel_size is `extraction: {planes: {voxel_size: 1.0}}`.\n"
          "# sensor and extraction.* are per side (both clouds unless a side is chosen); `sensor` restarts\n"
          "# the extraction from that preset before the other keys apply. Unknown keys are an error.\n";
  for (const RegistrationConfigKey& key : registration_config_keys()) {
    std::string path = key.path, type = type_name(key);
    path.resize(path_width, ' ');
    type.resize(type_width, ' ');
    text << path << "  " << type << "  " << key.description;
    if (key.ranged) text << "; valid " << valid_range_text(key);
    if (key.choices != nullptr) text << "; one of " << joined(key.choices(), "|");
    text << "\n";
  }
  return text.str();
}

void apply_registration_config(const std::string& path, RegistrationOptions& options, const std::string& side) {
  if (side != "both" && side != "source" && side != "target")
    throw Error("apply_registration_config: side must be both, source or target, got '" + side + "'");
  // Only a regular file of bounded size is parsed: a FIFO would block the reader, and a 100 MB
  // YAML list took 4.3 GB as nodes.
  std::error_code code;
  const std::filesystem::file_status status = std::filesystem::status(path, code);
  if (code || !std::filesystem::exists(status)) throw file_error(path, "cannot open the configuration file");
  if (!std::filesystem::is_regular_file(status))
    throw file_error(path, "the configuration is not a regular file (a directory, FIFO or device)");
  const std::uintmax_t bytes = std::filesystem::file_size(path, code);
  if (code || bytes > kMaxConfigFileBytes)
    throw file_error(path, "the configuration file holds " + std::to_string(bytes) + " bytes, more than the " +
                               std::to_string(kMaxConfigFileBytes) + " a configuration may have");
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw file_error(path, "cannot open the configuration file");
  } catch (const YAML::Exception& error) {
    throw file_error(path, "invalid YAML: " + excerpt(error.what(), 200));
  }
  if (root.IsNull()) return;  // an empty file changes nothing
  if (!root.IsMap()) throw file_error(path, "the configuration must be a mapping of sections");
  std::vector<std::pair<const RegistrationConfigKey*, YAML::Node>> found;
  collect_keys(root, "", path, found);
  std::vector<ConfigSide> sides;
  if (side != "target") sides.push_back(ConfigSide::Source);
  if (side != "source") sides.push_back(ConfigSide::Target);
  // `sensor` first: it restarts the extraction, the other keys then override it. (The entries are
  // visited in two passes, not reordered: assigning a YAML::Node rewrites the node it refers to.)
  for (const bool sensor_pass : {true, false}) {
    for (const auto& [key, node] : found) {
      if ((key->path == kSensorKey) != sensor_pass) continue;
      if (!key->per_side) {
        read_member(node, *key, key->member(options, ConfigSide::Source), path);
        continue;
      }
      for (const ConfigSide each : sides) {
        read_member(node, *key, key->member(options, each), path);
        if (sensor_pass) extraction_of(options, each) = extraction_preset(extraction_of(options, each).preset);
      }
    }
  }
  try {
    validate_dense_search_options(options.dense_search);
    if (options.ambiguity.half_turn_samples < 6)
      throw Error("ambiguity.half_turn_samples must be at least 6, got " + std::to_string(options.ambiguity.half_turn_samples));
    if (!(options.ambiguity.minimum_overlap >= 0.0 && options.ambiguity.minimum_overlap <= 1.0))
      throw Error("ambiguity.minimum_overlap must be a fraction in [0, 1], got " + std::to_string(options.ambiguity.minimum_overlap));
    if (!(options.ambiguity.isolation_cell >= 0.0 && std::isfinite(options.ambiguity.isolation_cell)))
      throw Error("ambiguity.isolation_cell must be a length >= 0 in metres, got " + std::to_string(options.ambiguity.isolation_cell));
    if (options.ambiguity.isolation_neighbours < 1)
      throw Error("ambiguity.isolation_neighbours must be at least 1, got " + std::to_string(options.ambiguity.isolation_neighbours));
    for (const ExtractionOptions* extraction : {&options.source_extraction, &options.target_extraction}) {
      if (!(extraction->isolation_cell >= 0.0 && std::isfinite(extraction->isolation_cell)))
        throw Error("extraction.isolation_cell must be a length >= 0 in metres, got " + std::to_string(extraction->isolation_cell));
      if (extraction->isolation_neighbours < 1)
        throw Error("extraction.isolation_neighbours must be at least 1, got " + std::to_string(extraction->isolation_neighbours));
    }
    if (!(options.ambiguity.free_space_height >= 0.0 && std::isfinite(options.ambiguity.free_space_height)))
      throw Error("ambiguity.free_space_height must be a height >= 0 in metres, got " + std::to_string(options.ambiguity.free_space_height));
    if (!(options.ambiguity.confirm_below >= 0.0 && options.ambiguity.confirm_below <= 1.0))
      throw Error("ambiguity.confirm_below must be a fraction in [0, 1], got " + std::to_string(options.ambiguity.confirm_below));
    if (!(options.estimation.level_ground_lever_arm > 0.0))
      throw Error("estimation.level_ground_lever_arm_m must be a length > 0 in metres, got " +
                  std::to_string(options.estimation.level_ground_lever_arm));
    if (!(options.ambiguity.confirm_over_identity >= 0.0 && options.ambiguity.confirm_over_identity <= 1.0))
      throw Error("ambiguity.confirm_over_identity must be a fraction in [0, 1], got " +
                  std::to_string(options.ambiguity.confirm_over_identity));
  } catch (const Error& error) {
    throw file_error(path, error.what());
  }
}

std::vector<std::string> switched_off_checks(const RegistrationOptions& options) {
  const AmbiguityOptions& a = options.ambiguity;
  std::vector<std::string> off;
  const auto note = [&off](bool is_off, const char* key, double value, const char* rule, const char* check) {
    if (is_off) off.push_back(std::string(key) + " " + number_text(value) + " (" + rule + "): " + check + " is off");
  };
  note(a.overlap_margin < 0.0, "ambiguity.overlap_margin", a.overlap_margin, "< 0", "the check against not moving");
  note(a.minimum_overlap == 0.0, "ambiguity.minimum_overlap", a.minimum_overlap, "0", "the overlap floor");
  note(a.confirm_below == 0.0, "ambiguity.confirm_below", a.confirm_below, "0", "the dense search's confirmation of low overlaps");
  note(a.confirm_over_identity == 0.0, "ambiguity.confirm_over_identity", a.confirm_over_identity, "0",
       "the dense search's confirmation of answers barely beating not moving");
  note(a.half_turn_margin < 0.0, "ambiguity.half_turn_margin", a.half_turn_margin, "< 0", "the half-turn check");
  note(a.free_space_limit < 0.0, "ambiguity.free_space_limit", a.free_space_limit, "< 0", "the free-space check");
  note(a.ground_tilt_limit_degrees < 0.0, "ambiguity.ground_tilt_limit_deg", a.ground_tilt_limit_degrees, "< 0",
       "the ground-tilt check");
  return off;
}

std::string registration_config_yaml(const RegistrationOptions& options, const std::string& side) {
  if (side != "source" && side != "target")
    throw Error("registration_config_yaml: side must be source or target, got '" + side + "'");
  const ConfigSide which = side == "source" ? ConfigSide::Source : ConfigSide::Target;
  RegistrationOptions values = options;  // the table reaches members through non-const options
  YAML::Emitter out;
  out << YAML::BeginMap;
  std::vector<std::string> open_sections;  // the nested mappings the previous key was written in
  for (const RegistrationConfigKey& key : registration_config_keys()) {
    std::vector<std::string> parts;
    for (std::size_t begin = 0, dot = 0; dot != std::string::npos; begin = dot + 1) {
      dot = key.path.find('.', begin);
      parts.push_back(key.path.substr(begin, dot == std::string::npos ? std::string::npos : dot - begin));
    }
    std::size_t shared = 0;  // sections this key shares with the previous one (the table groups each section's keys)
    while (shared < open_sections.size() && shared + 1 < parts.size() && open_sections[shared] == parts[shared]) ++shared;
    while (open_sections.size() > shared) {
      out << YAML::EndMap;
      open_sections.pop_back();
    }
    while (open_sections.size() + 1 < parts.size()) {
      const std::string& section = parts[open_sections.size()];
      out << YAML::Key << section << YAML::Value << YAML::BeginMap;
      open_sections.push_back(section);
    }
    out << YAML::Key << parts.back() << YAML::Value;
    write_member(out, key.member(values, which));
  }
  for (std::size_t section = 0; section < open_sections.size(); ++section) out << YAML::EndMap;
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

namespace {

// Point statistics of a set of points (a voxel, a slab): count, sum, sum of outer products, for its PCA normal.
struct VoxelMoments {
  double count = 0.0;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
};

// A planar voxel: unit normal (sign arbitrary), centre and point count.
struct PlanarVoxel {
  Eigen::Vector3d normal;
  Eigen::Vector3d center;
  double weight;
};

// PCA normals of the planar voxels of (at most ~100 k evenly strided points of) the cloud.
std::vector<PlanarVoxel> planar_voxels(const PointCloud& cloud, double voxel_size) {
  const std::size_t stride = std::max<std::size_t>(1, cloud.size() / 100000);
  CellMap<VoxelMoments> voxels(cloud.size() / stride / 8);
  for (std::size_t i = 0; i < cloud.size(); i += stride) {
    const Eigen::Vector3d p = cloud.point(i);
    if (!p.allFinite()) continue;
    const Eigen::Vector3d cell = (p / voxel_size).array().floor();
    if ((cell.array().abs() > 1e5).any()) continue;  // within cell_key's 21 bits an axis
    VoxelMoments& voxel = voxels[cell_key(cell.cast<int>())];
    voxel.count += 1.0;
    voxel.sum += p;
    voxel.outer += p * p.transpose();
  }
  std::vector<PlanarVoxel> planar;
  voxels.for_each([&](std::uint64_t, const VoxelMoments& voxel) {
    if (voxel.count < 8.0) return;
    const Eigen::Vector3d mean = voxel.sum / voxel.count;
    const Eigen::Matrix3d covariance = voxel.outer / voxel.count - mean * mean.transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
    const Eigen::Vector3d values = solver.eigenvalues();  // ascending
    if (!(values(1) > 0.0) || values(0) > 0.04 * values(1) || values(1) < 0.01 * values(2)) return;  // a patch, not a line
    planar.push_back({solver.eigenvectors().col(0), mean, voxel.count});
  });
  // Hash-map order is not deterministic across library versions: sort for reproducible candidates.
  std::sort(planar.begin(), planar.end(), [](const PlanarVoxel& a, const PlanarVoxel& b) {
    return std::tie(a.center.x(), a.center.y(), a.center.z()) < std::tie(b.center.x(), b.center.y(), b.center.z());
  });
  return planar;
}

// Weight of the planar voxels whose normal is within the cone |n . direction| >= cosine.
double normal_support(const std::vector<PlanarVoxel>& voxels, const Eigen::Vector3d& direction, double cosine) {
  double support = 0.0;
  for (const PlanarVoxel& voxel : voxels)
    if (std::abs(voxel.normal.dot(direction)) >= cosine) support += voxel.weight;
  return support;
}

// Points in the fullest slab of thickness 2 * `half_thickness` perpendicular to `normal`:
// offsets along `normal` (those within `reach` of the origin) are binned at `half_thickness` and the
// heaviest pair of adjacent bins wins (the lowest on a tie). Returns the count and writes the
// slab's centre offset. An array, not a hash map: this runs for ~550 directions per cloud. `bins`
// must hold zeros on entry and is left so; only the bins the points reach are scanned and cleared
// (on a street scan ~150 of the ~2,400 a 120 m reach spans).
std::size_t fullest_slab(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& normal, double half_thickness,
                         double reach, std::vector<std::uint32_t>& bins, double* centre) {
  const std::size_t bin_count = static_cast<std::size_t>(std::ceil(2.0 * reach / half_thickness)) + 2;
  if (bins.size() < bin_count) bins.resize(bin_count, 0);
  std::size_t lowest = bin_count, highest = 0;
  for (const Eigen::Vector3d& p : points) {
    const double offset = p.dot(normal);
    if (std::abs(offset) < reach) {
      const std::size_t bin = static_cast<std::size_t>((offset + reach) / half_thickness);
      ++bins[bin];
      lowest = std::min(lowest, bin);
      highest = std::max(highest, bin);
    }
  }
  std::size_t best = 0, best_bin = 0;
  if (lowest <= highest) {
    // Pairs beyond [lowest - 1, highest] hold nothing and never beat an occupied one.
    for (std::size_t bin = lowest > 0 ? lowest - 1 : 0; bin <= highest && bin + 1 < bin_count; ++bin)
      if (bins[bin] + bins[bin + 1] > best) {
        best = bins[bin] + bins[bin + 1];
        best_bin = bin;
      }
    std::fill(bins.begin() + static_cast<std::ptrdiff_t>(lowest), bins.begin() + static_cast<std::ptrdiff_t>(highest) + 1, 0u);
  }
  *centre = static_cast<double>(best_bin + 1) * half_thickness - reach;
  return best;
}

// The plane that the most points lie on, among planes tilted at most 12 deg from `mode`, fitted
// to those points (least squares). The voxel normals that find `mode` lean when a voxel holds a
// single scan line: its noise lies along the beam, so its PCA normal tilts by the beam's elevation,
// and on a 16-ring scanner's ground, where rings are metres apart, most ground voxels are such
// lines (docs/registration.md, "How auto finds the up axis", has the measurements). Points do not
// lean: the direction whose slab of 0.2 m (a few times a LiDAR's range noise) holds the most points
// is searched on three grids (1, 0.25 and 0.0625 deg), and the points of that slab are fitted by
// PCA, twice. A fit that leaves the searched cone keeps the grid's direction. Known bias: a slab
// 0.2 m thick can hold a road and the kerb-high pavement on one side, so on streets with kerbs the
// plane leans up to ~1 deg across the street.
Eigen::Vector3d settle_on_fullest_plane(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& mode) {
  constexpr double kRadians = kPi / 180.0;
  const double search_cosine = std::cos(12.0 * kRadians);
  constexpr double kHalfThickness = 0.1;
  Eigen::Vector3d best = mode;
  double centre = 0.0;
  double reach = 0.0;
  for (const Eigen::Vector3d& p : points) reach = std::max(reach, p.norm());
  reach = std::min(reach, 1000.0) + kHalfThickness;  // a kilometre from the sensor bounds the histogram
  // The fine grids count every third point (<= 7 k), the 1-deg grid every ninth (<= 2.3 k): ~10 ms
  // per KITTI scan here instead of ~40. Both strides are co-prime with ring counts (16, 32, 64,
  // 128): a stride of 4 kept 4 of a VLP-16's 16 rings, and 12 of 69 simulated VLP-16 scans then
  // came out over 2 deg off.
  std::vector<Eigen::Vector3d> sparse, sparser;
  for (std::size_t i = 0; i < points.size(); i += 3) sparse.push_back(points[i]);
  for (std::size_t i = 0; i < points.size(); i += 9) sparser.push_back(points[i]);
  std::vector<std::uint32_t> bins;
  for (const auto& [step_degrees, radius_degrees] : {std::pair{1.0, 12.0}, std::pair{0.25, 1.0}, std::pair{0.0625, 0.25}}) {
    const std::vector<Eigen::Vector3d>& counted = step_degrees > 0.5 ? sparser : sparse;
    std::size_t best_count = fullest_slab(counted, best, kHalfThickness, reach, bins, &centre);  // on this grid's sample
    const Eigen::Vector3d around = best;
    const Eigen::Vector3d helper = std::abs(around.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    const Eigen::Vector3d first = (helper - helper.dot(around) * around).normalized();
    const Eigen::Vector3d second = around.cross(first);
    const int steps = static_cast<int>(std::round(radius_degrees / step_degrees));
    for (int a = -steps; a <= steps; ++a)
      for (int b = -steps; b <= steps; ++b) {
        if (a * a + b * b > steps * steps || (a == 0 && b == 0)) continue;
        const Eigen::Vector3d direction =
            (around + std::tan(a * step_degrees * kRadians) * first + std::tan(b * step_degrees * kRadians) * second).normalized();
        if (direction.dot(mode) < search_cosine) continue;
        double offset = 0.0;
        const std::size_t count = fullest_slab(counted, direction, kHalfThickness, reach, bins, &offset);
        if (count > best_count) {
          best_count = count;
          best = direction;
          centre = offset;
        }
      }
  }
  Eigen::Vector3d normal = best;
  for (int round = 0; round < 2; ++round) {
    VoxelMoments slab;
    for (const Eigen::Vector3d& p : points)
      if (std::abs(p.dot(normal) - centre) <= kHalfThickness) {
        slab.count += 1.0;
        slab.sum += p;
        slab.outer += p * p.transpose();
      }
    if (slab.count < 3.0) break;
    const Eigen::Vector3d mean = slab.sum / slab.count;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(slab.outer / slab.count - mean * mean.transpose());
    Eigen::Vector3d fitted = solver.eigenvectors().col(0);
    if (fitted.dot(mode) < 0.0) fitted = -fitted;
    if (fitted.dot(mode) < search_cosine) break;
    normal = fitted;
    centre = mean.dot(normal);
  }
  return normal;
}

}  // namespace

UpDirectionEstimate estimate_up_direction(const PointCloud& cloud) {
  constexpr double kDegrees = 180.0 / kPi;
  UpDirectionEstimate estimate;
  std::vector<double> ranges;
  std::vector<Eigen::Vector3d> sample;
  const std::size_t stride = std::max<std::size_t>(1, cloud.size() / 20000);
  for (std::size_t i = 0; i < cloud.size(); i += stride)
    if (cloud.point(i).allFinite()) {
      sample.push_back(cloud.point(i));
      ranges.push_back(sample.back().norm());
    }
  if (ranges.empty()) {
    estimate.reason = "no finite point: +z assumed";
    return estimate;
  }
  std::nth_element(ranges.begin(), ranges.begin() + static_cast<std::ptrdiff_t>(ranges.size() / 2), ranges.end());
  const double voxel_size = std::clamp(ranges[ranges.size() / 2] / 15.0, 0.1, 1.0);
  const std::vector<PlanarVoxel> voxels = planar_voxels(cloud, voxel_size);
  double total = 0.0;
  for (const PlanarVoxel& voxel : voxels) total += voxel.weight;
  if (voxels.size() < 20) {
    estimate.reason = std::to_string(voxels.size()) + " planar voxels (fewer than 20): +z assumed";
    return estimate;
  }
  const double cone = std::cos(10.0 / kDegrees);
  const double upright_limit = std::cos(45.0 / kDegrees);
  // Candidate directions: the normals of (at most 500 evenly chosen) planar voxels.
  const std::size_t candidate_stride = std::max<std::size_t>(1, voxels.size() / 500);
  Eigen::Vector3d best_upright = Eigen::Vector3d::Zero(), best_overall = Eigen::Vector3d::Zero();
  double upright_support = 0.0, overall_support = 0.0;
  for (std::size_t n = 0; n < voxels.size(); n += candidate_stride) {
    const Eigen::Vector3d& candidate = voxels[n].normal;
    const double support = normal_support(voxels, candidate, cone);
    if (support > overall_support) {
      overall_support = support;
      best_overall = candidate;
    }
    if (std::abs(candidate.z()) >= upright_limit && support > upright_support) {
      upright_support = support;
      best_upright = candidate;
    }
  }
  const bool upright = upright_support > 0.0;
  Eigen::Vector3d up = upright ? best_upright : best_overall;
  // Refine: the weighted mean of the sign-aligned normals within 10 deg, twice.
  for (int round = 0; round < 2; ++round) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const PlanarVoxel& voxel : voxels) {
      const double alignment = voxel.normal.dot(up);
      if (std::abs(alignment) >= cone) sum += (alignment < 0.0 ? -1.0 : 1.0) * voxel.weight * voxel.normal;
    }
    if (sum.norm() > 0.0) up = sum.normalized();
  }
  up = settle_on_fullest_plane(sample, up);
  if (upright) {
    if (up.z() < 0.0) up = -up;
  } else {
    // Orient so that most of the mode's planar points lie below the sensor at the origin.
    double below = 0.0, above = 0.0;
    for (const PlanarVoxel& voxel : voxels)
      if (std::abs(voxel.normal.dot(up)) >= cone) (voxel.center.dot(up) < 0.0 ? below : above) += voxel.weight;
    if (above > below) up = -up;
  }
  estimate.found = true;
  estimate.up = up;
  estimate.support = normal_support(voxels, up, cone) / total;
  estimate.tilt_degrees = std::acos(std::clamp(up.z(), -1.0, 1.0)) * kDegrees;
  std::ostringstream reason;
  reason.precision(3);
  reason << "up (" << up.x() << ", " << up.y() << ", " << up.z() << "), tilt " << estimate.tilt_degrees << " deg, "
         << 100.0 * estimate.support << "% of planar voxels (" << voxel_size << " m) within 10 deg"
         << (upright ? "" : "; no horizontal mode within 45 deg of +z: the best-supported plane normal, sensor above it");
  estimate.reason = reason.str();
  return estimate;
}

namespace {

// Nadir rule of guess_sensor_preset: at least this share of the x-y extent's cells covered ...
constexpr double kNadirOccupancy = 0.55;
// ... with a z span at most this fraction of the extent's shorter side.
constexpr double kNadirHeightRatio = 0.35;

// The 1st and 99th percentiles of `values` by selection, not a full sort (reorders `values`).
template <typename T>
std::pair<double, double> central_span(std::vector<T>& values) {
  const auto low_at = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 100);
  const auto high_at = values.begin() + static_cast<std::ptrdiff_t>(values.size() * 99 / 100);
  std::nth_element(values.begin(), high_at, values.end());
  std::nth_element(values.begin(), low_at, high_at);
  return {static_cast<double>(*low_at), static_cast<double>(*high_at)};
}

// Rings: maximal runs of occupied elevation bins separated by empty bins, among the
// elevations between `low` and `high` (degrees). Bins are 0.05 deg, wider for sparse clouds so that
// they hold at least ~20 points on average; a bin is occupied when it holds more than half the mean
// count (ring bins hold many times the mean, while a non-repetitive scanner fills the span evenly).
// A filled span (more than 70% of bins occupied) is not a ring structure: 0.
int count_elevation_rings(const std::vector<double>& elevations, double low, double high) {
  const double bin_width = std::max(0.05, 20.0 * (high - low) / static_cast<double>(elevations.size()));
  const int bin_count = std::max(1, static_cast<int>(std::ceil((high - low) / bin_width)) + 1);
  std::vector<std::size_t> histogram(static_cast<std::size_t>(bin_count), 0);
  for (const double elevation : elevations)
    if (elevation >= low && elevation <= high)
      ++histogram[static_cast<std::size_t>(std::min(bin_count - 1, static_cast<int>((elevation - low) / bin_width)))];
  const std::size_t occupied_threshold = std::max<std::size_t>(2, elevations.size() / (2 * static_cast<std::size_t>(bin_count)));
  bool inside = false;
  int runs = 0;
  int occupied = 0;
  for (const std::size_t count : histogram) {
    const bool is_occupied = count > occupied_threshold;
    occupied += is_occupied ? 1 : 0;
    if (is_occupied && !inside) ++runs;
    inside = is_occupied;
  }
  return occupied > 0.7 * bin_count ? 0 : runs;
}

// Azimuth coverage, median range, elevation span and rings of `cloud`, in its own frame.
void measure_sensor_geometry(const PointCloud& cloud, SensorGuess& guess) {
  constexpr double kDegrees = 180.0 / kPi;
  std::vector<char> azimuth_bins(360, 0);
  std::vector<double> ranges;
  std::vector<double> elevations;  // of points beyond 10 m (the rings are sharp there)
  ranges.reserve(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d p = cloud.point(i);
    const double horizontal = std::hypot(p.x(), p.y());
    const double range = p.norm();
    ranges.push_back(range);
    if (horizontal > 0.5) {
      const int bin = static_cast<int>(std::floor((std::atan2(p.y(), p.x()) * kDegrees + 180.0))) % 360;
      azimuth_bins[static_cast<std::size_t>(std::max(0, bin))] = 1;
    }
    if (range > 10.0) elevations.push_back(std::atan2(p.z(), horizontal) * kDegrees);
  }
  guess.azimuth_coverage = static_cast<double>(std::count(azimuth_bins.begin(), azimuth_bins.end(), 1)) / 360.0;
  std::nth_element(ranges.begin(), ranges.begin() + static_cast<std::ptrdiff_t>(ranges.size() / 2), ranges.end());
  guess.median_range = ranges[ranges.size() / 2];
  if (elevations.size() < 100) return;
  const auto [low, high] = central_span(elevations);  // the ring histogram needs no order
  guess.elevation_span_degrees = high - low;
  guess.ring_count = count_elevation_rings(elevations, low, high);
}

// How a cloud covers its horizontal extent, for telling a nadir (airborne) scan: the extent is the
// 1st..99th percentile of x and of y; `occupancy` is the share of its square cells, three mean
// point spacings wide (sqrt(extent area / points)), that hold a point; `height_ratio` is the z
// span (1st..99th percentile) over the extent's shorter side. A scanner on the ground leaves most
// far cells of its extent empty (its density falls with the square of the range); one looking
// down covers the ground evenly. Measured in the cloud's frame, z up (LAS files are).
struct NadirCoverage {
  double occupancy = 0.0;     // share of occupied cells
  double height_ratio = 1e9;  // z span / shorter horizontal side
};

NadirCoverage measure_nadir_coverage(const PointCloud& cloud) {
  NadirCoverage coverage;
  const std::size_t count = cloud.size();
  if (count < 1000) return coverage;
  Eigen::Vector3d low, high;
  std::vector<float> values(count);
  for (int axis = 0; axis < 3; ++axis) {
    for (std::size_t i = 0; i < count; ++i) values[i] = cloud.positions(axis, static_cast<Eigen::Index>(i));
    std::tie(low[axis], high[axis]) = central_span(values);
  }
  const Eigen::Vector3d extent = high - low;
  if (!(extent.x() > 0.0 && extent.y() > 0.0)) return coverage;
  coverage.height_ratio = extent.z() / std::min(extent.x(), extent.y());
  const double cell = 3.0 * std::sqrt(extent.x() * extent.y() / static_cast<double>(count));
  const std::size_t columns = static_cast<std::size_t>(std::ceil(extent.x() / cell)) + 1;
  const std::size_t rows = static_cast<std::size_t>(std::ceil(extent.y() / cell)) + 1;
  std::vector<char> occupied(columns * rows, 0);
  for (std::size_t i = 0; i < count; ++i) {
    const double x = cloud.positions(0, static_cast<Eigen::Index>(i)) - low.x();
    const double y = cloud.positions(1, static_cast<Eigen::Index>(i)) - low.y();
    if (x < 0.0 || y < 0.0 || x > extent.x() || y > extent.y()) continue;
    occupied[static_cast<std::size_t>(x / cell) * rows + static_cast<std::size_t>(y / cell)] = 1;
  }
  const double cells = std::ceil(extent.x() / cell) * std::ceil(extent.y() / cell);
  coverage.occupancy = static_cast<double>(std::count(occupied.begin(), occupied.end(), 1)) / cells;
  return coverage;
}

// The preset rule of guess_sensor_preset on the measured geometry; appends the rule that chose to `reason`.
std::string choose_preset(const SensorGuess& guess, const NadirCoverage& nadir, std::ostringstream& reason) {
  // Measured (on the points that keep company, as here) on 82 ground-level scans: ../shared/data's
  // KITTI, nuScenes, HDL-32, VLP-16, Livox Avia and Mid-360, BALM and 3DTK clouds and the simulated
  // monument's 7 stations. Those flatter than 0.35 covered at most 41% of their cells, the others at
  // most 54% except the two stations inside the monument's drum (77-78%, z span 0.99 of the
  // extent); rooms and objects that cover theirs evenly are tall against it (3DMatch 0.62-1.23, 76-87%).
  // The one airborne tile (Autzen, in metres) covered 67% at 0.18. With one airborne sample the
  // thresholds sit between the groups, not on a tuned margin.
  if (nadir.occupancy >= kNadirOccupancy && nadir.height_ratio <= kNadirHeightRatio) {
    reason << "x-y extent covered evenly (>= " << 100.0 * kNadirOccupancy << "% of cells) and flat (z span <= "
           << kNadirHeightRatio << " of it): a nadir view, airborne";
    return "airborne";
  }
  if (guess.azimuth_coverage < 0.5) {
    reason << "narrow horizontal field of view (< 50%): avia";
    return "avia";
  }
  if (guess.point_count > 1500000) {
    reason << "more than 1.5 M points: static scan, monument";
    return "monument";
  }
  if (guess.elevation_span_degrees < 35.0) {
    // A spinning multi-beam scanner looks at a narrow elevation band (HDL-64E 27 deg, VLP-16 30 deg);
    // its density (or ring count, when the rings are separable) tells a 64-beam from a 16-beam head.
    const bool dense = guess.point_count >= 60000 || guess.ring_count >= 48;
    reason << "narrow elevation span (< 35 deg) of a spinning scanner, "
           << (dense ? ">= 60 k points or >= 48 rings: vlp64" : "< 60 k points and < 48 rings: vlp16");
    return dense ? "vlp64" : "vlp16";
  }
  reason << "360 deg coverage and a tall (>= 35 deg) elevation span of a non-repetitive scanner: mid360";
  return "mid360";
}

}  // namespace

SensorGuess guess_sensor_preset(const PointCloud& cloud) {
  SensorGuess guess;
  guess.point_count = cloud.size();
  if (cloud.empty()) {
    guess.preset = "vlp64";
    guess.reason = "empty cloud: default preset vlp64";
    return guess;
  }
  // A platform's own body (more than 10% of the points within 1.5 m, e.g. 3DTK's robot) would
  // dominate every measurement: measure the scene beyond 2 m, and crop there.
  std::size_t near_field_points = 0;
  for (Eigen::Index i = 0; i < cloud.positions.cols(); ++i) near_field_points += cloud.positions.col(i).norm() < 1.5F ? 1 : 0;
  const double near_field_fraction = static_cast<double>(near_field_points) / static_cast<double>(cloud.size());
  if (near_field_fraction > 0.1) {
    PointCloud scene;
    std::vector<Eigen::Index> far;
    for (Eigen::Index i = 0; i < cloud.positions.cols(); ++i)
      if (cloud.positions.col(i).norm() >= 2.0F) far.push_back(i);
    scene.positions.resize(3, static_cast<Eigen::Index>(far.size()));
    for (std::size_t n = 0; n < far.size(); ++n) scene.positions.col(static_cast<Eigen::Index>(n)) = cloud.positions.col(far[n]);
    guess = guess_sensor_preset(scene);
    guess.point_count = cloud.size();
    guess.near_field_fraction = near_field_fraction;
    guess.minimum_range = std::max(2.0, guess.minimum_range);
    std::ostringstream reason;
    reason.precision(3);
    reason << 100.0 * near_field_fraction << "% of the " << cloud.size()
           << " points lie within 1.5 m (the platform itself): measured beyond 2 m and cropped there; " << guess.reason;
    guess.reason = reason.str();
    return guess;
  }
  // Rings and the elevation span are properties of the sensor head, so they are measured in the
  // cloud's own frame (a tilted spinning LiDAR keeps its rings there); the up axis only tells the
  // extraction where the ground is.
  // Spurious returns spread through the scene (dust, rain, multipath echoes) would widen the
  // elevation span and blur the planar voxels the up axis comes from, so both are measured on the
  // points that keep company (the checks' rule, AmbiguityOptions::isolation_cell). Under 30% uniform
  // outliers a KITTI scan's span measured 47.7 deg and it was taken for a Mid-360.
  const PointCloud accompanied = without_isolated_points(cloud, AmbiguityOptions{}.isolation_cell);
  const PointCloud& measured = accompanied.empty() ? cloud : accompanied;
  guess.up = estimate_up_direction(measured);
  guess.near_field_fraction = near_field_fraction;
  measure_sensor_geometry(measured, guess);
  std::ostringstream reason;
  reason.precision(3);
  reason << guess.point_count << " points";
  if (measured.size() < cloud.size()) reason << " (" << cloud.size() - measured.size() << " isolated left out)";
  reason << ", azimuth coverage " << 100.0 * guess.azimuth_coverage << "%, "
         << (guess.ring_count > 0 ? std::to_string(guess.ring_count) + " elevation rings" : std::string("rings not separable"))
         << ", elevation span " << guess.elevation_span_degrees << " deg, median range "
         << guess.median_range << " m -> ";
  // On the points that keep company too: spurious returns spread through the bounding box would
  // fill its cells.
  const NadirCoverage nadir = measure_nadir_coverage(measured);
  reason << "x-y cells covered " << 100.0 * nadir.occupancy << "%, z span / x-y extent " << nadir.height_ratio << ", ";
  guess.preset = choose_preset(guess, nadir, reason);
  guess.minimum_range = extraction_preset(guess.preset).minimum_range;
  guess.reason = reason.str();
  return guess;
}

RegistrationOptions resolve_registration_side(const std::string& preset, const PointCloud& cloud, const std::string& side,
                                              std::string* notes) {
  if (preset != "auto") return registration_preset(preset);
  const SensorGuess guess = guess_sensor_preset(cloud);
  RegistrationOptions options = registration_preset(guess.preset);
  if (guess.up.found) options.source_extraction.up = options.target_extraction.up = guess.up.up;
  if (guess.near_field_fraction > 0.1)  // self-hits of the platform: crop them (its preset's value when larger)
    options.source_extraction.minimum_range = options.target_extraction.minimum_range =
        std::max(guess.minimum_range, options.source_extraction.minimum_range);
  if (notes != nullptr) *notes += (notes->empty() ? "" : "; ") + side + " auto: " + guess.reason + "; " + guess.up.reason;
  return options;
}

RegistrationOptions resolve_registration_options(const std::string& source_preset, const PointCloud& source,
                                                 const std::string& target_preset, const PointCloud& target,
                                                 std::string* notes) {
  // The two sides are measured at the same time (auto: ~30 ms per KITTI scan here), each with its
  // own notes, joined source first.
  RegistrationOptions options, target_side;
  std::string source_notes, target_notes;
  tbb::parallel_invoke([&] { options = resolve_registration_side(source_preset, source, "source", &source_notes); },
                       [&] { target_side = resolve_registration_side(target_preset, target, "target", &target_notes); });
  options.target_extraction = target_side.target_extraction;  // the source side's preset sets the shared stages
  if (notes != nullptr)
    for (const std::string* side_notes : {&source_notes, &target_notes})
      if (!side_notes->empty()) *notes += (notes->empty() ? "" : "; ") + *side_notes;
  return options;
}

}  // namespace quadrix
