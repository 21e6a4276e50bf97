// Quadric algebra: paper §"Quadrics" (Eqs. (quadrics equation), (Q and normal), (Q=PCP),
// (quadrics further expanded), the normalisation rule, (geometry analysis), (solve t)) and the
// degeneracy table "Characteristics of typical quadrics".
#include "geometry/quadric.h"

#include "geometry/error.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

namespace quadrix {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

struct TypeName {
  QuadricType type;
  const char* name;
};

constexpr TypeName kTypeNames[] = {
    {QuadricType::Point, "point"},
    {QuadricType::Line, "line"},
    {QuadricType::Plane, "plane"},
    {QuadricType::Sphere, "sphere"},
    {QuadricType::Ellipsoid, "ellipsoid"},
    {QuadricType::CircularCylinder, "circular_cylinder"},
    {QuadricType::EllipticCylinder, "elliptic_cylinder"},
    {QuadricType::CircularCone, "circular_cone"},
    {QuadricType::EllipticCone, "elliptic_cone"},
    {QuadricType::HyperboloidOneSheet, "hyperboloid_one_sheet"},
    {QuadricType::HyperboloidTwoSheets, "hyperboloid_two_sheets"},
    {QuadricType::EllipticParaboloid, "elliptic_paraboloid"},
    {QuadricType::HyperbolicParaboloid, "hyperbolic_paraboloid"},
    {QuadricType::ParabolicCylinder, "parabolic_cylinder"},
    {QuadricType::HyperbolicCylinder, "hyperbolic_cylinder"},
    {QuadricType::IntersectingPlanes, "intersecting_planes"},
    {QuadricType::ParallelPlanes, "parallel_planes"},
    {QuadricType::Imaginary, "imaginary"},
    {QuadricType::Invalid, "invalid"},
};

int sign_of(double value) { return value > 0.0 ? 1 : (value < 0.0 ? -1 : 0); }

// Spectral analysis of Q33 and the centre equation Q33 t + l = 0 (Eq. (solve t)), shared by
// normalisation and decomposition.
struct CenterAnalysis {
  Eigen::Matrix3d eigenvectors = Eigen::Matrix3d::Identity();  // columns, Eigen's ascending order
  Eigen::Vector3d eigenvalues = Eigen::Vector3d::Zero();
  std::array<int, 3> signs{{0, 0, 0}};   // -1 / 0 / +1 per eigenvalue after the zero test
  double max_abs_eigenvalue = 0.0;
  int rank = 0;                          // numerical rank of Q33
  bool consistent = true;                // rank(Q33) == rank([Q33 | l])
  Eigen::Vector3d center = Eigen::Vector3d::Zero();       // minimum-norm t with Q33 t = -l (range part)
  Eigen::Vector3d null_residual = Eigen::Vector3d::Zero();  // m: the part of l in the null space of Q33
  double constant = 0.0;                 // c44 = k + l . t (Schur complement of Q33 in Q)
  bool constant_is_zero = true;
};

CenterAnalysis analyse_center(const Eigen::Matrix4d& matrix, const DecompositionTolerances& tolerances) {
  CenterAnalysis analysis;
  const Eigen::Matrix3d q33 = matrix.topLeftCorner<3, 3>();
  const Eigen::Vector3d linear = matrix.block<3, 1>(0, 3);
  const double k = matrix(3, 3);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(q33);
  analysis.eigenvectors = solver.eigenvectors();
  analysis.eigenvalues = solver.eigenvalues();
  analysis.max_abs_eigenvalue = analysis.eigenvalues.cwiseAbs().maxCoeff();
  const double zero_level = tolerances.zero_eigenvalue * analysis.max_abs_eigenvalue;
  for (int i = 0; i < 3; ++i) {
    const double value = analysis.eigenvalues[i];
    analysis.signs[i] = (analysis.max_abs_eigenvalue == 0.0 || std::abs(value) <= zero_level) ? 0 : sign_of(value);
    if (analysis.signs[i] != 0) ++analysis.rank;
  }
  const Eigen::Vector3d linear_in_eigenbasis = analysis.eigenvectors.transpose() * linear;
  for (int i = 0; i < 3; ++i) {
    if (analysis.signs[i] != 0) {
      analysis.center -= (linear_in_eigenbasis[i] / analysis.eigenvalues[i]) * analysis.eigenvectors.col(i);
    } else {
      analysis.null_residual += linear_in_eigenbasis[i] * analysis.eigenvectors.col(i);
    }
  }
  // Consistency of [Q33 | l]: the null-space part of l against the magnitude of l (and of
  // sqrt(max|l_i| |k|), which has the units of l) so that the test is scale and unit invariant.
  const double linear_scale = std::max(linear.norm(), std::sqrt(analysis.max_abs_eigenvalue * std::abs(k)));
  analysis.consistent = analysis.null_residual.norm() <= tolerances.consistency * linear_scale;
  const double linear_term = linear.dot(analysis.center);
  analysis.constant = k + linear_term;
  analysis.constant_is_zero =
      std::abs(analysis.constant) <= tolerances.zero_constant * std::max(std::abs(k), std::abs(linear_term));
  return analysis;
}

// The factor (scale and sign) that normalises Q (paper normalisation rule, see Quadric::normalized).
double normalization_factor(const Eigen::Matrix4d& matrix, const CenterAnalysis& analysis) {
  double magnitude;
  if (analysis.rank > 0 && analysis.consistent && !analysis.constant_is_zero) {
    // For rank-3 Q33, det Q = det Q33 * c44 (Schur complement), so |prod l(Q33) / prod l(Q)| = 1/|c44|;
    // the same c44 is used for the rank-deficient consistent quadrics, whose pseudo-determinant
    // ratio is not invariant under rigid motions.
    magnitude = 1.0 / std::abs(analysis.constant);
  } else {
    magnitude = 1.0 / matrix.norm();
  }
  int positives = 0;
  int negatives = 0;
  for (int s : analysis.signs) {
    positives += s > 0;
    negatives += s < 0;
  }
  int sign = 1;
  if (positives < negatives) {
    sign = -1;
  } else if (positives == negatives) {
    if (analysis.consistent && !analysis.constant_is_zero) {
      sign = analysis.constant > 0.0 ? -1 : 1;  // ties: c44 < 0
    } else {
      int largest = 0;  // remaining ties: the eigenvalue of largest magnitude positive
      for (int i = 1; i < 3; ++i)
        if (std::abs(analysis.eigenvalues[i]) > std::abs(analysis.eigenvalues[largest])) largest = i;
      sign = analysis.eigenvalues[largest] >= 0.0 ? 1 : -1;
    }
  }
  return sign * magnitude;
}

// Makes the largest-magnitude component of v positive (deterministic axis sign).
Eigen::Vector3d largest_component_positive(const Eigen::Vector3d& v) {
  Eigen::Index index = 0;
  v.cwiseAbs().maxCoeff(&index);
  return v[index] < 0.0 ? Eigen::Vector3d(-v) : v;
}

// Completes a rotation whose columns flagged in `defined` are already unit and sign-normalised.
// One defined column u: the next column (cyclically) is the world axis least aligned with u made
// orthogonal to u, the last completes a right-handed frame. None: identity. Two or three: the third
// (c, or the missing one) is the cross product, so det = +1.
Eigen::Matrix3d complete_rotation(const Eigen::Matrix3d& axes, const std::array<bool, 3>& defined) {
  const int count = int(defined[0]) + int(defined[1]) + int(defined[2]);
  Eigen::Matrix3d rotation = axes;
  if (count == 0) return Eigen::Matrix3d::Identity();
  if (count == 1) {
    const int i = defined[0] ? 0 : (defined[1] ? 1 : 2);
    const Eigen::Vector3d u = axes.col(i);
    Eigen::Index least = 0;
    u.cwiseAbs().minCoeff(&least);
    Eigen::Vector3d v = Eigen::Vector3d::Unit(least) - u[least] * u;
    v.normalize();
    rotation.col((i + 1) % 3) = v;
    rotation.col((i + 2) % 3) = u.cross(v);
    return rotation;
  }
  const int missing = !defined[0] ? 0 : (!defined[1] ? 1 : 2);
  if (count == 2 || rotation.determinant() < 0.0) {
    rotation.col(missing) = rotation.col((missing + 1) % 3).cross(rotation.col((missing + 2) % 3));
  }
  return rotation;
}

void set_mask(Eigen::Vector3d& mask, double a, double b, double c) { mask = Eigen::Vector3d(a, b, c); }

// Eq. (Q=PCP) with C given directly.
Eigen::Matrix4d congruence(const Eigen::Matrix4d& canonical, const Eigen::Isometry3d& pose) {
  const Eigen::Matrix4d inverse = pose.inverse(Eigen::Isometry).matrix();
  return inverse.transpose() * canonical * inverse;
}

std::string vector_text(const Eigen::Vector3d& v) {
  std::ostringstream out;
  out << "(" << v[0] << ", " << v[1] << ", " << v[2] << ")";
  return out.str();
}

// Closest point to y on {p : sum_i A_i p_i^2 = c} for diagonal A (ellipse, ellipsoid, elliptic cone).
// The candidate nearest to `y` among those on the surface sum(A_i p_i^2) = level (relative residual
// <= 1e-6, rejecting ill-conditioned ones); the one with the smallest residual when none qualifies.
template <int N>
Eigen::Matrix<double, N, 1> nearest_on_surface(const Eigen::Matrix<double, N, 1>& coefficients, double level,
                                               const Eigen::Matrix<double, N, 1>& y,
                                               const std::vector<Eigen::Matrix<double, N, 1>>& candidates) {
  using Vector = Eigen::Matrix<double, N, 1>;
  Vector best = y;
  double best_distance = kInfinity;
  double best_residual = kInfinity;
  Vector fallback = y;
  for (const Vector& p : candidates) {
    double value = -level;
    double size = std::abs(level);
    for (int i = 0; i < N; ++i) {
      value += coefficients[i] * p[i] * p[i];
      size += std::abs(coefficients[i]) * p[i] * p[i];
    }
    const double residual = size > 0.0 ? std::abs(value) / size : 0.0;
    if (residual < best_residual) {
      best_residual = residual;
      fallback = p;
    }
    if (residual > 1e-6) continue;
    const double distance = (p - y).norm();
    if (distance < best_distance) {
      best_distance = distance;
      best = p;
    }
  }
  return std::isinf(best_distance) ? fallback : best;
}

// Lagrange: p = (I + mu A)^-1 y with F(mu) = sum A_i y_i^2 / (1 + mu A_i)^2 - c = 0 on the interval
// where I + mu A > 0. F is strictly decreasing there, so the root is found by bisection (Eberly's
// robust scheme generalised to indefinite A), and by weak duality it is the global minimum. When y
// vanishes on the axes of a pole, the minimum may sit on the interval's end (the boundary
// candidates below). The apex of a cone (c = 0) is also a candidate.
template <int N>
Eigen::Matrix<double, N, 1> closest_on_central_quadric(const Eigen::Matrix<double, N, 1>& coefficients, double level,
                                                        const Eigen::Matrix<double, N, 1>& y) {
  using Vector = Eigen::Matrix<double, N, 1>;
  double largest_positive = 0.0;
  double largest_negative = 0.0;
  for (int i = 0; i < N; ++i) {
    largest_positive = std::max(largest_positive, coefficients[i]);
    largest_negative = std::max(largest_negative, -coefficients[i]);
  }
  const double lower = -1.0 / largest_positive;  // there is always a positive coefficient here
  const double upper = largest_negative > 0.0 ? 1.0 / largest_negative : kInfinity;
  const double magnitude = y.cwiseAbs().maxCoeff();
  const double negligible = 1e-12 * magnitude;
  std::array<bool, N> at_lower{};
  std::array<bool, N> at_upper{};
  bool lower_pole_active = false;
  bool upper_pole_active = false;
  for (int i = 0; i < N; ++i) {
    at_lower[i] = coefficients[i] == largest_positive;
    at_upper[i] = largest_negative > 0.0 && coefficients[i] == -largest_negative;
    if (at_lower[i] && std::abs(y[i]) > negligible) lower_pole_active = true;
    if (at_upper[i] && std::abs(y[i]) > negligible) upper_pole_active = true;
  }
  // F over the terms not excluded (excluded terms sit on a pole with y ~ 0).
  auto function = [&](double mu, const std::array<bool, N>& excluded) {
    double sum = -level;
    for (int i = 0; i < N; ++i) {
      if (excluded[i] || y[i] == 0.0) continue;
      const double denominator = 1.0 + mu * coefficients[i];
      sum += coefficients[i] * y[i] * y[i] / (denominator * denominator);
    }
    return sum;
  };
  const std::array<bool, N> none{};
  std::vector<Vector> candidates;
  auto point_for = [&](double mu) {
    Vector p;
    for (int i = 0; i < N; ++i) p[i] = y[i] == 0.0 ? 0.0 : y[i] / (1.0 + mu * coefficients[i]);
    return p;
  };
  // Interior root.
  const double lower_value = lower_pole_active ? kInfinity : function(lower, at_lower);
  double right = upper;
  double upper_value = -kInfinity;
  if (std::isinf(upper)) {
    right = std::max(1.0, 2.0 * std::abs(lower));
    for (int iteration = 0; iteration < 2000 && function(right, none) > 0.0; ++iteration) right *= 2.0;
    upper_value = function(right, none);
  } else if (!upper_pole_active) {
    upper_value = function(upper, at_upper);
  }
  if (lower_value > 0.0 && (upper_value < 0.0 || (std::isinf(upper) && upper_value <= 0.0))) {
    double left = lower;
    for (int iteration = 0; iteration < 400; ++iteration) {
      const double middle = 0.5 * (left + right);
      if (middle <= left || middle >= right) break;
      if (function(middle, none) > 0.0) left = middle; else right = middle;
    }
    candidates.push_back(point_for(0.5 * (left + right)));
  }
  // Boundary candidates: the pole's axes take up the remaining level.
  auto add_boundary = [&](double mu, const std::array<bool, N>& pole, double pole_coefficient) {
    Vector p = point_for(mu);
    double rest = 0.0;
    int first = -1;
    double pole_norm = 0.0;
    for (int i = 0; i < N; ++i) {
      if (pole[i]) {
        if (first < 0) first = i;
        pole_norm += y[i] * y[i];
        p[i] = 0.0;
      } else {
        rest += coefficients[i] * p[i] * p[i];
      }
    }
    const double squared = (level - rest) / pole_coefficient;
    if (squared < 0.0 || first < 0) return;
    const double length = std::sqrt(squared);
    if (pole_norm > 0.0) {
      const double scale = length / std::sqrt(pole_norm);
      for (int i = 0; i < N; ++i) if (pole[i]) p[i] = y[i] * scale;
    } else {
      p[first] = length;
    }
    candidates.push_back(p);
  };
  if (!lower_pole_active) add_boundary(lower, at_lower, largest_positive);
  if (largest_negative > 0.0 && !upper_pole_active) add_boundary(upper, at_upper, -largest_negative);
  if (level == 0.0) candidates.push_back(Vector::Zero());
  return nearest_on_surface(coefficients, level, y, candidates);
}

// Closest point on the circular double cone rho = tan(alpha) |z| in the axial half-plane (closed form).
Eigen::Vector3d closest_on_circular_cone(double tangent, const Eigen::Vector3d& y) {
  const double rho = std::hypot(y[0], y[1]);
  const double z = y[2];
  const double cosine = 1.0 / std::sqrt(1.0 + tangent * tangent);
  const double sine = tangent * cosine;
  Eigen::Vector2d best(0.0, 0.0);  // apex
  double best_distance = std::hypot(rho, z);
  for (double direction : {1.0, -1.0}) {
    const Eigen::Vector2d generatrix(sine, direction * cosine);
    const double projection = rho * generatrix[0] + z * generatrix[1];
    if (projection <= 0.0) continue;
    const Eigen::Vector2d foot = projection * generatrix;
    const double distance = std::hypot(rho - foot[0], z - foot[1]);
    if (distance < best_distance) {
      best_distance = distance;
      best = foot;
    }
  }
  const Eigen::Vector2d azimuth = rho > 0.0 ? Eigen::Vector2d(y[0] / rho, y[1] / rho) : Eigen::Vector2d(1.0, 0.0);
  return Eigen::Vector3d(best[0] * azimuth[0], best[0] * azimuth[1], best[1]);
}

// Closest point in canonical coordinates; `exact` false for types without a closed/robust solver.
bool closest_in_canonical(const QuadricDecomposition& shape, const Eigen::Vector3d& y, Eigen::Vector3d& closest) {
  const Eigen::Vector3d& s = shape.scale;
  switch (shape.type) {
    case QuadricType::Point:
      closest.setZero();
      return true;
    case QuadricType::Line:
      closest = Eigen::Vector3d(0.0, 0.0, y[2]);
      return true;
    case QuadricType::Plane:
      closest = Eigen::Vector3d(0.0, y[1], y[2]);
      return true;
    case QuadricType::Sphere: {
      const double norm = y.norm();
      closest = norm > 0.0 ? Eigen::Vector3d(y * (s[0] / norm)) : Eigen::Vector3d(s[0], 0.0, 0.0);
      return true;
    }
    case QuadricType::Ellipsoid:
      closest = closest_on_central_quadric<3>(s.cwiseProduct(s).cwiseInverse(), 1.0, y);
      return true;
    case QuadricType::CircularCylinder: {
      const double rho = std::hypot(y[0], y[1]);
      closest = rho > 0.0 ? Eigen::Vector3d(y[0] * s[0] / rho, y[1] * s[0] / rho, y[2]) : Eigen::Vector3d(s[0], 0.0, y[2]);
      return true;
    }
    case QuadricType::EllipticCylinder: {
      const Eigen::Vector2d coefficients(1.0 / (s[0] * s[0]), 1.0 / (s[1] * s[1]));
      const Eigen::Vector2d planar = closest_on_central_quadric<2>(coefficients, 1.0, y.head<2>());
      closest = Eigen::Vector3d(planar[0], planar[1], y[2]);
      return true;
    }
    case QuadricType::CircularCone:
      closest = closest_on_circular_cone(s[0], y);
      return true;
    case QuadricType::EllipticCone:
      closest = closest_on_central_quadric<3>(Eigen::Vector3d(1.0 / (s[0] * s[0]), 1.0 / (s[1] * s[1]), -1.0), 0.0, y);
      return true;
    default:
      return false;
  }
}

}  // namespace

std::string quadric_type_name(QuadricType type) {
  for (const TypeName& entry : kTypeNames)
    if (entry.type == type) return entry.name;
  return "invalid";
}

QuadricType quadric_type_from_name(const std::string& name) {
  for (const TypeName& entry : kTypeNames)
    if (name == entry.name) return entry.type;
  if (name == "cylinder") return QuadricType::CircularCylinder;
  if (name == "cone") return QuadricType::CircularCone;
  std::string known;
  for (const TypeName& entry : kTypeNames) known += std::string(known.empty() ? "" : ", ") + entry.name;
  throw Error("unknown quadric type '" + name + "': expected one of " + known + ", cylinder, cone");
}

DegeneracyIndicators degeneracy_indicators(QuadricType type) {
  // Paper Table "Characteristics of typical quadrics"; the other real types by the same reasoning
  // (a zero eigenvalue frees the translation along its axis; a rotational symmetry frees the
  // rotation of the axes that are not unique; a zero c44 leaves only ratios of scales).
  DegeneracyIndicators d;
  switch (type) {
    case QuadricType::Point: set_mask(d.scale, 0, 0, 0); set_mask(d.rotation, 0, 0, 0); set_mask(d.translation, 1, 1, 1); break;
    case QuadricType::Line: set_mask(d.scale, 0, 0, 0); set_mask(d.rotation, 0, 0, 1); set_mask(d.translation, 1, 1, 0); break;
    case QuadricType::Plane: set_mask(d.scale, 0, 0, 0); set_mask(d.rotation, 1, 0, 0); set_mask(d.translation, 1, 0, 0); break;
    case QuadricType::Sphere: set_mask(d.scale, 1, 1, 1); set_mask(d.rotation, 0, 0, 0); set_mask(d.translation, 1, 1, 1); break;
    case QuadricType::Ellipsoid: set_mask(d.scale, 1, 1, 1); set_mask(d.rotation, 1, 1, 1); set_mask(d.translation, 1, 1, 1); break;
    case QuadricType::CircularCylinder: set_mask(d.scale, 1, 1, 0); set_mask(d.rotation, 0, 0, 1); set_mask(d.translation, 1, 1, 0); break;
    case QuadricType::EllipticCylinder: set_mask(d.scale, 1, 1, 0); set_mask(d.rotation, 1, 1, 1); set_mask(d.translation, 1, 1, 0); break;
    case QuadricType::CircularCone: set_mask(d.scale, 1, 1, 0); set_mask(d.rotation, 0, 0, 1); set_mask(d.translation, 1, 1, 1); break;
    case QuadricType::EllipticCone: set_mask(d.scale, 1, 1, 0); set_mask(d.rotation, 1, 1, 1); set_mask(d.translation, 1, 1, 1); break;
    case QuadricType::HyperboloidOneSheet:
    case QuadricType::HyperboloidTwoSheets: set_mask(d.scale, 1, 1, 1); set_mask(d.rotation, 1, 1, 1); set_mask(d.translation, 1, 1, 1); break;
    case QuadricType::EllipticParaboloid:
    case QuadricType::HyperbolicParaboloid: set_mask(d.scale, 1, 1, 0); set_mask(d.rotation, 1, 1, 1); set_mask(d.translation, 1, 1, 1); break;
    case QuadricType::ParabolicCylinder: set_mask(d.scale, 1, 0, 0); set_mask(d.rotation, 1, 1, 1); set_mask(d.translation, 1, 1, 0); break;
    case QuadricType::HyperbolicCylinder: set_mask(d.scale, 1, 1, 0); set_mask(d.rotation, 1, 1, 1); set_mask(d.translation, 1, 1, 0); break;
    case QuadricType::IntersectingPlanes: set_mask(d.scale, 1, 0, 0); set_mask(d.rotation, 1, 1, 1); set_mask(d.translation, 1, 1, 0); break;
    case QuadricType::ParallelPlanes: set_mask(d.scale, 1, 0, 0); set_mask(d.rotation, 1, 0, 0); set_mask(d.translation, 1, 0, 0); break;
    case QuadricType::Imaginary:
    case QuadricType::Invalid: break;
  }
  return d;
}

Eigen::Isometry3d QuadricDecomposition::pose() const {
  Eigen::Isometry3d result = Eigen::Isometry3d::Identity();
  result.linear() = rotation;
  result.translation() = center;
  return result;
}

Quadric::Quadric(const Eigen::Matrix4d& matrix) : matrix_(0.5 * (matrix + matrix.transpose())) {}

Quadric Quadric::from_parameters(const Vector10d& q) {
  // Eq. (Q and normal): q = [A, B, C, D, E, F, G, H, I, J].
  Eigen::Matrix4d m;
  m << q[0], q[3], q[4], q[6],
       q[3], q[1], q[5], q[7],
       q[4], q[5], q[2], q[8],
       q[6], q[7], q[8], q[9];
  return Quadric(m);
}

Quadric Quadric::from_canonical(QuadricType type, const Eigen::Vector3d& scale, const Eigen::Isometry3d& pose) {
  const std::string where = "Quadric::from_canonical(" + quadric_type_name(type) + ")";
  if (!scale.allFinite()) throw Error(where + ": scale " + vector_text(scale) + " is not finite");
  if (!pose.matrix().allFinite()) throw Error(where + ": pose is not finite");
  const Eigen::Matrix3d rotation = pose.linear();
  if ((rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).norm() > 1e-6 || rotation.determinant() < 0.0)
    throw Error(where + ": pose rotation is not a proper rotation (R^T R != I or det R < 0)");
  static const char* const kAxisNames[] = {"a", "b", "c"};
  auto required = [&](int axis) {
    if (!(scale[axis] > 0.0))
      throw Error(where + ": scale along axis " + kAxisNames[axis] + " must be > 0, got " + vector_text(scale));
    return 1.0 / (scale[axis] * scale[axis]);
  };
  auto weight = [&](int axis) { return scale[axis] > 0.0 ? 1.0 / (scale[axis] * scale[axis]) : 1.0; };
  Eigen::Matrix4d canonical = Eigen::Matrix4d::Zero();
  auto diagonal = [&](double a, double b, double c, double d) { canonical.diagonal() << a, b, c, d; };
  switch (type) {
    case QuadricType::Point: diagonal(weight(0), weight(1), weight(2), 0.0); break;
    case QuadricType::Line: diagonal(weight(0), weight(1), 0.0, 0.0); break;
    case QuadricType::Plane: diagonal(weight(0), 0.0, 0.0, 0.0); break;
    case QuadricType::Sphere:
    case QuadricType::Ellipsoid: diagonal(required(0), required(1), required(2), -1.0); break;
    case QuadricType::CircularCylinder:
    case QuadricType::EllipticCylinder: diagonal(required(0), required(1), 0.0, -1.0); break;
    case QuadricType::CircularCone:
    case QuadricType::EllipticCone: diagonal(required(0), required(1), -1.0, 0.0); break;
    case QuadricType::HyperboloidOneSheet: diagonal(required(0), required(1), -required(2), -1.0); break;
    case QuadricType::HyperboloidTwoSheets: diagonal(required(0), required(1), -required(2), 1.0); break;
    case QuadricType::EllipticParaboloid:
      diagonal(required(0), required(1), 0.0, 0.0);
      canonical(2, 3) = canonical(3, 2) = -1.0;
      break;
    case QuadricType::HyperbolicParaboloid:
      diagonal(required(0), -required(1), 0.0, 0.0);
      canonical(2, 3) = canonical(3, 2) = -1.0;
      break;
    case QuadricType::ParabolicCylinder:
      diagonal(required(0), 0.0, 0.0, 0.0);
      canonical(1, 3) = canonical(3, 1) = -1.0;
      break;
    case QuadricType::HyperbolicCylinder: diagonal(required(0), -required(1), 0.0, -1.0); break;
    case QuadricType::IntersectingPlanes: diagonal(required(0), -1.0, 0.0, 0.0); break;
    case QuadricType::ParallelPlanes: diagonal(required(0), 0.0, 0.0, -1.0); break;
    case QuadricType::Imaginary:
    case QuadricType::Invalid:
      throw Error(where + ": this type has no real canonical form to build from");
  }
  return Quadric(congruence(canonical, pose));  // Eq. (Q=PCP)
}

Vector10d Quadric::parameters() const {
  const Eigen::Matrix4d& m = matrix_;
  Vector10d q;
  q << m(0, 0), m(1, 1), m(2, 2), m(0, 1), m(0, 2), m(1, 2), m(0, 3), m(1, 3), m(2, 3), m(3, 3);
  return q;
}

double Quadric::evaluate(const Eigen::Vector3d& x) const {
  const Eigen::Vector4d h(x[0], x[1], x[2], 1.0);
  return h.dot(matrix_ * h);  // Eq. (quadrics equation)
}

Eigen::Vector3d Quadric::gradient(const Eigen::Vector3d& x) const {
  const Eigen::Vector4d h(x[0], x[1], x[2], 1.0);
  return 2.0 * (matrix_.topRows<3>() * h);  // Eq. (Q and normal): grad f = (grad Q) x
}

double Quadric::sampson_distance(const Eigen::Vector3d& x) const {
  const double value = evaluate(x);
  const double gradient_norm = gradient(x).norm();
  if (value == 0.0) return 0.0;
  if (gradient_norm == 0.0) return kInfinity;
  return std::abs(value) / gradient_norm;
}

Quadric Quadric::normalized(const DecompositionTolerances& tolerances) const {
  if (!matrix_.allFinite() || matrix_.topLeftCorner<3, 3>().isZero(0.0)) return *this;
  const CenterAnalysis analysis = analyse_center(matrix_, tolerances);
  if (analysis.rank == 0) return *this;
  Quadric result;
  result.matrix_ = matrix_ * normalization_factor(matrix_, analysis);
  return result;
}

Quadric Quadric::transformed(const Eigen::Isometry3d& transform) const {
  Quadric result;
  result.matrix_ = congruence(matrix_, transform);  // Q' = T^-T Q T^-1
  result.matrix_ = 0.5 * (result.matrix_ + result.matrix_.transpose());
  return result;
}

namespace {

// Whether sorted eigenvalues i and j are equal within `level` (the symmetry test of decompose).
bool eigenvalues_equal(const Eigen::Vector3d& lambda, double level, int i, int j) {
  return std::abs(lambda[i] - lambda[j]) <= level;
}

// Type and centre kind from the rank of Q33, whether the centre equation (Eq. (solve t)) is
// consistent, the count of positive eigenvalues and the sign of the constant c44 (paper Table
// "Characteristics of typical quadrics"); equal eigenvalues tell spheres, circular cylinders and
// circular cones from their elliptic kin.
std::pair<QuadricType, CenterKind> classify_quadric(int rank, bool consistent, int positives, int constant_sign,
                                                    const Eigen::Vector3d& lambda, double equal_level) {
  const auto equal = [&](int i, int j) { return eigenvalues_equal(lambda, equal_level, i, j); };
  if (rank == 3) {
    if (positives == 3)
      return {constant_sign < 0 ? (equal(0, 2) ? QuadricType::Sphere : QuadricType::Ellipsoid)
                                : (constant_sign == 0 ? QuadricType::Point : QuadricType::Imaginary),
              CenterKind::Central};
    return {constant_sign < 0 ? QuadricType::HyperboloidOneSheet
                              : (constant_sign == 0 ? (equal(0, 1) ? QuadricType::CircularCone : QuadricType::EllipticCone)
                                                    : QuadricType::HyperboloidTwoSheets),
            CenterKind::Central};
  }
  if (rank == 2) {
    if (!consistent)
      return {positives == 2 ? QuadricType::EllipticParaboloid : QuadricType::HyperbolicParaboloid, CenterKind::NoCenter};
    if (positives == 2)
      return {constant_sign < 0 ? (equal(0, 1) ? QuadricType::CircularCylinder : QuadricType::EllipticCylinder)
                                : (constant_sign == 0 ? QuadricType::Line : QuadricType::Imaginary),
              CenterKind::LinearCenter};
    return {constant_sign == 0 ? QuadricType::IntersectingPlanes : QuadricType::HyperbolicCylinder, CenterKind::LinearCenter};
  }
  if (!consistent) return {QuadricType::ParabolicCylinder, CenterKind::NoCenter};
  return {constant_sign < 0 ? QuadricType::ParallelPlanes : (constant_sign == 0 ? QuadricType::Plane : QuadricType::Imaginary),
          CenterKind::PlanarCenter};
}

// Scales, Eq. (geometry analysis): s = sqrt(|1/l|) with |c44| = 1 after normalisation; cones and
// intersecting planes (c44 = 0) give tangents of half-angles; paraboloids sqrt(|m|/|l|). Before the
// I_s mask.
Eigen::Vector3d canonical_scales(QuadricType type, const Eigen::Vector3d& lambda, double residual_norm) {
  Eigen::Vector3d scale = Eigen::Vector3d::Zero();
  switch (type) {
    case QuadricType::Sphere:
    case QuadricType::Ellipsoid:
    case QuadricType::HyperboloidOneSheet:
    case QuadricType::HyperboloidTwoSheets:
      scale = lambda.cwiseAbs().cwiseInverse().cwiseSqrt();
      break;
    case QuadricType::CircularCylinder:
    case QuadricType::EllipticCylinder:
    case QuadricType::HyperbolicCylinder:
      scale.head<2>() = lambda.head<2>().cwiseAbs().cwiseInverse().cwiseSqrt();
      break;
    case QuadricType::ParallelPlanes:
      scale[0] = std::sqrt(1.0 / std::abs(lambda[0]));
      break;
    case QuadricType::CircularCone:
    case QuadricType::EllipticCone:
      scale[0] = std::sqrt(std::abs(lambda[2]) / lambda[0]);
      scale[1] = std::sqrt(std::abs(lambda[2]) / lambda[1]);
      break;
    case QuadricType::IntersectingPlanes:
      scale[0] = std::sqrt(std::abs(lambda[1]) / lambda[0]);
      break;
    case QuadricType::EllipticParaboloid:
    case QuadricType::HyperbolicParaboloid:
      scale[0] = std::sqrt(residual_norm / std::abs(lambda[0]));
      scale[1] = std::sqrt(residual_norm / std::abs(lambda[1]));
      break;
    case QuadricType::ParabolicCylinder:
      scale[0] = std::sqrt(residual_norm / std::abs(lambda[0]));
      break;
    default:
      break;
  }
  return scale;
}

// Symmetry: equal eigenvalues leave only the unique axis defined (paper §"Quadric Degeneracy"),
// which narrows the rotation indicator I_R of ellipsoids, hyperboloids and elliptic paraboloids.
void narrow_rotation_indicator(QuadricType type, const Eigen::Vector3d& lambda, double equal_level,
                               Eigen::Vector3d& rotation_indicator) {
  const auto equal = [&](int i, int j) { return eigenvalues_equal(lambda, equal_level, i, j); };
  if (type == QuadricType::Ellipsoid) {
    if (equal(0, 1)) rotation_indicator = Eigen::Vector3d(0, 0, 1);
    else if (equal(1, 2)) rotation_indicator = Eigen::Vector3d(1, 0, 0);
  } else if (type == QuadricType::HyperboloidOneSheet || type == QuadricType::HyperboloidTwoSheets ||
             type == QuadricType::EllipticParaboloid) {
    if (equal(0, 1)) rotation_indicator = Eigen::Vector3d(0, 0, 1);
  }
}

// Rotation R_q = +/- R_hat diag(I_R): defined axes sign-normalised (largest component positive,
// except a paraboloid's opening axis, `geometric`), undefined axes completed deterministically, det = +1.
Eigen::Matrix3d normalised_rotation(Eigen::Matrix3d axes, const Eigen::Vector3d& rotation_indicator, QuadricType type,
                                    const std::array<bool, 3>& geometric) {
  std::array<bool, 3> defined{{false, false, false}};
  for (int k = 0; k < 3; ++k) defined[k] = rotation_indicator[k] > 0.5 || type == QuadricType::Imaginary;
  for (int k = 0; k < 3; ++k)
    if (defined[k] && !geometric[k]) axes.col(k) = largest_component_positive(axes.col(k));
  if (!(defined[0] && defined[1] && defined[2])) return complete_rotation(axes, defined);
  if (geometric[2]) axes.col(1) = axes.col(2).cross(axes.col(0));
  else axes.col(2) = axes.col(0).cross(axes.col(1));
  return axes;
}

}  // namespace

QuadricDecomposition Quadric::decompose(const DecompositionTolerances& tolerances) const {
  QuadricDecomposition result;
  if (!matrix_.allFinite()) return result;
  CenterAnalysis analysis = analyse_center(matrix_, tolerances);
  if (analysis.rank == 0) return result;
  // Normalisation rule (scale ambiguity): eigenvalues, m and c44 scale with Q, the centre does not.
  const double factor = normalization_factor(matrix_, analysis);
  analysis.eigenvalues *= factor;
  analysis.null_residual *= factor;
  analysis.constant *= factor;
  analysis.max_abs_eigenvalue *= std::abs(factor);
  for (int i = 0; i < 3; ++i) analysis.signs[i] *= factor > 0.0 ? 1 : -1;

  // Axis order: positive eigenvalues (descending, so l_a >= l_b >= l_c for ellipsoids as in the
  // paper), then negative ones, then zeros.
  std::array<int, 3> order{{0, 1, 2}};
  auto group = [&](int i) { return analysis.signs[i] > 0 ? 0 : (analysis.signs[i] < 0 ? 1 : 2); };
  std::sort(order.begin(), order.end(), [&](int i, int j) {
    if (group(i) != group(j)) return group(i) < group(j);
    return std::abs(analysis.eigenvalues[i]) > std::abs(analysis.eigenvalues[j]);
  });
  Eigen::Matrix3d axes;
  Eigen::Vector3d lambda;
  int positives = 0;
  for (int k = 0; k < 3; ++k) {
    axes.col(k) = analysis.eigenvectors.col(order[k]);
    lambda[k] = analysis.eigenvalues[order[k]];
    positives += analysis.signs[order[k]] > 0;
  }
  const double equal_level = tolerances.equal_eigenvalues * analysis.max_abs_eigenvalue;
  const int constant_sign = (!analysis.consistent || analysis.constant_is_zero) ? 0 : sign_of(analysis.constant);
  const int rank = analysis.rank;
  const auto [type, center_kind] = classify_quadric(rank, analysis.consistent, positives, constant_sign, lambda, equal_level);

  result.type = type;
  result.center_kind = center_kind;
  result.rank_q33 = rank;
  result.rank_q = analysis.consistent ? rank + (constant_sign != 0 ? 1 : 0) : rank + 2;
  result.eigenvalues = lambda;
  result.constant = analysis.consistent ? analysis.constant : 0.0;
  result.indicators = degeneracy_indicators(type);
  result.center = analysis.center;

  // Geometric sign of the axis along which a paraboloid opens (Eq. (solve t) has no solution).
  std::array<bool, 3> geometric{{false, false, false}};
  const double residual_norm = analysis.null_residual.norm();
  const double vertex_shift = residual_norm > 0.0 ? analysis.constant / (2.0 * residual_norm) : 0.0;
  if (type == QuadricType::EllipticParaboloid || type == QuadricType::HyperbolicParaboloid) {
    axes.col(2) = -analysis.null_residual / residual_norm;
    geometric[2] = true;
    result.center = analysis.center + vertex_shift * axes.col(2);  // the vertex
  } else if (type == QuadricType::ParabolicCylinder) {
    axes.col(1) = -analysis.null_residual / residual_norm;
    geometric[1] = true;
    axes.col(2) = axes.col(0).cross(axes.col(1));
  }

  result.scale = canonical_scales(type, lambda, residual_norm).cwiseProduct(result.indicators.scale);
  narrow_rotation_indicator(type, lambda, equal_level, result.indicators.rotation);
  result.rotation = normalised_rotation(axes, result.indicators.rotation, type, geometric);
  if (type == QuadricType::ParabolicCylinder) {
    // Vertex line: move along the opening axis to the vertex, then take its minimum-norm point.
    Eigen::Vector3d vertex = analysis.center + vertex_shift * result.rotation.col(1);
    vertex -= vertex.dot(result.rotation.col(2)) * result.rotation.col(2);
    result.center = vertex;
  }
  return result;
}

Quadric quadric_from_decomposition(const QuadricDecomposition& shape) {
  if (shape.type == QuadricType::Invalid || shape.type == QuadricType::Imaginary) return Quadric();
  return Quadric::from_canonical(shape.type, shape.scale, shape.pose());
}

double orthogonal_distance(const QuadricDecomposition& shape, const Eigen::Vector3d& x) {
  if (shape.type == QuadricType::Invalid || shape.type == QuadricType::Imaginary) return kInfinity;
  const Eigen::Vector3d local = shape.rotation.transpose() * (x - shape.center);
  Eigen::Vector3d closest;
  if (closest_in_canonical(shape, local, closest)) return (closest - local).norm();
  return quadric_from_decomposition(shape).sampson_distance(x);
}

Eigen::Vector3d closest_surface_point(const QuadricDecomposition& shape, const Eigen::Vector3d& x) {
  if (shape.type == QuadricType::Invalid || shape.type == QuadricType::Imaginary) return x;
  const Eigen::Vector3d local = shape.rotation.transpose() * (x - shape.center);
  Eigen::Vector3d closest;
  if (closest_in_canonical(shape, local, closest)) return shape.rotation * closest + shape.center;
  const Quadric quadric = quadric_from_decomposition(shape);
  const Eigen::Vector3d gradient = quadric.gradient(x);
  const double squared = gradient.squaredNorm();
  if (squared == 0.0) return x;
  return x - (quadric.evaluate(x) / squared) * gradient;
}

}  // namespace quadrix
