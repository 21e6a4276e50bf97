// Pose specifications, simulation runs over several poses, and the `quadrix synth` output folder.
#include "experiments/synthetic/synthetic_output.h"

#include "geometry/constants.h"
#include "geometry/error.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace quadrix {

namespace {

using nlohmann::ordered_json;

/// Rounds to 12 significant digits so files show short, stable numbers.
double tidy(double value) {
  if (!std::isfinite(value)) return value;
  char buffer[40];
  std::snprintf(buffer, sizeof(buffer), "%.12g", value);
  const double rounded = std::strtod(buffer, nullptr);
  return rounded == 0.0 ? 0.0 : rounded;  // no "-0.0"
}

template <typename Derived>
ordered_json vector_json(const Eigen::MatrixBase<Derived>& values) {
  ordered_json array = ordered_json::array();
  for (Eigen::Index i = 0; i < values.size(); ++i) array.push_back(tidy(values(i)));
  return array;
}

ordered_json matrix_json(const Eigen::Matrix4d& matrix) {
  ordered_json rows = ordered_json::array();
  for (int r = 0; r < 4; ++r) rows.push_back(vector_json(matrix.row(r).transpose()));
  return rows;
}

Eigen::Isometry3d pose_from_angles(const std::vector<double>& values) {
  const double to_radians = kPi / 180.0;
  const double yaw = values[3] * to_radians;
  const double pitch = values.size() > 4 ? values[4] * to_radians : 0.0;
  const double roll = values.size() > 5 ? values[5] * to_radians : 0.0;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                   Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                      .toRotationMatrix();
  pose.translation() = Eigen::Vector3d(values[0], values[1], values[2]);
  return pose;
}

/// Numbers of one entry separated by commas and/or whitespace; throws naming `where`.
std::vector<double> parse_numbers(const std::string& text, const std::string& where) {
  std::string spaced = text;
  for (char& character : spaced)
    if (character == ',' || character == '\t') character = ' ';
  std::istringstream stream(spaced);
  std::vector<double> values;
  std::string token;
  while (stream >> token) {
    char* end = nullptr;
    const double value = std::strtod(token.c_str(), &end);
    if (end == token.c_str() || *end != '\0' || !std::isfinite(value))
      throw Error(where + ": '" + token + "' is not a finite number");
    values.push_back(value);
  }
  return values;
}

Eigen::Isometry3d pose_from_numbers(const std::vector<double>& values, const std::string& where) {
  if (values.size() >= 4 && values.size() <= 6) return pose_from_angles(values);
  if (values.size() == 12 || values.size() == 16) {
    Eigen::Matrix4d matrix = Eigen::Matrix4d::Identity();
    for (std::size_t i = 0; i < values.size(); ++i) matrix(static_cast<int>(i / 4), static_cast<int>(i % 4)) = values[i];
    const Eigen::Matrix3d rotation = matrix.topLeftCorner<3, 3>();
    if (!(rotation.transpose() * rotation).isApprox(Eigen::Matrix3d::Identity(), 1e-6) || rotation.determinant() < 0.0)
      throw Error(where + ": the 3x3 block is not a rotation matrix");
    if (values.size() == 16 && !matrix.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1), 1e-9))
      throw Error(where + ": the last row of a 4x4 pose must be 0 0 0 1");
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = rotation;
    pose.translation() = matrix.topRightCorner<3, 1>();
    return pose;
  }
  throw Error(where + ": expected 4-6 numbers (x y z yaw_deg [pitch_deg [roll_deg]]) or 12/16 (row-major pose), got " +
              std::to_string(values.size()));
}

const char* pattern_name(ScanPattern pattern) {
  switch (pattern) {
    case ScanPattern::Spinning: return "spinning";
    case ScanPattern::Rosette: return "rosette";
    case ScanPattern::Dome: return "dome";
  }
  return "unknown";
}

void write_text(const std::string& path, const std::string& text) {
  write_file_atomically(path, [&text](std::ostream& stream) { stream << text; });
}

}  // namespace

std::string three_digits(std::size_t index) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%03zu", index);
  return buffer;
}

std::string decimal_text(double value, int decimals) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.*f", decimals, value);
  return buffer;
}

std::vector<Eigen::Isometry3d> parse_pose_spec(const std::string& spec) {
  std::vector<Eigen::Isometry3d> poses;
  std::error_code error;
  if (std::filesystem::is_regular_file(spec, error)) {
    std::ifstream file(spec);
    if (!file) throw file_error(spec, "cannot open the pose file");
    std::string line;
    int line_number = 0;
    while (std::getline(file, line)) {
      ++line_number;
      const auto comment = line.find('#');
      if (comment != std::string::npos) line.erase(comment);
      if (line.find_first_not_of(" \t\r,") == std::string::npos) continue;
      const std::string where = spec + ":" + std::to_string(line_number);
      poses.push_back(pose_from_numbers(parse_numbers(line, where), where));
    }
    if (poses.empty()) throw file_error(spec, "no poses in the file");
    return poses;
  }
  std::size_t start = 0;
  int entry = 0;
  while (start <= spec.size()) {
    const std::size_t end = std::min(spec.find(';', start), spec.size());
    const std::string text = spec.substr(start, end - start);
    ++entry;
    if (text.find_first_not_of(" \t") != std::string::npos) {
      const std::string where = "--poses entry " + std::to_string(entry) + " '" + text + "'";
      const auto values = parse_numbers(text, where);
      if (values.size() < 4 || values.size() > 6)
        throw Error(where + ": expected x,y,z,yaw_deg[,pitch_deg[,roll_deg]] (or the path of an existing pose file)");
      poses.push_back(pose_from_angles(values));
    }
    start = end + 1;
  }
  if (poses.empty()) throw Error("--poses: no poses in '" + spec + "' (expected x,y,z,yaw_deg;... or a pose file)");
  return poses;
}

std::vector<Eigen::Isometry3d> default_sensor_poses(const Scene& scene, const SensorModel& sensor) {
  return sensor.pattern == ScanPattern::Dome ? scene.default_tls_stations : scene.default_lidar_poses;
}

SyntheticRun run_synthetic(const Scene& scene, const SensorModel& sensor, const std::vector<Eigen::Isometry3d>& poses,
                           std::uint64_t seed) {
  if (poses.empty()) throw Error("run_synthetic: at least one sensor pose is needed");
  SyntheticRun run;
  run.scene = scene;
  run.sensor = sensor;
  run.seed = seed;
  const RayCaster caster(run.scene);
  for (std::size_t i = 0; i < poses.size(); ++i)
    run.scans.push_back(simulate_scan(run.scene, caster, sensor, poses[i], seed, static_cast<std::uint32_t>(i)));
  return run;
}

Eigen::Isometry3d relative_transform(const Eigen::Isometry3d& target_pose, const Eigen::Isometry3d& source_pose) {
  return target_pose.inverse() * source_pose;
}

std::string primitives_json(const Scene& scene, int record_samples) {
  ordered_json primitives = ordered_json::array();
  for (const auto& primitive : scene.primitives) {
    ordered_json entry;
    entry["id"] = primitive.id;
    entry["name"] = primitive.name;
    entry["label"] = static_cast<std::uint32_t>(primitive.label);
    entry["label_name"] = semantic_label_name(primitive.label);
    entry["surface_type"] = quadric_type_name(primitive.surface_type);
    entry["model_type"] = quadric_type_name(primitive.model_type);
    entry["scale"] = vector_json(primitive.scale);
    entry["pose"] = matrix_json(primitive.pose.matrix());
    entry["extent"] = {{"minimum", vector_json(primitive.extent.minimum)},
                       {"maximum", vector_json(primitive.extent.maximum)}};
    ordered_json polygon = ordered_json::array();
    for (const auto& vertex : primitive.polygon) polygon.push_back(vector_json(vertex));
    entry["polygon"] = polygon;
    if (primitive.mean_free_path > 0.0) entry["mean_free_path"] = primitive.mean_free_path;
    entry["area_m2"] = tidy(primitive_surface_area(primitive));
    entry["surface_quadric"] = vector_json(surface_quadric(primitive).parameters());
    entry["model_quadric"] = vector_json(model_quadric(primitive).parameters());
    const auto record = ground_truth_record(primitive, record_samples).to_array();
    entry["record"] = vector_json(Eigen::Map<const Eigen::Matrix<double, 21, 1>>(record.data()));
    primitives.push_back(entry);
  }
  ordered_json document;
  document["scene"] = scene.name;
  document["seed"] = scene.seed;
  document["conventions"] = {
      {"frame", "world, metres, z up"},
      {"pose", "canonical frame -> world, 4x4 row-major; canonical axes a, b, c = pose columns 0, 1, 2"},
      {"canonical_surfaces",
       "plane: a = 0; cylinder: a^2/sa^2 + b^2/sb^2 = 1; sphere/ellipsoid: sum x_i^2/s_i^2 = 1; "
       "cone: a^2/sa^2 + b^2/sb^2 = c^2 (scale = tan of half-angles, 1)"},
      {"extent", "surface kept where canonical coordinates lie in [minimum, maximum] (a ignored for planes)"},
      {"polygon", "planes only: convex polygon in (b, c), counter-clockwise, further bounding the surface"},
      {"mean_free_path", "porous volumes (foliage) only: mean depth, m, a ray travels inside before it stops"},
      {"quadric", "10 parameters A..J of x^T Q x = 0 (paper Eq. quadrics equation), Quadric::from_canonical"},
      {"record", "21 numbers of paper Struct. 1: label, q(10), full scale(3), full rotation quaternion w,x,y,z(4), "
                 "full centre(3), from the model quadric and the statistics of true surface samples"}};
  document["primitives"] = primitives;
  return document.dump(1) + "\n";
}

namespace {

// The files of a synthetic folder as scene.json lists them, and their paths in writing order.
struct FileIndex {
  ordered_json files = ordered_json::array();
  std::vector<std::string> written;

  void add(const std::string& path, const std::string& kind, const std::string& description) {
    files.push_back({{"path", path}, {"kind", kind}, {"description", description}});
    written.push_back(path);
  }
};

// Every scan (cloud in its sensor frame) and its sensor pose; returns scene.json's "scans".
ordered_json write_scans(const std::filesystem::path& root, const SyntheticRun& run, const SyntheticOutputOptions& options,
                         const std::string& extension, FileIndex& index) {
  ordered_json scans = ordered_json::array();
  CloudWriteOptions cloud_options;
  cloud_options.format = options.cloud_format;
  cloud_options.binary = options.binary;
  for (std::size_t i = 0; i < run.scans.size(); ++i) {
    const SimulatedScan& scan = run.scans[i];
    const std::string cloud_path = "scan_" + three_digits(i) + extension;
    const std::string pose_path = "pose_" + three_digits(i) + ".txt";
    write_point_cloud((root / cloud_path).string(), scan.cloud, cloud_options);
    write_pose_matrix((root / pose_path).string(), scan.sensor_pose);
    index.add(cloud_path, "point_cloud",
              "scan " + std::to_string(i) + " in its sensor frame; label = semantic label, primitive_id = true primitive");
    index.add(pose_path, "sensor_pose", "sensor -> world pose of scan " + std::to_string(i) + ", 4x4 row-major");
    std::size_t primitives_seen = 0;
    for (std::size_t count : scan.points_per_primitive) primitives_seen += count > 0 ? 1 : 0;
    scans.push_back({{"index", i},
                     {"cloud", cloud_path},
                     {"pose", pose_path},
                     {"sensor_to_world", matrix_json(scan.sensor_pose.matrix())},
                     {"rays", scan.rays},
                     {"points", scan.cloud.size()},
                     {"misses", scan.misses},
                     {"too_near", scan.too_near},
                     {"dropped", scan.dropped},
                     {"primitives_seen", primitives_seen}});
  }
  return scans;
}

// Ground-truth relative transforms of every pair (target = lower index, source = higher index) and
// pairs.tsv; returns scene.json's "pairs".
ordered_json write_pairs(const std::filesystem::path& root, const SyntheticRun& run, const std::string& extension,
                         FileIndex& index) {
  ordered_json pairs = ordered_json::array();
  std::ostringstream tsv;
  tsv << "id\tsource\ttarget\tgt\tgt_quality\tsensor\tkind\tt_m\trot_deg\n";
  for (std::size_t target = 0; target < run.scans.size(); ++target) {
    for (std::size_t source = target + 1; source < run.scans.size(); ++source) {
      const Eigen::Isometry3d transform = relative_transform(run.scans[target].sensor_pose, run.scans[source].sensor_pose);
      const std::string path = "T_" + three_digits(target) + "_from_" + three_digits(source) + ".txt";
      write_pose_matrix((root / path).string(), transform);
      index.add(path, "ground_truth_transform",
                "maps points of scan " + std::to_string(source) + " (source) into the frame of scan " +
                    std::to_string(target) + " (target): p_target = R p_source + t");
      const double translation = transform.translation().norm();
      const double cosine = std::clamp((transform.linear().trace() - 1.0) / 2.0, -1.0, 1.0);
      const double rotation_deg = std::acos(cosine) * 180.0 / kPi;
      const std::string source_cloud = "scan_" + three_digits(source) + extension;
      const std::string target_cloud = "scan_" + three_digits(target) + extension;
      pairs.push_back({{"source", source_cloud},
                       {"target", target_cloud},
                       {"transform", path},
                       {"translation_m", tidy(translation)},
                       {"rotation_deg", tidy(rotation_deg)}});
      tsv << run.scene.name << "_" << run.sensor.name << "_" << three_digits(source) << "_to_" << three_digits(target)
          << '\t' << source_cloud << '\t' << target_cloud << '\t' << path << "\texact\t" << run.sensor.name
          << "\tsynthetic\t" << decimal_text(translation, 2) << '\t' << decimal_text(rotation_deg, 1) << '\n';
    }
  }
  write_text((root / "pairs.tsv").string(), tsv.str());
  index.add("pairs.tsv", "pair_list", "every pair in the shared data folder's pairs.tsv format (paths relative to this folder)");
  return pairs;
}

// Returned points per primitive (rows) and scan (columns) as point_counts.csv.
void write_point_counts(const std::filesystem::path& root, const SyntheticRun& run, FileIndex& index) {
  std::ostringstream counts;
  counts << "primitive_id,name,label,model_type";
  for (std::size_t i = 0; i < run.scans.size(); ++i) counts << ",scan_" << three_digits(i);
  counts << '\n';
  for (const auto& primitive : run.scene.primitives) {
    counts << primitive.id << ',' << primitive.name << ',' << semantic_label_name(primitive.label) << ','
           << quadric_type_name(primitive.model_type);
    for (const auto& scan : run.scans) counts << ',' << scan.points_per_primitive[primitive.id];
    counts << '\n';
  }
  write_text((root / "point_counts.csv").string(), counts.str());
  index.add("point_counts.csv", "point_counts", "returned points per primitive (rows) and scan (columns)");
}

// scene.json's description of the run: scene, seed, sensor, frames, primitive and label tables.
ordered_json scene_description(const SyntheticRun& run) {
  ordered_json sensor;
  sensor["name"] = run.sensor.name;
  sensor["description"] = run.sensor.description;
  sensor["pattern"] = pattern_name(run.sensor.pattern);
  sensor["rays_per_scan"] = run.sensor.ray_count();
  sensor["min_range_m"] = tidy(run.sensor.min_range);
  sensor["max_range_m"] = tidy(run.sensor.max_range);
  sensor["range_noise_sigma_m"] = tidy(run.sensor.range_noise_sigma);
  sensor["dropout_probability"] = tidy(run.sensor.dropout_probability);
  ordered_json labels = ordered_json::array();
  for (const auto& row : semantic_label_table())
    labels.push_back({{"id", static_cast<std::uint32_t>(row.label)}, {"name", row.name}, {"description", row.description}});
  ordered_json type_counts = ordered_json::object();
  for (const auto& [type, count] : count_model_types(run.scene)) type_counts[type] = count;

  ordered_json scene;
  scene["format"] = "quadrix synthetic scene, version 1";
  scene["scene"] = run.scene.name;
  scene["description"] = run.scene.description;
  scene["seed"] = run.seed;
  scene["sensor"] = sensor;
  scene["frames"] = {{"world", "scene frame: metres, z up; primitives and sensor poses are given in it"},
                     {"sensor", "x forward, y left, z up; every cloud is in its own sensor frame"},
                     {"transforms", "T_<target>_from_<source>.txt maps SOURCE points into the TARGET frame "
                                    "(p_target = R p_source + t), the shared data folder's convention"}};
  scene["primitive_count"] = run.scene.primitives.size();
  scene["model_type_counts"] = type_counts;
  scene["labels"] = labels;
  return scene;
}

}  // namespace

std::vector<std::string> write_synthetic_folder(const std::string& directory, const SyntheticRun& run,
                                                const SyntheticOutputOptions& options) {
  if (options.cloud_format != CloudFormat::Ply && options.cloud_format != CloudFormat::Pcd)
    throw Error("--format: synthetic clouds are written as ply or pcd, not " + cloud_format_name(options.cloud_format));
  std::error_code error;
  std::filesystem::create_directories(directory, error);
  if (error || !std::filesystem::is_directory(directory))
    throw file_error(directory, "cannot create the output folder: " + error.message());
  const std::filesystem::path root(directory);
  const std::string extension = options.cloud_format == CloudFormat::Ply ? ".ply" : ".pcd";

  FileIndex index;
  write_text((root / "primitives.json").string(), primitives_json(run.scene, options.record_samples));
  index.add("primitives.json", "ground_truth_primitives",
            "every bounded true surface: type, scale, pose, extent, label, quadric (10) and 21-number record");
  const ordered_json scans = write_scans(root, run, options, extension, index);
  const ordered_json pairs = write_pairs(root, run, extension, index);
  write_point_counts(root, run, index);

  // scene.json last: it describes everything above.
  ordered_json scene = scene_description(run);
  index.add("scene.json", "index", "this file: what every file is");
  scene["files"] = index.files;
  scene["scans"] = scans;
  scene["pairs"] = pairs;
  write_text((root / "scene.json").string(), scene.dump(1) + "\n");
  return index.written;
}

std::vector<std::string> synthetic_folder_names() {
  return {"scene.json", "primitives.json", "pairs.tsv", "point_counts.csv", "scan_*.ply", "scan_*.pcd",
          "pose_*.txt", "T_*_from_*.txt"};
}

}  // namespace quadrix
