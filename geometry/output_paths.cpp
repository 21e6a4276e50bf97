// Output checks and whole-folder replacement (see output_paths.h).
#include "geometry/output_paths.h"

#include "geometry/error.h"

#include <Eigen/Core>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <fnmatch.h>
#include <filesystem>
#include <optional>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>
#include <utility>

namespace quadrix {
namespace {

namespace fs = std::filesystem;

// What identifies a file: device and inode when it exists, else its canonical path.
struct Identity {
  bool exists = false;
  dev_t device = 0;
  ino_t inode = 0;
  std::string canonical;
  bool operator==(const Identity& other) const {
    return exists && other.exists ? device == other.device && inode == other.inode : canonical == other.canonical;
  }
};

Identity identity_of(const std::string& path) {
  Identity identity;
  std::error_code code;
  identity.canonical = fs::weakly_canonical(fs::absolute(path, code), code).string();
  struct stat status {};
  if (::stat(path.c_str(), &status) == 0) {
    identity.exists = true;
    identity.device = status.st_dev;
    identity.inode = status.st_ino;
  }
  return identity;
}

// The system folders no output belongs in (their files are not data: /proc/self/..., /dev/null).
bool in_system_folder(const std::string& canonical) {
  for (const std::string folder : {"/proc", "/sys", "/dev"})
    if (canonical == folder || canonical.rfind(folder + "/", 0) == 0) return true;
  return false;
}

// The nearest existing folder at or above `folder` (where missing folders would be created).
fs::path nearest_existing(fs::path folder) {
  std::error_code code;
  while (!folder.empty() && !fs::exists(folder, code) && folder.has_parent_path() && folder.parent_path() != folder)
    folder = folder.parent_path();
  return folder.empty() ? fs::path(".") : folder;
}

// Error unless a file can be created in `folder` (or in the folder that would hold it once created).
void require_writable_folder(const std::string& option, const std::string& path, const fs::path& folder) {
  const fs::path existing = nearest_existing(folder);
  std::error_code code;
  if (!fs::is_directory(existing, code))
    throw Error(option + " " + path + ": '" + existing.string() + "' is not a folder, so nothing can be written below it");
  if (::access(existing.c_str(), W_OK | X_OK) != 0)
    throw Error(option + " " + path + ": cannot write in '" + existing.string() + "': " + std::strerror(errno));
}

// Error unless `path` is a regular file or nothing (a symlink counts as what it leads to).
void require_replaceable(const std::string& option, const std::string& path) {
  std::error_code code;
  const fs::file_status link = fs::symlink_status(path, code);
  if (code || !fs::exists(link)) return;
  const fs::file_status target = fs::status(path, code);
  if (fs::is_symlink(link) && (code || !fs::exists(target)))
    throw Error(option + " " + path + ": a symlink to nothing; refused (it would be replaced by a file)");
  if (fs::is_directory(target)) throw Error(option + " " + path + ": is a folder, expected a file name");
  if (!fs::is_regular_file(target))
    throw Error(option + " " + path + ": is not a regular file (a device, FIFO or socket); refused, it would be replaced");
}

}  // namespace

void check_outputs(const std::vector<PlannedOutput>& outputs, const std::vector<std::string>& inputs) {
  std::vector<std::pair<std::string, Identity>> known;  // inputs, then the outputs checked so far
  for (const std::string& input : inputs)
    if (!input.empty()) known.emplace_back("input " + input, identity_of(input));
  std::vector<fs::path> folders;
  for (const PlannedOutput& output : outputs) {
    if (output.path.empty()) continue;
    const Identity identity = identity_of(output.path);
    if (in_system_folder(identity.canonical))
      throw Error(output.option + " " + output.path + ": lies in a system folder (/proc, /sys, /dev), not a place for files");
    require_replaceable(output.option, output.path);
    const fs::path folder = fs::path(identity.canonical).parent_path();
    require_writable_folder(output.option, output.path, folder);
    for (const auto& [what, other] : known)
      if (identity == other)
        throw Error(output.option + " " + output.path + ": is the same file as " + what + "; refused (it would be overwritten)");
    known.emplace_back(output.option + " " + output.path, identity);
    folders.push_back(folder);
  }
  for (const fs::path& folder : folders) {
    std::error_code code;
    fs::create_directories(folder, code);
    if (code) throw Error("cannot create the folder '" + folder.string() + "': " + code.message());
  }
}

namespace {

// Whether `name` matches one of `patterns` (shell patterns; a leading dot must be matched explicitly).
bool matches_any(const std::string& name, const std::vector<std::string>& patterns) {
  for (const std::string& pattern : patterns)
    if (::fnmatch(pattern.c_str(), name.c_str(), FNM_PERIOD) == 0) return true;
  return false;
}

// Removes staging folders beside `target` left by processes that no longer run (killed with
// SIGKILL, or by a power cut): ".NAME.staging-PID" whose PID is gone.
void remove_abandoned_staging(const fs::path& target) {
  const std::string prefix = "." + target.filename().string() + ".staging-";
  std::error_code code;
  for (const fs::directory_entry& entry : fs::directory_iterator(target.parent_path(), code)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    const std::string digits = name.substr(prefix.size());
    if (digits.empty() || digits.size() > 9 || !std::all_of(digits.begin(), digits.end(), ::isdigit)) continue;
    const pid_t owner = static_cast<pid_t>(std::stol(digits));
    if (owner == ::getpid() || (::kill(owner, 0) != 0 && errno == ESRCH)) fs::remove_all(entry.path(), code);
  }
}

}  // namespace

FolderReplacement::FolderReplacement(std::string option, std::string folder, std::vector<std::string> own_names,
                                     const std::vector<std::string>& inputs, FolderSharing sharing)
    : option_(std::move(option)), folder_(std::move(folder)), own_names_(std::move(own_names)), sharing_(sharing) {
  if (folder_.empty()) throw Error(option_ + ": expected a folder name");
  const Identity identity = identity_of(folder_);
  if (in_system_folder(identity.canonical))
    throw Error(option_ + " " + folder_ + ": lies in a system folder (/proc, /sys, /dev), not a place for files");
  std::error_code code;
  const fs::file_status link = fs::symlink_status(folder_, code);
  const fs::file_status status = fs::status(folder_, code);
  if (fs::is_symlink(link) && !fs::exists(status))
    throw Error(option_ + " " + folder_ + ": a symlink to nothing; refused (give a folder)");
  if (fs::exists(status)) {
    if (!fs::is_directory(status)) throw Error(option_ + " " + folder_ + ": exists and is not a folder");
    fs::directory_iterator entries(folder_, code);
    if (code) throw Error(option_ + " " + folder_ + ": cannot list the folder: " + code.message());
    for (const fs::directory_entry& entry : entries) {
      const std::string name = entry.path().filename().string();
      if (sharing_ == FolderSharing::OwnFilesOnly) {
        if (matches_any(name, own_names_)) require_replaceable(option_, entry.path().string());
        continue;
      }
      if (!matches_any(name, own_names_))
        throw Error(option_ + " " + folder_ + ": holds '" + name +
                    "', which this command does not write; the folder is replaced whole, so give a new or empty "
                    "folder (or one an earlier run of this command wrote)");
    }
  }
  for (const std::string& input : inputs) {
    if (input.empty()) continue;
    const std::string canonical = identity_of(input).canonical;
    if (sharing_ == FolderSharing::OwnFilesOnly) {
      if (fs::path(canonical).parent_path() == fs::path(identity.canonical) &&
          matches_any(fs::path(canonical).filename().string(), own_names_))
        throw Error(option_ + " " + folder_ + ": the input " + input + " is one of the files this command writes there; refused");
      continue;
    }
    if (canonical == identity.canonical || canonical.rfind(identity.canonical + "/", 0) == 0)
      throw Error(option_ + " " + folder_ + ": holds the input " + input + "; refused (the folder is replaced whole)");
  }
  const fs::path target(identity.canonical);
  require_writable_folder(option_, folder_, target.parent_path());
  target_ = target.string();
  root_ = (target.parent_path() / ("." + target.filename().string() + ".staging-" + std::to_string(::getpid()))).string();
  staging_ = (fs::path(root_) / target.filename()).string();
}

FolderReplacement::~FolderReplacement() {
  if (committed_ || !tracked_) return;
  std::error_code code;
  fs::remove_all(root_, code);
}

std::string FolderReplacement::staging_folder() {
  if (!tracked_) {
    std::error_code code;
    fs::create_directories(fs::path(root_).parent_path(), code);
    if (code) throw Error(option_ + " " + folder_ + ": cannot create the folder '" + fs::path(root_).parent_path().string() +
                          "': " + code.message());
    remove_abandoned_staging(target_);
    tracked_ = std::make_unique<RemovedOnSignal>(root_);
    if (!fs::create_directory(root_, code) || code || !fs::create_directory(staging_, code) || code) {
      fs::remove_all(root_, code);
      tracked_.reset();
      throw Error(option_ + " " + folder_ + ": cannot create the staging folder '" + staging_ + "'");
    }
  }
  return staging_;
}

std::string FolderReplacement::path(const std::string& name) {
  if (!matches_any(name, own_names_)) throw Error("FolderReplacement: '" + name + "' is not one of the folder's own files");
  return (fs::path(staging_folder()) / name).string();
}

void FolderReplacement::commit() {
  if (!tracked_) return;  // nothing was staged
  // The swap and the removal of the old folder are not interrupted halfway by SIGINT or SIGTERM: a
  // signal arriving meanwhile ends the process right after, with the new folder in place.
  sigset_t blocked, previous;
  sigemptyset(&blocked);
  for (const int signal_number : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&blocked, signal_number);
  pthread_sigmask(SIG_BLOCK, &blocked, &previous);
  std::error_code code;
  int renamed = -1;
  int error = 0;
  if (sharing_ == FolderSharing::OwnFilesOnly && fs::is_directory(target_, code)) {
    // Each staged file over its namesake (a rename within one file system), the others untouched.
    renamed = 0;
    for (const fs::directory_entry& entry : fs::directory_iterator(staging_, code)) {
      const fs::path destination = fs::path(target_) / entry.path().filename();
      if (::rename(entry.path().c_str(), destination.c_str()) != 0 && renamed == 0) {
        renamed = -1;
        error = errno;
      }
    }
  } else if (fs::exists(fs::symlink_status(target_, code))) {
    renamed = ::renameat2(AT_FDCWD, staging_.c_str(), AT_FDCWD, target_.c_str(), RENAME_EXCHANGE);
    if (renamed != 0) {  // a file system without RENAME_EXCHANGE: the old folder aside, then the new one in
      const std::string aside = (fs::path(root_) / ".old").string();
      if (::rename(target_.c_str(), aside.c_str()) == 0) {
        renamed = ::rename(staging_.c_str(), target_.c_str());
        error = errno;
        if (renamed != 0) ::rename(aside.c_str(), target_.c_str());
      } else {
        error = errno;
      }
    }
  } else {
    renamed = ::rename(staging_.c_str(), target_.c_str());
    error = errno;
  }
  fs::remove_all(root_, code);  // the old folder after a swap; the new files after a failure
  tracked_.reset();
  committed_ = renamed == 0;
  pthread_sigmask(SIG_SETMASK, &previous, nullptr);
  if (renamed != 0)
    throw Error(option_ + " " + folder_ + ": cannot put the new files in place: " + std::strerror(error));
}

void require_finite_points(const PointCloud& cloud, const std::string& what) {
  for (Eigen::Index i = 0; i < cloud.positions.cols(); ++i)
    if (!cloud.positions.col(i).allFinite())
      throw Error(what + ": point " + std::to_string(i) +
                  " is no longer finite (a coordinate beyond float range); check the origin or pose given");
}

}  // namespace quadrix
