// Benchmark outputs: summaries from rows, pairs.csv, run.json, summary.md, SVG plots, shard merge
// (see benchmark_runner.h). Every number of a summary comes from the rows, so a merged run and a
// single run summarise identically.
#include "experiments/benchmark/benchmark_runner.h"

#include "geometry/error.h"
#include "geometry/io.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <set>
#include <sstream>

namespace quadrix {
namespace {

namespace fs = std::filesystem;

// Quantile by linear interpolation between order statistics (q in [0, 1]); 0 for no values.
double quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const double position = q * static_cast<double>(values.size() - 1);
  const std::size_t below = static_cast<std::size_t>(std::floor(position));
  const std::size_t above = std::min(below + 1, values.size() - 1);
  return values[below] + (position - static_cast<double>(below)) * (values[above] - values[below]);
}

double mean(const std::vector<double>& values) {
  if (values.empty()) return 0.0;
  double sum = 0.0;
  for (const double value : values) sum += value;
  return sum / static_cast<double>(values.size());
}

std::string format(const char* pattern, double value) {
  char text[64];
  std::snprintf(text, sizeof(text), pattern, value);
  return text;
}

std::string exact(double value) {
  char text[40];
  std::snprintf(text, sizeof(text), "%.17g", value);
  return text;
}

// CSV field: quoted when it holds a comma, a quote or a line break.
std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string quoted = "\"";
  for (const char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c == '\n' || c == '\r' ? ' ' : c);
  return quoted + "\"";
}


const std::vector<std::string>& csv_columns() {
  static const std::vector<std::string> columns{
      "task",          "pair_id",      "trial",          "method",  "difficulty",         "kind",
      "has_gt",        "status",       "success",        "rte_m",   "rre_deg",            "yaw_deg",
      "tilt_deg",      "shift_x_m",    "shift_y_m",      "seed",    "correspondences",    "inliers",
      "recalled",      "true_partners", "quadric_inliers", "best_clique_inliers", "clique_inliers", "source_model_bytes", "target_model_bytes",
      "overlap",       "identity_overlap", "timings_ms", "message"};
  return columns;
}

// Columns added after the first files were written; older files without them still read (value 0).
bool is_later_column(const std::string& name) {
  return name == "overlap" || name == "identity_overlap" || name == "tilt_deg" || name == "true_partners" ||
         name == "quadric_inliers" || name == "best_clique_inliers" || name == "clique_inliers";
}

std::string timings_text(const std::map<std::string, double>& timings) {
  std::string text;
  for (const auto& entry : timings) text += (text.empty() ? "" : ";") + entry.first + "=" + exact(entry.second);
  return text;
}

// Colour `index` of `count` series: the Tableau-like palette while it lasts, else evenly spaced
// hues alternating in lightness, so that no two series of a plot share a colour.
std::string colour(std::size_t index, std::size_t count) {
  static const char* colours[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b",
                                  "#e377c2", "#7f7f7f", "#bcbd22", "#17becf", "#393b79", "#ad494a"};
  if (count <= 12) return colours[index];
  return "hsl(" + std::to_string(static_cast<int>(360.0 * static_cast<double>(index) / static_cast<double>(count))) + ",70%," +
         (index % 2 == 0 ? "42%" : "62%") + ")";
}

// Width a line of SVG text takes at `font_size` px in a sans-serif font, generously (0.6 em a character).
int text_width(const std::string& text, int font_size) {
  return static_cast<int>(std::ceil(0.6 * font_size * static_cast<double>(text.size())));
}

// The smallest of 1, 2, 5 x 10^k at least `value` (> 0): an axis end that follows the data.
double nice_ceiling(double value) {
  const double decade = std::pow(10.0, std::floor(std::log10(value)));
  for (const double step : {1.0, 2.0, 5.0, 10.0})
    if (step * decade >= value * (1.0 - 1e-12)) return step * decade;
  return 10.0 * decade;
}

std::string escape_xml(const std::string& text) {
  std::string escaped;
  for (const char c : text) {
    if (c == '<') escaped += "&lt;";
    else if (c == '>') escaped += "&gt;";
    else if (c == '&') escaped += "&amp;";
    else escaped += c;
  }
  return escaped;
}

// Closes an SVG document after a legend of one coloured square per method at (x, top).
std::string with_method_legend(const std::string& body, const std::vector<MethodSummary>& summaries, int x, int top) {
  std::ostringstream svg;
  svg << body;
  for (std::size_t m = 0; m < summaries.size(); ++m)
    svg << "<rect x=\"" << x << "\" y=\"" << top + 18 * static_cast<int>(m) << "\" width=\"12\" height=\"12\" fill=\""
        << colour(m, summaries.size()) << "\"/><text x=\"" << x + 18 << "\" y=\"" << top + 10 + 18 * static_cast<int>(m) << "\">"
        << escape_xml(summaries[m].method) << "</text>\n";
  svg << "</svg>\n";
  return svg.str();
}

// Stage order of the time plot and table: pipeline order, then anything else alphabetically, total last.
std::vector<std::string> ordered_stages(const std::map<std::string, std::pair<double, double>>& stages) {
  static const std::vector<std::string> pipeline{"preset",    "modelling_source", "modelling_target", "correspondences",
                                                 "graphs",    "cliques",          "estimation",       "selection",
                                                 "downsample", "features",        "matching"};
  std::vector<std::string> order;
  for (const std::string& stage : pipeline)
    if (stages.count(stage)) order.push_back(stage);
  for (const auto& entry : stages)
    if (entry.first != "total" && std::find(order.begin(), order.end(), entry.first) == order.end()) order.push_back(entry.first);
  return order;
}

// Difficulties in order of first appearance over every summary.
std::vector<std::string> difficulty_order(const std::vector<BenchRow>* rows, const std::vector<MethodSummary>& summaries) {
  std::vector<std::string> order;
  if (rows)
    for (const BenchRow& row : *rows)
      if (std::find(order.begin(), order.end(), row.difficulty) == order.end()) order.push_back(row.difficulty);
  for (const MethodSummary& summary : summaries)
    for (const auto& entry : summary.by_difficulty)
      if (std::find(order.begin(), order.end(), entry.first) == order.end()) order.push_back(entry.first);
  return order;
}

}  // namespace

std::vector<std::string> parse_csv_fields(const std::string& line) {
  std::vector<std::string> fields;
  std::string field;
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        field += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        field += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      fields.push_back(field);
      field.clear();
    } else if (c != '\r') {
      field += c;
    }
  }
  fields.push_back(field);
  return fields;
}

std::vector<MethodSummary> summarize_bench(const std::vector<BenchRow>& rows, const std::vector<std::string>& methods) {
  std::vector<MethodSummary> summaries;
  for (const std::string& method : methods) {
    MethodSummary summary;
    summary.method = method;
    std::vector<double> rte;
    std::vector<double> rre;
    std::vector<double> inlier_ratios;
    std::vector<double> correspondences;
    std::vector<double> bytes;
    std::size_t recalled = 0;
    std::size_t recall_rows = 0;
    std::map<std::string, std::vector<double>> stages;
    for (const BenchRow& row : rows) {
      if (row.method != method) continue;
      ++summary.tasks;
      ++summary.statuses[row.status];
      for (const auto& entry : row.timings_ms) stages[entry.first].push_back(entry.second);
      if (row.correspondences >= 0) correspondences.push_back(static_cast<double>(row.correspondences));
      if (row.source_model_bytes >= 0) bytes.push_back(static_cast<double>(row.source_model_bytes));
      if (row.target_model_bytes >= 0) bytes.push_back(static_cast<double>(row.target_model_bytes));
      if (!row.has_ground_truth) {
        ++summary.without_ground_truth;
        continue;
      }
      ++summary.with_ground_truth;
      StatusOutcome& outcome = summary.outcomes_by_kind[row.kind.empty() ? "-" : row.kind][row.status];
      ++(row.success ? outcome.right : outcome.wrong);
      if (row.status == "ok" && !row.success) ++summary.ok_and_wrong;
      auto& bin = summary.by_difficulty[row.difficulty];
      ++bin.second;
      summary.rte_values.push_back(row.rte);
      summary.rre_values.push_back(row.rre);
      if (row.success) {
        ++summary.successes;
        ++bin.first;
        rte.push_back(row.rte);
        rre.push_back(row.rre);
      }
      if (row.true_partners >= 0) {
        TrueCorrespondenceStages& found = summary.stages_by_difficulty[row.difficulty];
        found.modelled.push_back(static_cast<double>(row.true_partners));
        found.matched.push_back(static_cast<double>(row.quadric_inliers));
        found.best_clique.push_back(static_cast<double>(row.best_clique_inliers));
        found.chosen_clique.push_back(static_cast<double>(row.clique_inliers));
      }
      if (row.recalled >= 0) {
        ++recall_rows;
        recalled += static_cast<std::size_t>(row.recalled);
        if (row.correspondences > 0 && row.inliers >= 0)
          inlier_ratios.push_back(static_cast<double>(row.inliers) / static_cast<double>(row.correspondences));
        else if (row.correspondences == 0)
          inlier_ratios.push_back(0.0);
      }
    }
    if (summary.tasks == 0) continue;
    summary.median_rte = quantile(rte, 0.5);
    summary.median_rre = quantile(rre, 0.5);
    summary.mean_rte = mean(rte);
    summary.mean_rre = mean(rre);
    if (recall_rows > 0) {
      summary.correspondence_recall = static_cast<double>(recalled) / static_cast<double>(recall_rows);
      summary.mean_inlier_ratio = mean(inlier_ratios);
    }
    if (!correspondences.empty()) summary.mean_correspondences = mean(correspondences);
    if (!bytes.empty()) summary.median_model_bytes = quantile(bytes, 0.5);
    for (const auto& entry : stages) summary.stage_ms[entry.first] = {quantile(entry.second, 0.5), quantile(entry.second, 0.9)};
    if (summary.stage_ms.count("total")) {
      summary.median_total_ms = summary.stage_ms["total"].first;
      summary.p90_total_ms = summary.stage_ms["total"].second;
    }
    summaries.push_back(std::move(summary));
  }
  const auto quadrix = std::find_if(summaries.begin(), summaries.end(), [](const MethodSummary& s) { return s.method == "quadrix"; });
  if (quadrix != summaries.end() && quadrix->median_total_ms > 0.0)
    for (MethodSummary& summary : summaries) summary.time_ratio_to_quadrix = summary.median_total_ms / quadrix->median_total_ms;
  return summaries;
}

std::string bench_summary_text(const std::vector<MethodSummary>& summaries) {
  std::ostringstream text;
  for (const MethodSummary& s : summaries) {
    text << std::left << std::setw(18) << s.method << " success ";
    if (s.with_ground_truth)
      text << s.successes << "/" << s.with_ground_truth << " (" << format("%.1f", 100.0 * s.success_rate()) << "%)";
    else
      text << "-";
    text << "  median " << format("%.0f", s.median_total_ms) << " ms (p90 " << format("%.0f", s.p90_total_ms) << ")";
    if (s.time_ratio_to_quadrix > 0.0) text << "  x" << format("%.2f", s.time_ratio_to_quadrix) << " Quadrix's time";
    if (s.without_ground_truth) text << "  no ground truth: " << s.without_ground_truth;
    if (s.with_ground_truth && s.statuses.count("ok")) text << "  ok and wrong: " << s.ok_and_wrong;
    text << "\n";
  }
  return text.str();
}

std::string bench_success_by_difficulty_markdown(const std::vector<MethodSummary>& summaries, const std::string& heading) {
  std::ostringstream md;
  const std::vector<std::string> difficulties = difficulty_order(nullptr, summaries);
  if (!difficulties.empty()) {
    md << "\n" << heading << " Success per difficulty\n\n| method |";
    for (const std::string& difficulty : difficulties) md << " " << difficulty << " |";
    md << "\n|---|";
    for (std::size_t k = 0; k < difficulties.size(); ++k) md << "---|";
    md << "\n";
    for (const MethodSummary& s : summaries) {
      md << "| " << s.method << " |";
      for (const std::string& difficulty : difficulties) {
        const auto found = s.by_difficulty.find(difficulty);
        if (found == s.by_difficulty.end() || found->second.second == 0)
          md << " - |";
        else
          md << " " << found->second.first << "/" << found->second.second << " ("
             << format("%.1f", 100.0 * double(found->second.first) / double(found->second.second)) << "%) |";
      }
      md << "\n";
    }
  }
  return md.str();
}

std::string bench_status_outcomes_markdown(const std::vector<MethodSummary>& summaries, const std::string& heading) {
  std::ostringstream md;
  md << "\n" << heading << " Status against ground truth\n\nEach status as right / wrong by the success rule, per pair kind "
        "(rows with ground truth). `ok` and wrong is the error `ok` must never make.\n\n"
        "| method | kind | status: right / wrong |\n|---|---|---|\n";
  for (const MethodSummary& s : summaries)
    for (const auto& [kind, outcomes] : s.outcomes_by_kind) {
      md << "| " << s.method << " | " << kind << " |";
      for (const auto& [status, outcome] : outcomes) md << " " << status << " " << outcome.right << " / " << outcome.wrong << ";";
      md << " |\n";
    }
  return md.str();
}

std::string bench_true_correspondence_stages_markdown(const std::vector<MethodSummary>& summaries,
                                                      const std::string& heading) {
  std::ostringstream md;
  const std::vector<std::string> difficulties = difficulty_order(nullptr, summaries);
  const bool any_stages = std::any_of(summaries.begin(), summaries.end(),
                                     [](const MethodSummary& s) { return !s.stages_by_difficulty.empty(); });
  if (any_stages) {
    md << "\n" << heading << " Where the true correspondences are lost\n\nA true correspondence pairs fitted quadrics of one class "
          "whose full centres lie within 0.5 m under the ground truth (augmented points left out). modelled: source "
          "quadrics with such a partner in the target model (all that matching could find); matched: among the "
          "putative correspondences; best clique: "
          "the most in one level's maximum clique; chosen: in the chosen candidate's clique. Medians, then the share of "
          "pairs with at least 3 (the fewest that fix a transform).\n\n"
          "| method | difficulty | pairs | modelled | matched | best clique | chosen | >= 3 modelled | >= 3 matched | "
          ">= 3 best clique | >= 3 chosen |\n|---|---|---|---|---|---|---|---|---|---|---|\n";
    const auto share_of_three = [](const std::vector<double>& counts) {
      const auto enough = std::count_if(counts.begin(), counts.end(), [](double count) { return count >= 3.0; });
      return format("%.0f%%", 100.0 * static_cast<double>(enough) / static_cast<double>(counts.size()));
    };
    for (const MethodSummary& s : summaries)
      for (const std::string& difficulty : difficulties) {
        const auto found = s.stages_by_difficulty.find(difficulty);
        if (found == s.stages_by_difficulty.end()) continue;
        const TrueCorrespondenceStages& stages = found->second;
        md << "| " << s.method << " | " << difficulty << " | " << stages.modelled.size();
        for (const auto* counts : {&stages.modelled, &stages.matched, &stages.best_clique, &stages.chosen_clique})
          md << " | " << format("%.0f", quantile(*counts, 0.5));
        for (const auto* counts : {&stages.modelled, &stages.matched, &stages.best_clique, &stages.chosen_clique})
          md << " | " << share_of_three(*counts);
        md << " |\n";
      }
  }
  return md.str();
}

std::string bench_summary_markdown(const std::vector<MethodSummary>& summaries, const std::string& title) {
  std::ostringstream md;
  md << "# " << title << "\n\n";
  md << "Success: RTE <= 2 m and RRE <= 5 deg, over rows with ground truth; rows without one are counted apart "
        "(\"no GT\"). RTE/RRE are medians over successes. IR = mean inlier ratio of the putative correspondences "
        "(0.5 m), CR = correspondence recall (>= 3 inliers). Times run from both clouds in memory to the transform "
        "(Quadrix: both modelling times included even when a model was reused).\n\n";
  md << "| method | success | no GT | RTE m | RRE deg | IR % | CR % | median ms | p90 ms | time / Quadrix | median model bytes/frame |\n";
  md << "|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const MethodSummary& s : summaries) {
    md << "| " << s.method << " | ";
    if (s.with_ground_truth)
      md << s.successes << "/" << s.with_ground_truth << " (" << format("%.1f", 100.0 * s.success_rate()) << "%)";
    else
      md << "-";
    md << " | " << s.without_ground_truth << " | " << (s.successes ? format("%.3f", s.median_rte) : "-") << " | "
       << (s.successes ? format("%.3f", s.median_rre) : "-") << " | "
       << (s.mean_inlier_ratio >= 0.0 ? format("%.2f", 100.0 * s.mean_inlier_ratio) : "-") << " | "
       << (s.correspondence_recall >= 0.0 ? format("%.1f", 100.0 * s.correspondence_recall) : "-") << " | "
       << format("%.1f", s.median_total_ms) << " | " << format("%.1f", s.p90_total_ms) << " | "
       << (s.time_ratio_to_quadrix > 0.0 ? format("%.2f", s.time_ratio_to_quadrix) : "-") << " | "
       << (s.median_model_bytes >= 0.0 ? format("%.0f", s.median_model_bytes) : "-") << " |\n";
  }
  md << bench_success_by_difficulty_markdown(summaries, "##") << bench_status_outcomes_markdown(summaries, "##")
     << bench_true_correspondence_stages_markdown(summaries, "##");
  md << "\n## Time per stage (median / p90, ms)\n\n| method | stage | median | p90 |\n|---|---|---|---|\n";
  for (const MethodSummary& s : summaries) {
    std::vector<std::string> stages = ordered_stages(s.stage_ms);
    if (s.stage_ms.count("total")) stages.push_back("total");
    for (const std::string& stage : stages)
      md << "| " << s.method << " | " << stage << " | " << format("%.2f", s.stage_ms.at(stage).first) << " | "
         << format("%.2f", s.stage_ms.at(stage).second) << " |\n";
  }
  md << "\n## Statuses\n\n| method | statuses |\n|---|---|\n";
  for (const MethodSummary& s : summaries) {
    md << "| " << s.method << " |";
    for (const auto& entry : s.statuses) md << " " << entry.first << " " << entry.second << ";";
    md << " |\n";
  }
  return md.str();
}

void write_bench_rows_csv(const std::string& path, const std::vector<BenchRow>& rows) {
  write_file_atomically(path, [&](std::ostream& out) {
    const std::vector<std::string>& columns = csv_columns();
    for (std::size_t c = 0; c < columns.size(); ++c) out << (c ? "," : "") << columns[c];
    out << "\n";
    for (const BenchRow& r : rows) {
      out << r.task << "," << csv_field(r.pair_id) << "," << r.trial << "," << csv_field(r.method) << ","
          << csv_field(r.difficulty) << "," << csv_field(r.kind) << "," << (r.has_ground_truth ? 1 : 0) << ","
          << csv_field(r.status) << "," << (r.has_ground_truth ? (r.success ? "1" : "0") : "") << ","
          << (r.has_ground_truth ? exact(r.rte) : "") << "," << (r.has_ground_truth ? exact(r.rre) : "") << ","
          << exact(r.yaw_degrees) << "," << exact(r.tilt_degrees) << "," << exact(r.shift_x) << "," << exact(r.shift_y) << "," << r.seed << ","
          << r.correspondences << "," << r.inliers << "," << r.recalled << "," << r.true_partners << ","
          << r.quadric_inliers << "," << r.best_clique_inliers << "," << r.clique_inliers << "," << r.source_model_bytes << ","
          << r.target_model_bytes << "," << exact(r.overlap) << "," << exact(r.identity_overlap) << ","
          << csv_field(timings_text(r.timings_ms)) << "," << csv_field(r.message) << "\n";
    }
  });
}

std::vector<BenchRow> read_bench_rows_csv(const std::string& path) {
  std::ifstream file(path);
  if (!file) throw file_error(path, "cannot open the benchmark rows");
  std::string line;
  std::size_t line_number = 0;
  std::vector<BenchRow> rows;
  std::vector<std::string> columns;             // the file's header
  std::map<std::string, std::size_t> index_of;  // column name -> field index in this file
  while (std::getline(file, line)) {
    ++line_number;
    const std::string where = path + ":" + std::to_string(line_number);
    const std::vector<std::string> fields = parse_csv_fields(line);
    if (line_number == 1) {
      // Columns are found by name: every current column must be there, except the later ones.
      columns = fields;
      for (std::size_t c = 0; c < fields.size(); ++c)
        if (!index_of.emplace(fields[c], c).second) throw Error(where + ": column " + fields[c] + " appears twice in the header");
      for (const std::string& name : csv_columns())
        if (!index_of.count(name) && !is_later_column(name))
          throw Error(where + ": header is not the benchmark row header (" + csv_columns().front() + ",...): no column " + name);
      continue;
    }
    if (line.empty()) continue;
    if (fields.size() != columns.size())
      throw Error(where + ": " + std::to_string(fields.size()) + " fields, expected " + std::to_string(columns.size()));
    const auto field = [&](const std::string& name) -> const std::string& { return fields[index_of.at(name)]; };
    const auto number = [&](const std::string& name, double absent) {
      if (!index_of.count(name)) return absent;
      try {
        std::size_t used = 0;
        const double value = std::stod(field(name), &used);
        if (used != field(name).size()) throw std::invalid_argument(field(name));
        return value;
      } catch (const std::exception&) {
        throw Error(where + ": column " + name + " '" + field(name) + "' is not a number");
      }
    };
    const auto integer = [&](const std::string& name) {
      try {
        std::size_t used = 0;
        const long long value = std::stoll(field(name), &used);
        if (used != field(name).size()) throw std::invalid_argument(field(name));
        return value;
      } catch (const std::exception&) {
        throw Error(where + ": column " + name + " '" + field(name) + "' is not an integer");
      }
    };
    BenchRow r;
    r.task = static_cast<std::size_t>(integer("task"));
    r.pair_id = field("pair_id");
    r.trial = static_cast<int>(integer("trial"));
    r.method = field("method");
    r.difficulty = field("difficulty");
    r.kind = field("kind");
    r.has_ground_truth = integer("has_gt") != 0;
    r.status = field("status");
    if (r.has_ground_truth) {
      r.success = integer("success") != 0;
      r.rte = number("rte_m", 0.0);
      r.rre = number("rre_deg", 0.0);
    }
    r.yaw_degrees = number("yaw_deg", 0.0);
    r.tilt_degrees = number("tilt_deg", 0.0);
    r.shift_x = number("shift_x_m", 0.0);
    r.shift_y = number("shift_y_m", 0.0);
    r.seed = static_cast<std::uint64_t>(integer("seed"));
    r.correspondences = integer("correspondences");
    r.inliers = integer("inliers");
    r.recalled = static_cast<int>(integer("recalled"));
    for (const auto& [name, value] : {std::pair<const char*, long long*>{"true_partners", &r.true_partners},
                                      {"quadric_inliers", &r.quadric_inliers},
                                      {"best_clique_inliers", &r.best_clique_inliers},
                                      {"clique_inliers", &r.clique_inliers}})
      if (index_of.count(name)) *value = integer(name);
    r.source_model_bytes = integer("source_model_bytes");
    r.target_model_bytes = integer("target_model_bytes");
    r.overlap = number("overlap", -1.0);
    r.identity_overlap = number("identity_overlap", -1.0);
    std::istringstream timings(field("timings_ms"));
    for (std::string entry; std::getline(timings, entry, ';');) {
      const auto equals = entry.find('=');
      if (equals == std::string::npos) throw Error(where + ": timings entry '" + entry + "' is not name=ms");
      try {
        r.timings_ms[entry.substr(0, equals)] = std::stod(entry.substr(equals + 1));
      } catch (const std::exception&) {
        throw Error(where + ": timings entry '" + entry + "' is not name=ms");
      }
    }
    r.message = field("message");
    rows.push_back(std::move(r));
  }
  if (line_number == 0) throw file_error(path, "empty file (expected the benchmark row header)");
  return rows;
}

std::vector<MethodSummary> write_bench_outputs(const std::string& folder, const std::vector<BenchRow>& rows,
                                               const BenchRunInfo& info) {
  fs::create_directories(folder);
  const fs::path base(folder);
  write_bench_rows_csv((base / "pairs.csv").string(), rows);
  nlohmann::json run;
  run["title"] = info.title;
  run["methods"] = info.methods;
  run["task_count"] = info.task_count;
  run["shard_index"] = info.shard_index;
  run["shard_count"] = info.shard_count;
  run["options"] = info.options_text;
  write_file_atomically((base / "run.json").string(), [&](std::ostream& out) { out << run.dump(2) << "\n"; });
  const std::vector<MethodSummary> summaries = summarize_bench(rows, info.methods);
  std::string title = info.title;
  if (info.shard_count > 1) title += " (shard " + std::to_string(info.shard_index) + "/" + std::to_string(info.shard_count) + ")";
  write_file_atomically((base / "summary.md").string(), [&](std::ostream& out) {
    out << bench_summary_markdown(summaries, title) << "\nOptions: `" << info.options_text << "`\n";
  });
  write_file_atomically((base / "success_by_difficulty.svg").string(), [&](std::ostream& out) { out << bench_success_svg(summaries); });
  write_file_atomically((base / "error_cdf.svg").string(), [&](std::ostream& out) { out << bench_error_cdf_svg(summaries); });
  write_file_atomically((base / "time_per_stage.svg").string(), [&](std::ostream& out) { out << bench_time_svg(summaries); });
  return summaries;
}

BenchRunInfo read_bench_run_info(const std::string& folder) {
  const std::string path = (fs::path(folder) / "run.json").string();
  std::ifstream file(path);
  if (!file) throw file_error(path, "cannot open (is this a `quadrix bench --out` folder?)");
  BenchRunInfo info;
  try {
    const nlohmann::json run = nlohmann::json::parse(file);
    info.title = run.at("title").get<std::string>();
    info.methods = run.at("methods").get<std::vector<std::string>>();
    info.task_count = run.at("task_count").get<std::size_t>();
    info.shard_index = run.at("shard_index").get<int>();
    info.shard_count = run.at("shard_count").get<int>();
    info.options_text = run.at("options").get<std::string>();
  } catch (const nlohmann::json::exception& error) {
    throw file_error(path, std::string("not a benchmark run description: ") + error.what());
  }
  return info;
}

namespace {

// The " --method a,b" part of a run's options text, and the text without it: runs of other methods
// over the same tasks (same pairs, trials, seed and options) merge into one run of all methods.
std::pair<std::string, std::string> split_method_option(const std::string& options_text) {
  const std::string flag = " --method ";
  const std::size_t begin = options_text.find(flag);
  if (begin == std::string::npos) return {options_text, ""};
  const std::size_t value = begin + flag.size();
  const std::size_t end = std::min(options_text.find(' ', value), options_text.size());
  return {options_text.substr(0, begin) + options_text.substr(end), options_text.substr(value, end - value)};
}

}  // namespace

std::vector<MethodSummary> merge_bench_outputs(const std::vector<std::string>& folders, const std::string& out_folder) {
  if (folders.empty()) throw Error("bench merge: no folder given");
  BenchRunInfo merged = read_bench_run_info(folders.front());
  const auto [common_options, first_methods] = split_method_option(merged.options_text);
  std::vector<BenchRow> rows;
  for (const std::string& folder : folders) {
    const BenchRunInfo info = read_bench_run_info(folder);
    if (split_method_option(info.options_text).first != common_options || info.task_count != merged.task_count ||
        info.title != merged.title)
      throw file_error((fs::path(folder) / "run.json").string(),
                       "belongs to another run (options other than --method, title or task count differ from " +
                           folders.front() + ")");
    for (const std::string& method : info.methods)
      if (std::find(merged.methods.begin(), merged.methods.end(), method) == merged.methods.end())
        merged.methods.push_back(method);
    const std::vector<BenchRow> part = read_bench_rows_csv((fs::path(folder) / "pairs.csv").string());
    rows.insert(rows.end(), part.begin(), part.end());
  }
  if (!first_methods.empty()) {
    std::string methods;
    for (const std::string& method : merged.methods) methods += (methods.empty() ? "" : ",") + method;
    merged.options_text.replace(merged.options_text.find(" --method ") + std::string(" --method ").size(),
                                first_methods.size(), methods);
  }
  const auto method_rank = [&](const std::string& method) {
    return static_cast<std::size_t>(std::find(merged.methods.begin(), merged.methods.end(), method) - merged.methods.begin());
  };
  std::sort(rows.begin(), rows.end(), [&](const BenchRow& a, const BenchRow& b) {
    return a.task != b.task ? a.task < b.task : method_rank(a.method) < method_rank(b.method);
  });
  std::set<std::pair<std::size_t, std::string>> seen;
  for (const BenchRow& row : rows)
    if (!seen.insert({row.task, row.method}).second)
      throw Error("bench merge: task " + std::to_string(row.task) + " (" + row.pair_id + ", " + row.method +
                  ") appears in more than one folder");
  std::string missing;
  std::size_t missing_count = 0;
  for (std::size_t task = 0; task < merged.task_count; ++task)
    for (const std::string& method : merged.methods)
      if (!seen.count({task, method})) {
        if (++missing_count <= 10) missing += (missing.empty() ? "" : ", ") + std::to_string(task) + "/" + method;
      }
  if (missing_count)
    throw Error("bench merge: " + std::to_string(missing_count) + " task rows are missing (task/method: " + missing +
                (missing_count > 10 ? ", ..." : "") + "); give every shard folder of every method");
  merged.shard_index = 1;
  merged.shard_count = 1;
  return write_bench_outputs(out_folder, rows, merged);
}

std::string bench_success_svg(const std::vector<MethodSummary>& summaries) {
  const std::vector<std::string> difficulties = difficulty_order(nullptr, summaries);
  const int left = 60, top = 40, plot_height = 240, group_width = std::max<int>(60, 24 * static_cast<int>(summaries.size()) + 30);
  const std::string title = "Success rate per difficulty (RTE <= 2 m, RRE <= 5 deg)";
  const int width = std::max(left + group_width * static_cast<int>(std::max<std::size_t>(difficulties.size(), 1)) + 180,
                             left + text_width(title, 14) + 20);  // the title fits
  const int height = top + plot_height + 60;
  std::ostringstream svg;
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
      << "\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  svg << "<text x=\"" << left << "\" y=\"20\" font-size=\"14\">" << escape_xml(title) << "</text>\n";
  for (int percent = 0; percent <= 100; percent += 25) {
    const double y = top + plot_height * (1.0 - percent / 100.0);
    svg << "<line x1=\"" << left << "\" x2=\"" << width - 180 << "\" y1=\"" << y << "\" y2=\"" << y << "\" stroke=\"#ddd\"/>"
        << "<text x=\"" << left - 8 << "\" y=\"" << y + 4 << "\" text-anchor=\"end\">" << percent << "%</text>\n";
  }
  for (std::size_t d = 0; d < difficulties.size(); ++d) {
    const int x0 = left + group_width * static_cast<int>(d) + 15;
    for (std::size_t m = 0; m < summaries.size(); ++m) {
      const auto found = summaries[m].by_difficulty.find(difficulties[d]);
      if (found == summaries[m].by_difficulty.end() || found->second.second == 0) continue;
      const double rate = double(found->second.first) / double(found->second.second);
      const double bar = plot_height * rate;
      svg << "<rect x=\"" << x0 + 24 * static_cast<int>(m) << "\" y=\"" << top + plot_height - bar << "\" width=\"20\" height=\""
          << bar << "\" fill=\"" << colour(m, summaries.size()) << "\"><title>" << escape_xml(summaries[m].method) << " "
          << escape_xml(difficulties[d]) << ": " << found->second.first << "/" << found->second.second << "</title></rect>\n";
    }
    svg << "<text x=\"" << x0 + 12 * static_cast<int>(summaries.size()) << "\" y=\"" << top + plot_height + 18
        << "\" text-anchor=\"middle\">" << escape_xml(difficulties[d]) << "</text>\n";
  }
  return with_method_legend(svg.str(), summaries, width - 170, top);
}

std::string bench_error_cdf_svg(const std::vector<MethodSummary>& summaries) {
  const int panel_width = 320, panel_height = 220, left = 60, top = 40, gap = 80;
  const int width = left + 2 * panel_width + gap + 180;
  const int height = top + panel_height + 60;
  std::ostringstream svg;
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
      << "\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  // The axis follows the data: it ends at the largest error rounded up to 1/2/5 x 10^k, but at
  // most at twice the success threshold (failures' errors, metres to kilometres, are drawn at the
  // right edge). The dashed line marks the threshold when it is inside the axis.
  struct Panel {
    const char* name;
    double limit;
    double threshold;
  } panels[2] = {{"RTE (m)", 4.0, 2.0}, {"RRE (deg)", 10.0, 5.0}};
  for (int p = 0; p < 2; ++p) {
    double largest = 0.0;
    for (const MethodSummary& summary : summaries)
      for (const double value : p == 0 ? summary.rte_values : summary.rre_values)
        if (std::isfinite(value)) largest = std::max(largest, value);
    if (largest > 0.0) panels[p].limit = std::min(panels[p].limit, nice_ceiling(largest));
  }
  for (int p = 0; p < 2; ++p) {
    const int x0 = left + p * (panel_width + gap);
    svg << "<text x=\"" << x0 << "\" y=\"20\" font-size=\"14\">CDF of " << panels[p].name << "</text>\n";
    svg << "<rect x=\"" << x0 << "\" y=\"" << top << "\" width=\"" << panel_width << "\" height=\"" << panel_height
        << "\" fill=\"none\" stroke=\"#888\"/>\n";
    if (panels[p].threshold <= panels[p].limit) {
      const double threshold_x = x0 + panel_width * panels[p].threshold / panels[p].limit;
      svg << "<line x1=\"" << threshold_x << "\" x2=\"" << threshold_x << "\" y1=\"" << top << "\" y2=\"" << top + panel_height
          << "\" stroke=\"#999\" stroke-dasharray=\"4,3\"/>\n";
    }
    for (int tick = 0; tick <= 4; ++tick) {
      const double value = panels[p].limit * tick / 4.0;
      svg << "<text x=\"" << x0 + panel_width * tick / 4 << "\" y=\"" << top + panel_height + 16 << "\" text-anchor=\"middle\">"
          << format("%g", value) << "</text>\n";
      svg << "<text x=\"" << x0 - 6 << "\" y=\"" << top + panel_height * (4 - tick) / 4 + 4 << "\" text-anchor=\"end\">"
          << 25 * tick << "%</text>\n";
    }
    for (std::size_t m = 0; m < summaries.size(); ++m) {
      std::vector<double> values = p == 0 ? summaries[m].rte_values : summaries[m].rre_values;
      if (values.empty()) continue;
      std::sort(values.begin(), values.end());
      std::ostringstream points;
      double previous_y = top + panel_height;
      points << x0 << "," << previous_y;
      for (std::size_t k = 0; k < values.size(); ++k) {
        const double x = x0 + panel_width * std::min(values[k], panels[p].limit) / panels[p].limit;
        const double y = top + panel_height * (1.0 - double(k + 1) / double(values.size()));
        points << " " << x << "," << previous_y << " " << x << "," << y;
        previous_y = y;
      }
      points << " " << x0 + panel_width << "," << previous_y;
      svg << "<polyline fill=\"none\" stroke-width=\"2\" stroke=\"" << colour(m, summaries.size()) << "\" points=\"" << points.str() << "\"/>\n";
    }
  }
  svg << "<text x=\"" << left << "\" y=\"" << height - 8 << "\" fill=\"#555\">pairs with ground truth; dashed: the success "
         "threshold (2 m, 5 deg); errors past the axis end are drawn at its edge</text>\n";
  return with_method_legend(svg.str(), summaries, width - 170, top);
}

std::string bench_time_svg(const std::vector<MethodSummary>& summaries) {
  std::vector<std::string> stages;
  double longest = 0.0;
  for (const MethodSummary& s : summaries) {
    double sum = 0.0;
    for (const std::string& stage : ordered_stages(s.stage_ms)) {
      if (std::find(stages.begin(), stages.end(), stage) == stages.end()) stages.push_back(stage);
      sum += s.stage_ms.at(stage).first;
    }
    longest = std::max(longest, sum);
  }
  if (!(longest > 0.0)) longest = 1.0;
  const int left = 140, top = 40, bar_height = 22, plot_width = 460;
  const int height = top + 30 * static_cast<int>(summaries.size()) + 40 + 18 * static_cast<int>(stages.size());
  const std::string title = "Median time per stage (ms; a bar is the sum of its stages' medians, longest " +
                            format("%.0f", longest) + " ms)";
  const int width = std::max(left + plot_width + 40, 10 + text_width(title, 14) + 10);  // the title fits
  std::ostringstream svg;
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
      << "\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  svg << "<text x=\"10\" y=\"20\" font-size=\"14\">" << escape_xml(title) << "</text>\n";
  for (std::size_t m = 0; m < summaries.size(); ++m) {
    const int y = top + 30 * static_cast<int>(m);
    svg << "<text x=\"" << left - 8 << "\" y=\"" << y + 15 << "\" text-anchor=\"end\">" << escape_xml(summaries[m].method) << "</text>\n";
    double x = left;
    for (std::size_t k = 0; k < stages.size(); ++k) {
      const auto found = summaries[m].stage_ms.find(stages[k]);
      if (found == summaries[m].stage_ms.end()) continue;
      const double w = plot_width * found->second.first / longest;
      svg << "<rect x=\"" << x << "\" y=\"" << y << "\" width=\"" << w << "\" height=\"" << bar_height << "\" fill=\"" << colour(k, stages.size())
          << "\"><title>" << escape_xml(stages[k]) << ": " << format("%.2f", found->second.first) << " ms</title></rect>\n";
      x += w;
    }
  }
  const int legend_top = top + 30 * static_cast<int>(summaries.size()) + 20;
  for (std::size_t k = 0; k < stages.size(); ++k)
    svg << "<rect x=\"" << left << "\" y=\"" << legend_top + 18 * static_cast<int>(k) << "\" width=\"12\" height=\"12\" fill=\""
        << colour(k, stages.size()) << "\"/><text x=\"" << left + 18 << "\" y=\"" << legend_top + 10 + 18 * static_cast<int>(k) << "\">"
        << escape_xml(stages[k]) << "</text>\n";
  svg << "</svg>\n";
  return svg.str();
}

}  // namespace quadrix
