// Running the simulator over a set of sensor poses and writing the self-describing output folder of
// `quadrix synth`: clouds, ground-truth primitives, sensor poses, ground-truth relative transforms
// of every pair of scans, per-primitive point counts and a scene.json that lists every file.
#pragma once

#include "experiments/synthetic/scanner_simulator.h"
#include "experiments/synthetic/synthetic_scene.h"
#include "geometry/io.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <string>
#include <vector>

namespace quadrix {

/// A scan index as the file names of a synthetic folder write it: three digits, zero-padded ("007").
std::string three_digits(std::size_t index);
/// `value` with exactly `decimals` digits after the point, as pairs.tsv writes distances and angles.
std::string decimal_text(double value, int decimals);

/// Parses a POSE_SPEC (sensor -> world poses in the scene's world frame, z up, metres, degrees):
/// either inline entries "x,y,z,yaw_deg[,pitch_deg[,roll_deg]]" separated by ';' (rotation
/// Rz(yaw) Ry(pitch) Rx(roll)), or the path of a text file with one pose a line: the same 4 to 6
/// numbers, or 12 (row-major 3x4) or 16 (row-major 4x4) numbers; separators are spaces or commas,
/// '#' starts a comment. Throws quadrix::Error naming the entry or file line that is wrong.
std::vector<Eigen::Isometry3d> parse_pose_spec(const std::string& spec);

/// The poses used without --poses: the scene's TLS stations for a Dome sensor, else its LiDAR pair.
std::vector<Eigen::Isometry3d> default_sensor_poses(const Scene& scene, const SensorModel& sensor);

/// A simulated data set: a scene scanned by one sensor from several poses.
struct SyntheticRun {
  Scene scene;                       ///< the scene with its ground truth
  SensorModel sensor;                ///< the sensor used for every scan
  std::uint64_t seed = 0;            ///< seed of the noise and dropout draws
  std::vector<SimulatedScan> scans;  ///< one per pose, in pose order
};

/// Scans `scene` from every pose (noise stream: seed and scan index). Throws quadrix::Error when
/// `poses` is empty.
SyntheticRun run_synthetic(const Scene& scene, const SensorModel& sensor, const std::vector<Eigen::Isometry3d>& poses,
                           std::uint64_t seed);

/// Options of write_synthetic_folder.
struct SyntheticOutputOptions {
  CloudFormat cloud_format = CloudFormat::Ply;  ///< Ply or Pcd
  bool binary = true;                           ///< binary clouds (false: ascii)
  int record_samples = 4000;                    ///< true-surface samples per primitive for the records' statistics
};

/// The ground-truth primitives as JSON text: for each, id, name, label (id and name), surface and
/// model type names, scale, pose (4x4 row-major), extent, polygon, both quadrics' 10 parameters,
/// the 21-number record and the bounded area. Numbers carry 12 significant digits.
std::string primitives_json(const Scene& scene, int record_samples = 4000);

/// Ground-truth transform mapping points of scan `source` into the frame of scan `target`:
/// T = pose_target^-1 * pose_source (p_target = R p_source + t).
Eigen::Isometry3d relative_transform(const Eigen::Isometry3d& target_pose, const Eigen::Isometry3d& source_pose);

/// Writes the folder (created if missing; existing files of the same names are replaced):
///   scene.json            what everything is (scene, sensor, frames, labels, files, scans, pairs)
///   primitives.json       primitives_json()
///   scan_NNN.<ply|pcd>    clouds in the sensor frame; labels = semantic label, field primitive_id
///   pose_NNN.txt          sensor -> world, 4x4 row-major
///   T_TTT_SSS.txt         for every pair target TTT < source SSS: maps SOURCE points into the TARGET frame
///   pairs.tsv             the pairs in the format of the shared data folder's pairs.tsv
///   point_counts.csv      returned points per primitive and scan
/// Returns the relative paths written, in the order listed in scene.json. Same run -> identical bytes.
std::vector<std::string> write_synthetic_folder(const std::string& directory, const SyntheticRun& run,
                                                const SyntheticOutputOptions& options = {});

/// Every name write_synthetic_folder may write, as shell patterns: what a folder replaced by a new
/// run may hold (FolderReplacement's own names).
std::vector<std::string> synthetic_folder_names();

}  // namespace quadrix
