// Fuzz target: read_pose_matrix on text files (16 or 12 numbers, '#' comments, commas).
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace quadrix;
  static const fuzz::InputFile file("pose_matrix", ".txt");
  const std::string& path = file.write(data, size);
  try {
    fuzz::check_pose(read_pose_matrix(path));
  } catch (const Error& error) {
    fuzz::require_names(error, path);
  }
  return 0;
}
