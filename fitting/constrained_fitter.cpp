// Type-constrained orthogonal-distance fits with Ceres (see constrained_fitter.h). Every solve runs
// in unit space (points centred on their mean and divided by their RMS radius) for conditioning;
// the canonical parameters are mapped back to metres and turned into Q = P^-T C P^-1 (paper
// Eq. (Q=PCP)) with Quadric::from_canonical.
#include "fitting/constrained_fitter.h"

#include "fitting/statistical_fitter.h"
#include "fitting/taubin_fitter.h"
#include "geometry/constants.h"
#include "geometry/error.h"

#include <ceres/ceres.h>
#include <ceres/manifold.h>
#include <ceres/sphere_manifold.h>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace quadrix {
namespace {


/// Canonical parameters of a candidate surface in unit space (conventions of Quadric::from_canonical).
struct CanonicalShape {
  QuadricType type = QuadricType::Invalid;                 ///< requested type
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();         ///< semi-axes / radius; cones: tan of half-angles
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  ///< columns a, b, c (det +1)
  Eigen::Vector3d center = Eigen::Vector3d::Zero();        ///< centre, axis point or apex
};

/// One Ceres solve from one initial value.
struct Solution {
  CanonicalShape shape;                                              ///< optimised parameters
  double cost = std::numeric_limits<double>::infinity();             ///< Ceres final cost
  ceres::TerminationType termination = ceres::FAILURE;               ///< why Ceres stopped
  std::string message;                                               ///< Ceres' message
};

/// A rotation whose third column is `axis` (unit), completed to a right-handed frame.
Eigen::Matrix3d frame_with_axis_c(const Eigen::Vector3d& axis) {
  const Eigen::Vector3d c = axis.normalized();
  const Eigen::Vector3d helper = std::abs(c.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d a = (helper - helper.dot(c) * c).normalized();
  Eigen::Matrix3d frame;
  frame << a, c.cross(a), c;
  return frame;
}

/// sqrt that is 0 with zero derivative at 0 (points exactly on an axis).
template <typename T>
T safe_sqrt(const T& value) {
  if (value > T(0)) return sqrt(value);
  return T(0);
}

// ---- Residuals with closed-form orthogonal distances ------------------------------------------

/// Sphere: ||u - t|| - r.
struct SphereDistance {
  Eigen::Vector3d u;
  template <typename T>
  bool operator()(const T* center, const T* radius, T* residual) const {
    const T dx = T(u.x()) - center[0], dy = T(u.y()) - center[1], dz = T(u.z()) - center[2];
    residual[0] = safe_sqrt(dx * dx + dy * dy + dz * dz) - radius[0];
    return true;
  }
};

/// Circular cylinder: ||(u - p) x d|| - r with d a unit vector.
struct CylinderDistance {
  Eigen::Vector3d u;
  template <typename T>
  bool operator()(const T* point, const T* direction, const T* radius, T* residual) const {
    const T vx = T(u.x()) - point[0], vy = T(u.y()) - point[1], vz = T(u.z()) - point[2];
    const T cx = vy * direction[2] - vz * direction[1];
    const T cy = vz * direction[0] - vx * direction[2];
    const T cz = vx * direction[1] - vy * direction[0];
    residual[0] = safe_sqrt(cx * cx + cy * cy + cz * cz) - radius[0];
    return true;
  }
};

/// Gauge of a line of centres: the axis point is the foot of the perpendicular from the centroid
/// (the unit-space origin), p . d = 0. Zero at every optimum, so it fixes the gauge without bias.
struct AxisPointGauge {
  template <typename T>
  bool operator()(const T* point, const T* direction, T* residual) const {
    residual[0] = point[0] * direction[0] + point[1] * direction[1] + point[2] * direction[2];
    return true;
  }
};

/// Circular double cone with apex a, unit axis d, half-angle theta: in the (rho, h) half-plane the
/// surface is the pair of rays rho = |h| tan(theta), so the exact distance is rho cos(theta) - |h| sin(theta).
struct ConeDistance {
  Eigen::Vector3d u;
  template <typename T>
  bool operator()(const T* apex, const T* direction, const T* angle, T* residual) const {
    const T vx = T(u.x()) - apex[0], vy = T(u.y()) - apex[1], vz = T(u.z()) - apex[2];
    T height = vx * direction[0] + vy * direction[1] + vz * direction[2];
    const T cx = vy * direction[2] - vz * direction[1];
    const T cy = vz * direction[0] - vx * direction[2];
    const T cz = vx * direction[1] - vy * direction[0];
    const T radial = safe_sqrt(cx * cx + cy * cy + cz * cz);
    if (height < T(0)) height = -height;
    residual[0] = radial * cos(angle[0]) - height * sin(angle[0]);
    return true;
  }
};

// ---- Orthogonal distance regression with latent foot points -----------------------------------

/// Ellipsoid: u - (t + R diag(s) [cos a cos b, sin a cos b, sin b]); minimised over (a, b) this is the
/// orthogonal distance vector.
struct EllipsoidFoot {
  Eigen::Vector3d u;
  template <typename T>
  bool operator()(const T* center, const T* quaternion, const T* scale, const T* surface, T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> rotation(quaternion);
    const Eigen::Matrix<T, 3, 1> local(scale[0] * cos(surface[0]) * cos(surface[1]),
                                       scale[1] * sin(surface[0]) * cos(surface[1]), scale[2] * sin(surface[1]));
    const Eigen::Matrix<T, 3, 1> foot = rotation * local;
    for (int k = 0; k < 3; ++k) residual[k] = T(u[k]) - (center[k] + foot[k]);
    return true;
  }
};

/// Elliptic cylinder: u - (t + R [s_a cos a, s_b sin a, h]).
struct EllipticCylinderFoot {
  Eigen::Vector3d u;
  template <typename T>
  bool operator()(const T* center, const T* quaternion, const T* scale, const T* surface, T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> rotation(quaternion);
    const Eigen::Matrix<T, 3, 1> local(scale[0] * cos(surface[0]), scale[1] * sin(surface[0]), surface[1]);
    const Eigen::Matrix<T, 3, 1> foot = rotation * local;
    for (int k = 0; k < 3; ++k) residual[k] = T(u[k]) - (center[k] + foot[k]);
    return true;
  }
};

/// Elliptic cone: u - (apex + R [tan_a h cos a, tan_b h sin a, h]).
struct EllipticConeFoot {
  Eigen::Vector3d u;
  template <typename T>
  bool operator()(const T* apex, const T* quaternion, const T* tangents, const T* surface, T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> rotation(quaternion);
    const Eigen::Matrix<T, 3, 1> local(tangents[0] * surface[1] * cos(surface[0]),
                                       tangents[1] * surface[1] * sin(surface[0]), surface[1]);
    const Eigen::Matrix<T, 3, 1> foot = rotation * local;
    for (int k = 0; k < 3; ++k) residual[k] = T(u[k]) - (apex[k] + foot[k]);
    return true;
  }
};

/// Gauge of the elliptic cylinder's centre along its axis: t . (R e_c) = 0.
struct RotatedAxisGauge {
  template <typename T>
  bool operator()(const T* center, const T* quaternion, T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> rotation(quaternion);
    const Eigen::Matrix<T, 3, 1> axis = rotation * Eigen::Matrix<T, 3, 1>(T(0), T(0), T(1));
    residual[0] = center[0] * axis[0] + center[1] * axis[1] + center[2] * axis[2];
    return true;
  }
};

// ---- Initial values ----------------------------------------------------------------------------

/// Algebraic (Kasa) circle fit to 2-D points: returns centre and radius, or nothing when ill-posed.
std::optional<std::pair<Eigen::Vector2d, double>> algebraic_circle(const Eigen::Matrix2Xd& points) {
  if (points.cols() < 3) return std::nullopt;
  Eigen::MatrixXd design(points.cols(), 3);
  Eigen::VectorXd target(points.cols());
  for (Eigen::Index i = 0; i < points.cols(); ++i) {
    design.row(i) << 2.0 * points(0, i), 2.0 * points(1, i), 1.0;
    target(i) = points.col(i).squaredNorm();
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(design);
  if (qr.rank() < 3) return std::nullopt;
  const Eigen::Vector3d solution = qr.solve(target);
  const double squared_radius = solution(2) + solution.head<2>().squaredNorm();
  if (!(squared_radius > 0.0) || !std::isfinite(squared_radius)) return std::nullopt;
  return std::make_pair(Eigen::Vector2d(solution.head<2>()), std::sqrt(squared_radius));
}

/// Algebraic sphere fit: centre and radius, or nothing when ill-posed.
std::optional<std::pair<Eigen::Vector3d, double>> algebraic_sphere(const Eigen::Matrix3Xd& points) {
  if (points.cols() < 4) return std::nullopt;
  Eigen::MatrixXd design(points.cols(), 4);
  Eigen::VectorXd target(points.cols());
  for (Eigen::Index i = 0; i < points.cols(); ++i) {
    design.row(i) << 2.0 * points(0, i), 2.0 * points(1, i), 2.0 * points(2, i), 1.0;
    target(i) = points.col(i).squaredNorm();
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(design);
  if (qr.rank() < 4) return std::nullopt;
  const Eigen::Vector4d solution = qr.solve(target);
  const double squared_radius = solution(3) + solution.head<3>().squaredNorm();
  if (!(squared_radius > 0.0) || !std::isfinite(squared_radius)) return std::nullopt;
  return std::make_pair(Eigen::Vector3d(solution.head<3>()), std::sqrt(squared_radius));
}

/// Circular-cylinder initial value with axis direction `axis`: circle fitted to the projection.
std::optional<CanonicalShape> cylinder_guess(const Eigen::Matrix3Xd& unit, const Eigen::Vector3d& axis) {
  const Eigen::Matrix3d frame = frame_with_axis_c(axis);
  const Eigen::Matrix2Xd projected = frame.leftCols<2>().transpose() * unit;
  const auto circle = algebraic_circle(projected);
  if (!circle) return std::nullopt;
  CanonicalShape shape;
  shape.type = QuadricType::CircularCylinder;
  shape.rotation = frame;
  shape.center = frame.leftCols<2>() * circle->first;
  shape.scale << circle->second, circle->second, 1.0;
  return shape;
}

/// Circular-cone initial value with axis direction `axis`: axis position from a circle fitted to the
/// projection, then the line rho = k h + b fitted by least squares gives tan(theta) = |k| and the apex.
std::optional<CanonicalShape> cone_guess(const Eigen::Matrix3Xd& unit, const Eigen::Vector3d& axis) {
  const auto cylinder = cylinder_guess(unit, axis);
  if (!cylinder) return std::nullopt;
  const Eigen::Vector3d direction = axis.normalized();
  const Eigen::Vector3d axis_point = cylinder->center;
  Eigen::Matrix2d normal = Eigen::Matrix2d::Zero();
  Eigen::Vector2d right = Eigen::Vector2d::Zero();
  for (Eigen::Index i = 0; i < unit.cols(); ++i) {
    const Eigen::Vector3d v = unit.col(i) - axis_point;
    const double height = v.dot(direction);
    const double radial = (v - height * direction).norm();
    const Eigen::Vector2d row(height, 1.0);
    normal += row * row.transpose();
    right += row * radial;
  }
  if (std::abs(normal.determinant()) < 1e-12) return std::nullopt;
  const Eigen::Vector2d line = normal.ldlt().solve(right);
  if (!(std::abs(line(0)) > 1e-3) || !std::isfinite(line(0))) return std::nullopt;
  CanonicalShape shape;
  shape.type = QuadricType::CircularCone;
  const double tangent = std::min(std::abs(line(0)), 1e2);
  shape.scale << tangent, tangent, 1.0;
  shape.center = axis_point + (-line(1) / line(0)) * direction;
  shape.rotation = frame_with_axis_c(direction);
  return shape;
}

/// The family of a type for accepting Taubin results (circular and elliptic variants together,
/// sphere with ellipsoid).
int family(QuadricType type) {
  switch (type) {
    case QuadricType::Sphere: case QuadricType::Ellipsoid: return 1;
    case QuadricType::CircularCylinder: case QuadricType::EllipticCylinder: return 2;
    case QuadricType::CircularCone: case QuadricType::EllipticCone: return 3;
    default: return 100 + static_cast<int>(type);
  }
}

bool is_cone(QuadricType type) { return type == QuadricType::CircularCone || type == QuadricType::EllipticCone; }

/// Taubin's decomposition as an initial value of `type` in unit space, when it is of the same family.
std::optional<CanonicalShape> taubin_guess(const Eigen::Matrix3Xd& points, QuadricType type, const Eigen::Vector3d& mean,
                                           double radius) {
  TaubinFitterOptions taubin_options;
  taubin_options.evaluation.residuals = ResidualEvaluation::Skip;  // only the decomposition is used
  const QuadricFit taubin = make_taubin_fitter(taubin_options)->fit(points, Eigen::Matrix3Xd(), type);
  if (taubin.status != FitStatus::Ok && taubin.status != FitStatus::TypeMismatch) return std::nullopt;
  if (family(taubin.shape.type) != family(type)) return std::nullopt;
  if (!taubin.shape.scale.allFinite() || !taubin.shape.center.allFinite()) return std::nullopt;
  CanonicalShape shape;
  shape.type = type;
  shape.rotation = taubin.shape.rotation;
  if (shape.rotation.determinant() < 0.0) shape.rotation.col(0) *= -1.0;
  shape.center = (taubin.shape.center - mean) / radius;
  shape.scale = is_cone(type) ? taubin.shape.scale : Eigen::Vector3d(taubin.shape.scale / radius);
  if (is_cone(type)) shape.scale(2) = 1.0;
  if (type == QuadricType::Sphere) shape.scale.setConstant(shape.scale.mean());
  if (type == QuadricType::CircularCylinder || type == QuadricType::CircularCone)
    shape.scale.head<2>().setConstant(shape.scale.head<2>().mean());
  if (type == QuadricType::CircularCylinder || type == QuadricType::EllipticCylinder) {
    // The cylinder's centre is any point of its axis: take the foot from the centroid (unit origin).
    const Eigen::Vector3d axis = shape.rotation.col(2);
    shape.center -= shape.center.dot(axis) * axis;
    shape.scale(2) = 1.0;
  }
  const int defined = (type == QuadricType::Sphere || type == QuadricType::Ellipsoid) ? 3 : 2;
  if (!(shape.scale.head(defined).minCoeff() > 0.0)) return std::nullopt;
  return shape;
}

/// Every initial value of `type` (unit space): the statistical pose with each principal direction
/// as the axis, the algebraic sphere, and Taubin's fit of the same family.
std::vector<CanonicalShape> initial_values(QuadricType type, const Eigen::Matrix3Xd& unit, const Eigen::Matrix3d& principal,
                                           const Eigen::Vector3d& principal_sigma,
                                           const std::optional<CanonicalShape>& taubin) {
  std::vector<CanonicalShape> guesses;
  switch (type) {
    case QuadricType::Sphere: {
      CanonicalShape statistical;
      statistical.type = type;
      statistical.scale.setConstant(1.0);  // RMS radius is 1 in unit space
      guesses.push_back(statistical);
      if (const auto sphere = algebraic_sphere(unit)) {
        CanonicalShape algebraic;
        algebraic.type = type;
        algebraic.center = sphere->first;
        algebraic.scale.setConstant(sphere->second);
        guesses.push_back(algebraic);
      }
      break;
    }
    case QuadricType::Ellipsoid: {
      CanonicalShape statistical;  // a full ellipsoid surface has variance s^2 / 3 along each axis
      statistical.type = type;
      statistical.rotation = principal;
      statistical.scale = (std::sqrt(3.0) * principal_sigma).cwiseMax(1e-3);
      guesses.push_back(statistical);
      if (const auto sphere = algebraic_sphere(unit)) {
        CanonicalShape algebraic = statistical;
        algebraic.center = sphere->first;
        algebraic.scale.setConstant(sphere->second);
        guesses.push_back(algebraic);
      }
      break;
    }
    case QuadricType::CircularCylinder:
    case QuadricType::EllipticCylinder:
      for (int axis = 0; axis < 3; ++axis)
        if (auto guess = cylinder_guess(unit, principal.col(axis))) {
          guess->type = type;
          guesses.push_back(*guess);
        }
      break;
    case QuadricType::CircularCone:
    case QuadricType::EllipticCone:
      for (int axis = 0; axis < 3; ++axis)
        if (auto guess = cone_guess(unit, principal.col(axis))) {
          guess->type = type;
          guesses.push_back(*guess);
        }
      break;
    default:
      break;
  }
  if (taubin) guesses.push_back(*taubin);
  return guesses;
}

// ---- Solves ------------------------------------------------------------------------------------

ceres::Solver::Options solver_options(const ConstrainedFitterOptions& options, bool schur) {
  ceres::Solver::Options solver;
  solver.linear_solver_type = schur ? ceres::DENSE_SCHUR : ceres::DENSE_QR;
  solver.max_num_iterations = options.max_iterations;
  solver.function_tolerance = options.function_tolerance;
  solver.gradient_tolerance = options.gradient_tolerance;
  solver.parameter_tolerance = options.parameter_tolerance;
  solver.num_threads = 1;  // callers parallelise over elements
  solver.logging_type = ceres::SILENT;
  solver.minimizer_progress_to_stdout = false;
  return solver;
}

ceres::LossFunction* make_loss(const ConstrainedFitterOptions& options, double unit_radius) {
  if (options.robust_loss_scale <= 0.0) return nullptr;
  return new ceres::CauchyLoss(options.robust_loss_scale / unit_radius);
}

Solution finish_solve(const ceres::Solver::Summary& summary, const CanonicalShape& shape) {
  Solution solution;
  solution.shape = shape;
  solution.cost = summary.final_cost;
  solution.termination = summary.termination_type;
  solution.message = summary.BriefReport();
  return solution;
}

Solution solve_sphere(const Eigen::Matrix3Xd& unit, const CanonicalShape& guess, const ConstrainedFitterOptions& options,
                      double unit_radius) {
  double center[3] = {guess.center.x(), guess.center.y(), guess.center.z()};
  double radius = guess.scale(0);
  ceres::Problem problem;
  for (Eigen::Index i = 0; i < unit.cols(); ++i)
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<SphereDistance, 1, 3, 1>(new SphereDistance{unit.col(i)}),
                             make_loss(options, unit_radius), center, &radius);
  problem.SetParameterLowerBound(&radius, 0, 1e-9);
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options(options, false), &problem, &summary);
  CanonicalShape shape = guess;
  shape.center = Eigen::Vector3d(center[0], center[1], center[2]);
  shape.scale.setConstant(radius);
  shape.rotation.setIdentity();
  return finish_solve(summary, shape);
}

Solution solve_cylinder(const Eigen::Matrix3Xd& unit, const CanonicalShape& guess, const ConstrainedFitterOptions& options,
                        double unit_radius) {
  const Eigen::Vector3d axis = guess.rotation.col(2);
  double point[3] = {guess.center.x(), guess.center.y(), guess.center.z()};
  double direction[3] = {axis.x(), axis.y(), axis.z()};
  double radius = guess.scale(0);
  ceres::Problem problem;
  for (Eigen::Index i = 0; i < unit.cols(); ++i)
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<CylinderDistance, 1, 3, 3, 1>(new CylinderDistance{unit.col(i)}),
        make_loss(options, unit_radius), point, direction, &radius);
  problem.AddResidualBlock(new ceres::AutoDiffCostFunction<AxisPointGauge, 1, 3, 3>(new AxisPointGauge), nullptr, point,
                           direction);
  problem.SetManifold(direction, new ceres::SphereManifold<3>());
  problem.SetParameterLowerBound(&radius, 0, 1e-9);
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options(options, false), &problem, &summary);
  CanonicalShape shape = guess;
  shape.center = Eigen::Vector3d(point[0], point[1], point[2]);
  shape.rotation = frame_with_axis_c(Eigen::Vector3d(direction[0], direction[1], direction[2]));
  shape.scale << radius, radius, 1.0;
  return finish_solve(summary, shape);
}

Solution solve_cone(const Eigen::Matrix3Xd& unit, const CanonicalShape& guess, const ConstrainedFitterOptions& options,
                    double unit_radius) {
  const Eigen::Vector3d axis = guess.rotation.col(2);
  double apex[3] = {guess.center.x(), guess.center.y(), guess.center.z()};
  double direction[3] = {axis.x(), axis.y(), axis.z()};
  double angle = std::atan(guess.scale(0));
  ceres::Problem problem;
  for (Eigen::Index i = 0; i < unit.cols(); ++i)
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<ConeDistance, 1, 3, 3, 1>(new ConeDistance{unit.col(i)}),
                             make_loss(options, unit_radius), apex, direction, &angle);
  problem.SetManifold(direction, new ceres::SphereManifold<3>());
  problem.SetParameterLowerBound(&angle, 0, 1e-6);
  problem.SetParameterUpperBound(&angle, 0, kPi / 2.0 - 1e-6);
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options(options, false), &problem, &summary);
  CanonicalShape shape = guess;
  shape.center = Eigen::Vector3d(apex[0], apex[1], apex[2]);
  shape.rotation = frame_with_axis_c(Eigen::Vector3d(direction[0], direction[1], direction[2]));
  shape.scale << std::tan(angle), std::tan(angle), 1.0;
  return finish_solve(summary, shape);
}

/// Latent surface coordinates of u on the initial shape (angles for the ellipsoid; angle and
/// height for elliptic cylinders and cones), from the point's canonical-frame coordinates.
Eigen::Vector2d initial_surface_coordinates(QuadricType type, const CanonicalShape& shape, const Eigen::Vector3d& u) {
  const Eigen::Vector3d local = shape.rotation.transpose() * (u - shape.center);
  switch (type) {
    case QuadricType::Ellipsoid: {
      const Eigen::Vector3d direction = local.cwiseQuotient(shape.scale);
      const double norm = direction.norm();
      if (!(norm > 0.0)) return Eigen::Vector2d::Zero();
      return {std::atan2(direction.y(), direction.x()), std::asin(std::clamp(direction.z() / norm, -1.0, 1.0))};
    }
    case QuadricType::EllipticCylinder:
      return {std::atan2(local.y() / shape.scale(1), local.x() / shape.scale(0)), local.z()};
    default: {  // elliptic cone: h = z, angle from the scaled radial coordinates (h < 0 flips it by pi)
      const double height = std::abs(local.z()) > 1e-9 ? local.z() : 1e-9;
      return {std::atan2(local.y() / (shape.scale(1) * height), local.x() / (shape.scale(0) * height)), height};
    }
  }
}

Solution solve_latent(QuadricType type, const Eigen::Matrix3Xd& unit, const CanonicalShape& guess,
                      const ConstrainedFitterOptions& options, double unit_radius) {
  double center[3] = {guess.center.x(), guess.center.y(), guess.center.z()};
  Eigen::Quaterniond initial_rotation(guess.rotation);
  initial_rotation.normalize();
  double quaternion[4] = {initial_rotation.x(), initial_rotation.y(), initial_rotation.z(), initial_rotation.w()};
  double scale[3] = {guess.scale(0), guess.scale(1), guess.scale(2)};
  const int scale_count = type == QuadricType::Ellipsoid ? 3 : 2;
  std::vector<double> surface(2 * static_cast<std::size_t>(unit.cols()));
  ceres::Problem problem;
  auto* ordering = new ceres::ParameterBlockOrdering;
  for (Eigen::Index i = 0; i < unit.cols(); ++i) {
    double* coordinates = surface.data() + 2 * i;
    const Eigen::Vector2d start = initial_surface_coordinates(type, guess, unit.col(i));
    coordinates[0] = start(0);
    coordinates[1] = start(1);
    ceres::CostFunction* cost = nullptr;
    if (type == QuadricType::Ellipsoid)
      cost = new ceres::AutoDiffCostFunction<EllipsoidFoot, 3, 3, 4, 3, 2>(new EllipsoidFoot{unit.col(i)});
    else if (type == QuadricType::EllipticCylinder)
      cost = new ceres::AutoDiffCostFunction<EllipticCylinderFoot, 3, 3, 4, 2, 2>(new EllipticCylinderFoot{unit.col(i)});
    else
      cost = new ceres::AutoDiffCostFunction<EllipticConeFoot, 3, 3, 4, 2, 2>(new EllipticConeFoot{unit.col(i)});
    problem.AddResidualBlock(cost, make_loss(options, unit_radius), center, quaternion, scale, coordinates);
    ordering->AddElementToGroup(coordinates, 0);
  }
  if (type == QuadricType::EllipticCylinder)
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<RotatedAxisGauge, 1, 3, 4>(new RotatedAxisGauge), nullptr,
                             center, quaternion);
  problem.SetManifold(quaternion, new ceres::EigenQuaternionManifold());
  for (int k = 0; k < scale_count; ++k) problem.SetParameterLowerBound(scale, k, 1e-9);
  ordering->AddElementToGroup(center, 1);
  ordering->AddElementToGroup(quaternion, 1);
  ordering->AddElementToGroup(scale, 1);
  ceres::Solver::Options solver = solver_options(options, true);
  solver.linear_solver_ordering.reset(ordering);
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  CanonicalShape shape = guess;
  shape.center = Eigen::Vector3d(center[0], center[1], center[2]);
  shape.rotation = Eigen::Quaterniond(quaternion[3], quaternion[0], quaternion[1], quaternion[2]).normalized().toRotationMatrix();
  shape.scale << scale[0], scale[1], (scale_count == 3 ? scale[2] : 1.0);
  if (type == QuadricType::EllipticCone) {  // the tangents are |t|; a negative one flips an axis
    shape.scale.head<2>() = shape.scale.head<2>().cwiseAbs();
  }
  return finish_solve(summary, shape);
}

Solution solve(QuadricType type, const Eigen::Matrix3Xd& unit, const CanonicalShape& guess,
               const ConstrainedFitterOptions& options, double unit_radius) {
  switch (type) {
    case QuadricType::Sphere: return solve_sphere(unit, guess, options, unit_radius);
    case QuadricType::CircularCylinder: return solve_cylinder(unit, guess, options, unit_radius);
    case QuadricType::CircularCone: return solve_cone(unit, guess, options, unit_radius);
    default: return solve_latent(type, unit, guess, options, unit_radius);
  }
}

/// Sagitta r (1 - cos(min(span, pi) / 2)) of the arc the points cover around a circular cylinder's
/// axis (span = 2 pi minus the largest angular gap between them) and their RMS distance to it: the
/// depth of curvature the points show against their scatter.
std::pair<double, double> cylinder_arc_sagitta(const Eigen::Matrix3Xd& unit, const CanonicalShape& shape) {
  const Eigen::Matrix3d frame = frame_with_axis_c(shape.rotation.col(2));
  const double radius = shape.scale(0);
  std::vector<double> angles;
  angles.reserve(static_cast<std::size_t>(unit.cols()));
  double sum_squared = 0.0;
  for (Eigen::Index i = 0; i < unit.cols(); ++i) {
    const Eigen::Vector3d local = frame.transpose() * (unit.col(i) - shape.center);
    angles.push_back(std::atan2(local.y(), local.x()));
    sum_squared += std::pow(local.head<2>().norm() - radius, 2);
  }
  if (angles.empty()) return {0.0, 0.0};
  std::sort(angles.begin(), angles.end());
  double largest_gap = angles.front() + 2.0 * kPi - angles.back();
  for (std::size_t i = 1; i < angles.size(); ++i) largest_gap = std::max(largest_gap, angles[i] - angles[i - 1]);
  const double span = std::min(2.0 * kPi - largest_gap, kPi);
  return {radius * (1.0 - std::cos(span / 2.0)), std::sqrt(sum_squared / static_cast<double>(unit.cols()))};
}

// ---- The fitter --------------------------------------------------------------------------------

bool is_supported(QuadricType type) {
  const auto types = constrained_fitter_types();
  return std::find(types.begin(), types.end(), type) != types.end();
}

// ---- Stages of a typed fit -------------------------------------------------------------------

/// Marks `result` when the type has no model here or there are too few points for it; throws on NaN or infinite points.
bool accept_input(const Eigen::Matrix3Xd& points, QuadricType type, QuadricFit& result) {
  if (!is_supported(type)) {
    result.status = FitStatus::Failed;
    result.message = "the constrained fitter has no model for a " + quadric_type_name(type);
    return false;
  }
  if (static_cast<std::size_t>(points.cols()) < minimum_points_for_type(type)) {
    result.status = FitStatus::TooFewPoints;
    result.message = "a " + quadric_type_name(type) + " needs at least " + std::to_string(minimum_points_for_type(type)) +
                     " points, got " + std::to_string(points.cols());
    return false;
  }
  if (!points.allFinite()) throw Error("constrained fitter: the points contain NaN or infinite coordinates");
  return true;
}

/// Point, line and plane: the orthogonal-distance minimiser is closed-form (centroid; total least
/// squares line and plane through the centroid), which is exactly the statistical fitter's answer.
QuadricFit fit_linear_type(const Eigen::Matrix3Xd& points, QuadricType type, const FitEvaluationOptions& evaluation) {
  StatisticalFitterOptions linear_options;
  linear_options.evaluation = evaluation;
  QuadricFit linear = make_statistical_fitter(linear_options)->fit(points, Eigen::Matrix3Xd(), type);
  if (linear.status == FitStatus::Ok && type == QuadricType::Point) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = linear.statistics.center;
    linear.quadric = Quadric::from_canonical(QuadricType::Point, Eigen::Vector3d::Ones(), pose);
    evaluate_fit(points, linear, {}, evaluation);
  }
  return linear;
}

/// The points centred on their mean and divided by their RMS radius, with their principal axes.
struct UnitSpace {
  Eigen::Vector3d mean;        ///< centroid in metres
  double radius = 0.0;         ///< RMS distance to the centroid in metres
  Eigen::Matrix3Xd unit;       ///< the points in unit space
  Eigen::Matrix3d principal;   ///< principal axes, descending variance, right-handed
  Eigen::Vector3d sigma;       ///< standard deviation along each principal axis
};

/// Finds the principal axes of unit-space points (descending variance, right-handed) and the spread along each.
void find_principal_axes(UnitSpace& space) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(space.unit * space.unit.transpose() /
                                                       static_cast<double>(space.unit.cols()));
  space.principal << eigen.eigenvectors().col(2), eigen.eigenvectors().col(1), eigen.eigenvectors().col(0);
  if (space.principal.determinant() < 0.0) space.principal.col(2) *= -1.0;
  space.sigma = eigen.eigenvalues().reverse().cwiseMax(0.0).cwiseSqrt();
}

/// Marks `result` Degenerate when the spread cannot fix the type: collinear points, or coplanar ones but for a cylinder.
bool accept_spread(const Eigen::Vector3d& sigma, QuadricType type, QuadricFit& result) {
  if (sigma(1) <= 1e-9 * sigma(0)) {
    result.status = FitStatus::Degenerate;
    result.message = "the points are collinear; a " + quadric_type_name(type) + " is not determined";
    return false;
  }
  if (sigma(2) <= 1e-9 * sigma(0) && type != QuadricType::CircularCylinder && type != QuadricType::EllipticCylinder) {
    result.status = FitStatus::Degenerate;
    result.message = "the points are coplanar; a " + quadric_type_name(type) + " through them is not unique";
    return false;
  }
  return true;
}

/// Moves the points into unit space for conditioning; nothing (`result` Degenerate) when they cannot fix the type.
std::optional<UnitSpace> move_to_unit_space(const Eigen::Matrix3Xd& points, QuadricType type, QuadricFit& result) {
  UnitSpace space;
  space.mean = points.rowwise().mean();
  space.radius = std::sqrt((points.colwise() - space.mean).colwise().squaredNorm().mean());
  result.statistics = point_statistics(points);
  if (!(space.radius > 0.0)) {
    result.status = FitStatus::Degenerate;
    result.message = "all points coincide";
    return std::nullopt;
  }
  space.unit = (points.colwise() - space.mean) / space.radius;
  find_principal_axes(space);
  if (!accept_spread(space.sigma, type, result)) return std::nullopt;
  return space;
}

/// The evenly strided subsample the initial values are solved on (unused when there are few points: all are used).
struct Subsample {
  bool used = false;        ///< false: the subsample would be every point
  Eigen::Matrix3Xd points;  ///< the subsample in metres (empty when unused)
  Eigen::Matrix3Xd unit;    ///< the subsample in unit space (empty when unused)
};

/// Takes an evenly strided subsample of at most `subsample_points` points, in metres and in unit space.
Subsample take_subsample(const Eigen::Matrix3Xd& points, const UnitSpace& space, int subsample_points) {
  const ResidualSample coarse =
      residual_sample(points.cols(), FitEvaluationOptions{ResidualEvaluation::Subsample, std::max(subsample_points, 1)});
  Subsample sample;
  sample.used = coarse.count < points.cols();
  if (!sample.used) return sample;
  sample.points = Eigen::Matrix3Xd(Eigen::Map<const Eigen::Matrix3Xd, 0, Eigen::OuterStride<>>(
      points.data(), 3, coarse.count, Eigen::OuterStride<>(3 * coarse.stride)));
  sample.unit = Eigen::Matrix3Xd((sample.points.colwise() - space.mean) / space.radius);
  return sample;
}

/// Whether a Ceres solve ended with a finite cost and finite parameters.
bool is_usable(const Solution& solution) {
  return solution.termination != ceres::FAILURE && solution.termination != ceres::USER_FAILURE &&
         std::isfinite(solution.cost) && solution.shape.scale.allFinite() && solution.shape.center.allFinite();
}

/// Brings the unit-space shape back to metres and into Q = P^-T C P^-1 (paper Eq. (Q=PCP)).
Quadric to_metric_quadric(QuadricType type, const CanonicalShape& shape, const UnitSpace& space) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = shape.rotation;
  pose.translation() = space.mean + space.radius * shape.center;
  Eigen::Vector3d scale = shape.scale;
  if (!is_cone(type)) scale *= space.radius;
  if (type == QuadricType::CircularCylinder || type == QuadricType::EllipticCylinder) scale(2) = 1.0;
  if (is_cone(type)) scale(2) = 1.0;
  return Quadric::from_canonical(type, scale, pose);
}

class ConstrainedFitter final : public QuadricFitter {
 public:
  explicit ConstrainedFitter(const ConstrainedFitterOptions& options) : options_(options) {}

  std::string name() const override { return "constrained"; }

  QuadricFit fit(const Eigen::Matrix3Xd& points, const Eigen::Matrix3Xd& /*normals*/, FitTypeHint hint) const override {
    const auto start = std::chrono::steady_clock::now();
    QuadricFit result = hint ? fit_type(points, *hint, options_.evaluation) : fit_automatic(points);
    result.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return result;
  }

 private:
  /// Without a hint: every automatic type, lowest BIC among the usable fits.
  QuadricFit fit_automatic(const Eigen::Matrix3Xd& points) const {
    QuadricFit best;
    best.status = FitStatus::Failed;
    best.message = "no automatic type could be fitted";
    double best_criterion = std::numeric_limits<double>::infinity();
    const double n = static_cast<double>(points.cols());
    const StatisticalPose pose = point_statistics(points, 1.0);
    // The choice needs residuals: when the caller skips them they are read on the default subsample.
    FitEvaluationOptions automatic_evaluation = options_.evaluation;
    if (automatic_evaluation.residuals == ResidualEvaluation::Skip)
      automatic_evaluation = FitEvaluationOptions{ResidualEvaluation::Subsample, FitEvaluationOptions{}.max_points};
    const double size = std::max(pose.scale.norm(), 1e-12);
    for (const QuadricType type : options_.automatic_types) {
      QuadricFit candidate = fit_type(points, type, automatic_evaluation);
      if (candidate.status != FitStatus::Ok && candidate.status != FitStatus::NotConverged) {
        if (best.status != FitStatus::Ok && best.status != FitStatus::NotConverged) best = candidate;
        continue;
      }
      // Floor the RMS at 1e-9 of the element's size so exact fits tie and the fewest parameters win.
      const double rms = std::max(candidate.residual_rms, 1e-9 * size);
      const double criterion = n * std::log(rms * rms) + constrained_type_degrees_of_freedom(type) * std::log(n);
      if (criterion < best_criterion) {
        best_criterion = criterion;
        best = candidate;
      }
    }
    return best;
  }

  /// Fits one type: checks the input, solves from every initial value in unit space, keeps the best sound shape.
  QuadricFit fit_type(const Eigen::Matrix3Xd& points, QuadricType type, const FitEvaluationOptions& evaluation) const {
    QuadricFit result;
    result.type = type;
    if (!accept_input(points, type, result)) return result;
    if (type == QuadricType::Point || type == QuadricType::Line || type == QuadricType::Plane)
      return fit_linear_type(points, type, evaluation);
    const std::optional<UnitSpace> space = move_to_unit_space(points, type, result);
    if (!space) return result;
    // Every initial value is solved on an evenly strided subsample (all points when there are few);
    // the best one is then polished on every point.
    const Subsample coarse = take_subsample(points, *space, options_.subsample_points);
    const std::vector<CanonicalShape> guesses = guess_initial_values(points, type, *space, coarse);
    if (guesses.empty()) {
      result.status = FitStatus::Degenerate;
      result.message = "no initial value for a " + quadric_type_name(type) + " (the points do not resemble one)";
      return result;
    }
    const std::optional<Solution> best = solve_from_best_guess(type, guesses, *space, coarse);
    if (!best) {
      result.status = FitStatus::Failed;
      result.message = "every Ceres solve failed for the " + quadric_type_name(type);
      return result;
    }
    const Eigen::Matrix3Xd& start_unit = coarse.used ? coarse.unit : space->unit;
    if (type == QuadricType::CircularCylinder && !accept_cylinder_curvature(start_unit, best->shape, space->radius, result))
      return result;
    if (!accept_shape_scale(type, best->shape, space->radius, result)) return result;
    result.quadric = to_metric_quadric(type, best->shape, *space);
    result.status = best->termination == ceres::CONVERGENCE ? FitStatus::Ok : FitStatus::NotConverged;
    if (result.status == FitStatus::NotConverged) result.message = "Ceres stopped early: " + best->message;
    evaluate_fit(points, result, {}, evaluation);
    return result;
  }

  /// Guesses the initial values from the principal axes (and Taubin's algebraic fit when enabled) on the subsample.
  std::vector<CanonicalShape> guess_initial_values(const Eigen::Matrix3Xd& points, QuadricType type, const UnitSpace& space,
                                                   const Subsample& coarse) const {
    const Eigen::Matrix3Xd& start_unit = coarse.used ? coarse.unit : space.unit;
    std::optional<CanonicalShape> taubin;
    if (options_.use_taubin_initialisation)
      taubin = taubin_guess(coarse.used ? coarse.points : points, type, space.mean, space.radius);
    return initial_values(type, start_unit, space.principal, space.sigma, taubin);
  }

  /// Solves from every initial value, then the best one again to the full tolerances; nothing when every solve failed.
  std::optional<Solution> solve_from_best_guess(QuadricType type, const std::vector<CanonicalShape>& guesses,
                                                const UnitSpace& space, const Subsample& coarse) const {
    const Eigen::Matrix3Xd& start_unit = coarse.used ? coarse.unit : space.unit;
    // Screening: every initial value gets a few iterations on the subsample; only the best one is
    // then solved to the full tolerances (on every point when polishing).
    const bool screen = guesses.size() > 1 && options_.screening_iterations > 0;
    ConstrainedFitterOptions screening = options_;
    screening.max_iterations = std::min(options_.screening_iterations, options_.max_iterations);
    std::optional<Solution> best;
    for (const CanonicalShape& guess : guesses) {
      Solution solution = solve(type, start_unit, guess, screen ? screening : options_, space.radius);
      if (is_usable(solution) && (!best || solution.cost < best->cost)) best = solution;
    }
    if (!best) return best;
    const bool polish = coarse.used && options_.polish_on_all_points;
    if (screen || polish) {
      Solution final_solution = solve(type, polish ? space.unit : start_unit, best->shape, options_, space.radius);
      if (is_usable(final_solution)) best = final_solution;
    }
    return best;
  }

  /// Marks `result` Degenerate when the arc's sagitta is below minimum_sagitta_ratio x the residual (no curvature).
  bool accept_cylinder_curvature(const Eigen::Matrix3Xd& start_unit, const CanonicalShape& shape, double radius,
                                 QuadricFit& result) const {
    const auto [sagitta, rms] = cylinder_arc_sagitta(start_unit, shape);
    if (sagitta < options_.minimum_sagitta_ratio * rms) {
      result.status = FitStatus::Degenerate;
      char text[220];
      std::snprintf(text, sizeof(text),
                    "the points do not show the cylinder's curvature: the sagitta of their arc (%.3g m at radius "
                    "%.3g m) is below %.3g x the residual (%.3g m)",
                    sagitta * radius, shape.scale(0) * radius, options_.minimum_sagitta_ratio, rms * radius);
      result.message = text;
      return false;
    }
    return true;
  }

  /// Marks `result` Degenerate when a scale (or a cone's apex distance) runs away or a defined scale vanishes.
  bool accept_shape_scale(QuadricType type, const CanonicalShape& shape, double radius, QuadricFit& result) const {
    const int defined = (type == QuadricType::Sphere || type == QuadricType::Ellipsoid) ? 3 : 2;
    const double largest = is_cone(type) ? std::max(shape.scale.head<2>().maxCoeff(), shape.center.norm())
                                         : shape.scale.head(defined).maxCoeff();
    const double smallest = shape.scale.head(defined).minCoeff();
    if (largest > options_.largest_relative_scale || !(smallest > 1e-8)) {
      result.status = FitStatus::Degenerate;
      result.message = "the best " + quadric_type_name(type) + " degenerates (scale or apex distance " +
                       std::to_string(largest * radius) + " m, smallest scale " + std::to_string(smallest) +
                       "): the points are nearly flat or straight";
      return false;
    }
    return true;
  }

  ConstrainedFitterOptions options_;
};

}  // namespace

std::vector<QuadricType> constrained_fitter_types() {
  return {QuadricType::Point,           QuadricType::Line,          QuadricType::Plane,
          QuadricType::Sphere,          QuadricType::Ellipsoid,     QuadricType::CircularCylinder,
          QuadricType::EllipticCylinder, QuadricType::CircularCone, QuadricType::EllipticCone};
}

int constrained_type_degrees_of_freedom(QuadricType type) {
  switch (type) {
    case QuadricType::Point: return 3;
    case QuadricType::Plane: return 3;
    case QuadricType::Line: return 4;
    case QuadricType::Sphere: return 4;
    case QuadricType::CircularCylinder: return 5;
    case QuadricType::CircularCone: return 6;
    case QuadricType::EllipticCylinder: return 6;
    case QuadricType::EllipticCone: return 7;
    case QuadricType::Ellipsoid: return 9;
    default: return 9;
  }
}

std::unique_ptr<QuadricFitter> make_constrained_fitter(const ConstrainedFitterOptions& options) {
  return std::make_unique<ConstrainedFitter>(options);
}

}  // namespace quadrix
