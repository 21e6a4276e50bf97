// The paper's statistics-based quadric fit (§"Quadric Fitting": centralisation, eigenvalue
// decomposition, s_s = k_s * sigma_s, C_e = S^-T I_C S^-1, Q = P_s^-T C_e P_s^-1).
#pragma once

#include "fitting/quadric_fitter.h"

#include <memory>

namespace quadrix {

/// Options of the statistical fitter.
struct StatisticalFitterOptions {
  double scale_factor = kStatisticalScaleFactor;  ///< k_s: 1.645 covers 90% of a Gaussian (paper)
  double minimum_relative_scale = 1e-6;           ///< scales below this * largest scale are clamped to it (flat/thin elements)
  QuadricType automatic_type = QuadricType::Ellipsoid;  ///< type used without a hint (paper: geometry-only clusters -> ellipsoid)
  FitEvaluationOptions evaluation;                      ///< how the residual statistics are computed (default: every point)
};

/// The statistical fitter with explicit options (make_quadric_fitter("statistical") uses the defaults).
std::unique_ptr<QuadricFitter> make_statistical_fitter(const StatisticalFitterOptions& options = {});

}  // namespace quadrix
