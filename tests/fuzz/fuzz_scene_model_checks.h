// Invariants of a scene model a reader accepted, shared by the JSON and binary model harnesses:
// it passes validate_scene_model, its rotations are unit quaternions, and both writers accept it
// and read back the same model (a reader must not accept what the writers cannot write).
#pragma once

#include "fitting/scene_model.h"
#include "tests/fuzz/fuzz_support.h"

#include <cmath>

namespace quadrix::fuzz {

/// True when `a` and `b` hold the same records, types, counts, ground, descriptors and timings.
inline bool same_model(const SceneModel& a, const SceneModel& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (a.records[i].to_array() != b.records[i].to_array()) return false;
  return a.types == b.types && a.element_point_counts == b.element_point_counts &&
         a.augmented_begin == b.augmented_begin && a.augmented_descriptors == b.augmented_descriptors &&
         a.has_ground == b.has_ground && a.ground_normal == b.ground_normal && a.ground_offset == b.ground_offset &&
         a.source_point_count == b.source_point_count && a.timings_ms == b.timings_ms;
}

/// Traps unless `model` is valid, has unit rotations and round-trips through both formats.
inline void check_scene_model(const SceneModel& model) {
  try {
    validate_scene_model(model);
  } catch (const Error& error) {
    fail(std::string("an accepted model is invalid: ") + error.what());
  }
  for (const QuadricRecord& record : model.records) require(std::abs(record.full_rotation.norm() - 1.0) <= 1e-9);
  try {
    require(same_model(model, scene_model_from_binary(scene_model_to_binary(model), "round-trip.qsm")));
    require(same_model(model, scene_model_from_json(scene_model_to_json(model), "round-trip.json")));
  } catch (const Error& error) {
    fail(std::string("an accepted model does not round-trip: ") + error.what());
  }
}

}  // namespace quadrix::fuzz
