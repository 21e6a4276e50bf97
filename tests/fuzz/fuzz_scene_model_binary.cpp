// Fuzz target: scene_model_from_binary (the .qsm model format). Every input is parsed as it is and
// once more with its last four bytes replaced by the FNV-1a checksum of the others, so mutations
// get past the checksum to the records, descriptors and timings behind it.
#include "tests/fuzz/fuzz_scene_model_checks.h"

namespace {

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
  const std::uint32_t checksum = quadrix::scene_model_binary_checksum(bytes.data(), bytes.size() - 4);
  for (std::size_t i = 0; i < 4; ++i) bytes[bytes.size() - 4 + i] = static_cast<char>((checksum >> (8 * i)) & 0xFFu);
  if (bytes.compare(0, std::string::npos, reinterpret_cast<const char*>(data), size) != 0) parse(bytes);
  return 0;
}
