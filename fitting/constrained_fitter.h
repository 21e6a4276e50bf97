// Type-constrained geometric quadric fits (`constrained`): for a requested type, the
// canonical parameters (scale, rotation, centre of paper Eq. (Q=PCP)) that minimise the sum of
// squared TRUE orthogonal point-to-surface distances, solved with Ceres; the quadric is then
// built with Quadric::from_canonical so its type is exact by construction.
//   plane, line  closed-form total least squares (the exact orthogonal-distance minimiser:
//                centroid + smallest/largest covariance eigenvector), computed by the statistical fitter;
//   point        the centroid (the orthogonal-distance minimiser);
//   sphere       residual | ||x - t|| - r |;
//   cylinder     residual | ||(x - p) x d|| - r |, unit axis d on a sphere manifold;
//   cone         residual | rho cos(theta) - |h| sin(theta) | (rho, h: radial and axial coordinates
//                from the apex), the exact distance to the double cone;
//   ellipsoid, elliptic cylinder, elliptic cone  orthogonal distance regression with one latent
//                surface parameter pair per point (the foot point), rotation on a quaternion manifold.
// Initial values: the statistical pose (each principal direction tried as the axis, circle/sphere
// fitted algebraically in it) and, where the Taubin fit returns the same family, Taubin's
// decomposition; each is solved on a deterministic subsample of at most subsample_points points, and
// the solution with the lowest cost is polished on every point.
#pragma once

#include "fitting/quadric_fitter.h"

#include <memory>
#include <vector>

namespace quadrix {

/// Options of the constrained fitter.
struct ConstrainedFitterOptions {
  int max_iterations = 200;              ///< Levenberg-Marquardt iterations per initial value
  double function_tolerance = 1e-15;     ///< Ceres: stop when |d cost| / cost falls below this
  double gradient_tolerance = 1e-16;     ///< Ceres: stop when the projected gradient max-norm falls below this
  double parameter_tolerance = 1e-13;    ///< Ceres: stop when |d x| <= tol * (|x| + tol)
  double robust_loss_scale = 0.0;        ///< Cauchy loss scale in metres on each distance; 0 = plain least squares
  bool use_taubin_initialisation = true; ///< also start from Taubin's fit when it returns the requested family
  FitEvaluationOptions evaluation;       ///< how the residual statistics are computed (default: every point)
  /// Every initial value is solved on an evenly strided subsample of at most this many points; the
  /// best solution is then the start of one solve on every point (see polish_on_all_points).
  int subsample_points = 1500;
  bool polish_on_all_points = true;      ///< refine the subsample's best solution on every point (false: keep it)
  /// With several initial values, each first gets at most this many iterations on the subsample and
  /// only the lowest-cost one is solved to the tolerances above (0: solve every one fully).
  int screening_iterations = 15;
  /// Largest radius / scale (relative to the RMS radius of the points) accepted before the fit is
  /// reported Degenerate (nearly flat points make a cylinder or sphere radius diverge).
  double largest_relative_scale = 1e3;
  /// A circular cylinder is reported Degenerate when the sagitta of the arc its points cover,
  /// r (1 - cos(min(span, pi) / 2)), is below this times their RMS distance to it: a narrow, noisy
  /// strip (a sparse LiDAR pole seen by a few rings) fits any large radius about equally well.
  double minimum_sagitta_ratio = 1.0;
  /// Types tried without a hint; the one with the lowest BIC = n ln(RSS/n) + k ln(n) is returned
  /// (k = the type's degrees of freedom), so a more general type must explain the points clearly better.
  std::vector<QuadricType> automatic_types = {QuadricType::Plane,       QuadricType::Line,
                                              QuadricType::Sphere,      QuadricType::CircularCylinder,
                                              QuadricType::CircularCone, QuadricType::Ellipsoid};
};

/// Types the constrained fitter can fit: point, line, plane, sphere, ellipsoid, circular and elliptic
/// cylinder, circular and elliptic cone (others return FitStatus::Failed naming the type).
std::vector<QuadricType> constrained_fitter_types();

/// Degrees of freedom of a supported type's surface (plane 3, line 4, sphere 4, cylinder 5, cone 6,
/// elliptic cylinder 6, elliptic cone 7, ellipsoid 9, point 3); used by the automatic type choice.
int constrained_type_degrees_of_freedom(QuadricType type);

/// The constrained fitter with explicit options (make_quadric_fitter("constrained") uses the defaults).
std::unique_ptr<QuadricFitter> make_constrained_fitter(const ConstrainedFitterOptions& options = {});

}  // namespace quadrix
