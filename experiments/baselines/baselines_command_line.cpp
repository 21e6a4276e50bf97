// quadrix-baselines: runs one baseline (Open3D FPFH + RANSAC / FGR, PCL prerejective) on two point
// cloud files and prints its result as one JSON object (baseline_protocol.h) on stdout. `quadrix
// bench` runs it in a child process, so the `quadrix` executable does not load Open3D.
#include "experiments/baselines/baselines.h"
#include "geometry/error.h"
#include "geometry/io.h"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>
#include <fstream>
#include <sstream>
#include <stdexcept>

int main(int argc, char** argv) {
  CLI::App app{"Runs one baseline registration method and prints its result as JSON (used by quadrix bench)"};
  std::string method, source_path, target_path, options_path;
  std::string names;
  for (const std::string& name : quadrix::baseline_method_names()) names += (names.empty() ? "" : "|") + name;
  app.add_option("method", method, "Baseline: " + names)->required();
  app.add_option("source", source_path, "Source point cloud file")->required();
  app.add_option("target", target_path, "Target point cloud file")->required();
  app.add_option("--options", options_path, "JSON file of BaselineOptions fields (missing fields keep their defaults)");
  CLI11_PARSE(app, argc, argv);
  try {
    quadrix::BaselineOptions options;
    if (!options_path.empty()) {
      std::ifstream file(options_path);
      if (!file) throw quadrix::Error(options_path + ": cannot open the options file");
      std::ostringstream text;
      text << file.rdbuf();
      try {
        options = quadrix::baseline_options_from_json(text.str());
      } catch (const quadrix::Error& error) {
        throw quadrix::Error(options_path + ": " + error.what());
      }
    }
    const quadrix::PointCloud source = quadrix::read_point_cloud(source_path);
    const quadrix::PointCloud target = quadrix::read_point_cloud(target_path);
    const quadrix::BaselineResult result = quadrix::run_baseline(method, source, target, options);
    std::printf("%s\n", quadrix::baseline_result_to_json(result).c_str());
    return 0;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "quadrix-baselines: %s\n", error.what());
    return 2;
  }
}
