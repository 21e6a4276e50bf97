// `quadrix view INPUT --out page.html [--points N]`: the interactive 3-D page (DESIGN.md §7) of a
// `quadrix register --out` folder (registration page), a `quadrix model` JSON file or a
// `quadrix synth` folder (model pages), or the map page of a `quadrix map --out` folder (map_page.h). One self-contained HTML file: three.js from Debian's
// libjs-three and the data are inlined, so it opens from disk without a network.
#include "geometry/output_paths.h"
#include "experiments/command_line/command_registry.h"
#include "experiments/reports/interactive_page.h"
#include "experiments/reports/map_page.h"
#include "geometry/error.h"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

namespace quadrix::cli {
namespace {

struct ViewCommandOptions {
  std::string input;                 ///< register folder, model JSON or synth folder
  std::string out;                   ///< HTML page to write
  std::size_t point_budget = 400000; ///< most points written into the page
};

// The page of `options.input` and what kind it is.
std::string page_of(const ViewCommandOptions& options, std::string& kind) {
  const std::filesystem::path input(options.input);
  std::string html;
  if (is_map_folder(options.input)) {  // before the registration branch: a map folder has a report.json too
    html = map_page_html(read_map_folder(options.input, options.point_budget));
    kind = "map";
  } else if (std::filesystem::is_directory(input) && std::filesystem::exists(input / "report.json")) {
    RegistrationPageInput page = read_registration_folder(options.input);
    page.point_budget = options.point_budget;
    html = registration_page_html(page);
    kind = "registration";
  } else if (std::filesystem::is_directory(input) && std::filesystem::exists(input / "scene.json")) {
    ModelPageInput page = read_synthetic_folder_page(options.input);
    page.point_budget = options.point_budget;
    html = model_page_html(page);
    kind = "synthetic scene";
  } else if (std::filesystem::is_regular_file(input) && input.extension() == ".json") {
    ModelPageInput page = read_model_json_page(options.input);
    page.point_budget = options.point_budget;
    html = model_page_html(page);
    kind = "model";
  } else {
    throw file_error(options.input,
                     "expected a `quadrix register --out` folder (report.json), a `quadrix synth` folder (scene.json), "
                     "a map folder (poses.tsv and edges.csv) or a `quadrix model` JSON file");
  }
  return html;
}

void run(const ViewCommandOptions& options) {
  // The page never replaces what it shows: the input file, or a data file of the input folder.
  std::vector<std::string> inputs{options.input};
  std::error_code code;
  if (std::filesystem::is_directory(options.input, code))
    for (const std::filesystem::directory_entry& entry : std::filesystem::directory_iterator(options.input, code))
      if (entry.path().extension() != ".html") inputs.push_back(entry.path().string());
  check_outputs({{"--out", options.out}}, inputs);
  std::string kind;
  std::string html;
  try {
    html = page_of(options, kind);
  } catch (const nlohmann::json::exception& error) {
    // A file of the wrong shape (a string where a number belongs) is bad input, not a fault.
    throw file_error(options.input, std::string("a JSON file holds a value of the wrong type or form: ") + error.what());
  }
  write_page(options.out, html);
  std::printf("wrote %s (%s page, %.1f MB)\n", options.out.c_str(), kind.c_str(), static_cast<double>(html.size()) / 1e6);
}

const CommandRegistration registration(65, [](CLI::App& app) {
  auto options = std::make_shared<ViewCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "view", "Write an interactive 3-D page (one self-contained HTML file) of a registration, a model or a synthetic scene");
  command->add_option("input", options->input,
                      "A `quadrix register --out` folder, a `quadrix model` JSON file, a `quadrix synth` folder or a map folder")
      ->required();
  command->add_option("--out", options->out, "HTML page to write")->required();
  command->add_option("--points", options->point_budget, "Most points written into the page (subsampled evenly)")
      ->capture_default_str()
      ->check(CLI::Range(std::size_t{1}, std::size_t{5000000}));
  command->callback([options] { run(*options); });
});

}  // namespace
}  // namespace quadrix::cli
