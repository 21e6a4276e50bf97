// A disk that refuses a write: `quadrix model` onto a read-only file system, onto a full one, and with
// its tiles' temporary folder on a full one. Each run must end with exit code 2 and a message that
// names the path, leave a good file already there byte-identical, leave no temporary file or tile
// folder behind, and never write a half file. The file systems are small tmpfs mounts made for the
// test; the tests skip, saying why, where mounting is not permitted (not root, or no CAP_SYS_ADMIN).
#include <gtest/gtest.h>

#include <sys/mount.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

namespace quadrix {
namespace {

namespace fs = std::filesystem;

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// A scratch folder with a tmpfs of `size` mounted at `mount` inside it; unmounted and removed at
/// destruction. `mounted` is false (and `why` says why) where the system refuses the mount.
struct SmallDisk {
  fs::path root, mount;
  bool mounted = false;
  std::string why;
  explicit SmallDisk(const std::string& options) {
    root = fs::temp_directory_path() / ("quadrix_disk_" + std::to_string(std::random_device{}()));
    mount = root / "disk";
    fs::create_directories(mount);
    if (::mount("tmpfs", mount.c_str(), "tmpfs", 0, options.c_str()) == 0)
      mounted = true;
    else
      why = std::string("cannot mount a tmpfs here (") + std::strerror(errno) + "): the disk-fault tests need root with CAP_SYS_ADMIN";
  }
  /// Makes the mounted file system read-only.
  bool make_read_only() {
    return ::mount("tmpfs", mount.c_str(), "tmpfs", MS_REMOUNT | MS_RDONLY, nullptr) == 0;
  }
  ~SmallDisk() {
    if (mounted) ::umount2(mount.c_str(), MNT_DETACH);
    std::error_code ignored;
    fs::remove_all(root, ignored);
  }
};

struct CommandRun {
  int exit_code = -1;
  std::string output;
};

/// Runs quadrix with `arguments` (and `environment` prefixed, e.g. "TMPDIR=..."), stdout and stderr together.
CommandRun run_quadrix(const fs::path& scratch, const std::string& arguments, const std::string& environment = "") {
  const fs::path log = scratch / "log.txt";
  const int status =
      std::system((environment + " " + QUADRIX_EXECUTABLE + " " + arguments + " > '" + log.string() + "' 2>&1").c_str());
  CommandRun run;
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  run.output = read_text(log);
  return run;
}

/// Names of the entries of `folder` (sorted), to compare a folder before and after a run.
std::string listing(const fs::path& folder) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(folder)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  std::string text;
  for (const std::string& name : names) text += name + "\n";
  return text;
}

class DiskFaults : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    scratch_ = fs::temp_directory_path() / ("quadrix_disk_faults_" + std::to_string(std::random_device{}()));
    fs::create_directories(scratch_);
    // One street scan of the simulator (about 127,000 points, a few MB in binary PLY).
    const CommandRun synth = run_quadrix(scratch_, "synth street --seed 3 --sensor hdl64 --out '" + (scratch_ / "street").string() + "'");
    ASSERT_EQ(synth.exit_code, 0) << synth.output;
    scan_ = scratch_ / "street" / "scan_000.ply";
    ASSERT_TRUE(fs::exists(scan_));
  }
  static void TearDownTestSuite() {
    std::error_code ignored;
    fs::remove_all(scratch_, ignored);
  }
  static fs::path scratch_, scan_;
};
fs::path DiskFaults::scratch_;
fs::path DiskFaults::scan_;

TEST_F(DiskFaults, AModelOntoAReadOnlyFileSystemIsRefusedBeforeTheWorkAndKeepsTheOldFile) {
  SmallDisk disk("size=4m");
  if (!disk.mounted) GTEST_SKIP() << disk.why;
  const fs::path out = disk.mount / "model.json";
  std::ofstream(out) << "{\"a good model\": true}\n";
  ASSERT_TRUE(disk.make_read_only()) << std::strerror(errno);
  const CommandRun run = run_quadrix(scratch_, "model '" + scan_.string() + "' --no-page --out '" + out.string() + "'");
  EXPECT_EQ(run.exit_code, 2) << run.output;
  EXPECT_NE(run.output.find(out.string()), std::string::npos) << "the message names the output: " << run.output;
  EXPECT_EQ(run.output.find("internal error"), std::string::npos) << run.output;
  EXPECT_EQ(read_text(out), "{\"a good model\": true}\n");
  EXPECT_EQ(listing(disk.mount), "model.json\n");
}

TEST_F(DiskFaults, AModelOntoAFullDiskFailsWithoutAHalfFileAndKeepsTheOldOne) {
  // 64 KiB: the good file fits, the mesh of a street scan (megabytes) does not.
  SmallDisk disk("size=64k");
  if (!disk.mounted) GTEST_SKIP() << disk.why;
  const fs::path mesh = disk.mount / "mesh.ply";
  const std::string good = "ply\nformat ascii 1.0\nelement vertex 0\nend_header\n";
  std::ofstream(mesh) << good;
  const CommandRun run = run_quadrix(scratch_, "model '" + scan_.string() + "' --preset vlp64 --no-page --out '" +
                                            (scratch_ / "model.json").string() + "' --mesh '" + mesh.string() + "'");
  EXPECT_EQ(run.exit_code, 2) << run.output;
  EXPECT_NE(run.output.find(mesh.string()), std::string::npos) << "the message names the file: " << run.output;
  EXPECT_EQ(run.output.find("internal error"), std::string::npos) << run.output;
  EXPECT_EQ(read_text(mesh), good) << "the good file was changed";
  EXPECT_EQ(listing(disk.mount), "mesh.ply\n") << "a temporary file was left behind";
}

TEST_F(DiskFaults, TilesOnAFullDiskFailWithAMessageAndLeaveNoTileFolder) {
  // The tiles' temporary folder goes where TMPDIR says; 256 KiB holds a fraction of the scan's tiles.
  SmallDisk disk("size=256k");
  if (!disk.mounted) GTEST_SKIP() << disk.why;
  const fs::path out = scratch_ / "tiled.json";
  std::ofstream(out) << "{\"a good model\": true}\n";
  const CommandRun run = run_quadrix(scratch_, "model '" + scan_.string() + "' --preset monument --tile-size 20 --no-page --out '" + out.string() + "'",
                              "TMPDIR='" + disk.mount.string() + "'");
  EXPECT_EQ(run.exit_code, 2) << run.output;
  EXPECT_NE(run.output.find(disk.mount.string()), std::string::npos) << "the message names where the tiles went: " << run.output;
  EXPECT_EQ(run.output.find("internal error"), std::string::npos) << run.output;
  EXPECT_EQ(read_text(out), "{\"a good model\": true}\n");
  EXPECT_EQ(listing(disk.mount), "") << "the temporary tiles were left behind";
}

}  // namespace
}  // namespace quadrix
