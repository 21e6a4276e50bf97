// SceneModel: class names and types (REFERENCE.md "Class -> quadric type"), validation, and the
// binary and JSON file formats (paper Struct. 1 records, 21 numbers each).
#include "fitting/scene_model.h"
#include "fitting/shape_parameters.h"

#include "geometry/error.h"
#include "geometry/io.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>

namespace quadrix {

std::string element_class_name(ElementClass element_class) {
  switch (element_class) {
    case ElementClass::Ground: return "ground";
    case ElementClass::Plane: return "plane";
    case ElementClass::Line: return "line";
    case ElementClass::Object: return "object";
    case ElementClass::Vehicle: return "vehicle";
    case ElementClass::Trunk: return "trunk";
    case ElementClass::Vegetation: return "vegetation";
    case ElementClass::Cylinder: return "cylinder";
    case ElementClass::Sphere: return "sphere";
    case ElementClass::Cone: return "cone";
  }
  throw Error("element_class_name: unknown element class " + std::to_string(static_cast<std::uint32_t>(element_class)));
}

QuadricType quadric_type_for_class(ElementClass element_class) {
  switch (element_class) {
    case ElementClass::Ground: return QuadricType::Plane;
    case ElementClass::Plane: return QuadricType::Plane;
    case ElementClass::Line: return QuadricType::Line;
    case ElementClass::Object: return QuadricType::Ellipsoid;
    case ElementClass::Vehicle: return QuadricType::Ellipsoid;
    case ElementClass::Trunk: return QuadricType::EllipticCylinder;
    case ElementClass::Vegetation: return QuadricType::Ellipsoid;
    case ElementClass::Cylinder: return QuadricType::CircularCylinder;
    case ElementClass::Sphere: return QuadricType::Sphere;
    case ElementClass::Cone: return QuadricType::CircularCone;
  }
  throw Error("quadric_type_for_class: unknown element class " +
              std::to_string(static_cast<std::uint32_t>(element_class)));
}

const std::vector<ElementClass>& all_element_classes() {
  static const std::vector<ElementClass> classes = {
      ElementClass::Ground,  ElementClass::Plane,      ElementClass::Line,     ElementClass::Object,
      ElementClass::Vehicle, ElementClass::Trunk,      ElementClass::Vegetation, ElementClass::Cylinder,
      ElementClass::Sphere,  ElementClass::Cone};
  return classes;
}

ElementClass element_class_from_label(std::uint32_t label) {
  for (const ElementClass element_class : all_element_classes())
    if (static_cast<std::uint32_t>(element_class) == label) return element_class;
  throw Error("element class label " + std::to_string(label) + " is not one of 1..10 (ground .. cone)");
}

ElementClass element_class_from_name(const std::string& name) {
  std::string valid;
  for (const ElementClass element_class : all_element_classes()) {
    if (element_class_name(element_class) == name) return element_class;
    valid += (valid.empty() ? "" : ", ") + element_class_name(element_class);
  }
  throw Error("unknown element class '" + name + "' (expected one of: " + valid + ")");
}

namespace {

bool finite_record(const QuadricRecord& record) {
  for (const double value : record.to_array())
    if (!std::isfinite(value)) return false;
  return true;
}

}  // namespace

SceneModel translated(SceneModel model, const Eigen::Vector3d& offset) {
  if (!offset.allFinite()) throw Error("translated: the offset must be finite");
  Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
  motion.translation() = offset;
  for (QuadricRecord& record : model.records) {
    record.q = record.quadric().transformed(motion).normalized().parameters();
    record.full_center += offset;
  }
  if (model.has_ground) model.ground_offset -= model.ground_normal.dot(offset);
  return model;
}

SceneModel scaled(SceneModel model, double factor) {
  if (!(factor > 0.0) || !std::isfinite(factor)) throw Error("scaled: the factor must be finite and positive");
  // x' = S x with S = diag(f, f, f, 1): x'^T (S^-T Q S^-1) x' = x^T Q x.
  const Eigen::Vector4d inverse(1.0 / factor, 1.0 / factor, 1.0 / factor, 1.0);
  for (QuadricRecord& record : model.records) {
    const Eigen::Matrix4d matrix = inverse.asDiagonal() * record.quadric().matrix() * inverse.asDiagonal();
    record.q = Quadric(matrix).normalized().parameters();
    record.full_center *= factor;
    record.full_scale *= factor;
  }
  if (model.has_ground) model.ground_offset *= factor;
  return model;
}

void validate_scene_model(const SceneModel& model) {
  const std::size_t count = model.records.size();
  if (model.types.size() != count)
    throw Error("scene model: types has " + std::to_string(model.types.size()) + " entries, expected one per record (" +
                std::to_string(count) + ")");
  if (model.element_point_counts.size() != count)
    throw Error("scene model: element_point_counts has " + std::to_string(model.element_point_counts.size()) +
                " entries, expected one per record (" + std::to_string(count) + ")");
  if (model.augmented_begin > count)
    throw Error("scene model: augmented_begin " + std::to_string(model.augmented_begin) + " exceeds the record count " +
                std::to_string(count));
  if (model.source_point_count > kMaxExactSourcePoints)
    throw Error("scene model: source_point_count " + std::to_string(model.source_point_count) +
                " exceeds 2^53, the largest count the JSON format holds exactly");
  const std::size_t augmented = count - model.augmented_begin;
  if (!model.augmented_descriptors.empty() && model.augmented_descriptors.size() != augmented)
    throw Error("scene model: augmented_descriptors has " + std::to_string(model.augmented_descriptors.size()) +
                " entries, expected 0 or one per augmented point (" + std::to_string(augmented) + ")");
  for (std::size_t index = 0; index < count; ++index) {
    if (!finite_record(model.records[index]))
      throw Error("scene model: record " + std::to_string(index) + " has a non-finite number");
    element_class_from_label(model.records[index].label);
    if (static_cast<int>(model.types[index]) > static_cast<int>(QuadricType::Invalid))
      throw Error("scene model: record " + std::to_string(index) + " has an unknown quadric type");
  }
  if (!model.ground_normal.allFinite() || !std::isfinite(model.ground_offset))
    throw Error("scene model: ground normal or offset is not finite");
  for (std::size_t index = 0; index < model.augmented_descriptors.size(); ++index)
    for (const float value : model.augmented_descriptors[index])
      if (!std::isfinite(value))
        throw Error("scene model: augmented descriptor " + std::to_string(index) + " has a non-finite number");
  for (const auto& [name, milliseconds] : model.timings_ms)
    if (!std::isfinite(milliseconds)) throw Error("scene model: timing '" + name + "' is not finite");
}

// ---------------------------------------------------------------------------------------------
// Binary format (documented at kSceneModelBinaryVersion).

std::uint32_t scene_model_binary_checksum(const char* data, std::size_t size) {
  std::uint32_t hash = 2166136261u;
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= static_cast<std::uint8_t>(data[i]);
    hash *= 16777619u;
  }
  return hash;
}

namespace {

constexpr char kMagic[8] = {'Q', 'D', 'X', 'S', 'C', 'E', 'N', 'E'};

class LittleEndianWriter {
 public:
  void bytes(const void* data, std::size_t size) { buffer_.append(static_cast<const char*>(data), size); }
  template <typename Unsigned>
  void unsigned_integer(Unsigned value) {
    for (std::size_t i = 0; i < sizeof(Unsigned); ++i) buffer_.push_back(static_cast<char>((value >> (8 * i)) & 0xFFu));
  }
  void float64(double value) {
    std::uint64_t bits;
    std::memcpy(&bits, &value, sizeof bits);
    unsigned_integer(bits);
  }
  void float32(float value) {
    std::uint32_t bits;
    std::memcpy(&bits, &value, sizeof bits);
    unsigned_integer(bits);
  }
  std::string& buffer() { return buffer_; }

 private:
  std::string buffer_;
};

class LittleEndianReader {
 public:
  LittleEndianReader(const std::string& bytes, std::size_t end, std::string source)
      : bytes_(bytes), end_(end), source_(std::move(source)) {}
  void need(std::size_t size, const std::string& field) const {
    if (end_ - position_ < size)
      throw file_error(source_, "truncated scene model: " + field + " needs " + std::to_string(size) +
                                    " bytes at offset " + std::to_string(position_) + ", only " +
                                    std::to_string(end_ - position_) + " left");
  }
  template <typename Unsigned>
  Unsigned unsigned_integer(const std::string& field) {
    need(sizeof(Unsigned), field);
    Unsigned value = 0;
    for (std::size_t i = 0; i < sizeof(Unsigned); ++i)
      value |= static_cast<Unsigned>(static_cast<std::uint8_t>(bytes_[position_ + i])) << (8 * i);
    position_ += sizeof(Unsigned);
    return value;
  }
  double float64(const std::string& field) {
    const std::uint64_t bits = unsigned_integer<std::uint64_t>(field);
    double value;
    std::memcpy(&value, &bits, sizeof value);
    return value;
  }
  float float32(const std::string& field) {
    const std::uint32_t bits = unsigned_integer<std::uint32_t>(field);
    float value;
    std::memcpy(&value, &bits, sizeof value);
    return value;
  }
  std::string text(std::size_t size, const std::string& field) {
    need(size, field);
    std::string value = bytes_.substr(position_, size);
    position_ += size;
    return value;
  }
  std::size_t remaining() const { return end_ - position_; }
  std::size_t position() const { return position_; }

 private:
  const std::string& bytes_;
  std::size_t end_;
  std::size_t position_ = 0;
  std::string source_;
};

}  // namespace

std::string scene_model_to_binary(const SceneModel& model) {
  validate_scene_model(model);
  LittleEndianWriter writer;
  writer.bytes(kMagic, sizeof kMagic);
  writer.unsigned_integer<std::uint32_t>(kSceneModelBinaryVersion);
  writer.unsigned_integer<std::uint64_t>(model.records.size());
  writer.unsigned_integer<std::uint64_t>(model.augmented_begin);
  writer.unsigned_integer<std::uint64_t>(model.source_point_count);
  writer.unsigned_integer<std::uint8_t>(model.has_ground ? 1 : 0);
  for (int axis = 0; axis < 3; ++axis) writer.float64(model.ground_normal(axis));
  writer.float64(model.ground_offset);
  for (std::size_t index = 0; index < model.records.size(); ++index) {
    for (const double value : model.records[index].to_array()) writer.float64(value);
    writer.unsigned_integer<std::uint8_t>(static_cast<std::uint8_t>(model.types[index]));
    writer.unsigned_integer<std::uint32_t>(model.element_point_counts[index]);
  }
  writer.unsigned_integer<std::uint64_t>(model.augmented_descriptors.size());
  for (const auto& descriptor : model.augmented_descriptors)
    for (const float value : descriptor) writer.float32(value);
  writer.unsigned_integer<std::uint32_t>(static_cast<std::uint32_t>(model.timings_ms.size()));
  for (const auto& [name, milliseconds] : model.timings_ms) {
    writer.unsigned_integer<std::uint32_t>(static_cast<std::uint32_t>(name.size()));
    writer.bytes(name.data(), name.size());
    writer.float64(milliseconds);
  }
  const std::uint32_t checksum = scene_model_binary_checksum(writer.buffer().data(), writer.buffer().size());
  writer.unsigned_integer<std::uint32_t>(checksum);
  return std::move(writer.buffer());
}

SceneModel scene_model_from_binary(const std::string& bytes, const std::string& source_name) {
  if (bytes.size() < sizeof kMagic + 4 || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    throw file_error(source_name, "not a quadrix scene model: expected the magic bytes \"QDXSCENE\" at offset 0");
  if (bytes.size() < sizeof kMagic + 8)
    throw file_error(source_name, "truncated scene model: no room for the version and checksum");
  const std::size_t payload = bytes.size() - 4;
  LittleEndianReader reader(bytes, bytes.size(), source_name);
  reader.text(sizeof kMagic, "magic");
  const std::uint32_t version = reader.unsigned_integer<std::uint32_t>("version");
  if (version != kSceneModelBinaryVersion)
    throw file_error(source_name, "scene model version " + std::to_string(version) + " is not supported (expected " +
                                      std::to_string(kSceneModelBinaryVersion) + ")");
  std::uint32_t stored_checksum = 0;
  for (int i = 0; i < 4; ++i)
    stored_checksum |= static_cast<std::uint32_t>(static_cast<std::uint8_t>(bytes[payload + i])) << (8 * i);
  LittleEndianReader body(bytes, payload, source_name);
  body.text(sizeof kMagic + 4, "header");

  SceneModel model;
  const std::uint64_t count = body.unsigned_integer<std::uint64_t>("record count");
  constexpr std::size_t kRecordBytes = 21 * 8 + 1 + 4;
  if (count > body.remaining() / kRecordBytes)
    throw file_error(source_name, "record count " + std::to_string(count) + " does not fit in the file (" +
                                      std::to_string(bytes.size()) + " bytes); the file is truncated or corrupted");
  model.augmented_begin = body.unsigned_integer<std::uint64_t>("augmented_begin");
  model.source_point_count = body.unsigned_integer<std::uint64_t>("source_point_count");
  const std::uint8_t has_ground = body.unsigned_integer<std::uint8_t>("has_ground");
  if (has_ground > 1) throw file_error(source_name, "has_ground must be 0 or 1, found " + std::to_string(has_ground));
  model.has_ground = has_ground == 1;
  for (int axis = 0; axis < 3; ++axis) model.ground_normal(axis) = body.float64("ground_normal");
  model.ground_offset = body.float64("ground_offset");
  model.records.reserve(count);
  for (std::uint64_t index = 0; index < count; ++index) {
    const std::string field = "record " + std::to_string(index);
    std::array<double, 21> values;
    for (double& value : values) value = body.float64(field);
    const std::uint8_t type = body.unsigned_integer<std::uint8_t>(field + " type");
    if (type > static_cast<std::uint8_t>(QuadricType::Invalid))
      throw file_error(source_name, field + ": quadric type code " + std::to_string(type) + " is not 0.." +
                                        std::to_string(static_cast<int>(QuadricType::Invalid)));
    const std::uint32_t points = body.unsigned_integer<std::uint32_t>(field + " point count");
    try {
      model.records.push_back(QuadricRecord::from_array(values));
    } catch (const Error& error) {
      throw file_error(source_name, field + ": " + error.what());
    }
    model.types.push_back(static_cast<QuadricType>(type));
    model.element_point_counts.push_back(points);
  }
  const std::uint64_t descriptor_count = body.unsigned_integer<std::uint64_t>("descriptor count");
  if (descriptor_count > body.remaining() / (4 * kFpfhSize))
    throw file_error(source_name, "descriptor count " + std::to_string(descriptor_count) +
                                      " does not fit in the file; the file is truncated or corrupted");
  model.augmented_descriptors.resize(descriptor_count);
  for (auto& descriptor : model.augmented_descriptors)
    for (float& value : descriptor) value = body.float32("augmented descriptor");
  const std::uint32_t timing_count = body.unsigned_integer<std::uint32_t>("timing count");
  for (std::uint32_t index = 0; index < timing_count; ++index) {
    const std::uint32_t length = body.unsigned_integer<std::uint32_t>("timing name length");
    const std::string name = body.text(length, "timing name");
    model.timings_ms[name] = body.float64("timing value");
  }
  if (body.remaining() != 0)
    throw file_error(source_name, std::to_string(body.remaining()) + " unexpected bytes after the timings at offset " +
                                      std::to_string(body.position()));
  const std::uint32_t checksum = scene_model_binary_checksum(bytes.data(), payload);
  if (checksum != stored_checksum)
    throw file_error(source_name, "checksum mismatch (stored " + std::to_string(stored_checksum) + ", computed " +
                                      std::to_string(checksum) + "): the file is corrupted");
  try {
    validate_scene_model(model);
  } catch (const Error& error) {
    throw file_error(source_name, error.what());
  }
  return model;
}

void write_scene_model_binary(const std::string& path, const SceneModel& model) {
  const std::string bytes = scene_model_to_binary(model);
  write_file_atomically(path, [&](std::ostream& stream) { stream.write(bytes.data(), static_cast<std::streamsize>(bytes.size())); });
}

namespace {

std::string read_whole_file(const std::string& path) {
  std::ifstream stream(path, std::ios::binary);
  if (!stream) throw file_error(path, "cannot open for reading");
  std::string bytes((std::istreambuf_iterator<char>(stream)), std::istreambuf_iterator<char>());
  if (stream.bad()) throw file_error(path, "read error");
  return bytes;
}

}  // namespace

SceneModel read_scene_model_binary(const std::string& path) { return scene_model_from_binary(read_whole_file(path), path); }

// ---------------------------------------------------------------------------------------------
// JSON: a small writer and a strict reader for the subset the writer emits (RFC 8259 values).

namespace {

std::string json_number(double value) {
  if (!std::isfinite(value)) throw Error("scene model JSON: cannot write a non-finite number");
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", value);
  return buffer;
}

std::string json_string(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buffer[8];
      std::snprintf(buffer, sizeof buffer, "\\u%04x", static_cast<unsigned>(static_cast<unsigned char>(c)));
      out += buffer;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

template <typename Range>
std::string json_array(const Range& values) {
  std::string out = "[";
  bool first = true;
  for (const auto value : values) {
    out += (first ? "" : ", ") + json_number(static_cast<double>(value));
    first = false;
  }
  return out + "]";
}

struct JsonValue {
  enum class Kind { Null, Boolean, Number, String, Array, Object } kind = Kind::Null;
  bool boolean = false;
  double number = 0.0;
  std::string text;
  std::vector<JsonValue> items;
  std::vector<std::pair<std::string, JsonValue>> members;

  const JsonValue* find(const std::string& key) const {
    for (const auto& [name, value] : members)
      if (name == key) return &value;
    return nullptr;
  }
};

class JsonParser {
 public:
  JsonParser(const std::string& text, std::string source) : text_(text), source_(std::move(source)) {}

  JsonValue parse_document() {
    JsonValue value = parse_value(0);
    skip_space();
    if (position_ != text_.size()) fail("unexpected text after the JSON document");
    return value;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    std::size_t line = 1;
    for (std::size_t i = 0; i < position_ && i < text_.size(); ++i) line += text_[i] == '\n';
    throw file_error(source_, "line " + std::to_string(line) + ": " + what);
  }
  void skip_space() {
    while (position_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[position_]))) ++position_;
  }
  bool consume(char c) {
    skip_space();
    if (position_ < text_.size() && text_[position_] == c) {
      ++position_;
      return true;
    }
    return false;
  }
  void expect(char c) {
    if (!consume(c)) fail(std::string("expected '") + c + "'");
  }
  JsonValue parse_value(int depth) {
    if (depth > 64) fail("JSON nested too deeply");
    skip_space();
    if (position_ >= text_.size()) fail("unexpected end of the JSON text");
    const char c = text_[position_];
    JsonValue value;
    if (c == '{') {
      ++position_;
      value.kind = JsonValue::Kind::Object;
      if (consume('}')) return value;
      do {
        skip_space();
        std::string key = parse_string();
        expect(':');
        value.members.emplace_back(std::move(key), parse_value(depth + 1));
      } while (consume(','));
      expect('}');
    } else if (c == '[') {
      ++position_;
      value.kind = JsonValue::Kind::Array;
      if (consume(']')) return value;
      do value.items.push_back(parse_value(depth + 1));
      while (consume(','));
      expect(']');
    } else if (c == '"') {
      value.kind = JsonValue::Kind::String;
      value.text = parse_string();
    } else if (text_.compare(position_, 4, "true") == 0) {
      position_ += 4;
      value.kind = JsonValue::Kind::Boolean;
      value.boolean = true;
    } else if (text_.compare(position_, 5, "false") == 0) {
      position_ += 5;
      value.kind = JsonValue::Kind::Boolean;
    } else if (text_.compare(position_, 4, "null") == 0) {
      position_ += 4;
    } else {
      const char* begin = text_.c_str() + position_;
      char* end = nullptr;
      value.number = std::strtod(begin, &end);
      if (end == begin) fail("expected a JSON value");
      if (!std::isfinite(value.number))
        fail("number '" + std::string(begin, static_cast<std::size_t>(end - begin)) +
             "' is not finite (NaN, infinity or out of the double range)");
      value.kind = JsonValue::Kind::Number;
      position_ += static_cast<std::size_t>(end - begin);
    }
    return value;
  }
  std::string parse_string() {
    if (position_ >= text_.size() || text_[position_] != '"') fail("expected a string");
    ++position_;
    std::string out;
    while (true) {
      if (position_ >= text_.size()) fail("unterminated string");
      const char c = text_[position_++];
      if (c == '"') break;
      if (c != '\\') {
        out += c;
        continue;
      }
      if (position_ >= text_.size()) fail("unterminated escape");
      const char escape = text_[position_++];
      switch (escape) {
        case '"': out += '"'; break;
        case '\\': out += '\\'; break;
        case '/': out += '/'; break;
        case 'b': out += '\b'; break;
        case 'f': out += '\f'; break;
        case 'n': out += '\n'; break;
        case 'r': out += '\r'; break;
        case 't': out += '\t'; break;
        case 'u': {
          if (position_ + 4 > text_.size()) fail("short \\u escape");
          unsigned code = 0;
          for (int digit = 0; digit < 4; ++digit) {
            const char hex = text_[position_ + digit];
            const int value = hex >= '0' && hex <= '9'   ? hex - '0'
                              : hex >= 'a' && hex <= 'f' ? hex - 'a' + 10
                              : hex >= 'A' && hex <= 'F' ? hex - 'A' + 10
                                                         : -1;
            if (value < 0) fail("\\u escape '" + text_.substr(position_, 4) + "' is not 4 hexadecimal digits");
            code = code * 16 + static_cast<unsigned>(value);
          }
          position_ += 4;
          if (code < 0x80) {
            out += static_cast<char>(code);
          } else if (code < 0x800) {
            out += static_cast<char>(0xC0 | (code >> 6));
            out += static_cast<char>(0x80 | (code & 0x3F));
          } else {
            out += static_cast<char>(0xE0 | (code >> 12));
            out += static_cast<char>(0x80 | ((code >> 6) & 0x3F));
            out += static_cast<char>(0x80 | (code & 0x3F));
          }
          break;
        }
        default: fail(std::string("unknown escape \\") + escape);
      }
    }
    return out;
  }

  const std::string& text_;
  std::string source_;
  std::size_t position_ = 0;
};

// 2^64: the integers a JSON number may hold for a std::size_t field are those below it.
constexpr double kTwoToThe64 = 18446744073709551616.0;

const JsonValue& member(const JsonValue& object, const std::string& key, const std::string& where,
                        const std::string& source, JsonValue::Kind kind) {
  const JsonValue* value = object.kind == JsonValue::Kind::Object ? object.find(key) : nullptr;
  if (value == nullptr) throw file_error(source, where + ": missing field \"" + key + "\"");
  if (value->kind != kind) throw file_error(source, where + "." + key + ": wrong JSON type");
  return *value;
}

std::vector<double> number_array(const JsonValue& array, std::size_t expected, const std::string& where,
                                 const std::string& source) {
  if (array.kind != JsonValue::Kind::Array || array.items.size() != expected)
    throw file_error(source, where + ": expected an array of " + std::to_string(expected) + " numbers");
  std::vector<double> values;
  for (const JsonValue& item : array.items) {
    if (item.kind != JsonValue::Kind::Number) throw file_error(source, where + ": expected numbers only");
    values.push_back(item.number);
  }
  return values;
}

}  // namespace

std::string scene_model_to_json(const SceneModel& model, const std::string& extra_stats) {
  validate_scene_model(model);
  std::ostringstream out;
  out << "{\n  \"format\": \"quadrix-scene-model\",\n  \"version\": 1,\n  \"quadrics\": [";
  std::map<std::string, int> counts_by_class, counts_by_type;
  for (std::size_t index = 0; index < model.records.size(); ++index) {
    const QuadricRecord& record = model.records[index];
    const bool augmented = index >= model.augmented_begin;
    const std::string class_name = element_class_name(element_class_from_label(record.label));
    const std::string type_name = quadric_type_name(model.types[index]);
    if (!augmented) {
      ++counts_by_class[class_name];
      ++counts_by_type[type_name];
    }
    const Eigen::Matrix3d rotation = record.full_rotation.normalized().toRotationMatrix();
    std::vector<double> rotation_matrix;
    for (int row = 0; row < 3; ++row)
      for (int column = 0; column < 3; ++column) rotation_matrix.push_back(rotation(row, column));
    const auto values = record.to_array();
    out << (index == 0 ? "\n" : ",\n") << "    {\"index\": " << index << ", \"label\": " << record.label
        << ", \"class\": " << json_string(class_name) << ", \"type\": " << json_string(type_name)
        << ", \"points\": " << model.element_point_counts[index] << ", \"augmented\": " << (augmented ? "true" : "false")
        << ",\n     \"q\": " << json_array(std::vector<double>(record.q.data(), record.q.data() + 10))
        << ",\n     \"scale\": " << json_array(std::vector<double>(record.full_scale.data(), record.full_scale.data() + 3))
        << ",\n     \"rotation\": "
        << json_array(std::vector<double>{record.full_rotation.w(), record.full_rotation.x(), record.full_rotation.y(),
                                          record.full_rotation.z()})
        << ",\n     \"rotation_matrix\": " << json_array(rotation_matrix)
        << ",\n     \"center\": " << json_array(std::vector<double>(record.full_center.data(), record.full_center.data() + 3))
        << ",\n     \"shape\": " << shape_parameters_json(record_shape_parameters(record, model.types[index]))
        << ",\n     \"record\": " << json_array(values) << "}";
  }
  out << (model.records.empty() ? "],\n" : "\n  ],\n");
  out << "  \"ground\": {\"found\": " << (model.has_ground ? "true" : "false")
      << ", \"normal\": " << json_array(std::vector<double>(model.ground_normal.data(), model.ground_normal.data() + 3))
      << ", \"offset\": " << json_number(model.ground_offset) << "},\n";
  out << "  \"augmented_begin\": " << model.augmented_begin << ",\n";
  out << "  \"augmented_descriptors\": [";
  for (std::size_t index = 0; index < model.augmented_descriptors.size(); ++index)
    out << (index == 0 ? "\n    " : ",\n    ") << json_array(model.augmented_descriptors[index]);
  out << (model.augmented_descriptors.empty() ? "],\n" : "\n  ],\n");
  out << "  \"stats\": {\n    \"source_points\": " << model.source_point_count << ",\n    \"records\": " << model.size()
      << ",\n    \"augmented_points\": " << model.augmented_count() << ",\n    \"counts_by_class\": {";
  bool first = true;
  for (const auto& [name, count] : counts_by_class) {
    out << (first ? "" : ", ") << json_string(name) << ": " << count;
    first = false;
  }
  out << "},\n    \"counts_by_type\": {";
  first = true;
  for (const auto& [name, count] : counts_by_type) {
    out << (first ? "" : ", ") << json_string(name) << ": " << count;
    first = false;
  }
  out << "},\n    \"timings_ms\": {";
  first = true;
  for (const auto& [name, milliseconds] : model.timings_ms) {
    out << (first ? "" : ", ") << json_string(name) << ": " << json_number(milliseconds);
    first = false;
  }
  out << "},\n    \"binary_bytes\": " << scene_model_to_binary(model).size();
  if (!extra_stats.empty()) out << ",\n    " << extra_stats;
  out << "\n  }\n}\n";
  return out.str();
}

SceneModel scene_model_from_json(const std::string& text, const std::string& source_name) {
  const JsonValue document = JsonParser(text, source_name).parse_document();
  using Kind = JsonValue::Kind;
  if (document.kind != Kind::Object) throw file_error(source_name, "expected a JSON object at the top level");
  const JsonValue& format = member(document, "format", "document", source_name, Kind::String);
  if (format.text != "quadrix-scene-model")
    throw file_error(source_name, "format is \"" + format.text + "\", expected \"quadrix-scene-model\"");
  const double version = member(document, "version", "document", source_name, Kind::Number).number;
  if (version != 1.0) throw file_error(source_name, "version " + json_number(version) + " is not supported (expected 1)");

  SceneModel model;
  const JsonValue& quadrics = member(document, "quadrics", "document", source_name, Kind::Array);
  for (std::size_t index = 0; index < quadrics.items.size(); ++index) {
    const std::string where = "quadrics[" + std::to_string(index) + "]";
    const JsonValue& item = quadrics.items[index];
    const std::vector<double> values = number_array(member(item, "record", where, source_name, Kind::Array), 21,
                                                    where + ".record", source_name);
    std::array<double, 21> record_values;
    std::copy(values.begin(), values.end(), record_values.begin());
    try {
      model.records.push_back(QuadricRecord::from_array(record_values));
      model.types.push_back(quadric_type_from_name(member(item, "type", where, source_name, Kind::String).text));
    } catch (const Error& error) {
      throw file_error(source_name, where + ": " + error.what());
    }
    const double points = member(item, "points", where, source_name, Kind::Number).number;
    if (!(points >= 0.0 && points <= 4294967295.0 && std::floor(points) == points))
      throw file_error(source_name, where + ".points: expected a non-negative integer");
    model.element_point_counts.push_back(static_cast<std::uint32_t>(points));
  }
  const JsonValue& ground = member(document, "ground", "document", source_name, Kind::Object);
  model.has_ground = member(ground, "found", "ground", source_name, Kind::Boolean).boolean;
  const std::vector<double> normal =
      number_array(member(ground, "normal", "ground", source_name, Kind::Array), 3, "ground.normal", source_name);
  model.ground_normal = Eigen::Vector3d(normal[0], normal[1], normal[2]);
  model.ground_offset = member(ground, "offset", "ground", source_name, Kind::Number).number;
  const double augmented_begin = member(document, "augmented_begin", "document", source_name, Kind::Number).number;
  if (!(augmented_begin >= 0.0 && std::floor(augmented_begin) == augmented_begin && augmented_begin < kTwoToThe64))
    throw file_error(source_name, "augmented_begin: expected a non-negative integer below 2^64");
  model.augmented_begin = static_cast<std::size_t>(augmented_begin);
  const JsonValue& descriptors = member(document, "augmented_descriptors", "document", source_name, Kind::Array);
  for (std::size_t index = 0; index < descriptors.items.size(); ++index) {
    const std::vector<double> values = number_array(descriptors.items[index], kFpfhSize,
                                                    "augmented_descriptors[" + std::to_string(index) + "]", source_name);
    std::array<float, kFpfhSize> descriptor;
    for (int bin = 0; bin < kFpfhSize; ++bin) descriptor[bin] = static_cast<float>(values[bin]);
    model.augmented_descriptors.push_back(descriptor);
  }
  const JsonValue& stats = member(document, "stats", "document", source_name, Kind::Object);
  const double source_points = member(stats, "source_points", "stats", source_name, Kind::Number).number;
  if (!(source_points >= 0.0 && std::floor(source_points) == source_points && source_points < kTwoToThe64))
    throw file_error(source_name, "stats.source_points: expected a non-negative integer below 2^64");
  model.source_point_count = static_cast<std::size_t>(source_points);
  const JsonValue& timings = member(stats, "timings_ms", "stats", source_name, Kind::Object);
  for (const auto& [name, value] : timings.members) {
    if (value.kind != Kind::Number) throw file_error(source_name, "stats.timings_ms." + name + ": expected a number");
    model.timings_ms[name] = value.number;
  }
  try {
    validate_scene_model(model);
  } catch (const Error& error) {
    throw file_error(source_name, error.what());
  }
  return model;
}

void write_scene_model_json(const std::string& path, const SceneModel& model, const std::string& extra_stats) {
  const std::string text = scene_model_to_json(model, extra_stats);
  write_file_atomically(path, [&](std::ostream& stream) { stream << text; });
}

SceneModel read_scene_model_json(const std::string& path) { return scene_model_from_json(read_whole_file(path), path); }

}  // namespace quadrix
