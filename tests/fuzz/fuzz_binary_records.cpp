// Fuzz target: the raw float-record readers (KITTI .bin, nuScenes .pcd.bin through the --format
// override) and SemanticKITTI .label, all on the same bytes.
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace quadrix;
  static const fuzz::InputFile file("binary_records", ".bin");
  const std::string& path = file.write(data, size);
  fuzz::read_cloud_both_ways(path, CloudFormat::KittiBin);
  fuzz::read_cloud_both_ways(path, CloudFormat::NuScenesBin, CloudFormat::NuScenesBin);
  try {
    const std::vector<std::uint32_t> labels = read_semantic_kitti_labels(path);
    fuzz::require(labels.size() * 4 == size);
    // The same count is accepted, any other is an Error naming the file.
    fuzz::require(read_semantic_kitti_labels(path, labels.size()).size() == labels.size());
    try {
      read_semantic_kitti_labels(path, labels.size() + 1);
      fuzz::fail("a label file was accepted for a scan with one point more");
    } catch (const Error& error) {
      fuzz::require_names(error, path);
    }
  } catch (const Error& error) {
    fuzz::require_names(error, path);
    fuzz::require(size % 4 != 0);
  }
  return 0;
}
