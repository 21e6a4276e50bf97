// Text point clouds: XYZ (whitespace-separated, '#' comments) and CSV (comma-separated, optional header).
#include "geometry/io.h"
#include "geometry/io_internal.h"

#include <algorithm>
#include <cctype>

namespace quadrix {
namespace io_internal {

namespace {

std::string_view trim(std::string_view text) {
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.front()))) text.remove_prefix(1);
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.remove_suffix(1);
  if (text.size() >= 2 && (text.front() == '"' || text.front() == '\'') && text.back() == text.front())
    text = text.substr(1, text.size() - 2);
  return text;
}

// Strips a '#' comment (and what follows) from a line.
std::string_view strip_comment(std::string_view line) {
  const std::size_t hash = line.find('#');
  return hash == std::string_view::npos ? line : line.substr(0, hash);
}

// Splits a CSV line at commas (no quoting of numbers; quotes around header names are removed).
void split_csv(std::string_view line, std::vector<std::string_view>& cells) {
  cells.clear();
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    cells.push_back(trim(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
}

// Shared row parser: `split` fills the cells of a line; the first data line fixes the column count.
template <typename Split>
PointCloud read_delimited(const std::string& path, const CloudReadOptions& options, CloudReadReport& report,
                          bool allow_header, Split split, const char* encoding) {
  const FileBytes bytes = read_file_bytes(path);
  LineReader lines(bytes.view());
  std::string_view line;
  std::vector<std::string_view> cells;
  std::vector<std::string> names;
  std::vector<FieldColumn> columns;
  std::size_t rows = 0;
  const std::size_t estimated_rows = std::count(bytes.data.get(), bytes.data.get() + bytes.size, '\n') + 1;
  while (lines.next(line)) {
    line = strip_comment(line);
    split(line, cells);
    if (cells.empty() || (cells.size() == 1 && cells[0].empty())) continue;
    const std::string where = "line " + std::to_string(lines.line_number()) + ": ";
    if (columns.empty()) {
      double probe = 0;
      if (allow_header && !parse_double(cells[0], probe)) {
        if (!names.empty()) throw file_error(path, where + "a second header line; expected numbers");
        for (std::string_view cell : cells) {
          if (cell.empty()) throw file_error(path, where + "header has an empty column name");
          names.emplace_back(cell);
        }
        continue;
      }
      if (names.empty()) {
        names = headerless_column_names(cells.size());
      } else if (names.size() != cells.size()) {
        throw file_error(path, where + "has " + std::to_string(cells.size()) + " values but the header names " +
                                   std::to_string(names.size()) + " columns");
      }
      if (names.size() < 3)
        throw file_error(path, where + "has " + std::to_string(cells.size()) +
                                   " column(s); expected at least x, y, z");
      columns.resize(names.size());
      for (std::size_t c = 0; c < names.size(); ++c) {
        columns[c].name = names[c];
        columns[c].values.reserve(estimated_rows);
      }
    }
    if (cells.size() != columns.size())
      throw file_error(path, where + "has " + std::to_string(cells.size()) + " values, expected " +
                                 std::to_string(columns.size()) + " like the first data line");
    for (std::size_t c = 0; c < cells.size(); ++c) {
      double value = 0;
      if (!parse_double(cells[c], value))
        throw file_error(path, where + "'" + std::string(cells[c]) + "' is not a number (column " +
                                   std::to_string(c + 1) + ", '" + columns[c].name + "')");
      columns[c].values.push_back(value);
    }
    ++rows;
  }
  if (columns.empty()) {
    // No data lines: an empty cloud, but the header (if any) must still name x, y and z.
    for (const std::string& name : names) columns.push_back({name, true, {}});
    if (columns.empty()) columns = {{"x", true, {}}, {"y", true, {}}, {"z", true, {}}};
  }
  report.encoding = encoding;
  report.fields.clear();
  for (const FieldColumn& column : columns) report.fields.push_back(column.name);
  return assemble_cloud(path, columns, rows, options, report);
}

}  // namespace

PointCloud read_xyz_cloud(const std::string& path, const CloudReadOptions& options, CloudReadReport& report) {
  return read_delimited(
      path, options, report, false,
      [](std::string_view line, std::vector<std::string_view>& cells) { split_tokens(line, cells); }, "ascii");
}

PointCloud read_csv_cloud(const std::string& path, const CloudReadOptions& options, CloudReadReport& report) {
  return read_delimited(
      path, options, report, true,
      [](std::string_view line, std::vector<std::string_view>& cells) {
        if (trim(line).empty()) {
          cells.clear();
          return;
        }
        split_csv(line, cells);
      },
      "ascii csv");
}

}  // namespace io_internal
}  // namespace quadrix
