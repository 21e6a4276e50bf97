// quadrix::Error: the one exception type for bad input and API misuse (DESIGN.md §4).
// Degenerate data is never an exception: stages report it as a status in their result.
#pragma once

#include <stdexcept>
#include <string>

namespace quadrix {

/// Bad input or API misuse; the message names the file, line or field and what was expected.
class Error : public std::runtime_error {
 public:
  /// Builds an error whose what() is exactly `message`.
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

/// Builds an Error for a file: "<path>: <what was wrong>".
inline Error file_error(const std::string& path, const std::string& what) {
  return Error(path + ": " + what);
}

}  // namespace quadrix
