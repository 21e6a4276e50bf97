// The "nlopt" refiner: the same objective as the Ceres backend, F = 1/2 sum_k rho(w_k ||e_k||^2)
// (Eq. (quadrics distance)), minimised over a 6-parameter increment delta = [phi; rho] around the
// start pose T0: T(delta) = T0 [+] delta = (R0 Exp(phi), t0 + R0 rho).
//
// Algorithms: "lbfgs" (NLOPT_LD_LBFGS, default), "slsqp" (NLOPT_LD_SLSQP, no constraints) and the
// derivative-free "bobyqa" (NLOPT_LN_BOBYQA, initial steps initial_rotation_step /
// initial_translation_step). The gradient is exact through the retraction:
//   dF/d delta = sum_k rho'(s_k) w_k e_k^T [ J_phi(T) Jr(phi) | J_rho(T) Exp(phi)^T ],
// with J = Eq. (Jacobian of quadrics distance) at T = T(delta) and Jr the right Jacobian of SO(3).
//
// Stopping rules: ftol_rel = function_tolerance (|ΔF| / |F|), xtol_abs = parameter_tolerance on
// every component of delta, stopval = absolute_cost_tolerance (F is >= 0), maxeval =
// max_evaluations; bounds |phi_i| <= pi and |rho_i| <= 1e4 m keep BOBYQA's trust region finite.
// NLopt does not expose iterations: `iterations` counts evaluations that improved the best cost.
// NLOPT_ROUNDOFF_LIMITED (no further progress possible in floating point) counts as converged.
#include "estimation/refiner.h"

#include "geometry/constants.h"
#include "geometry/error.h"

#include <nlopt.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <string>

namespace quadrix {
namespace {

// Right Jacobian of SO(3): Exp(phi + d) ~ Exp(phi) Exp(Jr(phi) d).
Eigen::Matrix3d right_jacobian_so3(const Eigen::Vector3d& phi) {
  const double angle = phi.norm();
  const Eigen::Matrix3d phi_hat = skew(phi);
  if (angle < 1e-6) return Eigen::Matrix3d::Identity() - 0.5 * phi_hat + (1.0 / 6.0) * phi_hat * phi_hat;
  const double angle2 = angle * angle;
  return Eigen::Matrix3d::Identity() - (1.0 - std::cos(angle)) / angle2 * phi_hat +
         (angle - std::sin(angle)) / (angle2 * angle) * phi_hat * phi_hat;
}

struct ObjectiveData {
  const std::vector<QuadricFactor>* factors = nullptr;
  Eigen::Isometry3d start = Eigen::Isometry3d::Identity();
  RobustLoss loss = RobustLoss::None;
  double loss_scale = 1.0;
  int evaluations = 0;
  int improvements = 0;
  double best_cost = std::numeric_limits<double>::infinity();
};

double objective(unsigned dimension, const double* x, double* gradient, void* opaque) {
  auto* data = static_cast<ObjectiveData*>(opaque);
  (void)dimension;
  const Eigen::Map<const Vector6d> increment(x);
  const Eigen::Isometry3d pose = apply_increment(data->start, increment);
  Vector6d total_gradient = Vector6d::Zero();
  double cost = 0.0;
  Vector12d residual;
  Matrix12x6d jacobian;
  Eigen::Matrix3d rotation_chain;
  Eigen::Matrix3d translation_chain;
  if (gradient) {
    const Eigen::Vector3d phi = increment.head<3>();
    rotation_chain = right_jacobian_so3(phi);
    // J_rho(T) = d e / d t_world * R, and d t / d rho = R0 = R Exp(phi)^T.
    translation_chain = data->start.linear().transpose() * pose.linear();
    translation_chain.transposeInPlace();
  }
  for (const QuadricFactor& factor : *data->factors) {
    if (gradient) {
      quadric_distance_with_jacobian(factor, pose, &residual, &jacobian);
    } else {
      residual = quadric_distance(factor, pose);
    }
    const double squared = factor.weight * residual.squaredNorm();
    const LossValue value = evaluate_robust_loss(data->loss, data->loss_scale, squared);
    cost += 0.5 * value.rho;
    if (gradient) {
      const Eigen::Matrix<double, 1, 12> scaled = value.derivative * factor.weight * residual.transpose();
      total_gradient.head<3>() += (scaled * jacobian.leftCols<3>() * rotation_chain).transpose();
      total_gradient.tail<3>() += (scaled * jacobian.rightCols<3>() * translation_chain).transpose();
    }
  }
  if (gradient) Eigen::Map<Vector6d>{gradient} = total_gradient;
  ++data->evaluations;
  if (cost < data->best_cost) {
    data->best_cost = cost;
    ++data->improvements;
  }
  return cost;
}

nlopt_algorithm algorithm_from_name(const std::string& name) {
  if (name == "lbfgs") return NLOPT_LD_LBFGS;
  if (name == "slsqp") return NLOPT_LD_SLSQP;
  if (name == "bobyqa") return NLOPT_LN_BOBYQA;
  throw Error("nlopt refiner: unknown algorithm '" + name + "' (expected lbfgs, slsqp or bobyqa)");
}

class NloptRefiner final : public Refiner {
 public:
  std::string name() const override { return "nlopt"; }

  RefinementResult refine(const std::vector<QuadricFactor>& factors, const Eigen::Isometry3d& initial,
                          const RefinerOptions& options) const override {
    const auto start_time = std::chrono::steady_clock::now();
    const std::string algorithm = options.algorithm.empty() ? "lbfgs" : options.algorithm;
    const nlopt_algorithm nlopt_code = algorithm_from_name(algorithm);
    if (options.max_evaluations <= 0) throw Error("nlopt refiner: max_evaluations must be > 0");
    if (options.loss != RobustLoss::None && !(options.loss_scale > 0.0 && std::isfinite(options.loss_scale)))
      throw Error(std::string("nlopt refiner: loss_scale must be finite and > 0 for loss '") +
                  robust_loss_name(options.loss) + "'");
    if (!(options.initial_rotation_step > 0.0) || !(options.initial_translation_step > 0.0))
      throw Error("nlopt refiner: initial_rotation_step and initial_translation_step must be > 0");
    RefinementResult result = start_refinement(name(), algorithm, factors, initial, options, start_time);
    if (result.status == RefinementStatus::Degenerate) return result;

    ObjectiveData data;
    data.factors = &factors;
    data.start = initial;
    data.loss = options.loss;
    data.loss_scale = options.loss_scale;

    const std::unique_ptr<nlopt_opt_s, decltype(&nlopt_destroy)> optimizer(nlopt_create(nlopt_code, 6), &nlopt_destroy);
    if (!optimizer) throw Error("nlopt refiner: nlopt_create failed for algorithm '" + algorithm + "'");
    constexpr double kTranslationBound = 1e4;
    const double lower[6] = {-kPi, -kPi, -kPi, -kTranslationBound, -kTranslationBound, -kTranslationBound};
    const double upper[6] = {kPi, kPi, kPi, kTranslationBound, kTranslationBound, kTranslationBound};
    const double steps[6] = {options.initial_rotation_step, options.initial_rotation_step, options.initial_rotation_step,
                             options.initial_translation_step, options.initial_translation_step,
                             options.initial_translation_step};
    nlopt_opt handle = optimizer.get();
    nlopt_set_min_objective(handle, &objective, &data);
    nlopt_set_lower_bounds(handle, lower);
    nlopt_set_upper_bounds(handle, upper);
    nlopt_set_initial_step(handle, steps);
    nlopt_set_ftol_rel(handle, options.function_tolerance);
    nlopt_set_xtol_abs1(handle, options.parameter_tolerance);
    nlopt_set_stopval(handle, options.absolute_cost_tolerance);
    nlopt_set_maxeval(handle, options.max_evaluations);
    if (nlopt_code == NLOPT_LD_LBFGS) nlopt_set_vector_storage(handle, 10);

    double increment[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    double minimum = 0.0;
    const nlopt_result code = nlopt_optimize(handle, increment, &minimum);

    result.evaluations = data.evaluations;
    result.iterations = data.improvements;
    switch (code) {
      case NLOPT_SUCCESS:
      case NLOPT_STOPVAL_REACHED:
      case NLOPT_FTOL_REACHED:
      case NLOPT_XTOL_REACHED:
        result.status = RefinementStatus::Converged;
        break;
      case NLOPT_ROUNDOFF_LIMITED:
        result.status = RefinementStatus::Converged;
        break;
      case NLOPT_MAXEVAL_REACHED:
      case NLOPT_MAXTIME_REACHED:
        result.status = RefinementStatus::MaxIterations;
        break;
      default:
        result.status = RefinementStatus::Failed;
        break;
    }
    result.message = std::string("nlopt ") + nlopt_algorithm_name(nlopt_code) + ": " + nlopt_result_to_string(code);
    if (result.status != RefinementStatus::Failed && Eigen::Map<const Vector6d>(increment).allFinite()) {
      const Eigen::Isometry3d refined = apply_increment(initial, Eigen::Map<const Vector6d>(increment));
      const double refined_cost = refinement_cost(factors, refined, options.loss, options.loss_scale);
      if (refined_cost <= result.initial_cost) {
        result.transform = refined;
        result.final_cost = refined_cost;
      }
    } else if (result.status != RefinementStatus::Failed) {
      result.status = RefinementStatus::Failed;
      result.message += " (non-finite increment)";
    }
    mark_degenerate_solution(factors, options, &result);
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
    return result;
  }
};

}  // namespace

std::unique_ptr<Refiner> make_nlopt_refiner() { return std::make_unique<NloptRefiner>(); }

}  // namespace quadrix
