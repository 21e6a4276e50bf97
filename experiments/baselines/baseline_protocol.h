// The baselines' data without their libraries: the options, the result, the method names and their
// JSON form. `quadrix bench` runs each baseline in its own process (quadrix-baselines) and reads the
// result back through this protocol, so neither `quadrix` nor the benchmark links Open3D.
#pragma once

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

/// Baseline options as a JSON object text (every field, by its member name).
std::string baseline_options_to_json(const BaselineOptions& options);
/// Reads baseline_options_to_json output; unknown or mistyped fields are quadrix::Error naming the field.
BaselineOptions baseline_options_from_json(const std::string& text);

/// A baseline result as a JSON object text (transform as 16 row-major numbers, solved, message, timings, cpu_ms, counts).
std::string baseline_result_to_json(const BaselineResult& result);
/// Reads baseline_result_to_json output; throws quadrix::Error naming the missing or mistyped field.
BaselineResult baseline_result_from_json(const std::string& text);

}  // namespace quadrix
