// Mapping: the scan list's checks on bad input (each an Error naming the row), the evaluation's
// metrics on known trajectories, and the whole pipeline on the real BALM walk with odometry drift
// added (seeded random walk plus a yaw bias): the ATE after the pose graph, no wrong used loop edge.
#include "estimation/mapping.h"
#include "geometry/error.h"
#include "geometry/io.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <functional>
#include <sstream>
#include <unistd.h>

namespace quadrix {
namespace {

namespace fs = std::filesystem;

constexpr double kPi = 3.14159265358979323846;

/// A fresh temporary folder, removed at the end of the test.
struct TemporaryFolder {
  fs::path path;
  TemporaryFolder() {
    path = fs::temp_directory_path() / ("quadrix_map_test_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TemporaryFolder() { fs::remove_all(path); }
};

void write(const fs::path& path, const std::string& text) {
  std::ofstream stream(path);
  stream << text;
}

/// A small cloud file (a box of points) for list tests that need scans to exist.
void write_cloud(const fs::path& path, double scale = 1.0) {
  PointCloud cloud;
  cloud.positions.resize(3, 400);
  std::mt19937 random(7);
  std::uniform_real_distribution<float> coordinate(-20.0f, 20.0f);
  for (int index = 0; index < 400; ++index)
    cloud.positions.col(index) = Eigen::Vector3f(coordinate(random), coordinate(random), coordinate(random) * 0.1f) * static_cast<float>(scale);
  write_point_cloud(path.string(), cloud);
}

const std::string kIdentity = "1 0 0 0 0 1 0 0 0 0 1 0";

std::string error_of(const std::function<void()>& action) {
  try {
    action();
  } catch (const Error& error) {
    return error.what();
  }
  return "";
}

TEST(ScanList, ReadsSessionsOdometryAndPathsRelativeToTheList) {
  TemporaryFolder folder;
  write_cloud(folder.path / "a.ply");
  write_cloud(folder.path / "b.ply");
  write(folder.path / "scans.tsv", "session\tscan\todometry\nwalk\ta.ply\t" + kIdentity + "\nwalk\tb.ply\t1 0 0 2 0 1 0 0 0 0 1 0\n"
                                   "car\tb.ply\t-\ncar\ta.ply\t-\n");
  const ScanList list = read_scan_list((folder.path / "scans.tsv").string());
  ASSERT_EQ(list.scans.size(), 4u);
  EXPECT_EQ(list.sessions, (std::vector<std::string>{"walk", "car"}));
  EXPECT_EQ(list.scans[1].path, (folder.path / "b.ply").string());
  ASSERT_TRUE(list.scans[1].odometry.has_value());
  EXPECT_NEAR(list.scans[1].odometry->translation().x(), 2.0, 1e-12);
  EXPECT_FALSE(list.scans[2].odometry.has_value());
  EXPECT_EQ(list.scans[3].row, 5u);
}

TEST(ScanList, BadInputIsAnErrorNamingTheRow) {
  TemporaryFolder folder;
  write_cloud(folder.path / "a.ply");
  write_cloud(folder.path / "b.ply");
  const fs::path list = folder.path / "scans.tsv";
  const auto check = [&](const std::string& text, const std::string& expected) {
    write(list, text);
    const std::string message = error_of([&] { read_scan_list(list.string()); });
    EXPECT_NE(message.find(expected), std::string::npos) << "message: '" << message << "' lacks '" << expected << "'";
  };
  const std::string header = "session\tscan\todometry\n";
  check(header + "s\ta.ply\t-\ns\tmissing.ply\t-\n", "row 3: scan file");
  check(header + "s\ta.ply\t1 0 0\ns\tb.ply\t-\n", "row 2: odometry: expected 12 numbers");
  check(header + "s\ta.ply\t1 0 0 0 0 1 0 0 0 0 1 x\ns\tb.ply\t" + kIdentity + "\n", "row 2: odometry: pose number 12");
  check(header + "s\ta.ply\t2 0 0 0 0 1 0 0 0 0 1 0\ns\tb.ply\t" + kIdentity + "\n", "not a rotation");
  check(header + "s\ta.ply\t-\ns\tb.ply\t-\nt\ta.ply\t-\n", "row 4: session 't' has one scan");
  check(header + "s\ta.ply\t-\ns\ta.ply\t-\n", "row 3: scan 'a.ply' of session 's' is listed twice");
  check(header + "s\ta.ply\t-\ns\tb.ply\t" + kIdentity + "\n", "row 3: session 's' gives odometry on some rows");
  check(header + "s\ta.ply\t-\nt\ta.ply\t-\nt\tb.ply\t-\ns\tb.ply\t-\n", "row 5: session 's' continues");
  check("scan\todometry\n", "row 1: expected a header");
}

TEST(ScanList, ScansInMillimetresAreAnErrorAndNothingIsWritten) {
  TemporaryFolder folder;
  write_cloud(folder.path / "a.ply", 1000.0);
  write_cloud(folder.path / "b.ply", 1000.0);
  write(folder.path / "scans.tsv", "session\tscan\todometry\ns\ta.ply\t-\ns\tb.ply\t-\n");
  const ScanList list = read_scan_list((folder.path / "scans.tsv").string());
  const std::string message = error_of([&] { map_scans(list); });
  EXPECT_NE(message.find("row 2 (a.ply)"), std::string::npos) << message;
  EXPECT_NE(message.find("millimetres"), std::string::npos) << message;
}

TEST(PoseTable, ReadsOneColumnOrTwelveAndIgnoresTheFrame) {
  TemporaryFolder folder;
  write(folder.path / "poses.tsv", "session\tscan\tpose\tframe\ns\ta.ply\t1 0 0 3 0 1 0 0 0 0 1 0\tmap\n");
  write(folder.path / "wide.tsv", "session\tscan\tr00\tr01\tr02\tt0\tr10\tr11\tr12\tt1\tr20\tr21\tr22\tt2\n"
                                  "s\ta.ply\t1\t0\t0\t3\t0\t1\t0\t0\t0\t0\t1\t0\n");
  for (const char* name : {"poses.tsv", "wide.tsv"}) {
    const std::vector<PoseRow> rows = read_pose_table((folder.path / name).string());
    ASSERT_EQ(rows.size(), 1u) << name;
    EXPECT_NEAR(rows[0].pose.translation().x(), 3.0, 1e-12) << name;
  }
  write(folder.path / "bad.tsv", "session\tscan\tpose\ns\ta.ply\t1 0 0\n");
  EXPECT_NE(error_of([&] { read_pose_table((folder.path / "bad.tsv").string()); }).find("row 2"), std::string::npos);
}

TEST(MapEvaluation, UmeyamaRecoversARigidMotionAndKittiErrorIsZeroOnTheTruth) {
  std::mt19937 random(5);
  std::normal_distribution<double> noise(0.0, 10.0);
  Eigen::Matrix3Xd points(3, 20);
  for (int index = 0; index < 20; ++index) points.col(index) = Eigen::Vector3d(noise(random), noise(random), noise(random));
  Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
  motion.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  motion.translation() = Eigen::Vector3d(4, -2, 9);
  const Eigen::Isometry3d found = umeyama_alignment(points, motion * points);
  EXPECT_TRUE(found.isApprox(motion, 1e-9));

  std::vector<Eigen::Isometry3d> truth, biased;
  for (int index = 0; index <= 300; ++index) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Eigen::Vector3d(index, 0, 0);
    truth.push_back(pose);
    pose.translation() = Eigen::Vector3d(1.01 * index, 0, 0);  // 1 % scale error
    biased.push_back(pose);
  }
  const auto [zero, zero_rotation, segments] = kitti_relative_error(truth, truth);
  EXPECT_EQ(zero, 0.0);
  EXPECT_GT(segments, 0u);
  EXPECT_NEAR(std::get<0>(kitti_relative_error(biased, truth)), 1.0, 1e-6);
}

TEST(MapEvaluation, ReturnsAreLoopsNotTheScansJustBehind) {
  // A square block of 4 x 100 m driven once, 5 m a scan, then 30 m more along its first side: the
  // scans of that last stretch return to the start, those before only have scans behind them.
  MapResult result;
  std::vector<PoseRow> truth;
  const auto at = [](double s) {
    const int side = std::min(3, static_cast<int>(s / 100.0));
    const double along = s - 100.0 * side;
    const Eigen::Vector3d corners[4] = {{0, 0, 0}, {100, 0, 0}, {100, 100, 0}, {0, 100, 0}};
    const Eigen::Vector3d directions[4] = {{1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}};
    return s >= 400.0 ? Eigen::Vector3d(s - 400.0, 0, 0) : Eigen::Vector3d(corners[side] + along * directions[side]);
  };
  for (int index = 0; index <= 86; ++index) {  // 0 .. 430 m
    ScanEntry entry;
    entry.session = "a";
    entry.scan = std::to_string(index) + ".ply";
    result.list.scans.push_back(entry);
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = at(5.0 * index);
    result.poses.push_back(pose);
    result.odometry.push_back(pose);
    result.in_map_frame.push_back(true);
    truth.push_back({"a", entry.scan, pose, ""});
  }
  result.list.sessions = {"a"};
  const auto loop = [&](std::size_t from, std::size_t to, const Eigen::Isometry3d& error) {
    MapEdge edge;
    edge.from = from, edge.to = to, edge.kind = MapEdgeKind::Loop, edge.status = "ok", edge.used = true;
    edge.transform = error * result.poses[to].inverse() * result.poses[from];
    result.edges.push_back(edge);
  };
  loop(10, 6, Eigen::Isometry3d::Identity());   // 20 m behind on the same street: no loop
  loop(82, 2, Eigen::Isometry3d::Identity());   // 410 m back at the start, 0 m apart: a return closed
  Eigen::Isometry3d wrong = Eigen::Isometry3d::Identity();
  wrong.translation() = Eigen::Vector3d(3, 0, 0);
  loop(84, 3, wrong);                           // a return, but the edge is 3 m off: not closed
  const MapEvaluation evaluation = evaluate_map(result, truth, 30.0, 15.0);
  // Returns: the last side's final 30 m (scans 74..80, within 30 m of the start, which the path
  // left around the block) and the second pass over the first side (81..86): 13. The corners are
  // none: every scan between a corner's two sides stays within 30 m.
  EXPECT_EQ(evaluation.returns, 13u);
  EXPECT_EQ(evaluation.closed_returns, 1u) << "only the right edge to an earlier pass closes a return";
  EXPECT_EQ(evaluation.wrong_used_loop_edges, 1u);
  EXPECT_GT(evaluation.true_revisits, 70u) << "the older count takes nearly every scan as a revisit";
}

/// The BALM walk as a scan list with odometry that drifts: each step of the true motion is followed
/// by a yaw of `yaw_bias_degrees` per metre plus noise (seeded), integrated from the first pose.
struct DriftedWalk {
  ScanList list;
  std::vector<PoseRow> truth;
};

/// The shared BALM walk's scans and true poses (poses.txt: a cloud name and 12 numbers a line, the
/// rotation made orthonormal), in walk order.
std::vector<std::pair<std::string, Eigen::Isometry3d>> read_balm_walk(const std::string& root) {
  std::ifstream poses(root + "/poses.txt");
  std::vector<std::pair<std::string, Eigen::Isometry3d>> walk;
  std::string line;
  while (std::getline(poses, line)) {
    std::istringstream fields(line);
    std::string name;
    fields >> name;
    Eigen::Matrix<double, 3, 4> matrix;
    for (int k = 0; k < 12; ++k) fields >> matrix(k / 4, k % 4);
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(matrix.leftCols<3>(), Eigen::ComputeFullU | Eigen::ComputeFullV);
    pose.linear() = svd.matrixU() * svd.matrixV().transpose();
    pose.translation() = matrix.col(3);
    walk.emplace_back(name, pose);
  }
  return walk;
}

/// Writes every `stride`-th point of the cloud `source` to `destination` (a shorter test, same geometry).
void write_thinned(const std::string& source, const std::string& destination, Eigen::Index stride) {
  const PointCloud cloud = read_point_cloud(source);
  PointCloud thinned;
  thinned.positions.resize(3, (static_cast<Eigen::Index>(cloud.size()) + stride - 1) / stride);
  for (Eigen::Index k = 0; k < thinned.positions.cols(); ++k) thinned.positions.col(k) = cloud.positions.col(stride * k);
  write_point_cloud(destination, thinned);
}

DriftedWalk drifted_balm(const fs::path& folder, unsigned seed, std::size_t first, std::size_t count, double yaw_bias_degrees,
                         bool with_odometry = true) {
  const std::string root = testing::shared_data_path("balm_sequence");
  const std::vector<std::pair<std::string, Eigen::Isometry3d>> walk = read_balm_walk(root);
  std::mt19937 random(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::ostringstream list;
  list << "session\tscan\todometry\n";
  DriftedWalk result;
  Eigen::Isometry3d odometry = walk[first].second;
  for (std::size_t index = first; index < std::min(walk.size(), first + count); ++index) {
    if (index > first) {
      Eigen::Isometry3d step = walk[index - 1].second.inverse() * walk[index].second;
      const double length = step.translation().norm();
      Eigen::Isometry3d error = Eigen::Isometry3d::Identity();
      error.linear() = (Eigen::AngleAxisd(kPi / 180 * (yaw_bias_degrees * length + 0.3 * noise(random)), Eigen::Vector3d::UnitZ()) *
                        Eigen::AngleAxisd(kPi / 180 * 0.2 * noise(random), Eigen::Vector3d::UnitX()))
                           .toRotationMatrix();
      error.translation() = (0.02 + 0.03 * length) * Eigen::Vector3d(noise(random), noise(random), 0.3 * noise(random));
      odometry = odometry * step * error;
    }
    list << "walk\t" << root << "/" << walk[index].first << "\t";
    for (int k = 0; k < 12; ++k)
      if (with_odometry) list << (k ? " " : "") << odometry.matrix()(k / 4, k % 4);
    list << (with_odometry ? "\n" : "-\n");
    result.truth.push_back({"walk", root + "/" + walk[index].first, walk[index].second, ""});
  }
  write(folder / "scans.tsv", list.str());
  result.list = read_scan_list((folder / "scans.tsv").string());
  return result;
}

TEST(MappingBalm, DriftedWalkIsClosedWithinFifteenCentimetres) {
  QUADRIX_REQUIRE_SHARED_DATA("balm_sequence/poses.txt");
  TemporaryFolder folder;
  const DriftedWalk walk = drifted_balm(folder.path, 2026, 0, 44, 0.5);
  MapOptions options;
  options.loop_radius = 8.0;  // fewer candidate pairs than the default radius gives: the test stays near a minute
  const MapResult result = map_scans(walk.list, options);
  const MapEvaluation evaluation = evaluate_map(result, walk.truth);
  std::printf("BALM, 44 scans: ATE %.3f m (odometry %.3f m); loop edges used %zu, wrong %zu; ok %zu wrong %zu; recall %zu/%zu; %.0f ms a scan\n",
              evaluation.ate, evaluation.ate_odometry, evaluation.used_loop_edges, evaluation.wrong_used_loop_edges,
              evaluation.ok_loop_edges, evaluation.wrong_ok_loop_edges, evaluation.closed_revisits, evaluation.true_revisits,
              result.timings_ms.at("total") / result.list.scans.size());
  EXPECT_GT(evaluation.ate_odometry, 1.0) << "the added drift should matter";
  EXPECT_LE(evaluation.ate, 0.15);
  EXPECT_EQ(evaluation.wrong_used_loop_edges, 0u);
  EXPECT_GT(evaluation.used_loop_edges, 0u);
  // The files: all there, and a second write replaces the first.
  write_map((folder.path / "map").string(), result, options, map_evaluation_json(evaluation));
  for (const char* name : {"poses.tsv", "edges.csv", "report.json", "map.ply", "map_model.qsm"})
    EXPECT_TRUE(fs::exists(folder.path / "map" / name)) << name;
  const std::vector<PoseRow> written = read_pose_table((folder.path / "map" / "poses.tsv").string());
  ASSERT_EQ(written.size(), walk.list.scans.size());
  EXPECT_TRUE(written.back().pose.isApprox(result.poses.back(), 1e-6));
  EXPECT_EQ(written.back().frame, "map");
}

TEST(MappingBalm, WithoutOdometryConsecutiveScansAreRegistered) {
  QUADRIX_REQUIRE_SHARED_DATA("balm_sequence/poses.txt");
  TemporaryFolder folder;
  // Ten scans of the walk once it moves (about 2 m apart), with no odometry at all.
  const DriftedWalk walk = drifted_balm(folder.path, 1, 6, 10, 0.0, false);
  ASSERT_FALSE(walk.list.scans[1].odometry.has_value());
  const MapResult result = map_scans(walk.list);
  std::size_t answered = 0;
  for (const MapEdge& edge : result.edges)
    if (edge.kind == MapEdgeKind::Odometry) answered += edge.status == "ok" || edge.status == "ambiguous";
  EXPECT_EQ(answered, 9u);
  const MapEvaluation evaluation = evaluate_map(result, walk.truth);
  std::printf("BALM without odometry, 10 scans: registered odometry ATE %.3f m, map ATE %.3f m\n", evaluation.ate_odometry, evaluation.ate);
  EXPECT_LE(evaluation.ate_odometry, 0.3);
}

/// A two-session scan list from the BALM walk for executor tests: session `a` (the first `with_odometry`
/// scans once the walk moves, with their true poses as odometry) and session `b` (the next
/// `without_odometry` scans, no odometry: registered scan to scan), every cloud thinned to every
/// other point to keep the test short.
ScanList two_session_walk(const fs::path& folder, std::size_t with_odometry, std::size_t without_odometry) {
  const std::string root = testing::shared_data_path("balm_sequence");
  std::ifstream poses(root + "/poses.txt");
  std::ostringstream list;
  list << "session\tscan\todometry\n";
  std::string line;
  for (std::size_t index = 0; std::getline(poses, line) && index < 6 + with_odometry + without_odometry; ++index) {
    if (index < 6) continue;  // the walk stands still at first
    std::istringstream fields(line);
    std::string name, pose;
    fields >> name;
    std::getline(fields, pose);
    write_thinned(root + "/" + name, (folder / (name + ".ply")).string(), 2);
    const bool odometry = index < 6 + with_odometry;
    list << (odometry ? "a" : "b") << "\t" << name << ".ply\t" << (odometry ? pose.substr(1) : "-") << "\n";
  }
  write(folder / "scans.tsv", list.str());
  return read_scan_list((folder / "scans.tsv").string());
}

TEST(MappingExecutor, AnotherExecutorSeesTheBatchesAndGivesTheSameMap) {
  QUADRIX_REQUIRE_SHARED_DATA("balm_sequence/poses.txt");
  TemporaryFolder folder;
  const ScanList list = two_session_walk(folder.path, 5, 3);
  MapOptions options;
  options.minimum_loop_travel = 3.0;  // loop candidates within the short session `a`
  options.candidates_per_scan = 1;
  options.place_candidates_per_scan = 1;
  const MapResult in_process = map_scans(list, options);

  // An executor that does what a remote worker does, passing models and edges through their bytes.
  std::vector<std::vector<std::size_t>> model_batches;
  std::vector<std::vector<MapPairRequest>> pair_batches;
  std::vector<std::string> stored(list.scans.size());
  MapExecutor executor;
  executor.model = [&](const std::vector<std::size_t>& scans) {
    model_batches.push_back(scans);
    std::vector<MappedScan> models;
    for (std::size_t scan : scans) {
      stored[scan] = mapped_scan_to_bytes(model_map_scan(list, scan, options));
      models.push_back(mapped_scan_from_bytes(stored[scan]));
    }
    return models;
  };
  executor.register_pairs = [&](const std::vector<MapPairRequest>& pairs) {
    pair_batches.push_back(pairs);
    std::vector<MapEdge> edges;
    for (const MapPairRequest& pair : pairs)
      edges.push_back(map_edge_from_bytes(map_edge_to_bytes(register_map_pair(
          list, pair, mapped_scan_from_bytes(stored[pair.from]), mapped_scan_from_bytes(stored[pair.to]), options))));
    return edges;
  };
  const MapResult elsewhere = map_scans(list, options, {}, executor);
  // Models made elsewhere carry no registration options: registering their pairs here is refused.
  MapExecutor models_only;
  models_only.model = executor.model;
  EXPECT_THROW(map_scans(list, options, {}, models_only), Error);

  // Batches: every scan modelled at once; the chain of session b one pair at a time in time order,
  // each from its local guess; within session a, one batch per scan; across, one batch of all.
  ASSERT_EQ(model_batches.size(), 1u);
  EXPECT_EQ(model_batches[0], std::vector<std::size_t>({0, 1, 2, 3, 4, 5, 6, 7}));
  ASSERT_GE(pair_batches.size(), 4u);
  for (std::size_t k = 0; k < 2; ++k) {
    ASSERT_EQ(pair_batches[k].size(), 1u);
    EXPECT_EQ(pair_batches[k][0].from, 6 + k);
    EXPECT_EQ(pair_batches[k][0].to, 5 + k);
    EXPECT_TRUE(pair_batches[k][0].local_guess.has_value());
    EXPECT_EQ(pair_batches[k][0].kind, MapEdgeKind::Odometry);
  }
  for (std::size_t k = 2; k + 1 < pair_batches.size(); ++k) {
    ASSERT_EQ(pair_batches[k].size(), 1u);  // candidates_per_scan
    EXPECT_LT(pair_batches[k][0].from, 5u);
    EXPECT_LT(pair_batches[k][0].to, pair_batches[k][0].from);
    EXPECT_FALSE(pair_batches[k][0].local_guess.has_value());
  }
  EXPECT_GT(pair_batches.size(), 3u) << "session a should have loop candidates";
  // Across sessions: the place candidates in one batch (one for each scan of b), then one batch a
  // round of the joint-frame search.
  std::size_t across = 2;
  while (across < pair_batches.size() && pair_batches[across][0].from < 5u) ++across;
  ASSERT_LT(across, pair_batches.size());
  ASSERT_EQ(pair_batches[across].size(), 3u);
  std::size_t joint_batches = 0;
  for (const JointRound& round : in_process.joint_rounds) joint_batches += round.registered > 0;
  EXPECT_EQ(pair_batches.size() - across - 1, joint_batches);
  for (std::size_t k = across; k < pair_batches.size(); ++k)
    for (const MapPairRequest& pair : pair_batches[k]) {
      EXPECT_GE(pair.from, 5u);
      EXPECT_LT(pair.to, 5u);
      EXPECT_FALSE(pair.local_guess.has_value());
    }

  // The same map.
  ASSERT_EQ(elsewhere.edges.size(), in_process.edges.size());
  for (std::size_t k = 0; k < in_process.edges.size(); ++k) {
    const MapEdge &a = in_process.edges[k], &b = elsewhere.edges[k];
    EXPECT_EQ(a.from, b.from);
    EXPECT_EQ(a.to, b.to);
    EXPECT_EQ(a.kind, b.kind);
    EXPECT_EQ(a.status, b.status) << k;
    EXPECT_EQ(a.used, b.used) << k;
    EXPECT_EQ(a.across_sessions, b.across_sessions);
    EXPECT_TRUE(a.transform.matrix().isApprox(b.transform.matrix(), 1e-12)) << k;
    EXPECT_EQ(a.information, b.information) << k;
  }
  ASSERT_EQ(elsewhere.poses.size(), in_process.poses.size());
  for (std::size_t k = 0; k < in_process.poses.size(); ++k)
    EXPECT_LE((in_process.poses[k].matrix() - elsewhere.poses[k].matrix()).cwiseAbs().maxCoeff(), 1e-9) << k;
  EXPECT_EQ(elsewhere.presets, in_process.presets);
  EXPECT_EQ(elsewhere.place_ranking, in_process.place_ranking);
  EXPECT_EQ(elsewhere.joint_candidates, in_process.joint_candidates);
}

/// Two sessions over the same stretch of the BALM walk (scans 6-21): `a` the even scans with their
/// true poses as odometry, `b` the odd ones with a yaw drift of `yaw_bias_degrees` per metre (plus
/// seeded noise) in a frame of their own (turned by 1 rad and shifted 30 m); clouds thinned to a
/// third. `truth` in the map frame (a's).
DriftedWalk interleaved_sessions(const fs::path& folder, double yaw_bias_degrees, unsigned seed) {
  const std::string root = testing::shared_data_path("balm_sequence");
  std::ostringstream list;
  list << "session\tscan\todometry\n";
  std::mt19937 random(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  Eigen::Isometry3d own_frame = Eigen::Isometry3d::Identity();
  own_frame.linear() = Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  own_frame.translation() = Eigen::Vector3d(30.0, -12.0, 2.0);
  DriftedWalk result;
  const std::vector<std::pair<std::string, Eigen::Isometry3d>> whole = read_balm_walk(root);
  // Scans 6-21: the walk stands still at first.
  const std::vector<std::pair<std::string, Eigen::Isometry3d>> walk(whole.begin() + 6, whole.begin() + std::min<std::size_t>(22, whole.size()));
  for (const auto& [name, pose] : walk) write_thinned(root + "/" + name, (folder / (name + ".ply")).string(), 3);
  for (const std::string session : {"a", "b"}) {
    Eigen::Isometry3d odometry = Eigen::Isometry3d::Identity();
    std::size_t previous = walk.size();
    for (std::size_t index = session == "a" ? 0 : 1; index < walk.size(); index += 2) {
      if (previous == walk.size()) {
        odometry = session == "a" ? walk[index].second : own_frame;
      } else if (session == "a") {
        odometry = walk[index].second;
      } else {
        const Eigen::Isometry3d step = walk[previous].second.inverse() * walk[index].second;
        const double length = step.translation().norm();
        Eigen::Isometry3d error = Eigen::Isometry3d::Identity();
        error.linear() = Eigen::AngleAxisd(kPi / 180 * (yaw_bias_degrees * length + 0.3 * noise(random)), Eigen::Vector3d::UnitZ())
                             .toRotationMatrix();
        error.translation() = (0.02 + 0.03 * length) * Eigen::Vector3d(noise(random), noise(random), 0.3 * noise(random));
        odometry = odometry * step * error;
      }
      previous = index;
      list << session << "\t" << walk[index].first << ".ply\t";
      for (int k = 0; k < 12; ++k) list << (k ? " " : "") << odometry.matrix()(k / 4, k % 4);
      list << "\n";
      result.truth.push_back({session, walk[index].first + ".ply", walk[index].second, ""});
    }
  }
  write(folder / "scans.tsv", list.str());
  result.list = read_scan_list((folder / "scans.tsv").string());
  return result;
}

/// Options for the interleaved sessions that register only what joins them: no loops within a
/// session, one place candidate for every `stride`-th scan, no joint-frame rounds.
MapOptions edges_across_only(std::size_t stride) {
  MapOptions options;
  options.minimum_loop_travel = 1000.0;
  options.place_candidates_per_scan = 1;
  options.place_query_stride = stride;
  options.joint_rounds = 0;
  return options;
}

// Two sessions that the place descriptor joins by few edges (every fourth scan of b queries it):
// the radius search in the joint map frame, once b is placed, registers each of b's scans with its
// neighbour in a, so b is held along its whole path instead of at its anchors.
TEST(MappingJointFrame, RadiusSearchAfterPlacementJoinsSessionsAlongTheirPath) {
  QUADRIX_REQUIRE_SHARED_DATA("balm_sequence/poses.txt");
  TemporaryFolder folder;
  const DriftedWalk walk = interleaved_sessions(folder.path, 0.7, 5);
  MapOptions options = edges_across_only(4);
  const MapResult placed_only = map_scans(walk.list, options);
  options.joint_rounds = 3;
  const MapResult joint = map_scans(walk.list, options);
  const MapEvaluation before = evaluate_map(placed_only, walk.truth);
  const MapEvaluation after = evaluate_map(joint, walk.truth);
  const auto right_across = [&](const MapResult& result) {
    std::size_t right = 0;
    for (const MapEdge& edge : result.edges)
      if (edge.used && edge.across_sessions)
        right += registration_succeeded(edge.transform, walk.truth[edge.to].pose.inverse() * walk.truth[edge.from].pose);
    return right;
  };
  std::printf("two interleaved sessions: place candidates only: ATE %.3f m, %zu right used edges across; with the joint-frame "
              "search (%zu rounds): ATE %.3f m, %zu right used edges across; odometry %.3f m; wrong used %zu / %zu\n",
              before.ate, right_across(placed_only), joint.joint_rounds.size(), after.ate, right_across(joint), before.ate_odometry,
              before.wrong_used_loop_edges, after.wrong_used_loop_edges);
  EXPECT_TRUE(placed_only.joint_rounds.empty());
  ASSERT_FALSE(joint.joint_rounds.empty());
  EXPECT_TRUE(placed_only.in_map_frame.back()) << "the place candidates alone should place b";
  EXPECT_GT(right_across(joint), right_across(placed_only) + 3);
  EXPECT_EQ(after.wrong_used_loop_edges, 0u);
  EXPECT_LT(after.ate, before.ate);
  EXPECT_LE(after.ate, 0.15);
  EXPECT_GT(before.ate, 0.2) << "b's drift should matter when it is held at two scans only";
  // Place recognition: every scan of b searched, its neighbour in a among the joint-frame candidates.
  EXPECT_EQ(after.joint_place_queries, 8u);
  EXPECT_EQ(after.joint_place_hits, after.joint_place_queries);
  EXPECT_EQ(before.joint_place_hits, before.place_hits);
  // The information calibration: a group per session's odometry and per pair of sessions' loop
  // edges, each with finite positive factors, and at least one round solved.
  std::set<std::string> names;
  for (const InformationGroup& group : joint.information_groups) {
    names.insert(group.name);
    EXPECT_TRUE(std::isfinite(group.rotation_factor) && group.rotation_factor > 0.0) << group.name;
    EXPECT_TRUE(std::isfinite(group.translation_factor) && group.translation_factor > 0.0) << group.name;
  }
  EXPECT_EQ(names, (std::set<std::string>{"odometry a", "odometry b", "loop a-b"}));
  EXPECT_FALSE(joint.calibration_costs.empty());
  EXPECT_LE(joint.calibration_costs.size(), MapOptions{}.information_rounds);
}

// Edges between two sessions must agree: the first place-descriptor pair between the interleaved
// sessions is answered `ok` but turned by 180 deg and shifted 100 m (what a look-alike street gives
// across sensors). The relative pose of the sessions the right edges agree on does not predict it,
// so it leaves the graph and b is placed by the right ones; with the consensus gate opened it is
// used, and the map is wrong.
TEST(MappingPlaceConsensus, AWrongOkEdgeBetweenSessionsThatTheOthersContradictLeavesTheGraph) {
  QUADRIX_REQUIRE_SHARED_DATA("balm_sequence/poses.txt");
  TemporaryFolder folder;
  const DriftedWalk walk = interleaved_sessions(folder.path, 0.7, 5);
  MapOptions options = edges_across_only(2);
  std::vector<std::string> stored(walk.list.scans.size());
  bool corrupted = false;
  std::pair<std::size_t, std::size_t> corrupted_pair;
  MapExecutor executor;
  executor.model = [&](const std::vector<std::size_t>& scans) {
    std::vector<MappedScan> models;
    for (std::size_t scan : scans) {
      stored[scan] = mapped_scan_to_bytes(model_map_scan(walk.list, scan, options));
      models.push_back(mapped_scan_from_bytes(stored[scan]));
    }
    return models;
  };
  executor.register_pairs = [&](const std::vector<MapPairRequest>& pairs) {
    std::vector<MapEdge> edges;
    for (const MapPairRequest& pair : pairs) {
      edges.push_back(register_map_pair(walk.list, pair, mapped_scan_from_bytes(stored[pair.from]),
                                        mapped_scan_from_bytes(stored[pair.to]), options));
      if (!corrupted && walk.list.scans[pair.from].session != walk.list.scans[pair.to].session) {
        Eigen::Isometry3d turn = Eigen::Isometry3d::Identity();
        turn.linear() = Eigen::AngleAxisd(kPi, Eigen::Vector3d::UnitZ()).toRotationMatrix();
        turn.translation() = Eigen::Vector3d(100.0, 0.0, 0.0);
        edges.back().transform = turn * edges.back().transform;
        edges.back().status = "ok";
        corrupted = true;
        corrupted_pair = {pair.from, pair.to};
      }
    }
    return edges;
  };
  const MapResult checked = map_scans(walk.list, options, {}, executor);
  ASSERT_TRUE(corrupted);
  const auto wrong_edge = [&](const MapResult& result) -> const MapEdge& {
    for (const MapEdge& edge : result.edges)
      if (edge.kind == MapEdgeKind::Loop && edge.from == corrupted_pair.first && edge.to == corrupted_pair.second) return edge;
    throw Error("the corrupted edge is missing");
  };
  const MapEvaluation evaluation = evaluate_map(checked, walk.truth);
  std::size_t right_used_across = 0;
  for (const MapEdge& edge : checked.edges)
    if (edge.used && edge.across_sessions)
      right_used_across += registration_succeeded(edge.transform, walk.truth[edge.to].pose.inverse() * walk.truth[edge.from].pose);
  std::printf("place consensus: corrupted edge used %d (%s); %zu right edges across used; ATE %.3f m; wrong used %zu\n",
              wrong_edge(checked).used, wrong_edge(checked).note.c_str(), right_used_across, evaluation.ate, evaluation.wrong_used_loop_edges);
  EXPECT_FALSE(wrong_edge(checked).used);
  EXPECT_NE(wrong_edge(checked).note.find("departs by"), std::string::npos) << wrong_edge(checked).note;
  EXPECT_GE(right_used_across, 2u);
  EXPECT_TRUE(checked.in_map_frame.back()) << "the right edges should place b";
  EXPECT_EQ(evaluation.wrong_used_loop_edges, 0u);
  EXPECT_LE(evaluation.ate, 0.4);
  // The gate opened: the outlier test on the calibrated graph catches the wrong edge after the solve.
  options.place_consensus_rotation_degrees = 360.0;
  options.place_consensus_translation = 1e9;
  corrupted = false;
  const MapResult snooped = map_scans(walk.list, options, {}, executor);
  EXPECT_FALSE(wrong_edge(snooped).used);
  EXPECT_NE(wrong_edge(snooped).note.find("outlier test"), std::string::npos) << wrong_edge(snooped).note;
  EXPECT_GE(snooped.outlier_edges, 1u);
  EXPECT_EQ(evaluate_map(snooped, walk.truth).wrong_used_loop_edges, 0u);
  // Both off: the wrong edge is used.
  options.outlier_threshold = 0.0;
  corrupted = false;
  const MapResult unchecked = map_scans(walk.list, options, {}, executor);
  EXPECT_TRUE(wrong_edge(unchecked).used);
  EXPECT_EQ(unchecked.outlier_edges, 0u);
  EXPECT_EQ(evaluate_map(unchecked, walk.truth).wrong_used_loop_edges, 1u);
}

// The place vote: every answer between the two sessions is forced to `ambiguous` (as pairs of one
// place by two different sensors mostly are). Without the vote nothing joins b. With it, the right
// answers, which agree on one pose of b's frame, join b with no wrong edge used. When every other
// answer is replaced by a wrong one that agrees with the other wrong ones on another pose (a
// look-alike place turned round, 60 m off), neither pose wins twice the other's votes, and b is not
// joined. b's odometry drifts 0.05 deg a metre: the vote needs right edges to agree within 3 deg.
TEST(MappingPlaceVote, AgreeingAmbiguousAnswersJoinSessionsAndATieWithWrongOnesDoesNot) {
  QUADRIX_REQUIRE_SHARED_DATA("balm_sequence/poses.txt");
  TemporaryFolder folder;
  const DriftedWalk walk = interleaved_sessions(folder.path, 0.05, 5);
  MapOptions options = edges_across_only(1);
  options.place_candidates_per_scan = 2;
  std::map<std::pair<std::size_t, std::size_t>, MapEdge> answers;  // registered once, reused by every run
  bool corrupt = false;
  MapExecutor executor;
  std::vector<std::optional<MappedScan>> models(walk.list.scans.size());  // modelled once, reused by every run
  executor.model = [&](const std::vector<std::size_t>& scans) {
    std::vector<MappedScan> modelled;
    for (std::size_t scan : scans) {
      if (!models[scan]) models[scan] = model_map_scan(walk.list, scan, options);
      modelled.push_back(*models[scan]);
    }
    return modelled;
  };
  executor.register_pairs = [&](const std::vector<MapPairRequest>& pairs) {
    std::vector<MapEdge> edges;
    std::size_t across = 0;
    for (const MapPairRequest& pair : pairs) {
      const auto key = std::make_pair(pair.from, pair.to);
      if (!answers.count(key)) answers[key] = register_map_pair(walk.list, pair, *models[pair.from], *models[pair.to], options);
      MapEdge edge = answers[key];
      if (walk.list.scans[pair.from].session != walk.list.scans[pair.to].session) {
        if (edge.status == "ok") edge.status = "ambiguous";
        if (corrupt && across++ % 2 == 1) {
          // The same wrong pose of b's frame for each: Z' = Z · O⁻¹ · D · O, O the `from` scan's odometry.
          Eigen::Isometry3d wrong = Eigen::Isometry3d::Identity();
          wrong.linear() = Eigen::AngleAxisd(kPi, Eigen::Vector3d::UnitZ()).toRotationMatrix();
          wrong.translation() = Eigen::Vector3d(60.0, 0.0, 0.0);
          const Eigen::Isometry3d odometry = *walk.list.scans[pair.from].odometry;
          edge.transform = edge.transform * odometry.inverse() * wrong * odometry;
          edge.status = "ambiguous";
        }
      }
      edges.push_back(edge);
    }
    return edges;
  };
  options.place_vote_minimum = 0;
  const MapResult no_vote = map_scans(walk.list, options, {}, executor);
  options.place_vote_minimum = 3;
  const MapResult voted = map_scans(walk.list, options, {}, executor);
  corrupt = true;
  const MapResult tied = map_scans(walk.list, options, {}, executor);
  const MapEvaluation evaluation = evaluate_map(voted, walk.truth);
  std::size_t voted_edges = 0, right_voted = 0;
  for (const MapEdge& edge : voted.edges)
    if (edge.voted) {
      ++voted_edges;
      right_voted += registration_succeeded(edge.transform, walk.truth[edge.to].pose.inverse() * walk.truth[edge.from].pose);
      EXPECT_NE(edge.note.find("place vote"), std::string::npos) << edge.note;
    }
  std::printf("place vote: without it b joined %d; with it %zu edges voted in (%zu right), b joined %d, ATE %.3f m, wrong used %zu; "
              "half the answers wrong and agreeing: b joined %d\n",
              static_cast<int>(no_vote.in_map_frame.back()), voted_edges, right_voted, static_cast<int>(voted.in_map_frame.back()),
              evaluation.ate, evaluation.wrong_used_loop_edges, static_cast<int>(tied.in_map_frame.back()));
  EXPECT_FALSE(no_vote.in_map_frame.back());
  EXPECT_TRUE(voted.in_map_frame.back());
  EXPECT_GE(voted_edges, 3u);
  EXPECT_EQ(evaluation.wrong_used_loop_edges, 0u);
  EXPECT_LE(evaluation.ate, 0.3);
  EXPECT_FALSE(tied.in_map_frame.back());
  for (const MapEdge& edge : tied.edges) EXPECT_FALSE(edge.voted);
}

TEST(MappingExecutor, TransferBytesRoundTripAndRefuseDamage) {
  MappedScan scan;
  scan.model.records.resize(2);
  for (std::size_t k = 0; k < 2; ++k) {
    scan.model.records[k].label = static_cast<std::uint32_t>(1 + k);
    for (int c = 0; c < 10; ++c) scan.model.records[k].q(c) = 0.1 * c + static_cast<double>(k);
  }
  scan.model.types = {QuadricType::Plane, QuadricType::Plane};
  scan.model.element_point_counts = {10, 20};
  scan.model.augmented_begin = 2;
  scan.model.source_point_count = 30;
  scan.descriptor = Eigen::VectorXd::LinSpaced(40, 0.0, 1.0 / 3.0);
  scan.preset = "vlp16";
  scan.modelling_ms = 12.5;
  const std::string bytes = mapped_scan_to_bytes(scan);
  const MappedScan back = mapped_scan_from_bytes(bytes);
  EXPECT_EQ(back.descriptor, scan.descriptor);
  EXPECT_EQ(back.preset, "vlp16");
  EXPECT_FALSE(back.augmented.has_value());
  EXPECT_EQ(mapped_scan_to_bytes(back), bytes);
  EXPECT_NE(error_of([&] { mapped_scan_from_bytes(bytes.substr(0, bytes.size() - 3), "worker 3"); }).find("worker 3"),
            std::string::npos);

  MapEdge edge;
  edge.from = 7;
  edge.to = 2;
  edge.kind = MapEdgeKind::Loop;
  edge.status = "ambiguous";
  edge.transform = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()) * Eigen::Translation3d(1.0 / 3.0, 2, -5);
  edge.information(1, 4) = 0.25;
  edge.inliers = 12345;
  edge.inlier_rmse = 0.0421;
  edge.registration_information(5, 0) = 1.0 / 7.0;
  edge.note = "why";
  const MapEdge edge_back = map_edge_from_bytes(map_edge_to_bytes(edge));
  EXPECT_EQ(edge_back.from, 7u);
  EXPECT_EQ(edge_back.kind, MapEdgeKind::Loop);
  EXPECT_EQ(edge_back.status, "ambiguous");
  EXPECT_EQ(edge_back.transform.matrix(), edge.transform.matrix());
  EXPECT_EQ(edge_back.information, edge.information);
  EXPECT_EQ(edge_back.inliers, edge.inliers);
  EXPECT_EQ(edge_back.inlier_rmse, edge.inlier_rmse);
  EXPECT_EQ(edge_back.registration_information, edge.registration_information);
  EXPECT_EQ(edge_back.note, "why");
  EXPECT_NE(error_of([&] { map_edge_from_bytes(bytes); }).find("bad magic"), std::string::npos);
}

}  // namespace
}  // namespace quadrix

namespace quadrix {
namespace {

/// A synthetic place: a ground plane 1.8 m below the sensor and 60 boxes (cars, posts,
/// façade pieces) 4-38 m around, seen by a sensor turned by `heading`, keeping every `stride`-th point
/// and only those within `field_of_view` of its forward axis (a sparse or narrow sensor).
PointCloud place_scan(unsigned place, double heading, int stride, double field_of_view) {
  std::mt19937 random(place);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Eigen::Vector3d> points;
  for (int box = 0; box < 60; ++box) {
    const double range = 4.0 + 34.0 * unit(random), bearing = 2.0 * kPi * unit(random);
    const Eigen::Vector2d centre(range * std::cos(bearing), range * std::sin(bearing));
    const double width = 0.5 + 3.0 * unit(random), height = 0.8 + 4.0 * unit(random);
    for (double u = -width / 2; u <= width / 2; u += 0.1)
      for (double v = -width / 2; v <= width / 2; v += 0.1)
        for (double z = 0.0; z <= height; z += 0.2) points.emplace_back(centre.x() + u, centre.y() + v, z - 1.8);
  }
  for (double x = -40.0; x <= 40.0; x += 0.5)
    for (double y = -40.0; y <= 40.0; y += 0.5) points.emplace_back(x, y, -1.8);
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(-heading, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  std::vector<Eigen::Vector3f> kept;
  for (std::size_t index = 0; index < points.size(); index += static_cast<std::size_t>(stride)) {
    const Eigen::Vector3d local = turn * points[index];
    if (std::abs(std::atan2(local.y(), local.x())) <= field_of_view / 2) kept.push_back(local.cast<float>());
  }
  PointCloud cloud;
  cloud.positions.resize(3, static_cast<Eigen::Index>(kept.size()));
  for (std::size_t index = 0; index < kept.size(); ++index) cloud.positions.col(static_cast<Eigen::Index>(index)) = kept[index];
  return cloud;
}

// The place descriptor matches a place across headings and sensors: a dense 360 deg scan of each of
// eight places; the same places seen turned by a random heading, by a sensor with an eighth of the
// points, and by one with a 70 deg field of view (a Livox's) rank their own place first among the
// eight. A scan turned by a whole number of sectors (6 deg) is at distance 0 from itself.
TEST(PlaceDescriptor, FindsThePlaceUnderAnyHeadingAcrossDensityAndFieldOfView) {
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  std::vector<Eigen::VectorXd> dense;
  for (unsigned place = 0; place < 8; ++place) dense.push_back(place_descriptor(place_scan(100 + place, 0.0, 1, 2 * kPi), up));
  EXPECT_EQ(dense[0].size(), 120);
  EXPECT_NEAR(place_distance(dense[3], place_descriptor(place_scan(103, 30.0 * kPi / 180.0 + 1e-4, 1, 2 * kPi), up)), 0.0, 0.05);
  std::mt19937 random(17);
  std::uniform_real_distribution<double> heading(0.0, 2.0 * kPi);
  for (const auto& [stride, field_of_view] : std::vector<std::pair<int, double>>{{1, 2 * kPi}, {8, 2 * kPi}, {1, 70.0 * kPi / 180.0}})
    for (unsigned place = 0; place < 8; ++place) {
      const Eigen::VectorXd query = place_descriptor(place_scan(100 + place, heading(random), stride, field_of_view), up);
      std::size_t best = 0;
      for (std::size_t other = 1; other < dense.size(); ++other)
        if (place_distance(query, dense[other]) < place_distance(query, dense[best])) best = other;
      EXPECT_EQ(best, place) << "stride " << stride << ", field of view " << field_of_view;
    }
  // Nothing seen in common: no comparison.
  PointCloud empty;
  EXPECT_TRUE(std::isinf(place_distance(dense[0], place_descriptor(empty, up))));
  EXPECT_THROW(place_distance(dense[0], Eigen::VectorXd::Zero(40)), Error);
}

// Options out of range are errors naming the option, before any scan is read.
TEST(MapOptionsCheck, OutOfRangeOptionsAreErrorsNamingTheOption) {
  ScanList list;
  list.source = "scans.tsv";
  list.scans.push_back({"a", "missing.ply", "/nonexistent/missing.ply", 2, std::nullopt});
  list.sessions = {"a"};
  const auto message = [&](const std::function<void(MapOptions&)>& change) {
    MapOptions options;
    change(options);
    return error_of([&] { map_scans(list, options); });
  };
  EXPECT_NE(message([](MapOptions& o) { o.outlier_threshold = -1.0; }).find("outlier_threshold"), std::string::npos);
  EXPECT_NE(message([](MapOptions& o) { o.outlier_threshold = std::numeric_limits<double>::infinity(); }).find("outlier_threshold"),
            std::string::npos);
  EXPECT_NE(message([](MapOptions& o) { o.place_vote_ratio = 0.5; }).find("place_vote_ratio"), std::string::npos);
  EXPECT_NE(message([](MapOptions& o) { o.place_vote_translation = 0.0; }).find("place_vote_translation"), std::string::npos);
  EXPECT_NE(message([](MapOptions& o) { o.information_tolerance = 1.0; }).find("information_tolerance"), std::string::npos);
  // In range: the options pass and the missing scan is what fails, named.
  EXPECT_NE(message([](MapOptions&) {}).find("missing.ply"), std::string::npos);
}

// The odometry gate of loop edges within a session: a right edge a few tens of metres back passes;
// the same edge turned by a half turn, or shifted by metres, does not; after a long path the gate
// opens and leaves the edge to the registration; k = 0 switches it off.
TEST(OdometryGate, KeepsRightLoopEdgesAndRefusesHalfTurnsAtShortRange) {
  const MapOptions options;  // 5 sigmas of 1 deg and 5 % a metre
  std::mt19937 random(31);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (int trial = 0; trial < 50; ++trial) {
    const double path = 16.0 + 12.0 * (trial % 5);  // 16 to 64 m back along the path
    Eigen::Isometry3d predicted = Eigen::Isometry3d::Identity();
    predicted.linear() = Eigen::AngleAxisd(0.3 * noise(random), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    predicted.translation() = Eigen::Vector3d(-path, 2.0 * noise(random), 0.1 * noise(random));
    // The truth departs from the odometry by its drift: 0.5 deg and 1 % of the path, at most.
    Eigen::Isometry3d right = predicted;
    right.linear() = Eigen::AngleAxisd(0.5 * 3.14159265358979 / 180.0 * noise(random), Eigen::Vector3d::UnitZ()) * right.linear();
    right.translation() += 0.01 * path * Eigen::Vector3d(noise(random), noise(random), 0.0).normalized();
    EXPECT_TRUE(consistent_with_odometry(right, predicted, path, options)) << "path " << path;
    Eigen::Isometry3d turned = right;
    turned.linear() = Eigen::AngleAxisd(3.14159265358979, Eigen::Vector3d::UnitZ()) * turned.linear();
    std::string why;
    if (path < 36.0) {  // 5 sigmas of 1 deg a metre reach 180 deg at 36 m
      EXPECT_FALSE(consistent_with_odometry(turned, predicted, path, options, &why)) << "path " << path;
      EXPECT_NE(why.find("departs from the odometry by 1"), std::string::npos) << why;  // 170-180 deg
    } else {
      EXPECT_TRUE(consistent_with_odometry(turned, predicted, path, options)) << "the gate is open after " << path << " m";
    }
  }
  // A shift of 30 m at 16 m of path (a scan matched to the wrong pass of a street) is refused.
  Eigen::Isometry3d predicted = Eigen::Isometry3d::Identity();
  predicted.translation() = Eigen::Vector3d(-16.0, 0.0, 0.0);
  Eigen::Isometry3d shifted = predicted;
  shifted.translation().x() += 30.0;
  EXPECT_FALSE(consistent_with_odometry(shifted, predicted, 16.0, options));
  MapOptions off;
  off.odometry_gate_sigmas = 0.0;
  EXPECT_TRUE(consistent_with_odometry(shifted, predicted, 16.0, off));
  // A scan slid 6 m along the street onto the scan 16 m behind it with its rotation right (0.03 deg:
  // no heading error to explain the shift) is refused, however much rotation the path would allow.
  Eigen::Isometry3d slid = predicted;
  slid.linear() = Eigen::AngleAxisd(0.03 * kPi / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  slid.translation().x() += 6.3;
  std::string why;
  EXPECT_FALSE(consistent_with_odometry(slid, predicted, 16.0, options, &why));
  EXPECT_NE(why.find("6.30 m"), std::string::npos) << why;
  // After a long path the rotation is the registration's to judge, but the translation must still
  // fit the rotation it departs by: a right-angle turn at 48 m explains a 40 m shift, none does not.
  Eigen::Isometry3d far = Eigen::Isometry3d::Identity();
  far.translation() = Eigen::Vector3d(-48.0, 0.0, 0.0);
  Eigen::Isometry3d far_shifted = far;
  far_shifted.translation().y() += 40.0;
  EXPECT_FALSE(consistent_with_odometry(far_shifted, far, 48.0, options));
  far_shifted.linear() = Eigen::AngleAxisd(kPi / 2.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_TRUE(consistent_with_odometry(far_shifted, far, 48.0, options));
}

// The second-stage gate of ambiguous edges within a session (arbitrate_ambiguous_edges): a walk
// round a 20 m square block twice with a yaw-biased odometry (0.5 deg a metre plus noise, as the
// BALM walk's test drift), `ok` loop edges from the second lap to the first every 10 m (the truth
// plus 2 cm / 0.1 deg noise), right ambiguous edges between them, and one ambiguous edge turned
// 82 deg and shifted 12 m from the odometry over 18 m of path: the odometry gate (5 sigmas of 1 deg
// a metre: 90 deg) lets it through, as it let through such an edge on the real walk; the map of
// the sure edges refuses it and keeps every right one. Five seeds.
TEST(AmbiguousEdgeGate, TheMapOfTheSureEdgesRefusesATurnedEdgeTheOdometryGateLetsThrough) {
  const MapOptions options;
  for (unsigned seed = 1; seed <= 5; ++seed) {
    std::mt19937 random(seed);
    std::normal_distribution<double> noise(0.0, 1.0);
    // The true walk: 2 m steps round a 20 m square, anticlockwise, twice (80 steps).
    std::vector<Eigen::Isometry3d> truth;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    for (int step = 0; step < 81; ++step) {
      truth.push_back(pose);
      Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
      motion.translation() = Eigen::Vector3d(2.0, 0.0, 0.0);
      if (step % 10 == 9) motion.linear() = Eigen::AngleAxisd(kPi / 2.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      pose = pose * motion;
    }
    const std::size_t count = truth.size();
    std::vector<Eigen::Isometry3d> odometry{truth.front()};
    std::vector<MapEdge> edges;
    std::vector<double> travelled{0.0};
    for (std::size_t index = 1; index < count; ++index) {
      Eigen::Isometry3d step = truth[index - 1].inverse() * truth[index];
      const double length = step.translation().norm();
      Eigen::Isometry3d error = Eigen::Isometry3d::Identity();
      error.linear() = Eigen::AngleAxisd((0.5 * length + 0.3 * noise(random)) * kPi / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      error.translation() = (0.02 + 0.03 * length) * Eigen::Vector3d(noise(random), noise(random), 0.3 * noise(random));
      odometry.push_back(odometry.back() * step * error);
      travelled.push_back(travelled.back() + length);
      MapEdge edge;
      edge.from = index;
      edge.to = index - 1;
      edge.status = "given";
      edge.used = true;
      edge.transform = odometry[index - 1].inverse() * odometry[index];
      edge.information.diagonal().head<3>().setConstant(1.0 / std::pow(std::max(0.5, length) * kPi / 180.0, 2));
      edge.information.diagonal().tail<3>().setConstant(1.0 / std::pow(std::max(0.05, 0.05 * length), 2));
      edges.push_back(edge);
    }
    const auto loop = [&](std::size_t from, std::size_t to, const std::string& status, const Eigen::Isometry3d& measured) {
      MapEdge edge;
      edge.from = from;
      edge.to = to;
      edge.kind = MapEdgeKind::Loop;
      edge.status = status;
      edge.used = true;
      edge.transform = measured;
      edge.information.diagonal().head<3>().setConstant(1.0 / std::pow(options.loop_rotation_sigma_degrees * kPi / 180.0, 2));
      edge.information.diagonal().tail<3>().setConstant(1.0 / std::pow(options.loop_translation_sigma, 2));
      edges.push_back(edge);
      return edges.size() - 1;
    };
    const auto noisy_truth = [&](std::size_t from, std::size_t to) {
      Eigen::Isometry3d measured = truth[to].inverse() * truth[from];
      measured.linear() = Eigen::AngleAxisd(0.1 * kPi / 180.0 * noise(random), Eigen::Vector3d::UnitZ()) * measured.linear();
      measured.translation() += 0.02 * Eigen::Vector3d(noise(random), noise(random), noise(random));
      return measured;
    };
    for (std::size_t index = 45; index < count; index += 5) loop(index, index - 40, "ok", noisy_truth(index, index - 40));
    std::vector<std::size_t> right;
    // Right ambiguous edges between scans the sure edges anchor (at the walk's loose start, where the
    // map of the sure edges is the odometry alone, its heading may be off by more than the gate).
    for (std::size_t index = 47; index < count; index += 10) right.push_back(loop(index, index - 40, "ambiguous", noisy_truth(index, index - 40)));
    // The turned edge: scan 30 onto scan 21 (18 m back), departing from the odometry by 82 deg and 12 m.
    Eigen::Isometry3d turned = odometry[21].inverse() * odometry[30];
    turned.linear() = Eigen::AngleAxisd(82.0 * kPi / 180.0, Eigen::Vector3d::UnitZ()) * turned.linear();
    turned.translation() += Eigen::Vector3d(12.0, 0.0, 0.0);
    ASSERT_TRUE(consistent_with_odometry(turned, odometry[21].inverse() * odometry[30], travelled[30] - travelled[21], options))
        << "seed " << seed << ": the odometry gate refuses the turned edge; the case is not the one this test is for";
    const std::size_t wrong = loop(30, 21, "ambiguous", turned);

    // Without the gate (limits no edge can exceed) the turned edge would stay in the graph.
    MapOptions open = options;
    open.ambiguous_gate_rotation_degrees = 360.0;
    open.ambiguous_gate_translation = 1e9;
    std::vector<MapEdge> unjudged = edges;
    EXPECT_EQ(arbitrate_ambiguous_edges(unjudged, odometry, open), 0u);
    EXPECT_TRUE(unjudged[wrong].used);

    std::vector<MapEdge> judged = edges;
    EXPECT_EQ(arbitrate_ambiguous_edges(judged, odometry, options), 1u) << "seed " << seed;
    EXPECT_FALSE(judged[wrong].used) << "seed " << seed;
    EXPECT_NE(judged[wrong].note.find("departs from the map of the sure edges"), std::string::npos) << judged[wrong].note;
    for (std::size_t index : right)
      EXPECT_TRUE(judged[index].used) << "seed " << seed << ": right ambiguous edge " << index << " refused: " << judged[index].note;
    for (std::size_t index = 0; index < edges.size(); ++index) {
      if (edges[index].status != "ambiguous") {
        EXPECT_TRUE(judged[index].used) << "only ambiguous edges are judged";
      }
    }
    // Ambiguous edges across sessions are not this gate's (the joint-frame rounds judge those).
    std::vector<MapEdge> across = edges;
    across[wrong].across_sessions = true;
    arbitrate_ambiguous_edges(across, odometry, options);
    EXPECT_TRUE(across[wrong].used);
  }
}

}  // namespace
}  // namespace quadrix
