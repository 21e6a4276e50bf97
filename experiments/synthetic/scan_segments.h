// Segments cut from simulated scans, with the true primitive of each: what a quadric fitter sees in
// practice (paper §"Quadric Fitting": segments are fragmented, unevenly sampled and noisy). Used to
// train the learned fitter (`quadrix fitter-segments` writes them for
// fitting/training/train_learned_fitter.py), as the held-apart set of the fitter study and as the
// accuracy test of the learned fitter.
//
// Each scan puts one sensor (hdl64, vlp16, livox, tls) at a random place of a synthetic scene
// (street with a new layout per seed, corridor, monument); the points of every primitive hit are one
// segment, so a segment is what the sensor saw of it: one side of a pole, a band of a column, a
// patch of a dome, sampled along scan rings. Planes are cut to a disc-shaped patch; points of
// neighbouring primitives within a random distance leak in; extra segments are half-space crops of
// the visible part. Scenes hold few cones and spheres (traffic cones, bollards, one dome), so
// "object scans" add them: one object of random size and pose on a ground plane, often with a wall
// behind it, at a log-uniform range, seen by the same sensors and cut the same way.
#pragma once

#include "geometry/quadric.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <string>
#include <vector>

namespace quadrix {

/// How scan segments are generated. The same options give the same segments on every machine.
struct ScanSegmentOptions {
  std::uint64_t seed = 1;                                            ///< scenes (street layout), sensor places, noise draws
  int scans = 12;                                                    ///< simulated scans of scenes; scan k uses scene, sensor = k-th of the lists (cyclic)
  int object_scans = 12;                                             ///< then scans of one random object on the ground (types in turn, see below)
  std::vector<std::string> scenes = {"street", "street", "corridor", "street", "monument"};  ///< cycled per scan (the street twice as often: most types live there)
  std::vector<std::string> sensors = {"hdl64", "vlp16", "livox", "tls"};  ///< cycled per scan, offset from the scenes
  std::vector<QuadricType> types = {QuadricType::Plane, QuadricType::Line, QuadricType::Sphere,
                                    QuadricType::CircularCylinder, QuadricType::CircularCone,
                                    QuadricType::Ellipsoid};         ///< true types kept (poles count as lines and as cylinders)
  double min_range = 2.0;                                            ///< segment centroids nearer than this to the sensor are dropped, metres
  double max_range = 80.0;                                           ///< and farther than this
  int min_points = 15;                                               ///< segments (and crops) with fewer own points are dropped
  int max_points = 2000;                                             ///< larger segments are thinned by an even stride in scan order
  double max_leak_distance = 0.3;                                    ///< points of other primitives within d ~ U(0, this) of the segment join it, metres
  int crops_per_segment = 1;                                         ///< extra half-space crops of each segment (kept when 20-90% of its points remain)
  double max_noise = 0.05;                                           ///< half the scans draw the range noise sigma in [0, this]; the others keep the sensor's
  double plane_patch_min_radius = 2.0;                               ///< planes: a disc patch of radius in [min, max] around a random point, metres
  double plane_patch_max_radius = 12.0;                              ///< see plane_patch_min_radius
};

/// One segment with its truth, in the SENSOR frame of its scan.
struct ScanSegment {
  QuadricType type = QuadricType::Invalid;                 ///< true type (a pole: Line, or CircularCylinder for its surface)
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();         ///< true canonical scale (radii; cones: tan, tan, 1; plane/line: 1)
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  ///< true canonical frame -> sensor frame
  Eigen::Matrix3Xd points;                                 ///< the segment in scan order, leaked points included, metres
  Eigen::Matrix3Xd full_surface;                           ///< up to 300 noise-free samples of the whole bounded true surface
  int leaked_points = 0;                                   ///< points of other primitives in `points`
  double visible_fraction = 1.0;                           ///< share of the surface seen (see scan_segment_visible_fraction)
  double noise = 0.0;                                      ///< range noise sigma of the scan, metres
  double range = 0.0;                                      ///< distance of the segment's centroid from the sensor, metres
  bool crop = false;                                       ///< a half-space crop of another segment
  std::string scene;                                       ///< scene name
  std::string sensor;                                      ///< sensor preset
  std::string label;                                       ///< semantic label name of the primitive
  int scan = 0;                                            ///< index of the scan it came from
};

/// Share of a surface covered by points given in its canonical frame (own points only): cylinders,
/// cones and lines 1 - (largest empty angular gap around the axis) / 2 pi; spheres and ellipsoids the
/// area of the spherical cap (in the unit-sphere frame x / scale) around the mean direction that
/// holds 95% of the points; planes the bounding rectangle of the points over the extent's rectangle.
double scan_segment_visible_fraction(QuadricType type, const Eigen::Vector3d& scale, const Eigen::Matrix3Xd& local_points,
                                     const Eigen::Vector3d& extent_size);

/// Simulates the scans and cuts the segments (in scan order, then primitive id). Throws
/// quadrix::Error for an unknown scene or sensor or a non-positive count.
std::vector<ScanSegment> make_scan_segments(const ScanSegmentOptions& options);

/// Writes segments for the training script as float32/float64 .npy files in `directory` (created):
///   points.npy   (P, 3) float32, every segment's points in order;
///   segments.npy (K, 27) float64 per segment: offset, count, type (QuadricType value), scale (3),
///                rotation (9, row-major), translation (3), visible fraction, noise, range, leaked
///                points, crop (0/1), scan, scene index (into options.scenes; its size for an object
///                scan), sensor index, label id;
///   plus segments.json naming the columns, types, scenes and sensors.
void write_scan_segments(const std::string& directory, const std::vector<ScanSegment>& segments,
                         const ScanSegmentOptions& options);

}  // namespace quadrix
