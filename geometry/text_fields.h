// Fields of a line of a text table (TSV lists, pose tables, pair lists): the one split and trim that
// every reader of such tables uses, so that they agree on empty and padded fields.
#pragma once

#include <sstream>
#include <string>
#include <vector>

namespace quadrix {

/// The fields of `line` between `separator`s, empty ones included (a trailing separator ends with an empty field).
inline std::vector<std::string> split_fields(const std::string& line, char separator) {
  std::vector<std::string> fields;
  std::string field;
  std::istringstream stream(line);
  while (std::getline(stream, field, separator)) fields.push_back(field);
  if (!line.empty() && line.back() == separator) fields.emplace_back();
  return fields;
}

/// `text` without leading and trailing spaces, tabs and line ends.
inline std::string trimmed(const std::string& text) {
  const auto first = text.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return "";
  return text.substr(first, text.find_last_not_of(" \t\r\n") - first + 1);
}

}  // namespace quadrix
