// Fuzz target: read_kitti_poses (one row-major 3x4 pose of 12 numbers a line).
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace quadrix;
  static const fuzz::InputFile file("kitti_poses", ".txt");
  const std::string& path = file.write(data, size);
  try {
    for (const Eigen::Isometry3d& pose : read_kitti_poses(path)) fuzz::check_pose(pose);
  } catch (const Error& error) {
    fuzz::require_names(error, path);
  }
  return 0;
}
