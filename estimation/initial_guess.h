// Registration from a pose the caller already has (odometry, a previous answer; beyond the paper):
// point-to-plane ICP from it, coarse to fine, then the same verification as a global answer. With
// RegistrationOptions::local_only it is the only answer; otherwise it competes with the global one.
#pragma once

#include "estimation/registration_types.h"
#include "estimation/verification.h"

namespace quadrix {

/// The answer of local registration: point-to-plane ICP from `options.initial_guess` (required) on
/// the checks' prepared pair, refine_answer at correspondence distances from
/// `options.initial_guess_reach` halved down to dense_search.correspondence_distance, with the
/// models for the checks. Its status is provisional (`ok`: there is no quadric rival to be unsure
/// about; `failed` when a cloud has no point to align); verify_prepared_answer decides. Sets
/// from_initial_guess and the "guess_icp" timing.
RegistrationResult align_from_guess(const SceneModel& source, const SceneModel& target, const VerificationInputs& inputs,
                                    const RegistrationOptions& options);

/// The global answer and the one from the initial guess, both verified, compete: the better status
/// wins (`ok`, then `ambiguous`, then none), then, with the same status, the one landing more of the
/// source on the target (check_overlap's measure); the global answer wins ties. Two `ok` answers
/// that disagree (AmbiguityOptions::translation_disagreement, rotation_disagreement_degrees) leave
/// the winner `ambiguous` (findings.guess_disagrees). The result keeps the global run's candidates
/// and counts (best_candidate is candidates.size() when the guess won) and its timings, with the
/// guess's run added as "initial_guess".
RegistrationResult compete_with_guess(RegistrationResult global, RegistrationResult guessed, const RegistrationOptions& options);

}  // namespace quadrix
