// Output checks and whole-folder replacement (geometry/output_paths.h), called directly: what the
// commands and the Python functions that write a folder rely on, including the path where the work
// throws before the folder is committed.
#include "geometry/error.h"
#include "geometry/output_paths.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <stdexcept>
#include <string>
#include <sys/stat.h>
#include <unistd.h>

namespace quadrix {
namespace {

namespace fs = std::filesystem;

class OutputPaths : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() /
            ("quadrix_output_paths_" + std::to_string(::getpid()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    fs::create_directories(root_);
  }
  void TearDown() override { fs::remove_all(root_); }

  static void write(const fs::path& path, const std::string& text) {
    fs::create_directories(path.parent_path());
    std::ofstream(path) << text;
  }
  static std::string read(const fs::path& path) {
    std::ifstream in(path);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }
  // Names in `folder`, and whether its parent holds anything but `folder` itself (a staging leftover).
  static std::set<std::string> names(const fs::path& folder) {
    std::set<std::string> found;
    for (const auto& entry : fs::directory_iterator(folder)) found.insert(entry.path().filename().string());
    return found;
  }

  fs::path root_;
};

TEST_F(OutputPaths, AnExceptionBeforeCommitLeavesTheOldFolderAndNoStaging) {
  const fs::path out = root_ / "out";
  write(out / "report.json", "old report");
  write(out / "scan_000.ply", "old cloud");
  try {
    FolderReplacement folder("out", out.string(), {"report.json", "scan_*.ply"}, {});
    write(fs::path(folder.staging_folder()) / "report.json", "new report");
    throw std::runtime_error("the work failed midway");
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(read(out / "report.json"), "old report");
  EXPECT_EQ(read(out / "scan_000.ply"), "old cloud");
  EXPECT_EQ(names(root_), std::set<std::string>{"out"}) << "the staging folder beside it must be gone";
}

TEST_F(OutputPaths, CommitReplacesTheFolderWholeAndRemovesTheOldOne) {
  const fs::path out = root_ / "out";
  write(out / "report.json", "old report");
  write(out / "scan_001.ply", "a scan the new run does not write");
  FolderReplacement folder("out", out.string(), {"report.json", "scan_*.ply"}, {});
  write(folder.path("report.json"), "new report");
  write(folder.path("scan_000.ply"), "new cloud");
  EXPECT_EQ(read(out / "report.json"), "old report") << "nothing changes before commit";
  folder.commit();
  EXPECT_EQ(names(out), (std::set<std::string>{"report.json", "scan_000.ply"}));
  EXPECT_EQ(read(out / "report.json"), "new report");
  EXPECT_EQ(names(root_), std::set<std::string>{"out"});
}

TEST_F(OutputPaths, NothingStagedLeavesTheFolderAlone) {
  const fs::path out = root_ / "out";
  write(out / "report.json", "old report");
  {
    FolderReplacement folder("out", out.string(), {"report.json"}, {});
    folder.commit();
  }
  EXPECT_EQ(read(out / "report.json"), "old report");
}

TEST_F(OutputPaths, AForeignFolderOrOneHoldingAnInputIsRefusedBeforeTheWork) {
  const fs::path out = root_ / "out";
  write(out / "thesis.tex", "not ours");
  try {
    FolderReplacement folder("--out", out.string(), {"report.json"}, {});
    FAIL() << "a folder holding other files must be refused";
  } catch (const Error& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("--out"), std::string::npos) << message;
    EXPECT_NE(message.find("thesis.tex"), std::string::npos) << message;
  }
  EXPECT_EQ(read(out / "thesis.tex"), "not ours");

  const fs::path own = root_ / "own";
  write(own / "scan_000.ply", "an input");
  EXPECT_THROW(FolderReplacement("--out", own.string(), {"scan_*.ply"}, {(own / "scan_000.ply").string()}), Error);
  EXPECT_EQ(read(own / "scan_000.ply"), "an input");
}

TEST_F(OutputPaths, SharedFoldersKeepOtherFilesAndReplaceOnlyTheirOwn) {
  const fs::path out = root_ / "studies";
  write(out / "other.md", "someone else's");
  write(out / "refiners.md", "old");
  FolderReplacement folder("--out", out.string(), {"refiners.*"}, {}, FolderSharing::OwnFilesOnly);
  write(folder.path("refiners.md"), "new");
  write(folder.path("refiners.csv"), "new table");
  folder.commit();
  EXPECT_EQ(names(out), (std::set<std::string>{"other.md", "refiners.csv", "refiners.md"}));
  EXPECT_EQ(read(out / "refiners.md"), "new");
  EXPECT_EQ(read(out / "other.md"), "someone else's");
}

TEST_F(OutputPaths, OutputsThatAreNotRegularFilesOrAreInputsAreRefused) {
  const fs::path input = root_ / "scan.ply";
  write(input, "cloud");
  EXPECT_THROW(check_outputs({{"--out", input.string()}}, {input.string()}), Error);
  EXPECT_THROW(check_outputs({{"--out", root_.string()}}, {}), Error) << "a directory is no output file";
  const fs::path fifo = root_ / "fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_THROW(check_outputs({{"--out", fifo.string()}}, {}), Error);
  EXPECT_THROW(check_outputs({{"--out", (root_ / "a.json").string()}, {"--binary", (root_ / "a.json").string()}}, {}),
               Error)
      << "two outputs on one path";
  EXPECT_NO_THROW(check_outputs({{"--out", (root_ / "new" / "a.json").string()}, {"--mesh", ""}}, {input.string()}));
  EXPECT_EQ(read(input), "cloud");
}

}  // namespace
}  // namespace quadrix
