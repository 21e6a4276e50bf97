// Taubin's algebraic fit (G. Taubin, "Estimation of planar curves, surfaces, and nonplanar space
// curves defined by implicit equations", PAMI 1991): minimise sum f(x)^2 / sum ||grad f(x)||^2
// over q, i.e. the generalised eigenproblem M q = mu N q with M = sum m m^T (m = monomials of
// paper Eq. (quadrics equation)) and N = sum_k sum (dm/dx_k)(dm/dx_k)^T; q is the eigenvector of
// the smallest mu. N is singular in the constant term J (it has no gradient), so J is eliminated
// in closed form first (J = -M_J9 q9 / M_JJ) and the reduced 9x9 problem is solved.
#include "fitting/taubin_fitter.h"

#include "fitting/statistical_fitter.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>

namespace quadrix {
namespace {

using Matrix10 = Eigen::Matrix<double, 10, 10>;

/// Monomials m(x) with q . m(x) = f_q(x) for q = [A..J] (paper Eq. (quadrics equation)).
template <typename Column>
void write_monomials(const Eigen::Vector3d& x, Column&& m) {
  m << x.x() * x.x(), x.y() * x.y(), x.z() * x.z(), 2 * x.x() * x.y(), 2 * x.x() * x.z(), 2 * x.y() * x.z(),
      2 * x.x(), 2 * x.y(), 2 * x.z(), 1.0;
}

/// G_k (4 x 10): row r of G_k^T [x y z 1]^T is d m_r / d x_k, so the monomial gradients are linear
/// in the homogeneous point and sum_i (dm/dx_k)(dm/dx_k)^T = G_k^T S G_k with S = sum_i [x;1][x;1]^T.
std::array<Eigen::Matrix<double, 4, 10>, 3> gradient_coefficients() {
  std::array<Eigen::Matrix<double, 4, 10>, 3> g;
  for (auto& matrix : g) matrix.setZero();
  // d/dx: [2x, 0, 0, 2y, 2z, 0, 2, 0, 0, 0]
  g[0](0, 0) = 2; g[0](1, 3) = 2; g[0](2, 4) = 2; g[0](3, 6) = 2;
  // d/dy: [0, 2y, 0, 2x, 0, 2z, 0, 2, 0, 0]
  g[1](1, 1) = 2; g[1](0, 3) = 2; g[1](2, 5) = 2; g[1](3, 7) = 2;
  // d/dz: [0, 0, 2z, 0, 2x, 2y, 0, 0, 2, 0]
  g[2](2, 2) = 2; g[2](0, 4) = 2; g[2](1, 5) = 2; g[2](3, 8) = 2;
  return g;
}

/// True when `found` is an acceptable answer to `requested` (circular/elliptic variants count as one family).
bool same_family(QuadricType requested, QuadricType found) {
  const auto family = [](QuadricType type) {
    switch (type) {
      case QuadricType::Sphere: case QuadricType::Ellipsoid: return 1;
      case QuadricType::CircularCylinder: case QuadricType::EllipticCylinder: return 2;
      case QuadricType::CircularCone: case QuadricType::EllipticCone: return 3;
      default: return 100 + static_cast<int>(type);
    }
  };
  if (requested == QuadricType::Sphere) return found == QuadricType::Sphere;
  return family(requested) == family(found);
}

class TaubinFitter final : public QuadricFitter {
 public:
  explicit TaubinFitter(const TaubinFitterOptions& options) : options_(options) {}

  std::string name() const override { return "taubin"; }

  QuadricFit fit(const Eigen::Matrix3Xd& points, const Eigen::Matrix3Xd& /*normals*/, FitTypeHint hint) const override {
    const auto start = std::chrono::steady_clock::now();
    QuadricFit result;
    const auto finish = [&](QuadricFit& fit) -> QuadricFit& {
      fit.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      return fit;
    };
    // A point, line or plane makes the quadric problem rank-deficient (every product of the plane's
    // linear form with any other linear form fits); Taubin's estimator of a degree-1 surface is the
    // total-least-squares fit, which is exactly what the statistical fitter computes for these types.
    if (hint && (*hint == QuadricType::Point || *hint == QuadricType::Line || *hint == QuadricType::Plane)) {
      StatisticalFitterOptions linear_options;
      linear_options.evaluation = options_.evaluation;
      QuadricFit linear = make_statistical_fitter(linear_options)->fit(points, Eigen::Matrix3Xd(), hint);
      linear.time_ms = 0.0;
      return finish(linear);
    }
    if (points.cols() < 9) {
      result.status = FitStatus::TooFewPoints;
      result.message = "an algebraic quadric fit needs at least 9 points, got " + std::to_string(points.cols());
      return finish(result);
    }
    // Two passes give t_s, the covariance and so the RMS radius; a third accumulates the moments.
    Eigen::Matrix3d covariance;
    result.statistics = point_statistics(points, kStatisticalScaleFactor, &covariance);
    // Normalise to unit space (centroid at the origin, RMS radius sqrt(2)) for conditioning.
    const Eigen::Vector3d center = result.statistics.center;
    const double rms = std::sqrt(covariance.trace());
    if (!(rms > 0.0)) {
      result.status = FitStatus::Degenerate;
      result.message = "all points coincide";
      return finish(result);
    }
    const double sigma = rms / std::sqrt(2.0);
    const double inverse_sigma = 1.0 / sigma;
    // M = sum m m^T, accumulated as a symmetric rank update per block of monomial columns on the stack.
    constexpr Eigen::Index kBlock = 128;
    Eigen::Matrix<double, 10, kBlock> block;
    Matrix10 moments = Matrix10::Zero();
    for (Eigen::Index begin = 0; begin < points.cols(); begin += kBlock) {
      const Eigen::Index size = std::min(kBlock, points.cols() - begin);
      for (Eigen::Index j = 0; j < size; ++j)
        write_monomials((points.col(begin + j) - center) * inverse_sigma, block.col(j));
      moments.selfadjointView<Eigen::Lower>().rankUpdate(block.leftCols(size));
    }
    // N = sum_k G_k^T S G_k, with S of the unit-space points: sum x x^T = n cov / sigma^2, sum x = 0.
    const double count = static_cast<double>(points.cols());
    Eigen::Matrix4d homogeneous_moments = Eigen::Matrix4d::Zero();
    homogeneous_moments.topLeftCorner<3, 3>() = covariance * (count * inverse_sigma * inverse_sigma);
    homogeneous_moments(3, 3) = count;
    static const std::array<Eigen::Matrix<double, 4, 10>, 3> coefficients = gradient_coefficients();
    Matrix10 gradient_moments = Matrix10::Zero();
    for (const auto& g : coefficients) gradient_moments.noalias() += g.transpose() * homogeneous_moments * g;
    moments = moments.selfadjointView<Eigen::Lower>();
    // Eliminate J (index 9): for fixed q9 the best J is -M_{9,0:9} q9 / M_99.
    const double constant_moment = moments(9, 9);
    const Eigen::Matrix<double, 9, 1> cross = moments.block<9, 1>(0, 9);
    const Eigen::Matrix<double, 9, 9> reduced = moments.topLeftCorner<9, 9>() - cross * cross.transpose() / constant_moment;
    const Eigen::Matrix<double, 9, 9> constraint = gradient_moments.topLeftCorner<9, 9>();
    Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::Matrix<double, 9, 9>> solver(reduced, constraint);
    if (solver.info() != Eigen::Success) {
      result.status = FitStatus::Degenerate;
      result.message = "the gradient moment matrix is singular (points on a curve, not a surface)";
      return finish(result);
    }
    Vector10d unit_parameters;
    unit_parameters.head<9>() = solver.eigenvectors().col(0);
    unit_parameters(9) = -cross.dot(unit_parameters.head<9>()) / constant_moment;
    // Back to the world: x_u = A x with A = [I/sigma, -c/sigma; 0, 1], so Q = A^T Q_u A.
    Eigen::Matrix4d to_unit = Eigen::Matrix4d::Identity();
    to_unit.topLeftCorner<3, 3>() /= sigma;
    to_unit.topRightCorner<3, 1>() = -center / sigma;
    const Quadric unit = Quadric::from_parameters(unit_parameters);
    result.quadric = Quadric(to_unit.transpose() * unit.matrix() * to_unit);
    result.status = FitStatus::Ok;
    snap_near_cone(points, result, rms);
    evaluate_fit(points, result, options_.type_tolerances, options_.evaluation);
    // With a hint, the fit answers it when either its tolerant reading (preferred: a noisy circular
    // cylinder reads as circular) or the exact type of Q is of the hinted family (a long exact
    // ellipsoid reads as a cylinder under the loose zero tolerance).
    if (result.status == FitStatus::Ok && hint && !same_family(*hint, result.type)) {
      if (same_family(*hint, result.shape.type)) {
        result.type = result.shape.type;
      } else {
        result.status = FitStatus::TypeMismatch;
        result.message = "asked for a " + quadric_type_name(*hint) + ", the algebraic fit is a " +
                         quadric_type_name(result.type) + " (exactly: " + quadric_type_name(result.shape.type) + ")";
      }
    }
    return finish(result);
  }

 private:
  /// Replaces a hyperboloid by its asymptotic cone (same centre, axes and tangents s_a / s_c, s_b / s_c)
  /// under the two tests of TaubinFitterOptions::cone_snap_gap, noting it in the message. `size` is
  /// the points' RMS radius.
  void snap_near_cone(const Eigen::Matrix3Xd& points, QuadricFit& fit, double size) const {
    if (!(options_.cone_snap_residual_ratio > 0.0)) return;
    const QuadricDecomposition shape = fit.quadric.decompose();
    if (shape.type != QuadricType::HyperboloidOneSheet && shape.type != QuadricType::HyperboloidTwoSheets) return;
    const Eigen::Vector3d& s = shape.scale;  // semi-axes; c is the axis of the opposite sign
    const double gap = std::max(s(0) * s(2) / std::hypot(s(0), s(2)), s(1) * s(2) / std::hypot(s(1), s(2)));
    if (!(gap <= options_.cone_snap_gap * size)) return;
    const Quadric cone = Quadric::from_canonical(QuadricType::EllipticCone,
                                                 Eigen::Vector3d(s(0) / s(2), s(1) / s(2), 1.0), shape.pose());
    const ResidualSample sample = residual_sample(
        points.cols(), FitEvaluationOptions{ResidualEvaluation::Subsample, std::max(options_.cone_snap_points, 1)});
    double hyperboloid_sum = 0.0, cone_sum = 0.0;
    for (Eigen::Index i = 0; i < sample.count; ++i) {
      const Eigen::Vector3d x = points.col(i * sample.stride);
      hyperboloid_sum += std::pow(fit.quadric.sampson_distance(x), 2);
      cone_sum += std::pow(cone.sampson_distance(x), 2);
    }
    const double ratio = std::sqrt(cone_sum / hyperboloid_sum);
    if (!(ratio <= options_.cone_snap_residual_ratio)) return;
    fit.quadric = cone;
    char note[200];
    std::snprintf(note, sizeof(note),
                  "%s within %.3g m (%.2g%% of the RMS radius) of its asymptotic cone, whose residual is %.3g times "
                  "its own: read as the cone",
                  quadric_type_name(shape.type).c_str(), gap, 100.0 * gap / size, ratio);
    fit.message = note;
  }

  TaubinFitterOptions options_;
};

}  // namespace

std::unique_ptr<QuadricFitter> make_taubin_fitter(const TaubinFitterOptions& options) {
  return std::make_unique<TaubinFitter>(options);
}

}  // namespace quadrix
