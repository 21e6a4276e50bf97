// Taubin's algebraic quadric fit (Taubin 1991): minimise sum f^2 / sum ||grad f||^2 over the 10
// parameters as a generalised eigenproblem, on points normalised to unit space. Asked for a point,
// line or plane it returns the total-least-squares fit (Taubin's estimator for degree-1 surfaces).
#pragma once

#include "fitting/quadric_fitter.h"

#include <memory>

namespace quadrix {

/// Options of the Taubin fitter.
struct TaubinFitterOptions {
  /// Tolerances used to read the type off the fitted Q. Looser than the exact-geometry defaults
  /// because an algebraic fit to noisy points never has exactly zero or exactly equal eigenvalues:
  /// an eigenvalue below 1% of the largest counts as zero, two within 5% count as equal.
  DecompositionTolerances type_tolerances{1e-2, 5e-2, 1e-2};
  FitEvaluationOptions evaluation;  ///< how the residual statistics are computed (default: every point)
  /// Noise opens a small waist (one sheet) or apex gap (two sheets) in the algebraic fit of a cone,
  /// which the exact type reading calls a hyperboloid however close it is. Such a hyperboloid is
  /// replaced by its asymptotic cone when (1) its largest distance to that cone, max over k = a, b of
  /// s_k s_c / sqrt(s_k^2 + s_c^2) (at the waist or vertex), is at most cone_snap_gap times the points'
  /// RMS radius, and (2) the cone's RMS first-order (Sampson) residual is at most
  /// cone_snap_residual_ratio times the hyperboloid's on cone_snap_points evenly strided points, i.e.
  /// the points do not see the waist.
  double cone_snap_gap = 0.1;
  double cone_snap_residual_ratio = 1.1;  ///< (2) above; 0 disables the snap
  int cone_snap_points = 1000;            ///< (2) above: points compared, evenly strided
};

/// The Taubin fitter with explicit options (make_quadric_fitter("taubin") uses the defaults).
std::unique_ptr<QuadricFitter> make_taubin_fitter(const TaubinFitterOptions& options = {});

}  // namespace quadrix
