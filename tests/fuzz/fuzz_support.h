// Shared pieces of the fuzz harnesses: the per-process input file handed to path-taking readers, the
// check that a caught quadrix::Error names its file, and cheap invariants of a successful read.
// A violated expectation ends the process with __builtin_trap(), which libFuzzer (and the replay
// runner under ctest) report as a crash together with the input that caused it.
#pragma once

#include "geometry/error.h"
#include "geometry/io.h"

#include <Eigen/Geometry>

#include <cerrno>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace quadrix::fuzz {

/// Ends the process as a crash when `condition` is false (an invariant of a reader is broken).
inline void require(bool condition) {
  if (!condition) __builtin_trap();
}

/// Ends the process as a crash after printing why (e.g. the message of an Error that must not happen).
[[noreturn]] inline void fail(const std::string& why) {
  std::fprintf(stderr, "fuzz harness: %s\n", why.c_str());
  std::fflush(stderr);
  __builtin_trap();
}

/// Folder for the per-process input files: /dev/shm when writable (no disk I/O), else $TMPDIR, else /tmp.
inline std::string scratch_folder() {
  if (::access("/dev/shm", W_OK) == 0) return "/dev/shm";
  if (const char* folder = std::getenv("TMPDIR"); folder != nullptr && *folder != '\0') return folder;
  return "/tmp";
}

/// A file named for this process, harness and extension, rewritten for every input and removed at exit.
class InputFile {
 public:
  /// `harness` names the file (quadrix-fuzz-<harness>-<pid><extension>); `extension` picks the reader.
  InputFile(const char* harness, const char* extension)
      : path_(scratch_folder() + "/quadrix-fuzz-" + harness + "-" + std::to_string(::getpid()) + extension) {}
  ~InputFile() { ::unlink(path_.c_str()); }
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;

  /// Replaces the file's contents by `size` bytes at `data`; traps when the file system refuses.
  const std::string& write(const std::uint8_t* data, std::size_t size) const {
    const int descriptor = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
    require(descriptor >= 0);
    std::size_t done = 0;
    while (done < size) {
      const ssize_t wrote = ::write(descriptor, data + done, size - done);
      if (wrote < 0 && errno == EINTR) continue;
      require(wrote > 0);
      done += static_cast<std::size_t>(wrote);
    }
    require(::close(descriptor) == 0);
    return path_;
  }
  /// The file's path.
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

/// A reader's clean failure must name what it read: traps when the message lacks `name`. With the
/// environment variable QUADRIX_FUZZ_VERBOSE set, every such message is printed (to read what a
/// reproducer now reports).
inline void require_names(const Error& error, const std::string& name) {
  static const bool verbose = std::getenv("QUADRIX_FUZZ_VERBOSE") != nullptr;
  if (verbose) std::fprintf(stderr, "quadrix::Error: %s\n", error.what());
  if (std::string(error.what()).find(name) == std::string::npos)
    fail("the error does not name '" + name + "': " + error.what());
}

/// Invariants of a successful cloud read: finite positions, every optional field one entry a point,
/// the report's counts adding up and the format the extension chose.
inline void check_cloud(const PointCloud& cloud, const CloudReadReport& report, CloudFormat format) {
  const std::size_t points = cloud.size();
  require(cloud.positions.rows() == 3);
  require(cloud.positions.allFinite());
  require(cloud.intensity.empty() || cloud.intensity.size() == points);
  require(cloud.labels.empty() || cloud.labels.size() == points);
  require(cloud.colors.empty() || cloud.colors.size() == points);
  for (const auto& [name, values] : cloud.extra_fields) {
    require(!name.empty());
    require(values.size() == points);
  }
  require(report.format == format);
  require(report.points_in_file == points + report.non_finite_dropped);
}

/// Reads `path` as `requested` (Auto: by extension), expecting `format`, with the default options
/// (non-finite points dropped) and, when that succeeds, again with reject_non_finite and without extra
/// fields: the strict read fails exactly when the first one dropped points, and otherwise returns the
/// same positions. Errors must name the file.
inline void read_cloud_both_ways(const std::string& path, CloudFormat format,
                                 CloudFormat requested = CloudFormat::Auto) {
  CloudReadOptions options;
  options.format = requested;
  CloudReadReport report;
  PointCloud cloud;
  try {
    cloud = read_point_cloud(path, options, &report);
  } catch (const Error& error) {
    require_names(error, path);
    return;
  }
  check_cloud(cloud, report, format);
  CloudReadOptions strict = options;
  strict.reject_non_finite = true;
  strict.keep_extra_fields = false;
  CloudReadReport strict_report;
  try {
    const PointCloud strict_cloud = read_point_cloud(path, strict, &strict_report);
    require(report.non_finite_dropped == 0);
    check_cloud(strict_cloud, strict_report, format);
    require(strict_cloud.extra_fields.empty());
    require(strict_cloud.size() == cloud.size() && strict_cloud.positions == cloud.positions);
  } catch (const Error& error) {
    require_names(error, path);
    require(report.non_finite_dropped > 0);
  }
}

/// Invariants of a pose a reader returned: finite, bottom row 0 0 0 1, the rotation orthonormal
/// within kPoseOrthonormalityTolerance and not a reflection.
inline void check_pose(const Eigen::Isometry3d& pose) {
  const Eigen::Matrix4d& matrix = pose.matrix();
  require(matrix.allFinite());
  require(matrix.row(3) == Eigen::RowVector4d(0, 0, 0, 1));
  const Eigen::Matrix3d rotation = matrix.topLeftCorner<3, 3>();
  const double deviation = (rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  require(deviation <= kPoseOrthonormalityTolerance);
  require(rotation.determinant() > 0.0);
}

}  // namespace quadrix::fuzz
