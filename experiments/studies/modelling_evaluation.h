// Scoring a modelling run against a synthetic scene's ground truth (modelling acceptance): which true
// primitives were recovered as elements, whether their fitted type is right, and how far the fitted
// centre is on the axes that define it.
#pragma once

#include "experiments/synthetic/synthetic_output.h"
#include "fitting/extraction.h"
#include "fitting/scene_modelling.h"
#include "geometry/point_cloud.h"

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace quadrix {

/// Every scan of a run moved into the world frame (sensor pose applied) and concatenated, keeping
/// the labels and the "primitive_id" field: a multi-station static scan as one cloud.
PointCloud merge_scans_in_world(const SyntheticRun& run);

/// True when a fitted type counts as the true model type: equal, or the same family with free
/// aspect ratio (circular/elliptic cylinder, circular/elliptic cone).
bool fitted_type_matches(QuadricType fitted, QuadricType truth);

/// Centre error of a fitted record against a true primitive on the primitive's non-degenerate axes
/// (paper's I_t): planes along the normal only, lines and cylinders across the axis only, central
/// types and cones (apex) in all three directions. Metres.
double centre_error_on_defined_axes(const ScenePrimitive& primitive, const Eigen::Vector3d& fitted_centre);

/// How one ground-truth primitive fared.
struct PrimitiveRecovery {
  std::uint32_t primitive = 0;                 ///< primitive id
  std::string name;                            ///< primitive name
  QuadricType truth_type = QuadricType::Invalid;  ///< the type modelling should fit (ScenePrimitive::model_type)
  std::size_t points = 0;                      ///< its points in the cloud
  int element = -1;                            ///< element holding the most of its points (-1: none)
  double element_share = 0.0;                  ///< fraction of its points in that element
  bool recovered = false;                      ///< element_share >= the evaluation's minimum share
  bool modelled = false;                       ///< that element has a record in the model (kept by top-K_e)
  QuadricType fitted_type = QuadricType::Invalid;  ///< type of that record
  bool type_correct = false;                   ///< fitted_type_matches(fitted_type, truth_type)
  double centre_error = 0.0;                   ///< centre_error_on_defined_axes of that record's t_f, m
};

/// Acceptance numbers of a modelling run on a synthetic scene.
struct ModellingEvaluation {
  std::vector<PrimitiveRecovery> primitives;   ///< every primitive with at least the minimum points
  std::size_t recovered = 0;                   ///< of those, recovered
  std::size_t type_correct = 0;                ///< of the recovered, with the right fitted type
  double recovered_fraction = 0.0;             ///< recovered / evaluated (0 when none evaluated)
  double type_correct_fraction = 0.0;          ///< type_correct / recovered (0 when none recovered)
  double median_centre_error = 0.0;            ///< median centre error over the recovered and modelled, m
  std::map<QuadricType, int> record_types;     ///< quadric records in the model per type (augmented points excluded)
};

/// Matches elements to primitives by point-id majority: for each primitive with at least
/// `minimum_points` points, the element that holds the most of them is its element, and the
/// primitive is recovered when that element holds at least `minimum_share` of them (so a ground
/// element that also holds the sidewalks recovers each sidewalk, but a wall split into pieces with
/// none holding half of it is not recovered). `primitive_ids` holds one id per point of the cloud
/// that was modelled (the simulator's "primitive_id" field; negative: no primitive).
ModellingEvaluation evaluate_modelling(const Scene& scene, const std::vector<float>& primitive_ids,
                                       const ModellingResult& result, std::size_t minimum_points = 200,
                                       double minimum_share = 0.5);

/// How one class's points fared: a modelling run's element classes against per-point labels.
struct ClassScore {
  ElementClass element_class = ElementClass::Ground;  ///< the class scored
  std::size_t labelled = 0;   ///< scored points whose label maps to this class
  std::size_t predicted = 0;  ///< scored points in an element of this class
  std::size_t agreeing = 0;   ///< scored points both labelled and predicted as this class
  double recall = 0.0;        ///< agreeing / labelled (0 when none is labelled)
  double precision = 0.0;     ///< agreeing / predicted (0 when none is predicted)
};

/// Per-point agreement of an extraction's element classes with SemanticKITTI labels.
struct ClassScores {
  std::vector<ClassScore> classes;  ///< ground, plane, line, vehicle, trunk, vegetation, in this order
  std::size_t scored = 0;           ///< points within the extraction's range whose label maps to a class
  std::map<ElementClass, std::map<std::string, std::size_t>> confusion;  ///< labelled class -> where its scored points went: an element class name (element_class_name), or "none" when in no element
};

/// Scores the classes of `extraction` (of `cloud`) against `labels`, one SemanticKITTI label per
/// point of `cloud`, mapped by element_class_for_semantic_kitti_label (pole and traffic sign are
/// Line, building and fence Plane, road and sidewalk Ground...). Points outside the extraction's
/// range (within_range with `options`) and points whose label maps to no class (unlabelled,
/// person, other-object) are not scored. A point's prediction is the class of the element holding
/// it; a point in no element, or in an Object element, counts against recall. Throws
/// quadrix::Error when `labels` does not hold one label per point or an element names a point
/// outside the cloud.
ClassScores score_element_classes(const PointCloud& cloud, const ExtractionResult& extraction,
                                  const std::vector<std::uint32_t>& labels, const ExtractionOptions& options);

}  // namespace quadrix
