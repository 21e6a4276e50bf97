// PCD v0.5-0.7: ascii, binary and binary_compressed (PCL's LZF decompressor) reading; ascii and binary
// writing. Packed rgb/rgba fields become colours; "_" padding fields are skipped; COUNT > 1 fields become
// name_0, name_1, ... extra fields.
#include "geometry/io.h"
#include "geometry/io_internal.h"

#include <pcl/io/lzf.h>

#include <cstring>
#include <limits>
#include <ostream>

namespace quadrix {
namespace io_internal {

namespace {

struct PcdField {
  std::string name;
  std::size_t size = 4;
  char type = 'F';
  std::size_t count = 1;
  ScalarType scalar = ScalarType::Float32;
  std::size_t offset = 0;  // byte offset inside a binary point record
};

struct PcdHeader {
  std::vector<PcdField> fields;
  std::size_t width = 0, height = 0, points = 0;
  bool have_points = false;
  std::string data;            // ascii | binary | binary_compressed
  std::size_t body_offset = 0;
  std::size_t body_first_line = 0;
  std::size_t point_stride = 0;
};

bool is_packed_color(const PcdField& field) {
  return (field.name == "rgb" || field.name == "rgba") && field.size == 4 && field.count == 1;
}

/// The header as written, before SIZE, TYPE and COUNT can be checked against FIELDS.
struct PcdHeaderLines {
  PcdHeader header;  // field names, WIDTH, HEIGHT, POINTS, DATA and where the body starts
  std::vector<std::string> size_text, type_text, count_text;
  bool have_fields = false, have_width = false, have_height = false;
};

/// Reads the key lines up to DATA; SIZE, TYPE and COUNT stay text, since FIELDS may come after them.
PcdHeaderLines read_pcd_header_lines(const std::string& path, std::string_view text) {
  PcdHeaderLines result;
  PcdHeader& header = result.header;
  LineReader lines(text);
  std::string_view line;
  std::vector<std::string_view> tokens;
  bool any_key = false;
  while (true) {
    if (!lines.next(line)) {
      if (!any_key) throw file_error(path, "bad magic: not a PCD file (no FIELDS/DATA header)");
      throw file_error(path, "PCD header has no DATA line (truncated header)");
    }
    const std::string where = "header line " + std::to_string(lines.line_number()) + ": ";
    split_tokens(line, tokens);
    if (tokens.empty() || tokens[0].front() == '#') continue;
    const std::string key(tokens[0]);
    auto single_size = [&](std::size_t& value) {
      if (tokens.size() != 2 || !parse_size(tokens[1], value))
        throw file_error(path, where + key + " expects one non-negative integer, got '" + std::string(line) + "'");
    };
    if (key == "VERSION") {
      any_key = true;
    } else if (key == "FIELDS" || key == "COLUMNS") {
      any_key = result.have_fields = true;
      for (std::size_t k = 1; k < tokens.size(); ++k) {
        PcdField field;
        field.name = std::string(tokens[k]);
        header.fields.push_back(field);
      }
    } else if (key == "SIZE") {
      for (std::size_t k = 1; k < tokens.size(); ++k) result.size_text.emplace_back(tokens[k]);
    } else if (key == "TYPE") {
      for (std::size_t k = 1; k < tokens.size(); ++k) result.type_text.emplace_back(tokens[k]);
    } else if (key == "COUNT") {
      for (std::size_t k = 1; k < tokens.size(); ++k) result.count_text.emplace_back(tokens[k]);
    } else if (key == "WIDTH") {
      single_size(header.width);
      result.have_width = true;
    } else if (key == "HEIGHT") {
      single_size(header.height);
      result.have_height = true;
    } else if (key == "POINTS") {
      single_size(header.points);
      header.have_points = true;
    } else if (key == "VIEWPOINT") {
      if (tokens.size() != 8) throw file_error(path, where + "VIEWPOINT expects 7 numbers");
    } else if (key == "DATA") {
      if (tokens.size() != 2 || (tokens[1] != "ascii" && tokens[1] != "binary" && tokens[1] != "binary_compressed"))
        throw file_error(path, where + "DATA must be ascii, binary or binary_compressed, got '" + std::string(line) + "'");
      header.data = std::string(tokens[1]);
      break;
    } else {
      throw file_error(path, where + "unknown PCD header key '" + key + "'");
    }
  }
  header.body_offset = lines.position();
  header.body_first_line = lines.line_number() + 1;
  return result;
}

/// Checks that FIELDS exists and that SIZE, TYPE and (when given) COUNT have one entry per field.
void check_pcd_field_lists(const std::string& path, const PcdHeaderLines& lines) {
  if (!lines.have_fields || lines.header.fields.empty()) throw file_error(path, "PCD header has no FIELDS line");
  const std::size_t n = lines.header.fields.size();
  if (lines.size_text.size() != n)
    throw file_error(path, "PCD header: SIZE has " + std::to_string(lines.size_text.size()) + " entries for " +
                               std::to_string(n) + " FIELDS");
  if (lines.type_text.size() != n)
    throw file_error(path, "PCD header: TYPE has " + std::to_string(lines.type_text.size()) + " entries for " +
                               std::to_string(n) + " FIELDS");
  if (!lines.count_text.empty() && lines.count_text.size() != n)
    throw file_error(path, "PCD header: COUNT has " + std::to_string(lines.count_text.size()) + " entries for " +
                               std::to_string(n) + " FIELDS");
}

/// The scalar type of a field's TYPE letter and SIZE, or an error naming both as the file spells them.
ScalarType pcd_scalar_type(const std::string& path, const PcdField& field, const std::string& type_text,
                           const std::string& size_text) {
  const std::string kind = std::string(1, field.type) + std::to_string(field.size);
  if (kind == "I1") return ScalarType::Int8;
  if (kind == "U1") return ScalarType::UInt8;
  if (kind == "I2") return ScalarType::Int16;
  if (kind == "U2") return ScalarType::UInt16;
  if (kind == "I4") return ScalarType::Int32;
  if (kind == "U4") return ScalarType::UInt32;
  if (kind == "I8") return ScalarType::Int64;
  if (kind == "U8") return ScalarType::UInt64;
  if (kind == "F4") return ScalarType::Float32;
  if (kind == "F8") return ScalarType::Float64;
  throw file_error(path, "PCD header: field '" + field.name + "' has unsupported TYPE " + type_text + " SIZE " + size_text +
                             " (expected I/U of size 1, 2, 4, 8 or F of size 4, 8)");
}

/// Gives each field its size, type, count and byte offset (values a point capped first); returns the record size.
std::size_t lay_out_pcd_fields(const std::string& path, PcdHeaderLines& lines) {
  std::size_t offset = 0;
  std::size_t values_per_point = 0;
  for (std::size_t f = 0; f < lines.header.fields.size(); ++f) {
    PcdField& field = lines.header.fields[f];
    const std::string& size_text = lines.size_text[f];
    const std::string& type_text = lines.type_text[f];
    if (!parse_size(size_text, field.size))
      throw file_error(path, "PCD header: SIZE of field '" + field.name + "' is '" + size_text + "'");
    if (type_text.size() != 1)
      throw file_error(path, "PCD header: TYPE of field '" + field.name + "' is '" + type_text + "' (expected I, U or F)");
    field.type = type_text[0];
    if (!lines.count_text.empty() && (!parse_size(lines.count_text[f], field.count) || field.count == 0))
      throw file_error(path, "PCD header: COUNT of field '" + field.name + "' is '" + lines.count_text[f] +
                                 "' (expected a positive integer)");
    values_per_point += field.count;
    if (field.count > kMaxValuesPerPoint || values_per_point > kMaxValuesPerPoint)
      throw file_error(path, "PCD header: COUNT of field '" + field.name + "' is " + lines.count_text[f] +
                                 ", more than the " + std::to_string(kMaxValuesPerPoint) +
                                 " values a point this reader supports");
    field.scalar = pcd_scalar_type(path, field, type_text, size_text);
    field.offset = offset;
    offset += field.size * field.count;
  }
  return offset;
}

/// Checks WIDTH x HEIGHT against POINTS: HEIGHT defaults to 1 and POINTS to WIDTH x HEIGHT.
void check_pcd_dimensions(const std::string& path, PcdHeaderLines& lines) {
  PcdHeader& header = lines.header;
  if (!lines.have_width) throw file_error(path, "PCD header has no WIDTH line");
  if (!lines.have_height) header.height = 1;
  if (header.height != 0 && header.width > std::numeric_limits<std::size_t>::max() / header.height)
    throw file_error(path, "PCD header: WIDTH x HEIGHT overflows");
  if (!header.have_points) header.points = header.width * header.height;
  if (header.points != header.width * header.height)
    throw file_error(path, "PCD header: POINTS " + std::to_string(header.points) + " differs from WIDTH x HEIGHT = " +
                               std::to_string(header.width * header.height));
}

/// Reads and checks a PCD header: its fields laid out, its dimensions consistent, the body located.
PcdHeader parse_pcd_header(const std::string& path, std::string_view text) {
  PcdHeaderLines lines = read_pcd_header_lines(path, text);
  check_pcd_field_lists(path, lines);
  lines.header.point_stride = lay_out_pcd_fields(path, lines);
  check_pcd_dimensions(path, lines);
  return std::move(lines.header);
}

// Output columns for one PCD field: one column a COUNT element, or red/green/blue for packed colours.
struct FieldTarget {
  std::vector<std::size_t> columns;  // indices into the column list (empty for "_" padding)
};

// The columns a PCD header declares, one per scalar (a packed rgb/rgba field becomes red, green,
// blue), and for each field the columns it fills. Fills report.fields.
struct PcdColumns {
  std::vector<FieldColumn> columns;
  std::vector<FieldTarget> targets;  // per header field

  // Stores a packed 0x00RRGGBB colour of field `f` at `row`.
  void store_color(std::size_t f, std::size_t row, std::uint32_t packed) {
    columns[targets[f].columns[0]].values[row] = (packed >> 16) & 0xFF;
    columns[targets[f].columns[1]].values[row] = (packed >> 8) & 0xFF;
    columns[targets[f].columns[2]].values[row] = packed & 0xFF;
  }
  // Appends a packed 0x00RRGGBB colour of field `f`.
  void append_color(std::size_t f, std::uint32_t packed) {
    columns[targets[f].columns[0]].values.push_back((packed >> 16) & 0xFF);
    columns[targets[f].columns[1]].values.push_back((packed >> 8) & 0xFF);
    columns[targets[f].columns[2]].values.push_back(packed & 0xFF);
  }
};

// The columns, each sized to `rows` values (binary data, whose size was checked) or empty (ascii,
// appended line by line: the header's count is not sized before the lines are there).
PcdColumns pcd_columns(const PcdHeader& header, std::size_t rows, CloudReadReport& report) {
  PcdColumns result;
  result.targets.resize(header.fields.size());
  report.fields.clear();
  for (std::size_t f = 0; f < header.fields.size(); ++f) {
    const PcdField& field = header.fields[f];
    if (field.name == "_") continue;
    report.fields.push_back(field.name);
    if (is_packed_color(field)) {
      for (const char* channel : {"red", "green", "blue"}) {
        result.targets[f].columns.push_back(result.columns.size());
        result.columns.push_back({channel, false, std::vector<double>(rows)});
      }
      continue;
    }
    for (std::size_t c = 0; c < field.count; ++c) {
      result.targets[f].columns.push_back(result.columns.size());
      const std::string name = field.count == 1 ? field.name : field.name + "_" + std::to_string(c);
      result.columns.push_back({name, scalar_is_floating(field.scalar), std::vector<double>(rows)});
    }
  }
  return result;
}

// DATA ascii: one line of values per point.
void read_pcd_ascii(const std::string& path, const FileBytes& bytes, const PcdHeader& header, PcdColumns& columns) {
  const std::size_t rows = header.points;
  LineReader lines(bytes.view(), header.body_offset, header.body_first_line);
  std::string_view line;
  std::vector<std::string_view> tokens;
  std::size_t expected_tokens = 0;
  for (const PcdField& field : header.fields) expected_tokens += field.count;
  std::size_t row = 0;
  while (row < rows && lines.next(line)) {
    split_tokens(line, tokens);
    if (tokens.empty()) continue;
    const std::string where = "line " + std::to_string(lines.line_number()) + ": ";
    if (tokens.size() != expected_tokens)
      throw file_error(path, where + "expected " + std::to_string(expected_tokens) + " values, found " +
                                 std::to_string(tokens.size()));
    std::size_t token = 0;
    for (std::size_t f = 0; f < header.fields.size(); ++f) {
      const PcdField& field = header.fields[f];
      for (std::size_t c = 0; c < field.count; ++c, ++token) {
        double value = 0;
        if (!parse_double(tokens[token], value))
          throw file_error(path, where + "'" + std::string(tokens[token]) + "' is not a number (field '" + field.name + "')");
        if (columns.targets[f].columns.empty()) continue;
        if (is_packed_color(field)) {
          std::uint32_t packed = 0;
          if (field.type == 'F') {
            const float as_float = static_cast<float>(value);
            std::memcpy(&packed, &as_float, 4);
          } else {
            packed = static_cast<std::uint32_t>(value);
          }
          columns.append_color(f, packed);
        } else {
          columns.columns[columns.targets[f].columns[c]].values.push_back(value);
        }
      }
    }
    ++row;
  }
  if (row < rows)
    throw file_error(path, "truncated: header declares " + std::to_string(rows) + " points, the data has " +
                               std::to_string(row) + " lines");
}

// Checks binary data after the header can hold the POINTS the header declares, before anything is
// sized to that count: binary needs POINTS x record size bytes, binary_compressed an uncompressed
// size of POINTS x record size from an LZF stream inside the file (LZF expands at most 88-fold: a
// 3-byte back reference copies at most 264 bytes).
void check_binary_data_size(const std::string& path, const FileBytes& bytes, const PcdHeader& header) {
  const std::size_t available = bytes.size - header.body_offset;
  const std::size_t rows = header.points;
  const std::size_t stride = header.point_stride;
  if (stride != 0 && rows > std::numeric_limits<std::size_t>::max() / stride)
    throw file_error(path, "PCD header: POINTS x record size overflows");
  const std::size_t needed = rows * stride;
  if (header.data != "binary_compressed") {
    if (available < needed)
      throw file_error(path, "truncated: binary data needs " + std::to_string(rows) + " points x " + std::to_string(stride) +
                                 " bytes = " + std::to_string(needed) + " bytes, only " + std::to_string(available) +
                                 " follow the header");
    return;
  }
  if (available < 8) throw file_error(path, "truncated: binary_compressed data has no size words");
  const char* body = bytes.data.get() + header.body_offset;
  std::uint32_t compressed_size = 0, uncompressed_size = 0;
  std::memcpy(&compressed_size, body, 4);
  std::memcpy(&uncompressed_size, body + 4, 4);
  if (uncompressed_size != needed)
    throw file_error(path, "binary_compressed: uncompressed size " + std::to_string(uncompressed_size) +
                               " differs from POINTS x record size = " + std::to_string(needed));
  if (compressed_size > available - 8)
    throw file_error(path, "truncated: binary_compressed data declares " + std::to_string(compressed_size) +
                               " compressed bytes, only " + std::to_string(available - 8) + " follow");
  if (needed > 88 * static_cast<std::size_t>(compressed_size))
    throw file_error(path, "binary_compressed: " + std::to_string(compressed_size) + " compressed bytes cannot hold " +
                               std::to_string(needed) + " uncompressed bytes (LZF expands at most 88-fold)");
}

// The binary body of a binary or binary_compressed PCD (sizes checked by check_binary_data_size);
// binary_compressed is LZF-decompressed into `storage`.
const char* pcd_binary_body(const std::string& path, const FileBytes& bytes, const PcdHeader& header,
                            std::unique_ptr<char[]>& storage) {
  const char* body = bytes.data.get() + header.body_offset;
  if (header.data != "binary_compressed") return body;
  const std::size_t needed = header.points * header.point_stride;
  std::uint32_t compressed_size = 0;
  std::memcpy(&compressed_size, body, 4);
  storage.reset(new char[needed > 0 ? needed : 1]);
  if (needed > 0) {
    const unsigned int produced =
        pcl::lzfDecompress(body + 8, compressed_size, storage.get(), static_cast<unsigned int>(needed));
    if (produced != needed)
      throw file_error(path, "binary_compressed: LZF data is corrupt (decompressed " + std::to_string(produced) + " of " +
                                 std::to_string(needed) + " bytes)");
  }
  return storage.get();
}

// DATA binary (point-major records) and binary_compressed (after LZF, field-major arrays: all x, then all y, ...).
void read_pcd_binary(const std::string& path, const FileBytes& bytes, const PcdHeader& header, PcdColumns& columns) {
  std::unique_ptr<char[]> decompressed;
  const char* data = pcd_binary_body(path, bytes, header, decompressed);
  const bool field_major = header.data == "binary_compressed";
  const std::size_t rows = header.points;
  std::size_t field_block = 0;  // start of the current field's array in field-major data
  std::vector<double> packed;
  for (std::size_t f = 0; f < header.fields.size(); ++f) {
    const PcdField& field = header.fields[f];
    const std::size_t element_stride = field_major ? field.size * field.count : header.point_stride;
    const char* base = field_major ? data + field_block : data + field.offset;
    field_block += rows * field.size * field.count;
    if (columns.targets[f].columns.empty()) continue;
    if (is_packed_color(field)) {
      packed.resize(rows);
      decode_strided(base, element_stride, rows, ScalarType::UInt32, false, packed.data());
      for (std::size_t row = 0; row < rows; ++row) columns.store_color(f, row, static_cast<std::uint32_t>(packed[row]));
      continue;
    }
    for (std::size_t c = 0; c < field.count; ++c)
      decode_strided(base + c * field.size, element_stride, rows, field.scalar, false,
                     columns.columns[columns.targets[f].columns[c]].values.data());
  }
}

}  // namespace

BinaryRecordLayout pcd_record_layout(const std::string& path, std::string_view text) {
  const PcdHeader header = parse_pcd_header(path, text);
  if (header.data != "binary")
    throw file_error(path, "is DATA " + header.data +
                               " PCD, which is not streamed (DATA binary is); read it whole or convert it to binary");
  BinaryRecordLayout layout;
  layout.encoding = header.data;
  layout.body_offset = header.body_offset;
  layout.record_size = header.point_stride;
  layout.records = header.points;
  for (const PcdField& field : header.fields) {
    if (field.name == "_" || is_packed_color(field)) continue;
    for (std::size_t c = 0; c < field.count; ++c)
      layout.fields.push_back({field.count == 1 ? field.name : field.name + "_" + std::to_string(c), field.scalar,
                               field.offset + c * field.size});
  }
  return layout;
}

PointCloud read_pcd_cloud(const std::string& path, const CloudReadOptions& options, CloudReadReport& report) {
  const FileBytes bytes = read_file_bytes(path);
  const PcdHeader header = parse_pcd_header(path, bytes.view());
  const bool ascii = header.data == "ascii";
  if (!ascii) check_binary_data_size(path, bytes, header);
  PcdColumns columns = pcd_columns(header, ascii ? 0 : header.points, report);
  if (header.data == "ascii") read_pcd_ascii(path, bytes, header, columns);
  else read_pcd_binary(path, bytes, header, columns);
  report.encoding = header.data;
  return assemble_cloud(path, columns.columns, header.points, options, report);
}

void write_pcd_cloud(const std::string& path, const PointCloud& cloud, bool binary) {
  const std::size_t n = cloud.size();
  const bool has_intensity = !cloud.intensity.empty(), has_labels = !cloud.labels.empty();
  const bool has_colors = !cloud.colors.empty();
  // A cloud kept relative to a local origin is written back in the file's frame, in double.
  const bool in_double = !cloud.local_origin.isZero(0.0);
  const std::size_t position_bytes = in_double ? 24 : 12;
  std::string fields = "FIELDS x y z", sizes = in_double ? "SIZE 8 8 8" : "SIZE 4 4 4", types = "TYPE F F F",
              counts = "COUNT 1 1 1";
  auto add = [&](const std::string& name, char type) {
    fields += " " + name;
    sizes += " 4";
    types += std::string(" ") + type;
    counts += " 1";
  };
  if (has_intensity) add("intensity", 'F');
  if (has_labels) add("label", 'U');
  if (has_colors) add("rgb", 'U');
  std::vector<const std::vector<float>*> extras;
  for (const auto& [name, values] : cloud.extra_fields) {
    add(name, 'F');
    extras.push_back(&values);
  }
  std::string header = "# .PCD v0.7 - Point Cloud Data file format (written by quadrix)\nVERSION 0.7\n" + fields +
                       "\n" + sizes + "\n" + types + "\n" + counts + "\nWIDTH " + std::to_string(n) +
                       "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + std::to_string(n) + "\nDATA " +
                       (binary ? "binary" : "ascii") + "\n";
  auto packed_color = [&](std::size_t i) {
    return (static_cast<std::uint32_t>(cloud.colors[i][0]) << 16) | (static_cast<std::uint32_t>(cloud.colors[i][1]) << 8) |
           static_cast<std::uint32_t>(cloud.colors[i][2]);
  };
  write_file_atomically(path, [&](std::ostream& stream) {
    stream.write(header.data(), static_cast<std::streamsize>(header.size()));
    const float* positions = cloud.positions.data();
    if (binary) {
      const std::size_t stride =
          position_bytes + 4 * ((has_intensity ? 1 : 0) + (has_labels ? 1 : 0) + (has_colors ? 1 : 0) + extras.size());
      std::string body(n * stride, '\0');
      char* cursor = body.data();
      for (std::size_t i = 0; i < n; ++i) {
        if (in_double) {
          const Eigen::Vector3d point = cloud.point_in_file_frame(i);
          std::memcpy(cursor, point.data(), 24);
        } else {
          std::memcpy(cursor, positions + 3 * i, 12);
        }
        cursor += position_bytes;
        if (has_intensity) (std::memcpy(cursor, &cloud.intensity[i], 4), cursor += 4);
        if (has_labels) (std::memcpy(cursor, &cloud.labels[i], 4), cursor += 4);
        if (has_colors) {
          const std::uint32_t color = packed_color(i);
          std::memcpy(cursor, &color, 4);
          cursor += 4;
        }
        for (const std::vector<float>* values : extras) (std::memcpy(cursor, &(*values)[i], 4), cursor += 4);
      }
      stream.write(body.data(), static_cast<std::streamsize>(body.size()));
      return;
    }
    std::string text;
    text.reserve(64 * 1024);
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d point = cloud.point_in_file_frame(i);
      for (int axis = 0; axis < 3; ++axis) {
        if (axis) text += ' ';
        if (in_double) append_number(text, point[axis]);
        else append_number(text, positions[3 * i + axis]);
      }
      if (has_intensity) (text += ' ', append_number(text, cloud.intensity[i]));
      if (has_labels) (text += ' ', append_number(text, static_cast<std::uint64_t>(cloud.labels[i])));
      if (has_colors) (text += ' ', append_number(text, static_cast<std::uint64_t>(packed_color(i))));
      for (const std::vector<float>* values : extras) (text += ' ', append_number(text, (*values)[i]));
      text += '\n';
      if (text.size() > 60 * 1024) {
        stream.write(text.data(), static_cast<std::streamsize>(text.size()));
        text.clear();
      }
    }
    stream.write(text.data(), static_cast<std::streamsize>(text.size()));
  });
}

}  // namespace io_internal
}  // namespace quadrix
