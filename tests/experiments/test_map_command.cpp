// `quadrix map` on bad input: exit code 2, a message naming the row, and an existing output folder
// left as it was (nothing written half).
#include "geometry/io.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <sys/wait.h>
#include <unistd.h>

namespace quadrix {
namespace {

namespace fs = std::filesystem;

struct CommandOutput {
  int exit_code = -1;
  std::string text;
};

CommandOutput run(const std::string& arguments, const fs::path& folder) {
  const fs::path log = folder / "log.txt";
  const int status = std::system((std::string(QUADRIX_EXECUTABLE) + " " + arguments + " > " + log.string() + " 2>&1").c_str());
  CommandOutput output;
  output.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream stream(log);
  std::stringstream text;
  text << stream.rdbuf();
  output.text = text.str();
  return output;
}

void write_cloud(const fs::path& path, float scale) {
  PointCloud cloud;
  cloud.positions.resize(3, 300);
  std::mt19937 random(3);
  std::uniform_real_distribution<float> coordinate(-15.0f, 15.0f);
  for (int index = 0; index < 300; ++index) cloud.positions.col(index) = Eigen::Vector3f(coordinate(random), coordinate(random), 1.0f) * scale;
  write_point_cloud(path.string(), cloud);
}

TEST(MapCommand, BadInputExitsWithTwoNamesTheRowAndLeavesTheOutputAlone) {
  const fs::path folder = fs::temp_directory_path() / ("quadrix_map_command_" + std::to_string(::getpid()));
  fs::remove_all(folder);
  fs::create_directories(folder / "out");
  std::ofstream(folder / "out" / "poses.tsv") << "an earlier map\n";
  write_cloud(folder / "a.ply", 1.0f);
  write_cloud(folder / "b.ply", 1.0f);
  write_cloud(folder / "mm.ply", 1000.0f);
  const auto check = [&](const std::string& list, const std::string& expected) {
    std::ofstream(folder / "scans.tsv") << list;
    const CommandOutput output = run("map " + (folder / "scans.tsv").string() + " --out " + (folder / "out").string(), folder);
    EXPECT_EQ(output.exit_code, 2) << output.text;
    EXPECT_NE(output.text.find(expected), std::string::npos) << output.text;
    std::ifstream earlier(folder / "out" / "poses.tsv");
    std::string line;
    std::getline(earlier, line);
    EXPECT_EQ(line, "an earlier map") << "the output folder was touched";
  };
  const std::string header = "session\tscan\todometry\n";
  check(header + "s\ta.ply\t-\ns\tgone.ply\t-\n", "row 3: scan file");
  check(header + "s\ta.ply\t1 0 0 0\ns\tb.ply\t-\n", "row 2: odometry");
  check(header + "s\ta.ply\t-\nt\tb.ply\t-\n", "has one scan");
  check(header + "s\ta.ply\t-\ns\ta.ply\t-\n", "listed twice");
  check(header + "s\ta.ply\t-\ns\tmm.ply\t-\n", "row 3 (mm.ply)");
  fs::remove_all(folder);
}

}  // namespace
}  // namespace quadrix
