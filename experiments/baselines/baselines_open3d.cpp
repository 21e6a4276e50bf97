// Open3D 0.16 baselines: FPFH + RANSAC (RegistrationRANSACBasedOnFeatureMatching) and FPFH + FGR
// (FastGlobalRegistrationBasedOnFeatureMatching, Zhou et al. ECCV 2016), with the settings of
// Open3D's global-registration example scaled to outdoor LiDAR (baselines.h). Open3D parallelises
// normals, FPFH and RANSAC with OpenMP: the thread count is set per call from BaselineOptions::threads.
#include "experiments/baselines/baselines_backends.h"

#include <open3d/geometry/KDTreeSearchParam.h>
#include <open3d/geometry/PointCloud.h>
#include <open3d/pipelines/registration/CorrespondenceChecker.h>
#include <open3d/pipelines/registration/FastGlobalRegistration.h>
#include <open3d/pipelines/registration/Feature.h>
#include <open3d/pipelines/registration/Registration.h>
#include <open3d/pipelines/registration/TransformationEstimation.h>
#include <open3d/utility/Logging.h>
#include <open3d/utility/Random.h>

#include <omp.h>

#include <cstdlib>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

namespace quadrix::baselines_detail {
namespace {

namespace o3d_geometry = open3d::geometry;
namespace o3d_registration = open3d::pipelines::registration;

/// One cloud after the shared front end: down-sampled points with normals, and their FPFH.
struct PreparedCloud {
  std::shared_ptr<o3d_geometry::PointCloud> points;     ///< voxel centroids with normals
  std::shared_ptr<o3d_registration::Feature> features;  ///< 33 x N FPFH
};

/// Makes Open3D honour omp_set_num_threads. Open3D 0.16 sizes its parallel loops with
/// utility::EstimateMaxThreads(), which returns omp_get_max_threads() only when OMP_NUM_THREADS or
/// OMP_DYNAMIC is set in the environment and otherwise all physical cores (so `threads = 1` would
/// silently run on every core). When neither is set, this sets OMP_DYNAMIC=false, which is libgomp's
/// default, so nothing changes for OpenMP itself; once per process, before the first Open3D call.
void let_open3d_follow_openmp_thread_count() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (std::getenv("OMP_NUM_THREADS") == nullptr && std::getenv("OMP_DYNAMIC") == nullptr)
      setenv("OMP_DYNAMIC", "false", /*overwrite=*/0);
  });
}

/// Converts a Quadrix cloud to an Open3D cloud (positions only).
o3d_geometry::PointCloud to_open3d(const PointCloud& cloud) {
  o3d_geometry::PointCloud converted;
  converted.points_.reserve(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) converted.points_.push_back(cloud.point(i));
  return converted;
}

/// The front end shared by both Open3D baselines, timed per stage into `result`.
std::pair<PreparedCloud, PreparedCloud> prepare_pair(const PointCloud& source, const PointCloud& target,
                                                     const BaselineOptions& options, BaselineResult& result) {
  Stopwatch stopwatch;
  PreparedCloud prepared_source;
  PreparedCloud prepared_target;
  prepared_source.points = to_open3d(source).VoxelDownSample(options.voxel_size);
  prepared_target.points = to_open3d(target).VoxelDownSample(options.voxel_size);
  result.timings_ms["downsample"] = stopwatch.lap_ms();

  const o3d_geometry::KDTreeSearchParamHybrid normal_search(options.normal_radius, options.normal_max_neighbours);
  for (PreparedCloud* prepared : {&prepared_source, &prepared_target}) {
    prepared->points->EstimateNormals(normal_search, /*fast_normal_computation=*/true);
    prepared->points->OrientNormalsTowardsCameraLocation(Eigen::Vector3d::Zero());  // the sensor, as PCL does
  }
  result.timings_ms["normals"] = stopwatch.lap_ms();

  const o3d_geometry::KDTreeSearchParamHybrid feature_search(options.feature_radius, options.feature_max_neighbours);
  prepared_source.features = o3d_registration::ComputeFPFHFeature(*prepared_source.points, feature_search);
  prepared_target.features = o3d_registration::ComputeFPFHFeature(*prepared_target.points, feature_search);
  result.timings_ms["features"] = stopwatch.lap_ms();

  result.counts["source_points"] = static_cast<double>(prepared_source.points->points_.size());
  result.counts["target_points"] = static_cast<double>(prepared_target.points->points_.size());
  return {prepared_source, prepared_target};
}

/// Runs the shared front end, then `estimate` (the library's global estimator) on the prepared clouds;
/// fills the transform, inlier count, solved flag and timings. `name` prefixes the messages.
BaselineResult run_with_open3d(
    const std::string& name, const PointCloud& source, const PointCloud& target, const BaselineOptions& options,
    const std::function<o3d_registration::RegistrationResult(const PreparedCloud&, const PreparedCloud&)>& estimate) {
  open3d::utility::SetVerbosityLevel(open3d::utility::VerbosityLevel::Error);
  let_open3d_follow_openmp_thread_count();
  omp_set_num_threads(options.threads);
  open3d::utility::random::Seed(static_cast<int>(options.seed));

  Stopwatch total;
  BaselineResult result;
  try {
    auto [prepared_source, prepared_target] = prepare_pair(source, target, options, result);
    const std::size_t source_points = prepared_source.points->points_.size();
    const std::size_t target_points = prepared_target.points->points_.size();
    if (source_points < minimum_points || target_points < minimum_points) {
      result.message = name + ": too few points after " + std::to_string(options.voxel_size) +
                       " m voxel down-sampling (source " + std::to_string(source_points) + ", target " +
                       std::to_string(target_points) + ", need " + std::to_string(minimum_points) + ")";
      result.timings_ms["registration"] = 0.0;
      result.timings_ms["total"] = total.lap_ms();
      return result;
    }

    Stopwatch registration;
    const o3d_registration::RegistrationResult estimated = estimate(prepared_source, prepared_target);
    result.timings_ms["registration"] = registration.lap_ms();
    result.transform.matrix() = estimated.transformation_;  // Open3D: p_target = T p_source, our convention

    const o3d_registration::RegistrationResult evaluated = o3d_registration::EvaluateRegistration(
        *prepared_source.points, *prepared_target.points, options.max_correspondence_distance,
        estimated.transformation_);
    const std::size_t inliers = evaluated.correspondence_set_.size();
    result.counts["inliers"] = static_cast<double>(inliers);
    result.solved = inliers >= minimum_points;
    std::ostringstream message;
    message << name << ": " << source_points << "/" << target_points << " down-sampled points, ";
    message << inliers << " inliers within " << options.max_correspondence_distance << " m (fitness "
            << evaluated.fitness_ << ")";
    if (!result.solved) message << "; no transform with at least " << minimum_points << " inliers";
    result.message = message.str();
  } catch (const std::exception& error) {
    result = BaselineResult{};
    result.message = name + ": Open3D failed: " + error.what();
  }
  result.timings_ms["total"] = total.lap_ms();
  return result;
}

}  // namespace

BaselineResult run_open3d_ransac(const PointCloud& source, const PointCloud& target, const BaselineOptions& options) {
  return run_with_open3d(
      "open3d-ransac", source, target, options,
      [&options](const PreparedCloud& prepared_source, const PreparedCloud& prepared_target) {
        const o3d_registration::CorrespondenceCheckerBasedOnEdgeLength edge_length(options.edge_length_similarity);
        const o3d_registration::CorrespondenceCheckerBasedOnDistance distance(options.max_correspondence_distance);
        return o3d_registration::RegistrationRANSACBasedOnFeatureMatching(
            *prepared_source.points, *prepared_target.points, *prepared_source.features, *prepared_target.features,
            options.mutual_filter, options.max_correspondence_distance,
            o3d_registration::TransformationEstimationPointToPoint(/*with_scaling=*/false), /*ransac_n=*/3,
            {edge_length, distance},
            o3d_registration::RANSACConvergenceCriteria(options.ransac_iterations, options.ransac_confidence));
      });
}

BaselineResult run_open3d_fgr(const PointCloud& source, const PointCloud& target, const BaselineOptions& options) {
  return run_with_open3d(
      "open3d-fgr", source, target, options,
      [&options](const PreparedCloud& prepared_source, const PreparedCloud& prepared_target) {
        o3d_registration::FastGlobalRegistrationOption fgr_options(
            /*division_factor=*/1.4, /*use_absolute_scale=*/true, /*decrease_mu=*/true,
            options.max_correspondence_distance, options.fgr_iterations, options.fgr_tuple_scale,
            options.fgr_maximum_tuple_count, /*tuple_test=*/true);
        return o3d_registration::FastGlobalRegistrationBasedOnFeatureMatching(
            *prepared_source.points, *prepared_target.points, *prepared_source.features, *prepared_target.features,
            fgr_options);
      });
}

}  // namespace quadrix::baselines_detail
