// papers/quadricsreg/README.md: our benchmark results beside the paper's transcribed tables (see bench_paper.h).
#include "experiments/benchmark/bench_paper.h"

#include "experiments/benchmark/benchmark_runner.h"
#include "geometry/error.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

namespace quadrix {
namespace {

namespace fs = std::filesystem;

// Our method names beside the paper's (same algorithm family; parameters differ, see README).
const std::map<std::string, std::string>& paper_method_names() {
  static const std::map<std::string, std::string> names{{"quadrix", "QuadricsReg"}, {"open3d-ransac", "RANSAC"}};
  return names;
}

std::string percent(double fraction) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f", 100.0 * fraction);
  return text;
}

std::string fixed(double value, const char* pattern) {
  char text[32];
  std::snprintf(text, sizeof(text), pattern, value);
  return text;
}

std::string relative_link(const fs::path& target, const std::string& page_folder) {
  return fs::relative(fs::absolute(target), fs::absolute(page_folder)).generic_string();
}

struct LoadedRun {
  std::string name;
  BenchRunInfo info;
  std::vector<MethodSummary> summaries;
};

int column(const CsvTable& table, const std::string& name) {
  const auto found = std::find(table.header.begin(), table.header.end(), name);
  return found == table.header.end() ? -1 : static_cast<int>(found - table.header.begin());
}

bool has_columns(const CsvTable& table, const std::vector<std::string>& names) {
  return std::all_of(names.begin(), names.end(), [&](const std::string& name) { return column(table, name) >= 0; });
}

const MethodSummary* find_method(const LoadedRun* run, const std::string& method) {
  if (!run) return nullptr;
  for (const MethodSummary& summary : run->summaries)
    if (summary.method == method) return &summary;
  return nullptr;
}

std::string success_cell(const MethodSummary* summary) {
  if (!summary || summary->with_ground_truth == 0) return "-";
  return percent(summary->success_rate()) + " (" + std::to_string(summary->successes) + "/" +
         std::to_string(summary->with_ground_truth) + ")";
}

std::string markdown_table(const CsvTable& table) {
  std::ostringstream md;
  md << "|";
  for (const std::string& name : table.header) md << " " << name << " |";
  md << "\n|";
  for (std::size_t c = 0; c < table.header.size(); ++c) md << "---|";
  md << "\n";
  for (const auto& row : table.rows) {
    md << "|";
    for (const std::string& cell : row) md << " " << cell << " |";
    md << "\n";
  }
  return md.str();
}

}  // namespace

CsvTable read_csv_table(const std::string& path) {
  std::ifstream file(path);
  if (!file) throw file_error(path, "cannot open the table");
  CsvTable table;
  table.name = fs::path(path).stem().string();
  std::string line;
  std::size_t line_number = 0;
  while (std::getline(file, line)) {
    ++line_number;
    if (line.empty() || line == "\r") continue;
    std::vector<std::string> fields = parse_csv_fields(line);
    if (table.header.empty()) {
      table.header = std::move(fields);
      continue;
    }
    if (fields.size() != table.header.size())
      throw Error(path + ":" + std::to_string(line_number) + ": " + std::to_string(fields.size()) + " fields, expected " +
                  std::to_string(table.header.size()) + " (as many as the header)");
    table.rows.push_back(std::move(fields));
  }
  if (table.header.empty()) throw file_error(path, "empty table (expected a header line)");
  return table;
}

namespace {

// The benchmark runs of the results folder: ablation runs by ablation name, the others in folder order.
struct LoadedRuns {
  std::vector<LoadedRun> runs;
  std::map<std::string, LoadedRun> ablations;  // ablation name -> run
};

// Loads every run folder (one with a run.json) of `results_folder`, sorted by name; none when it does not exist.
LoadedRuns load_runs(const std::string& results_folder) {
  LoadedRuns loaded;
  if (!fs::is_directory(results_folder)) return loaded;
  std::vector<fs::path> folders;
  for (const auto& entry : fs::directory_iterator(results_folder))
    if (entry.is_directory() && fs::exists(entry.path() / "run.json")) folders.push_back(entry.path());
  std::sort(folders.begin(), folders.end());
  for (const fs::path& folder : folders) {
    LoadedRun run;
    run.name = folder.filename().string();
    run.info = read_bench_run_info(folder.string());
    run.summaries = summarize_bench(read_bench_rows_csv((folder / "pairs.csv").string()), run.info.methods);
    if (run.name.rfind("ablation-", 0) == 0)
      loaded.ablations[run.name.substr(9)] = std::move(run);
    else
      loaded.runs.push_back(std::move(run));
  }
  return loaded;
}

// Loads every .csv table of `tables_folder`, sorted by name; none when it does not exist.
std::vector<CsvTable> load_tables(const std::string& tables_folder) {
  std::vector<CsvTable> tables;
  if (!fs::is_directory(tables_folder)) return tables;
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(tables_folder))
    if (entry.path().extension() == ".csv") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  for (const fs::path& file : files) tables.push_back(read_csv_table(file.string()));
  return tables;
}

// Writes the title and what the page holds, where it comes from and how success is counted.
void write_introduction(std::ostream& md) {
  md << "# QuadricsReg: our numbers beside the paper's\n\n"
     << "Generated by `make papers` (`quadrix paper`); do not edit by hand. The benchmark runs are in `results/` "
        "(one folder per run: `pairs.csv` per pair and method, `summary.md`, SVG plots, `run.json` with the exact "
        "options). The paper's tables are transcribed in `tables/`; `equations.md` maps each equation to its code.\n\n"
     << "Times are wall-clock on a 2-core shared, loaded machine, from both clouds in memory to the transform.\n"
        "Success means RTE <= 2 m and RRE <= 5 deg. Pairs without ground truth are listed but never counted.\n\n";
}

// Writes one run: its options, a row per method, and links to its summary and plots.
void write_run(std::ostream& md, const LoadedRun& run, const std::string& results_folder, const std::string& page_folder) {
  md << "### " << run.info.title << " (`results/" << run.name << "`)\n\n";
  md << "Options: `" << run.info.options_text << "`\n\n";
  md << "| method | success | no GT | median RTE m | median RRE deg | IR % | CR % | median ms | p90 ms | time / Quadrix | median model bytes/frame |\n"
     << "|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const MethodSummary& s : run.summaries)
    md << "| " << s.method << " | " << success_cell(&s) << " | " << s.without_ground_truth << " | "
       << (s.successes ? fixed(s.median_rte, "%.3f") : "-") << " | " << (s.successes ? fixed(s.median_rre, "%.3f") : "-")
       << " | " << (s.mean_inlier_ratio >= 0.0 ? percent(s.mean_inlier_ratio) : "-") << " | "
       << (s.correspondence_recall >= 0.0 ? percent(s.correspondence_recall) : "-") << " | "
       << fixed(s.median_total_ms, "%.0f") << " | " << fixed(s.p90_total_ms, "%.0f") << " | "
       << (s.time_ratio_to_quadrix > 0.0 ? fixed(s.time_ratio_to_quadrix, "%.2f") : "-") << " | "
       << (s.median_model_bytes >= 0.0 ? fixed(s.median_model_bytes, "%.0f") : "-") << " |\n";
  // Success per bin (when the run has several), each status against the truth, and where Quadrix's
  // true correspondences are lost.
  const bool several_bins = std::any_of(run.summaries.begin(), run.summaries.end(),
                                        [](const MethodSummary& s) { return s.by_difficulty.size() > 1; });
  if (several_bins) md << bench_success_by_difficulty_markdown(run.summaries, "####");
  md << bench_status_outcomes_markdown(run.summaries, "####") << bench_true_correspondence_stages_markdown(run.summaries, "####");
  const fs::path folder = fs::path(results_folder) / run.name;
  md << "\nPer pair, per difficulty and per stage: [summary.md](" << relative_link(folder / "summary.md", page_folder) << ").\n\n";
  for (const char* plot : {"success_by_difficulty.svg", "error_cdf.svg", "time_per_stage.svg"})
    md << "![" << plot << "](" << relative_link(folder / plot, page_folder) << ")\n";
  md << "\n";
}

// Writes the "Our runs" section: every run, or a note that there are none yet.
void write_our_runs(std::ostream& md, const std::vector<LoadedRun>& runs, const std::string& results_folder,
                    const std::string& page_folder) {
  md << "## Our runs\n\n";
  for (const LoadedRun& run : runs) write_run(md, run, results_folder, page_folder);
  if (runs.empty()) md << "No results yet: run `make papers`.\n\n";
}

// Writes the paper's KITTI-LC 00 easy success rates beside our loop-closure run's, then our methods the paper lacks.
void write_loop_closure_success(std::ostream& md, const CsvTable& table, const LoadedRun* loop_closure) {
  md << "### Loop-closure success rate (paper table `loop_closure_success.csv`)\n\n"
     << "| method (paper) | paper SR % | our method | our SR % |\n|---|---|---|---|\n";
  std::map<std::string, std::string> ours_by_paper_name;
  for (const auto& entry : paper_method_names()) ours_by_paper_name[entry.second] = entry.first;
  for (const auto& row : table.rows) {
    if (row[column(table, "dataset")] != "KITTI-LC" || row[column(table, "sequence")] != "00" ||
        row[column(table, "level")] != "easy")
      continue;
    const std::string& method = row[column(table, "method")];
    const auto ours = ours_by_paper_name.find(method);
    md << "| " << method << " | " << row[column(table, "success_rate_percent")] << " | "
       << (ours == ours_by_paper_name.end() ? "-" : ours->second) << " | "
       << (ours == ours_by_paper_name.end() ? "-" : success_cell(find_method(loop_closure, ours->second))) << " |\n";
  }
  if (loop_closure)
    for (const MethodSummary& s : loop_closure->summaries)
      if (!paper_method_names().count(s.method)) md << "| - | - | " << s.method << " | " << success_cell(&s) << " |\n";
  md << "\n";
}

// Writes the paper's easy-level correspondence numbers with ours from the loop-closure run below them.
void write_correspondence_evaluation(std::ostream& md, const CsvTable& table, const LoadedRun* loop_closure) {
  md << "### Correspondences (paper table `correspondence_evaluation.csv`, easy level)\n\n"
     << "| method | Num. | IR % | CR % | SR % |\n|---|---|---|---|---|\n";
  for (const auto& row : table.rows)
    if (row[column(table, "level")] == "easy")
      md << "| " << row[column(table, "method")] << " (paper) | " << row[column(table, "correspondences")] << " | "
         << row[column(table, "inlier_ratio_percent")] << " | " << row[column(table, "correspondence_recall_percent")]
         << " | " << row[column(table, "success_rate_percent")] << " |\n";
  if (const MethodSummary* s = find_method(loop_closure, "quadrix"))
    md << "| quadrix (ours, K_s = 20) | " << (s->mean_correspondences >= 0.0 ? fixed(s->mean_correspondences, "%.1f") : "-")
       << " | " << (s->mean_inlier_ratio >= 0.0 ? fixed(100.0 * s->mean_inlier_ratio, "%.2f") : "-") << " | "
       << (s->correspondence_recall >= 0.0 ? percent(s->correspondence_recall) : "-") << " | " << success_cell(s) << " |\n";
  md << "\n";
}

// Writes each paper ablation row of sequence 00 easy beside our run of the matching `--ablation`, if any.
void write_ablation(std::ostream& md, const CsvTable& table, const std::map<std::string, LoadedRun>& ablations) {
  md << "### Ablations (paper table `ablation.csv`, sequence 00 easy)\n\n"
     << "| module | setting | paper SR % | our run | our SR % |\n|---|---|---|---|---|\n";
  std::map<std::string, std::string> ablation_by_row;
  for (const std::string& name : bench_ablation_names()) ablation_by_row[bench_ablation_paper_row(name)] = name;
  ablation_by_row[bench_ablation_paper_row("default")] = "default";
  for (const auto& row : table.rows) {
    if (row[column(table, "sequence")] != "00" || row[column(table, "level")] != "easy") continue;
    const std::string key = row[column(table, "module")] + "|" + row[column(table, "setting")];
    const auto name = ablation_by_row.find(key);
    const LoadedRun* run = nullptr;
    if (name != ablation_by_row.end()) {
      const auto found = ablations.find(name->second);
      if (found != ablations.end()) run = &found->second;
    }
    md << "| " << row[column(table, "module")] << " | " << row[column(table, "setting")] << " | "
       << row[column(table, "success_rate_percent")] << " | "
       << (name == ablation_by_row.end() ? "-" : "`--ablation " + name->second + "`") << " | "
       << success_cell(find_method(run, "quadrix")) << " |\n";
  }
  md << "\n";
  if (!ablations.empty()) {
    const LoadedRun& any = ablations.begin()->second;
    md << "Our ablation runs: `" << any.info.options_text << "` with each `--ablation` (folders `results/ablation-*`).\n\n";
  }
}

// Writes the "Beside the paper" section: each known paper table that has its columns, beside our matching run.
void write_beside_the_paper(std::ostream& md, const std::vector<CsvTable>& tables, const LoadedRuns& loaded) {
  const LoadedRun* loop_closure = nullptr;
  for (const LoadedRun& run : loaded.runs)
    if (run.name.find("kitti-lc") != std::string::npos) loop_closure = &run;
  md << "## Beside the paper (KITTI-LC sequence 00, easy level 0-10 m)\n\n"
     << "We have the frames of six real KITTI-00 loop closures (0..5 -> 4438, 5.3-8.6 m, about 38 deg), all in the "
        "paper's easy bin; the paper's numbers are over about 200 pairs of the bin, ours over those six pairs under "
        "random yaw trials, so the comparison is indicative only.\n\n";
  for (const CsvTable& table : tables) {
    if (table.name == "loop_closure_success" &&
        has_columns(table, {"dataset", "sequence", "level", "method", "success_rate_percent"}))
      write_loop_closure_success(md, table, loop_closure);
    else if (table.name == "correspondence_evaluation" &&
             has_columns(table, {"method", "level", "correspondences", "inlier_ratio_percent",
                                 "correspondence_recall_percent", "success_rate_percent"}))
      write_correspondence_evaluation(md, table, loop_closure);
    else if (table.name == "ablation" &&
             has_columns(table, {"module", "setting", "sequence", "level", "success_rate_percent"}))
      write_ablation(md, table, loaded.ablations);
  }
}

// Writes "The paper's tables": each in full, or a link to its CSV when it is longer than 40 rows.
void write_paper_tables(std::ostream& md, const std::vector<CsvTable>& tables, const std::string& tables_folder,
                        const std::string& page_folder) {
  md << "## The paper's tables\n\n";
  for (const CsvTable& table : tables) {
    const fs::path file = fs::path(tables_folder) / (table.name + ".csv");
    md << "### `" << table.name << ".csv`\n\n";
    if (table.rows.size() <= 40)
      md << markdown_table(table) << "\n";
    else
      md << table.rows.size() << " rows in long form: [" << table.name << ".csv](" << relative_link(file, page_folder) << ").\n\n";
  }
}

}  // namespace

std::string quadricsreg_paper_page(const std::string& results_folder, const std::string& tables_folder,
                                   const std::string& page_folder) {
  const LoadedRuns loaded = load_runs(results_folder);
  const std::vector<CsvTable> tables = load_tables(tables_folder);
  std::ostringstream md;
  write_introduction(md);
  write_our_runs(md, loaded.runs, results_folder, page_folder);
  write_beside_the_paper(md, tables, loaded);
  write_paper_tables(md, tables, tables_folder, page_folder);
  return md.str();
}

}  // namespace quadrix
