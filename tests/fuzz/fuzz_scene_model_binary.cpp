// Fuzz target: scene_model_from_binary (the .qsm model format). Every input is parsed as it is and
// once more with its last four bytes replaced by the FNV-1a checksum of the others, so mutations
// get past the checksum to the records, descriptors and timings behind it.
#include "tests/fuzz/fuzz_scene_model_checks.h"

namespace {

// FNV-1a of `size` bytes, as the format stores it (see kSceneModelBinaryVersion).
std::uint32_t fnv1a(const char* data, std::size_t size) {
  std::uint32_t hash = 2166136261u;
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= static_cast<std::uint8_t>(data[i]);
    hash *= 16777619u;
  }
  return hash;
}

// Parses `bytes`; an accepted model must pass check_scene_model, a refused one name its source.
void parse(const std::string& bytes) {
  using namespace quadrix;
  const std::string source = "fuzz-model.qsm";
  SceneModel model;
  try {
    model = scene_model_from_binary(bytes, source);
  } catch (const Error& error) {
    fuzz::require_names(error, source);
    return;
  }
  fuzz::check_scene_model(model);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string bytes(reinterpret_cast<const char*>(data), size);
  parse(bytes);
  if (bytes.size() < 4) return 0;
  const std::uint32_t checksum = fnv1a(bytes.data(), bytes.size() - 4);
  for (std::size_t i = 0; i < 4; ++i) bytes[bytes.size() - 4 + i] = static_cast<char>((checksum >> (8 * i)) & 0xFFu);
  if (bytes.compare(0, std::string::npos, reinterpret_cast<const char*>(data), size) != 0) parse(bytes);
  return 0;
}
