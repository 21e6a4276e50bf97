// Fuzz target: both read_kitti_calibration overloads ("Tr:" / "Tr_velo_to_cam:" lines, and the
// per-sequence "seqA-B" / "seqA" lines looked up for a few sequence numbers).
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace quadrix;
  static const fuzz::InputFile file("kitti_calibration", ".txt");
  const std::string& path = file.write(data, size);
  try {
    fuzz::check_pose(read_kitti_calibration(path));
  } catch (const Error& error) {
    fuzz::require_names(error, path);
  }
  for (const int sequence : {0, 3, 10}) {
    try {
      fuzz::check_pose(read_kitti_calibration(path, sequence));
    } catch (const Error& error) {
      fuzz::require_names(error, path);
    }
  }
  return 0;
}
