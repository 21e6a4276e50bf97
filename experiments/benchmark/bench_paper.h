// The generated paper page papers/quadricsreg/README.md (`quadrix paper`, run by `make papers`):
// our benchmark results (every folder written by `quadrix bench --out`) beside the paper's tables
// transcribed as CSV (papers/quadricsreg/tables/*.csv, read generically: any CSV with a header).
#pragma once

#include <string>
#include <vector>

namespace quadrix {

/// A CSV table: header and rows of strings.
struct CsvTable {
  std::string name;                              ///< file stem ("ablation")
  std::vector<std::string> header;               ///< column names
  std::vector<std::vector<std::string>> rows;    ///< one entry per data line, as many fields as the header
};

/// Reads a CSV file with a header line; throws quadrix::Error naming the file and line when a row
/// has another field count than the header.
CsvTable read_csv_table(const std::string& path);

/// The Markdown page: for every results subfolder (sorted; `ablation-*` folders gathered into one
/// ablation table) the summary of its rows and its plots; then, when the paper tables hold the
/// columns needed (dataset, sequence, level, method or setting, success_rate_percent, ...), our
/// numbers beside the paper's for KITTI-LC sequence 00 at the easy level (the only loop closures we
/// have frames for); then every other table in full (long ones linked). Links are relative to
/// `page_folder`. Throws quadrix::Error naming an unreadable results folder or table.
std::string quadricsreg_paper_page(const std::string& results_folder, const std::string& tables_folder,
                                   const std::string& page_folder);

}  // namespace quadrix
