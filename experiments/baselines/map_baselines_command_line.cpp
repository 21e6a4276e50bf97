// quadrix-map-baselines METHOD SCANS.tsv --out DIR [--gt TRUTH.tsv]: a mapping baseline (odometry,
// icp-loops, multiway; map_baselines.h) on a scan list, written in `quadrix map`'s folder format.
#include "experiments/baselines/map_baselines.h"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>

int main(int argc, char** argv) {
  CLI::App app{"Runs a mapping baseline (odometry alone, ICP loop closure with radius search, Open3D multiway registration) "
               "on a SCANS.tsv and writes poses.tsv, edges.csv and report.json"};
  std::string method, scans, out, truth;
  quadrix::MapBaselineOptions options;
  app.add_option("method", method, "odometry, icp-loops or multiway")->required();
  app.add_option("scans", scans, "SCANS.tsv: session, scan, odometry")->required();
  app.add_option("--out", out, "Output folder")->required();
  app.add_option("--gt", truth, "True poses (poses.tsv format): ATE and wrong used loop edges into report.json");
  app.add_option("--radius", options.radius, "Loop candidate radius around the odometry position, m")->capture_default_str();
  app.add_option("--min-age", options.min_age, "Candidates are more than this many scans older")->capture_default_str();
  app.add_option("--voxel", options.voxel_size, "ICP down-sampling voxel, m")->capture_default_str();
  app.add_option("--icp-distance", options.icp_distance, "ICP maximum correspondence distance, m")->capture_default_str();
  app.add_option("--min-fitness", options.min_fitness, "icp-loops gate: least ICP fitness")->capture_default_str();
  app.add_option("--max-rmse", options.max_rmse, "icp-loops gate: largest ICP inlier RMSE, m")->capture_default_str();
  app.add_option("--threads", options.threads, "OpenMP threads of Open3D")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    const quadrix::MapBaselineSummary summary = quadrix::run_map_baseline(method, scans, out, truth, options);
    std::printf("%s: %d scans, %d loop candidates, %d loop edges used, %.1f s", summary.method.c_str(), summary.scans,
                summary.loop_candidates, summary.loop_edges_used, summary.seconds);
    for (const auto& [name, value] : summary.ate) std::printf(", ATE %s %.2f m", name.c_str(), value);
    if (summary.wrong_used_edges >= 0) std::printf(", %d used loop edges wrong", summary.wrong_used_edges);
    std::printf("\n");
    return 0;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "quadrix-map-baselines: %s\n", error.what());
    return 2;
  }
}
