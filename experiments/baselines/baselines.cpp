// Name dispatch and option validation of the baseline registration methods (baselines.h).
#include "experiments/baselines/baselines.h"

#include "experiments/baselines/baselines_backends.h"

#include <stdexcept>
#include <string>
#include <utility>

namespace quadrix {
namespace {

using BaselineRunner = BaselineResult (*)(const PointCloud&, const PointCloud&, const BaselineOptions&);

/// Every baseline by name, in the order baseline_method_names lists them.
const std::vector<std::pair<std::string, BaselineRunner>>& baseline_registry() {
  static const std::vector<std::pair<std::string, BaselineRunner>> registry = {
      {"open3d-ransac", &baselines_detail::run_open3d_ransac},
      {"open3d-fgr", &baselines_detail::run_open3d_fgr},
      {"pcl-prerejective", &baselines_detail::run_pcl_prerejective},
  };
  return registry;
}

/// Throws std::invalid_argument naming `field` unless `valid`.
void require_option(bool valid, const std::string& field, const std::string& expected, double value) {
  if (!valid)
    throw std::invalid_argument("BaselineOptions::" + field + " must be " + expected + ", got " + std::to_string(value));
}

/// Checks every field of `options` that the libraries would otherwise misuse silently.
void validate_options(const BaselineOptions& options) {
  require_option(options.voxel_size > 0.0, "voxel_size", "> 0 m", options.voxel_size);
  require_option(options.normal_radius > 0.0, "normal_radius", "> 0 m", options.normal_radius);
  require_option(options.normal_max_neighbours >= 3, "normal_max_neighbours", ">= 3", options.normal_max_neighbours);
  require_option(options.feature_radius > 0.0, "feature_radius", "> 0 m", options.feature_radius);
  require_option(options.feature_max_neighbours >= 3, "feature_max_neighbours", ">= 3", options.feature_max_neighbours);
  require_option(options.max_correspondence_distance > 0.0, "max_correspondence_distance", "> 0 m",
                 options.max_correspondence_distance);
  require_option(options.edge_length_similarity >= 0.0 && options.edge_length_similarity < 1.0,
                 "edge_length_similarity", "in [0, 1)", options.edge_length_similarity);
  require_option(options.ransac_iterations >= 1, "ransac_iterations", ">= 1", options.ransac_iterations);
  require_option(options.ransac_confidence > 0.0 && options.ransac_confidence <= 1.0, "ransac_confidence",
                 "in (0, 1]", options.ransac_confidence);
  require_option(options.fgr_iterations >= 1, "fgr_iterations", ">= 1", options.fgr_iterations);
  require_option(options.fgr_tuple_scale > 0.0 && options.fgr_tuple_scale < 1.0, "fgr_tuple_scale", "in (0, 1)",
                 options.fgr_tuple_scale);
  require_option(options.fgr_maximum_tuple_count >= 3, "fgr_maximum_tuple_count", ">= 3",
                 options.fgr_maximum_tuple_count);
  require_option(options.prerejective_iterations >= 1, "prerejective_iterations", ">= 1",
                 options.prerejective_iterations);
  require_option(options.prerejective_samples >= 3, "prerejective_samples", ">= 3", options.prerejective_samples);
  require_option(options.prerejective_feature_neighbours >= 1, "prerejective_feature_neighbours", ">= 1",
                 options.prerejective_feature_neighbours);
  require_option(options.prerejective_inlier_fraction > 0.0 && options.prerejective_inlier_fraction <= 1.0,
                 "prerejective_inlier_fraction", "in (0, 1]", options.prerejective_inlier_fraction);
  require_option(options.threads >= 1, "threads", ">= 1", options.threads);
}

}  // namespace

BaselineResult run_baseline(const std::string& method, const PointCloud& source, const PointCloud& target,
                            const BaselineOptions& options) {
  const auto& registry = baseline_registry();
  for (const auto& entry : registry) {
    if (entry.first != method) continue;
    validate_options(options);
    if (source.empty() || target.empty()) {
      BaselineResult result;
      result.message = std::string(source.empty() ? "source" : "target") + " cloud is empty; " + method +
                       " needs at least " + std::to_string(baselines_detail::minimum_points) + " points per cloud";
      result.timings_ms["total"] = 0.0;
      return result;
    }
    const double cpu_start = baselines_detail::thread_cpu_ms();
    BaselineResult result = entry.second(source, target, options);
    result.cpu_ms = baselines_detail::thread_cpu_ms() - cpu_start;
    return result;
  }
  std::string known;
  for (const auto& entry : registry) known += (known.empty() ? "" : ", ") + entry.first;
  throw std::invalid_argument("unknown baseline method '" + method + "' (known: " + known + ")");
}

}  // namespace quadrix
