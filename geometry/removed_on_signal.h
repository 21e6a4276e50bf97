// Paths removed when the process is ended by SIGINT, SIGTERM or SIGHUP: the temporary files of
// write_file_atomically and the staging folders of commands that replace a folder at once.
#pragma once

#include <string>

namespace quadrix {

/// Installs handlers of SIGINT, SIGTERM and SIGHUP that remove every path a live RemovedOnSignal
/// holds (newest first: a file, or a folder with everything in it) and then end the process by that
/// signal.
void remove_on_signals();

/// While it lives, `path` (a temporary file or a staging folder) is removed if the process
/// is ended by a signal remove_on_signals handles. At most 256 live at once (beyond: not tracked).
class RemovedOnSignal {
 public:
  /// Tracks `path` (an empty path tracks nothing).
  explicit RemovedOnSignal(const std::string& path);
  /// Stops tracking (the path itself is left as it is).
  ~RemovedOnSignal();
  RemovedOnSignal(const RemovedOnSignal&) = delete;
  RemovedOnSignal& operator=(const RemovedOnSignal&) = delete;

 private:
  int slot_ = -1;
};

}  // namespace quadrix
