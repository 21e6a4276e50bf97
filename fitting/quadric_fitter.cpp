// Registry, shared evaluation and small helpers of the QuadricFitter interface.
#include "fitting/quadric_fitter.h"

#include "fitting/cgal_fitter.h"
#include "fitting/constrained_fitter.h"
#include "fitting/learned_fitter.h"
#include "fitting/statistical_fitter.h"
#include "fitting/taubin_fitter.h"
#include "geometry/error.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <utility>

namespace quadrix {

std::string fit_status_name(FitStatus status) {
  switch (status) {
    case FitStatus::Ok: return "ok";
    case FitStatus::TooFewPoints: return "too_few_points";
    case FitStatus::Degenerate: return "degenerate";
    case FitStatus::TypeMismatch: return "type_mismatch";
    case FitStatus::NotConverged: return "not_converged";
    case FitStatus::Failed: return "failed";
  }
  return "failed";
}

FitTypeHint fit_type_hint_from_name(const std::string& name) {
  if (name == "auto") return std::nullopt;
  static const std::vector<std::pair<std::string, QuadricType>> accepted = {
      {"point", QuadricType::Point},
      {"line", QuadricType::Line},
      {"plane", QuadricType::Plane},
      {"sphere", QuadricType::Sphere},
      {"ellipsoid", QuadricType::Ellipsoid},
      {"cylinder", QuadricType::CircularCylinder},
      {"circular_cylinder", QuadricType::CircularCylinder},
      {"elliptic_cylinder", QuadricType::EllipticCylinder},
      {"cone", QuadricType::CircularCone},
      {"circular_cone", QuadricType::CircularCone},
      {"elliptic_cone", QuadricType::EllipticCone},
  };
  for (const auto& [text, type] : accepted)
    if (text == name) return type;
  throw Error("--type: unknown quadric type '" + name +
              "' (expected auto, point, line, plane, sphere, ellipsoid, cylinder, elliptic_cylinder, cone, elliptic_cone)");
}

std::size_t minimum_points_for_type(QuadricType type) {
  switch (type) {
    case QuadricType::Point: return 1;
    case QuadricType::Line: return 2;
    case QuadricType::Plane: return 3;
    case QuadricType::Sphere: return 4;
    default: return 9;  // a general quadric has 9 degrees of freedom
  }
}

std::string residual_evaluation_name(ResidualEvaluation evaluation) {
  switch (evaluation) {
    case ResidualEvaluation::Exact: return "exact";
    case ResidualEvaluation::Subsample: return "subsample";
    case ResidualEvaluation::Skip: return "skip";
  }
  return "exact";
}

ResidualEvaluation residual_evaluation_from_name(const std::string& name, const std::string& field) {
  for (const ResidualEvaluation evaluation :
       {ResidualEvaluation::Exact, ResidualEvaluation::Subsample, ResidualEvaluation::Skip})
    if (residual_evaluation_name(evaluation) == name) return evaluation;
  throw Error(field + ": unknown residual evaluation '" + name + "' (expected exact, subsample or skip)");
}

ResidualSample residual_sample(Eigen::Index point_count, const FitEvaluationOptions& evaluation) {
  ResidualSample sample;
  if (evaluation.residuals == ResidualEvaluation::Skip || point_count <= 0) return sample;
  if (evaluation.residuals == ResidualEvaluation::Subsample) {
    if (evaluation.max_points < 1)
      throw Error("fitter evaluation: max_points must be at least 1 for subsampled residuals, got " +
                  std::to_string(evaluation.max_points));
    sample.stride = (point_count + evaluation.max_points - 1) / evaluation.max_points;
  }
  sample.count = (point_count + sample.stride - 1) / sample.stride;
  return sample;
}

namespace {
using FitterFactory = std::function<std::unique_ptr<QuadricFitter>(const FitEvaluationOptions&)>;

/// Options of type `Options` with only the residual evaluation changed.
template <typename Options>
Options with_evaluation(const FitEvaluationOptions& evaluation) {
  Options options;
  options.evaluation = evaluation;
  return options;
}

const std::vector<std::pair<std::string, FitterFactory>>& fitter_registry() {
  static const std::vector<std::pair<std::string, FitterFactory>> registry = {
      {"statistical", [](const FitEvaluationOptions& e) { return make_statistical_fitter(with_evaluation<StatisticalFitterOptions>(e)); }},
      {"taubin", [](const FitEvaluationOptions& e) { return make_taubin_fitter(with_evaluation<TaubinFitterOptions>(e)); }},
      {"learned", [](const FitEvaluationOptions& e) { return make_learned_fitter(with_evaluation<LearnedFitterOptions>(e)); }},
      {"auto", [](const FitEvaluationOptions& e) {
         AutoFitterOptions options;
         options.learned.evaluation = e;
         options.statistical.evaluation = e;
         return make_auto_fitter(options);
       }},
      {"constrained", [](const FitEvaluationOptions& e) { return make_constrained_fitter(with_evaluation<ConstrainedFitterOptions>(e)); }},
      {"cgal", [](const FitEvaluationOptions& e) { return make_cgal_fitter(with_evaluation<CgalFitterOptions>(e)); }},
  };
  return registry;
}
}  // namespace

std::unique_ptr<QuadricFitter> make_quadric_fitter(const std::string& name) {
  return make_quadric_fitter(name, FitEvaluationOptions{});
}

std::unique_ptr<QuadricFitter> make_quadric_fitter(const std::string& name, const FitEvaluationOptions& evaluation) {
  for (const auto& [registered, factory] : fitter_registry())
    if (registered == name) return factory(evaluation);
  std::string valid;
  for (const auto& entry : fitter_registry()) valid += (valid.empty() ? "" : ", ") + entry.first;
  throw Error("--fitter: unknown fitter '" + name + "' (expected one of: " + valid + ")");
}

std::vector<std::string> quadric_fitter_names() {
  std::vector<std::string> names;
  for (const auto& entry : fitter_registry()) names.push_back(entry.first);
  return names;
}

double unit_space_algebraic_distance(const Eigen::Matrix3Xd& points, const Quadric& quadric) {
  return unit_space_algebraic_distance(points, quadric, ResidualSample{1, points.cols()});
}

double unit_space_algebraic_distance(const Eigen::Matrix3Xd& points, const Quadric& quadric, const ResidualSample& sample) {
  if (sample.count <= 0) return 0.0;
  const auto column = [&](Eigen::Index i) { return points.col(i * sample.stride); };
  const double count = static_cast<double>(sample.count);
  // Unit space: x_u = (x - c) / sigma; the world quadric seen in unit space is A^-T Q A^-1 with
  // A = [I/sigma, -c/sigma; 0, 1], i.e. Q_u = B^T Q B with B = A^-1 = [sigma I, c; 0, 1].
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  for (Eigen::Index i = 0; i < sample.count; ++i) center += column(i);
  center /= count;
  double squared_radius = 0.0;
  for (Eigen::Index i = 0; i < sample.count; ++i) squared_radius += (column(i) - center).squaredNorm();
  const double radius = std::sqrt(squared_radius / count);
  const double sigma = radius > 0.0 ? radius : 1.0;
  Eigen::Matrix4d to_world = Eigen::Matrix4d::Identity();
  to_world.topLeftCorner<3, 3>() *= sigma;
  to_world.topRightCorner<3, 1>() = center;
  const Quadric unit(to_world.transpose() * quadric.matrix() * to_world);
  const Quadric normalized = unit.normalized();
  double sum = 0.0;
  for (Eigen::Index i = 0; i < sample.count; ++i) sum += normalized.sampson_distance((column(i) - center) / sigma);
  return sum / count;
}

StatisticalPose point_statistics(const Eigen::Matrix3Xd& points, double scale_factor, Eigen::Matrix3d* covariance_out) {
  // Paper §"Quadric Fitting", statistics-based method steps 1-2: t_s = mean, covariance of the
  // centred points, R_s = its eigenvectors by descending eigenvalue, s_s = k_s sqrt(eigenvalues).
  StatisticalPose pose;
  const Eigen::Index count = points.cols();
  if (covariance_out != nullptr) covariance_out->setZero();
  if (count < 1) return pose;
  pose.center = points.rowwise().mean();
  // Second pass: the six distinct sums of centred products in scalars (no copy of the points).
  double xx = 0.0, xy = 0.0, xz = 0.0, yy = 0.0, yz = 0.0, zz = 0.0;
  const double* data = points.data();
  const double cx = pose.center.x(), cy = pose.center.y(), cz = pose.center.z();
  for (Eigen::Index i = 0; i < count; ++i) {
    const double x = data[3 * i] - cx, y = data[3 * i + 1] - cy, z = data[3 * i + 2] - cz;
    xx += x * x;
    xy += x * y;
    xz += x * z;
    yy += y * y;
    yz += y * z;
    zz += z * z;
  }
  Eigen::Matrix3d covariance;
  covariance << xx, xy, xz, xy, yy, yz, xz, yz, zz;
  covariance /= static_cast<double>(count);
  if (covariance_out != nullptr) *covariance_out = covariance;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  // Largest-magnitude component positive: the sign rule of geometry's statistical_pose.
  const auto signed_direction = [](const Eigen::Vector3d& v) {
    Eigen::Index index = 0;
    v.cwiseAbs().maxCoeff(&index);
    return v[index] < 0.0 ? Eigen::Vector3d(-v) : v;
  };
  Eigen::Vector3d variance;
  for (int k = 0; k < 3; ++k) variance[k] = std::max(0.0, solver.eigenvalues()[2 - k]);
  pose.rotation.col(0) = signed_direction(solver.eigenvectors().col(2));
  pose.rotation.col(1) = signed_direction(solver.eigenvectors().col(1));
  pose.rotation.col(2) = pose.rotation.col(0).cross(pose.rotation.col(1));  // det R_s = +1
  pose.scale = scale_factor * variance.cwiseSqrt();
  return pose;
}

void evaluate_fit(const Eigen::Matrix3Xd& points, QuadricFit& fit, const DecompositionTolerances& type_tolerances,
                  const FitEvaluationOptions& evaluation) {
  const auto start = std::chrono::steady_clock::now();
  // The shape (and so the residuals) is the exact geometry of Q; only the type label uses the
  // fitter's tolerances, so a nearly-circular ellipse is reported as circular without moving Q.
  fit.shape = fit.quadric.decompose();
  const DecompositionTolerances exact;
  const bool same_tolerances = type_tolerances.zero_eigenvalue == exact.zero_eigenvalue &&
                               type_tolerances.equal_eigenvalues == exact.equal_eigenvalues &&
                               type_tolerances.consistency == exact.consistency &&
                               type_tolerances.zero_constant == exact.zero_constant;
  fit.type = same_tolerances ? fit.shape.type : fit.quadric.decompose(type_tolerances).type;
  const ResidualSample sample = residual_sample(points.cols(), evaluation);
  fit.residual_evaluation = evaluation.residuals;
  fit.residual_points = sample.count;
  if (evaluation.residuals == ResidualEvaluation::Skip) {
    fit.residual_rms = fit.residual_max = fit.algebraic_distance = std::numeric_limits<double>::quiet_NaN();
  } else {
    double sum_squared = 0.0;
    double largest = 0.0;
    for (Eigen::Index i = 0; i < sample.count; ++i) {
      const double distance = orthogonal_distance(fit.shape, points.col(i * sample.stride));
      sum_squared += distance * distance;
      largest = std::max(largest, distance);
    }
    fit.residual_rms = sample.count > 0 ? std::sqrt(sum_squared / static_cast<double>(sample.count)) : 0.0;
    fit.residual_max = largest;
    fit.algebraic_distance = unit_space_algebraic_distance(points, fit.quadric, sample);
    if (!std::isfinite(fit.residual_rms) || !std::isfinite(fit.algebraic_distance)) {
      fit.status = FitStatus::Failed;
      fit.message = "non-finite residual";
    }
  }
  fit.evaluation_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace quadrix
