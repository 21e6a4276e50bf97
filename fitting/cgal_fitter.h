// The `cgal` fitter: the element's primitive found by CGAL 5.5 shape detection (Efficient
// RANSAC, Schnabel et al. 2007) restricted to the requested type, its parameters (plane normal and
// offset, sphere centre and radius, cylinder axis and radius, cone apex, axis and half-angle)
// converted to Q = P^-T C P^-1 (paper Eq. (Q=PCP)) with Quadric::from_canonical. Planes are refitted
// to the detected inliers with CGAL's linear least squares; lines and points, which Efficient RANSAC
// does not detect, come from CGAL's least-squares line fit and centroid. Without a hint every shape
// (plane, sphere, cylinder, cone) is searched and the one covering the most points is kept.
// Normals are estimated with CGAL's jet fitting when the caller gives none.
#pragma once

#include "fitting/quadric_fitter.h"

#include <memory>
#include <vector>

namespace quadrix {

/// Options of the CGAL shape-detection fitter (every Efficient_RANSAC parameter is set from these).
struct CgalFitterOptions {
  /// epsilon: largest point-to-shape distance of an inlier, as a fraction of the bounding-box diagonal
  /// (CGAL's documentation example uses 1%).
  double epsilon_fraction = 0.01;
  /// Multipliers of epsilon tried in order until a shape covering minimum_coverage is found: starting
  /// tight picks a precise candidate on clean elements (at 1% every candidate within 1% covers all points
  /// and radii come out 1-3% off), growing lets noisy elements (noise above 1% of their size) still fit.
  std::vector<double> epsilon_multipliers = {0.25, 0.5, 1.0, 2.0, 4.0};
  /// min_points: a shape must cover at least this fraction of the element's points.
  double minimum_coverage = 0.5;
  /// normal_threshold: |cos| of the largest deviation between a point's normal and the shape's normal.
  double normal_threshold = 0.85;
  /// probability: chance of missing the largest candidate shape (CGAL's default 0.01 would cost more draws; 0.05 as in its example).
  double probability = 0.05;
  /// cluster_epsilon as a fraction of the bounding-box diagonal: 1 keeps all inliers in one connected
  /// component (the element is already one object; sparse partial segments must not be split).
  double cluster_epsilon_fraction = 1.0;
  /// Neighbours of CGAL::jet_estimate_normals when no normals are given.
  int normal_neighbours = 18;
  /// Seed of CGAL's default random generator (reset at every fit, so fits are reproducible).
  unsigned seed = 5489u;
  /// How the residual statistics are computed (default: every point).
  FitEvaluationOptions evaluation;
};

/// Types the CGAL fitter can return: point, line, plane, sphere, circular cylinder, circular cone.
std::vector<QuadricType> cgal_fitter_types();

/// The CGAL fitter with explicit options (make_quadric_fitter("cgal") uses the defaults).
std::unique_ptr<QuadricFitter> make_cgal_fitter(const CgalFitterOptions& options = {});

}  // namespace quadrix
