// Registration from an initial guess (see initial_guess.h).
#include "estimation/initial_guess.h"

#include "estimation/stage_timing.h"

#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace quadrix {
namespace {

using stage_timing::timed;

// The correspondence distances of ICP from the initial guess: initial_guess_reach, halved down to
// the dense search's own distance (which is always the last).
std::vector<double> guess_reaches(const RegistrationOptions& options) {
  const double finest = options.dense_search.correspondence_distance;
  std::vector<double> reaches;
  for (double reach = options.initial_guess_reach; reach > finest && reaches.size() < 16; reach /= 2.0) reaches.push_back(reach);
  reaches.push_back(finest);
  return reaches;
}

// Rank of a verified status: `ok` before `ambiguous` before no answer.
int status_rank(RegistrationStatus status) {
  return status == RegistrationStatus::Ok ? 0 : status == RegistrationStatus::Ambiguous ? 1 : 2;
}

}  // namespace

RegistrationResult align_from_guess(const SceneModel& source, const SceneModel& target, const VerificationInputs& inputs,
                                     const RegistrationOptions& options) {
  RegistrationResult result;
  result.source_model = source;
  result.target_model = target;
  result.counts.source_quadrics = source.augmented_begin;
  result.counts.target_quadrics = target.augmented_begin;
  result.counts.source_augmented_points = source.augmented_count();
  result.counts.target_augmented_points = target.augmented_count();
  result.from_initial_guess = true;
  const Eigen::Isometry3d guess = *options.initial_guess;
  if (!inputs.prepared) {
    result.findings.estimation_failure = RegistrationStatus::Failed;
    result.message = "no points to align from the initial guess (a cloud is empty within its range limits)";
    apply_registration_status(result);
    return result;
  }
  timed(result, "guess_icp", [&] {
    DenseSearchOptions icp = options.dense_search;
    Eigen::Isometry3d transform = guess;
    for (const double reach : guess_reaches(options)) {
      icp.correspondence_distance = reach;
      transform = refine_answer(*inputs.prepared, transform, ground_plane_of(source), icp).transform;
    }
    result.transform = transform;
  });
  std::ostringstream summary;
  summary.precision(3);
  summary << "point-to-plane ICP from the initial guess (moved it " << translation_error(result.transform, guess) << " m, "
          << rotation_error_degrees(result.transform, guess) << " deg)";
  result.message = summary.str();
  apply_registration_status(result);
  return result;
}

RegistrationResult compete_with_guess(RegistrationResult global, RegistrationResult guessed, const RegistrationOptions& options) {
  const auto overlap_of = [](const RegistrationResult& r) { return r.overlap ? r.overlap->transformed : 0.0; };
  const int global_rank = status_rank(global.status), guess_rank = status_rank(guessed.status);
  const bool both_ok = global_rank == 0 && guess_rank == 0;
  const bool disagree = translation_error(global.transform, guessed.transform) > options.ambiguity.translation_disagreement ||
                        rotation_error_degrees(global.transform, guessed.transform) > options.ambiguity.rotation_disagreement_degrees;
  const bool guess_wins = guess_rank < global_rank ||
                          (guess_rank == global_rank && guess_rank < 2 && disagree && overlap_of(guessed) > overlap_of(global));
  double guess_ms = 0.0;
  for (const auto& [stage, ms] : guessed.timings_ms) guess_ms += ms;
  std::ostringstream other;
  other.precision(3);
  const RegistrationResult& loser = guess_wins ? global : guessed;
  other << "; " << (guess_wins ? "the initial guess's answer won over the global one" : "the global answer won over the initial guess's")
        << " (" << registration_status_name(loser.status) << ", overlap " << overlap_of(loser) << ", "
        << translation_error(global.transform, guessed.transform) << " m and "
        << rotation_error_degrees(global.transform, guessed.transform) << " deg apart)";
  RegistrationResult winner = std::move(guess_wins ? guessed : global);
  if (guess_wins) {
    winner.candidates = std::move(global.candidates);
    winner.counts = global.counts;
    winner.best_to_second_ratio = global.best_to_second_ratio;
    winner.best_candidate = winner.candidates.size();
    std::map<std::string, double> timings = std::move(global.timings_ms);
    timings["initial_guess"] = guess_ms;
    winner.timings_ms = std::move(timings);
  } else {
    winner.timings_ms["initial_guess"] = guess_ms;
  }
  winner.message += other.str();
  if (both_ok && disagree) {
    winner.findings.guess_disagrees = true;
    winner.message += ": both verified ok, not sure";
    apply_registration_status(winner);
  }
  return winner;
}

}  // namespace quadrix
