// `quadrix paper [--results DIR] [--tables DIR] [--out FILE]`: writes the paper page
// papers/quadricsreg/README.md from the benchmark results and the transcribed tables (bench_paper.h).
#include "experiments/benchmark/bench_paper.h"
#include "experiments/command_line/command_registry.h"
#include "geometry/io.h"

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

namespace quadrix::cli {
namespace {

struct PaperCommandOptions {
  std::string results = "papers/quadricsreg/results";  ///< folders written by `quadrix bench --out`
  std::string tables = "papers/quadricsreg/tables";    ///< the paper's tables as CSV
  std::string out = "papers/quadricsreg/README.md";    ///< the page
};

const CommandRegistration registration(75, [](CLI::App& app) {
  auto options = std::make_shared<PaperCommandOptions>();
  CLI::App* command = app.add_subcommand("paper", "Write the QuadricsReg paper page: our benchmark results beside the paper's tables");
  command->group(kResearchCommands);
  command->add_option("--results", options->results, "Folder of benchmark runs (one `quadrix bench --out` folder each)")
      ->capture_default_str();
  command->add_option("--tables", options->tables, "Folder of the paper's tables as CSV")->capture_default_str();
  command->add_option("--out", options->out, "Markdown page to write")->capture_default_str();
  command->callback([options] {
    const std::string folder = std::filesystem::path(options->out).parent_path().string();
    const std::string page = quadricsreg_paper_page(options->results, options->tables, folder.empty() ? "." : folder);
    write_file_atomically(options->out, [&](std::ostream& out) { out << page; });
    std::printf("wrote %s (%zu bytes)\n", options->out.c_str(), page.size());
  });
});

}  // namespace
}  // namespace quadrix::cli
