// PCL 1.13 baseline: FPFH + SampleConsensusPrerejective (Buch et al., ICRA 2013), the settings of
// PCL's "robust pose estimation of rigid objects" tutorial scaled to outdoor LiDAR (baselines.h).
// Normals and FPFH use PCL's OpenMP estimators with BaselineOptions::threads threads; the
// prerejective RANSAC itself is single-threaded and draws from the C library's rand().
#include "experiments/baselines/baselines_backends.h"

#include <pcl/features/fpfh_omp.h>
#include <pcl/features/normal_3d_omp.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/sample_consensus_prerejective.h>

#include <cmath>
#include <cstdlib>
#include <exception>
#include <sstream>
#include <string>
#include <vector>

namespace quadrix::baselines_detail {
namespace {

using PclPoints = pcl::PointCloud<pcl::PointXYZ>;
using PclNormals = pcl::PointCloud<pcl::Normal>;
using PclFeatures = pcl::PointCloud<pcl::FPFHSignature33>;

/// One cloud after the shared front end: down-sampled points with a finite normal, and their FPFH.
struct PreparedCloud {
  PclPoints::Ptr points{new PclPoints};        ///< voxel centroids whose normal is finite
  PclNormals::Ptr normals{new PclNormals};     ///< normals oriented towards the sensor at the origin
  PclFeatures::Ptr features{new PclFeatures};  ///< FPFH per point
};

/// Converts a Quadrix cloud to a PCL cloud (positions only).
PclPoints::Ptr to_pcl(const PointCloud& cloud) {
  PclPoints::Ptr converted(new PclPoints);
  converted->resize(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const auto column = cloud.positions.col(static_cast<Eigen::Index>(i));
    (*converted)[i] = pcl::PointXYZ(column.x(), column.y(), column.z());
  }
  return converted;
}

/// Voxel centroids of `cloud` (PCL VoxelGrid, the same rule as Open3D's VoxelDownSample).
PclPoints::Ptr downsample(const PointCloud& cloud, double voxel_size) {
  pcl::VoxelGrid<pcl::PointXYZ> grid;
  grid.setInputCloud(to_pcl(cloud));
  const auto leaf = static_cast<float>(voxel_size);
  grid.setLeafSize(leaf, leaf, leaf);
  PclPoints::Ptr filtered(new PclPoints);
  grid.filter(*filtered);
  return filtered;
}

/// Normals of `points` by radius search, keeping only points whose normal is finite (PCL leaves
/// NaN where a neighbourhood has fewer than 3 points, and FPFH of a NaN normal is meaningless).
void estimate_normals(const PclPoints::Ptr& points, const BaselineOptions& options, PreparedCloud& prepared) {
  pcl::NormalEstimationOMP<pcl::PointXYZ, pcl::Normal> estimation(static_cast<unsigned>(options.threads));
  estimation.setInputCloud(points);
  estimation.setRadiusSearch(options.normal_radius);
  estimation.setViewPoint(0.0f, 0.0f, 0.0f);  // the sensor
  PclNormals all_normals;
  estimation.compute(all_normals);
  for (std::size_t i = 0; i < points->size(); ++i) {
    const pcl::Normal& normal = all_normals[i];
    if (!std::isfinite(normal.normal_x) || !std::isfinite(normal.normal_y) || !std::isfinite(normal.normal_z))
      continue;
    prepared.points->push_back((*points)[i]);
    prepared.normals->push_back(normal);
  }
}

/// FPFH of every prepared point.
void estimate_features(const BaselineOptions& options, PreparedCloud& prepared) {
  pcl::FPFHEstimationOMP<pcl::PointXYZ, pcl::Normal, pcl::FPFHSignature33> estimation(
      static_cast<unsigned>(options.threads));
  estimation.setInputCloud(prepared.points);
  estimation.setInputNormals(prepared.normals);
  estimation.setRadiusSearch(options.feature_radius);
  estimation.compute(*prepared.features);
}

/// Source points within `distance` of a target point once moved by `transform`.
std::size_t count_inliers(const PclPoints& source, const PclPoints::Ptr& target, const Eigen::Matrix4f& transform,
                          double distance) {
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  tree.setInputCloud(target);
  std::vector<int> index(1);
  std::vector<float> squared_distance(1);
  const float limit = static_cast<float>(distance * distance);
  std::size_t inliers = 0;
  for (const pcl::PointXYZ& point : source) {
    const Eigen::Vector4f moved = transform * Eigen::Vector4f(point.x, point.y, point.z, 1.0f);
    if (tree.nearestKSearch(pcl::PointXYZ(moved.x(), moved.y(), moved.z()), 1, index, squared_distance) == 1 &&
        squared_distance[0] <= limit)
      ++inliers;
  }
  return inliers;
}

}  // namespace

BaselineResult run_pcl_prerejective(const PointCloud& source, const PointCloud& target,
                                    const BaselineOptions& options) {
  const std::string name = "pcl-prerejective";
  Stopwatch total;
  Stopwatch stage;
  BaselineResult result;
  try {
    const PclPoints::Ptr source_down = downsample(source, options.voxel_size);
    const PclPoints::Ptr target_down = downsample(target, options.voxel_size);
    result.timings_ms["downsample"] = stage.lap_ms();

    PreparedCloud prepared_source;
    PreparedCloud prepared_target;
    estimate_normals(source_down, options, prepared_source);
    estimate_normals(target_down, options, prepared_target);
    result.timings_ms["normals"] = stage.lap_ms();
    result.counts["source_points"] = static_cast<double>(prepared_source.points->size());
    result.counts["target_points"] = static_cast<double>(prepared_target.points->size());
    const std::size_t source_points = prepared_source.points->size();
    const std::size_t target_points = prepared_target.points->size();
    if (source_points < minimum_points || target_points < minimum_points) {
      result.message = name + ": too few points with a normal after " + std::to_string(options.voxel_size) +
                       " m voxel down-sampling (source " + std::to_string(source_points) + ", target " +
                       std::to_string(target_points) + ", need " + std::to_string(minimum_points) + ")";
      result.timings_ms["features"] = 0.0;
      result.timings_ms["registration"] = 0.0;
      result.timings_ms["total"] = total.lap_ms();
      return result;
    }

    estimate_features(options, prepared_source);
    estimate_features(options, prepared_target);
    result.timings_ms["features"] = stage.lap_ms();

    std::srand(options.seed);  // SampleConsensusPrerejective samples with rand()
    pcl::SampleConsensusPrerejective<pcl::PointXYZ, pcl::PointXYZ, pcl::FPFHSignature33> align;
    align.setInputSource(prepared_source.points);
    align.setSourceFeatures(prepared_source.features);
    align.setInputTarget(prepared_target.points);
    align.setTargetFeatures(prepared_target.features);
    align.setMaximumIterations(options.prerejective_iterations);
    align.setNumberOfSamples(options.prerejective_samples);
    align.setCorrespondenceRandomness(options.prerejective_feature_neighbours);
    align.setSimilarityThreshold(static_cast<float>(options.edge_length_similarity));
    align.setMaxCorrespondenceDistance(options.max_correspondence_distance);
    align.setInlierFraction(static_cast<float>(options.prerejective_inlier_fraction));
    PclPoints aligned;
    align.align(aligned);
    result.timings_ms["registration"] = stage.lap_ms();

    const Eigen::Matrix4f transform = align.getFinalTransformation();  // maps source into the target frame
    result.transform.matrix() = transform.cast<double>();
    const std::size_t inliers =
        count_inliers(*prepared_source.points, prepared_target.points, transform, options.max_correspondence_distance);
    result.counts["inliers"] = static_cast<double>(inliers);
    result.solved = align.hasConverged() && inliers >= minimum_points;
    std::ostringstream message;
    message << name << ": " << source_points << "/" << target_points << " down-sampled points, " << inliers
            << " inliers within " << options.max_correspondence_distance << " m (fitness "
            << static_cast<double>(inliers) / static_cast<double>(source_points) << ")";
    if (!align.hasConverged())
      message << "; no hypothesis reached the inlier fraction " << options.prerejective_inlier_fraction << " in "
              << options.prerejective_iterations << " iterations";
    result.message = message.str();
    if (!result.solved) result.transform = Eigen::Isometry3d::Identity();
  } catch (const std::exception& error) {
    result = BaselineResult{};
    result.message = name + ": PCL failed: " + error.what();
  }
  result.timings_ms["total"] = total.lap_ms();
  return result;
}

}  // namespace quadrix::baselines_detail
