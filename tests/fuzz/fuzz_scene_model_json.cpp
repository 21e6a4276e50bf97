// Fuzz target: scene_model_from_json (the model JSON written by `quadrix model`).
#include "tests/fuzz/fuzz_scene_model_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace quadrix;
  const std::string source = "fuzz-model.json";
  SceneModel model;
  try {
    model = scene_model_from_json(std::string(reinterpret_cast<const char*>(data), size), source);
  } catch (const Error& error) {
    fuzz::require_names(error, source);
    return 0;
  }
  fuzz::check_scene_model(model);
  return 0;
}
