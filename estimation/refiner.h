// Refinement of one transformation candidate from its quadric factors (Algorithm 1, LMOptimizer):
// minimise  F(T) = 1/2 sum_k rho(w_k ||e_k(T)||^2)  over T in SE(3), e_k = Eq. (quadrics distance),
// starting from the SVD estimate. Backends are chosen by name from a registry so studies can
// compare them on the same objective:
//   "ceres": Levenberg-Marquardt (or dogleg) with the analytic Jacobian on an SE(3) manifold
//            (quaternion + translation, tangent [phi; rho] of the right perturbation).
//   "nlopt": L-BFGS, SLSQP (gradient = sum rho' J^T w e, exact through the retraction) or the
//            derivative-free BOBYQA, over a 6-parameter increment delta around the start pose.
// Before optimising, both check that the factors constrain all 6 DoF (rank of J^T J at the start)
// and refuse with status Degenerate otherwise, reporting the unconstrained directions; they check
// again at the refined pose (a start far from alignment can hide a structural degeneracy).
#pragma once

#include "estimation/quadric_distance.h"
#include "geometry/error.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace quadrix {

/// Outcome of a refinement.
enum class RefinementStatus : std::uint8_t {
  Converged,      ///< a stopping tolerance was met
  MaxIterations,  ///< the iteration/evaluation budget ran out first (the pose is the best found)
  Failed,         ///< the backend reported an error (the pose is the start pose)
  Degenerate,     ///< the factors do not constrain all 6 DoF: at the start pose (no optimisation ran, transform = start)
                  ///< or at the refined pose (transform = refined, but not unique along weak_directions)
};

/// Lower-case status name ("converged", "max_iterations", "failed", "degenerate").
inline const char* refinement_status_name(RefinementStatus status) {
  switch (status) {
    case RefinementStatus::Converged: return "converged";
    case RefinementStatus::MaxIterations: return "max_iterations";
    case RefinementStatus::Failed: return "failed";
    case RefinementStatus::Degenerate: return "degenerate";
  }
  return "failed";
}

/// Options shared by every backend (published defaults: LM, 300 iterations, tolerance 1e-8).
struct RefinerOptions {
  std::string algorithm;             ///< backend algorithm; empty = default. ceres: "levenberg_marquardt" | "dogleg"; nlopt: "lbfgs" | "slsqp" | "bobyqa"
  int max_iterations = 300;          ///< ceres: max LM iterations; nlopt: not used (see max_evaluations)
  int max_evaluations = 5000;        ///< nlopt: maxeval, objective evaluations; ceres: not used
  double function_tolerance = 1e-8;  ///< stop when |ΔF| / F < this (ceres function_tolerance, nlopt ftol_rel)
  double gradient_tolerance = 1e-10; ///< ceres: max-norm of the projected gradient; nlopt: not used
  double parameter_tolerance = 1e-10;///< stop when the step is below this: ceres parameter_tolerance (relative), nlopt xtol_abs on delta
  double absolute_cost_tolerance = 1e-20;  ///< nlopt: stop when F < this (stopval); ceres stops there via its gradient test
  RobustLoss loss = RobustLoss::None;      ///< robust kernel applied to w ||e||^2 per factor
  double loss_scale = 1.0;                 ///< a of Huber/Cauchy, Phi of DCS (units of ||e||, i.e. metres / unit-vector length)
  double initial_rotation_step = 0.05;     ///< nlopt BOBYQA initial step of phi, radians
  double initial_translation_step = 0.5;   ///< nlopt BOBYQA initial step of rho, metres
  double degeneracy_threshold = 1e-6;      ///< eigenvalue of J^T J below this * largest: direction unconstrained
  bool check_degeneracy = true;            ///< false: optimise even when J^T J is rank-deficient (free directions keep the start pose); used by term ablations
};

/// Result and diagnostics of one refinement (identical fields for every backend).
struct RefinementResult {
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();  ///< refined T (the start pose unless optimised)
  RefinementStatus status = RefinementStatus::Failed;           ///< see RefinementStatus
  std::string backend;                 ///< registry name ("ceres", "nlopt")
  std::string algorithm;               ///< algorithm actually run
  int iterations = 0;                  ///< ceres: minimiser iterations; nlopt: evaluations that improved the best cost
  int evaluations = 0;                 ///< objective (residual) evaluations
  double initial_cost = 0.0;           ///< F at the start pose
  double final_cost = 0.0;             ///< F at the returned pose
  double seconds = 0.0;                ///< wall-clock time of the refinement
  std::size_t factor_count = 0;        ///< factors in the problem
  int constrained_rank = 0;            ///< rank of J^T J (6 = fully constrained; when Degenerate, at the pose that failed the check)
  std::vector<Vector6d> weak_directions;  ///< unit increments [phi; rho] that J^T J does not constrain
  std::string message;                 ///< backend report or why the problem is degenerate
};

/// The common start of every backend's refine(): rejects negative or non-finite factor weights
/// (quadrix::Error naming the backend and factor), fills the result's backend, algorithm, start
/// transform, factor count and initial cost, and analyses the constraints at the start pose; when
/// fewer than 6 DoF are constrained the result comes back with status Degenerate (and its time),
/// otherwise with status Failed until the backend sets its own outcome.
inline RefinementResult start_refinement(const std::string& backend, const std::string& algorithm,
                                         const std::vector<QuadricFactor>& factors, const Eigen::Isometry3d& initial,
                                         const RefinerOptions& options,
                                         std::chrono::steady_clock::time_point start_time) {
  for (std::size_t k = 0; k < factors.size(); ++k)
    if (!(factors[k].weight >= 0.0) || !std::isfinite(factors[k].weight))
      throw Error(backend + " refiner: factor " + std::to_string(k) + " has a negative or non-finite weight");
  RefinementResult result;
  result.backend = backend;
  result.algorithm = algorithm;
  result.transform = initial;
  result.factor_count = factors.size();
  result.initial_cost = refinement_cost(factors, initial, options.loss, options.loss_scale);
  result.final_cost = result.initial_cost;
  const ConstraintAnalysis constraints = analyse_constraints(factors, initial, options.degeneracy_threshold);
  result.constrained_rank = constraints.rank;
  result.weak_directions = constraints.weak_directions;
  if (constraints.rank < 6 && options.check_degeneracy) {
    result.status = RefinementStatus::Degenerate;
    result.message = "the factors constrain only " + std::to_string(constraints.rank) +
                     " of 6 degrees of freedom at the start pose (see weak_directions)";
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
  }
  return result;
}

/// Re-checks degeneracy at the refined pose and marks `result` Degenerate (rank, weak directions,
/// message) when a DoF is free there: the start-pose check can miss a structural degeneracy, e.g.
/// misaligned parallel planes look constrained until they are aligned. Shared by every backend.
inline void mark_degenerate_solution(const std::vector<QuadricFactor>& factors, const RefinerOptions& options,
                                     RefinementResult* result) {
  if (result->status == RefinementStatus::Failed || !options.check_degeneracy) return;
  const ConstraintAnalysis at_solution = analyse_constraints(factors, result->transform, options.degeneracy_threshold);
  if (at_solution.rank == 6) return;
  result->status = RefinementStatus::Degenerate;
  result->constrained_rank = at_solution.rank;
  result->weak_directions = at_solution.weak_directions;
  result->message = "the factors constrain only " + std::to_string(at_solution.rank) +
                    " of 6 degrees of freedom at the refined pose (see weak_directions); " + result->message;
}

/// A refinement backend: same objective, same result fields.
class Refiner {
 public:
  virtual ~Refiner() = default;
  /// Registry name of the backend.
  virtual std::string name() const = 0;
  /// Refines `initial` on `factors`. Throws quadrix::Error for an unknown algorithm, a negative
  /// weight or non-positive budgets; degenerate factor sets give status Degenerate.
  virtual RefinementResult refine(const std::vector<QuadricFactor>& factors, const Eigen::Isometry3d& initial,
                                  const RefinerOptions& options = {}) const = 0;
};

/// The built-in Ceres backend.
std::unique_ptr<Refiner> make_ceres_refiner();
/// The built-in NLopt backend.
std::unique_ptr<Refiner> make_nlopt_refiner();

/// Makes a refiner.
using RefinerFactory = std::function<std::unique_ptr<Refiner>()>;

/// The registry by name, holding "ceres" and "nlopt" from the start.
inline std::map<std::string, RefinerFactory>& refiner_registry() {
  static std::map<std::string, RefinerFactory> registry{{"ceres", &make_ceres_refiner}, {"nlopt", &make_nlopt_refiner}};
  return registry;
}

/// Adds or replaces a backend under `name`.
inline void register_refiner(const std::string& name, RefinerFactory factory) {
  refiner_registry()[name] = std::move(factory);
}

/// Names of every registered backend, sorted.
inline std::vector<std::string> refiner_names() {
  std::vector<std::string> names;
  for (const auto& entry : refiner_registry()) names.push_back(entry.first);
  return names;
}

/// The backend registered under `name`; throws quadrix::Error listing the known names otherwise.
inline std::unique_ptr<Refiner> make_refiner(const std::string& name) {
  const auto& registry = refiner_registry();
  const auto found = registry.find(name);
  if (found == registry.end()) {
    std::string known;
    for (const auto& entry : registry) known += (known.empty() ? "" : ", ") + entry.first;
    throw Error("unknown refiner '" + name + "' (known: " + known + ")");
  }
  return found->second();
}

}  // namespace quadrix
