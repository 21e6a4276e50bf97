// Mapping baselines on a scan list (SCANS.tsv: session, scan, odometry), each writing the map
// folder format of `quadrix map` (poses.tsv, edges.csv, report.json) so its evaluation reads them:
//   odometry   the given odometry alone (each session in its own frame);
//   icp-loops  LIO-SAM's loop closure: for each scan the nearest older scan (more than min_age scans
//              back) within `radius` metres of its odometry position, Open3D point-to-plane ICP from
//              the odometry's relative pose, accepted when its fitness and RMSE pass the gate, then
//              Open3D's pose graph (Levenberg-Marquardt) over odometry and accepted loop edges;
//   multiway   Open3D's multiway registration: ICP edges between every pair of scans within `radius`
//              (more than min_age apart), all as uncertain edges, optimised with Open3D's global
//              optimisation whose line process prunes the edges it does not trust.
// All three keep the given odometry as the odometry edges, so they differ only in their loop edges;
// a loop ICP that finds no correspondence near the odometry's guess is `failed` and left out.
// None of them can join sessions: ICP needs an initial guess and sessions share no frame, so each
// session keeps its own frame (report.json lists it under sessions_not_joined).
#pragma once

#include <Eigen/Geometry>

#include <map>
#include <string>
#include <vector>

namespace quadrix {

/// Options of the mapping baselines.
struct MapBaselineOptions {
  double radius = 15.0;          ///< loop candidate search radius around the odometry position, m (LIO-SAM's default)
  int min_age = 50;              ///< a candidate is more than this many scans older (LIO-SAM: 30 s of driving)
  double voxel_size = 0.5;       ///< ICP down-sampling, m
  double icp_distance = 1.5;     ///< ICP maximum correspondence distance, m
  int icp_iterations = 50;       ///< ICP iterations
  double min_fitness = 0.5;      ///< icp-loops gate: least fraction of source points with a correspondence
  double max_rmse = 0.55;        ///< icp-loops gate: largest RMSE of those correspondences, m (LIO-SAM's fitness-score gate, 0.3 m^2, as an RMSE)
  double edge_prune_threshold = 0.25;  ///< multiway: line-process weight below which an edge is pruned (Open3D's default)
  int threads = 2;               ///< OpenMP threads of Open3D
};

/// What a baseline run measured.
struct MapBaselineSummary {
  std::string method;                      ///< odometry, icp-loops or multiway
  int scans = 0;                           ///< scans in the list
  int loop_candidates = 0;                 ///< pairs registered as loop candidates
  int loop_edges_used = 0;                 ///< loop edges the pose graph kept
  double seconds = 0.0;                    ///< wall-clock time of the whole run
  std::map<std::string, double> ate;       ///< with truth: "session <name>" (each aligned alone) and "map" (session 1's frame, one alignment)
  int wrong_used_edges = -1;               ///< with truth: used loop edges more than 2 m or 5 degrees off (-1 without truth)
};

/// Names of the methods: odometry, icp-loops, multiway.
std::vector<std::string> map_baseline_methods();

/// Runs `method` on the scan list and writes OUT/poses.tsv, OUT/edges.csv and OUT/report.json;
/// with a truth file (poses.tsv format) also the ATE and the wrong used edges. Throws quadrix::Error
/// for an unknown method, a bad list or a session without odometry.
MapBaselineSummary run_map_baseline(const std::string& method, const std::string& scan_list, const std::string& out,
                                    const std::string& truth, const MapBaselineOptions& options);

}  // namespace quadrix
