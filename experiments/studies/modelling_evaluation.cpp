// Scoring a modelling run against synthetic ground truth (see modelling_evaluation.h).
#include "experiments/studies/modelling_evaluation.h"

#include "geometry/error.h"

#include <algorithm>
#include <cmath>

namespace quadrix {

PointCloud merge_scans_in_world(const SyntheticRun& run) {
  std::size_t total = 0;
  for (const SimulatedScan& scan : run.scans) total += scan.cloud.size();
  PointCloud merged;
  merged.positions.resize(3, static_cast<Eigen::Index>(total));
  merged.labels.reserve(total);
  std::vector<float>& ids = merged.extra_fields["primitive_id"];
  ids.reserve(total);
  Eigen::Index column = 0;
  for (const SimulatedScan& scan : run.scans) {
    const Eigen::Isometry3f pose = scan.sensor_pose.cast<float>();
    for (std::size_t i = 0; i < scan.cloud.size(); ++i)
      merged.positions.col(column++) = pose * Eigen::Vector3f(scan.cloud.positions.col(static_cast<Eigen::Index>(i)));
    merged.labels.insert(merged.labels.end(), scan.cloud.labels.begin(), scan.cloud.labels.end());
    const auto field = scan.cloud.extra_fields.find("primitive_id");
    if (field == scan.cloud.extra_fields.end()) throw Error("merge_scans_in_world: a scan has no primitive_id field");
    ids.insert(ids.end(), field->second.begin(), field->second.end());
  }
  return merged;
}

bool fitted_type_matches(QuadricType fitted, QuadricType truth) {
  const auto family = [](QuadricType type) {
    if (type == QuadricType::EllipticCylinder) return QuadricType::CircularCylinder;
    if (type == QuadricType::EllipticCone) return QuadricType::CircularCone;
    return type;
  };
  return family(fitted) == family(truth);
}

double centre_error_on_defined_axes(const ScenePrimitive& primitive, const Eigen::Vector3d& fitted_centre) {
  const Eigen::Vector3d delta = fitted_centre - primitive.pose.translation();
  const Eigen::Matrix3d axes = primitive.pose.linear();
  switch (primitive.model_type) {
    case QuadricType::Plane: return std::abs(axes.col(0).dot(delta));
    case QuadricType::Line:
    case QuadricType::CircularCylinder:
    case QuadricType::EllipticCylinder: return (delta - axes.col(2).dot(delta) * axes.col(2)).norm();
    default: return delta.norm();
  }
}

ModellingEvaluation evaluate_modelling(const Scene& scene, const std::vector<float>& primitive_ids,
                                       const ModellingResult& result, std::size_t minimum_points, double minimum_share) {
  const std::size_t point_count = primitive_ids.size();
  const auto& elements = result.extraction.elements;
  std::vector<int> element_of_point(point_count, -1);
  for (std::size_t e = 0; e < elements.size(); ++e)
    for (const std::uint32_t index : elements[e].point_indices) {
      if (index >= point_count)
        throw Error("evaluate_modelling: element point " + std::to_string(index) + " beyond the " +
                    std::to_string(point_count) + " primitive ids");
      element_of_point[index] = static_cast<int>(e);
    }
  // Points per (primitive, element).
  const std::size_t primitive_count = scene.primitives.size();
  std::vector<std::map<int, std::size_t>> shares(primitive_count);
  std::vector<std::size_t> totals(primitive_count, 0);
  for (std::size_t i = 0; i < point_count; ++i) {
    const float id = primitive_ids[i];
    if (!(id >= 0.0f) || static_cast<std::size_t>(id) >= primitive_count) continue;
    const auto primitive = static_cast<std::size_t>(id);
    ++totals[primitive];
    if (element_of_point[i] >= 0) ++shares[primitive][element_of_point[i]];
  }
  std::vector<int> record_of_element(elements.size(), -1);
  for (std::size_t r = 0; r < result.model.augmented_begin; ++r)
    record_of_element[static_cast<std::size_t>(result.record_elements[r])] = static_cast<int>(r);

  ModellingEvaluation evaluation;
  std::vector<double> centre_errors;
  for (std::size_t p = 0; p < primitive_count; ++p) {
    if (totals[p] < minimum_points) continue;
    const ScenePrimitive& truth = scene.primitives[p];
    PrimitiveRecovery recovery;
    recovery.primitive = truth.id;
    recovery.name = truth.name;
    recovery.truth_type = truth.model_type;
    recovery.points = totals[p];
    std::size_t best = 0;
    for (const auto& [element, count] : shares[p])
      if (count > best) {
        best = count;
        recovery.element = element;
      }
    recovery.element_share = static_cast<double>(best) / static_cast<double>(totals[p]);
    recovery.recovered = recovery.element >= 0 && recovery.element_share >= minimum_share;
    if (recovery.recovered) {
      ++evaluation.recovered;
      const int record = record_of_element[static_cast<std::size_t>(recovery.element)];
      if (record >= 0) {
        recovery.modelled = true;
        recovery.fitted_type = result.model.types[static_cast<std::size_t>(record)];
        recovery.type_correct = fitted_type_matches(recovery.fitted_type, recovery.truth_type);
        recovery.centre_error =
            centre_error_on_defined_axes(truth, result.model.records[static_cast<std::size_t>(record)].full_center);
        centre_errors.push_back(recovery.centre_error);
      }
      if (recovery.type_correct) ++evaluation.type_correct;
    }
    evaluation.primitives.push_back(recovery);
  }
  if (!evaluation.primitives.empty())
    evaluation.recovered_fraction = static_cast<double>(evaluation.recovered) / static_cast<double>(evaluation.primitives.size());
  if (evaluation.recovered > 0)
    evaluation.type_correct_fraction = static_cast<double>(evaluation.type_correct) / static_cast<double>(evaluation.recovered);
  if (!centre_errors.empty()) {
    const auto middle = centre_errors.begin() + static_cast<std::ptrdiff_t>(centre_errors.size() / 2);
    std::nth_element(centre_errors.begin(), middle, centre_errors.end());
    evaluation.median_centre_error = *middle;
  }
  for (std::size_t r = 0; r < result.model.augmented_begin; ++r) ++evaluation.record_types[result.model.types[r]];
  return evaluation;
}

ClassScores score_element_classes(const PointCloud& cloud, const ExtractionResult& extraction,
                                  const std::vector<std::uint32_t>& labels, const ExtractionOptions& options) {
  if (labels.size() != cloud.size())
    throw Error("score_element_classes: " + std::to_string(labels.size()) + " labels for " + std::to_string(cloud.size()) +
                " points (expected one label per point)");
  // The class each point was modelled as; -1: in no element.
  std::vector<int> predicted(cloud.size(), -1);
  for (const Element& element : extraction.elements)
    for (const std::uint32_t index : element.point_indices) {
      if (index >= cloud.size())
        throw Error("score_element_classes: an element holds point " + std::to_string(index) + " of a cloud of " +
                    std::to_string(cloud.size()) + " points");
      predicted[index] = static_cast<int>(element.element_class);
    }
  ClassScores scores;
  const std::vector<ElementClass> scored_classes = {ElementClass::Ground,  ElementClass::Plane, ElementClass::Line,
                                                    ElementClass::Vehicle, ElementClass::Trunk, ElementClass::Vegetation};
  std::map<ElementClass, ClassScore> by_class;
  for (const ElementClass element_class : scored_classes) by_class[element_class].element_class = element_class;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    ElementClass truth = ElementClass::Object;
    if (!element_class_for_semantic_kitti_label(labels[i], truth) || !within_range(cloud.point(i), options)) continue;
    ++scores.scored;
    const bool in_element = predicted[i] >= 0;
    const ElementClass modelled = in_element ? static_cast<ElementClass>(predicted[i]) : ElementClass::Object;
    ++scores.confusion[truth][in_element ? element_class_name(modelled) : "none"];
    const auto truth_score = by_class.find(truth);
    if (truth_score != by_class.end()) ++truth_score->second.labelled;
    const auto modelled_score = by_class.find(modelled);
    if (in_element && modelled_score != by_class.end()) {
      ++modelled_score->second.predicted;
      modelled_score->second.agreeing += modelled == truth ? 1 : 0;
    }
  }
  for (const ElementClass element_class : scored_classes) {
    ClassScore score = by_class[element_class];
    score.recall = score.labelled > 0 ? static_cast<double>(score.agreeing) / static_cast<double>(score.labelled) : 0.0;
    score.precision = score.predicted > 0 ? static_cast<double>(score.agreeing) / static_cast<double>(score.predicted) : 0.0;
    scores.classes.push_back(score);
  }
  return scores;
}

}  // namespace quadrix
