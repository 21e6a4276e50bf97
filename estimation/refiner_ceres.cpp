// The "ceres" refiner: Levenberg-Marquardt (Algorithm 1, LMOptimizer) on an SE(3) manifold with
// the analytic quadric-distance Jacobian (Eq. (Jacobian of quadrics distance)).
//
// Parameter block (7 doubles): [qx, qy, qz, qw, tx, ty, tz] (Eigen quaternion order, then t).
// Manifold: tangent delta = [phi; rho], Plus(x, delta) = (q * Exp(phi), t + R(q) rho), i.e. the
// retraction T [+] delta of quadric_distance.h. The cost function reports the ambient 12x7
// Jacobian J_a = J_delta * MinusJacobian(x); since MinusJacobian(x) * PlusJacobian(x) = I_6, Ceres'
// product J_a * PlusJacobian(x) is exactly the analytic 12x6 tangent Jacobian J_delta.
//
// Stopping rules (Ceres' own): |ΔF|/F < function_tolerance, max-norm of the projected gradient <
// gradient_tolerance, |Δx| < parameter_tolerance (|x| + parameter_tolerance), or max_iterations.
#include "estimation/refiner.h"

#include "geometry/error.h"

#include <ceres/ceres.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <string>

namespace quadrix {
namespace {

Eigen::Isometry3d pose_from_parameters(const double* x) {
  const Eigen::Map<const Eigen::Quaterniond> rotation(x);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = rotation.normalized().toRotationMatrix();
  pose.translation() = Eigen::Map<const Eigen::Vector3d>(x + 4);
  return pose;
}

// d Minus(y, x) / d y at y = x, 6x7: [2 (w I - [v]x), -2 v ; 0, R^T] (unit quaternion q = (v, w)).
Eigen::Matrix<double, 6, 7> minus_jacobian(const double* x) {
  const Eigen::Map<const Eigen::Quaterniond> rotation(x);
  const Eigen::Vector3d v = rotation.vec();
  const double w = rotation.w();
  Eigen::Matrix<double, 6, 7> jacobian = Eigen::Matrix<double, 6, 7>::Zero();
  jacobian.block<3, 3>(0, 0) = 2.0 * (w * Eigen::Matrix3d::Identity() - skew(v));
  jacobian.block<3, 1>(0, 3) = -2.0 * v;
  jacobian.block<3, 3>(3, 4) = rotation.normalized().toRotationMatrix().transpose();
  return jacobian;
}

// SE(3) with the right perturbation of quadric_distance.h (rotation first, body-frame translation).
class RightPerturbationSe3Manifold final : public ceres::Manifold {
 public:
  int AmbientSize() const override { return 7; }
  int TangentSize() const override { return 6; }

  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override {
    const Eigen::Map<const Vector6d> increment(delta);
    const Eigen::Isometry3d updated = apply_increment(pose_from_parameters(x), increment);
    Eigen::Quaterniond rotation(updated.linear());
    rotation.normalize();
    // Keep the quaternion on the same hemisphere as x so the parameters move continuously.
    if (rotation.coeffs().dot(Eigen::Map<const Eigen::Vector4d>(x)) < 0.0) rotation.coeffs() *= -1.0;
    Eigen::Map<Eigen::Vector4d>{x_plus_delta} = rotation.coeffs();
    Eigen::Map<Eigen::Vector3d>{x_plus_delta + 4} = updated.translation();
    return true;
  }

  // 7x6 row-major: [0.5 (w I + [v]x) ; -0.5 v^T] for the quaternion, R for the translation.
  bool PlusJacobian(const double* x, double* jacobian) const override {
    const Eigen::Map<const Eigen::Quaterniond> rotation(x);
    const Eigen::Vector3d v = rotation.vec();
    Eigen::Map<Eigen::Matrix<double, 7, 6, Eigen::RowMajor>> result(jacobian);
    result.setZero();
    result.block<3, 3>(0, 0) = 0.5 * (rotation.w() * Eigen::Matrix3d::Identity() + skew(v));
    result.block<1, 3>(3, 0) = -0.5 * v.transpose();
    result.block<3, 3>(4, 3) = rotation.normalized().toRotationMatrix();
    return true;
  }

  // y [-] x = [Log(R_x^T R_y); R_x^T (t_y - t_x)], the inverse of Plus.
  bool Minus(const double* y, const double* x, double* y_minus_x) const override {
    const Eigen::Isometry3d pose_x = pose_from_parameters(x);
    const Eigen::Isometry3d pose_y = pose_from_parameters(y);
    const Eigen::AngleAxisd relative(pose_x.linear().transpose() * pose_y.linear());
    Eigen::Map<Eigen::Vector3d>{y_minus_x} = relative.angle() * relative.axis();
    Eigen::Map<Eigen::Vector3d>{y_minus_x + 3} =
        pose_x.linear().transpose() * (pose_y.translation() - pose_x.translation());
    return true;
  }

  bool MinusJacobian(const double* x, double* jacobian) const override {
    Eigen::Map<Eigen::Matrix<double, 6, 7, Eigen::RowMajor>>{jacobian} = minus_jacobian(x);
    return true;
  }
};

// One factor: residual sqrt(w) e (Eq. (quadrics distance)), analytic Jacobian lifted to 7 parameters.
class QuadricDistanceCost final : public ceres::SizedCostFunction<12, 7> {
 public:
  explicit QuadricDistanceCost(const QuadricFactor& factor) : factor_(factor), root_weight_(std::sqrt(factor.weight)) {}

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const Eigen::Isometry3d pose = pose_from_parameters(parameters[0]);
    Vector12d residual;
    if (jacobians && jacobians[0]) {
      Matrix12x6d tangent_jacobian;
      quadric_distance_with_jacobian(factor_, pose, &residual, &tangent_jacobian);
      Eigen::Map<Eigen::Matrix<double, 12, 7, Eigen::RowMajor>>{jacobians[0]} =
          root_weight_ * tangent_jacobian * minus_jacobian(parameters[0]);
    } else {
      residual = quadric_distance(factor_, pose);
    }
    Eigen::Map<Vector12d>{residuals} = root_weight_ * residual;
    return true;
  }

 private:
  QuadricFactor factor_;
  double root_weight_;
};

// Dynamic covariance scaling (Agarwal et al. 2013) as an M-estimator on s = ||f||^2:
// rho(s) = s for s <= Phi, Phi (3 s - Phi) / (Phi + s) beyond; rho'(s) = (2 Phi / (Phi + s))^2 is the
// square of the DCS scale factor min(1, 2 Phi / (Phi + s)) applied to the residual.
class DynamicCovarianceScalingLoss final : public ceres::LossFunction {
 public:
  explicit DynamicCovarianceScalingLoss(double phi) : phi_(phi) {}
  void Evaluate(double s, double rho[3]) const override {
    const LossValue value = evaluate_robust_loss(RobustLoss::Dcs, phi_, s);
    rho[0] = value.rho;
    rho[1] = value.derivative;
    rho[2] = value.second;
  }

 private:
  double phi_;
};

ceres::LossFunction* make_loss(RobustLoss loss, double scale) {
  if (loss != RobustLoss::None && !(scale > 0.0 && std::isfinite(scale)))
    throw Error(std::string("ceres refiner: loss_scale must be finite and > 0 for loss '") + robust_loss_name(loss) + "'");
  switch (loss) {
    case RobustLoss::None: return nullptr;
    case RobustLoss::Huber: return new ceres::HuberLoss(scale);
    case RobustLoss::Cauchy: return new ceres::CauchyLoss(scale);
    case RobustLoss::Dcs: return new DynamicCovarianceScalingLoss(scale);
  }
  return nullptr;
}

class CeresRefiner final : public Refiner {
 public:
  std::string name() const override { return "ceres"; }

  RefinementResult refine(const std::vector<QuadricFactor>& factors, const Eigen::Isometry3d& initial,
                          const RefinerOptions& options) const override {
    const auto start_time = std::chrono::steady_clock::now();
    const std::string algorithm = options.algorithm.empty() ? "levenberg_marquardt" : options.algorithm;
    if (algorithm != "levenberg_marquardt" && algorithm != "dogleg")
      throw Error("ceres refiner: unknown algorithm '" + algorithm + "' (expected levenberg_marquardt or dogleg)");
    if (options.max_iterations <= 0) throw Error("ceres refiner: max_iterations must be > 0");
    RefinementResult result = start_refinement(name(), algorithm, factors, initial, options, start_time);
    if (result.status == RefinementStatus::Degenerate) return result;

    Eigen::Quaterniond start_rotation(initial.linear());
    start_rotation.normalize();
    double parameters[7];
    Eigen::Map<Eigen::Vector4d>{parameters} = start_rotation.coeffs();
    Eigen::Map<Eigen::Vector3d>{parameters + 4} = initial.translation();

    ceres::Problem problem;
    ceres::LossFunction* loss = make_loss(options.loss, options.loss_scale);  // shared; the problem deletes it once
    for (const QuadricFactor& factor : factors)
      problem.AddResidualBlock(new QuadricDistanceCost(factor), loss, parameters);
    problem.SetManifold(parameters, new RightPerturbationSe3Manifold);

    ceres::Solver::Options solver_options;
    solver_options.minimizer_type = ceres::TRUST_REGION;
    solver_options.trust_region_strategy_type =
        algorithm == "dogleg" ? ceres::DOGLEG : ceres::LEVENBERG_MARQUARDT;
    solver_options.linear_solver_type = ceres::DENSE_QR;
    solver_options.max_num_iterations = options.max_iterations;
    solver_options.function_tolerance = options.function_tolerance;
    solver_options.gradient_tolerance = options.gradient_tolerance;
    solver_options.parameter_tolerance = options.parameter_tolerance;
    solver_options.num_threads = 1;
    solver_options.logging_type = ceres::SILENT;
    solver_options.minimizer_progress_to_stdout = false;
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options, &problem, &summary);

    result.iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
    result.evaluations = summary.num_residual_evaluations;
    result.message = summary.message;
    switch (summary.termination_type) {
      case ceres::CONVERGENCE:
      case ceres::USER_SUCCESS: result.status = RefinementStatus::Converged; break;
      case ceres::NO_CONVERGENCE: result.status = RefinementStatus::MaxIterations; break;
      default: result.status = RefinementStatus::Failed; break;
    }
    if (result.status != RefinementStatus::Failed && summary.IsSolutionUsable()) {
      result.transform = pose_from_parameters(parameters);
      result.final_cost = refinement_cost(factors, result.transform, options.loss, options.loss_scale);
    }
    mark_degenerate_solution(factors, options, &result);
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
    return result;
  }
};

}  // namespace

std::unique_ptr<Refiner> make_ceres_refiner() { return std::make_unique<CeresRefiner>(); }

}  // namespace quadrix
