// `quadrix fitter-segments`: segments cut from simulated scans with their true primitives
// (experiments/synthetic/scan_segments.h), written as .npy for the learned fitter's training script:
//   quadrix fitter-segments --seed 101 --scans 600 --object-scans 3000 --out /tmp/segments
#include "geometry/output_paths.h"
#include "experiments/command_line/command_registry.h"
#include "experiments/synthetic/scan_segments.h"

#include <iostream>
#include <map>
#include <memory>
#include <string>

namespace quadrix::cli {
namespace {

const CommandRegistration registration(22, [](CLI::App& app) {
  auto options = std::make_shared<ScanSegmentOptions>();
  auto out = std::make_shared<std::string>("fitter_segments");
  CLI::App* command = app.add_subcommand(
      "fitter-segments",
      "Simulate scans of the synthetic scenes with every sensor and cut one segment per primitive seen (partial, "
      "ring-sampled, noisy, with neighbours' points); write points.npy, segments.npy and segments.json");
  command->group(kResearchCommands);
  command->add_option("--seed", options->seed, "Seed of scenes, sensor places and noise")->capture_default_str();
  command->add_option("--scans", options->scans, "Scans to simulate (scenes and sensors cycle)")->capture_default_str();
  command->add_option("--object-scans", options->object_scans, "Scans of one object on the ground, after the scene scans")
      ->capture_default_str();
  command->add_option("--scenes", options->scenes, "Scenes, cycled per scan")->delimiter(',')->capture_default_str();
  command->add_option("--sensors", options->sensors, "Sensors, cycled per scan")->delimiter(',')->capture_default_str();
  command->add_option("--crops", options->crops_per_segment, "Extra half-space crops per segment")->capture_default_str();
  command->add_option("--max-points", options->max_points, "Thin larger segments to this many points")->capture_default_str();
  command->add_option("--out", *out, "Output folder")->capture_default_str();
  command->callback([options, out] {
    // The output folder is checked before the simulation and replaced at once after it.
    FolderReplacement output("--out", *out, {"points.npy", "segments.npy", "segments.json"}, {});
    const std::vector<ScanSegment> segments = make_scan_segments(*options);
    write_scan_segments(output.staging_folder(), segments, *options);
    output.commit();
    std::map<std::string, int> counts;
    for (const ScanSegment& segment : segments) ++counts[quadric_type_name(segment.type)];
    std::cout << "fitter-segments: " << segments.size() << " segments from " << options->scans << " scene scans and "
              << options->object_scans << " object scans (";
    bool first = true;
    for (const auto& [name, count] : counts) {
      std::cout << (first ? "" : ", ") << name << ' ' << count;
      first = false;
    }
    std::cout << ") in " << *out << std::endl;
  });
});

}  // namespace
}  // namespace quadrix::cli
