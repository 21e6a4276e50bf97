// The C++ side of the Python overhead measurement (docs/python.md): reads SOURCE and TARGET once,
// then RUNS times resolves the `auto` presets and runs register_clouds on the clouds in memory
// (what quadrix.register does between its arguments and its result), and prints each wall time
// and the median in ms. Usage: quadrix_register_timing SOURCE TARGET [RUNS=5]
#include "estimation/registration.h"
#include "estimation/registration_config.h"
#include "geometry/io.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  if (argc != 3 && argc != 4) {
    std::fprintf(stderr, "usage: %s SOURCE TARGET [RUNS=5]\n", argv[0]);
    return 2;
  }
  const int runs = argc == 4 ? std::atoi(argv[3]) : 5;
  if (runs < 1) {
    std::fprintf(stderr, "RUNS must be >= 1\n");
    return 2;
  }
  const quadrix::PointCloud source = quadrix::read_point_cloud(argv[1]);
  const quadrix::PointCloud target = quadrix::read_point_cloud(argv[2]);
  std::vector<double> times;
  for (int run = 0; run < runs; ++run) {
    const auto start = std::chrono::steady_clock::now();
    const quadrix::RegistrationOptions options = quadrix::resolve_registration_options("auto", source, "auto", target);
    const quadrix::RegistrationResult result = quadrix::register_clouds(source, target, options);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    times.push_back(ms);
    std::printf("run %d: %.1f ms (%s; stages:", run + 1, ms, quadrix::registration_status_name(result.status));
    for (const auto& [stage, stage_ms] : result.timings_ms) std::printf(" %s %.1f", stage.c_str(), stage_ms);
    std::printf(")\n");
  }
  std::sort(times.begin(), times.end());
  std::printf("median %.1f ms over %d runs\n", times[times.size() / 2], runs);
  return 0;
}
