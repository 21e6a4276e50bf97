#include "experiments/synthetic/loop_closure_set.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "geometry/constants.h"
#include "geometry/error.h"
#include "experiments/synthetic/scanner_simulator.h"
#include "experiments/synthetic/synthetic_output.h"
#include "experiments/synthetic/synthetic_scene.h"
#include "geometry/io.h"

namespace quadrix {
namespace {

std::string bin_name(const std::pair<double, double>& bin) {
  std::ostringstream name;
  name << bin.first << "-" << bin.second;
  return name.str();
}

void check_options(const LoopClosureSetOptions& options) {
  if (options.streets < 1) throw Error("loop-closure set: streets must be at least 1, got " + std::to_string(options.streets));
  if (options.pairs_per_bin < 1)
    throw Error("loop-closure set: pairs per bin must be at least 1, got " + std::to_string(options.pairs_per_bin));
  if (options.bins.empty()) throw Error("loop-closure set: no distance bin given");
  for (const auto& bin : options.bins)
    if (!(bin.first >= 0.0 && bin.second > bin.first))
      throw Error("loop-closure set: bin " + bin_name(bin) + " must satisfy 0 <= min < max");
}

// Writes the scans of one pass that `used` marks (with their sensor poses) under `folder`, relative to `root`.
void write_used_scans(const std::filesystem::path& root, const std::string& folder, const SyntheticRun& run,
                      const std::vector<bool>& used) {
  std::filesystem::create_directories(root / folder);
  for (std::size_t i = 0; i < run.scans.size(); ++i) {
    if (!used[i]) continue;
    write_point_cloud((root / (folder + "/scan_" + three_digits(i) + ".ply")).string(), run.scans[i].cloud);
    write_pose_matrix((root / (folder + "/pose_" + three_digits(i) + ".txt")).string(), run.scans[i].sensor_pose);
  }
}

}  // namespace

std::vector<LoopClosureSetPair> write_loop_closure_set(const std::string& directory, const LoopClosureSetOptions& options) {
  check_options(options);
  const SensorModel& sensor = options.sensor;
  const SensorModel& source_sensor = options.source_sensor ? *options.source_sensor : sensor;
  const std::string sensor_column = options.source_sensor ? source_sensor.name + "->" + sensor.name : sensor.name;
  const std::filesystem::path root(directory);
  std::filesystem::create_directories(root);
  std::vector<LoopClosureSetPair> pairs;
  for (int street = 0; street < options.streets; ++street) {
    const std::uint64_t seed = options.first_seed + static_cast<std::uint64_t>(street);
    const std::string street_folder = "street_" + std::to_string(seed);
    std::filesystem::create_directories(root / street_folder);
    const StreetPass first = make_street_pass(seed, 1, options.scan_spacing, options.street);
    const StreetPass second = make_street_pass(seed, options.same_direction ? 3 : 2, options.scan_spacing, options.street);
    // Each pass is its own drive: its own noise and dropout stream.
    const SyntheticRun first_run = run_synthetic(first.scene, sensor, first.poses, seed * 2 + 1);
    const SyntheticRun second_run = run_synthetic(second.scene, source_sensor, second.poses, seed * 2 + 2);
    const std::string target_folder = street_folder + "/pass_1";
    const std::string source_folder = street_folder + "/pass_2";
    std::vector<bool> target_used(first.poses.size(), false), source_used(second.poses.size(), false);
    // Every (second-pass, first-pass) scan pair by bin, then a seeded draw of pairs_per_bin from each.
    std::vector<std::vector<std::pair<std::size_t, std::size_t>>> by_bin(options.bins.size());
    for (std::size_t s = 0; s < second.poses.size(); ++s)
      for (std::size_t t = 0; t < first.poses.size(); ++t) {
        const double distance = (second.poses[s].translation() - first.poses[t].translation()).norm();
        for (std::size_t b = 0; b < options.bins.size(); ++b)
          if (distance >= options.bins[b].first && distance < options.bins[b].second) by_bin[b].emplace_back(s, t);
      }
    PortableRandom random(mix_bits(seed ^ 0x5eedULL));
    for (std::size_t b = 0; b < options.bins.size(); ++b) {
      std::vector<std::pair<std::size_t, std::size_t>>& candidates = by_bin[b];
      const std::size_t wanted = std::min(candidates.size(), static_cast<std::size_t>(options.pairs_per_bin));
      for (std::size_t k = 0; k < wanted; ++k) {  // partial Fisher-Yates with the portable generator
        const int pick = random.uniform_integer(static_cast<int>(k), static_cast<int>(candidates.size()) - 1);
        std::swap(candidates[k], candidates[static_cast<std::size_t>(pick)]);
        const auto [s, t] = candidates[k];
        const Eigen::Isometry3d truth = relative_transform(first.poses[t], second.poses[s]);
        LoopClosureSetPair pair;
        pair.id = "street" + std::to_string(seed) + "_p2_" + three_digits(s) + "_to_p1_" + three_digits(t);
        pair.source = source_folder + "/scan_" + three_digits(s) + ".ply";
        pair.target = target_folder + "/scan_" + three_digits(t) + ".ply";
        source_used[s] = target_used[t] = true;
        pair.truth = street_folder + "/T_p1_" + three_digits(t) + "_from_p2_" + three_digits(s) + ".txt";
        pair.bin = bin_name(options.bins[b]);
        pair.distance = truth.translation().norm();
        pair.rotation = std::acos(std::clamp((truth.linear().trace() - 1.0) / 2.0, -1.0, 1.0)) * 180.0 / kPi;
        write_pose_matrix((root / pair.truth).string(), truth);
        pairs.push_back(pair);
      }
    }
    write_used_scans(root, target_folder, first_run, target_used);
    write_used_scans(root, source_folder, second_run, source_used);
  }
  write_file_atomically((root / "pairs.tsv").string(), [&](std::ostream& out) {
    out << "id\tsource\ttarget\tgt\tgt_quality\tsensor\tkind\tt_m\trot_deg\n";
    for (const LoopClosureSetPair& pair : pairs)
      out << pair.id << '\t' << pair.source << '\t' << pair.target << '\t' << pair.truth << "\texact\t" << sensor_column
          << '\t' << pair.bin << '\t' << decimal_text(pair.distance, 2) << '\t' << decimal_text(pair.rotation, 1) << '\n';
  });
  return pairs;
}

}  // namespace quadrix
