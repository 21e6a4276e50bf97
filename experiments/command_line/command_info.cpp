// `quadrix info FILE... [--format F]`: what a reader finds in each point-cloud file.
#include "experiments/command_line/command_registry.h"
#include "geometry/io.h"
#include "geometry/las.h"

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

// Prints what a LAS public header declares (coordinates are X * scale + offset, in the file's units).
void print_las_header(const LasHeader& header) {
  std::printf("  LAS        version %d.%d, point format %d, %zu-byte records (%zu extra bytes), %zu VLRs\n",
              header.version_major, header.version_minor, header.point_format, header.record_length,
              header.extra_bytes, header.vlr_count);
  std::printf("  count      %llu (header)\n", static_cast<unsigned long long>(header.point_count));
  std::printf("  scale      %.10g %.10g %.10g\n", header.scale.x(), header.scale.y(), header.scale.z());
  std::printf("  offset     %.10g %.10g %.10g\n", header.offset.x(), header.offset.y(), header.offset.z());
  std::printf("  header min %.4f %.4f %.4f\n", header.min.x(), header.min.y(), header.min.z());
  std::printf("  header max %.4f %.4f %.4f\n", header.max.x(), header.max.y(), header.max.z());
  if (!header.system_identifier.empty() || !header.generating_software.empty())
    std::printf("  written by %s / %s\n", header.system_identifier.c_str(), header.generating_software.c_str());
  const LasUnits& units = header.units;
  if (units.source.empty()) {
    std::printf("  units      not declared (no CRS record the reader understands)\n");
  } else {
    const std::string horizontal = units.horizontal_name.empty() ? "not declared" : units.horizontal_name;
    std::printf("  units      x, y: %s", horizontal.c_str());
    if (units.horizontal_metres > 0.0) std::printf(" (%.10g m)", units.horizontal_metres);
    if (!units.vertical_name.empty()) std::printf("; z: %s (%.10g m)", units.vertical_name.c_str(), units.vertical_metres);
    std::printf("; from the %s\n", units.source.c_str());
  }
}

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
  if (report.format == CloudFormat::Las) print_las_header(read_las_header(path));
  std::printf("  points     %zu in file, %zu finite, %zu dropped (non-finite)\n", report.points_in_file, cloud.size(),
              report.non_finite_dropped);
  std::printf("  fields     %s\n", fields.empty() ? "(none)" : fields.c_str());
  std::printf("  loaded     %s\n", loaded.c_str());
  if (!cloud.local_origin.isZero(0.0))
    std::printf("  origin     %.3f %.3f %.3f (local origin: positions kept relative to it in float32)\n",
                cloud.local_origin.x(), cloud.local_origin.y(), cloud.local_origin.z());
  if (cloud.empty()) {
    std::printf("  bounds     (empty cloud)\n");
  } else {
    const Eigen::Vector3d minimum = cloud.local_origin + cloud.positions.rowwise().minCoeff().cast<double>();
    const Eigen::Vector3d maximum = cloud.local_origin + cloud.positions.rowwise().maxCoeff().cast<double>();
    const Eigen::Vector3d extent = maximum - minimum;
    std::printf("  min        %.4f %.4f %.4f\n", minimum.x(), minimum.y(), minimum.z());
    std::printf("  max        %.4f %.4f %.4f\n", maximum.x(), maximum.y(), maximum.z());
    std::printf("  extent     %.4f x %.4f x %.4f m\n", extent.x(), extent.y(), extent.z());
  }
  std::printf("  read time  %.2f ms\n", milliseconds);
}

void run(const InfoOptions& options) {
  CloudReadOptions read_options;
  read_options.format = cloud_format_from_name(options.format);
  read_options.local_origin = LocalOrigin::Auto;  // bounds printed in the file's coordinates, without float32 rounding
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
      "info", "Describe point-cloud files: format, encoding, point counts, fields, bounding box, read time (LAS: the "
      "header's version, point format, count, scale, offset and bounds)");
  command->add_option("files", options->files, "Point-cloud files (.bin .pcd.bin .ply .pcd .xyz .txt .csv .npy .las)")
      ->required()
      ->expected(1, -1);
  command
      ->add_option("--format", options->format,
                   "Read every file as this format: auto (by extension), bin, kitti-bin, nuscenes-bin, ply, pcd, "
                   "xyz, csv, npy, las")
      ->capture_default_str();
  command->callback([options] { run(*options); });
});

}  // namespace
}  // namespace quadrix::cli
