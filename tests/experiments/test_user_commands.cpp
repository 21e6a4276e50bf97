// The user's surface of `quadrix`, tried as a new user would: `auto` accepted wherever a preset is
// and the default everywhere, bare `quadrix config`, --help grouping the research commands apart,
// plain shape parameters from `quadrix fit`, one-line terminal summaries, and pictures that explain
// themselves (legends, status, sensors) checked by reading the PNG back; the bench plots' titles
// and axes. Runs the built executable on a simulated street (`quadrix synth`).
#include "experiments/benchmark/benchmark_runner.h"
#include "experiments/reports/registration_report.h"
#include "geometry/io.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_STATIC
#include <stb/stb_image.h>

#include <Eigen/Geometry>

#include <array>
#include <chrono>
#include <functional>
#include <map>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>
#include <set>
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

// Runs `quadrix ARGUMENTS`, stdout into `out` and stderr into `out`.err; returns the exit status.
int quadrix(const std::string& arguments, const fs::path& out) {
  const int status = std::system((std::string(QUADRIX_EXECUTABLE) + " " + arguments + " > '" + out.string() + "' 2> '" +
                                  out.string() + ".err'").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

fs::path fresh_directory(const std::string& name) {
  const fs::path directory = fs::temp_directory_path() /
                             ("quadrix_user_" + name + "_" + std::to_string(std::chrono::steady_clock::now().time_since_epoch().count()));
  fs::create_directories(directory);
  return directory;
}

/// An RGB image read back from a PNG.
struct Picture {
  int width = 0, height = 0;
  std::vector<unsigned char> rgb;
  std::array<unsigned char, 3> at(int x, int y) const {
    const unsigned char* p = &rgb[3 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x))];
    return {p[0], p[1], p[2]};
  }
};

Picture read_png(const fs::path& path) {
  Picture picture;
  int channels = 0;
  unsigned char* pixels = stbi_load(path.string().c_str(), &picture.width, &picture.height, &channels, 3);
  EXPECT_NE(pixels, nullptr) << path;
  if (pixels == nullptr) return picture;
  picture.rgb.assign(pixels, pixels + 3 * static_cast<std::size_t>(picture.width) * static_cast<std::size_t>(picture.height));
  stbi_image_free(pixels);
  return picture;
}

// Whether the region [x0, x1) x [y0, y1) holds a solid block of `color`, at least `side` pixels
// square (a legend swatch; scattered points of that colour do not make one).
bool has_solid_block(const Picture& picture, int x0, int y0, int x1, int y1, std::array<unsigned char, 3> color, int side) {
  for (int y = y0; y + side <= y1 && y + side <= picture.height; ++y)
    for (int x = x0; x + side <= x1 && x + side <= picture.width; ++x) {
      bool solid = true;
      for (int dy = 0; dy < side && solid; ++dy)
        for (int dx = 0; dx < side && solid; ++dx) solid = picture.at(x + dx, y + dy) == color;
      if (solid) return true;
    }
  return false;
}

class UserCommands : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    directory_ = fresh_directory("suite");
    street_ = directory_ / "street";
    ASSERT_EQ(quadrix("synth street --seed 3 --sensor hdl64 --out '" + street_.string() + "'", directory_ / "synth.out"), 0)
        << read_text(directory_ / "synth.out.err");
    std::istringstream pairs(read_text(street_ / "pairs.tsv"));
    std::string header, id, source, target, truth;
    std::getline(pairs, header);
    pairs >> id >> source >> target >> truth;
    source_ = street_ / source;
    target_ = street_ / target;
    truth_ = street_ / truth;
  }
  static void TearDownTestSuite() { fs::remove_all(directory_); }
  static fs::path directory_, street_, source_, target_, truth_;
};
fs::path UserCommands::directory_, UserCommands::street_, UserCommands::source_, UserCommands::target_, UserCommands::truth_;

TEST_F(UserCommands, ModelAcceptsAutoAndUsesItByDefaultAsRegisterDoes) {
  const fs::path out = directory_ / "model_default.json", asked = directory_ / "model_auto.json";
  ASSERT_EQ(quadrix("model '" + source_.string() + "' --no-page --out '" + out.string() + "'", directory_ / "m1.out"), 0)
      << read_text(directory_ / "m1.out.err");
  ASSERT_EQ(quadrix("model '" + source_.string() + "' --preset auto --no-page --out '" + asked.string() + "'", directory_ / "m2.out"), 0)
      << read_text(directory_ / "m2.out.err");
  const nlohmann::json by_default = nlohmann::json::parse(read_text(out)), with_auto = nlohmann::json::parse(read_text(asked));
  EXPECT_EQ(by_default["stats"]["preset_requested"], "auto");
  EXPECT_EQ(with_auto["stats"]["preset_requested"], "auto");
  EXPECT_EQ(by_default["stats"]["preset"], with_auto["stats"]["preset"]);
  EXPECT_EQ(by_default["quadrics"].size(), with_auto["quadrics"].size());
  EXPECT_FALSE(by_default["stats"]["preset_notes"].get<std::string>().empty()) << "auto's measurements go to the model JSON";
  // The one-line preset summary on the terminal; the measurements behind --verbose.
  const std::string printed = read_text(directory_ / "m2.out");
  EXPECT_NE(printed.find("preset auto -> " + with_auto["stats"]["preset"].get<std::string>()), std::string::npos) << printed;
  EXPECT_EQ(printed.find("azimuth coverage"), std::string::npos) << printed;
  // Every record carries its plain shape parameters.
  for (const auto& record : by_default["quadrics"]) {
    ASSERT_TRUE(record.contains("shape")) << record.dump();
    const std::string type = record["type"];
    if (type == "plane") {
      EXPECT_TRUE(record["shape"].contains("normal") && record["shape"].contains("offset")) << record.dump();
    }
    if (type == "circular_cylinder") {
      EXPECT_GT(record["shape"]["radius"].get<double>(), 0.0) << record.dump();
    }
  }
}

TEST_F(UserCommands, BareConfigPrintsTheDefaultsAndExplainsAuto) {
  const fs::path out = directory_ / "config.yaml";
  ASSERT_EQ(quadrix("config", out), 0) << read_text(fs::path(out.string() + ".err"));
  const std::string text = read_text(out);
  EXPECT_NE(text.find("preset auto"), std::string::npos) << text.substr(0, 800);
  EXPECT_NE(text.find("chooses per cloud"), std::string::npos);
  // What it prints is a configuration `register --config` and `config --config` accept.
  EXPECT_EQ(quadrix("config --preset vlp16 --config '" + out.string() + "'", directory_ / "config2.yaml"), 0)
      << read_text(directory_ / "config2.yaml.err");
}

TEST_F(UserCommands, HelpListsTheResearchCommandsApart) {
  const fs::path out = directory_ / "help.txt";
  ASSERT_EQ(quadrix("--help", out), 0);
  const std::string help = read_text(out);
  const std::size_t research = help.find("Research commands");
  ASSERT_NE(research, std::string::npos) << help;
  for (const char* user : {"model", "register", "view", "info", "config", "fit", "synth", "bench"}) {
    const std::size_t at = help.find(std::string("\n  ") + user + " ");
    EXPECT_LT(at, research) << user << " is listed among the research commands:\n" << help;
  }
  for (const char* study : {"fitter-segments", "compare-refiners", "compare-fitters", "paper"}) {
    const std::size_t at = help.find(std::string("\n  ") + study);
    EXPECT_NE(at, std::string::npos) << study;
    EXPECT_GT(at, research) << study << " is listed among the user's commands:\n" << help;
  }
}

// Points on known shapes, written to a file, fitted by `quadrix fit`: the plain parameters must be
// the shape's (the fitter's accuracy on clean points is far inside these tolerances).
TEST_F(UserCommands, FitPrintsPlainShapeParameters) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const Eigen::Vector3d axis = Eigen::Vector3d(0.2, -0.1, 1.0).normalized();
  const Eigen::Matrix3d frame = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), axis).toRotationMatrix();
  const Eigen::Vector3d base(3.0, -2.0, 0.5);
  const auto fit = [&](const std::string& name, const std::string& type, const std::function<Eigen::Vector3d()>& sample) {
    PointCloud cloud;
    cloud.positions.resize(3, 3000);
    for (Eigen::Index i = 0; i < 3000; ++i) cloud.positions.col(i) = sample().cast<float>();
    const fs::path file = directory_ / (name + ".ply");
    write_point_cloud(file.string(), cloud);
    const fs::path out = directory_ / (name + ".json");
    EXPECT_EQ(quadrix("fit '" + file.string() + "' --type " + type + " --fitter constrained", out), 0) << read_text(fs::path(out.string() + ".err"));
    return nlohmann::json::parse(read_text(out));
  };
  const auto direction_error = [](const nlohmann::json& value, const Eigen::Vector3d& truth) {
    const Eigen::Vector3d v(value[0].get<double>(), value[1].get<double>(), value[2].get<double>());
    return std::acos(std::min(1.0, std::abs(v.normalized().dot(truth)))) * 180.0 / 3.141592653589793;
  };
  // Cylinder: radius 0.62, 3 m along the axis.
  const nlohmann::json cylinder = fit("cylinder", "cylinder", [&] {
    const double angle = 2.0 * 3.141592653589793 * unit(random), along = 3.0 * unit(random);
    return Eigen::Vector3d(base + frame * Eigen::Vector3d(0.62 * std::cos(angle), 0.62 * std::sin(angle), along));
  });
  ASSERT_TRUE(cylinder.contains("shape")) << cylinder.dump(2);
  EXPECT_NEAR(cylinder["shape"]["radius"].get<double>(), 0.62, 0.01) << cylinder.dump(2);
  EXPECT_LT(direction_error(cylinder["shape"]["axis"], axis), 0.5);
  EXPECT_NEAR(cylinder["shape"]["height"].get<double>(), 3.0, 0.05);
  EXPECT_EQ(cylinder["rotation"].size(), 4u) << "rotation is a quaternion (w, x, y, z), as in model records";
  EXPECT_EQ(cylinder["rotation_matrix"].size(), 9u);
  // Sphere: radius 1.5.
  const nlohmann::json sphere = fit("sphere", "sphere", [&] {
    const double z = 2.0 * unit(random) - 1.0, angle = 2.0 * 3.141592653589793 * unit(random), r = std::sqrt(1.0 - z * z);
    return Eigen::Vector3d(base + 1.5 * Eigen::Vector3d(r * std::cos(angle), r * std::sin(angle), z));
  });
  EXPECT_NEAR(sphere["shape"]["radius"].get<double>(), 1.5, 0.01) << sphere.dump(2);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(sphere["shape"]["center"][k].get<double>(), base[k], 0.01);
  // Cone: half-angle 25 deg, apex at `base`, 2 m along the axis.
  const double half_angle = 25.0 * 3.141592653589793 / 180.0;
  const nlohmann::json cone = fit("cone", "cone", [&] {
    const double along = 0.3 + 2.0 * unit(random), angle = 2.0 * 3.141592653589793 * unit(random);
    const double radius = along * std::tan(half_angle);
    return Eigen::Vector3d(base + frame * Eigen::Vector3d(radius * std::cos(angle), radius * std::sin(angle), along));
  });
  EXPECT_NEAR(cone["shape"]["half_angle_deg"].get<double>(), 25.0, 0.5) << cone.dump(2);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(cone["shape"]["apex"][k].get<double>(), base[k], 0.05);
  EXPECT_LT(direction_error(cone["shape"]["axis"], axis), 0.5);
  const Eigen::Vector3d cone_axis(cone["shape"]["axis"][0].get<double>(), cone["shape"]["axis"][1].get<double>(),
                                  cone["shape"]["axis"][2].get<double>());
  EXPECT_GT(cone_axis.dot(axis), 0.0) << "the axis points into the nappe holding the points";
  // Plane: normal n, n . x + offset = 0.
  const nlohmann::json plane = fit("plane", "plane", [&] {
    return Eigen::Vector3d(base + frame * Eigen::Vector3d(4.0 * unit(random) - 2.0, 4.0 * unit(random) - 2.0, 0.0));
  });
  EXPECT_LT(direction_error(plane["shape"]["normal"], axis), 0.5) << plane.dump(2);
  const Eigen::Vector3d normal(plane["shape"]["normal"][0].get<double>(), plane["shape"]["normal"][1].get<double>(),
                               plane["shape"]["normal"][2].get<double>());
  EXPECT_NEAR(normal.dot(base) + plane["shape"]["offset"].get<double>(), 0.0, 0.01);
}

TEST_F(UserCommands, RegisterPrintsShortLinesAndABirdsEyePictureWithLegendAndStatus) {
  const fs::path out = directory_ / "register.txt", folder = directory_ / "register";
  ASSERT_EQ(quadrix("register '" + source_.string() + "' '" + target_.string() + "' --gt '" + truth_.string() + "' --out '" +
                        folder.string() + "'",
                    out),
            0)
      << read_text(fs::path(out.string() + ".err"));
  std::istringstream lines(read_text(out));
  for (std::string line; std::getline(lines, line);)
    EXPECT_LE(line.size(), 200u) << "a terminal line is a paragraph: " << line;
  EXPECT_NE(read_text(out).find("RTE "), std::string::npos);
  const fs::path verbose = directory_ / "register_verbose.txt";
  ASSERT_EQ(quadrix("register '" + source_.string() + "' '" + target_.string() + "' --verbose", verbose), 0);
  EXPECT_NE(read_text(verbose).find("timings (ms"), std::string::npos) << read_text(verbose);

  const std::string status = nlohmann::json::parse(read_text(folder / "report.json"))["status"];
  const Picture bev = read_png(folder / "bev.png");
  ASSERT_GT(bev.width, 0);
  // The banner along the top has the status's colour; the legend below it shows the source and
  // target colours and the two sensor crosses.
  const auto banner = status_picture_color(status);
  EXPECT_EQ(bev.at(bev.width - 3, 3), (std::array<unsigned char, 3>{banner[0], banner[1], banner[2]})) << status;
  const int region_x = bev.width / 2, region_y = bev.height / 4;
  EXPECT_TRUE(has_solid_block(bev, 0, 0, region_x, region_y, kBirdsEyeTargetColor, 8)) << "no target swatch in the legend";
  EXPECT_TRUE(has_solid_block(bev, 0, 0, region_x, region_y, kBirdsEyeSourceColor, 8)) << "no source swatch in the legend";
  // Legend text: dark antialiased glyph pixels inside the legend.
  int dark = 0;
  for (int y = 0; y < region_y; ++y)
    for (int x = 0; x < region_x; ++x) dark += bev.at(x, y)[0] < 60 && bev.at(x, y)[1] < 60 && bev.at(x, y)[2] < 60 ? 1 : 0;
  EXPECT_GT(dark, 200) << "no legend text";
}

TEST(BirdsEyePicture, AnAmbiguousAnswerDoesNotLookLikeAnOkOne) {
  const fs::path directory = fresh_directory("bev_status");
  PointCloud cloud;
  cloud.positions = Eigen::Matrix3Xf::Random(3, 5000) * 20.0F;
  std::map<std::string, std::array<unsigned char, 3>> banners;
  for (const std::string status : {"ok", "ambiguous", "degenerate"}) {
    BirdsEyeOptions options;
    options.status = status;
    write_birds_eye_png((directory / (status + ".png")).string(), cloud, cloud, Eigen::Isometry3d::Identity(), options);
    const Picture picture = read_png(directory / (status + ".png"));
    banners[status] = picture.at(picture.width - 2, 2);
  }
  EXPECT_NE(banners["ok"], banners["ambiguous"]);
  EXPECT_NE(banners["ok"], banners["degenerate"]);
  EXPECT_EQ(banners["ambiguous"], (std::array<unsigned char, 3>{246, 227, 168}));
  fs::remove_all(directory);
}

TEST_F(UserCommands, ModelPictureHasALegendOfTheTypesDrawn) {
  const fs::path json = directory_ / "pictured.json", picture_path = directory_ / "pictured.png";
  ASSERT_EQ(quadrix("model '" + source_.string() + "' --no-page --out '" + json.string() + "' --picture '" + picture_path.string() + "'",
                    directory_ / "picture.out"),
            0)
      << read_text(directory_ / "picture.out.err");
  const Picture picture = read_png(picture_path);
  ASSERT_GT(picture.width, 0);
  // The legend (top left) has a swatch per type drawn, the walls' plane colour and the ground's.
  const int region_x = picture.width / 2, region_y = picture.height / 2;
  EXPECT_TRUE(has_solid_block(picture, 0, 0, region_x, region_y, {120, 140, 180}, 8)) << "no plane swatch in the legend";
  EXPECT_TRUE(has_solid_block(picture, 0, 0, region_x, region_y, {226, 220, 205}, 8)) << "no ground swatch in the legend";
}

TEST(BenchPlots, AxesFollowTheDataTitlesFitAndSeriesHaveTheirOwnColours) {
  MethodSummary precise;
  precise.method = "quadrix";
  precise.rte_values = {0.01, 0.02, 0.03, 0.045};
  precise.rre_values = {0.1, 0.2, 0.15, 0.3};
  precise.by_difficulty = {{"easy", {4, 4}}};
  for (int stage = 0; stage < 15; ++stage) precise.stage_ms["stage_" + std::to_string(stage)] = {1.0 + stage, 2.0 + stage};
  const std::string cdf = bench_error_cdf_svg({precise});
  // Every RTE is under 0.05 m: the axis ends at 0.05, not at 4 m.
  EXPECT_NE(cdf.find(">0.05<"), std::string::npos) << cdf.substr(0, 3000);
  EXPECT_EQ(cdf.find(">4<"), std::string::npos);
  EXPECT_EQ(cdf.find(">10<"), std::string::npos);  // every RRE is under 0.5 deg: that axis ends at 0.5, not 10
  // Titles fit the picture (0.6 em a character at 14 px).
  for (const std::string& svg : {bench_success_svg({precise}), bench_time_svg({precise}), cdf}) {
    std::smatch width, title;
    ASSERT_TRUE(std::regex_search(svg, width, std::regex("width=\"([0-9]+)\"")));
    ASSERT_TRUE(std::regex_search(svg, title, std::regex("font-size=\"14\">([^<]*)<")));
    EXPECT_LE(10 + 0.6 * 14 * static_cast<double>(title[1].str().size()), std::stod(width[1])) << title[1];
  }
  // 15 stages, 15 different colours.
  const std::string time = bench_time_svg({precise});
  std::set<std::string> fills;
  const std::regex fill("<rect x=\"[0-9.]+\" y=\"[0-9.]+\" width=\"[0-9.e+-]+\" height=\"22\" fill=\"([^\"]+)\"");
  for (auto it = std::sregex_iterator(time.begin(), time.end(), fill); it != std::sregex_iterator(); ++it) fills.insert((*it)[1]);
  EXPECT_EQ(fills.size(), 15u) << time.substr(0, 2000);
}

}  // namespace
}  // namespace quadrix
