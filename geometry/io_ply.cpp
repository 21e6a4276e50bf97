// PLY: ascii, binary_little_endian and binary_big_endian reading (any numeric property type, other
// elements and list properties skipped), point-cloud and triangle-mesh writing.
#include "geometry/io.h"
#include "geometry/io_internal.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <ostream>

namespace quadrix {
namespace io_internal {

namespace {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the binary readers assume a little-endian machine");

enum class PlyEncoding { Ascii, BinaryLittleEndian, BinaryBigEndian };

struct PlyProperty {
  std::string name;
  bool is_list = false;
  ScalarType type = ScalarType::Float32;        // value type (item type for lists)
  ScalarType count_type = ScalarType::UInt8;    // list length type
};

struct PlyElement {
  std::string name;
  std::size_t count = 0;
  std::vector<PlyProperty> properties;
  bool has_list() const {
    return std::any_of(properties.begin(), properties.end(), [](const PlyProperty& p) { return p.is_list; });
  }
  std::size_t scalar_stride() const {
    std::size_t stride = 0;
    for (const PlyProperty& property : properties) stride += scalar_size(property.type);
    return stride;
  }
};

struct PlyHeader {
  PlyEncoding encoding = PlyEncoding::Ascii;
  std::string encoding_name;
  std::vector<PlyElement> elements;
  std::size_t body_offset = 0;       // first byte after end_header's newline
  std::size_t body_first_line = 0;   // line number of the first body line (ascii)
};

bool ply_type_from_name(std::string_view name, ScalarType& type) {
  static const std::pair<const char*, ScalarType> names[] = {
      {"char", ScalarType::Int8},     {"int8", ScalarType::Int8},       {"uchar", ScalarType::UInt8},
      {"uint8", ScalarType::UInt8},   {"short", ScalarType::Int16},     {"int16", ScalarType::Int16},
      {"ushort", ScalarType::UInt16}, {"uint16", ScalarType::UInt16},   {"int", ScalarType::Int32},
      {"int32", ScalarType::Int32},   {"uint", ScalarType::UInt32},     {"uint32", ScalarType::UInt32},
      {"float", ScalarType::Float32}, {"float32", ScalarType::Float32}, {"double", ScalarType::Float64},
      {"float64", ScalarType::Float64}};
  for (const auto& [text, value] : names) {
    if (name == text) {
      type = value;
      return true;
    }
  }
  return false;
}

PlyHeader parse_ply_header(const std::string& path, std::string_view text) {
  PlyHeader header;
  LineReader lines(text);
  std::string_view line;
  std::vector<std::string_view> tokens;
  if (!lines.next(line) || line != "ply")
    throw file_error(path, "bad magic: line 1 must be 'ply' (not a PLY file or corrupted header)");
  bool have_format = false;
  while (true) {
    if (!lines.next(line)) throw file_error(path, "header has no 'end_header' line (truncated or not a PLY file)");
    const std::string where = "header line " + std::to_string(lines.line_number()) + ": ";
    split_tokens(line, tokens);
    if (tokens.empty()) continue;
    const std::string_view keyword = tokens[0];
    if (keyword == "end_header") break;
    if (keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "format") {
      if (tokens.size() != 3) throw file_error(path, where + "expected 'format <encoding> 1.0'");
      if (tokens[1] == "ascii") {
        header.encoding = PlyEncoding::Ascii;
      } else if (tokens[1] == "binary_little_endian") {
        header.encoding = PlyEncoding::BinaryLittleEndian;
      } else if (tokens[1] == "binary_big_endian") {
        header.encoding = PlyEncoding::BinaryBigEndian;
      } else {
        throw file_error(path, where + "unknown encoding '" + std::string(tokens[1]) +
                                   "' (expected ascii, binary_little_endian or binary_big_endian)");
      }
      if (tokens[2] != "1.0") throw file_error(path, where + "unsupported PLY version '" + std::string(tokens[2]) + "' (expected 1.0)");
      header.encoding_name = std::string(tokens[1]);
      have_format = true;
    } else if (keyword == "element") {
      PlyElement element;
      if (tokens.size() != 3 || !parse_size(tokens[2], element.count))
        throw file_error(path, where + "expected 'element <name> <count>' with a non-negative integer count, got '" +
                                   std::string(line) + "'");
      element.name = std::string(tokens[1]);
      header.elements.push_back(std::move(element));
    } else if (keyword == "property") {
      if (header.elements.empty()) throw file_error(path, where + "'property' before any 'element'");
      PlyProperty property;
      std::string_view type_name;
      if (tokens.size() >= 2 && tokens[1] == "list") {
        if (tokens.size() != 5) throw file_error(path, where + "expected 'property list <count type> <item type> <name>'");
        property.is_list = true;
        if (!ply_type_from_name(tokens[2], property.count_type))
          throw file_error(path, where + "unknown property type '" + std::string(tokens[2]) +
                                     "' (expected char, uchar, short, ushort, int, uint, float, double or int8..float64)");
        if (scalar_is_floating(property.count_type))
          throw file_error(path, where + "list count type '" + std::string(tokens[2]) + "' must be an integer type");
        type_name = tokens[3];
        property.name = std::string(tokens[4]);
      } else {
        if (tokens.size() != 3) throw file_error(path, where + "expected 'property <type> <name>'");
        type_name = tokens[1];
        property.name = std::string(tokens[2]);
      }
      if (!ply_type_from_name(type_name, property.type))
        throw file_error(path, where + "unknown property type '" + std::string(type_name) + "' for property '" +
                                   property.name +
                                   "' (expected char, uchar, short, ushort, int, uint, float, double or int8..float64)");
      header.elements.back().properties.push_back(std::move(property));
    } else {
      throw file_error(path, where + "unknown header keyword '" + std::string(keyword) + "'");
    }
  }
  if (!have_format) throw file_error(path, "header has no 'format' line");
  header.body_offset = lines.position();
  header.body_first_line = lines.line_number() + 1;
  return header;
}

// Reads the body element by element. Scalar values of an element go to `outputs[p]` when that pointer is
// set (sized to the element count); the list property `list_index` (or -1) goes to `list_values`/`list_sizes`.
class PlyBodyReader {
 public:
  PlyBodyReader(const std::string& path, const PlyHeader& header, std::string_view text)
      : path_(path), header_(header), text_(text), position_(header.body_offset),
        lines_(text, header.body_offset, header.body_first_line) {}

  void read(const PlyElement& element, const std::vector<std::vector<double>*>& outputs, int list_index,
            std::vector<double>* list_values, std::vector<std::size_t>* list_sizes) {
    if (header_.encoding == PlyEncoding::Ascii) {
      read_ascii(element, outputs, list_index, list_values, list_sizes);
    } else {
      read_binary(element, outputs, list_index, list_values, list_sizes);
    }
  }

 private:
  [[noreturn]] void truncated(const PlyElement& element, std::size_t record) const {
    throw file_error(path_, "truncated: element '" + element.name + "' declares " + std::to_string(element.count) +
                                " records but the data ends in record " + std::to_string(record));
  }

  // Refuses a binary element count the rest of the file cannot hold, before anything is sized to it:
  // a record takes at least one scalar or list length per property.
  void check_binary_count_fits(const PlyElement& element) const {
    const std::size_t remaining = text_.size() - position_;
    std::size_t minimum = 0;
    for (const PlyProperty& property : element.properties)
      minimum += scalar_size(property.is_list ? property.count_type : property.type);
    if (minimum != 0 && element.count > remaining / minimum)
      throw file_error(path_, "truncated: element '" + element.name + "' needs " + std::to_string(element.count) +
                                  " records of " + (element.has_list() ? "at least " : "") + std::to_string(minimum) +
                                  " bytes but only " + std::to_string(remaining) + " bytes follow the header");
  }

  void read_binary(const PlyElement& element, const std::vector<std::vector<double>*>& outputs, int list_index,
                   std::vector<double>* list_values, std::vector<std::size_t>* list_sizes) {
    const bool swap = header_.encoding == PlyEncoding::BinaryBigEndian;
    check_binary_count_fits(element);
    if (!element.has_list()) {
      const std::size_t stride = element.scalar_stride();  // the whole element fits: check_binary_count_fits
      std::size_t offset = 0;
      for (std::size_t p = 0; p < element.properties.size(); ++p) {
        if (p < outputs.size() && outputs[p]) {
          outputs[p]->resize(element.count);
          decode_strided(text_.data() + position_ + offset, stride, element.count, element.properties[p].type, swap,
                         outputs[p]->data());
        }
        offset += scalar_size(element.properties[p].type);
      }
      position_ += element.count * stride;
      return;
    }
    for (std::size_t p = 0; p < outputs.size(); ++p)
      if (outputs[p]) outputs[p]->resize(element.count);
    for (std::size_t record = 0; record < element.count; ++record) {
      for (std::size_t p = 0; p < element.properties.size(); ++p) {
        const PlyProperty& property = element.properties[p];
        if (!property.is_list) {
          const std::size_t size = scalar_size(property.type);
          if (text_.size() - position_ < size) truncated(element, record);
          if (p < outputs.size() && outputs[p])
            decode_strided(text_.data() + position_, size, 1, property.type, swap, outputs[p]->data() + record);
          position_ += size;
          continue;
        }
        const std::size_t count_size = scalar_size(property.count_type);
        if (text_.size() - position_ < count_size) truncated(element, record);
        double length_value = 0;
        decode_strided(text_.data() + position_, count_size, 1, property.count_type, swap, &length_value);
        position_ += count_size;
        if (length_value < 0)
          throw file_error(path_, "element '" + element.name + "' record " + std::to_string(record) + ": list '" +
                                      property.name + "' has negative length " + std::to_string(length_value));
        const std::size_t length = static_cast<std::size_t>(length_value);
        const std::size_t item_size = scalar_size(property.type);
        if ((text_.size() - position_) / item_size < length) truncated(element, record);
        if (static_cast<int>(p) == list_index) {
          const std::size_t start = list_values->size();
          list_values->resize(start + length);
          decode_strided(text_.data() + position_, item_size, length, property.type, swap, list_values->data() + start);
          list_sizes->push_back(length);
        }
        position_ += length * item_size;
      }
    }
  }

  // Values are appended line by line (never sized to the header's count first, which the file may not hold).
  void read_ascii(const PlyElement& element, const std::vector<std::vector<double>*>& outputs, int list_index,
                  std::vector<double>* list_values, std::vector<std::size_t>* list_sizes) {
    for (std::size_t p = 0; p < outputs.size(); ++p)
      if (outputs[p]) outputs[p]->clear();
    std::string_view line;
    for (std::size_t record = 0; record < element.count; ++record) {
      do {
        if (!lines_.next(line)) truncated(element, record);
        split_tokens(line, tokens_);
      } while (tokens_.empty());
      const std::string where = "line " + std::to_string(lines_.line_number()) + ": ";
      std::size_t token = 0;
      auto next_number = [&](const PlyProperty& property) {
        if (token >= tokens_.size())
          throw file_error(path_, where + "too few values for element '" + element.name + "' (property '" +
                                      property.name + "' missing)");
        double value = 0;
        if (!parse_double(tokens_[token], value))
          throw file_error(path_, where + "'" + std::string(tokens_[token]) + "' is not a number (property '" +
                                      property.name + "')");
        ++token;
        return value;
      };
      for (std::size_t p = 0; p < element.properties.size(); ++p) {
        const PlyProperty& property = element.properties[p];
        if (!property.is_list) {
          const double value = next_number(property);
          if (p < outputs.size() && outputs[p]) outputs[p]->push_back(value);
          continue;
        }
        const double length_value = next_number(property);
        if (!(length_value >= 0 && length_value == std::floor(length_value)))
          throw file_error(path_, where + "list '" + property.name + "' length '" + std::to_string(length_value) +
                                      "' is not a non-negative integer");
        if (length_value > static_cast<double>(tokens_.size() - token))
          throw file_error(path_, where + "list '" + property.name + "' length " + std::string(tokens_[token - 1]) +
                                      " exceeds the " + std::to_string(tokens_.size() - token) +
                                      " values left on the line");
        const std::size_t length = static_cast<std::size_t>(length_value);
        for (std::size_t k = 0; k < length; ++k) {
          const double value = next_number(property);
          if (static_cast<int>(p) == list_index) list_values->push_back(value);
        }
        if (static_cast<int>(p) == list_index) list_sizes->push_back(length);
      }
      if (token != tokens_.size())
        throw file_error(path_, where + "element '" + element.name + "' has " + std::to_string(tokens_.size()) +
                                    " values on this line, expected " + std::to_string(token));
    }
  }

  const std::string& path_;
  const PlyHeader& header_;
  std::string_view text_;
  std::size_t position_;
  LineReader lines_;
  std::vector<std::string_view> tokens_;
};

const PlyElement& find_vertex_element(const std::string& path, const PlyHeader& header, std::size_t& index) {
  for (index = 0; index < header.elements.size(); ++index)
    if (header.elements[index].name == "vertex") return header.elements[index];
  throw file_error(path, "has no 'vertex' element");
}

void write_text_header(std::string& out, const std::string& encoding, std::size_t vertices) {
  out += "ply\nformat " + encoding + " 1.0\ncomment written by quadrix\nelement vertex ";
  append_number(out, static_cast<std::uint64_t>(vertices));
  out += '\n';
}

template <typename T>
void put(char*& cursor, T value) {
  std::memcpy(cursor, &value, sizeof(T));
  cursor += sizeof(T);
}

}  // namespace

BinaryRecordLayout ply_record_layout(const std::string& path, std::string_view text) {
  const PlyHeader header = parse_ply_header(path, text);
  if (header.encoding == PlyEncoding::Ascii)
    throw file_error(path, "is ascii PLY, which is not streamed (binary PLY is); read it whole or convert it to binary");
  std::size_t vertex_index = 0;
  const PlyElement& vertex = find_vertex_element(path, header, vertex_index);
  BinaryRecordLayout layout;
  layout.encoding = header.encoding_name;
  layout.swap_bytes = header.encoding == PlyEncoding::BinaryBigEndian;
  layout.body_offset = header.body_offset;
  for (std::size_t e = 0; e <= vertex_index; ++e) {
    const PlyElement& element = header.elements[e];
    if (element.has_list())
      throw file_error(path, "element '" + element.name + "' has list properties" +
                                 (e < vertex_index ? " and comes before 'vertex'" : "") +
                                 ": its records vary in size, so the vertices cannot be streamed; read the file whole");
    if (e == vertex_index) break;
    const std::size_t stride = element.scalar_stride();
    if (stride != 0 && element.count > (std::numeric_limits<std::size_t>::max() - layout.body_offset) / stride)
      throw file_error(path, "element '" + element.name + "' declares " + std::to_string(element.count) +
                                 " records, more than any file holds");
    layout.body_offset += element.count * stride;
  }
  layout.records = vertex.count;
  layout.record_size = vertex.scalar_stride();
  std::size_t offset = 0;
  for (const PlyProperty& property : vertex.properties) {
    layout.fields.push_back({property.name, property.type, offset});
    offset += scalar_size(property.type);
  }
  return layout;
}

PointCloud read_ply_cloud(const std::string& path, const CloudReadOptions& options, CloudReadReport& report) {
  const FileBytes bytes = read_file_bytes(path);
  const PlyHeader header = parse_ply_header(path, bytes.view());
  std::size_t vertex_index = 0;
  const PlyElement& vertex = find_vertex_element(path, header, vertex_index);
  PlyBodyReader body(path, header, bytes.view());
  for (std::size_t e = 0; e < vertex_index; ++e) body.read(header.elements[e], {}, -1, nullptr, nullptr);

  std::vector<FieldColumn> columns;
  columns.reserve(vertex.properties.size());
  std::vector<std::vector<double>*> outputs(vertex.properties.size(), nullptr);
  report.fields.clear();
  for (const PlyProperty& property : vertex.properties) {
    if (property.is_list) continue;
    FieldColumn column;
    column.name = property.name;
    column.floating_point = scalar_is_floating(property.type);
    columns.push_back(std::move(column));
    report.fields.push_back(property.name);
  }
  for (std::size_t p = 0, c = 0; p < vertex.properties.size(); ++p)
    if (!vertex.properties[p].is_list) outputs[p] = &columns[c++].values;
  body.read(vertex, outputs, -1, nullptr, nullptr);
  report.encoding = header.encoding_name;
  return assemble_cloud(path, columns, vertex.count, options, report);
}

void write_ply_cloud(const std::string& path, const PointCloud& cloud, bool binary) {
  const std::size_t n = cloud.size();
  const bool has_intensity = !cloud.intensity.empty(), has_labels = !cloud.labels.empty();
  const bool has_colors = !cloud.colors.empty();
  std::vector<const std::vector<float>*> extras;
  std::string header;
  write_text_header(header, binary ? "binary_little_endian" : "ascii", n);
  // A cloud kept relative to a local origin is written back in the file's frame, in double.
  const bool in_double = !cloud.local_origin.isZero(0.0);
  const std::size_t position_bytes = in_double ? 24 : 12;
  header += in_double ? "property double x\nproperty double y\nproperty double z\n"
                      : "property float x\nproperty float y\nproperty float z\n";
  if (has_intensity) header += "property float intensity\n";
  if (has_labels) header += "property uint label\n";
  if (has_colors) header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  for (const auto& [name, values] : cloud.extra_fields) {
    header += "property float " + name + "\n";
    extras.push_back(&values);
  }
  header += "end_header\n";
  write_file_atomically(path, [&](std::ostream& stream) {
    stream.write(header.data(), static_cast<std::streamsize>(header.size()));
    const float* positions = cloud.positions.data();
    if (binary) {
      const std::size_t stride = position_bytes + (has_intensity ? 4 : 0) + (has_labels ? 4 : 0) +
                                 (has_colors ? 3 : 0) + 4 * extras.size();
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
        if (has_intensity) put(cursor, cloud.intensity[i]);
        if (has_labels) put(cursor, cloud.labels[i]);
        if (has_colors) {
          std::memcpy(cursor, cloud.colors[i].data(), 3);
          cursor += 3;
        }
        for (const std::vector<float>* values : extras) put(cursor, (*values)[i]);
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
      if (has_colors)
        for (int c = 0; c < 3; ++c) (text += ' ', append_number(text, static_cast<std::uint64_t>(cloud.colors[i][c])));
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

void write_mesh_ply(const std::string& path, const TriangleMesh& mesh) {
  const std::size_t n = static_cast<std::size_t>(mesh.vertices.cols());
  const bool has_colors = !mesh.colors.empty();
  if (has_colors && mesh.colors.size() != n)
    throw file_error(path, "cannot write mesh: " + std::to_string(mesh.colors.size()) + " colours for " +
                               std::to_string(n) + " vertices");
  for (std::size_t i = 0; i < n; ++i)
    if (!mesh.vertices.col(static_cast<Eigen::Index>(i)).allFinite())
      throw file_error(path, "cannot write mesh: vertex " + std::to_string(i) + " is not finite");
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int corner = 0; corner < 3; ++corner)
      if (mesh.triangles[t][corner] < 0 || static_cast<std::size_t>(mesh.triangles[t][corner]) >= n)
        throw file_error(path, "cannot write mesh: triangle " + std::to_string(t) + " uses vertex " +
                                   std::to_string(mesh.triangles[t][corner]) + " of " + std::to_string(n));
  std::string header;
  io_internal::write_text_header(header, "binary_little_endian", n);
  header += "property double x\nproperty double y\nproperty double z\n";
  if (has_colors) header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  header += "element face ";
  io_internal::append_number(header, static_cast<std::uint64_t>(mesh.triangles.size()));
  header += "\nproperty list uchar int vertex_indices\nend_header\n";
  write_file_atomically(path, [&](std::ostream& stream) {
    stream.write(header.data(), static_cast<std::streamsize>(header.size()));
    const std::size_t vertex_stride = 24 + (has_colors ? 3 : 0);
    std::string body(n * vertex_stride + mesh.triangles.size() * 13, '\0');
    char* cursor = body.data();
    for (std::size_t i = 0; i < n; ++i) {
      for (int axis = 0; axis < 3; ++axis) io_internal::put(cursor, mesh.vertices(axis, static_cast<Eigen::Index>(i)));
      if (has_colors) {
        std::memcpy(cursor, mesh.colors[i].data(), 3);
        cursor += 3;
      }
    }
    for (const Eigen::Vector3i& triangle : mesh.triangles) {
      io_internal::put(cursor, static_cast<std::uint8_t>(3));
      for (int corner = 0; corner < 3; ++corner) io_internal::put(cursor, static_cast<std::int32_t>(triangle[corner]));
    }
    stream.write(body.data(), static_cast<std::streamsize>(body.size()));
  });
}

TriangleMesh read_mesh_ply(const std::string& path) {
  using namespace io_internal;
  const FileBytes bytes = read_file_bytes(path);
  const PlyHeader header = parse_ply_header(path, bytes.view());
  std::size_t vertex_index = 0;
  const PlyElement& vertex = find_vertex_element(path, header, vertex_index);
  PlyBodyReader body(path, header, bytes.view());
  TriangleMesh mesh;
  std::vector<std::vector<double>> vertex_columns(vertex.properties.size());
  std::vector<double> face_values;
  std::vector<std::size_t> face_sizes;
  bool have_faces = false;
  for (const PlyElement& element : header.elements) {
    if (&element == &vertex) {
      std::vector<std::vector<double>*> outputs(vertex.properties.size(), nullptr);
      for (std::size_t p = 0; p < vertex.properties.size(); ++p)
        if (!vertex.properties[p].is_list) outputs[p] = &vertex_columns[p];
      body.read(element, outputs, -1, nullptr, nullptr);
    } else if (element.name == "face" && !have_faces) {
      int list_index = -1;
      for (std::size_t p = 0; p < element.properties.size(); ++p)
        if (element.properties[p].is_list &&
            (element.properties[p].name == "vertex_indices" || element.properties[p].name == "vertex_index"))
          list_index = static_cast<int>(p);
      if (list_index < 0) throw file_error(path, "element 'face' has no list property 'vertex_indices'");
      body.read(element, {}, list_index, &face_values, &face_sizes);
      have_faces = true;
    } else {
      body.read(element, {}, -1, nullptr, nullptr);
    }
  }
  auto column_named = [&](std::initializer_list<const char*> names) -> int {
    for (std::size_t p = 0; p < vertex.properties.size(); ++p)
      for (const char* name : names)
        if (!vertex.properties[p].is_list && vertex.properties[p].name == name) return static_cast<int>(p);
    return -1;
  };
  const int axes[3] = {column_named({"x"}), column_named({"y"}), column_named({"z"})};
  for (int axis = 0; axis < 3; ++axis)
    if (axes[axis] < 0) throw file_error(path, std::string("vertex element has no '") + "xyz"[axis] + "' property");
  mesh.vertices.resize(3, static_cast<Eigen::Index>(vertex.count));
  for (std::size_t i = 0; i < vertex.count; ++i) {
    for (int axis = 0; axis < 3; ++axis) mesh.vertices(axis, static_cast<Eigen::Index>(i)) = vertex_columns[axes[axis]][i];
    if (!mesh.vertices.col(static_cast<Eigen::Index>(i)).allFinite())
      throw file_error(path, "mesh vertex " + std::to_string(i) + " is not finite (NaN/inf); a mesh cannot drop vertices");
  }
  const int channels[3] = {column_named({"red", "diffuse_red"}), column_named({"green", "diffuse_green"}),
                           column_named({"blue", "diffuse_blue"})};
  if (channels[0] >= 0 && channels[1] >= 0 && channels[2] >= 0) {
    bool unit_range = true;
    for (int c = 0; c < 3; ++c) {
      if (!scalar_is_floating(vertex.properties[channels[c]].type)) unit_range = false;
      for (double value : vertex_columns[channels[c]]) unit_range = unit_range && value <= 1.0;
    }
    mesh.colors.resize(vertex.count);
    for (std::size_t i = 0; i < vertex.count; ++i)
      for (int c = 0; c < 3; ++c) {
        const double value = vertex_columns[channels[c]][i] * (unit_range ? 255.0 : 1.0);
        mesh.colors[i][c] = static_cast<std::uint8_t>(std::lround(std::clamp(std::isfinite(value) ? value : 0.0, 0.0, 255.0)));
      }
  }
  std::size_t offset = 0;
  for (std::size_t f = 0; f < face_sizes.size(); ++f) {
    const std::size_t corners = face_sizes[f];
    if (corners < 3) throw file_error(path, "face " + std::to_string(f) + " has " + std::to_string(corners) + " corners (need 3 or more)");
    for (std::size_t k = 0; k < corners; ++k) {
      const double index = face_values[offset + k];
      if (!(index >= 0 && index < static_cast<double>(vertex.count) && index == std::floor(index)))
        throw file_error(path, "face " + std::to_string(f) + " uses vertex index " + std::to_string(index) + " but there are " +
                                   std::to_string(vertex.count) + " vertices");
    }
    for (std::size_t k = 1; k + 1 < corners; ++k)
      mesh.triangles.emplace_back(static_cast<int>(face_values[offset]), static_cast<int>(face_values[offset + k]),
                                  static_cast<int>(face_values[offset + k + 1]));
    offset += corners;
  }
  return mesh;
}

}  // namespace quadrix
