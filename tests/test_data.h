// Access for tests to the real data in ../shared/data (skip with a clear message when absent) and to
// the crash reproducers of the fuzz harnesses (tests/fuzz/regressions).
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

namespace quadrix::testing {

/// Root of the real data: $QUADRIX_DATA_DIR if set, else the folder configured at build time.
inline std::filesystem::path shared_data_root() {
  if (const char* from_environment = std::getenv("QUADRIX_DATA_DIR")) return from_environment;
  return QUADRIX_DATA_DIR;
}

/// Full path of a file under the data root (no existence check).
inline std::string shared_data_path(const std::string& relative) { return (shared_data_root() / relative).string(); }

/// Full path of a crash reproducer the fuzz harness `harness` found (tests/fuzz/regressions/<harness>/<name>).
inline std::string fuzz_regression_path(const std::string& harness, const std::string& name) {
  return (std::filesystem::path(QUADRIX_FUZZ_REGRESSIONS_DIR) / harness / name).string();
}

}  // namespace quadrix::testing

/// Skips the current test, naming the file, when a real-data file is absent.
#define QUADRIX_REQUIRE_SHARED_DATA(relative)                                                   \
  do {                                                                                           \
    if (!std::filesystem::exists(::quadrix::testing::shared_data_path(relative)))               \
      GTEST_SKIP() << "real data absent: " << ::quadrix::testing::shared_data_path(relative)   \
                   << " (../shared/data is not beside the checkout)";                           \
  } while (0)
