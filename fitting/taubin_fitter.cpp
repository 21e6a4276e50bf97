// Taubin's algebraic fit (G. Taubin, "Estimation of planar curves, surfaces, and nonplanar space
// curves defined by implicit equations", PAMI 1991): minimise sum f(x)^2 / sum ||grad f(x)||^2
// over q, i.e. the generalised eigenproblem M q = mu N q with M = sum m m^T (m = monomials of
// paper Eq. (quadrics equation)) and N = sum_k sum (dm/dx_k)(dm/dx_k)^T; q is the eigenvector of
// the smallest mu. N is singular in the constant term J (it has no gradient), so J is eliminated
// in closed form first (J = -M_J9 q9 / M_JJ) and the reduced 9x9 problem is solved.
#include "fitting/taubin_fitter.h"

#include "fitting/statistical_fitter.h"

#include <Eigen/Eigenvalues>

#include <chrono>
#include <cmath>

namespace quadrix {
namespace {

using Vector10 = Eigen::Matrix<double, 10, 1>;
using Matrix10 = Eigen::Matrix<double, 10, 10>;

/// Monomials m(x) with q . m(x) = f_q(x) for q = [A..J] (paper Eq. (quadrics equation)).
Vector10 monomials(const Eigen::Vector3d& x) {
  Vector10 m;
  m << x.x() * x.x(), x.y() * x.y(), x.z() * x.z(), 2 * x.x() * x.y(), 2 * x.x() * x.z(), 2 * x.y() * x.z(),
      2 * x.x(), 2 * x.y(), 2 * x.z(), 1.0;
  return m;
}

/// Rows d m / d x, d m / d y, d m / d z.
Eigen::Matrix<double, 3, 10> monomial_gradients(const Eigen::Vector3d& x) {
  Eigen::Matrix<double, 3, 10> g = Eigen::Matrix<double, 3, 10>::Zero();
  g(0, 0) = 2 * x.x(); g(0, 3) = 2 * x.y(); g(0, 4) = 2 * x.z(); g(0, 6) = 2;
  g(1, 1) = 2 * x.y(); g(1, 3) = 2 * x.x(); g(1, 5) = 2 * x.z(); g(1, 7) = 2;
  g(2, 2) = 2 * x.z(); g(2, 4) = 2 * x.x(); g(2, 5) = 2 * x.y(); g(2, 8) = 2;
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
      QuadricFit linear = make_statistical_fitter()->fit(points, Eigen::Matrix3Xd(), hint);
      linear.time_ms = 0.0;
      return finish(linear);
    }
    if (points.cols() < 9) {
      result.status = FitStatus::TooFewPoints;
      result.message = "an algebraic quadric fit needs at least 9 points, got " + std::to_string(points.cols());
      return finish(result);
    }
    result.statistics = statistical_pose(points);
    // Normalise to unit space (centroid at the origin, RMS radius sqrt(2)) for conditioning.
    const Eigen::Vector3d center = points.rowwise().mean();
    const double rms = std::sqrt((points.colwise() - center).colwise().squaredNorm().mean());
    if (!(rms > 0.0)) {
      result.status = FitStatus::Degenerate;
      result.message = "all points coincide";
      return finish(result);
    }
    const double sigma = rms / std::sqrt(2.0);
    Matrix10 moments = Matrix10::Zero();
    Matrix10 gradient_moments = Matrix10::Zero();
    for (Eigen::Index i = 0; i < points.cols(); ++i) {
      const Eigen::Vector3d x = (points.col(i) - center) / sigma;
      const Vector10 m = monomials(x);
      moments.selfadjointView<Eigen::Lower>().rankUpdate(m);
      const Eigen::Matrix<double, 3, 10> g = monomial_gradients(x);
      gradient_moments.noalias() += g.transpose() * g;
    }
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
    Vector10 unit_parameters;
    unit_parameters.head<9>() = solver.eigenvectors().col(0);
    unit_parameters(9) = -cross.dot(unit_parameters.head<9>()) / constant_moment;
    // Back to the world: x_u = A x with A = [I/sigma, -c/sigma; 0, 1], so Q = A^T Q_u A.
    Eigen::Matrix4d to_unit = Eigen::Matrix4d::Identity();
    to_unit.topLeftCorner<3, 3>() /= sigma;
    to_unit.topRightCorner<3, 1>() = -center / sigma;
    const Quadric unit = Quadric::from_parameters(unit_parameters);
    result.quadric = Quadric(to_unit.transpose() * unit.matrix() * to_unit);
    result.status = FitStatus::Ok;
    evaluate_fit(points, result, options_.type_tolerances);
    // With a hint, the fit answers it when either the exact type of Q or its tolerant reading is of
    // the hinted family (a long exact ellipsoid reads as a cylinder under the loose zero tolerance).
    if (result.status == FitStatus::Ok && hint) {
      if (same_family(*hint, result.shape.type)) {
        result.type = result.shape.type;
      } else if (!same_family(*hint, result.type)) {
        result.status = FitStatus::TypeMismatch;
        result.message = "asked for a " + quadric_type_name(*hint) + ", the algebraic fit is a " +
                         quadric_type_name(result.type) + " (exactly: " + quadric_type_name(result.shape.type) + ")";
      }
    }
    return finish(result);
  }

 private:
  TaubinFitterOptions options_;
};

}  // namespace

std::unique_ptr<QuadricFitter> make_taubin_fitter(const TaubinFitterOptions& options) {
  return std::make_unique<TaubinFitter>(options);
}

}  // namespace quadrix
