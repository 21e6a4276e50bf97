// The interactive page (`quadrix view`, `quadrix register --out`, `quadrix model`) opened in a real
// browser: Debian's chromium, headless, from disk with no network. Each page must run without a
// JavaScript error (the page's own error hook and the console), draw a non-blank canvas (pixel
// statistics of a screenshot, decoded with stb_image), show the status in the side panel and report
// the time its first frame was drawn (data-ready-ms, logged). Skips when chromium is not installed.
#include "experiments/reports/interactive_page.h"
#include "experiments/reports/registration_report.h"
#include "geometry/io.h"
#include "geometry/error.h"
#include "experiments/headless_browser.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <regex>
#include <set>
#include <sstream>
#include <string>

namespace quadrix {
namespace {

namespace fs = std::filesystem;

using test::BrowserView;
using test::fresh_directory;
using test::kChromium;
using test::open_in_browser;
using test::read_text;

// Runs a shell command, its output into `log`; returns the exit status.
int run(const std::string& command, const fs::path& log) {
  return std::system((command + " > '" + log.string() + "' 2>&1").c_str());
}

// The checks every page must pass; `status` is what the side panel must show.
void expect_page_works(const fs::path& page, const std::string& status, const std::string& name) {
  ASSERT_TRUE(fs::exists(page)) << page;
  const double megabytes = static_cast<double>(fs::file_size(page)) / 1e6;
  EXPECT_LT(megabytes, 20.0) << page;
  const std::string html = read_text(page);
  for (const char* external : {"<script src", "<link ", "<img ", "<iframe"})
    EXPECT_EQ(html.find(external), std::string::npos) << page << ": the page must load nothing from outside itself (" << external << ")";
  const BrowserView view = open_in_browser(page);
  std::cout << name << ": " << page.filename().string() << " " << megabytes << " MB, first frame at " << view.ready_ms
            << " ms after opening, canvas " << view.canvas_colours << " colours, " << 100.0 * view.canvas_drawn << "% drawn\n";
  EXPECT_TRUE(view.error.empty()) << "JavaScript error: " << view.error;
  EXPECT_EQ(view.console.find("Uncaught"), std::string::npos) << view.console;
  EXPECT_GE(view.ready_ms, 0.0) << "the page never reported its first frame (data-ready-ms); DOM:\n" << view.dom.substr(0, 2000);
  EXPECT_NE(view.dom.find("<title>quadrix view ready"), std::string::npos);
  EXPECT_NE(view.dom.find(">status: " + status + "</div>"), std::string::npos) << "side panel without status " << status;
  EXPECT_GE(view.canvas_colours, 3) << "blank canvas";
  EXPECT_GE(view.canvas_drawn, 0.01) << "blank canvas";
}

class InteractivePage : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!fs::exists(kChromium)) return;
    directory_ = fresh_directory("suite");
    // The demo's synthetic street pair (experiments/command_line/demo.sh), registered with --out.
    const fs::path street = directory_ / "street";
    ASSERT_EQ(run(std::string(QUADRIX_EXECUTABLE) + " synth street --seed 3 --sensor hdl64 --out '" + street.string() + "'",
                  directory_ / "synth.log"),
              0)
        << read_text(directory_ / "synth.log");
    std::istringstream pairs(read_text(street / "pairs.tsv"));
    std::string header, id, source, target, truth;
    std::getline(pairs, header);
    pairs >> id >> source >> target >> truth;
    ASSERT_EQ(run(std::string(QUADRIX_EXECUTABLE) + " register '" + (street / source).string() + "' '" + (street / target).string() +
                      "' --gt '" + (street / truth).string() + "' --out '" + (directory_ / "register").string() + "'",
                  directory_ / "register.log"),
              0)
        << read_text(directory_ / "register.log");
    scan_ = street / source;
  }
  static void TearDownTestSuite() {
    if (!directory_.empty()) fs::remove_all(directory_);
  }
  void SetUp() override {
    if (!fs::exists(kChromium)) GTEST_SKIP() << kChromium << " not installed (apt-get install chromium): the page tests need a browser";
  }
  static fs::path directory_;
  static fs::path scan_;
};
fs::path InteractivePage::directory_;
fs::path InteractivePage::scan_;

std::string report_status(const fs::path& folder) {
  return nlohmann::json::parse(read_text(folder / "report.json")).at("status").get<std::string>();
}

TEST_F(InteractivePage, RegisterWritesAWorkingPageAndTheCliqueItDraws) {
  const fs::path folder = directory_ / "register";
  const nlohmann::json report = nlohmann::json::parse(read_text(folder / "report.json"));
  // report.json keeps its keys and gains each candidate's clique (record index pairs of the models).
  ASSERT_FALSE(report.at("candidates").empty());
  const nlohmann::json& winner = report["candidates"][0];
  EXPECT_TRUE(winner.contains("transform"));
  ASSERT_TRUE(winner.contains("clique"));
  EXPECT_EQ(winner["clique"].size(), winner["clique_size"].get<std::size_t>());
  ASSERT_TRUE(fs::exists(folder / "source_model.json"));
  const SceneModel source_model = read_scene_model_json((folder / "source_model.json").string());
  for (const auto& pair : winner["clique"]) EXPECT_LT(pair[0].get<std::size_t>(), source_model.size());
  expect_page_works(folder / "view.html", report_status(folder), "register --out view.html");
}

TEST_F(InteractivePage, ViewOfARegisterFolderDrawsTheCliqueLinesAndAppliesACandidate) {
  const fs::path folder = directory_ / "register";
  const fs::path page = directory_ / "registration.html";
  ASSERT_EQ(run(std::string(QUADRIX_EXECUTABLE) + " view '" + folder.string() + "' --out '" + page.string() + "'", directory_ / "view.log"), 0)
      << read_text(directory_ / "view.log");
  expect_page_works(page, report_status(folder), "view of a register folder");
  // "#candidate=1" applies candidate 1 as a click on its row does; the panel says so.
  const BrowserView view = open_in_browser(page, "#candidate=1");
  EXPECT_TRUE(view.error.empty()) << view.error;
  EXPECT_NE(view.dom.find("<span id=\"shown\">candidate 1 (level 1"), std::string::npos) << view.dom.substr(0, 3000);
}

TEST_F(InteractivePage, ModelPageShowsQuadricsAndTheRecordOfAPickedOne) {
  const fs::path json = directory_ / "model.json";
  ASSERT_EQ(run(std::string(QUADRIX_EXECUTABLE) + " model '" + scan_.string() + "' --preset vlp64 --out '" + json.string() + "'",
                directory_ / "model.log"),
            0)
      << read_text(directory_ / "model.log");
  const fs::path page = directory_ / "model.html";
  expect_page_works(page, "ok", "model page (quadrix model)");
  const BrowserView view = open_in_browser(page, "#pick=0");
  EXPECT_TRUE(view.error.empty()) << view.error;
  EXPECT_NE(view.dom.find("<b>quadric 0</b>"), std::string::npos);
  EXPECT_NE(view.dom.find("21-number record"), std::string::npos);
  // The page of the JSON alone (quadrics, no points) works too.
  const fs::path json_page = directory_ / "model_json.html";
  ASSERT_EQ(run(std::string(QUADRIX_EXECUTABLE) + " view '" + json.string() + "' --out '" + json_page.string() + "'", directory_ / "view.log"), 0)
      << read_text(directory_ / "view.log");
  expect_page_works(json_page, "ok", "view of model.json");
}

TEST_F(InteractivePage, SyntheticFolderPageShowsTheTruth) {
  const fs::path page = directory_ / "street.html";
  ASSERT_EQ(run(std::string(QUADRIX_EXECUTABLE) + " view '" + (directory_ / "street").string() + "' --out '" + page.string() + "'",
                directory_ / "view.log"),
            0)
      << read_text(directory_ / "view.log");
  expect_page_works(page, "ground truth", "view of a synth folder");
}

TEST_F(InteractivePage, TheHarnessSeesAJavaScriptError) {
  // A page whose data block is broken must fail the checks above: the harness can fail.
  std::string html = read_text(directory_ / "register" / "view.html");
  const std::string marker = "id=\"quadrix-data\">";
  const std::size_t at = html.find(marker);
  ASSERT_NE(at, std::string::npos);
  html.insert(at + marker.size(), "{broken");
  const fs::path page = directory_ / "broken.html";
  write_page(page.string(), html);
  const BrowserView view = open_in_browser(page);
  EXPECT_FALSE(view.error.empty());
  EXPECT_LT(view.ready_ms, 0.0);
  EXPECT_NE(view.console.find("Uncaught"), std::string::npos) << view.console;
}

TEST_F(InteractivePage, WithoutWebGlThePageSaysSoAndStillShowsThePanel) {
  const fs::path folder = directory_ / "register";
  const BrowserView view = open_in_browser(folder / "view.html", "", false);
  EXPECT_TRUE(view.error.empty()) << "a missing WebGL context is reported in the page, not as a script error: " << view.error;
  // Visible text in the view, the whole panel, and a page that still reports itself ready.
  EXPECT_NE(view.dom.find("id=\"no-webgl\""), std::string::npos) << view.dom.substr(0, 3000);
  EXPECT_NE(view.dom.find("could not create a WebGL context"), std::string::npos);
  EXPECT_NE(view.dom.find(">status: " + report_status(folder) + "</div>"), std::string::npos) << "panel missing";
  EXPECT_NE(view.dom.find("Candidates (click one to apply it)"), std::string::npos);
  EXPECT_NE(view.dom.find("(no WebGL: panel only)"), std::string::npos);
  EXPECT_GE(view.ready_ms, 0.0);
  // The model page too.
  const fs::path json = directory_ / "model_no_webgl.json";
  ASSERT_EQ(run(std::string(QUADRIX_EXECUTABLE) + " model '" + scan_.string() + "' --out '" + json.string() + "'",
                directory_ / "model_no_webgl.log"),
            0)
      << read_text(directory_ / "model_no_webgl.log");
  const BrowserView model_view = open_in_browser(directory_ / "model_no_webgl.html", "", false);
  EXPECT_TRUE(model_view.error.empty()) << model_view.error;
  EXPECT_NE(model_view.dom.find("could not create a WebGL context"), std::string::npos);
  EXPECT_NE(model_view.dom.find(">status: ok</div>"), std::string::npos);
}

TEST_F(InteractivePage, StringsFromACraftedReportAreShownAsTextAndNeverRun) {
  // report.json with markup in every place the panel shows: counts arrays, a candidate's clique
  // size, status, message, input names. The page must show them as text and run none of them.
  const fs::path folder = directory_ / "crafted";
  fs::create_directories(folder);
  for (const char* name : {"merged.ply", "source_model.json", "target_model.json"})
    fs::copy_file(directory_ / "register" / name, folder / name);
  nlohmann::json report = nlohmann::json::parse(read_text(directory_ / "register" / "report.json"));
  const std::string attack = "<img src=x onerror=\"document.body.setAttribute('data-pwned','1')\">";
  report["counts"]["clique_sizes"] = nlohmann::json::array({attack});
  report["candidates"][0]["clique_size"] = attack;
  report["candidates"][0]["refinement_status"] = attack;
  report["message"] = std::string("</script><script>document.body.setAttribute('data-pwned','2')</script>") + attack;
  report["input"]["source"] = attack;
  std::ofstream(folder / "report.json") << report.dump(2);
  const fs::path page = directory_ / "crafted.html";
  ASSERT_EQ(run(std::string(QUADRIX_EXECUTABLE) + " view '" + folder.string() + "' --out '" + page.string() + "'", directory_ / "view.log"), 0)
      << read_text(directory_ / "view.log");
  // The embedded JSON cannot close its script element: no '<' of the data survives as a byte.
  EXPECT_EQ(read_text(page).find("<img"), std::string::npos);
  const BrowserView view = open_in_browser(page);
  EXPECT_EQ(view.dom.find("data-pwned=\""), std::string::npos) << "script from report.json ran";
  EXPECT_EQ(view.dom.find("<img"), std::string::npos) << "markup from report.json became an element";
  EXPECT_NE(view.dom.find("&lt;img src=x onerror="), std::string::npos) << "the crafted strings are shown as text";
  EXPECT_TRUE(view.error.empty()) << view.error;
  EXPECT_GE(view.ready_ms, 0.0);
}

TEST_F(InteractivePage, AFileNamedLikeMarkupDoesNotBlankThePage) {
  // "<!--<script>" in a file name would put the script parser into its escaped state and swallow
  // the page's script if the embedded JSON kept it as is.
  const fs::path odd = directory_ / "<!--<script>.ply";
  fs::copy_file(scan_, odd);
  const fs::path json = directory_ / "odd.json";
  ASSERT_EQ(run(std::string(QUADRIX_EXECUTABLE) + " model '" + odd.string() + "' --out '" + json.string() + "'", directory_ / "odd.log"), 0)
      << read_text(directory_ / "odd.log");
  expect_page_works(directory_ / "odd.html", "ok", "model page of a file named <!--<script>.ply");
  const BrowserView view = open_in_browser(directory_ / "odd.html");
  EXPECT_NE(view.dom.find("&lt;!--&lt;script&gt;.ply"), std::string::npos) << "the file name is shown as text";
}

TEST(InteractivePageInput, ViewReadsOnlyFilesInsideTheFolderItWasGiven) {
  const fs::path directory = fresh_directory("outside");
  const fs::path street = directory / "street";
  ASSERT_EQ(run(std::string(QUADRIX_EXECUTABLE) + " synth street --seed 3 --sensor hdl64 --out '" + street.string() + "'",
                directory / "synth.log"),
            0)
      << read_text(directory / "synth.log");
  nlohmann::json scene = nlohmann::json::parse(read_text(street / "scene.json"));
  const std::string inside = scene["scans"][0]["cloud"].get<std::string>();
  fs::copy_file(street / inside, directory / "elsewhere.ply");
  for (const std::string& outside : {(directory / "elsewhere.ply").string(), std::string("../elsewhere.ply")}) {
    scene["scans"][0]["cloud"] = outside;
    std::ofstream(street / "scene.json") << scene.dump(2);
    const fs::path log = directory / "view.log";
    EXPECT_NE(run(std::string(QUADRIX_EXECUTABLE) + " view '" + street.string() + "' --out '" + (directory / "x.html").string() + "'", log), 0)
        << outside;
    EXPECT_NE(read_text(log).find("not a file inside the folder"), std::string::npos) << read_text(log);
    EXPECT_FALSE(fs::exists(directory / "x.html"));
  }
  // A link inside the folder that leads out of it is refused too.
  fs::create_symlink(directory / "elsewhere.ply", street / "link.ply");
  scene["scans"][0]["cloud"] = "link.ply";
  std::ofstream(street / "scene.json") << scene.dump(2);
  const fs::path log = directory / "view.log";
  EXPECT_NE(run(std::string(QUADRIX_EXECUTABLE) + " view '" + street.string() + "' --out '" + (directory / "x.html").string() + "'", log), 0);
  EXPECT_NE(read_text(log).find("leads outside the folder"), std::string::npos) << read_text(log);
  // The untouched description still works.
  scene["scans"][0]["cloud"] = inside;
  std::ofstream(street / "scene.json") << scene.dump(2);
  EXPECT_EQ(run(std::string(QUADRIX_EXECUTABLE) + " view '" + street.string() + "' --out '" + (directory / "x.html").string() + "'", log), 0)
      << read_text(log);
  fs::remove_all(directory);
}

TEST(InteractivePageInput, ViewRejectsAnInputItCannotShow) {
  const fs::path directory = fresh_directory("reject");
  const fs::path log = directory / "view.log";
  EXPECT_NE(run(std::string(QUADRIX_EXECUTABLE) + " view '" + directory.string() + "' --out '" + (directory / "x.html").string() + "'", log), 0);
  EXPECT_NE(read_text(log).find("expected a `quadrix register --out` folder"), std::string::npos) << read_text(log);
  EXPECT_FALSE(fs::exists(directory / "x.html"));
  fs::remove_all(directory);
}

TEST(InteractivePageInput, ARegisterFolderWithSensorOriginsIsShownSensorCentred) {
  // What `quadrix register --source-origin --target-origin --out` writes: merged.ply in the target
  // file's frame, report.json's transform between the sensor-centred clouds.
  const fs::path directory = fresh_directory("origins");
  PointCloud source, target;
  source.positions = Eigen::Matrix3Xf::Random(3, 40) * 10.0F;
  target.positions = Eigen::Matrix3Xf::Random(3, 30) * 10.0F;
  RegistrationResult result;
  result.transform = Eigen::Translation3d(2.0, -1.0, 0.5) * Eigen::AngleAxisd(0.6, Eigen::Vector3d::UnitZ());
  RegistrationReportContext context;
  context.source_sensor_origin = Eigen::Vector3d(800.0, 300.0, 20.0);
  context.target_sensor_origin = Eigen::Vector3d(806.0, 291.0, 20.5);
  write_registration_report((directory / "report.json").string(), result, context);
  write_point_cloud((directory / "merged.ply").string(),
                    centred_on_sensor(merge_aligned_clouds(source, target, result.transform), -context.target_sensor_origin));

  const RegistrationPageInput page = read_registration_folder(directory.string());
  ASSERT_EQ(page.source.size(), source.size());
  ASSERT_EQ(page.target.size(), target.size());
  for (std::size_t i = 0; i < target.size(); ++i) EXPECT_LT((page.target.point(i) - target.point(i)).norm(), 1e-3) << i;
  for (std::size_t i = 0; i < source.size(); ++i) EXPECT_LT((page.source.point(i) - source.point(i)).norm(), 1e-3) << i;
  fs::remove_all(directory);
}

TEST(InteractivePageInput, QuadricMeshStaysInsideTheBoxOfItsFullAttributes) {
  // A vertical cylinder of radius 1 (x^2 + y^2 - 1 = 0) whose points span z in [-2, 2]: the page's
  // mesh without an extent is cut to a box around t_f: three radii along the axis, 1.2 radii across.
  PageQuadric quadric;
  quadric.record.label = static_cast<std::uint32_t>(ElementClass::Cylinder);
  quadric.record.q << 1, 1, 0, 0, 0, 0, 0, 0, 0, -1;
  quadric.record.full_scale = Eigen::Vector3d(1.0, 1.0, 2.0);
  quadric.type = QuadricType::CircularCylinder;
  const TriangleMesh mesh = page_quadric_mesh(quadric, 24);
  ASSERT_GT(mesh.triangles.size(), 50u);
  EXPECT_LE(mesh.vertices.row(2).maxCoeff(), 3.0 + 0.3);
  EXPECT_GE(mesh.vertices.row(2).minCoeff(), -3.0 - 0.3);
  EXPECT_GT(mesh.vertices.row(2).maxCoeff(), 2.5);
  for (Eigen::Index v = 0; v < mesh.vertices.cols(); ++v) EXPECT_NEAR(mesh.vertices.col(v).head<2>().norm(), 1.0, 1e-6);
}

}  // namespace
}  // namespace quadrix
