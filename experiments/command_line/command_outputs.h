// Outputs of a `quadrix` command, checked before the work: every path a command will write is a
// regular file or nothing, in a writable folder that is not a system one, none is one of the
// command's inputs or another of its outputs; a folder the command fills is replaced all at once.
#pragma once

#include "geometry/point_cloud.h"
#include "geometry/removed_on_signal.h"

#include <memory>
#include <string>
#include <vector>

namespace quadrix::cli {

/// One file a command will write: the option naming it (for messages) and its path ("" : none).
struct PlannedOutput {
  std::string option;  ///< e.g. "--mesh"
  std::string path;    ///< where it goes; empty when the option was not given
};

/// Checks every output before the work and creates their missing parent folders; throws
/// quadrix::Error (exit 2) naming the option and the path when an output is a directory, a FIFO, a
/// device or a symlink to one or to nothing, lies under /proc, /sys or /dev, sits in a folder that
/// cannot be written (read-only file system, no permission), is one of `inputs` or another output
/// (same file by device and inode, or the same canonical path).
void check_outputs(const std::vector<PlannedOutput>& outputs, const std::vector<std::string>& inputs);

/// A folder whose files a command replaces all at once: they are written into a staging folder
/// beside it (".NAME.staging-PID"), which commit() swaps in with one rename (the old folder is then
/// removed). Interrupted (an exception, SIGINT, SIGTERM, SIGHUP) before commit(), the folder is
/// untouched and the staging folder removed.
class FolderReplacement {
 public:
  /// Checks, before the work, that `folder` (given by `option`) is nothing or a folder holding only
  /// files named in `own_names` (an earlier run's outputs), in a writable place, and holding none
  /// of `inputs`; else quadrix::Error.
  FolderReplacement(std::string option, std::string folder, std::vector<std::string> own_names,
                    const std::vector<std::string>& inputs);
  /// Removes the staging folder unless committed.
  ~FolderReplacement();
  FolderReplacement(const FolderReplacement&) = delete;
  FolderReplacement& operator=(const FolderReplacement&) = delete;

  /// Where the file `name` (one of own_names) is written: inside the staging folder (created on
  /// the first call), tracked for removal on a signal.
  std::string path(const std::string& name);
  /// Puts the staging folder in the folder's place at once (renameat2 RENAME_EXCHANGE when the
  /// folder exists) and removes the old contents.
  void commit();

 private:
  std::string option_;
  std::string folder_;
  std::string staging_;
  std::vector<std::string> own_names_;
  std::vector<std::unique_ptr<RemovedOnSignal>> tracked_;
  bool committed_ = false;
};

/// Error naming `what` (e.g. "--source-origin 1e308,0,0 moved SOURCE") unless every point of
/// `cloud` is finite: checked after every transform a user's numbers drive (an origin, a pose), since
/// positions are float32 and 1e39 or 1e308 - x is no longer a number there.
void require_finite_points(const PointCloud& cloud, const std::string& what);

}  // namespace quadrix::cli
