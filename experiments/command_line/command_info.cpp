// `quadrix info FILE... [--format F]`: what a reader finds in each point-cloud file.
#include "experiments/command_line/command_registry.h"
#include "geometry/io.h"

#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace quadrix::cli {
namespace {

/// Options of the info command.
struct InfoOptions {
  std::vector<std::string> files;  ///< point-cloud files to describe
  std::string format = "auto";     ///< format override (see cloud_format_from_name)
};

// Prints one file's description; throws quadrix::Error when it cannot be read.
void describe(const std::string& path, const CloudReadOptions& read_options) {
  CloudReadReport report;
  const auto start = std::chrono::steady_clock::now();
  const PointCloud cloud = read_point_cloud(path, read_options, &report);
  const double milliseconds = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  std::string fields;
  for (const std::string& field : report.fields) fields += (fields.empty() ? "" : " ") + field;
  std::string loaded = "positions";
  if (!cloud.intensity.empty()) loaded += ", intensity";
  if (!cloud.labels.empty()) loaded += ", labels";
  if (!cloud.colors.empty()) loaded += ", colours";
  for (const auto& entry : cloud.extra_fields) loaded += ", " + entry.first;
  std::printf("%s\n", path.c_str());
  std::printf("  format     %s (%s)\n", cloud_format_name(report.format).c_str(), report.encoding.c_str());
  std::printf("  points     %zu in file, %zu finite, %zu dropped (non-finite)\n", report.points_in_file, cloud.size(),
              report.non_finite_dropped);
  std::printf("  fields     %s\n", fields.empty() ? "(none)" : fields.c_str());
  std::printf("  loaded     %s\n", loaded.c_str());
  if (cloud.empty()) {
    std::printf("  bounds     (empty cloud)\n");
  } else {
    const Eigen::Vector3f minimum = cloud.positions.rowwise().minCoeff();
    const Eigen::Vector3f maximum = cloud.positions.rowwise().maxCoeff();
    const Eigen::Vector3f extent = maximum - minimum;
    std::printf("  min        %.4f %.4f %.4f\n", minimum.x(), minimum.y(), minimum.z());
    std::printf("  max        %.4f %.4f %.4f\n", maximum.x(), maximum.y(), maximum.z());
    std::printf("  extent     %.4f x %.4f x %.4f m\n", extent.x(), extent.y(), extent.z());
  }
  std::printf("  read time  %.2f ms\n", milliseconds);
}

void run(const InfoOptions& options) {
  CloudReadOptions read_options;
  read_options.format = cloud_format_from_name(options.format);
  std::size_t failed = 0;
  std::string last_error;
  for (std::size_t i = 0; i < options.files.size(); ++i) {
    if (i > 0) std::printf("\n");
    try {
      describe(options.files[i], read_options);
    } catch (const Error& error) {
      std::fflush(stdout);
      ++failed;
      last_error = error.what();
      if (options.files.size() > 1) std::fprintf(stderr, "quadrix: error: %s\n", error.what());
    }
    std::fflush(stdout);
  }
  if (failed == 0) return;
  if (options.files.size() == 1) throw Error(last_error);
  throw Error(std::to_string(failed) + " of " + std::to_string(options.files.size()) + " files could not be read");
}

const CommandRegistration registration(10, [](CLI::App& app) {
  auto options = std::make_shared<InfoOptions>();
  CLI::App* command = app.add_subcommand(
      "info", "Describe point-cloud files: format, encoding, point counts, fields, bounding box, read time");
  command->add_option("files", options->files, "Point-cloud files (.bin .pcd.bin .ply .pcd .xyz .txt .csv .npy)")
      ->required()
      ->expected(1, -1);
  command
      ->add_option("--format", options->format,
                   "Read every file as this format: auto (by extension), bin, kitti-bin, nuscenes-bin, ply, pcd, "
                   "xyz, csv, npy")
      ->capture_default_str();
  command->callback([options] { run(*options); });
});

}  // namespace
}  // namespace quadrix::cli
