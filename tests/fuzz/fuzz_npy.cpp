// Fuzz target: the NumPy .npy reader through both of its users, read_point_cloud (N x 3+ clouds)
// and read_pose_matrix (4x4 or 3x4 poses).
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace quadrix;
  static const fuzz::InputFile file("npy", ".npy");
  const std::string& path = file.write(data, size);
  fuzz::read_cloud_both_ways(path, CloudFormat::Npy);
  try {
    fuzz::check_pose(read_pose_matrix(path));
  } catch (const Error& error) {
    fuzz::require_names(error, path);
  }
  return 0;
}
