// Verification of an answer (see verification.h): the checks' points, the overlap guard, the
// free-space check, the half-turn check, the dense search's settling, the grounds' agreement and
// the measures a back end uses, in the order verify_prepared_answer runs them.
#include "estimation/verification.h"

#include "estimation/stage_timing.h"
#include "geometry/constants.h"
#include "geometry/voxel_cells.h"

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <utility>

namespace quadrix {
namespace {

using stage_timing::Clock;
using stage_timing::elapsed_ms;
using stage_timing::timed;

// Fewer points tested than this on either side judge nothing in the free-space check: a share of
// a few dozen points moves by tenths with a single car.
constexpr std::size_t kMinimumFreeSpaceTested = 100;

// Whether a free-space measure judges its answer at all (enough points tested each way).
bool free_space_judges(const FreeSpaceMeasure& measure) {
  return measure.source_tested >= kMinimumFreeSpaceTested && measure.target_tested >= kMinimumFreeSpaceTested;
}

// Whether a free-space measure demotes its answer for points in free space (check_free_space's rule).
bool puts_points_in_free_space(const FreeSpaceMeasure& measure, const AmbiguityOptions& options) {
  return free_space_judges(measure) && measure.sum() > options.free_space_limit;
}

}  // namespace

std::optional<Eigen::Vector4d> ground_plane_of(const SceneModel& model) {
  if (!model.has_ground) return std::nullopt;
  return Eigen::Vector4d(model.ground_normal.x(), model.ground_normal.y(), model.ground_normal.z(), model.ground_offset);
}

namespace {

// check_overlap against a target already hashed (`coverage`, at measure_overlap's 0.3 m).
void check_overlap_against(RegistrationResult& result, const PointCloud& source, const TargetCoverage& coverage,
                           const AmbiguityOptions& options) {
  timed(result, "overlap", [&] {
    const OverlapMeasure overlap = measure_overlap(source, coverage, result.transform, ground_plane_of(result.source_model));
    result.overlap = overlap;
    const bool was_ok = result.status == RegistrationStatus::Ok;
    result.findings.fits_worse_than_identity =
        options.overlap_margin >= 0.0 && overlap.sampled > 0 && overlap.transformed < overlap.identity - options.overlap_margin;
    // The floor: a wrong answer that happens to score well among the quadrics rarely puts much of
    // the source on the target (AmbiguityOptions::minimum_overlap; docs/registration.md says how it was set).
    result.findings.overlaps_too_little = overlap.sampled > 0 && overlap.transformed < options.minimum_overlap;
    // Between the floor and confirm_below right and wrong answers meet, and so do answers that land
    // hardly more than not moving (an ICP optimum near the start): such an answer waits for the dense
    // search (verify_registration), unless that search has just settled it.
    const bool low_overlap = overlap.transformed < options.confirm_below;
    const bool near_identity_overlap =
        options.confirm_over_identity > 0.0 && overlap.transformed < overlap.identity + options.confirm_over_identity;
    result.findings.overlap_unconfirmed =
        !result.findings.settled_by_dense_search && overlap.sampled > 0 && (low_overlap || near_identity_overlap);
    if (was_ok && result.findings.fits_worse_than_identity) {
      std::ostringstream why;
      why.precision(2);
      why << "; but only " << overlap.transformed << " of the source lands within " << overlap.distance
          << " m of the target, against " << overlap.identity << " left where it is (margin " << options.overlap_margin << ")";
      result.message += why.str();
    } else if (was_ok && result.findings.overlaps_too_little) {
      std::ostringstream why;
      why.precision(2);
      why << "; but only " << overlap.transformed << " of the source lands within " << overlap.distance
          << " m of the target, below the floor of " << options.minimum_overlap;
      result.message += why.str();
    } else if (was_ok && result.findings.overlap_unconfirmed) {
      std::ostringstream why;
      why.precision(2);
      why << "; " << overlap.transformed << " of the source lands within " << overlap.distance << " m of the target, ";
      if (low_overlap) why << "below " << options.confirm_below;
      else why << "less than " << options.confirm_over_identity << " more than the " << overlap.identity << " left where it is";
      why << ": the dense search must confirm it";
      result.message += why.str();
    }
    // Only an `ok` answer is demoted here; any other status stands as it is.
    if (was_ok) apply_registration_status(result);
  });
}

}  // namespace

void check_overlap(RegistrationResult& result, const PointCloud& source, const PointCloud& target,
                   const AmbiguityOptions& options) {
  // The hash of the target is part of what this check costs.
  std::optional<TargetCoverage> coverage;
  timed(result, "overlap", [&] { coverage.emplace(target, OverlapMeasure{}.distance); });
  check_overlap_against(result, source, *coverage, options);
}

namespace {

// The indices of the points of `cloud` within the extraction's range limits around its sensor
// (within_range, as extraction crops), ascending.
std::vector<std::uint32_t> indices_in_range(const PointCloud& cloud, const ExtractionOptions& extraction) {
  std::vector<std::uint32_t> kept;
  kept.reserve(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i)
    if (within_range(cloud.point(i), extraction)) kept.push_back(static_cast<std::uint32_t>(i));
  return kept;
}

// The dense search's best optimum beats every distinct optimum by the margin, with every close
// contender refined and inside the region searched (the rules of a settle but the overlap floor).
bool clear_winner(const DenseSearchResult& search, const DenseSearchOptions& options) {
  return search.margin >= options.decisive_margin && search.unrefined_contenders == 0 && search.best_in_searched_region;
}

// Whether the dense search's winner may replace the answer: clear of every distinct optimum, all close
// contenders refined, enough of the source on the target, and inside the grid searched around the
// answer (outside it, the winner is a local optimum of a grid that missed the truth).
bool dense_search_settles(const DenseSearchResult& search, const DenseSearchOptions& options) {
  return clear_winner(search, options) && search.optima[search.best].overlap >= options.minimum_overlap;
}

// A clear winner the search could not settle only because it lands too little of the source on
// the target (below dense_search.minimum_overlap).
bool clear_winner_below_floor(const DenseSearchResult& search, const DenseSearchOptions& options) {
  return clear_winner(search, options) && search.optima[search.best].overlap < options.minimum_overlap;
}

// The dense search's account for the message: direction, both optima, margin, and what failed.
// `result` holds the quadric answer and the search's findings.
std::string describe_dense_search(const DenseSearchResult& search, const RegistrationResult& result,
                                  const DenseSearchOptions& options) {
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
  if (search.screened_out > 0)
    why << " (" << search.screened_out << " optima left out: they put points in the other sensor's free space)";
  if (result.findings.settled_by_dense_search) {
    why << ": settled (margin " << search.margin << ")";
    if (result.findings.dense_search_unclear)
      why << ", within the margin " << options.ok_margin << " an ok answer needs here, not sure";
    return why.str();
  }
  // Not settled: the points do not single out an optimum either, so the quadric answer stands.
  why << ": not settled (margin " << search.margin;
  if (search.margin < options.decisive_margin) why << " < " << options.decisive_margin;
  if (best.overlap < options.minimum_overlap) why << ", best overlap below " << options.minimum_overlap;
  if (!search.best_in_searched_region) why << ", best optimum outside the grid searched around the answer (and no global start)";
  if (search.unrefined_contenders > 0)
    why << ", " << search.unrefined_contenders << " optima within " << options.refine_band
        << " of the best left unrefined beyond max_refined " << options.max_refined;
  why << (clear_winner_below_floor(search, options) ? "), its best optimum becomes the best guess" : "), the quadric answer stands");
  return why.str();
}

// Translations that put the source's quadrics on same-class target quadrics under `rotation`, best
// first (at most `count`): every pair of same-class records with a meaningful centre (not ground,
// planes or augmented points, whose centres are where the part seen happens to be) votes
// t = c_target - rotation * c_source; votes are binned by 1 m cells along the ground and a cell
// scores the votes of its 3 x 3 neighbourhood. A peak is the mean vote of its neighbourhood; peaks
// closer than 2 m to a better one are skipped. A Hough transform of the translation for one rotation.
std::vector<Eigen::Vector3d> vote_translations(const SceneModel& source, const SceneModel& target,
                                               const Eigen::Matrix3d& rotation, const Eigen::Vector3d& up,
                                               std::size_t count) {
  const auto votes_for = [](const QuadricRecord& record) {
    const ElementClass element_class = element_class_from_label(record.label);
    return element_class != ElementClass::Ground && element_class != ElementClass::Plane;
  };
  const Eigen::Vector3d first = up.unitOrthogonal(), second = up.cross(first);
  std::vector<Eigen::Vector3d> votes;
  for (std::size_t i = 0; i < source.augmented_begin; ++i) {
    if (!votes_for(source.records[i])) continue;
    const Eigen::Vector3d turned = rotation * source.records[i].full_center;
    for (std::size_t j = 0; j < target.augmented_begin; ++j)
      if (target.records[j].label == source.records[i].label) votes.push_back(target.records[j].full_center - turned);
  }
  const auto cell_of = [&](const Eigen::Vector3d& vote) {
    return Eigen::Vector2i(static_cast<int>(std::floor(vote.dot(first))), static_cast<int>(std::floor(vote.dot(second))));
  };
  std::map<std::pair<int, int>, std::vector<std::size_t>> cells;
  for (std::size_t v = 0; v < votes.size(); ++v) {
    const Eigen::Vector2i cell = cell_of(votes[v]);
    cells[{cell.x(), cell.y()}].push_back(v);
  }
  // Each cell's neighbourhood: its vote count and mean vote.
  std::vector<std::pair<std::size_t, Eigen::Vector3d>> peaks;
  for (const auto& [cell, members] : cells) {
    std::size_t support = 0;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy) {
        const auto neighbour = cells.find({cell.first + dx, cell.second + dy});
        if (neighbour == cells.end()) continue;
        support += neighbour->second.size();
        for (const std::size_t v : neighbour->second) sum += votes[v];
      }
    peaks.emplace_back(support, sum / static_cast<double>(support));
  }
  std::stable_sort(peaks.begin(), peaks.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<Eigen::Vector3d> chosen;
  for (const auto& peak : peaks) {
    if (chosen.size() >= count) break;
    const Eigen::Vector3d& translation = peak.second;  // a plain reference: C++17 lambdas cannot capture structured bindings
    const bool near_better = std::any_of(chosen.begin(), chosen.end(), [&](const Eigen::Vector3d& other) {
      return (translation - other).norm() < 2.0;
    });
    if (!near_better) chosen.push_back(translation);
  }
  return chosen;
}

// The up axis the half turn and the dense search move along the ground with: the target's ground
// normal, else the target extraction's up.
Eigen::Vector3d target_up(const RegistrationResult& result, const RegistrationOptions& options) {
  return result.target_model.has_ground ? result.target_model.ground_normal : options.target_extraction.up.normalized();
}

// Settles an `ambiguous` answer with the dense search along the weakest direction
// (search_weakest_direction), leaving out the optima `screen` rules out.
void settle_with_dense_search(RegistrationResult& result, const DenseSearchPair& prepared, const RegistrationOptions& options,
                              const OptimumScreen& screen) {
  std::vector<Eigen::Isometry3d> other_starts;
  for (std::size_t i = 0; i < result.candidates.size(); ++i)
    if (result.candidates[i].valid && i != result.best_candidate) other_starts.push_back(result.candidates[i].transform);
  // The mirror image the half-turn check found competes too.
  if (result.half_turn && result.half_turn->has_rival) other_starts.push_back(result.half_turn->rival);
  // The correlation over the ground's poses are global starts.
  std::vector<Eigen::Isometry3d> global_starts;
  for (const GroundPose& pose : result.ground_correlation) global_starts.push_back(pose.transform);
  std::optional<Eigen::Vector3d> up;
  if (result.target_model.has_ground) up = result.target_model.ground_normal;
  const DenseSearchResult search = search_weakest_direction(
      prepared, result.transform, other_starts, global_starts, up, ground_plane_of(result.source_model),
      options.ambiguity.translation_disagreement, options.ambiguity.rotation_disagreement_degrees, options.dense_search, screen);
  const bool settled = dense_search_settles(search, options.dense_search);
  result.findings.settled_by_dense_search = settled;
  result.findings.dense_search_unclear = settled && search.margin < options.dense_search.ok_margin;
  result.message += describe_dense_search(search, result, options.dense_search);
  result.dense_search = search;
  if (!settled) {
    // A clear winner that lands too little of the source to be called `ok` (outliers and low
    // overlap keep it below the floor) is still a better guess than the quadric answer it beat: it
    // becomes the answer, `ambiguous`. On the tuning set's hard bin with 10% outliers this took
    // success from 72 to 90 of 100 and changed no status of the clean tuning set.
    if (clear_winner_below_floor(search, options.dense_search)) result.transform = search.optima[search.best].transform;
    return;
  }
  result.transform = search.optima[search.best].transform;
  result.findings.fits_worse_than_identity = false;  // measured again on the new answer below
  result.findings.overlaps_too_little = false;
  result.findings.overlap_unconfirmed = false;
  result.findings.half_turn_rival = false;
  result.findings.half_turn_unclear = false;
  result.findings.in_free_space = false;  // measured again on the new answer (verify_prepared)
  result.findings.free_space_unjudged = false;
  apply_registration_status(result);
}

}  // namespace

void check_half_turn(RegistrationResult& result, const PointCloud& source, const PointCloud& target,
                     const RegistrationOptions& options, bool may_replace, const DenseSearchPair* prepared,
                     const OptimumScreen& screen) {
  const AmbiguityOptions& ambiguity = options.ambiguity;
  if ((result.status != RegistrationStatus::Ok && !(may_replace && result.status == RegistrationStatus::Ambiguous)) ||
      ambiguity.half_turn_margin < 0.0 || source.empty() || target.empty())
    return;
  timed(result, "half_turn", [&] {
    const std::optional<Eigen::Vector4d> source_ground = ground_plane_of(result.source_model);
    // The pivot: the centre of what the answer lands on the target, as check_overlap measured it for
    // this answer (measured here when it has not run).
    const std::optional<Eigen::Vector3d> pivot =
        result.overlap ? result.overlap->transformed_centre
                       : measure_overlap(source, target, result.transform, source_ground).transformed_centre;
    if (!pivot) return;
    // H: x -> R (x - c) + c, the half turn about the vertical axis through the overlap's centre c.
    const Eigen::Vector3d up = target_up(result, options);
    Eigen::Isometry3d half_turn = Eigen::Isometry3d::Identity();
    half_turn.linear() = Eigen::AngleAxisd(kPi, up).toRotationMatrix();
    half_turn.translation() = *pivot - half_turn.linear() * *pivot;
    const Eigen::Isometry3d turned = half_turn * result.transform;
    // Starts: the answer itself first, then the turned rotation at the translations the quadrics vote
    // for. A grid of starts around the turned answer (4 m along, 2 m across, every 2 m) changed no
    // result of the synthetic tuning set's 300 pairs and cost about 70 ms a pair on KITTI.
    std::vector<Eigen::Isometry3d> other_starts = {result.transform};
    for (const Eigen::Vector3d& translation :
         vote_translations(result.source_model, result.target_model, turned.linear(), up, ambiguity.half_turn_votes)) {
      Eigen::Isometry3d start = turned;
      start.translation() = translation;
      other_starts.push_back(start);
    }
    for (const Eigen::Vector3d& translation :
         correlate_translations(source, target, source_ground, ground_plane_of(result.target_model), turned.linear(),
                                turned.translation(), up,
                                ambiguity.half_turn_correlation_reach, ambiguity.half_turn_correlation_starts)) {
      Eigen::Isometry3d start = turned;
      start.translation() = translation;
      other_starts.push_back(start);
    }
    // No grid: the search's single "answer" start is the turned answer (range 0 either way).
    DenseSearchOptions grid = options.dense_search;
    grid.range = grid.across_range = 0.0;
    grid.source_samples = ambiguity.half_turn_samples;
    const DenseSearchResult search =
        search_weakest_direction(prepared ? *prepared : DenseSearchPair(source, target, grid), turned, other_starts, {}, up,
                                 source_ground, ambiguity.translation_disagreement, ambiguity.rotation_disagreement_degrees, grid, screen);
    // The answer's own optimum is the first start after the grid ("candidate 0"; the identity is
    // last); the rival is the best optimum anywhere that disagrees with it.
    const std::size_t answer_index = search.optima.size() - 1 - other_starts.size();
    const DenseOptimum& answer = search.optima[answer_index];
    HalfTurnCheck check;
    check.pivot = *pivot;
    check.answer_overlap = answer.overlap;
    for (const DenseOptimum& optimum : search.optima) {
      const bool disagrees =
          translation_error(optimum.transform, answer.transform) > ambiguity.translation_disagreement ||
          rotation_error_degrees(optimum.transform, answer.transform) > ambiguity.rotation_disagreement_degrees;
      if (disagrees && !optimum.screened_out && (!check.has_rival || optimum.overlap > check.rival_overlap)) {
        check.has_rival = true;
        check.rival_overlap = optimum.overlap;
        check.rival = optimum.transform;
      }
    }
    result.half_turn = check;
    result.findings.half_turn_rival = check.has_rival && check.rival_overlap > check.answer_overlap - ambiguity.half_turn_margin;
    // A sparse sensor's mirror image can out-overlap the truth (docs/registration.md, known
    // failures): its preset asks an `ok` answer to beat the rival by more.
    result.findings.half_turn_unclear =
        !result.findings.half_turn_rival && check.has_rival && check.rival_overlap > check.answer_overlap - ambiguity.half_turn_ok_margin;
    // A rival that beats the answer by the margin, and lands enough of the source to be settled by
    // the dense search's own rule, takes its place.
    const bool replaced = may_replace && check.has_rival && check.rival_overlap >= check.answer_overlap + ambiguity.half_turn_margin &&
               check.rival_overlap >= options.dense_search.minimum_overlap;
    std::ostringstream why;
    why.precision(3);
    why << "; half turn about (" << pivot->x() << ", " << pivot->y() << ", " << pivot->z() << "): answer overlap "
        << check.answer_overlap << ", best rival " << check.rival_overlap;
    if (check.has_rival)
      why << " at " << translation_error(check.rival, answer.transform) << " m, "
          << rotation_error_degrees(check.rival, answer.transform) << " deg";
    if (replaced)
      why << ": the rival fits better by more than the margin " << ambiguity.half_turn_margin << " and replaces the answer";
    else if (result.findings.half_turn_rival)
      why << ": within the margin " << ambiguity.half_turn_margin << ", not sure";
    else if (result.findings.half_turn_unclear)
      why << ": within the margin " << ambiguity.half_turn_ok_margin << " an ok answer needs here, not sure";
    result.message += why.str();
    if (!replaced && !result.findings.half_turn_rival && ambiguity.adopt_icp_optimum && answer.refined) {
      // The answer stands: its own ICP optimum (refined on all samples) replaces it, which removes
      // the few degrees a clique of far, coarse quadrics can leave.
      result.transform = answer.transform;
      result.message += "; answer refined by point-to-plane ICP";
    }
    if (replaced) {
      // The rival is only the best of a handful of starts: it stays `ambiguous` until the dense search
      // around it settles it (a street repeats along itself), with the old answer as a competing start.
      result.half_turn->rival = result.transform;
      result.half_turn->rival_overlap = check.answer_overlap;
      result.transform = check.rival;
      result.findings.half_turn_rival = true;
      result.findings.replaced_by_half_turn = true;
      result.findings.in_free_space = false;  // judged the replaced answer
      result.findings.free_space_unjudged = false;
    }
    apply_registration_status(result);
  });
}

void check_free_space(RegistrationResult& result, const PointCloud& source, const PointCloud& target,
                      const RangeImage& source_image, const RangeImage& target_image, const AmbiguityOptions& options) {
  if (result.status != RegistrationStatus::Ok || options.free_space_limit < 0.0) return;
  const std::optional<Eigen::Vector4d> source_ground = ground_plane_of(result.source_model), target_ground = ground_plane_of(result.target_model);
  if (!source_ground || !target_ground) {
    result.findings.free_space_unjudged = true;
    result.message += std::string("; free space: no ground in the ") + (source_ground ? "target" : "source") +
                      " model to measure heights from: not checked, not sure";
    apply_registration_status(result);
    return;
  }
  timed(result, "free_space", [&] {
    const FreeSpaceMeasure measure = measure_free_space(source, target, source_image, target_image, result.transform,
                                                        *source_ground, *target_ground, options.free_space_height);
    result.free_space = measure;
    std::ostringstream why;
    why.precision(3);
    why << "; free space: " << measure.source_in_target_free_space << " of " << measure.source_tested
        << " source points in the target sensor's, " << measure.target_in_source_free_space << " of "
        << measure.target_tested << " target points in the source sensor's";
    if (!free_space_judges(measure)) {
      why << ": too few points tested (fewer than " << kMinimumFreeSpaceTested << " a side) to judge, not sure";
      result.findings.free_space_unjudged = true;
    } else {
      why << " (sum " << measure.sum() << ", limit " << options.free_space_limit << ")";
      result.findings.in_free_space = puts_points_in_free_space(measure, options);
      if (result.findings.in_free_space) why << ": more than the limit, not sure";
    }
    result.message += why.str();
    apply_registration_status(result);
  });
}

namespace {

// The angle between two axes, degrees, whichever way each points.
double angle_between_axes_degrees(const Eigen::Vector3d& first, const Eigen::Vector3d& second) {
  return std::acos(std::min(1.0, std::abs(first.normalized().dot(second.normalized())))) * 180.0 / kPi;
}

}  // namespace

bool grounds_level(const SceneModel& source, const SceneModel& target, const RegistrationOptions& options) {
  return source.has_ground && target.has_ground &&
         angle_between_axes_degrees(source.ground_normal, options.source_extraction.up) <= kLevelGroundDegrees &&
         angle_between_axes_degrees(target.ground_normal, options.target_extraction.up) <= kLevelGroundDegrees;
}

void check_ground_agreement(RegistrationResult& result, const RegistrationOptions& options) {
  const double limit = options.ambiguity.ground_tilt_limit_degrees;
  if (result.status != RegistrationStatus::Ok || limit < 0.0) return;
  if (!grounds_level(result.source_model, result.target_model, options)) return;
  const Eigen::Vector3d source_normal = result.source_model.ground_normal, target_normal = result.target_model.ground_normal;
  const double tilt = angle_between_axes_degrees(result.transform.linear() * source_normal, target_normal);
  result.findings.grounds_disagree = tilt > limit;
  if (!result.findings.grounds_disagree) return;
  std::ostringstream why;
  why.precision(3);
  why << "; the answer tilts the source's ground " << tilt << " deg from the target's (limit " << limit << "): not sure";
  result.message += why.str();
  apply_registration_status(result);
}

namespace {

// Whether the options let a half-turn check or a dense search run on some answer.
bool may_search(const RegistrationOptions& options) {
  return options.ambiguity.half_turn_margin >= 0.0 || options.dense_search.enabled;
}

}  // namespace

VerificationInputs prepare_verification(const PointCloud& source, const PointCloud& target, const RegistrationOptions& options,
                           const ExtractionResult* source_extraction, const ExtractionResult* target_extraction,
                           bool may_answer) {
  // Every check measures the clouds within the extraction's range, without their isolated points:
  // a spurious return never lands on the other scan, so each one would count against the right
  // answer (docs/registration.md, "Isolated points").
  const double cell = options.ambiguity.isolation_cell, distance = OverlapMeasure{}.distance;
  const int neighbours = options.ambiguity.isolation_neighbours;
  // The extraction already chose those points when it cropped by the same range and left out
  // isolated points by the same rule (the defaults): the checks' input then takes ~4 ms a KITTI
  // pair instead of 8-10, and 7 instead of 49 under 30% outliers (docs/registration.md, "Time").
  const auto chosen_by = [&](const ExtractionResult* extraction, const PointCloud& cloud,
                             const ExtractionOptions& side) -> const ExtractionResult* {
    if (extraction == nullptr) return nullptr;
    const MeasuredPoints& measured = extraction->measured;
    const bool same = measured.cloud_size == cloud.size() && measured.sensor_origin == side.sensor_origin &&
                      measured.minimum_range == side.minimum_range && measured.maximum_range == side.maximum_range &&
                      measured.isolation_cell == cell && measured.isolation_neighbours == neighbours;
    return same ? extraction : nullptr;
  };
  const ExtractionResult* source_chosen = chosen_by(source_extraction, source, options.source_extraction);
  const ExtractionResult* target_chosen = chosen_by(target_extraction, target, options.target_extraction);
  // A side's points (and their indices in the cloud): the extraction's own, else cropped and, when
  // `filter`, without isolated points (accompanied_points among the cropped ones, as
  // without_isolated_points of the cropped cloud).
  const auto points_of = [&](const PointCloud& cloud, const ExtractionResult* chosen, const ExtractionOptions& side,
                             bool filter, std::size_t& isolated, std::vector<std::uint32_t>& indices) {
    if (chosen) {
      isolated = chosen->isolated_points;
      indices = chosen->measured.indices;
    } else {
      indices = indices_in_range(cloud, side);
      const std::size_t in_range = indices.size();
      if (filter) indices = accompanied_points(cloud.positions.cast<double>(), indices, cell, neighbours);
      isolated = in_range - indices.size();
    }
    PointCloud selected;
    selected.positions = cloud.positions(Eigen::all, indices);
    return selected;
  };
  VerificationInputs inputs;
  const bool prepare_search = may_answer && (may_search(options) || options.initial_guess.has_value());
  const bool free_space = may_answer && options.ambiguity.free_space_limit >= 0.0;
  const Clock::time_point start = Clock::now();
  // The target is hashed once, for every overlap measured after. When the isolation cube is the
  // overlap's own distance (the default), that hash's cells also tell the isolated target points.
  tbb::parallel_invoke(
      [&] {
        inputs.source = points_of(source, source_chosen, options.source_extraction, cell > 0.0, inputs.source_isolated_points,
                                  inputs.source_indices);
      },
      [&] {
        const bool hash_tells_isolated = !target_chosen && cell == distance;
        inputs.target = points_of(target, target_chosen, options.target_extraction, cell > 0.0 && !hash_tells_isolated,
                                  inputs.target_isolated_points, inputs.target_indices);
        inputs.coverage.emplace(inputs.target, distance);
        if (hash_tells_isolated) {
          const std::size_t hashed = inputs.target.size();
          const std::vector<Eigen::Index> kept = inputs.coverage->leave_out_isolated_points(neighbours);
          inputs.target.positions = inputs.target.positions(Eigen::all, kept).eval();
          std::vector<std::uint32_t> kept_indices(kept.size());
          for (std::size_t k = 0; k < kept.size(); ++k) kept_indices[k] = inputs.target_indices[static_cast<std::size_t>(kept[k])];
          inputs.target_indices = std::move(kept_indices);
          inputs.target_isolated_points += hashed - inputs.target.size();
        }
      });
  inputs.inputs_ms = elapsed_ms(start);
  // The searches' pair and the two range images as separate tasks: a core the matching leaves
  // idle takes some (on KITTI the images took ~6 ms more of the pair's time built one after each
  // side's points, ~3 ms a side).
  const Clock::time_point preparation = Clock::now();
  tbb::parallel_invoke(
      [&] {
        if (prepare_search && !inputs.source.empty() && !inputs.target.empty())
          inputs.prepared.emplace(inputs.source, inputs.target, options.dense_search);
      },
      [&] {
        if (free_space) inputs.source_image.emplace(inputs.source, options.source_extraction.sensor_origin);
      },
      [&] {
        if (free_space) inputs.target_image.emplace(inputs.target, options.target_extraction.sensor_origin);
      });
  inputs.preparation_ms = elapsed_ms(preparation);
  return inputs;
}

namespace {

// Whether the free-space check can clear an `ok` answer before the half-turn check: the half-turn
// check is on, and the images are made (prepare_verification makes them only when the free-space check is).
bool free_space_goes_first(const RegistrationResult& result, const VerificationInputs& inputs, const RegistrationOptions& options) {
  return result.status == RegistrationStatus::Ok && inputs.source_image && inputs.target_image &&
         options.ambiguity.half_turn_margin >= 0.0;
}

// An `ok` answer, refined by point-to-plane ICP (when adopt_icp_optimum) and then checked against
// what each sensor saw as empty. The half-turn check guards against a mirror image that fits about
// as well, and a mirror image puts façades where the other sensor's beams went through: on the
// tuning sets with no half-turn check (1,200 runs), the free-space check alone at its limit left no
// `ok` answer wrong, and the few the half-turn check would have replaced by the right rival all
// sum 0.35 or more (docs/registration.md, "Free space"). So an answer it clears stays `ok` without
// the half-turn check (about 20 ms a KITTI pair); one it does not clear goes on, `ambiguous`, to
// the half-turn check and the dense search. Returns whether it cleared the answer.
bool clear_by_free_space(RegistrationResult& result, const VerificationInputs& inputs, const RegistrationOptions& options) {
  const AmbiguityOptions& ambiguity = options.ambiguity;
  if (ambiguity.adopt_icp_optimum) {
    // The half-turn check's own ICP settings, so the answer is the one that check would adopt.
    DenseSearchOptions refinement = options.dense_search;
    refinement.source_samples = ambiguity.half_turn_samples;
    result.transform = timed(result, "answer_refinement", [&] {
      return refine_answer(*inputs.prepared, result.transform, ground_plane_of(result.source_model), refinement).transform;
    });
    result.message += "; answer refined by point-to-plane ICP";
  }
  check_free_space(result, inputs.source, inputs.target, *inputs.source_image, *inputs.target_image, ambiguity);
  if (result.status == RegistrationStatus::Ok) {
    result.message += ": clear, no half-turn check needed";
    return true;
  }
  return false;
}

// The checks of an answer, on inputs prepare_verification made for these clouds and options. Returns
// whether the free-space check already judged the answer it leaves (clear_by_free_space).
bool check_answer(RegistrationResult& result, const VerificationInputs& inputs, const RegistrationOptions& options) {
  result.timings_ms["check_inputs"] += inputs.inputs_ms;
  if (inputs.prepared || inputs.source_image) result.timings_ms["dense_preparation"] += inputs.preparation_ms;
  result.counts.source_isolated_points = inputs.source_isolated_points;
  result.counts.target_isolated_points = inputs.target_isolated_points;
  const PointCloud& cropped_source = inputs.source;
  const PointCloud& cropped_target = inputs.target;
  // The overlap guard first: an `ok` answer that fits the points worse than not moving becomes
  // `ambiguous`, and the dense search then gets its chance too.
  check_overlap_against(result, cropped_source, *inputs.coverage, options.ambiguity);
  const bool searches =
      (result.status == RegistrationStatus::Ok || result.status == RegistrationStatus::Ambiguous) && inputs.prepared.has_value();
  if (!searches) return false;
  if (free_space_goes_first(result, inputs, options) && clear_by_free_space(result, inputs, options)) return true;
  const DenseSearchPair& prepared = *inputs.prepared;
  const std::optional<Eigen::Vector4d> source_ground = ground_plane_of(result.source_model), target_ground = ground_plane_of(result.target_model);
  // Optima that put façades where the other sensor saw through are not candidates: with the
  // free-space check's own rule, the searches pick their best and their rivals among the others.
  OptimumScreen in_free_space;
  const AmbiguityOptions& ambiguity = options.ambiguity;
  if (ambiguity.free_space_screens_optima && inputs.source_image && inputs.target_image && source_ground && target_ground)
    in_free_space = [&](const Eigen::Isometry3d& transform) {
      return puts_points_in_free_space(measure_free_space(inputs.source, inputs.target, *inputs.source_image,
                                                          *inputs.target_image, transform, *source_ground, *target_ground,
                                                          ambiguity.free_space_height),
                                       ambiguity);
    };
  check_half_turn(result, cropped_source, cropped_target, options, true, &prepared, in_free_space);
  if (result.status != RegistrationStatus::Ambiguous || !options.dense_search.enabled) return false;
  // The dense search also starts from the poses of the correlation over yaw and ground translation,
  // which reach answers no quadric candidate is near (hard pairs whose cliques hold no true inlier).
  if (options.dense_search.correlation.poses > 0 && source_ground && target_ground)
    timed(result, "ground_correlation", [&] {
      result.ground_correlation =
          correlate_over_ground(cropped_source, cropped_target, *source_ground, *target_ground, options.dense_search.correlation);
      const std::vector<GroundPose>& poses = result.ground_correlation;
      std::ostringstream why;
      why.precision(3);
      why << "; correlation over the ground: " << poses.size() << " poses";
      if (!poses.empty()) why << ", best lands " << poses.front().share << " of the source cells at yaw " << poses.front().yaw_degrees << " deg";
      result.message += why.str();
    });
  timed(result, "dense_search", [&] { settle_with_dense_search(result, prepared, options, in_free_space); });
  // The new answer, under the same guards. A half-turned rival that fits it clearly better takes
  // its place, `ambiguous` (the dense search is not run again): on the tuning set under random yaw
  // one settled answer of 68 was a street's mirror image, and its rival the truth.
  if (result.findings.settled_by_dense_search) {
    check_overlap_against(result, cropped_source, *inputs.coverage, options.ambiguity);
    check_half_turn(result, cropped_source, cropped_target, options, true, &prepared, in_free_space);
  }
  return false;
}

}  // namespace

void verify_prepared_answer(RegistrationResult& result, const VerificationInputs& inputs, const RegistrationOptions& options) {
  const bool judged = check_answer(result, inputs, options);
  if (!judged && inputs.source_image && inputs.target_image)
    check_free_space(result, inputs.source, inputs.target, *inputs.source_image, *inputs.target_image, options.ambiguity);
  check_ground_agreement(result, options);
}

void measure_final_answer(RegistrationResult& result, const VerificationInputs& inputs, const RegistrationOptions& options) {
  result.fitness = result.inlier_rmse = 0.0;
  result.correspondences.clear();
  result.information.setZero();
  if (result.status != RegistrationStatus::Ok && result.status != RegistrationStatus::Ambiguous) return;
  timed(result, "quality", [&] {
    AnswerQuality quality = measure_answer_quality(inputs.source, inputs.target, result.transform, options.quality);
    for (PointCorrespondence& pair : quality.correspondences)
      pair = {inputs.source_indices[pair.first], inputs.target_indices[pair.second]};
    result.fitness = quality.fitness;
    result.inlier_rmse = quality.inlier_rmse;
    result.correspondences = std::move(quality.correspondences);
    result.information = quality.information;
  });
}

void verify_registration(RegistrationResult& result, const PointCloud& source, const PointCloud& target,
                         const RegistrationOptions& options, const ExtractionResult* source_extraction,
                         const ExtractionResult* target_extraction) {
  // The answer is known here: the searches' and the free-space check's preparation is paid only
  // when there is an answer to check.
  const bool may_answer = result.status == RegistrationStatus::Ok || result.status == RegistrationStatus::Ambiguous;
  const VerificationInputs inputs = prepare_verification(source, target, options, source_extraction, target_extraction, may_answer);
  verify_prepared_answer(result, inputs, options);
  measure_final_answer(result, inputs, options);
}

}  // namespace quadrix
