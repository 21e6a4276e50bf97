// Fuzz target: apply_registration_config, the YAML configuration reader behind --config. A file it
// accepts must leave valid options behind (unit up axes, ascending non-negative thresholds, a valid
// dense search) that registration_config_yaml writes and the reader reads back to the same text.
#include "estimation/registration_config.h"
#include "estimation/dense_search.h"
#include "tests/fuzz/fuzz_support.h"

#include <cmath>

namespace {

// Traps unless the options a configuration produced are usable.
void check_options(const quadrix::RegistrationOptions& options) {
  using quadrix::fuzz::require;
  for (const quadrix::ExtractionOptions* side : {&options.source_extraction, &options.target_extraction}) {
    require(side->up.allFinite());
    require(std::abs(side->up.norm() - 1.0) <= 1e-9);
  }
  const std::vector<double>& thresholds = options.graphs.thresholds;
  require(!thresholds.empty());
  for (std::size_t i = 0; i < thresholds.size(); ++i)
    require(thresholds[i] >= 0.0 && (i == 0 || thresholds[i] > thresholds[i - 1]));
  try {
    quadrix::validate_dense_search_options(options.dense_search);
  } catch (const quadrix::Error& error) {
    quadrix::fuzz::fail(std::string("an accepted configuration has invalid dense_search options: ") + error.what());
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace quadrix;
  static const fuzz::InputFile file("registration_config", ".yaml");
  static const fuzz::InputFile written("registration_config-written", ".yaml");
  const std::string& path = file.write(data, size);
  RegistrationOptions options;
  try {
    apply_registration_config(path, options);
  } catch (const Error& error) {
    fuzz::require_names(error, path);
    return 0;
  }
  check_options(options);
  for (const char* side : {"source", "target"}) {
    const std::string yaml = registration_config_yaml(options, side);
    written.write(reinterpret_cast<const std::uint8_t*>(yaml.data()), yaml.size());
    RegistrationOptions reread;
    try {
      apply_registration_config(written.path(), reread, side);
    } catch (const Error& error) {
      fuzz::fail("the written configuration does not read back: " + std::string(error.what()) + "\n" + yaml);
    }
    fuzz::require(registration_config_yaml(reread, side) == yaml);
  }
  return 0;
}
