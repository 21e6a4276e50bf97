// Fuzz target: read_point_cloud on .ply files (ascii, binary_little_endian, binary_big_endian; other
// elements before the vertices, list properties, every scalar type).
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const quadrix::fuzz::InputFile file("ply_cloud", ".ply");
  quadrix::fuzz::read_cloud_both_ways(file.write(data, size), quadrix::CloudFormat::Ply);
  return 0;
}
