// The mapping baselines on a small simulated drive: odometry alone reproduces the drive's own
// odometry ATE, every output is in the map folder format the map page reads, and bad scan lists
// are refused naming the row.
#include "experiments/baselines/map_baselines.h"
#include "experiments/reports/map_page.h"
#include "experiments/synthetic/town_drive.h"
#include "geometry/error.h"
#include "geometry/scan_list.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

namespace quadrix {
namespace {

namespace fs = std::filesystem;

TEST(MapBaselines, OdometryAloneOnASimulatedDrive) {
  const fs::path root = fs::temp_directory_path() / ("quadrix_map_baselines_" + std::to_string(getpid()));
  fs::remove_all(root);
  TownDriveOptions drive;
  drive.seed = 1001;
  drive.sensors = {sensor_preset("vlp16")};
  drive.sensors[0].azimuth_steps = 600;
  drive.length = 600.0;
  drive.scan_spacing = 25.0;
  const TownDriveSummary written = write_town_drive((root / "drive").string(), drive);
  const MapBaselineSummary odometry = run_map_baseline("odometry", (root / "drive" / "SCANS.tsv").string(), (root / "odometry").string(),
                                                       (root / "drive" / "truth.tsv").string(), MapBaselineOptions{});
  EXPECT_EQ(odometry.scans, static_cast<int>(written.plan.scans.size()));
  ASSERT_EQ(odometry.ate.count("map"), 1u);
  EXPECT_NEAR(odometry.ate.at("map"), written.odometry_ate[0], 1e-6);
  EXPECT_GT(odometry.ate.at("map"), 0.1);
  EXPECT_EQ(odometry.wrong_used_edges, 0);
  // The folder is a map folder: the page reads its poses and edges (one odometry edge per step).
  ASSERT_TRUE(is_map_folder((root / "odometry").string()));
  const MapPageInput page = read_map_folder((root / "odometry").string());
  EXPECT_EQ(page.poses.size(), written.plan.scans.size());
  EXPECT_EQ(page.edges.size(), written.plan.scans.size() - 1);
  EXPECT_TRUE(fs::exists(root / "odometry" / "report.json"));
  EXPECT_THROW(run_map_baseline("gtsam", (root / "drive" / "SCANS.tsv").string(), (root / "x").string(), "", {}), Error);
  // A duplicate row is refused, naming its line.
  std::ifstream in(root / "drive" / "SCANS.tsv");
  std::string header, first;
  std::getline(in, header);
  std::getline(in, first);
  std::ofstream(root / "drive" / "BAD.tsv") << header << '\n' << first << '\n' << first << '\n';
  try {
    read_scan_list((root / "drive" / "BAD.tsv").string());
    ADD_FAILURE() << "a duplicate row was accepted";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("row 3: "), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("listed twice"), std::string::npos) << error.what();
  }
  fs::remove_all(root);
}

}  // namespace
}  // namespace quadrix
