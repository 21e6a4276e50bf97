// map.html of a map folder: the folder's files parse (and malformed ones are refused naming the line),
// the odometry trajectory is the chain of the odometry edges, strings from the data can neither close
// the data's script element nor become HTML, and in headless Chromium the page draws the map with
// WebGL and, without WebGL, says so in visible text while its panel still shows the counts and the
// ATE. `quadrix view DIR` writes the same page for a map folder. Skips the browser part when
// chromium is not installed.
#include "experiments/reports/map_page.h"
#include "geometry/error.h"
#include "geometry/io.h"
#include "experiments/headless_browser.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>

namespace quadrix {
namespace {

namespace fs = std::filesystem;

using test::BrowserView;
using test::kChromium;
using test::read_text;
// A session name and an edge status that would run script if the page inserted them as HTML.
const std::string kHostileSession = "</script><script>document.body.setAttribute('data-pwned','1')</script>";
const std::string kHostileStatus = "<img src=x onerror=\"document.body.setAttribute('data-pwned','2')\">";

fs::path fresh_directory(const std::string& name) { return test::fresh_directory("map_" + name); }

std::string pose_row(const Eigen::Isometry3d& pose, char separator) {
  std::ostringstream text;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) text << (r || c ? std::string(1, separator) : "") << pose.matrix()(r, c);
  return text.str();
}

// A CSV field in double quotes, inner quotes doubled (RFC 4180).
std::string csv_quoted(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

Eigen::Isometry3d planar(double x, double y, double yaw) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  pose.translation() = Eigen::Vector3d(x, y, 0.0);
  return pose;
}

// A map folder of two sessions driving circles, odometry edges between consecutive scans (the
// odometry a little off the poses), loop edges of every status, a report with an ATE and a coloured map.
struct MapFolder {
  fs::path root;
  std::vector<Eigen::Isometry3d> after[2], odometry[2];
};

MapFolder write_map_folder(const fs::path& root) {
  MapFolder folder;
  folder.root = root;
  fs::create_directories(root);
  const std::string sessions[2] = {"1", kHostileSession};
  std::ofstream poses(root / "poses.tsv");
  poses << "session\tscan\tt00\tt01\tt02\tt03\tt10\tt11\tt12\tt13\tt20\tt21\tt22\tt23\n";
  std::ofstream edges(root / "edges.csv");
  edges << "from_session,from_scan,to_session,to_scan,kind,status,used,t00,t01,t02,t03,t10,t11,t12,t13,t20,t21,t22,t23,extra\n";
  for (int s = 0; s < 2; ++s) {
    const int count = 40;
    for (int k = 0; k < count; ++k) {
      const double angle = 2.0 * 3.14159265358979 * k / count;
      folder.after[s].push_back(planar(30.0 * std::cos(angle) + 5.0 * s, 30.0 * std::sin(angle), angle + 1.5707963));
      poses << sessions[s] << "\tscans/s" << s << "_" << k << ".ply\t" << pose_row(folder.after[s].back(), '\t') << '\n';
    }
    // Odometry with a yaw drift of 0.5 degrees a step: the "before" trajectory differs from "after".
    folder.odometry[s].push_back(folder.after[s][0]);
    for (int k = 0; k + 1 < count; ++k) {
      Eigen::Isometry3d step = folder.after[s][k].inverse() * folder.after[s][k + 1];
      step.linear() = step.linear() * Eigen::AngleAxisd(0.0087, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      folder.odometry[s].push_back(folder.odometry[s].back() * step);
      const Eigen::Isometry3d from_k_to_next = step.inverse();  // p_next = T p_k
      const std::string session = s == 0 ? sessions[0] : csv_quoted(sessions[1]);
      edges << session << ",scans/s" << s << "_" << k << ".ply," << session << ",scans/s" << s << "_" << k + 1
            << ".ply,odometry,ok,1," << pose_row(from_k_to_next, ',') << ",0\n";
    }
  }
  const char* statuses[] = {"ok", "ok", "ambiguous", "rejected"};
  for (int k = 0; k < 4; ++k)
    edges << "1,scans/s0_" << 30 + k << ".ply,1,scans/s0_" << k << ".ply,loop," << statuses[k] << "," << (k < 2 ? 1 : 0) << ","
          << pose_row(Eigen::Isometry3d::Identity(), ',') << ",0\n";
  edges << "1,scans/s0_5.ply," << csv_quoted(kHostileSession) << ",scans/s1_5.ply,loop," << csv_quoted(kHostileStatus) << ",0,"
        << pose_row(Eigen::Isometry3d::Identity(), ',') << ",0\n";
  std::ofstream(root / "report.json") << R"({"counts": {"scans": 80, "sessions": 2}, "evaluation": {"ate_m": 0.1234},
    "note": "</script><script>document.body.setAttribute('data-pwned','3')</script>"})";
  PointCloud map;
  map.positions.resize(3, 2000);
  for (int i = 0; i < 2000; ++i) {
    const double angle = 2.0 * 3.14159265358979 * i / 2000;
    map.positions.col(i) = Eigen::Vector3f(34.0f * std::cos(angle), 34.0f * std::sin(angle), static_cast<float>(i % 20) * 0.2f);
    map.colors.push_back({static_cast<std::uint8_t>(i % 255), 80, 160});
  }
  write_point_cloud((root / "map.ply").string(), map);
  return folder;
}

TEST(MapPage, ReadsTheFolderAndChainsTheOdometry) {
  const fs::path root = fresh_directory("read");
  const MapFolder folder = write_map_folder(root / "map");
  const MapPageInput input = read_map_folder(folder.root.string());
  ASSERT_EQ(input.poses.size(), 80u);
  EXPECT_EQ(input.poses[40].session, kHostileSession);
  EXPECT_EQ(input.edges.size(), 2u * 39u + 5u);
  EXPECT_EQ(input.edges.back().status, kHostileStatus);
  EXPECT_EQ(input.points.size(), 2000u);
  const std::vector<MapPagePose> before = odometry_trajectory(input.poses, input.edges);
  ASSERT_EQ(before.size(), 80u);
  for (int s = 0; s < 2; ++s)
    for (int k = 0; k < 40; ++k)
      EXPECT_LT((before[static_cast<std::size_t>(40 * s + k)].pose.matrix() - folder.odometry[s][static_cast<std::size_t>(k)].matrix()).norm(), 1e-3)
          << "session " << s << " scan " << k;
  // The odometry really is off: the last "before" pose is metres from the last "after" pose.
  EXPECT_GT((before[39].pose.translation() - input.poses[39].pose.translation()).norm(), 3.0);
  fs::remove_all(root);
}

TEST(MapPage, DataCannotCloseItsScriptElement) {
  const fs::path root = fresh_directory("escape");
  write_map_folder(root / "map");
  const std::string html = map_page_html(read_map_folder((root / "map").string()));
  // Only the page's own five script elements close: error hook, three.js, OrbitControls, data, page script.
  std::size_t closes = 0;
  for (std::size_t at = html.find("</script>"); at != std::string::npos; at = html.find("</script>", at + 1)) ++closes;
  EXPECT_EQ(closes, 5u);
  EXPECT_EQ(html.find("<script>document.body"), std::string::npos);
  EXPECT_EQ(html.find("<img src=x"), std::string::npos);
  for (const char* external : {"<script src", "<link ", "<iframe"}) EXPECT_EQ(html.find(external), std::string::npos) << external;
  // The page's own script (the last one) builds every element with textContent, never innerHTML.
  const std::size_t page_script = html.rfind("<script>");
  ASSERT_NE(page_script, std::string::npos);
  EXPECT_EQ(html.find("innerHTML", page_script), std::string::npos);
  fs::remove_all(root);
}

TEST(MapPage, RefusesMalformedFilesNamingTheLine) {
  const fs::path root = fresh_directory("bad");
  write_map_folder(root / "map");
  std::ofstream(root / "map" / "poses.tsv", std::ios::app) << "1\tscans/x.ply\t1\t0\t0\tnot-a-number\t0\t1\t0\t0\t0\t0\t1\t0\n";
  try {
    read_map_poses((root / "map" / "poses.tsv").string());
    ADD_FAILURE() << "a malformed pose was accepted";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("line 82"), std::string::npos) << error.what();
  }
  std::ofstream(root / "map" / "edges.csv") << "from_session,from_scan,to_session,to_scan,kind,status\n";
  EXPECT_THROW(read_map_edges((root / "map" / "edges.csv").string()), Error);
  fs::remove_all(root);
  EXPECT_FALSE(is_map_folder((root / "map").string()));
}

BrowserView open_page(const fs::path& page, bool webgl) { return test::open_in_browser(page, "", webgl); }

void expect_panel(const std::string& dom) {
  EXPECT_EQ(dom.find("data-error=\""), std::string::npos) << dom.substr(0, 3000);
  EXPECT_FALSE(std::regex_search(dom, std::regex("<body[^>]*data-pwned"))) << "a string from the data ran as script";
  EXPECT_TRUE(std::regex_search(dom, std::regex("<body[^>]*data-ready-ms=\"[0-9]+\""))) << dom.substr(0, 3000);
  EXPECT_NE(dom.find("<td>scans</td><td class=\"n\">80</td>"), std::string::npos);
  EXPECT_NE(dom.find("<td>evaluation.ate_m</td><td class=\"n\">0.123</td>"), std::string::npos);
  // The hostile session name is shown, as text.
  EXPECT_NE(dom.find("session &lt;/script&gt;&lt;script&gt;document.body.setAttribute"), std::string::npos);
}

TEST(MapPage, DrawsInChromiumWithAndWithoutWebGL) {
  if (!fs::exists(kChromium)) GTEST_SKIP() << kChromium << " not installed (apt-get install chromium)";
  const fs::path root = fresh_directory("browser_suite");
  write_map_folder(root / "map");
  const std::string page = write_map_page((root / "map").string());
  ASSERT_EQ(page, (root / "map" / "map.html").string());
  const BrowserView with = open_page(page, true);
  expect_panel(with.dom);
  EXPECT_EQ(with.dom.find("data-webgl=\"missing\""), std::string::npos) << "swiftshader WebGL was expected";
  EXPECT_EQ(with.dom.find("id=\"nowebgl\""), std::string::npos);
  EXPECT_NE(with.dom.find("<title>quadrix map ready"), std::string::npos);
  EXPECT_GE(with.canvas_colours, 4) << "trajectories, edges and points in several colours";
  EXPECT_GE(with.canvas_drawn, 0.005);
  const BrowserView without = open_page(page, false);
  expect_panel(without.dom);
  EXPECT_NE(without.dom.find("data-webgl=\"missing\""), std::string::npos);
  EXPECT_NE(without.dom.find("id=\"nowebgl\">WebGL is not available in this browser"), std::string::npos) << without.dom.substr(0, 3000);
  EXPECT_NE(without.dom.find("(no WebGL)</title>"), std::string::npos);
  fs::remove_all(root);
}

TEST(MapPage, QuadrixViewWritesTheMapPageOfAMapFolder) {
  const fs::path root = fresh_directory("view");
  write_map_folder(root / "map");
  const std::string command = std::string(QUADRIX_EXECUTABLE) + " view '" + (root / "map").string() + "' --out '" +
                              (root / "page.html").string() + "' > '" + (root / "view.log").string() + "' 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << read_text(root / "view.log");
  EXPECT_NE(read_text(root / "view.log").find("map page"), std::string::npos) << read_text(root / "view.log");
  EXPECT_NE(read_text(root / "page.html").find("id=\"quadrix-map-data\""), std::string::npos);
  fs::remove_all(root);
}

}  // namespace
}  // namespace quadrix
