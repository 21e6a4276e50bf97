// Fuzz target: LAS 1.0-1.4 on .las files: read_point_cloud both ways, read_las_header, and the
// streaming reader in chunks, which must yield exactly the points the whole-file reader kept.
#include "geometry/las.h"
#include "geometry/point_stream.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const quadrix::fuzz::InputFile file("las", ".las");
  const std::string& path = file.write(data, size);
  quadrix::fuzz::read_cloud_both_ways(path, quadrix::CloudFormat::Las);
  bool header_read = false;
  try {
    const quadrix::LasHeader header = quadrix::read_las_header(path);
    quadrix::fuzz::require(header.point_format >= 0 && header.point_format <= 10);
    quadrix::fuzz::require(header.point_data_offset <= header.file_size);
    quadrix::fuzz::require(header.point_count * header.record_length <= header.file_size - header.point_data_offset);
    header_read = true;
  } catch (const quadrix::Error& error) {
    quadrix::fuzz::require_names(error, path);
  }
  quadrix::PointCloud whole;
  bool whole_read = false;
  try {
    whole = quadrix::read_point_cloud(path);
    whole_read = true;
  } catch (const quadrix::Error& error) {
    quadrix::fuzz::require_names(error, path);
  }
  quadrix::fuzz::require(!whole_read || header_read);
  try {
    const std::unique_ptr<quadrix::PointStream> stream = quadrix::open_point_stream(path);
    quadrix::PointChunk chunk;
    std::size_t points = 0;
    while (stream->read(3, chunk)) {
      quadrix::fuzz::require(chunk.size() <= 3 && chunk.positions.allFinite());
      quadrix::fuzz::require(chunk.labels.size() == chunk.size() && chunk.intensity.size() == chunk.size());
      for (std::size_t i = 0; i < chunk.size(); ++i) {
        // The stream keeps doubles; the whole-file reader also drops what overflows float32.
        const Eigen::Vector3f position = chunk.positions.col(static_cast<Eigen::Index>(i)).cast<float>();
        if (!position.allFinite()) continue;
        if (whole_read)
          quadrix::fuzz::require(points < whole.size() && position == whole.positions.col(static_cast<Eigen::Index>(points)));
        ++points;
      }
    }
    quadrix::fuzz::require(!whole_read || points == whole.size());
  } catch (const quadrix::Error& error) {
    quadrix::fuzz::require_names(error, path);
    quadrix::fuzz::require(!whole_read);
  }
  return 0;
}
