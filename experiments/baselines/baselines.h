// Baseline global registration methods run beside Quadrix on the same pairs (`quadrix bench
// --method ...`, through the quadrix-baselines executable): Open3D 0.16 FPFH + RANSAC, Open3D FPFH + FGR, and PCL 1.13
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

#include "experiments/baselines/baseline_protocol.h"
#include "geometry/point_cloud.h"

#include <Eigen/Geometry>

#include <cstddef>
#include <map>
#include <string>
#include <vector>

namespace quadrix {

/// Runs baseline `method` on `source` → `target`. Throws std::invalid_argument on an unknown name
/// (the message lists the known ones) or an invalid option (the message names the field).
/// An empty or too sparse cloud gives solved = false with a message, never an exception.
BaselineResult run_baseline(const std::string& method, const PointCloud& source, const PointCloud& target,
                            const BaselineOptions& options = {});

}  // namespace quadrix
