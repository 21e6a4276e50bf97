// The town drive: its truth is consistent with its odometry (no drift: the odometry's relative motion
// is the true one, and drift grows with the distance), it revisits streets both ways, a revisited
// street shows other parked cars and pedestrians, and the same seed writes the same files.
#include "experiments/synthetic/town_drive.h"
#include "geometry/constants.h"
#include "geometry/error.h"
#include "geometry/io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>
#include <string>
#include <unistd.h>

namespace quadrix {
namespace {

namespace fs = std::filesystem;

std::string text_of(const fs::path& path) {
  std::ifstream file(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
}

// Small and fast: sparse VLP-16 scans 25 m apart over 800 m per session.
TownDriveOptions small_drive(std::uint64_t seed) {
  TownDriveOptions options;
  options.seed = seed;
  options.sensors = {sensor_preset("vlp16"), sensor_preset("vlp16")};
  options.sensors[0].azimuth_steps = 600;
  options.sensors[1].azimuth_steps = 600;
  options.length = 800.0;
  options.scan_spacing = 25.0;
  return options;
}

double rotation_degrees(const Eigen::Isometry3d& pose) {
  return std::acos(std::clamp((pose.linear().trace() - 1.0) / 2.0, -1.0, 1.0)) * 180.0 / kPi;
}

TEST(TownDrive, WithoutDriftTheOdometryIsTheTrueRelativeMotion) {
  TownDriveOptions options;
  options.seed = 1001;
  options.drift = DriftModel{0.0, 0.0, 0.0, 0.0, 0.0};
  const TownDrivePlan plan = plan_town_drive(options);
  ASSERT_EQ(plan.session_lengths.size(), 3u);
  for (double length : plan.session_lengths) EXPECT_GE(length, 1000.0);  // the "at least 1 km"
  // The truth's frame is session 1's odometry frame: its first pose is the identity.
  EXPECT_LT((plan.scans.front().truth.matrix() - Eigen::Matrix4d::Identity()).norm(), 1e-12);
  for (std::size_t i = 0; i < plan.scans.size(); ++i) {
    const TownDriveScan& scan = plan.scans[i];
    const TownDriveScan& first = *std::find_if(plan.scans.begin(), plan.scans.end(),
                                               [&](const TownDriveScan& s) { return s.session == scan.session; });
    // odometry_i = truth_first^-1 * truth_i for every scan of every session.
    const Eigen::Isometry3d expected = first.truth.inverse() * scan.truth;
    EXPECT_LT((expected.matrix() - scan.odometry.matrix()).norm(), 1e-6) << "session " << scan.session << " scan " << scan.index;
    if (scan.session == 1) {
      EXPECT_LT((scan.truth.matrix() - scan.odometry.matrix()).norm(), 1e-6);
    }
  }
}

TEST(TownDrive, DriftGrowsWithDistanceAndDependsOnTheSeed) {
  TownDriveOptions options;  // the defaults: 1200 m per session, 2 m spacing
  for (const std::uint64_t seed : {1001u, 1002u}) {
    options.seed = seed;
    const TownDrivePlan plan = plan_town_drive(options);
    for (int session = 1; session <= 3; ++session) {
      std::vector<const TownDriveScan*> scans;
      for (const TownDriveScan& scan : plan.scans)
        if (scan.session == session) scans.push_back(&scan);
      // Position error of the odometry after a tenth and after all of the session, first pose aligned.
      const auto error_at = [&](std::size_t k) -> Eigen::Vector3d {  // a vector, not an Eigen expression of temporaries
        return (scans.front()->truth * scans[k]->odometry).translation() - scans[k]->truth.translation();
      };
      const double early = error_at(scans.size() / 10).norm(), late = error_at(scans.size() - 1).norm();
      EXPECT_GT(late, 3.0) << "seed " << seed << " session " << session;  // drift a loop closure must remove
      EXPECT_GT(late, 3.0 * early) << "seed " << seed << " session " << session;
    }
  }
  options.seed = 1001;
  const TownDrivePlan a = plan_town_drive(options);
  options.seed = 1002;
  const TownDrivePlan b = plan_town_drive(options);
  EXPECT_GT((a.scans.back().odometry.translation() - b.scans.back().odometry.translation()).norm(), 1.0);
}

TEST(TownDrive, RevisitsBothWaysAcrossAndWithinSessions) {
  TownDriveOptions options;
  options.seed = 2001;
  const TownDrivePlan plan = plan_town_drive(options);
  const auto [same, opposite] = count_revisits(plan, 10.0);
  EXPECT_GT(same, 20);
  EXPECT_GT(opposite, 20);
  // Session 1 alone closes a loop: it passes within 10 m of an earlier leg of its own.
  TownDrivePlan first_only = plan;
  first_only.scans.erase(std::remove_if(first_only.scans.begin(), first_only.scans.end(),
                                        [](const TownDriveScan& s) { return s.session != 1; }),
                         first_only.scans.end());
  const auto [own_same, own_opposite] = count_revisits(first_only, 10.0);
  EXPECT_GT(own_same + own_opposite, 5);
  // Consecutive scans are one spacing apart and the vehicle stays level and upright.
  for (std::size_t i = 1; i < plan.scans.size(); ++i) {
    if (plan.scans[i].session != plan.scans[i - 1].session) continue;
    const Eigen::Isometry3d step = plan.scans[i - 1].world.inverse() * plan.scans[i].world;
    EXPECT_NEAR(step.translation().norm(), options.scan_spacing, 1.2);
    EXPECT_LT(rotation_degrees(step), 30.0);
    EXPECT_GT(plan.scans[i].world.linear()(2, 2), std::cos(3.0 * kPi / 180.0));
  }
}

TEST(TownDrive, ARevisitedStreetHasOtherDynamicObjects) {
  TownDriveOptions options;
  options.seed = 1001;
  const TownDrivePlan plan = plan_town_drive(options);
  // The first leg that revisits a street, and the leg of that street's previous visit.
  int revisit = -1, previous = -1;
  for (int leg = 0; leg < static_cast<int>(plan.leg_streets.size()) && revisit < 0; ++leg)
    for (int earlier = leg - 1; earlier >= 0; --earlier)
      if (plan.leg_streets[static_cast<std::size_t>(earlier)] == plan.leg_streets[static_cast<std::size_t>(leg)]) {
        revisit = leg;
        previous = earlier;
        break;
      }
  ASSERT_GE(revisit, 0);
  const Scene before = town_scene(options, plan, previous);
  const Scene after = town_scene(options, plan, revisit);
  const std::string prefix = "street" + std::to_string(plan.leg_streets[static_cast<std::size_t>(revisit)]) + "_";
  const auto of = [&](const Scene& scene, bool dynamic) {
    std::set<std::string> names;
    for (const ScenePrimitive& p : scene.primitives) {
      const bool is_dynamic = p.label == SemanticLabel::Car || p.label == SemanticLabel::Person;
      if (p.name.rfind(prefix, 0) == 0 && is_dynamic == dynamic) {
        std::ostringstream key;  // where it stands: the same name at another place is another object
        key << p.name << '@' << std::round(p.pose.translation().x() * 10) << ',' << std::round(p.pose.translation().y() * 10);
        names.insert(key.str());
      }
    }
    return names;
  };
  EXPECT_EQ(of(before, false), of(after, false));  // buildings, road, poles and trees stay
  const std::set<std::string> dynamic_before = of(before, true), dynamic_after = of(after, true);
  std::size_t kept = 0;
  for (const std::string& name : dynamic_after) kept += dynamic_before.count(name);
  EXPECT_GT(dynamic_before.size(), 5u);
  EXPECT_LT(kept, dynamic_after.size() / 2) << "most parked cars and every pedestrian change between visits";
}

TEST(TownDrive, WritesTheSameFilesForTheSameSeed) {
  const fs::path root = fs::temp_directory_path() / ("quadrix_town_drive_" + std::to_string(getpid()));
  fs::remove_all(root);
  const TownDriveSummary a = write_town_drive((root / "a").string(), small_drive(1001));
  const TownDriveSummary b = write_town_drive((root / "b").string(), small_drive(1001));
  const TownDriveSummary c = write_town_drive((root / "c").string(), small_drive(1002));
  ASSERT_GT(a.plan.scans.size(), 60u);
  EXPECT_EQ(a.points, b.points);
  for (const char* name : {"SCANS.tsv", "truth.tsv"}) {
    EXPECT_EQ(text_of(root / "a" / name), text_of(root / "b" / name)) << name;
    EXPECT_NE(text_of(root / "a" / name), text_of(root / "c" / name)) << name;
  }
  for (const TownDriveScan& scan : a.plan.scans) {
    ASSERT_EQ(text_of(root / "a" / scan.file), text_of(root / "b" / scan.file)) << scan.file;
  }
  // The files parse back: header, one row per scan, 12 numbers; the clouds have points with labels.
  std::ifstream scans(root / "a" / "SCANS.tsv");
  std::string line;
  std::getline(scans, line);
  EXPECT_EQ(line, "session\tscan\todometry");
  std::size_t rows = 0;
  while (std::getline(scans, line)) {
    std::istringstream row(line);
    std::string session, file, odometry;
    std::getline(row, session, '\t');
    std::getline(row, file, '\t');
    std::getline(row, odometry, '\t');
    std::istringstream numbers(odometry);
    int count = 0;
    for (double value; numbers >> value;) ++count;
    EXPECT_EQ(count, 12) << line;
    EXPECT_TRUE(fs::exists(root / "a" / file)) << file;
    ++rows;
  }
  EXPECT_EQ(rows, a.plan.scans.size());
  const PointCloud cloud = read_point_cloud((root / "a" / a.plan.scans[5].file).string());
  EXPECT_GT(cloud.size(), 5000u);
  EXPECT_EQ(cloud.labels.size(), cloud.size());
  EXPECT_TRUE(fs::exists(root / "a" / "README.md"));
  // Odometry alone is far off after 800 m; the aligned error is smaller than the end error.
  EXPECT_GT(a.odometry_end_error[0], 1.0);
  fs::remove_all(root);
}

TEST(TownDrive, RefusesBadOptions) {
  TownDriveOptions options;
  options.sensors.clear();
  EXPECT_THROW(plan_town_drive(options), Error);
  options = TownDriveOptions{};
  options.scan_spacing = 0.0;
  EXPECT_THROW(plan_town_drive(options), Error);
  options = TownDriveOptions{};
  options.scans = 1;
  EXPECT_THROW(plan_town_drive(options), Error);
  options = TownDriveOptions{};
  options.drift.yaw_bias_deg_per_m = -1.0;
  EXPECT_THROW(plan_town_drive(options), Error);
}

}  // namespace
}  // namespace quadrix
