// A simulated drive through a town, the benchmark of multi-scan mapping: a grid of 2 x 2 blocks
// whose 12 streets are street scenes (make_street_scene, level roads, end facades removed) joined
// by open intersections, one closed tour of 22 legs over them (3.8 km, every street driven, most
// both ways, no U-turn), and several sessions, each with its own sensor, driving part of the tour
// from its own start (odd sessions forward, even ones backwards) with its own drifting odometry.
// Parked cars and pedestrians of a street are re-drawn after every visit (make_street_pass), so a
// revisit sees other dynamic objects. Output (write_town_drive): scans/, SCANS.tsv (odometry),
// truth.tsv (poses in the map frame = the first session's odometry frame) and README.md.
#pragma once

#include "experiments/synthetic/scanner_simulator.h"
#include "experiments/synthetic/synthetic_scene.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace quadrix {

/// Odometry error model: per step of length d metres the measured relative motion is the true one
/// with its translation scaled by (1 + scale_error) plus Gaussian noise of sigma
/// translation_walk * sqrt(d) per axis, then rotated by a yaw of yaw_bias * d plus noise of sigma
/// yaw_walk * sqrt(d) and by roll / pitch noise of sigma tilt_walk * sqrt(d). The errors
/// accumulate along the chain (a random walk plus a bias). Each session draws the signs of its
/// scale error and yaw bias from the seed. All zero: the odometry equals the true relative motion.
/// The defaults leave 2.8-6.1 m of odometry ATE after 1.2 km (seeds 1001-1003, 2001-2002, every
/// session), the drift a loop closure has to remove.
struct DriftModel {
  double scale_error = 0.01;              ///< odometry scale error, fraction (0.01 = 1 % too long or short)
  double yaw_bias_deg_per_m = 0.005;      ///< heading bias, degrees per metre travelled
  double yaw_walk_deg_per_sqrt_m = 0.02;  ///< heading random walk, degrees per sqrt(metre)
  double tilt_walk_deg_per_sqrt_m = 0.002;  ///< roll and pitch random walk, degrees per sqrt(metre)
  double translation_walk_m_per_sqrt_m = 0.002;  ///< position random walk, metres per sqrt(metre)
};

/// Options of plan_town_drive and write_town_drive.
struct TownDriveOptions {
  std::uint64_t seed = 1001;                 ///< town layout (street seeds), routes' jitter, drift signs, scan noise
  std::vector<SensorModel> sensors{sensor_preset("hdl64"), sensor_preset("vlp16"), sensor_preset("livox")};  ///< one session per sensor, in order
  double length = 1200.0;                    ///< metres driven per session (ignored when scans is set)
  std::optional<int> scans;                  ///< scans per session instead of a length
  double scan_spacing = 2.0;                 ///< metres between consecutive scans of a session
  DriftModel drift;                          ///< odometry error model
  Foliage foliage = Foliage::Solid;          ///< street vegetation
};

/// One scan of the drive.
struct TownDriveScan {
  int session = 1;                           ///< 1-based session
  int index = 0;                             ///< 0-based scan index within the session
  std::string file;                          ///< cloud path relative to the drive folder (scans/s<session>_<index>.ply)
  Eigen::Isometry3d world = Eigen::Isometry3d::Identity();     ///< true sensor -> town frame
  Eigen::Isometry3d truth = Eigen::Isometry3d::Identity();     ///< true sensor -> map frame (session 1's first pose = identity)
  Eigen::Isometry3d odometry = Eigen::Isometry3d::Identity();  ///< drifted sensor -> this session's odometry frame (first scan = identity)
  int street = 0;                            ///< street (grid edge) the scan was taken on or next to
  int leg = 0;                               ///< global leg (visit of a street) over all sessions, in time order
  int street_visit = 1;                      ///< how many visits of this street before this one, plus 1 (make_street_pass's pass)
};

/// The poses of a drive, before any scan is simulated.
struct TownDrivePlan {
  std::vector<TownDriveScan> scans;          ///< every scan, session by session, in time order
  std::vector<int> leg_streets;              ///< street of each global leg
  double tour_length = 0.0;                  ///< metres of the closed tour (centreline)
  std::vector<double> session_lengths;       ///< metres driven by each session (lane path)
};

/// Plans the drive: routes, true poses, drifted odometry (no ray casting). Deterministic per
/// options. Throws quadrix::Error on bad options (no sensor, spacing or length not positive, fewer
/// than 2 scans in a session, a negative drift parameter).
TownDrivePlan plan_town_drive(const TownDriveOptions& options);

/// The town as seen during global leg `leg` of `plan`: static streets, intersections and the closing
/// walls, with every street's parked cars and pedestrians of its current visit.
Scene town_scene(const TownDriveOptions& options, const TownDrivePlan& plan, int leg);

/// Summary of a written drive.
struct TownDriveSummary {
  TownDrivePlan plan;                        ///< what was driven
  std::vector<double> odometry_ate;          ///< per session: RMSE of odometry positions against the truth after one SE(3) alignment, m
  std::vector<double> odometry_end_error;    ///< per session: position error of the last odometry pose (first pose aligned), m
  int same_direction_revisits = 0;           ///< scan pairs of different visits < 10 m apart, heading within 45 degrees
  int opposite_direction_revisits = 0;       ///< the same, heading more than 135 degrees apart
  std::size_t points = 0;                    ///< points written over all scans
};

/// Simulates every scan and writes DIR/scans/s<k>_<NNNN>.ply (binary, sensor frame, semantic labels),
/// DIR/SCANS.tsv (session, scan, odometry: 12 numbers), DIR/truth.tsv (session, scan, t00..t23: the
/// true pose in the map frame) and DIR/README.md. Text files are written atomically.
TownDriveSummary write_town_drive(const std::string& directory, const TownDriveOptions& options);

/// Counts revisits of a plan: pairs of scans on different legs at most `radius` metres apart,
/// split by heading difference (< 45 degrees: same direction, > 135 degrees: opposite).
std::pair<int, int> count_revisits(const TownDrivePlan& plan, double radius = 10.0);

/// RMSE of the positions of `estimate` against `truth` after the SE(3) alignment minimising it
/// (Umeyama without scale, as evo_ape --align). Both lists have the same length (>= 3).
double aligned_position_rmse(const std::vector<Eigen::Isometry3d>& estimate, const std::vector<Eigen::Isometry3d>& truth);

}  // namespace quadrix
