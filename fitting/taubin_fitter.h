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
};

/// The Taubin fitter with explicit options (make_quadric_fitter("taubin") uses the defaults).
std::unique_ptr<QuadricFitter> make_taubin_fitter(const TaubinFitterOptions& options = {});

}  // namespace quadrix
