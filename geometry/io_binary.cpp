// Raw binary formats: KITTI .bin, nuScenes .pcd.bin, SemanticKITTI .label and NumPy .npy.
#include "geometry/io.h"
#include "geometry/io_internal.h"

#include <cmath>
#include <cstring>
#include <limits>

namespace quadrix {
namespace io_internal {

namespace {

// Reads fixed-size float32 records (x, y, z, intensity[, ring]) with one pass over the bytes.
PointCloud read_float_records(const std::string& path, std::size_t floats_per_point, const char* layout,
                              const CloudReadOptions& options, CloudReadReport& report) {
  const std::size_t record = floats_per_point * sizeof(float);
  // The size is checked before any byte is read (a wrong file can be gigabytes).
  const std::size_t size = regular_file_size(path);
  if (size % record != 0)
    throw file_error(path, "size " + std::to_string(size) + " bytes is not a multiple of " +
                               std::to_string(record) + " (" + layout + "); truncated or not this format");
  const FileBytes bytes = read_file_bytes(path);
  if (bytes.size % record != 0) throw file_error(path, "the file changed size while it was read");
  const std::size_t rows = bytes.size / record;
  PointCloud cloud;
  cloud.positions.resize(3, static_cast<Eigen::Index>(rows));
  cloud.intensity.resize(rows);
  const bool keep_ring = floats_per_point == 5 && options.keep_extra_fields;
  std::vector<float>* ring = keep_ring ? &cloud.extra_fields["ring"] : nullptr;
  if (ring) ring->resize(rows);
  float* positions = cloud.positions.data();
  const char* source = bytes.data.get();
  std::size_t count = 0;
  for (std::size_t i = 0; i < rows; ++i, source += record) {
    float values[5];
    std::memcpy(values, source, record);
    if (std::isfinite(values[0]) && std::isfinite(values[1]) && std::isfinite(values[2])) {
      positions[3 * count] = values[0];
      positions[3 * count + 1] = values[1];
      positions[3 * count + 2] = values[2];
      cloud.intensity[count] = values[3];
      if (ring) (*ring)[count] = values[4];
      ++count;
    } else if (options.reject_non_finite) {
      throw_non_finite(path, i, !std::isfinite(values[0]) ? "x" : !std::isfinite(values[1]) ? "y" : "z");
    }
  }
  if (count != rows) {
    cloud.positions.conservativeResize(3, static_cast<Eigen::Index>(count));
    cloud.intensity.resize(count);
    if (ring) ring->resize(count);
  }
  report.encoding = "binary float32";
  report.points_in_file = rows;
  report.non_finite_dropped = rows - count;
  report.fields = {"x", "y", "z", "intensity"};
  if (floats_per_point == 5) report.fields.push_back("ring");
  return cloud;
}

// Value of key `key` in a NumPy header dict, e.g. 'descr': '<f8' -> "'<f8'"; empty when absent.
std::string npy_header_value(const std::string& header, const std::string& key) {
  const std::size_t at = header.find("'" + key + "'");
  if (at == std::string::npos) return {};
  std::size_t position = header.find(':', at);
  if (position == std::string::npos) return {};
  ++position;
  while (position < header.size() && header[position] == ' ') ++position;
  if (position >= header.size()) return {};
  std::size_t end = position;
  if (header[position] == '(') {
    end = header.find(')', position);
    return end == std::string::npos ? std::string() : header.substr(position, end - position + 1);
  }
  if (header[position] == '\'' || header[position] == '"') {
    end = header.find(header[position], position + 1);
    return end == std::string::npos ? std::string() : header.substr(position, end - position + 1);
  }
  while (end < header.size() && header[end] != ',' && header[end] != '}') ++end;
  std::string value = header.substr(position, end - position);
  while (!value.empty() && value.back() == ' ') value.pop_back();
  return value;
}

}  // namespace

PointCloud read_kitti_bin(const std::string& path, const CloudReadOptions& options, CloudReadReport& report) {
  return read_float_records(path, 4, "KITTI .bin stores float32 x, y, z, intensity: 16 bytes a point", options,
                            report);
}

PointCloud read_nuscenes_bin(const std::string& path, const CloudReadOptions& options, CloudReadReport& report) {
  return read_float_records(path, 5, "nuScenes .pcd.bin stores float32 x, y, z, intensity, ring: 20 bytes a point",
                            options, report);
}

NumpyMatrix read_npy_matrix(const std::string& path) {
  const FileBytes bytes = read_file_bytes(path);
  const unsigned char* data = reinterpret_cast<const unsigned char*>(bytes.data.get());
  if (bytes.size < 10 || std::memcmp(data, "\x93NUMPY", 6) != 0)
    throw file_error(path, "bad magic: not a NumPy .npy file (expected \\x93NUMPY at the start)");
  const int major = data[6];
  std::size_t header_length = 0;
  std::size_t header_start = 0;
  if (major == 1) {
    header_length = data[8] | (static_cast<std::size_t>(data[9]) << 8);
    header_start = 10;
  } else if (major == 2 || major == 3) {
    if (bytes.size < 12) throw file_error(path, "truncated .npy header");
    header_length = data[8] | (static_cast<std::size_t>(data[9]) << 8) | (static_cast<std::size_t>(data[10]) << 16) |
                    (static_cast<std::size_t>(data[11]) << 24);
    header_start = 12;
  } else {
    throw file_error(path, "unsupported .npy format version " + std::to_string(major) + " (expected 1, 2 or 3)");
  }
  if (header_start + header_length > bytes.size)
    throw file_error(path, "truncated .npy header (declares " + std::to_string(header_length) + " bytes, file has " +
                               std::to_string(bytes.size - header_start) + ")");
  const std::string header(bytes.data.get() + header_start, header_length);
  NumpyMatrix matrix;
  std::string descr = npy_header_value(header, "descr");
  if (descr.size() < 2) throw file_error(path, ".npy header has no 'descr' entry: " + header);
  descr = descr.substr(1, descr.size() - 2);
  matrix.dtype = descr;
  const std::string fortran = npy_header_value(header, "fortran_order");
  if (fortran != "True" && fortran != "False")
    throw file_error(path, ".npy header has no valid 'fortran_order' (True/False): " + header);
  const std::string shape_text = npy_header_value(header, "shape");
  if (shape_text.size() < 2) throw file_error(path, ".npy header has no 'shape' tuple: " + header);

  std::vector<std::size_t> shape;
  {
    std::vector<std::string_view> tokens;
    const std::string inner = shape_text.substr(1, shape_text.size() - 2);
    split_tokens(inner, tokens, ',');
    for (std::string_view token : tokens) {
      std::size_t value = 0;
      if (token == "L") continue;
      if (!token.empty() && token.back() == 'L') token.remove_suffix(1);
      if (!parse_size(token, value)) throw file_error(path, ".npy shape " + shape_text + " is not a tuple of integers");
      shape.push_back(value);
    }
  }
  if (shape.empty() || shape.size() > 2)
    throw file_error(path, ".npy shape " + shape_text + " is not 1-D or 2-D (expected N x 3 or more)");
  matrix.rows = shape[0];
  matrix.columns = shape.size() == 2 ? shape[1] : 1;

  const char order = descr.empty() ? '?' : descr[0];
  const std::string kind = descr.size() > 1 ? descr.substr(1) : std::string();
  ScalarType type;
  if (kind == "f4") {
    type = ScalarType::Float32;
  } else if (kind == "f8") {
    type = ScalarType::Float64;
  } else {
    throw file_error(path, ".npy dtype '" + descr + "' is not supported (expected float32 '<f4'/'>f4' or float64 '<f8'/'>f8')");
  }
  if (order != '<' && order != '>' && order != '=' && order != '|')
    throw file_error(path, ".npy dtype '" + descr + "' has an unknown byte-order mark");
  const bool swap = order == '>';
  const std::size_t item = scalar_size(type);
  const std::size_t data_start = header_start + header_length;
  const bool overflows =
      matrix.rows != 0 && matrix.columns > std::numeric_limits<std::size_t>::max() / item / matrix.rows;
  const std::size_t needed = overflows ? 0 : matrix.rows * matrix.columns * item;
  if (overflows || needed > bytes.size - data_start)
    throw file_error(path, ".npy data truncated: shape " + shape_text + " needs " +
                               (overflows ? std::string("more than 2^64") : std::to_string(needed)) + " bytes, file has " +
                               std::to_string(bytes.size - data_start));
  if (bytes.size - data_start != needed)
    throw file_error(path, ".npy data size mismatch: shape " + shape_text + " of " + descr + " needs " +
                               std::to_string(needed) + " bytes after the header, file has " +
                               std::to_string(bytes.size - data_start) +
                               (bytes.size - data_start < needed ? " (truncated)" : ""));
  matrix.values.resize(matrix.rows * matrix.columns);
  if (matrix.values.empty()) return matrix;  // N x 0 or 0 x N: no column to decode
  const char* source = bytes.data.get() + data_start;
  const bool fortran_order = fortran == "True";
  std::vector<double> column(matrix.rows);
  for (std::size_t c = 0; c < matrix.columns; ++c) {
    if (fortran_order) {
      decode_strided(source + c * matrix.rows * item, item, matrix.rows, type, swap, column.data());
    } else {
      decode_strided(source + c * item, matrix.columns * item, matrix.rows, type, swap, column.data());
    }
    for (std::size_t r = 0; r < matrix.rows; ++r) matrix.values[r * matrix.columns + c] = column[r];
  }
  return matrix;
}

PointCloud read_npy_cloud(const std::string& path, const CloudReadOptions& options, CloudReadReport& report) {
  NumpyMatrix matrix = read_npy_matrix(path);
  if (matrix.columns < 3)
    throw file_error(path, ".npy array has " + std::to_string(matrix.columns) +
                               " column(s); a point cloud needs N x 3 or more (x, y, z first)");
  if (matrix.columns > kMaxValuesPerPoint)
    throw file_error(path, ".npy array has " + std::to_string(matrix.columns) + " columns, more than the " +
                               std::to_string(kMaxValuesPerPoint) + " values a point this reader supports");
  const std::vector<std::string> names = headerless_column_names(matrix.columns);
  std::vector<FieldColumn> columns(matrix.columns);
  for (std::size_t c = 0; c < matrix.columns; ++c) {
    columns[c].name = names[c];
    columns[c].values.resize(matrix.rows);
    for (std::size_t r = 0; r < matrix.rows; ++r) columns[c].values[r] = matrix.values[r * matrix.columns + c];
  }
  report.encoding = matrix.dtype;
  report.fields = names;
  return assemble_cloud(path, columns, matrix.rows, options, report);
}

}  // namespace io_internal

std::vector<std::uint32_t> read_semantic_kitti_labels(const std::string& path, std::size_t expected_points) {
  const io_internal::FileBytes bytes = io_internal::read_file_bytes(path);
  if (bytes.size % 4 != 0)
    throw file_error(path, "size " + std::to_string(bytes.size) +
                               " bytes is not a multiple of 4 (SemanticKITTI .label stores one uint32 a point)");
  const std::size_t count = bytes.size / 4;
  if (expected_points != 0 && count != expected_points)
    throw file_error(path, "has " + std::to_string(count) + " labels but the scan has " +
                               std::to_string(expected_points) + " points");
  std::vector<std::uint32_t> labels(count);
  if (count > 0) std::memcpy(labels.data(), bytes.data.get(), count * 4);
  return labels;
}

}  // namespace quadrix
