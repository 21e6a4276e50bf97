// `quadrix compare-fitters`: the fitter study (experiments/studies/fitter_study.h). Writes fitters.csv,
// fitters.md and fitters.svg into --out. The committed report is produced from the repository root by
//   build/bin/quadrix compare-fitters --out papers/studies
#include "geometry/output_paths.h"
#include "experiments/command_line/command_registry.h"
#include "experiments/studies/fitter_study.h"
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

struct CompareFittersCommandOptions {
  std::vector<std::string> types;   ///< type names; empty = the study's defaults
  std::vector<double> noise;        ///< metres; empty = defaults
  std::vector<double> partiality;   ///< visible fractions; empty = defaults
  std::vector<double> outliers;     ///< outlier fractions; empty = defaults
  std::vector<std::string> fitters; ///< registry names; empty = all registered
  int trials = FitterStudyOptions{}.trials;                  ///< segments per grid cell
  int points = FitterStudyOptions{}.points_per_segment;      ///< points per synthetic segment
  int threads = FitterStudyOptions{}.threads;                ///< worker threads
  bool no_auto = false;             ///< skip the fits without a hint
  bool no_real = false;             ///< skip the real segments
  bool no_scans = false;            ///< skip the held-apart simulated scan segments
  std::string data;                 ///< data folder; default $QUADRIX_DATA_DIR or ../shared/data
  std::string out = "fitter_study"; ///< output folder
};

const CommandRegistration registration(45, [](CLI::App& app) {
  auto options = std::make_shared<CompareFittersCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "compare-fitters",
      "Run every quadric fitter on synthetic segments (type x noise x visible fraction x outliers), held-apart segments "
      "cut from simulated scans and real segments; "
      "write fitters.csv, fitters.md and fitters.svg");
  command->group(kResearchCommands);
  command->add_option("--types", options->types, "Synthetic types (default: plane line sphere ellipsoid cylinder elliptic_cylinder cone)")
      ->delimiter(',');
  command->add_option("--noise", options->noise, "Gaussian noise sigmas in metres (default: 0,0.01,0.02,0.05)")->delimiter(',');
  command->add_option("--partiality", options->partiality, "Visible fractions in (0,1] (default: 0.1,0.25,0.5,1)")->delimiter(',');
  command->add_option("--outliers", options->outliers, "Outlier fractions in [0,1) (default: 0,0.1,0.3)")->delimiter(',');
  std::string names;
  for (const auto& name : quadric_fitter_names()) names += (names.empty() ? "" : ", ") + name;
  command->add_option("--fitters", options->fitters, "Fitters to compare (default: all registered: " + names + ")")->delimiter(',');
  command->add_option("--trials", options->trials, "Segments per grid cell")->capture_default_str();
  command->add_option("--points", options->points, "Points per synthetic segment")->capture_default_str();
  command->add_option("--threads", options->threads, "Worker threads")->capture_default_str();
  command->add_flag("--no-auto", options->no_auto, "Skip the fits without a type hint (type accuracy)");
  command->add_flag("--no-real", options->no_real, "Skip the real segments from the data folder");
  command->add_flag("--no-scans", options->no_scans, "Skip the held-apart segments cut from simulated scans");
  command->add_option("--data", options->data, "Real data folder (default: $QUADRIX_DATA_DIR, else ../shared/data)");
  command->add_option("--out", options->out, "Output folder for fitters.csv, fitters.md, fitters.svg")->capture_default_str();
  command->callback([options, command] {
    FitterStudyOptions study;
    if (!options->types.empty()) {
      study.types.clear();
      for (const auto& name : options->types) {
        const FitTypeHint type = fit_type_hint_from_name(name);
        if (!type) throw Error("--types: 'auto' is not a type to generate");
        study.types.push_back(*type);
      }
    }
    if (!options->noise.empty()) study.noise_levels = options->noise;
    if (!options->partiality.empty()) study.visible_fractions = options->partiality;
    if (!options->outliers.empty()) study.outlier_fractions = options->outliers;
    study.fitters = options->fitters;
    study.trials = options->trials;
    study.points_per_segment = options->points;
    study.threads = options->threads;
    study.automatic_type = !options->no_auto;
    study.real_data = !options->no_real;
    study.scan_segments = !options->no_scans;
    if (!options->data.empty()) study.data_root = options->data;
    else if (const char* environment = std::getenv("QUADRIX_DATA_DIR")) study.data_root = environment;

    // The output folder is checked before the study and replaced at once after it.
    FolderReplacement output("--out", options->out, {"fitters.csv", "fitters.md", "fitters.svg"}, {study.data_root},
                             FolderSharing::OwnFilesOnly);  // papers/studies holds other studies too
    const bool terminal = isatty(fileno(stderr)) != 0;
    const auto start = std::chrono::steady_clock::now();
    const StudyProgress progress = [&](std::size_t done, std::size_t total) {
      if (!terminal || (done % 50 != 0 && done != total)) return;
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      const double rate = elapsed > 0.0 ? static_cast<double>(done) / elapsed : 0.0;
      const double left = rate > 0.0 ? static_cast<double>(total - done) / rate : 0.0;
      std::fprintf(stderr, "\rcompare-fitters: %zu/%zu fits, %.0f fits/s, %.0f s left   ", done, total, rate, left);
      if (done == total) std::fprintf(stderr, "\n");
    };
    const FitterStudyResult result = run_fitter_study(study, progress);

    const std::filesystem::path folder(output.staging_folder());
    // The command line as a user would retype it (only the options given).
    std::string command_line = "quadrix compare-fitters";
    for (const CLI::Option* option : command->get_options()) {
      if (option->count() == 0 || option->get_name() == "--help") continue;
      command_line += " " + option->get_name();
      if (option->get_type_size() == 0) continue;  // a flag: its name is the whole option
      for (const auto& value : option->results()) command_line += " " + value;
    }
    write_fitter_study_csv((folder / "fitters.csv").string(), result);
    write_fitter_study_markdown((folder / "fitters.md").string(), result, study, command_line);
    write_fitter_study_svg((folder / "fitters.svg").string(), result);
    output.commit();
    std::cout << "compare-fitters: " << result.rows.size() << " fits in " << result.seconds << " s; wrote "
              << (std::filesystem::path(options->out) / "fitters.md").string() << ", fitters.csv, fitters.svg" << std::endl;
  });
});

}  // namespace
}  // namespace quadrix::cli
