// Registration presets, YAML configuration and the `auto` preset (see registration_config.h).
#include "experiments/registration_config.h"

#include "geometry/error.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
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
           e.up.normalize();
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
                 {"minimum_plane_points", set(file, e.planes.minimum_plane_points)}});
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
                 {"augmentation_voxel", set(file, o.modelling.augmentation_voxel)}});
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
                 {"rotation_disagreement_degrees", set(file, o.ambiguity.rotation_disagreement_degrees)}});
         }}});
  if (refiner_registry().count(o.estimation.refiner) == 0)
    throw file_error(path, "key 'estimation.refiner': unknown refiner '" + o.estimation.refiner + "'");
}

RegistrationOptions load_registration_preset(const std::string& name) {
  RegistrationOptions options = registration_preset(name);
  const std::filesystem::path file = std::filesystem::path(registration_presets_directory()) / (name + ".yaml");
  if (std::filesystem::exists(file)) apply_registration_config(file.string(), options);
  return options;
}

SensorGuess guess_sensor_preset(const PointCloud& cloud) {
  SensorGuess guess;
  guess.point_count = cloud.size();
  if (cloud.empty()) {
    guess.preset = "vlp64";
    guess.reason = "empty cloud: default preset vlp64";
    return guess;
  }
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
  guess.reason = reason.str();
  return guess;
}

}  // namespace quadrix
