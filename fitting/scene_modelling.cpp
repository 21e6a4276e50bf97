// Quadric scene modelling (paper §"Quadric Fitting" and §"Quadric Modeling"): fit each element as
// its class's type, complete attributes (Eq. (full attributes) via make_quadric_record), keep the
// top-K_e per class by size V_a, augment sparse scenes with voxel points (+ FPFH descriptors, PCL).
#include "fitting/scene_modelling.h"
#include "fitting/extraction_internal.h"

#include "geometry/error.h"
#include "geometry/voxel_cells.h"

#include <pcl/features/fpfh_omp.h>
#include <pcl/features/normal_3d_omp.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <unordered_map>

namespace quadrix {

double record_size(const QuadricRecord& record, QuadricType type) {
  int axes = 3;
  switch (type) {
    case QuadricType::Point: return 0.0;
    case QuadricType::Line: axes = 1; break;
    case QuadricType::Plane: axes = 2; break;
    default: axes = 3; break;
  }
  double size = 1.0;
  for (int axis = 0; axis < axes; ++axis) size *= record.full_scale(axis);
  return size;
}

std::string modelling_status_name(ModellingStatus status) {
  return status == ModellingStatus::Ok ? "ok" : "empty";
}

namespace {

using Clock = std::chrono::steady_clock;

struct FittedElement {
  bool ok = false;
  QuadricRecord record;
  QuadricType type = QuadricType::Invalid;
  double size = 0.0;
  std::string message;
};

// The cloud down-sampled at `voxel`: one point at the mean of each voxel's points (the FPFH
// support surface, and what the one-plane test below looks at).
template <typename Points>
pcl::PointCloud<pcl::PointXYZ>::Ptr voxel_means(const Points& points, double voxel) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr surface(new pcl::PointCloud<pcl::PointXYZ>);
  CellMap<std::uint32_t> slot;  // cell -> index into cells, in the order cells are first met
  std::vector<detail::Moments> cells;
  const double inverse = 1.0 / voxel;
  for (Eigen::Index i = 0; i < points.cols(); ++i) {
    const Eigen::Vector3d point = points.col(i).template cast<double>();
    const Eigen::Vector3i c((point * inverse).array().floor().cast<int>());
    const auto [index, inserted] =
        slot.try_emplace(detail::voxel_key(c.x(), c.y(), c.z()), static_cast<std::uint32_t>(cells.size()));
    if (inserted) cells.emplace_back();
    cells[index].add(point);
  }
  surface->reserve(cells.size());
  for (const auto& cell : cells) {
    const Eigen::Vector3d m = cell.mean();
    surface->push_back(pcl::PointXYZ(static_cast<float>(m.x()), static_cast<float>(m.y()), static_cast<float>(m.z())));
  }
  return surface;
}

// Whether every point of `surface` lies within `tolerance` of one plane (the least-squares plane of
// the points, the normal its covariance's smallest eigenvector). Fewer than 3 points count as one plane.
bool surface_on_one_plane(const pcl::PointCloud<pcl::PointXYZ>& surface, double tolerance) {
  if (surface.size() < 3) return true;
  detail::Moments moments;
  for (const pcl::PointXYZ& p : surface) moments.add(Eigen::Vector3d(p.x, p.y, p.z));
  const Eigen::Vector3d centre = moments.mean();
  const Eigen::Matrix3d covariance = moments.outer / moments.count - centre * centre.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  const Eigen::Vector3d normal = solver.eigenvectors().col(0);
  for (const pcl::PointXYZ& p : surface)
    if (std::abs(normal.dot(Eigen::Vector3d(p.x, p.y, p.z) - centre)) > tolerance) return false;
  return true;
}

// FPFH (Rusu et al. 2009) of the augmented points on the support `surface` (voxel_means at
// descriptor_surface_voxel) with normals from a radius neighbourhood.
std::vector<std::array<float, kFpfhSize>> fpfh_descriptors(const pcl::PointCloud<pcl::PointXYZ>::Ptr& surface,
                                                           const Eigen::Matrix3Xd& keypoints,
                                                           const ModellingOptions& options) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr queries(new pcl::PointCloud<pcl::PointXYZ>);
  for (Eigen::Index i = 0; i < keypoints.cols(); ++i)
    queries->push_back(pcl::PointXYZ(static_cast<float>(keypoints(0, i)), static_cast<float>(keypoints(1, i)),
                                     static_cast<float>(keypoints(2, i))));
  pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
  pcl::PointCloud<pcl::Normal>::Ptr normals(new pcl::PointCloud<pcl::Normal>);
  pcl::NormalEstimationOMP<pcl::PointXYZ, pcl::Normal> normal_estimation(2);
  normal_estimation.setInputCloud(surface);
  normal_estimation.setSearchMethod(tree);
  normal_estimation.setRadiusSearch(options.descriptor_normal_radius);
  normal_estimation.compute(*normals);
  pcl::PointCloud<pcl::FPFHSignature33> features;
  pcl::FPFHEstimationOMP<pcl::PointXYZ, pcl::Normal, pcl::FPFHSignature33> fpfh(2);
  fpfh.setInputCloud(queries);
  fpfh.setSearchSurface(surface);
  fpfh.setInputNormals(normals);
  fpfh.setSearchMethod(tree);
  fpfh.setRadiusSearch(options.descriptor_radius);
  fpfh.compute(features);
  std::vector<std::array<float, kFpfhSize>> descriptors(static_cast<std::size_t>(keypoints.cols()));
  for (std::size_t i = 0; i < descriptors.size(); ++i)
    for (int bin = 0; bin < kFpfhSize; ++bin) {
      const float value = features[i].histogram[bin];
      descriptors[i][bin] = std::isfinite(value) ? value : 0.0f;  // PCL writes NaN where a point has too few neighbours
    }
  return descriptors;
}

// The tolerance of the one-plane test (lies_on_one_plane in scene_modelling.h says why 0.2 v).
double one_plane_tolerance(const ModellingOptions& options) { return 0.2 * options.descriptor_surface_voxel; }

// Every ceil(N / cap)-th column of `points` (at most `cap` of them, evenly spread along the element's
// point order, deterministic), or all of them when cap is 0 or N <= cap. A 70k-point ground or a
// 10k-point facade has the same plane from 4,000 evenly spread points; the fit's cost does not.
Eigen::Matrix3Xd fit_subsample(const Eigen::Matrix3Xd& points, int cap) {
  const Eigen::Index count = points.cols();
  if (cap <= 0 || count <= cap) return points;
  const Eigen::Index stride = (count + cap - 1) / cap;
  Eigen::Matrix3Xd sample(3, (count + stride - 1) / stride);
  for (Eigen::Index i = 0; i < sample.cols(); ++i) sample.col(i) = points.col(i * stride);
  return sample;
}

}  // namespace

void augment_scene_model(const Eigen::Matrix3Xd& points, ModellingResult& modelling, const ModellingOptions& options) {
  if (!(options.augmentation_voxel > 0.0)) throw Error("modelling option v_a (augmentation_voxel) must be positive");
  SceneModel& model = modelling.model;
  if (model.augmented_count() > 0) return;
  // A cloud on one plane: augmented points there are alike (FPFH sees only the plane's own angles)
  // and, like the plane, leave the three in-plane motions free, so they add no constraint and are not
  // made. On a flat 300 k-point scene the descriptors were ~95% of modelling's time (docs/reliability.md).
  const pcl::PointCloud<pcl::PointXYZ>::Ptr surface = voxel_means(points, options.descriptor_surface_voxel);
  if (surface_on_one_plane(*surface, one_plane_tolerance(options))) {
    modelling.message += std::string(modelling.message.empty() ? "" : "; ") +
                         "the cloud lies on one plane: no augmented points (they would add no constraint)";
    return;
  }
  const std::vector<Element>& elements = modelling.extraction.elements;
  // The kept records are grouped by class, largest V_a first (top-K_e above), so the first K_a
  // quadric records of each class are its K_a largest elements (K_a <= K_e).
  std::map<std::uint32_t, std::vector<int>> by_class;
  for (std::size_t r = 0; r < model.augmented_begin; ++r)
    by_class[model.records[r].label].push_back(modelling.record_elements[r]);
  // Each voxel of v_a becomes a point-type record at the voxel's mean (statistical pose of its points).
  struct Candidate {
    std::uint32_t label;
    int element;
    StatisticalPose statistics;
    std::uint32_t points;
  };
  std::vector<Candidate> candidates;
  for (auto& [label, members] : by_class) {
    const std::size_t take =
        std::min<std::size_t>(members.size(), static_cast<std::size_t>(options.augmented_elements_per_class));
    for (std::size_t k = 0; k < take; ++k) {
      const int e = members[k];
      std::unordered_map<std::uint64_t, std::size_t> slot;
      std::vector<std::vector<std::uint32_t>> voxels;
      const double inverse = 1.0 / options.augmentation_voxel;
      for (const std::uint32_t index : elements[e].point_indices) {
        const Eigen::Vector3i c((points.col(index) * inverse).array().floor().cast<int>());
        auto [it, inserted] = slot.try_emplace(detail::voxel_key(c.x(), c.y(), c.z()), voxels.size());
        if (inserted) voxels.emplace_back();
        voxels[it->second].push_back(index);
      }
      for (const auto& voxel : voxels) {
        const Eigen::Matrix3Xd voxel_points = detail::gather_points(points, voxel);
        candidates.push_back({label, e, statistical_pose(voxel_points), static_cast<std::uint32_t>(voxel.size())});
      }
    }
  }
  // At most maximum_augmented_points, evenly strided over the classes' voxels (deterministic): FPFH,
  // FPFH matching and selection grow with the count (KITTI: 5.9k points cost 0.44 s of FPFH alone).
  const std::size_t cap = options.maximum_augmented_points > 0 ? static_cast<std::size_t>(options.maximum_augmented_points)
                                                                : candidates.size();
  const std::size_t kept = std::min(cap, candidates.size());
  Eigen::Matrix3Xd keypoints(3, static_cast<Eigen::Index>(kept));
  for (std::size_t k = 0; k < kept; ++k) {
    const Candidate& candidate = candidates[k * candidates.size() / kept];
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = candidate.statistics.center;
    const Quadric point_quadric = Quadric::from_canonical(QuadricType::Point, Eigen::Vector3d::Ones(), pose);
    model.records.push_back(make_quadric_record(candidate.label, point_quadric, candidate.statistics));
    model.types.push_back(QuadricType::Point);
    model.element_point_counts.push_back(candidate.points);
    modelling.record_elements.push_back(candidate.element);
    keypoints.col(static_cast<Eigen::Index>(k)) = candidate.statistics.center;
  }
  if (options.compute_descriptors && kept > 0) model.augmented_descriptors = fpfh_descriptors(surface, keypoints, options);
}

bool lies_on_one_plane(const PointCloud& cloud, const ModellingOptions& options) {
  const double voxel = options.descriptor_surface_voxel;
  if (!(voxel > 0.0)) throw Error("modelling option descriptor_surface_voxel must be positive");
  // Evenly strided points first: a cloud that is not one plane (every real scan) is told from at most
  // 500,000 of its points; only a cloud whose sample lies on one plane is then tested whole.
  constexpr Eigen::Index kSample = 500000;
  const Eigen::Index count = cloud.positions.cols();
  if (count > kSample) {
    const Eigen::Index stride = (count + kSample - 1) / kSample;
    const Eigen::Matrix3Xf sample = cloud.positions(Eigen::all, Eigen::seq(0, count - 1, stride));
    if (!surface_on_one_plane(*voxel_means(sample, voxel), one_plane_tolerance(options))) return false;
  }
  return surface_on_one_plane(*voxel_means(cloud.positions, voxel), one_plane_tolerance(options));
}

ModellingResult model_elements(const Eigen::Matrix3Xd& points, const ExtractionResult& extraction,
                               const ModellingOptions& options) {
  if (options.quadrics_per_class < 0 || options.augmentation_threshold < 0 || options.augmented_elements_per_class < 0 ||
      options.maximum_augmented_points < 0)
    throw Error("modelling options: K_e, delta_a, K_a and maximum_augmented_points must be non-negative");
  if (!(options.augmentation_voxel > 0.0)) throw Error("modelling option v_a (augmentation_voxel) must be positive");
  if (options.maximum_fit_points < 0) throw Error("modelling option maximum_fit_points must be non-negative (0: no cap)");
  // Modelling reads only the fitted quadric and type, never the residual statistics, so the fitter
  // skips them (the same quadric either way; exact residuals were most of each fit's cost).
  const std::unique_ptr<QuadricFitter> fitter =
      make_quadric_fitter(options.fitter, FitEvaluationOptions{ResidualEvaluation::Skip});
  ModellingResult result;
  result.extraction = extraction;
  SceneModel& model = result.model;
  model.has_ground = extraction.has_ground;
  model.ground_normal = extraction.ground_normal;
  model.ground_offset = extraction.ground_offset;
  model.timings_ms = extraction.timings_ms;
  const auto& elements = extraction.elements;

  // Fitting (paper §"Quadric Fitting"): type from the class (or the detector), full attributes from
  // the statistical pose (paper Eq. (full attributes)).
  auto stage = Clock::now();
  std::vector<FittedElement> fitted(elements.size());
  tbb::parallel_for(std::size_t(0), elements.size(), [&](std::size_t e) {
    const Element& element = elements[e];
    const QuadricType type = element.detected_type != QuadricType::Invalid ? element.detected_type
                                                                            : quadric_type_for_class(element.element_class);
    const Eigen::Matrix3Xd element_points = detail::gather_points(points, element.point_indices);
    FittedElement& out = fitted[e];
    if (element.point_indices.size() < minimum_points_for_type(type)) {
      out.message = "too few points";
      return;
    }
    const QuadricFit fit = fitter->fit(fit_subsample(element_points, options.maximum_fit_points), Eigen::Matrix3Xd(), type);
    if (fit.status != FitStatus::Ok || !fit.quadric.matrix().allFinite()) {
      out.message = fit_status_name(fit.status) + (fit.message.empty() ? "" : ": " + fit.message);
      return;
    }
    const StatisticalPose statistics = statistical_pose(element_points);
    out.record = make_quadric_record(static_cast<std::uint32_t>(element.element_class), fit.quadric, statistics);
    bool finite = true;
    for (const double value : out.record.to_array()) finite = finite && std::isfinite(value);
    if (!finite) {
      out.message = "non-finite record";
      return;
    }
    out.type = fit.type;
    out.size = record_size(out.record, fit.type);
    out.ok = true;
  });
  std::map<std::string, int> failures;
  for (const FittedElement& f : fitted) {
    if (f.ok)
      ++result.elements_fitted;
    else {
      ++result.elements_failed;
      ++failures[f.message];
    }
  }
  model.timings_ms["fitting"] = detail::elapsed_ms(stage);

  // Top-K_e per class by size V_a (paper §"Quadric Modeling").
  stage = Clock::now();
  std::map<std::uint32_t, std::vector<int>> by_class;
  for (int e = 0; e < static_cast<int>(elements.size()); ++e)
    if (fitted[e].ok) by_class[static_cast<std::uint32_t>(elements[e].element_class)].push_back(e);
  for (auto& [label, members] : by_class) {
    std::stable_sort(members.begin(), members.end(), [&](int a, int b) { return fitted[a].size > fitted[b].size; });
    const std::size_t keep = std::min<std::size_t>(members.size(), static_cast<std::size_t>(options.quadrics_per_class));
    result.elements_dropped_by_top_k += members.size() - keep;
    for (std::size_t k = 0; k < keep; ++k) {
      const int e = members[k];
      model.records.push_back(fitted[e].record);
      model.types.push_back(fitted[e].type);
      model.element_point_counts.push_back(static_cast<std::uint32_t>(elements[e].point_indices.size()));
      result.record_elements.push_back(e);
    }
  }
  model.augmented_begin = model.records.size();
  model.timings_ms["selection"] = detail::elapsed_ms(stage);

  // Augmentation when fewer than delta_a quadrics (paper §"Quadric Modeling").
  stage = Clock::now();
  if (static_cast<int>(model.records.size()) < options.augmentation_threshold) augment_scene_model(points, result, options);
  model.timings_ms["augmentation"] = detail::elapsed_ms(stage);

  if (model.augmented_begin == 0) {
    result.status = ModellingStatus::Empty;
    result.message = elements.empty() ? "no elements were extracted" : "no element could be fitted";
  }
  if (!extraction.message.empty()) result.message += (result.message.empty() ? "" : "; ") + extraction.message;
  for (const auto& [reason, count] : failures)
    result.message += (result.message.empty() ? "" : "; ") + std::to_string(count) + " element(s) not fitted (" + reason + ")";
  return result;
}

ModellingResult model_scene(const PointCloud& cloud, const ExtractionOptions& extraction_options,
                            const ModellingOptions& modelling_options, const std::vector<std::uint32_t>& labels) {
  const auto start = Clock::now();
  const Eigen::Matrix3Xd points = cloud.positions.cast<double>();
  const ExtractionResult extraction = detail::extract_elements_of_points(points, cloud, extraction_options, labels);
  ModellingResult result = model_elements(points, extraction, modelling_options);
  result.model.source_point_count = cloud.size();
  result.model.timings_ms["total"] = detail::elapsed_ms(start);
  return result;
}

}  // namespace quadrix
