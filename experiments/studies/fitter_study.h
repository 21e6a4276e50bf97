// The fitter study (`quadrix compare-fitters`): every registered QuadricFitter on synthetic
// segments of known type, scale and pose (type x noise x visible fraction x outliers x trials, fixed
// seeds) and on real segments cropped from ../shared/data, measured by type accuracy, scale, axis and
// centre error, point-to-surface residual and time per fit (paper §"Quadric Fitting"). Writes a CSV
// with one row per fit, a Markdown summary and an SVG plot.
#pragma once

#include "fitting/quadric_fitter.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace quadrix {

/// One synthetic element: points sampled on a known canonical surface, then partial, noisy, polluted.
struct SyntheticSegment {
  QuadricType type = QuadricType::Invalid;                 ///< true type
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();         ///< true canonical scale (cones: tangents; plane/line: extents)
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  ///< true pose P_q (canonical -> world)
  Eigen::Matrix3Xd points;                                 ///< the segment as a fitter sees it, metres
  Eigen::Matrix3Xd full_surface;                           ///< noise-free samples of the whole generating surface (for completion error)
  int outlier_count = 0;                                   ///< how many of `points` are uniform outliers (the first ones)
};

/// How a synthetic segment is generated.
struct SyntheticSegmentSpec {
  QuadricType type = QuadricType::Sphere;  ///< plane, line, sphere, ellipsoid, circular/elliptic cylinder, circular cone
  double noise = 0.0;                      ///< standard deviation of isotropic Gaussian noise per coordinate, metres
  double visible_fraction = 1.0;           ///< part of the surface observed: angular sector (cylinders, cones),
                                           ///< spherical cap (sphere, ellipsoid), sub-extent (plane, line)
  double outlier_fraction = 0.0;           ///< fraction of points replaced by uniform points in the segment's enlarged bounding box
  int points = 400;                        ///< points in the segment
  std::uint64_t seed = 1;                  ///< random seed (scale, pose, samples, noise, outliers)
};

/// Types the synthetic generator can produce.
std::vector<QuadricType> synthetic_segment_types();

/// Generates one synthetic segment; throws quadrix::Error for an unsupported type, a fraction outside
/// its range (visible in (0, 1], outliers in [0, 1)), negative noise or fewer than 1 point.
SyntheticSegment make_synthetic_segment(const SyntheticSegmentSpec& spec);

/// Options of the study (the defaults are the committed report's configuration).
struct FitterStudyOptions {
  std::vector<QuadricType> types = {QuadricType::Plane, QuadricType::Line, QuadricType::Sphere, QuadricType::Ellipsoid,
                                    QuadricType::CircularCylinder, QuadricType::EllipticCylinder,
                                    QuadricType::CircularCone};          ///< synthetic types
  std::vector<double> noise_levels = {0.0, 0.01, 0.02, 0.05};            ///< Gaussian sigma, metres (0/1/2/5 cm)
  std::vector<double> visible_fractions = {0.1, 0.25, 0.5, 1.0};         ///< observed part of the surface (10/25/50/100%)
  std::vector<double> outlier_fractions = {0.0, 0.1, 0.3};               ///< outlier share (0/10/30%)
  std::vector<std::string> fitters;                                      ///< registry names; empty = quadric_fitter_names()
  int trials = 1;                                                        ///< segments per grid cell (seeds differ per trial); 1 keeps the default run near 3 minutes on 2 cores
  int points_per_segment = 400;                                          ///< points in each synthetic segment
  std::uint64_t seed = 20240605;                                         ///< base seed; each segment's seed derives from it and its cell
  bool automatic_type = true;                                            ///< also fit every segment without a hint (type accuracy)
  bool real_data = true;                                                 ///< also fit the real segments when the data folder exists
  std::string data_root = "../shared/data";                              ///< folder of the real data
  int threads = 2;                                                       ///< worker threads (fits run concurrently: times include contention)
  int real_segment_max_points = 5000;                                    ///< real segments are thinned to at most this many points (every k-th)
  int kitti_facades = 3;                                                 ///< largest KITTI plane elements fitted as planes
  int kitti_poles = 4;                                                   ///< largest KITTI line elements (poles, trunks) fitted as cylinders and lines
  bool scan_segments = true;                                             ///< also fit held-apart segments cut from simulated scans (experiments/synthetic/scan_segments.h)
  std::uint64_t scan_seed = 7;                                           ///< their seed (the learned fitter is trained on seed 101: disjoint scenes, objects and noise)
  int scan_scene_scans = 40;                                             ///< scene scans of the held-apart set
  int scan_object_scans = 300;                                           ///< object scans of the held-apart set
  int scan_segments_per_type = 150;                                      ///< at most this many held-apart segments per type (an even stride through them)
  int scan_segment_max_points = 1000;                                    ///< held-apart segments are thinned to at most this many points
};

/// One fit in the study.
struct FitterStudyRow {
  std::string source;                                 ///< "synthetic", "scan" (held-apart scan segment) or the real segment's name
  std::string fitter;                                 ///< registry name
  std::string mode;                                   ///< "hint" (type given) or "auto" (no hint)
  QuadricType true_type = QuadricType::Invalid;       ///< generating type (real data: the type asked for)
  double noise = 0.0;                                 ///< metres (synthetic; scan segments: the scan's range noise sigma)
  double visible_fraction = 1.0;                      ///< synthetic (scan segments: measured, scan_segment_visible_fraction)
  double outlier_fraction = 0.0;                      ///< synthetic (scan segments: share of leaked neighbour points)
  int trial = 0;                                      ///< synthetic trial index; scan segments: index in the held-apart set
  int points = 0;                                     ///< points fitted
  FitStatus status = FitStatus::Failed;               ///< fitter's status
  QuadricType fitted_type = QuadricType::Invalid;     ///< type of the returned quadric
  bool type_correct = false;                          ///< status ok/not_converged and fitted_type == true_type
  double scale_error = 0.0;                           ///< max relative error of the defined scales (NaN: none defined / wrong family / real data)
  double axis_error_deg = 0.0;                        ///< angle of the defining axis (plane normal, line/cylinder/cone axis; ellipsoid: worst axis), degrees; real segments: deviation from the physical reference (RealSegment::reference_axis)
  double centre_error = 0.0;                          ///< metres: centre distance (central types), distance from the true axis (line, cylinders), offset along the normal (plane)
  double residual_rms = 0.0;                          ///< RMS orthogonal distance of the fitted points (outliers included), metres
  double surface_rms = 0.0;                           ///< RMS distance of the noise-free WHOLE true surface to the fit (completion error), metres
  Eigen::Vector3d fitted_scale = Eigen::Vector3d::Zero();  ///< decomposition scale of the fit
  double time_ms = 0.0;                               ///< the fitter's own time per fit
};

/// All fits of a study.
struct FitterStudyResult {
  std::vector<FitterStudyRow> rows;          ///< one per fit, in grid order
  std::vector<std::string> fitters;          ///< fitters run
  std::vector<std::string> real_notes;       ///< how each real segment was cut, or why it was skipped
  double seconds = 0.0;                      ///< wall time of the whole study
};

/// Progress callback: fits done, fits in total.
using StudyProgress = std::function<void(std::size_t done, std::size_t total)>;

/// Runs the study; throws quadrix::Error for an unknown fitter name or invalid grid values.
FitterStudyResult run_fitter_study(const FitterStudyOptions& options, const StudyProgress& progress = {});

/// A real segment cut from ../shared/data.
struct RealSegment {
  std::string name;                           ///< e.g. "table_plane"
  QuadricType type = QuadricType::Invalid;    ///< type it is fitted as
  Eigen::Matrix3Xd points;                    ///< its points, metres
  std::string how;                            ///< how it was cut (documented in the report)
  Eigen::Vector3d reference_axis = Eigen::Vector3d::Zero();  ///< direction the fitted axis should have (zero: none): vertical for poles, the table normal for the mug
  bool reference_is_perpendicular = false;    ///< true: the axis should be perpendicular to reference_axis (facade normals are horizontal)
};

/// The real segments: the table scene's table plane and mug (as a cylinder), the lamppost's pole (as
/// a cylinder and as a line). Missing files are skipped and named in `notes`.
std::vector<RealSegment> real_fitter_segments(const std::string& data_root, int max_points, std::vector<std::string>& notes);

/// Real KITTI segments cut by the project's own extraction (extract_elements, preset vlp64, geometry-only
/// classes) from kitti00/velodyne/000000.bin: the `facades` largest Plane elements fitted as planes and the
/// `poles` largest Line elements (poles and tree trunks: the data has no labels to tell them apart)
/// fitted as circular cylinders and as lines. A missing file is skipped and named in `notes`.
std::vector<RealSegment> kitti_fitter_segments(const std::string& data_root, int max_points, int facades, int poles,
                                               std::vector<std::string>& notes);

/// Writes one CSV row per fit (header first), atomically.
void write_fitter_study_csv(const std::string& path, const FitterStudyResult& result);
/// Writes the Markdown summary (tables per fitter x type / noise / visible fraction / outliers, real
/// segments, the command that produced it), atomically.
void write_fitter_study_markdown(const std::string& path, const FitterStudyResult& result,
                                 const FitterStudyOptions& options, const std::string& command_line);
/// Writes an SVG with median scale error against noise and against visible fraction per fitter, atomically.
void write_fitter_study_svg(const std::string& path, const FitterStudyResult& result);

}  // namespace quadrix
