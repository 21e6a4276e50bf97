// Fuzz target: read_point_cloud on .pcd files (ascii, binary, binary_compressed with the LZF
// decoder; packed rgb/rgba, COUNT > 1 and "_" padding fields).
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const quadrix::fuzz::InputFile file("pcd", ".pcd");
  quadrix::fuzz::read_cloud_both_ways(file.write(data, size), quadrix::CloudFormat::Pcd);
  return 0;
}
