// Point-cloud, label, mesh and pose I/O. Readers validate everything and throw quadrix::Error
// naming the file and what was wrong; non-finite points are dropped and counted. Writers write a
// temporary file beside the target and rename it, so a failed write never leaves a half file.
#pragma once

#include "geometry/error.h"
#include "geometry/mesh.h"
#include "geometry/point_cloud.h"

#include <Eigen/Geometry>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

namespace quadrix {

/// Point-cloud file formats. `Auto` chooses by extension.
enum class CloudFormat {
  Auto,         ///< by extension: .bin, .pcd.bin, .ply, .pcd, .xyz/.txt, .csv, .npy, .las
  KittiBin,     ///< float32 x, y, z, intensity (16 bytes a point)
  NuScenesBin,  ///< float32 x, y, z, intensity, ring (20 bytes a point)
  Ply,          ///< ascii, binary_little_endian, binary_big_endian
  Pcd,          ///< ascii, binary, binary_compressed
  Xyz,          ///< whitespace-separated x y z [more columns], '#' comments
  Csv,          ///< comma-separated, optional header row naming x,y,z
  Npy,          ///< NumPy N x 3+ float32/float64, C or Fortran order
  Las,          ///< ASPRS LAS 1.0-1.4, point formats 0-10 (uncompressed; LAZ is refused)
};

/// Name of a format ("kitti-bin", "ply", ...), as accepted by --format.
std::string cloud_format_name(CloudFormat format);
/// Parses --format values (auto, bin, kitti-bin, nuscenes-bin, ply, pcd, xyz, csv, npy, las); throws Error otherwise.
CloudFormat cloud_format_from_name(const std::string& name);
/// The format `path` would be read or written with under `Auto`; throws Error for unknown extensions.
CloudFormat cloud_format_from_path(const std::string& path);

/// What a reader found, for `quadrix info` and diagnostics.
struct CloudReadReport {
  CloudFormat format = CloudFormat::Auto;   ///< the format actually read
  std::string encoding;                     ///< e.g. "binary_little_endian", "binary_compressed", "ascii"
  std::size_t points_in_file = 0;           ///< records in the file, finite or not
  std::size_t non_finite_dropped = 0;       ///< points dropped because a coordinate was NaN/inf
  std::vector<std::string> fields;          ///< per-point fields in file order
};

/// Coordinates beyond which float32 storage loses more than half a millimetre (its spacing is
/// 0.98 mm from 8192 to 16384): an axis with a coordinate larger than this gets a local origin.
constexpr double kLocalOriginThreshold = 1e4;

/// A local origin for float storage of points near `reference` (file coordinates): on each axis
/// whose |reference| exceeds kLocalOriginThreshold, the reference rounded to a whole unit; zero on
/// the others (sensor-frame clouds keep their frame). Non-finite components give zero.
Eigen::Vector3d local_origin_near(const Eigen::Vector3d& reference);

/// Whether a reader stores positions relative to a local origin (PointCloud::local_origin).
enum class LocalOrigin {
  Zero,  ///< positions as in the file (float32: large coordinates are rounded)
  Auto,  ///< local_origin_near(the centre of the file's bounding box), subtracted in double before float storage
};

/// Options of read_point_cloud.
struct CloudReadOptions {
  CloudFormat format = CloudFormat::Auto;   ///< override the extension
  LocalOrigin local_origin = LocalOrigin::Zero;  ///< Auto keeps georeferenced coordinates exact (see PointCloud)
  bool keep_extra_fields = true;            ///< keep scalar fields other than x,y,z,intensity,label,rgb
  bool reject_non_finite = false;           ///< throw Error at the first NaN/inf coordinate instead of dropping it
};

/// Reads a point cloud; throws quadrix::Error naming the file (and line or field) on bad input.
/// Field roles by (case-insensitive) name: x, y, z (required); intensity, scalar_intensity, reflectance,
/// scalar_reflectance, remission -> intensity; label, scalar_label, semantic_label -> labels (integers
/// 0..2^32-1, else Error); red/green/blue (or r/g/b, diffuse_red/...) and PCD packed rgb/rgba -> colors
/// (integer types clamped to 0..255; floating types scaled by 255 when every value is <= 1, else clamped);
/// every other field -> extra_fields (when keep_extra_fields). Files without names (KITTI/nuScenes .bin,
/// XYZ, headerless CSV, .npy) name their columns: 3 -> x y z; 4 -> x y z intensity; 6 -> x y z red green
/// blue; any other count -> x y z column_4 column_5 ... (1-based). A point whose x, y or z is NaN/inf
/// (or overflows float) is dropped and counted in report->non_finite_dropped. LAS: intensity, the
/// classification as labels, RGB as colours, return_number and number_of_returns as extra fields.
/// KITTI/nuScenes .bin store float32 and always keep a zero local origin.
PointCloud read_point_cloud(const std::string& path, const CloudReadOptions& options = {},
                            CloudReadReport* report = nullptr);

/// Options of write_point_cloud.
struct CloudWriteOptions {
  CloudFormat format = CloudFormat::Auto;   ///< Ply or Pcd (others are read-only); Auto = by extension
  bool binary = true;                       ///< binary_little_endian PLY / binary PCD, else ascii
};

/// Writes positions and every present field (intensity, labels, colours, extra fields) atomically.
/// A cloud with a non-zero local_origin is written in the file's frame, its positions as doubles.
void write_point_cloud(const std::string& path, const PointCloud& cloud, const CloudWriteOptions& options = {});

/// Reads a SemanticKITTI .label file (uint32 per point, lower 16 bits = semantic class, upper = instance).
/// Throws Error when its size is not 4 * expected_points (pass 0 to skip the count check).
std::vector<std::uint32_t> read_semantic_kitti_labels(const std::string& path, std::size_t expected_points = 0);

/// Writes a triangle mesh as binary PLY (double x,y,z; uchar colours when present; int indices), atomically.
void write_mesh_ply(const std::string& path, const TriangleMesh& mesh);
/// Reads the vertices (and colours) and triangles of a PLY mesh; polygons with more than 3 corners are fanned.
TriangleMesh read_mesh_ply(const std::string& path);

/// Largest max|R^T R - I| a pose file may have before its rotation is rejected (covers 6-digit text).
constexpr double kPoseOrthonormalityTolerance = 1e-3;

/// Reads a 4x4 row-major text matrix (16 numbers, or 12 for the top 3 rows; '#' comments allowed), or a
/// .npy 4x4/3x4 array. Error names file and line; Error when the bottom row is not 0 0 0 1 or the rotation
/// is not orthonormal within kPoseOrthonormalityTolerance or has determinant < 0. Values are kept as written.
Eigen::Isometry3d read_pose_matrix(const std::string& path);
/// Writes a 4x4 row-major text matrix with full precision, atomically.
void write_pose_matrix(const std::string& path, const Eigen::Isometry3d& pose);
/// Reads KITTI pose lines (12 numbers a line, row-major 3x4).
std::vector<Eigen::Isometry3d> read_kitti_poses(const std::string& path);
/// Reads the velodyne->camera transform `Tr` (key "Tr:" or "Tr_velo_to_cam:") of a KITTI calibration file.
Eigen::Isometry3d read_kitti_calibration(const std::string& path);
/// As above, but also accepts per-sequence lines "seqA-B <12 numbers>" / "seqA <12 numbers>" (the format of
/// shared/data/kitti_poses/calib_Tr_velo_to_cam.txt) and picks the one covering `sequence`.
Eigen::Isometry3d read_kitti_calibration(const std::string& path, int sequence);

/// Writes a file through `write` into a temporary file beside `path`, then renames it over `path`.
/// On any exception the temporary is removed and the original file is untouched; so is it when a
/// signal remove_on_signals (geometry/removed_on_signal.h) handles ends the process. Only a regular
/// file (or nothing) is replaced: a directory, FIFO, device or socket at `path`, or a symlink to one
/// or to nothing, is an Error; a symlink to a regular file has that file replaced (the link stays).
void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write);

}  // namespace quadrix
