// One-line terminal summaries shared by the commands: the whole text of a status message or of the
// auto preset's measurements goes to report.json / model.json and behind --verbose; the terminal
// gets its first clause.
#pragma once

#include <cstddef>
#include <string>

namespace quadrix::cli {

/// Longest summary line the commands print without --verbose, characters (an 80-column terminal
/// plus a prefix such as "status ambiguous: ").
inline constexpr std::size_t kSummaryCharacters = 140;

/// The first clause of `text` (up to the first "; ", ": " after a status word is kept, or ". "),
/// cut at kSummaryCharacters on a word boundary with "..." when longer; the whole text when it
/// already fits.
inline std::string first_clause(const std::string& text) {
  std::size_t end = text.size();
  for (const char* separator : {"; ", ". ", " (", " - "}) {
    const std::size_t at = text.find(separator);
    if (at != std::string::npos && at > 0 && at < end) end = at;
  }
  std::string clause = text.substr(0, end);
  if (clause.size() > kSummaryCharacters) {
    std::size_t cut = clause.rfind(' ', kSummaryCharacters);
    if (cut == std::string::npos || cut < kSummaryCharacters / 2) cut = kSummaryCharacters;
    clause = clause.substr(0, cut) + "...";
  }
  return clause;
}

/// "STATUS" or "STATUS: first clause of MESSAGE" (the whole message when `verbose`), with a pointer
/// to where the rest is when it was cut.
inline std::string status_summary_line(const std::string& status, const std::string& message, bool verbose,
                                       const std::string& details_in = "--verbose") {
  if (message.empty()) return status;
  if (verbose) return status + ": " + message;
  const std::string clause = first_clause(message);
  return status + ": " + clause + (clause.size() < message.size() ? " (details: " + details_in + ")" : "");
}

/// "preset vlp64", or "preset auto -> vlp64 (measured on the cloud; details: --verbose)"; with
/// `verbose` the measurements follow on the next line.
inline std::string preset_summary_line(const std::string& requested, const std::string& used, const std::string& notes,
                                       bool verbose, const std::string& details_in = "--verbose") {
  if (requested != "auto") return "preset " + used;
  std::string line = "preset auto -> " + used + " (measured on the cloud";
  if (verbose) return line + ")\n  " + notes;
  return line + "; details: " + details_in + ")";
}

}  // namespace quadrix::cli
