// Registry, shared evaluation and small helpers of the QuadricFitter interface.
#include "fitting/quadric_fitter.h"

#include "fitting/cgal_fitter.h"
#include "fitting/constrained_fitter.h"
#include "fitting/learned_fitter.h"
#include "fitting/statistical_fitter.h"
#include "fitting/taubin_fitter.h"
#include "geometry/error.h"

#include <algorithm>
#include <cmath>
#include <functional>
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

namespace {
using FitterFactory = std::function<std::unique_ptr<QuadricFitter>()>;

const std::vector<std::pair<std::string, FitterFactory>>& fitter_registry() {
  static const std::vector<std::pair<std::string, FitterFactory>> registry = {
      {"statistical", [] { return make_statistical_fitter(); }},
      {"taubin", [] { return make_taubin_fitter(); }},
      {"learned", [] { return make_learned_fitter(); }},
      {"auto", [] { return make_auto_fitter(); }},
      {"constrained", [] { return make_constrained_fitter(); }},
      {"cgal", [] { return make_cgal_fitter(); }},
  };
  return registry;
}
}  // namespace

std::unique_ptr<QuadricFitter> make_quadric_fitter(const std::string& name) {
  for (const auto& [registered, factory] : fitter_registry())
    if (registered == name) return factory();
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
  if (points.cols() == 0) return 0.0;
  // Unit space: x_u = (x - c) / sigma; the world quadric seen in unit space is A^-T Q A^-1 with
  // A = [I/sigma, -c/sigma; 0, 1], i.e. Q_u = B^T Q B with B = A^-1 = [sigma I, c; 0, 1].
  const Eigen::Vector3d center = points.rowwise().mean();
  const double radius = std::sqrt((points.colwise() - center).colwise().squaredNorm().mean());
  const double sigma = radius > 0.0 ? radius : 1.0;
  Eigen::Matrix4d to_world = Eigen::Matrix4d::Identity();
  to_world.topLeftCorner<3, 3>() *= sigma;
  to_world.topRightCorner<3, 1>() = center;
  const Quadric unit(to_world.transpose() * quadric.matrix() * to_world);
  const Quadric normalized = unit.normalized();
  double sum = 0.0;
  for (Eigen::Index i = 0; i < points.cols(); ++i) {
    const Eigen::Vector3d x = (points.col(i) - center) / sigma;
    sum += normalized.sampson_distance(x);
  }
  return sum / static_cast<double>(points.cols());
}

void evaluate_fit(const Eigen::Matrix3Xd& points, QuadricFit& fit, const DecompositionTolerances& type_tolerances) {
  // The shape (and so the residuals) is the exact geometry of Q; only the type label uses the
  // fitter's tolerances, so a nearly-circular ellipse is reported as circular without moving Q.
  fit.shape = fit.quadric.decompose();
  fit.type = fit.quadric.decompose(type_tolerances).type;
  double sum_squared = 0.0;
  double largest = 0.0;
  for (Eigen::Index i = 0; i < points.cols(); ++i) {
    const double distance = orthogonal_distance(fit.shape, points.col(i));
    sum_squared += distance * distance;
    largest = std::max(largest, distance);
  }
  fit.residual_rms = points.cols() > 0 ? std::sqrt(sum_squared / static_cast<double>(points.cols())) : 0.0;
  fit.residual_max = largest;
  fit.algebraic_distance = unit_space_algebraic_distance(points, fit.quadric);
  if (!std::isfinite(fit.residual_rms) || !std::isfinite(fit.algebraic_distance)) {
    fit.status = FitStatus::Failed;
    fit.message = "non-finite residual";
  }
}

}  // namespace quadrix
