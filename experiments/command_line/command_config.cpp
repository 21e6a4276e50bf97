// `quadrix config [CLOUD] [--preset P|auto] [--config FILE.yaml] [--schema]`: prints the
// effective registration parameters as YAML (every key of registration_config_keys), so a user
// sees exactly what a preset, `auto` on their cloud, and their overrides amount to, and can save,
// edit and pass the result back with `quadrix register --config`; --schema prints the keys with
// their types and descriptions instead.
#include "experiments/command_line/command_registry.h"
#include "estimation/registration_config.h"
#include "geometry/error.h"
#include "geometry/io.h"
#include "geometry/las.h"

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

namespace quadrix::cli {
namespace {

struct ConfigCommandOptions {
  std::string cloud;            ///< cloud the auto preset measures (without it: the defaults auto starts from)
  std::string preset = "auto";  ///< preset name or auto
  std::string config;           ///< YAML overrides applied after the preset
  bool schema = false;          ///< print registration_config_schema instead of a configuration
};

void run(const ConfigCommandOptions& options) {
  if (options.schema) {
    std::printf("%s", registration_config_schema().c_str());
    return;
  }
  if (!options.config.empty() && !std::filesystem::exists(options.config))
    throw file_error(options.config, "configuration file does not exist");
  // auto without a cloud: auto chooses per cloud, so the defaults shown are those it starts from
  // (the library's choice for a cloud with nothing to measure), with the rule it applies.
  const bool auto_without_cloud = options.preset == "auto" && options.cloud.empty();
  // As `quadrix model` reads one cloud: relative to a local origin, and in metres (a LAS file in feet
  // is scaled), so auto measures what model and register measure.
  PointCloud cloud;
  CoordinateUnits units;
  if (!options.cloud.empty()) {
    units = coordinate_units(options.cloud);
    CloudReadOptions read_options;
    read_options.local_origin = LocalOrigin::Auto;
    cloud = read_point_cloud(options.cloud, read_options);
    if (units.metres_per_unit != 1.0) cloud.positions *= static_cast<float>(units.metres_per_unit);
  }
  std::string notes;
  RegistrationOptions registration = auto_without_cloud
                                         ? registration_preset(guess_sensor_preset(PointCloud{}).preset)
                                         : resolve_registration_options(options.preset, cloud, options.preset, cloud, &notes);
  if (!options.config.empty()) apply_registration_config(options.config, registration);
  if (auto_without_cloud) {
    std::printf("# quadrix config: preset auto (the default of register, model and Python) chooses per cloud:\n"
                "#   x-y extent covered evenly (>= 55%% of cells) and flat (z span <= 0.35 of it) -> airborne;\n"
                "#   narrow azimuth coverage (< 50%%) -> avia; more than 1.5 M points -> monument;\n"
                "#   elevation span < 35 deg -> vlp64 (>= 60 k points or >= 48 rings) or vlp16; else mid360;\n"
                "#   it also levels the extraction on the measured up axis and crops a platform's own body.\n"
                "# Without CLOUD these are the defaults it starts from (preset %s);\n"
                "# `quadrix config CLOUD` shows what auto picks for CLOUD.\n",
                registration.source_extraction.preset.c_str());
  } else {
    std::printf("# quadrix config: preset %s%s%s%s\n", options.preset == "auto" ? "auto -> " : "",
                registration.source_extraction.preset.c_str(), options.cloud.empty() ? "" : " for ", options.cloud.c_str());
  }
  if (units.metres_per_unit != 1.0)
    std::printf("# %s is in %s (%.10g m, declared by its %s): measured in metres; every length below is metres\n",
                options.cloud.c_str(), units.name.c_str(), units.metres_per_unit, units.source.c_str());
  if (!notes.empty()) std::printf("# %s\n", notes.c_str());
  std::printf("%s", registration_config_yaml(registration).c_str());
}

const CommandRegistration registration(55, [](CLI::App& app) {
  auto options = std::make_shared<ConfigCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "config", "Print the effective registration parameters as YAML (a preset, or auto measured on CLOUD, plus --config)");
  command->add_option("cloud", options->cloud, "Point cloud the auto preset measures (any supported format)");
  std::string presets;
  for (const auto& name : registration_preset_names()) presets += name + "|";
  command->add_option("--preset", options->preset, "Sensor preset: " + presets + "auto")->capture_default_str();
  command->add_option("--config", options->config, "YAML overrides applied after the preset");
  command->add_flag("--schema", options->schema, "Print every configuration key with its type and description");
  command->callback([options] { run(*options); });
});

}  // namespace
}  // namespace quadrix::cli
