// Quadric scene modelling (paper §"Quadric Fitting" and §"Quadric Modeling"): fit every extracted
// element with a QuadricFitter as the type of its class, complete degenerate attributes with the
// statistical pose (Eq. (full attributes)), keep the top-K_e per class by size V_a, and augment
// sparse scenes with voxel-down-sampled points of the largest elements (with FPFH descriptors).
#pragma once

#include "fitting/extraction.h"
#include "fitting/quadric_fitter.h"
#include "fitting/scene_model.h"
#include "geometry/point_cloud.h"

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace quadrix {

/// Options of the modelling step; defaults are the paper's (§"Implementation Details").
struct ModellingOptions {
  std::string fitter = "statistical";    ///< registry name of the QuadricFitter (make_quadric_fitter)
  int maximum_fit_points = 4000;         ///< larger elements (ground, facades) hand the fitter an evenly strided subsample of at most this many points; the record's statistical pose still uses every point (0: no cap)
  int quadrics_per_class = 50;           ///< K_e: quadrics kept per semantic class (paper 50)
  int augmentation_threshold = 60;       ///< delta_a: augment when fewer quadrics than this (paper 60)
  int augmented_elements_per_class = 10; ///< K_a: largest elements per class that are down-sampled (paper 10)
  double augmentation_voxel = 0.5;       ///< v_a: voxel size of the augmentation down-sampling, m (paper 0.5)
  int maximum_augmented_points = 1500;   ///< at most this many augmented points, evenly strided over the K_a elements' voxels (0: no cap; the paper has none, KITTI gives ~6k)
  bool compute_descriptors = true;       ///< compute FPFH descriptors of augmented points (PCL)
  double descriptor_normal_radius = 1.0; ///< normal estimation radius for FPFH, m (2 v_a)
  double descriptor_radius = 2.5;        ///< FPFH support radius, m (5 v_a)
  double descriptor_surface_voxel = 0.5; ///< the cloud is down-sampled at this voxel (v_a) for the FPFH support surface, m
};

/// Size V_a of a record (paper §"Quadric Modeling"): product of the first n full scales, n = 1 for
/// lines, 2 for planes (and ground), 3 for volumes; points have size 0.
double record_size(const QuadricRecord& record, QuadricType type);

/// Outcome of modelling.
enum class ModellingStatus {
  Ok,          ///< at least one quadric
  Empty,       ///< no element could be fitted (the model may still hold augmented points)
};

/// Lower-case name of a status ("ok", "empty").
std::string modelling_status_name(ModellingStatus status);

/// Everything modelling returns: the model plus what produced it.
struct ModellingResult {
  ModellingStatus status = ModellingStatus::Ok;  ///< outcome
  std::string message;                           ///< why, when not ok (extraction and fitting notes)
  SceneModel model;                              ///< the scene representation R
  ExtractionResult extraction;                   ///< the elements that were fitted
  std::vector<int> record_elements;              ///< element index (into extraction.elements) behind each record
  std::size_t elements_fitted = 0;               ///< elements whose fit returned ok
  std::size_t elements_failed = 0;               ///< elements whose fit failed (skipped)
  std::size_t elements_dropped_by_top_k = 0;     ///< fitted elements beyond K_e in their class
};

/// Fits the elements of `extraction` (indices into `points`) and builds the model (fills
/// model.timings_ms for "fitting", "selection", "augmentation"). `extraction` is copied into the result.
ModellingResult model_elements(const Eigen::Matrix3Xd& points, const ExtractionResult& extraction,
                               const ModellingOptions& options);

/// Adds the paper's augmented points to a model that has none (paper §"Quadric Modeling"): the
/// K_a largest kept elements per class, voxel-down-sampled at v_a, one point-type record per voxel
/// with its FPFH descriptor. model_elements calls it below delta_a quadrics; registration calls it
/// on the other side of a pair when only one side was augmented (augmented matches need both).
void augment_scene_model(const Eigen::Matrix3Xd& points, ModellingResult& modelling, const ModellingOptions& options);

/// Whether `cloud` lies on one plane, as augment_scene_model decides it: the means of its voxels of
/// edge v = options.descriptor_surface_voxel all within 0.2 v of their least-squares plane (fewer
/// than 3 voxels count as one plane). Within that the normals over FPFH's normal radius (2 v) tilt
/// by under atan(0.2 v / 2 v) ~ 6 degrees, inside one of FPFH's 11 angle bins. Such a cloud leaves
/// three motions free (two shifts in the plane, the turn about its normal): it cannot be registered.
bool lies_on_one_plane(const PointCloud& cloud, const ModellingOptions& options);

/// Extraction (extract_elements) followed by model_elements: the whole paper §"Quadric-based Scene
/// Representation". Timings of every stage and "total" are in model.timings_ms.
ModellingResult model_scene(const PointCloud& cloud, const ExtractionOptions& extraction_options,
                            const ModellingOptions& modelling_options, const std::vector<std::uint32_t>& labels = {});

}  // namespace quadrix
