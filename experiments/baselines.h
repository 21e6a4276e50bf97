// Baseline global registration methods run beside Quadrix in the same process on the same pairs
// (`quadrix bench --method ...`): Open3D 0.16 FPFH + RANSAC, Open3D FPFH + FGR, and PCL 1.13
// FPFH + SampleConsensusPrerejective. Open3D lives only in baselines_open3d.cpp and PCL only in
// baselines_pcl.cpp (separate translation units); this header speaks Eigen only.
//
// Every baseline runs the same front end on the cloud it is given (no range crop of its own):
// voxel down-sampling (centroid per voxel), normals from a radius search oriented towards the
// sensor at the origin, FPFH on every down-sampled point, then the library's global estimator.
// Defaults are the common KITTI settings of the FPFH peers (voxel 0.5 m, normal radius 2x voxel,
// FPFH radius 5x voxel; Open3D's global-registration example for RANSAC: mutual filter, edge-length
// 0.9 and distance checkers, 1.5x voxel inlier distance, 100k iterations at 0.999 confidence; FGR
// with Open3D's defaults; PCL's prerejective example: 3 samples, 5 nearest features, polygon
// similarity 0.9, inlier fraction 0.25).
//
// Threads: `threads` (default 1) bounds Open3D's and PCL's OpenMP loops; without it Open3D 0.16
// runs on every physical core. PCL's prerejective RANSAC is single-threaded. For comparison,
// Quadrix's register_clouds runs extraction, modelling and the compatibility graphs on TBB's default
// arena (every core) and the clique search (clique_threads = 1) and refinement on one thread.
#pragma once

#include "geometry/point_cloud.h"

#include <Eigen/Geometry>

#include <cstddef>
#include <map>
#include <string>
#include <vector>

namespace quadrix {

/// Parameters shared by every baseline; defaults are the fair KITTI settings documented in README.
struct BaselineOptions {
  double voxel_size = 0.5;                   ///< voxel down-sampling before features, m (peers on KITTI: 0.3-0.5)
  double normal_radius = 1.0;                ///< normal estimation radius, m (2x voxel)
  int normal_max_neighbours = 30;            ///< Open3D hybrid search cap for normals (its examples: 30); PCL uses the radius only
  double feature_radius = 2.5;               ///< FPFH radius, m (5x voxel)
  int feature_max_neighbours = 100;          ///< Open3D hybrid search cap for FPFH (its examples: 100); PCL uses the radius only
  double max_correspondence_distance = 0.75; ///< inlier distance of RANSAC / prerejective / FGR, m (1.5x voxel)
  bool mutual_filter = true;                 ///< Open3D RANSAC keeps only mutual nearest feature matches (falls back when < 9 remain)
  double edge_length_similarity = 0.9;       ///< Open3D RANSAC edge-length checker and PCL polygon similarity, in [0, 1)
  int ransac_iterations = 100000;            ///< Open3D RANSAC maximum iterations
  double ransac_confidence = 0.999;          ///< Open3D RANSAC confidence for early termination
  int fgr_iterations = 64;                   ///< FGR graduated non-convexity iterations (Open3D default)
  double fgr_tuple_scale = 0.95;             ///< FGR tuple-test similarity (Open3D default)
  int fgr_maximum_tuple_count = 1000;        ///< FGR tuples kept after the tuple test (Open3D default)
  int prerejective_iterations = 50000;       ///< PCL SampleConsensusPrerejective maximum iterations (PCL tutorial)
  int prerejective_samples = 3;              ///< PCL points sampled per hypothesis
  int prerejective_feature_neighbours = 5;   ///< PCL: a sample's match is drawn among this many nearest features
  double prerejective_inlier_fraction = 0.25;///< PCL: hypothesis accepted when this fraction of source points are inliers
  int threads = 1;                           ///< OpenMP threads of Open3D (normals, FPFH, RANSAC) and PCL (normals, FPFH) loops, >= 1
  unsigned seed = 42;                        ///< seed of the sampling baselines (process-global RNGs: not reproducible across concurrent calls)
};

/// What one baseline run returns.
struct BaselineResult {
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();  ///< maps source points into the target frame
  bool solved = false;                  ///< the method returned a transform supported by >= 3 inliers (not whether it is right)
  std::string message;                  ///< why not solved, or a short summary (points, matches, inliers)
  /// Wall times, ms: "downsample", "normals", "features", "registration" (matching + estimation), "total".
  std::map<std::string, double> timings_ms;
  /// CPU time of the calling thread for the whole call, ms: on a loaded machine the fairer cost; equal
  /// to the work done when threads = 1, an undercount when OpenMP workers also ran.
  double cpu_ms = 0.0;
  /// Counts: "source_points" / "target_points" after down-sampling, "inliers" (down-sampled source
  /// points within max_correspondence_distance of a down-sampled target point after the transform).
  std::map<std::string, double> counts;
};

/// Names accepted by run_baseline: "open3d-ransac", "open3d-fgr", "pcl-prerejective".
std::vector<std::string> baseline_method_names();

/// Runs baseline `method` on `source` → `target`. Throws std::invalid_argument on an unknown name
/// (the message lists the known ones) or an invalid option (the message names the field).
/// An empty or too sparse cloud gives solved = false with a message, never an exception.
BaselineResult run_baseline(const std::string& method, const PointCloud& source, const PointCloud& target,
                            const BaselineOptions& options = {});

}  // namespace quadrix
