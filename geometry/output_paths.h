// Outputs of a command or API call, checked before the work: every path a command will write is a
// regular file or nothing, in a writable folder that is not a system one, none is one of the
// command's inputs or another of its outputs; a folder the command fills is replaced all at once.
#pragma once

#include "geometry/point_cloud.h"
#include "geometry/removed_on_signal.h"

#include <memory>
#include <string>
#include <vector>

namespace quadrix {

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

/// Whether a command owns its output folder or shares it with other files.
enum class FolderSharing {
  Whole,          ///< the folder is the command's: replaced whole, other entries refused before the work
  OwnFilesOnly,   ///< the folder holds other files too (papers/studies): only the command's files are replaced, together
};

/// The folder a command fills (`--out DIR`), replaced all at once: checked before the work, built
/// beside it in a hidden staging folder (".NAME.staging-PID/NAME"), swapped in by commit() with one
/// rename (renameat2 RENAME_EXCHANGE when the folder exists), and the old folder removed only after
/// the swap. Interrupted before commit() (an exception, SIGINT, SIGTERM, SIGHUP), the folder is left
/// as it was and the staging folder is removed with everything in it. Every command that writes a
/// folder goes through it.
class FolderReplacement {
 public:
  /// Checks, before the work, that `folder` (given by `option`) is nothing or a folder holding only
  /// entries whose names match one of `own_names` (shell patterns such as "scan_*.ply": an earlier
  /// run's outputs; a matching folder counts whole), outside /proc, /sys and /dev, in a place where
  /// it can be created, and holding none of `inputs` (nor being one); else quadrix::Error.
  /// With FolderSharing::OwnFilesOnly other entries may stay; the command's own (existing ones
  /// must be regular files, none an input) are replaced at commit() by one rename each, with
  /// SIGINT, SIGTERM and SIGHUP blocked, so a signal cannot leave some old and some new.
  FolderReplacement(std::string option, std::string folder, std::vector<std::string> own_names,
                    const std::vector<std::string>& inputs, FolderSharing sharing = FolderSharing::Whole);
  /// Removes the staging folder unless committed.
  ~FolderReplacement();
  FolderReplacement(const FolderReplacement&) = delete;
  FolderReplacement& operator=(const FolderReplacement&) = delete;

  /// The staging folder, created empty on the first call: a writer fills it as it would the folder.
  std::string staging_folder();
  /// Where the file `name` (matching one of own_names) is written: inside the staging folder.
  std::string path(const std::string& name);
  /// Puts the staging folder in the folder's place at once and then removes the old folder.
  /// Nothing staged (staging_folder() never called): the folder is left as it is.
  void commit();

 private:
  std::string option_;
  std::string folder_;   // as given, for messages
  std::string target_;   // its canonical path: what is replaced (a symlink to a folder keeps pointing to it)
  std::string root_;     // ".NAME.staging-PID" beside the target, removed whole on a signal
  std::string staging_;  // root_/NAME: becomes the folder
  std::vector<std::string> own_names_;
  FolderSharing sharing_ = FolderSharing::Whole;
  std::unique_ptr<RemovedOnSignal> tracked_;
  bool committed_ = false;
};

/// Error naming `what` (e.g. "--source-origin 1e308,0,0 moved SOURCE") unless every point of
/// `cloud` is finite: checked after every transform a user's numbers drive (an origin, a pose), since
/// positions are float32 and 1e39 or 1e308 - x is no longer a number there.
void require_finite_points(const PointCloud& cloud, const std::string& what);

}  // namespace quadrix
