// `quadrix compare-refiners`: the refiner study (experiments/studies/refiner_study.h). Writes refiners.csv,
// refiners.md and refiners.svg into --out. The committed report is produced from the repository root by
//   make study-refiners   (build/bin/quadrix compare-refiners --out papers/studies)
#include "estimation/refiner.h"
#include "geometry/output_paths.h"
#include "experiments/command_line/command_registry.h"
#include "experiments/studies/refiner_study.h"
#include "geometry/error.h"

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

namespace quadrix::cli {
namespace {

struct CompareRefinersCommandOptions {
  std::vector<std::string> scenes;     ///< synthetic scene names; empty = the study's defaults
  std::vector<std::string> backends;   ///< refiner names; empty = all registered
  std::vector<std::string> losses;     ///< robust loss names; empty = none, huber, cauchy, dcs
  std::vector<double> outliers;        ///< wrong-correspondence shares; empty = defaults
  std::vector<double> noise;           ///< centre noise sigmas in metres; empty = defaults
  int trials = RefinerStudyOptions{}.trials;     ///< starts per cell / real correspondence set
  int threads = RefinerStudyOptions{}.threads;   ///< worker threads
  std::size_t real_pairs = 0;          ///< at most this many KITTI loop closures (0 = all)
  bool no_real = false;                ///< skip the real pairs
  std::string data;                    ///< data folder; default $QUADRIX_DATA_DIR or ../shared/data
  std::string out = "refiner_study";   ///< output folder
};

const CommandRegistration registration(46, [](CLI::App& app) {
  auto options = std::make_shared<CompareRefinersCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "compare-refiners",
      "Refine perturbed poses with every refiner backend x algorithm x robust loss on synthetic monument/street models "
      "and real KITTI loop closures; write refiners.csv, refiners.md and refiners.svg");
  command->group(kResearchCommands);
  command->add_option("--scenes", options->scenes, "Synthetic scenes (default: monument,street)")->delimiter(',');
  std::string names;
  for (const auto& name : refiner_names()) names += (names.empty() ? "" : ", ") + name;
  command->add_option("--backends", options->backends, "Refiner backends (default: all registered: " + names + ")")->delimiter(',');
  command->add_option("--losses", options->losses, "Robust losses (default: none,huber,cauchy,dcs)")->delimiter(',');
  command->add_option("--outlier-fractions", options->outliers, "Shares of wrong synthetic correspondences in [0,1) (default: 0,0.1,0.25,0.5)")
      ->delimiter(',');
  command->add_option("--noise", options->noise,
                      "Synthetic centre noise sigmas in metres; axes get 25 deg and scales 2.5 (relative) per metre of it "
                      "(default: 0,0.02 = noise-free and 2 cm / 0.5 deg / 5%)")
      ->delimiter(',');
  command->add_option("--trials", options->trials, "Perturbed starts per synthetic cell and per real correspondence set")->capture_default_str();
  command->add_option("--threads", options->threads, "Worker threads (times include contention above 1)")->capture_default_str();
  command->add_option("--real-pairs", options->real_pairs, "At most this many KITTI loop-closure pairs (0 = all)")->capture_default_str();
  command->add_flag("--no-real", options->no_real, "Skip the real KITTI pairs");
  command->add_option("--data", options->data, "Real data folder holding pairs.tsv (default: $QUADRIX_DATA_DIR, else ../shared/data)");
  command->add_option("--out", options->out, "Output folder for refiners.csv, refiners.md, refiners.svg")->capture_default_str();
  command->callback([options, command] {
    RefinerStudyOptions study;
    if (!options->scenes.empty()) study.scenes = options->scenes;
    study.backends = options->backends;
    if (!options->losses.empty()) {
      study.losses.clear();
      for (const auto& name : options->losses) study.losses.push_back(robust_loss_from_name(name));
    }
    if (!options->outliers.empty()) study.outlier_fractions = options->outliers;
    if (!options->noise.empty()) {
      study.noise_levels.clear();
      for (const double sigma : options->noise) study.noise_levels.push_back({sigma, 25.0 * sigma, 2.5 * sigma});
    }
    study.trials = options->trials;
    study.threads = options->threads;
    study.max_real_pairs = options->real_pairs;
    study.real_data = !options->no_real;
    if (!options->data.empty()) study.data_root = options->data;
    else if (const char* environment = std::getenv("QUADRIX_DATA_DIR")) study.data_root = environment;
    // The output folder is checked before the study and replaced at once after it.
    FolderReplacement output("--out", options->out, {"refiners.csv", "refiners.md", "refiners.svg"}, {study.data_root},
                             FolderSharing::OwnFilesOnly);  // papers/studies holds other studies too

    const bool terminal = isatty(fileno(stderr)) != 0;
    const auto start = std::chrono::steady_clock::now();
    const RefinerStudyProgress progress = [&](std::size_t done, std::size_t total) {
      if (!terminal || (done % 100 != 0 && done != total)) return;
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      std::fprintf(stderr, "\rcompare-refiners: %zu/%zu refinements, %.0f s   ", done, total, elapsed);
      if (done == total) std::fprintf(stderr, "\n");
    };
    const RefinerStudyResult result = run_refiner_study(study, progress);
    const std::filesystem::path folder(output.staging_folder());

    // The command line as a user would retype it: every option given, in declaration order.
    std::string command_line = "quadrix compare-refiners";
    for (const CLI::Option* option : command->get_options()) {
      if (option->count() == 0 || option->get_name() == "--help") continue;
      command_line += " " + option->get_name();
      std::string values;
      for (const auto& value : option->results()) values += (values.empty() ? "" : ",") + value;
      if (option->get_expected_max() != 0) command_line += " " + values;  // a flag's name is the whole option
    }
    write_refiner_study_csv((folder / "refiners.csv").string(), result);
    write_refiner_study_markdown((folder / "refiners.md").string(), result, study, command_line);
    write_refiner_study_svg((folder / "refiners.svg").string(), result);
    output.commit();
    std::cout << "compare-refiners: " << result.rows.size() << " refinements in " << result.seconds << " s; wrote "
              << (std::filesystem::path(options->out) / "refiners.md").string() << ", refiners.csv, refiners.svg" << std::endl;
  });
});

}  // namespace
}  // namespace quadrix::cli
