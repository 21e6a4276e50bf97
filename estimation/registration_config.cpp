// Registration presets, YAML configuration and the `auto` preset (see registration_config.h).
#include "estimation/registration_config.h"

#include "geometry/error.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <type_traits>
#include <tuple>
#include <unordered_map>
#include <sstream>

namespace quadrix {
namespace {

// Reads one scalar of type T at `key`, naming the file and key on a type error.
template <typename T>
T scalar(const YAML::Node& node, const std::string& file, const std::string& key) {
  if (!node.IsScalar()) throw file_error(file, "key '" + key + "' must be a scalar");
  try {
    return node.as<T>();
  } catch (const YAML::Exception&) {
    throw file_error(file, "key '" + key + "' has an invalid value '" + node.Scalar() + "'");
  }
}

using Setter = std::function<void(const YAML::Node&, const std::string& key)>;

// Walks a mapping; every key must be known (unknown keys are an Error naming key and file).
void walk(const YAML::Node& node, const std::string& file, const std::string& prefix,
          const std::map<std::string, Setter>& setters) {
  if (!node.IsMap()) throw file_error(file, "'" + prefix + "' must be a mapping");
  for (const auto& entry : node) {
    const std::string name = entry.first.as<std::string>();
    const std::string key = prefix.empty() ? name : prefix + "." + name;
    const auto found = setters.find(name);
    if (found == setters.end()) {
      std::string known;
      for (const auto& setter : setters) known += (known.empty() ? "" : ", ") + setter.first;
      throw file_error(file, "unknown key '" + key + "' (known here: " + known + ")");
    }
    found->second(entry.second, key);
  }
}

template <typename T>
Setter set(const std::string& file, T& target) {
  return [&target, file](const YAML::Node& node, const std::string& key) { target = scalar<T>(node, file, key); };
}

void apply_extraction(const YAML::Node& node, const std::string& file, ExtractionOptions& e) {
  walk(node, file, "extraction",
       {{"minimum_range", set(file, e.minimum_range)},
        {"maximum_range", set(file, e.maximum_range)},
        {"static_scan", set(file, e.static_scan)},
        {"up",
         [&e, file](const YAML::Node& value, const std::string& key) {
           if (!value.IsSequence() || value.size() != 3) throw file_error(file, "key '" + key + "' must be a list of 3 numbers");
           for (int i = 0; i < 3; ++i) e.up[i] = scalar<double>(value[i], file, key);
           if (!(e.up.norm() > 0.0)) throw file_error(file, "key '" + key + "' must not be the zero vector");
           if (std::abs(e.up.norm() - 1.0) > 1e-12) e.up.normalize();  // a unit vector is kept bit for bit
         }},
        {"ground",
         [&e, file](const YAML::Node& value, const std::string& key) {
           walk(value, file, key,
                {{"inlier_distance", set(file, e.ground.inlier_distance)},
                 {"max_slope_deg", set(file, e.ground.max_slope_deg)},
                 {"max_step_height", set(file, e.ground.max_step_height)}});
         }},
        {"planes",
         [&e, file](const YAML::Node& value, const std::string& key) {
           walk(value, file, key,
                {{"voxel_size", set(file, e.planes.voxel_size)},
                 {"merge_distance", set(file, e.planes.merge_distance)},
                 {"normal_cosine", set(file, e.planes.normal_cosine)},
                 {"eigenvalue_ratio", set(file, e.planes.eigenvalue_ratio)},
                 {"minimum_plane_points", set(file, e.planes.minimum_plane_points)},
                 {"cluster_plane_width", set(file, e.planes.cluster_plane_width)},
                 {"cluster_plane_area", set(file, e.planes.cluster_plane_area)}});
         }},
        {"trunks",
         [&e, file](const YAML::Node& value, const std::string& key) {
           walk(value, file, key,
                {{"enabled", set(file, e.trunks.enabled)},
                 {"maximum_radius", set(file, e.trunks.maximum_radius)},
                 {"minimum_height", set(file, e.trunks.minimum_height)},
                 {"crownless_minimum_radius", set(file, e.trunks.crownless_minimum_radius)},
                 {"crownless_slice_points", set(file, e.trunks.crownless_slice_points)},
                 {"crownless_top_tolerance_deg", set(file, e.trunks.crownless_top_tolerance_deg)}});
         }},
        {"clusters",
         [&e, file](const YAML::Node& value, const std::string& key) {
           walk(value, file, key,
                {{"radius", set(file, e.clusters.radius)},
                 {"minimum_points", set(file, e.clusters.minimum_points)},
                 {"maximum_points", set(file, e.clusters.maximum_points)},
                 {"maximum_extent", set(file, e.clusters.maximum_extent)}});
         }},
        {"lines",
         [&e, file](const YAML::Node& value, const std::string& key) {
           walk(value, file, key,
                {{"inlier_distance", set(file, e.lines.inlier_distance)},
                 {"minimum_points", set(file, e.lines.minimum_points)},
                 {"minimum_length", set(file, e.lines.minimum_length)}});
         }},
        {"shapes", [&e, file](const YAML::Node& value, const std::string& key) {
           walk(value, file, key,
                {{"simplification_voxel", set(file, e.shapes.simplification_voxel)},
                 {"epsilon", set(file, e.shapes.epsilon)},
                 {"cluster_epsilon", set(file, e.shapes.cluster_epsilon)},
                 {"minimum_points", set(file, e.shapes.minimum_points)},
                 {"normal_threshold", set(file, e.shapes.normal_threshold)}});
         }}});
}

}  // namespace

std::vector<std::string> registration_preset_names() { return extraction_preset_names(); }

RegistrationOptions registration_preset(const std::string& name) {
  RegistrationOptions options;
  options.source_extraction = extraction_preset(name);
  options.target_extraction = options.source_extraction;
  // Static scans model CGAL-detected shapes of a known type: the constrained fitter keeps that type
  // and fits all its points (the monument's drum: radius 21.65 m), where the statistical fitter's
  // moments of a partial arc are far off (16.1 m).
  if (name == "monument") options.modelling.fitter = "constrained";
  return options;
}

std::string registration_presets_directory() {
  if (const char* from_environment = std::getenv("QUADRIX_PRESETS_DIR")) return from_environment;
  return (std::filesystem::path(__FILE__).parent_path() / "presets").string();
}

void apply_registration_config(const std::string& path, RegistrationOptions& options, const std::string& side) {
  if (side != "both" && side != "source" && side != "target")
    throw Error("apply_registration_config: side must be both, source or target, got '" + side + "'");
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw file_error(path, "cannot open the configuration file");
  } catch (const YAML::Exception& error) {
    throw file_error(path, std::string("invalid YAML: ") + error.what());
  }
  if (root.IsNull()) return;  // an empty file changes nothing
  if (!root.IsMap()) throw file_error(path, "the configuration must be a mapping of sections");
  const bool source_side = side != "target";
  const bool target_side = side != "source";
  // `sensor` first: it restarts the extraction, the other sections then override it.
  if (const YAML::Node sensor = root["sensor"]) {
    const std::string name = scalar<std::string>(sensor, path, "sensor");
    ExtractionOptions base;
    try {
      base = extraction_preset(name);
    } catch (const Error& error) {
      throw file_error(path, std::string("key 'sensor': ") + error.what());
    }
    if (source_side) options.source_extraction = base;
    if (target_side) options.target_extraction = base;
  }
  RegistrationOptions& o = options;
  const std::string file = path;
  walk(root, path, "",
       {{"sensor", [](const YAML::Node&, const std::string&) {}},
        {"extraction",
         [&](const YAML::Node& value, const std::string&) {
           if (source_side) apply_extraction(value, file, o.source_extraction);
           if (target_side) apply_extraction(value, file, o.target_extraction);
         }},
        {"modelling",
         [&](const YAML::Node& value, const std::string& key) {
           walk(value, file, key,
                {{"fitter", set(file, o.modelling.fitter)},
                 {"quadrics_per_class", set(file, o.modelling.quadrics_per_class)},
                 {"augmentation_threshold", set(file, o.modelling.augmentation_threshold)},
                 {"augmented_elements_per_class", set(file, o.modelling.augmented_elements_per_class)},
                 {"augmentation_voxel", set(file, o.modelling.augmentation_voxel)},
                 {"maximum_augmented_points", set(file, o.modelling.maximum_augmented_points)}});
         }},
        {"matching",
         [&](const YAML::Node& value, const std::string& key) {
           walk(value, file, key,
                {{"top_k_similar", set(file, o.correspondences.top_k_similar)},
                 {"match_augmented_points", set(file, o.correspondences.match_augmented_points)},
                 {"clique_time_limit_ms", set(file, o.clique_time_limit_ms)},
                 {"clique_threads", set(file, o.clique_threads)},
                 {"thresholds", [&](const YAML::Node& list, const std::string& list_key) {
                    if (!list.IsSequence() || list.size() == 0)
                      throw file_error(file, "key '" + list_key + "' must be a non-empty list of metres");
                    o.graphs.thresholds.clear();
                    for (const auto& item : list) o.graphs.thresholds.push_back(scalar<double>(item, file, list_key));
                    for (std::size_t i = 0; i < o.graphs.thresholds.size(); ++i)
                      if (!(o.graphs.thresholds[i] >= 0.0) || (i > 0 && o.graphs.thresholds[i] <= o.graphs.thresholds[i - 1]))
                        throw file_error(file, "key '" + list_key + "' must be non-negative and strictly ascending");
                  }}});
         }},
        {"estimation",
         [&](const YAML::Node& value, const std::string& key) {
           walk(value, file, key,
                {{"refiner", set(file, o.estimation.refiner)},
                 {"max_iterations", set(file, o.estimation.refinement.max_iterations)},
                 {"function_tolerance", set(file, o.estimation.refinement.function_tolerance)},
                 {"manhattan_tolerance_degrees", set(file, o.estimation.manhattan_tolerance_degrees)},
                 {"augment_non_central", set(file, o.estimation.augment_non_central)},
                 {"use_ground_constraint", set(file, o.estimation.use_ground_constraint)},
                 {"ground_weight", set(file, o.estimation.ground_weight)},
                 {"minimum_inliers", set(file, o.estimation.minimum_inliers)}});
         }},
        {"selection",
         [&](const YAML::Node& value, const std::string& key) {
           walk(value, file, key,
                {{"dcs_phi", set(file, o.selection.dcs_phi)},
                 {"manhattan_tolerance_degrees", set(file, o.selection.manhattan_tolerance_degrees)}});
         }},
        {"ambiguity", [&](const YAML::Node& value, const std::string& key) {
           walk(value, file, key,
                {{"score_ratio", set(file, o.ambiguity.score_ratio)},
                 {"translation_disagreement", set(file, o.ambiguity.translation_disagreement)},
                 {"rotation_disagreement_degrees", set(file, o.ambiguity.rotation_disagreement_degrees)},
                 {"minimum_clique_for_ok", set(file, o.ambiguity.minimum_clique_for_ok)},
                 {"overlap_margin", set(file, o.ambiguity.overlap_margin)}});
         }},
        {"dense_search", [&](const YAML::Node& value, const std::string& key) {
           walk(value, file, key,
                {{"enabled", set(file, o.dense_search.enabled)},
                 {"voxel_size", set(file, o.dense_search.voxel_size)},
                 {"source_samples", set(file, o.dense_search.source_samples)},
                 {"normal_neighbours", set(file, o.dense_search.normal_neighbours)},
                 {"correspondence_distance", set(file, o.dense_search.correspondence_distance)},
                 {"iterations", set(file, o.dense_search.iterations)},
                 {"step", set(file, o.dense_search.step)},
                 {"range", set(file, o.dense_search.range)},
                 {"across_step", set(file, o.dense_search.across_step)},
                 {"across_range", set(file, o.dense_search.across_range)},
                 {"refine_band", set(file, o.dense_search.refine_band)},
                 {"max_refined", set(file, o.dense_search.max_refined)},
                 {"minimum_overlap", set(file, o.dense_search.minimum_overlap)},
                 {"decisive_margin", set(file, o.dense_search.decisive_margin)}});
         }}});
  if (refiner_registry().count(o.estimation.refiner) == 0)
    throw file_error(path, "key 'estimation.refiner': unknown refiner '" + o.estimation.refiner + "'");
  try {
    validate_dense_search_options(o.dense_search);
  } catch (const Error& error) {
    throw file_error(path, error.what());
  }
}

std::string registration_config_yaml(const RegistrationOptions& options, const std::string& side) {
  if (side != "source" && side != "target")
    throw Error("registration_config_yaml: side must be source or target, got '" + side + "'");
  const ExtractionOptions& e = side == "source" ? options.source_extraction : options.target_extraction;
  YAML::Emitter out;
  // Doubles as their shortest exact decimal (std::to_chars): "0.15", and reading it back gives the same double.
  const auto text = [](const auto& value) {
    if constexpr (std::is_floating_point_v<std::decay_t<decltype(value)>>) {
      std::array<char, 32> buffer{};
      const auto end = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value).ptr;
      return std::string(buffer.data(), end);
    } else {
      return value;
    }
  };
  const auto key_value = [&out, &text](const char* key, const auto& value) { out << YAML::Key << key << YAML::Value << text(value); };
  const auto list = [&out, &text](const char* key, const std::vector<double>& values) {
    out << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (const double value : values) out << text(value);
    out << YAML::EndSeq;
  };
  const auto begin = [&out](const char* key) { out << YAML::Key << key << YAML::Value << YAML::BeginMap; };
  out << YAML::BeginMap;
  begin("extraction");
  key_value("minimum_range", e.minimum_range);
  key_value("maximum_range", e.maximum_range);
  key_value("static_scan", e.static_scan);
  list("up", {e.up.x(), e.up.y(), e.up.z()});
  begin("ground");
  key_value("inlier_distance", e.ground.inlier_distance);
  key_value("max_slope_deg", e.ground.max_slope_deg);
  key_value("max_step_height", e.ground.max_step_height);
  out << YAML::EndMap;
  begin("planes");
  key_value("voxel_size", e.planes.voxel_size);
  key_value("merge_distance", e.planes.merge_distance);
  key_value("normal_cosine", e.planes.normal_cosine);
  key_value("eigenvalue_ratio", e.planes.eigenvalue_ratio);
  key_value("minimum_plane_points", e.planes.minimum_plane_points);
  key_value("cluster_plane_width", e.planes.cluster_plane_width);
  key_value("cluster_plane_area", e.planes.cluster_plane_area);
  out << YAML::EndMap;
  begin("trunks");
  key_value("enabled", e.trunks.enabled);
  key_value("maximum_radius", e.trunks.maximum_radius);
  key_value("minimum_height", e.trunks.minimum_height);
  key_value("crownless_minimum_radius", e.trunks.crownless_minimum_radius);
  key_value("crownless_slice_points", e.trunks.crownless_slice_points);
  key_value("crownless_top_tolerance_deg", e.trunks.crownless_top_tolerance_deg);
  out << YAML::EndMap;
  begin("clusters");
  key_value("radius", e.clusters.radius);
  key_value("minimum_points", e.clusters.minimum_points);
  key_value("maximum_points", e.clusters.maximum_points);
  key_value("maximum_extent", e.clusters.maximum_extent);
  out << YAML::EndMap;
  begin("lines");
  key_value("inlier_distance", e.lines.inlier_distance);
  key_value("minimum_points", e.lines.minimum_points);
  key_value("minimum_length", e.lines.minimum_length);
  out << YAML::EndMap;
  begin("shapes");
  key_value("simplification_voxel", e.shapes.simplification_voxel);
  key_value("epsilon", e.shapes.epsilon);
  key_value("cluster_epsilon", e.shapes.cluster_epsilon);
  key_value("minimum_points", e.shapes.minimum_points);
  key_value("normal_threshold", e.shapes.normal_threshold);
  out << YAML::EndMap << YAML::EndMap;
  begin("modelling");
  key_value("fitter", options.modelling.fitter);
  key_value("quadrics_per_class", options.modelling.quadrics_per_class);
  key_value("augmentation_threshold", options.modelling.augmentation_threshold);
  key_value("augmented_elements_per_class", options.modelling.augmented_elements_per_class);
  key_value("augmentation_voxel", options.modelling.augmentation_voxel);
  key_value("maximum_augmented_points", options.modelling.maximum_augmented_points);
  out << YAML::EndMap;
  begin("matching");
  key_value("top_k_similar", options.correspondences.top_k_similar);
  key_value("match_augmented_points", options.correspondences.match_augmented_points);
  list("thresholds", options.graphs.thresholds);
  key_value("clique_time_limit_ms", options.clique_time_limit_ms);
  key_value("clique_threads", options.clique_threads);
  out << YAML::EndMap;
  begin("estimation");
  key_value("refiner", options.estimation.refiner);
  key_value("max_iterations", options.estimation.refinement.max_iterations);
  key_value("function_tolerance", options.estimation.refinement.function_tolerance);
  key_value("manhattan_tolerance_degrees", options.estimation.manhattan_tolerance_degrees);
  key_value("augment_non_central", options.estimation.augment_non_central);
  key_value("use_ground_constraint", options.estimation.use_ground_constraint);
  key_value("ground_weight", options.estimation.ground_weight);
  key_value("minimum_inliers", options.estimation.minimum_inliers);
  out << YAML::EndMap;
  begin("selection");
  key_value("dcs_phi", options.selection.dcs_phi);
  key_value("manhattan_tolerance_degrees", options.selection.manhattan_tolerance_degrees);
  out << YAML::EndMap;
  begin("ambiguity");
  key_value("score_ratio", options.ambiguity.score_ratio);
  key_value("translation_disagreement", options.ambiguity.translation_disagreement);
  key_value("rotation_disagreement_degrees", options.ambiguity.rotation_disagreement_degrees);
  key_value("minimum_clique_for_ok", options.ambiguity.minimum_clique_for_ok);
  key_value("overlap_margin", options.ambiguity.overlap_margin);
  out << YAML::EndMap;
  begin("dense_search");
  key_value("enabled", options.dense_search.enabled);
  key_value("voxel_size", options.dense_search.voxel_size);
  key_value("source_samples", options.dense_search.source_samples);
  key_value("normal_neighbours", options.dense_search.normal_neighbours);
  key_value("correspondence_distance", options.dense_search.correspondence_distance);
  key_value("iterations", options.dense_search.iterations);
  key_value("step", options.dense_search.step);
  key_value("range", options.dense_search.range);
  key_value("across_step", options.dense_search.across_step);
  key_value("across_range", options.dense_search.across_range);
  key_value("refine_band", options.dense_search.refine_band);
  key_value("max_refined", options.dense_search.max_refined);
  key_value("minimum_overlap", options.dense_search.minimum_overlap);
  key_value("decisive_margin", options.dense_search.decisive_margin);
  out << YAML::EndMap << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

RegistrationOptions load_registration_preset(const std::string& name) {
  RegistrationOptions options = registration_preset(name);
  const std::filesystem::path file = std::filesystem::path(registration_presets_directory()) / (name + ".yaml");
  if (std::filesystem::exists(file)) apply_registration_config(file.string(), options);
  return options;
}

namespace {

// Point statistics of one voxel (count, sum, sum of outer products) for its PCA normal.
struct VoxelMoments {
  double count = 0.0;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
};

// A planar voxel: unit normal (sign arbitrary), centre and point count.
struct PlanarVoxel {
  Eigen::Vector3d normal;
  Eigen::Vector3d center;
  double weight;
};

// PCA normals of the planar voxels of (at most ~100 k evenly strided points of) the cloud.
std::vector<PlanarVoxel> planar_voxels(const PointCloud& cloud, double voxel_size) {
  const std::size_t stride = std::max<std::size_t>(1, cloud.size() / 100000);
  std::unordered_map<std::int64_t, VoxelMoments> voxels;
  for (std::size_t i = 0; i < cloud.size(); i += stride) {
    const Eigen::Vector3d p = cloud.point(i);
    if (!p.allFinite()) continue;
    const Eigen::Vector3d cell = (p / voxel_size).array().floor();
    if ((cell.array().abs() > 1e5).any()) continue;
    const std::int64_t key = (static_cast<std::int64_t>(cell.x()) + (1 << 20)) * (std::int64_t{1} << 42) +
                             (static_cast<std::int64_t>(cell.y()) + (1 << 20)) * (std::int64_t{1} << 21) +
                             (static_cast<std::int64_t>(cell.z()) + (1 << 20));
    VoxelMoments& voxel = voxels[key];
    voxel.count += 1.0;
    voxel.sum += p;
    voxel.outer += p * p.transpose();
  }
  std::vector<PlanarVoxel> planar;
  for (const auto& [key, voxel] : voxels) {
    (void)key;
    if (voxel.count < 8.0) continue;
    const Eigen::Vector3d mean = voxel.sum / voxel.count;
    const Eigen::Matrix3d covariance = voxel.outer / voxel.count - mean * mean.transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
    const Eigen::Vector3d values = solver.eigenvalues();  // ascending
    if (!(values(1) > 0.0) || values(0) > 0.04 * values(1) || values(1) < 0.01 * values(2)) continue;  // a patch, not a line
    planar.push_back({solver.eigenvectors().col(0), mean, voxel.count});
  }
  // Hash-map order is not deterministic across library versions: sort for reproducible candidates.
  std::sort(planar.begin(), planar.end(), [](const PlanarVoxel& a, const PlanarVoxel& b) {
    return std::tie(a.center.x(), a.center.y(), a.center.z()) < std::tie(b.center.x(), b.center.y(), b.center.z());
  });
  return planar;
}

// Weight of the planar voxels whose normal is within the cone |n . direction| >= cosine.
double normal_support(const std::vector<PlanarVoxel>& voxels, const Eigen::Vector3d& direction, double cosine) {
  double support = 0.0;
  for (const PlanarVoxel& voxel : voxels)
    if (std::abs(voxel.normal.dot(direction)) >= cosine) support += voxel.weight;
  return support;
}

}  // namespace

UpDirectionEstimate estimate_up_direction(const PointCloud& cloud) {
  constexpr double kDegrees = 180.0 / M_PI;
  UpDirectionEstimate estimate;
  std::vector<double> ranges;
  const std::size_t stride = std::max<std::size_t>(1, cloud.size() / 20000);
  for (std::size_t i = 0; i < cloud.size(); i += stride)
    if (cloud.point(i).allFinite()) ranges.push_back(cloud.point(i).norm());
  if (ranges.empty()) {
    estimate.reason = "no finite point: +z assumed";
    return estimate;
  }
  std::nth_element(ranges.begin(), ranges.begin() + static_cast<std::ptrdiff_t>(ranges.size() / 2), ranges.end());
  const double voxel_size = std::clamp(ranges[ranges.size() / 2] / 15.0, 0.1, 1.0);
  const std::vector<PlanarVoxel> voxels = planar_voxels(cloud, voxel_size);
  double total = 0.0;
  for (const PlanarVoxel& voxel : voxels) total += voxel.weight;
  if (voxels.size() < 20) {
    estimate.reason = std::to_string(voxels.size()) + " planar voxels (fewer than 20): +z assumed";
    return estimate;
  }
  const double cone = std::cos(10.0 / kDegrees);
  const double upright_limit = std::cos(45.0 / kDegrees);
  // Candidate directions: the normals of (at most 500 evenly chosen) planar voxels.
  const std::size_t candidate_stride = std::max<std::size_t>(1, voxels.size() / 500);
  Eigen::Vector3d best_upright = Eigen::Vector3d::Zero(), best_overall = Eigen::Vector3d::Zero();
  double upright_support = 0.0, overall_support = 0.0;
  for (std::size_t n = 0; n < voxels.size(); n += candidate_stride) {
    const Eigen::Vector3d& candidate = voxels[n].normal;
    const double support = normal_support(voxels, candidate, cone);
    if (support > overall_support) {
      overall_support = support;
      best_overall = candidate;
    }
    if (std::abs(candidate.z()) >= upright_limit && support > upright_support) {
      upright_support = support;
      best_upright = candidate;
    }
  }
  const bool upright = upright_support > 0.0;
  Eigen::Vector3d up = upright ? best_upright : best_overall;
  // Refine: the weighted mean of the sign-aligned normals within 10 deg, twice.
  for (int round = 0; round < 2; ++round) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const PlanarVoxel& voxel : voxels) {
      const double alignment = voxel.normal.dot(up);
      if (std::abs(alignment) >= cone) sum += (alignment < 0.0 ? -1.0 : 1.0) * voxel.weight * voxel.normal;
    }
    if (sum.norm() > 0.0) up = sum.normalized();
  }
  if (upright) {
    if (up.z() < 0.0) up = -up;
  } else {
    // Orient so that most of the mode's planar points lie below the sensor at the origin.
    double below = 0.0, above = 0.0;
    for (const PlanarVoxel& voxel : voxels)
      if (std::abs(voxel.normal.dot(up)) >= cone) (voxel.center.dot(up) < 0.0 ? below : above) += voxel.weight;
    if (above > below) up = -up;
  }
  estimate.found = true;
  estimate.up = up;
  estimate.support = normal_support(voxels, up, cone) / total;
  estimate.tilt_degrees = std::acos(std::clamp(up.z(), -1.0, 1.0)) * kDegrees;
  std::ostringstream reason;
  reason.precision(3);
  reason << "up (" << up.x() << ", " << up.y() << ", " << up.z() << "), tilt " << estimate.tilt_degrees << " deg, "
         << 100.0 * estimate.support << "% of planar voxels (" << voxel_size << " m) within 10 deg"
         << (upright ? "" : "; no horizontal mode within 45 deg of +z: the best-supported plane normal, sensor above it");
  estimate.reason = reason.str();
  return estimate;
}

SensorGuess guess_sensor_preset(const PointCloud& cloud) {
  SensorGuess guess;
  guess.point_count = cloud.size();
  if (cloud.empty()) {
    guess.preset = "vlp64";
    guess.reason = "empty cloud: default preset vlp64";
    return guess;
  }
  // A platform's own body (more than 10% of the points within 1.5 m, e.g. 3DTK's robot) would
  // dominate every measurement: measure the scene beyond 2 m, and crop there.
  std::size_t near_field_points = 0;
  for (Eigen::Index i = 0; i < cloud.positions.cols(); ++i) near_field_points += cloud.positions.col(i).norm() < 1.5F ? 1 : 0;
  const double near_field_fraction = static_cast<double>(near_field_points) / static_cast<double>(cloud.size());
  if (near_field_fraction > 0.1) {
    PointCloud scene;
    std::vector<Eigen::Index> far;
    for (Eigen::Index i = 0; i < cloud.positions.cols(); ++i)
      if (cloud.positions.col(i).norm() >= 2.0F) far.push_back(i);
    scene.positions.resize(3, static_cast<Eigen::Index>(far.size()));
    for (std::size_t n = 0; n < far.size(); ++n) scene.positions.col(static_cast<Eigen::Index>(n)) = cloud.positions.col(far[n]);
    guess = guess_sensor_preset(scene);
    guess.point_count = cloud.size();
    guess.near_field_fraction = near_field_fraction;
    guess.minimum_range = std::max(2.0, guess.minimum_range);
    std::ostringstream reason;
    reason.precision(3);
    reason << 100.0 * near_field_fraction << "% of the " << cloud.size()
           << " points lie within 1.5 m (the platform itself): measured beyond 2 m and cropped there; " << guess.reason;
    guess.reason = reason.str();
    return guess;
  }
  // Rings and the elevation span are properties of the sensor head, so they are measured in the
  // cloud's own frame (a tilted spinning LiDAR keeps its rings there); the up axis only tells the
  // extraction where the ground is.
  guess.up = estimate_up_direction(cloud);
  constexpr double kDegrees = 180.0 / M_PI;
  std::vector<char> azimuth_bins(360, 0);
  std::vector<double> ranges;
  std::vector<double> elevations;  // of points beyond 10 m (the rings are sharp there)
  ranges.reserve(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d p = cloud.point(i);
    const double horizontal = std::hypot(p.x(), p.y());
    const double range = p.norm();
    ranges.push_back(range);
    if (horizontal > 0.5) {
      const int bin = static_cast<int>(std::floor((std::atan2(p.y(), p.x()) * kDegrees + 180.0))) % 360;
      azimuth_bins[static_cast<std::size_t>(std::max(0, bin))] = 1;
    }
    if (range > 10.0) elevations.push_back(std::atan2(p.z(), horizontal) * kDegrees);
  }
  guess.near_field_fraction = near_field_fraction;
  guess.azimuth_coverage = static_cast<double>(std::count(azimuth_bins.begin(), azimuth_bins.end(), 1)) / 360.0;
  std::nth_element(ranges.begin(), ranges.begin() + static_cast<std::ptrdiff_t>(ranges.size() / 2), ranges.end());
  guess.median_range = ranges[ranges.size() / 2];
  if (elevations.size() >= 100) {
    std::sort(elevations.begin(), elevations.end());
    const double low = elevations[elevations.size() / 100];
    const double high = elevations[elevations.size() * 99 / 100];
    guess.elevation_span_degrees = high - low;
    // Rings: maximal runs of occupied elevation bins (0.05 deg, wider for sparse clouds) separated by empty bins. A bin is occupied
    // when it holds more than half the mean count per bin: ring bins hold many times the mean, while a
    // non-repetitive scanner fills the span evenly (even when sparse, where fixed thresholds see noise as rings).
    // Bins hold at least ~20 points on average, so sparse clouds do not turn counting noise into rings.
    const double bin_width = std::max(0.05, 20.0 * (high - low) / static_cast<double>(elevations.size()));
    const int bin_count = std::max(1, static_cast<int>(std::ceil((high - low) / bin_width)) + 1);
    std::vector<std::size_t> histogram(static_cast<std::size_t>(bin_count), 0);
    for (const double elevation : elevations)
      if (elevation >= low && elevation <= high)
        ++histogram[static_cast<std::size_t>(std::min(bin_count - 1, static_cast<int>((elevation - low) / bin_width)))];
    const std::size_t occupied_threshold =
        std::max<std::size_t>(2, elevations.size() / (2 * static_cast<std::size_t>(bin_count)));
    bool inside = false;
    int runs = 0;
    int occupied = 0;
    for (const std::size_t count : histogram) {
      const bool is_occupied = count > occupied_threshold;
      occupied += is_occupied ? 1 : 0;
      if (is_occupied && !inside) ++runs;
      inside = is_occupied;
    }
    // A filled span (more than 70% of bins occupied) is not a ring structure.
    guess.ring_count = occupied > 0.7 * bin_count ? 0 : runs;
  }
  std::ostringstream reason;
  reason.precision(3);
  reason << guess.point_count << " points, azimuth coverage " << 100.0 * guess.azimuth_coverage << "%, "
         << guess.ring_count << " elevation rings over " << guess.elevation_span_degrees << " deg, median range "
         << guess.median_range << " m -> ";
  if (guess.azimuth_coverage < 0.5) {
    guess.preset = "avia";
    reason << "narrow horizontal field of view (< 50%): avia";
  } else if (guess.point_count > 1500000) {
    guess.preset = "monument";
    reason << "more than 1.5 M points: static scan, monument";
  } else if (guess.elevation_span_degrees < 35.0) {
    // A spinning multi-beam scanner looks at a narrow elevation band (HDL-64E 27 deg, VLP-16 30 deg);
    // its density (or ring count, when the rings are separable) tells a 64-beam from a 16-beam head.
    const bool dense = guess.point_count >= 60000 || guess.ring_count >= 48;
    guess.preset = dense ? "vlp64" : "vlp16";
    reason << "narrow elevation span (< 35 deg) of a spinning scanner, "
           << (dense ? ">= 60 k points or >= 48 rings: vlp64" : "< 60 k points and < 48 rings: vlp16");
  } else {
    guess.preset = "mid360";
    reason << "360 deg coverage and a tall (>= 35 deg) elevation span of a non-repetitive scanner: mid360";
  }
  guess.minimum_range = extraction_preset(guess.preset).minimum_range;
  guess.reason = reason.str();
  return guess;
}

RegistrationOptions resolve_registration_options(const std::string& source_preset, const PointCloud& source,
                                                 const std::string& target_preset, const PointCloud& target,
                                                 std::string* notes) {
  // One side: a named preset's options as they are, or auto's guess with the measured up axis.
  const auto resolve = [&](const std::string& requested, const PointCloud& cloud, const char* side) {
    if (requested != "auto") return load_registration_preset(requested);
    const SensorGuess guess = guess_sensor_preset(cloud);
    RegistrationOptions options = load_registration_preset(guess.preset);
    if (guess.up.found) options.source_extraction.up = options.target_extraction.up = guess.up.up;
    if (guess.near_field_fraction > 0.1)  // self-hits of the platform: crop them (its preset's value when larger)
      options.source_extraction.minimum_range = options.target_extraction.minimum_range =
          std::max(guess.minimum_range, options.source_extraction.minimum_range);
    if (notes != nullptr)
      *notes += std::string(notes->empty() ? "" : "; ") + side + " auto: " + guess.reason + "; " + guess.up.reason;
    return options;
  };
  RegistrationOptions options = resolve(source_preset, source, "source");  // the source side's preset sets the shared stages
  options.target_extraction = resolve(target_preset, target, "target").target_extraction;
  return options;
}

}  // namespace quadrix
