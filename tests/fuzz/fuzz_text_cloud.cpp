// Fuzz target: the delimited text readers, XYZ (.xyz/.txt, whitespace, '#' comments) and CSV
// (commas, optional header row), on the same bytes.
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace quadrix;
  static const fuzz::InputFile xyz("text_cloud", ".xyz");
  static const fuzz::InputFile csv("text_cloud", ".csv");
  fuzz::read_cloud_both_ways(xyz.write(data, size), CloudFormat::Xyz);
  fuzz::read_cloud_both_ways(csv.write(data, size), CloudFormat::Csv);
  return 0;
}
