// Scan lists (SCANS.tsv, the KITTI odometry layout) and pose tables (poses.tsv): what a mapping run
// reads and writes about many scans, parsed with checks that name the row of bad input. Read by
// `quadrix map` (estimation/mapping.h) and the mapping baselines alike, so both accept the same lists.
#pragma once

#include <Eigen/Geometry>

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace quadrix {

/// One scan of a scan list.
struct ScanEntry {
  std::string session;                         ///< session name (scans of one session share an odometry frame)
  std::string scan;                            ///< the cloud file as written in the list
  std::string path;                            ///< the cloud file resolved against the list's folder
  std::size_t row = 0;                         ///< 1-based line of the list (or frame index of a KITTI layout)
  std::optional<Eigen::Isometry3d> odometry;   ///< sensor pose in the session's odometry frame (p_odom = R p_scan + t), when given
};

/// A scan list: scans grouped by session, each session's scans in time order.
struct ScanList {
  std::string source;                          ///< the list file (or KITTI folder), for messages
  std::vector<ScanEntry> scans;                ///< every scan, sessions contiguous, in list order
  std::vector<std::string> sessions;           ///< session names in order of first appearance
};

/// Reads SCANS.tsv: a header naming the tab-separated columns `session`, `scan` and `odometry` (any
/// order, other columns ignored), then one row per scan; `odometry` is 12 numbers separated by
/// spaces (row-major 3x4) or `-`. Throws quadrix::Error naming the file and the row for a missing
/// column or file, a malformed or non-rigid pose, a session mixing given and missing odometry, a
/// session split over non-adjacent rows, a session with one scan, or a duplicated row.
ScanList read_scan_list(const std::string& path);

/// The KITTI odometry layout: `velodyne_folder/*.bin` in name order, one session named `session`,
/// with the poses file's lines (12 numbers each, one per frame, camera frame) turned into LiDAR poses
/// Tr^-1 P Tr when `calibration` (a KITTI calib file) is given, else taken as they are; `poses`
/// empty: no odometry. Frames beyond the poses file are an Error naming it.
ScanList read_kitti_scan_list(const std::string& velodyne_folder, const std::string& poses = "",
                              const std::string& calibration = "", const std::string& session = "kitti");

/// A table of poses (poses.tsv): header, then `session`, `scan` and the 12 numbers of the pose
/// (one column of 12 space-separated numbers, or 12 columns), further columns ignored.
struct PoseRow {
  std::string session;                                     ///< session name
  std::string scan;                                        ///< scan as in the scan list
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  ///< sensor pose
  std::string frame;                                       ///< the `frame` column when present ("map" or "own")
};

/// Reads a poses.tsv; throws quadrix::Error naming the file and row.
std::vector<PoseRow> read_pose_table(const std::string& path);

}  // namespace quadrix
