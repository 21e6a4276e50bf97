// The registration pairs of a benchmark (`quadrix bench`): read from a pairs.tsv file (the format
// of ../shared/data/pairs.tsv), generated from a KITTI-layout sequence by the paper's loop-closure
// rule (Eq. (loop pair gen)) or odometry rule (Eq. of the odometry pairs, §"Dataset from Odometry"),
// or read from the published QuadricsReg pair lists (lc_sample/*/test_A_B.txt).
#pragma once

#include <Eigen/Geometry>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace quadrix {

/// One registration pair of a benchmark.
struct BenchPair {
  std::string id;                                  ///< unique name of the pair (pairs.tsv `id`, or kitti<seq>_<mode>_<i>_<j>)
  std::string source;                              ///< source cloud file (absolute, or relative to the working directory)
  std::string target;                              ///< target cloud file
  std::optional<Eigen::Isometry3d> ground_truth;   ///< T_gt mapping source points into the target frame; unset: no ground truth
  std::string ground_truth_quality = "none";       ///< exact | approx | none (pairs.tsv `gt_quality`)
  std::string sensor;                              ///< sensor name (pairs.tsv `sensor`)
  std::string kind;                                ///< loop_closure | odometry | local | ... (pairs.tsv `kind`)
  std::string difficulty;                          ///< difficulty bin ("0-10", "10 m", ...) the summary groups by; defaults to `kind`
  double distance = -1.0;                          ///< distance between the two sensor positions, m (-1: unknown)
  std::string source_labels;                       ///< SemanticKITTI .label file of the source (pairs.tsv `source_labels`; "" none)
  std::string target_labels;                       ///< SemanticKITTI .label file of the target (pairs.tsv `target_labels`; "" none)
};

/// Reads a pairs.tsv file: a header line naming at least the columns id, source, target, gt
/// (optional: gt_quality, sensor, kind, t_m, rot_deg, source_labels, target_labels: SemanticKITTI
/// .label files for `quadrix bench --labels`), then one tab-separated pair a line; blank
/// lines and lines starting with '#' are skipped. Paths are relative to the file's folder; gt "-"
/// (or gt_quality "none") means no ground truth. The ground-truth files are read here. Throws
/// quadrix::Error naming the file and line for a missing column, a duplicate id or an unreadable pose.
std::vector<BenchPair> read_pairs_tsv(const std::string& path);

/// A KITTI odometry sequence in LiDAR frames: frames that have both a cloud file and a pose.
struct KittiSequence {
  std::string name;                                 ///< two-digit sequence name ("00")
  std::vector<int> frames;                          ///< N_p: frame indices with a cloud (ascending)
  std::vector<std::string> cloud_paths;             ///< cloud file of each entry of `frames` (empty when poses-only)
  std::vector<Eigen::Isometry3d> lidar_poses;       ///< LiDAR pose of every frame index of the pose file, P(i) Tr
};

/// Loads sequence `sequence` of a KITTI-layout folder: clouds ROOT/sequences/SS/velodyne/NNNNNN.*
/// (.bin preferred, any readable cloud format accepted), poses ROOT/poses/SS.txt or
/// ROOT/sequences/SS/poses.txt (camera frame, 12 numbers a line), calibration `calibration_path` when
/// given (a KITTI calib.txt or the per-sequence "seqA-B" file of ../shared/data/kitti_poses), else
/// ROOT/sequences/SS/calib.txt. LiDAR pose of frame i = P(i) Tr. Throws quadrix::Error naming the
/// missing file or folder.
KittiSequence load_kitti_sequence(const std::string& root, const std::string& sequence,
                                  const std::string& calibration_path = "");

/// Every frame index of `poses` as N_p, without cloud files (pair generation from poses alone).
KittiSequence kitti_sequence_from_poses(const std::string& name, const std::vector<Eigen::Isometry3d>& lidar_poses);

/// A distance bin [minimum, maximum] in metres (d^min_lc, d^max_lc).
struct DistanceBin {
  double minimum = 0.0;  ///< d^min, m
  double maximum = 0.0;  ///< d^max, m
  /// "0-10" style name.
  std::string name() const;
};

/// Parses "0-10,10-20,20-30" into bins; throws quadrix::Error naming the bad entry.
std::vector<DistanceBin> parse_distance_bins(const std::string& text);

/// Parses "1..10" (every integer), "1,5,10" or "2.5" into odometry distances d_odo; throws quadrix::Error.
std::vector<double> parse_odometry_distances(const std::string& text);

/// Options of the loop-closure rule.
struct LoopClosureOptions {
  int minimum_frame_gap = 100;      ///< t_lc: |i - j| >= this (the paper gives no value; 100 frames = 10 s at 10 Hz)
  std::size_t pairs_per_bin = 1000; ///< uniform spatial sampling keeps at most this many pairs per bin (paper: ~1000)
  double sampling_cell = 10.0;      ///< cell size of the uniform spatial sampling, m (grid on the source position)
  std::uint64_t seed = 1;           ///< seed of the order within a sampling cell
};

/// Paper Eq. (loop pair gen): every (i, j), i < j in N_p, with d^min <= ||t_i - t_j|| <= d^max and
/// |i - j| >= t_lc, per bin; then uniform spatial sampling when a bin holds more than pairs_per_bin:
/// the pairs are grouped by the grid cell of the source position, and cells are visited round-robin
/// (pairs within a cell in seeded random order) until pairs_per_bin are taken. Source = i, target =
/// j, ground truth T_j_from_i = L(j)^-1 L(i); difficulty = bin name; kind "loop_closure". Output is
/// sorted by bin, then (i, j).
std::vector<BenchPair> generate_loop_closure_pairs(const KittiSequence& sequence, const std::vector<DistanceBin>& bins,
                                                   const LoopClosureOptions& options = {});

/// Options of the odometry rule.
struct OdometryOptions {
  double tolerance = 0.5;            ///< keep (i, j) only when | ||t_i - t_j|| - d_odo | <= this, m (ours: the paper's argmin has no bound)
  std::size_t pairs_per_distance = 500;  ///< uniform spatial sampling keeps at most this many per distance (paper: ~500)
  double sampling_cell = 10.0;       ///< cell size of the sampling grid, m
  std::uint64_t seed = 1;            ///< seed of the order within a sampling cell
};

/// The paper's odometry rule: for every i in N_p, j = argmin_{k in N_p, k > i} | ||t_i - t_k|| - d_odo |
/// (later frames only: odometry moves forward; ties take the smaller k), per distance d_odo; then
/// the same uniform spatial sampling. Difficulty = "<d> m"; kind "odometry".
std::vector<BenchPair> generate_odometry_pairs(const KittiSequence& sequence, const std::vector<double>& distances,
                                               const OdometryOptions& options = {});

/// One line of a published QuadricsReg pair list.
struct ListedPair {
  int sequence = 0;              ///< `seq`: sequence of the query (source)
  int frame = 0;                 ///< `i`: query frame
  int database_sequence = 0;     ///< `seq_db`: sequence of the database (target)
  int database_frame = 0;        ///< `j`: database frame
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();  ///< mot1..mot16 (4x4 row-major): maps frame i into frame j
};

/// Reads a published list (header "seq i seq_db j mot1 .. mot16", then 20 numbers a line). Throws
/// quadrix::Error naming the file and line for a wrong column count, a non-integer index or a
/// non-orthonormal rotation.
std::vector<ListedPair> read_pair_list(const std::string& path);

/// The listed pairs as benchmark pairs: clouds ROOT/sequences/SS/velodyne/NNNNNN.* when `root` is
/// given (missing files are an Error naming them), ground truth = the listed transform, difficulty =
/// the list's bin from its file name (test_0_10.txt -> "0-10"), kind "loop_closure".
std::vector<BenchPair> listed_pairs_to_bench(const std::vector<ListedPair>& listed, const std::string& list_path,
                                             const std::string& root = "");

/// The cloud file of frame `frame` in ROOT/sequences/SS/velodyne (NNNNNN.bin, else the first
/// NNNNNN.<ext> in a readable cloud format), or "" when there is none.
std::string kitti_frame_path(const std::string& root, const std::string& sequence, int frame);

}  // namespace quadrix
