// QuadricFitter: one interface for every way of fitting a quadric to an element's points
// (paper §"Quadric Fitting"), with a registry by name so experiments can compare them.
#pragma once

#include "geometry/quadric.h"
#include "geometry/quadric_record.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace quadrix {

/// Outcome of a fit.
enum class FitStatus {
  Ok,            ///< a quadric of the returned type was fitted
  TooFewPoints,  ///< fewer points than the type needs (see minimum_points_for_type)
  Degenerate,    ///< the points do not determine the requested shape (e.g. collinear points for a plane)
  TypeMismatch,  ///< an unconstrained fitter found a different type than the hint asked for
  NotConverged,  ///< an iterative fitter stopped before its tolerance
  Failed,        ///< numerical failure (non-finite result)
};

/// Lower-case name of a status ("ok", "too_few_points", ...), stable for JSON.
std::string fit_status_name(FitStatus status);

/// The types a fit can be asked for. `std::nullopt` (auto) lets the fitter choose.
using FitTypeHint = std::optional<QuadricType>;

/// Parses the --type option: auto, point, line, plane, sphere, ellipsoid, cylinder (circular),
/// elliptic_cylinder, cone (circular), elliptic_cone; throws quadrix::Error otherwise.
FitTypeHint fit_type_hint_from_name(const std::string& name);

/// Minimum number of points a type needs to be fitted (point 1, line 2, plane 3, sphere 4, others 9).
std::size_t minimum_points_for_type(QuadricType type);

/// How evaluate_fit computes a fit's residual statistics (residual_rms, residual_max, algebraic_distance).
/// Exact orthogonal distances cost far more than most fits (an ellipsoid's distance is iterative), so
/// callers that do not read the statistics choose a cheaper mode.
enum class ResidualEvaluation {
  Exact,      ///< every point (the default; what `quadrix fit` prints)
  Subsample,  ///< an evenly strided deterministic subsample of at most FitEvaluationOptions::max_points points
  Skip,       ///< none: the three statistics are NaN (for callers that only use the quadric, e.g. scene modelling)
};

/// Lower-case name of a residual evaluation ("exact", "subsample", "skip"), stable for JSON and CSV.
std::string residual_evaluation_name(ResidualEvaluation evaluation);

/// Parses a residual evaluation name (exact, subsample, skip); throws quadrix::Error naming `field` otherwise.
ResidualEvaluation residual_evaluation_from_name(const std::string& name, const std::string& field = "--residuals");

/// How a fitter evaluates its result (every fitter's options carry one; make_quadric_fitter takes one).
struct FitEvaluationOptions {
  ResidualEvaluation residuals = ResidualEvaluation::Exact;  ///< which points the residual statistics use
  int max_points = 2000;  ///< Subsample: at most this many points, every ceil(N / max_points)-th one (>= 1)
};

/// The columns a residual evaluation visits: every `stride`-th point from column 0, `count` of them
/// (count 0 for Skip or no points).
struct ResidualSample {
  Eigen::Index stride = 1;  ///< step between visited columns
  Eigen::Index count = 0;   ///< visited columns
};

/// The deterministic residual sample of `point_count` points under `evaluation`; throws quadrix::Error
/// when Subsample has max_points < 1.
ResidualSample residual_sample(Eigen::Index point_count, const FitEvaluationOptions& evaluation);

/// Everything a fitter returns.
struct QuadricFit {
  FitStatus status = FitStatus::Failed;             ///< outcome
  QuadricType type = QuadricType::Invalid;          ///< type the fitter assigns (may use looser tolerances than shape)
  Quadric quadric;                                  ///< Q (not normalised; decompose() normalises)
  QuadricDecomposition shape;                       ///< exact decomposition of Q: scale, rotation, centre, indicators
  StatisticalPose statistics;                       ///< t_s, R_s, s_s of the points (paper's statistical fit)
  double residual_rms = 0.0;                        ///< RMS orthogonal point-to-surface distance, metres
  double residual_max = 0.0;                        ///< largest orthogonal distance, metres
  double algebraic_distance = 0.0;                  ///< f_p2s of paper Eq. (f_p2s) in unit space (see unit_space_algebraic_distance)
  double time_ms = 0.0;                             ///< wall time of the fit, residual evaluation included
  ResidualEvaluation residual_evaluation = ResidualEvaluation::Exact;  ///< how the residual statistics were computed
  Eigen::Index residual_points = 0;                 ///< points the residual statistics were computed on (0: skipped)
  double evaluation_ms = 0.0;                       ///< part of time_ms spent in evaluate_fit (type reading and residuals)
  std::string message;                              ///< human-readable detail for non-ok statuses
};

/// A way of fitting quadrics. Implementations are stateless and thread-safe.
class QuadricFitter {
 public:
  virtual ~QuadricFitter() = default;
  /// Registry name ("statistical", "taubin", ...).
  virtual std::string name() const = 0;
  /// Fits `points` (3 x N, metres; `normals` 3 x N unit vectors or empty) with an optional type hint.
  virtual QuadricFit fit(const Eigen::Matrix3Xd& points, const Eigen::Matrix3Xd& normals, FitTypeHint type) const = 0;
};

/// Creates a fitter by registry name; throws quadrix::Error listing the valid names otherwise.
std::unique_ptr<QuadricFitter> make_quadric_fitter(const std::string& name);
/// Creates a fitter by registry name with its default options except the residual evaluation
/// (e.g. FitEvaluationOptions{ResidualEvaluation::Skip} for scene modelling).
std::unique_ptr<QuadricFitter> make_quadric_fitter(const std::string& name, const FitEvaluationOptions& evaluation);
/// Names of every registered fitter.
std::vector<std::string> quadric_fitter_names();

/// f_p2s of paper Eq. (f_p2s): points and Q mapped to unit space (centred on the points' mean,
/// scaled so the RMS radius is 1), then the mean first-order distance |f(x)| / ||grad f(x)||
/// (the paper's |x^T Q x| / |grad(Q) x| read with a norm in the denominator, after Taubin 1991).
double unit_space_algebraic_distance(const Eigen::Matrix3Xd& points, const Quadric& quadric);
/// The same f_p2s over the columns of `sample` only (their mean and RMS radius define the unit space).
double unit_space_algebraic_distance(const Eigen::Matrix3Xd& points, const Quadric& quadric, const ResidualSample& sample);

/// t_s, R_s and s_s of the points exactly as statistical_pose (geometry/quadric_record.h) defines them
/// (mean, descending covariance eigenvectors with its sign rule, k_s sigma), computed in two passes
/// without copying the points; also returns the covariance (1/n sum of centred outer products).
StatisticalPose point_statistics(const Eigen::Matrix3Xd& points, double scale_factor = kStatisticalScaleFactor,
                                 Eigen::Matrix3d* covariance = nullptr);

/// Fills shape (exact decomposition of Q), type (Q classified with `type_tolerances`),
/// residual_rms / residual_max (orthogonal distances to the exact shape) and algebraic_distance of
/// `fit` over the points `evaluation` selects (NaN when it skips them), and residual_evaluation,
/// residual_points and evaluation_ms, so every fitter reports the same numbers (statistics are the
/// fitter's to fill).
void evaluate_fit(const Eigen::Matrix3Xd& points, QuadricFit& fit, const DecompositionTolerances& type_tolerances = {},
                  const FitEvaluationOptions& evaluation = {});

}  // namespace quadrix
