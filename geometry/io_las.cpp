// ASPRS LAS 1.0-1.4 reading (point data record formats 0-10), written here from the open
// specification (LAS 1.4 R15) because Debian 12 packages no LAS library: no PDAL, LASzip or
// libLAS. Uncompressed only: LAZ is refused with the command that decompresses it.
#include "geometry/io.h"
#include "geometry/io_internal.h"
#include "geometry/las.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>

namespace quadrix {
namespace io_internal {

namespace {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the LAS reader assumes a little-endian machine");

/// Bytes of the public header block each version needs at least (LAS 1.0-1.2: 227, 1.3: 235, 1.4: 375).
std::size_t minimum_header_size(int minor) { return minor <= 2 ? 227 : minor == 3 ? 235 : 375; }

/// Bytes of a variable-length record's header.
constexpr std::size_t kVlrHeaderSize = 54;

template <typename T>
T load(const char* bytes, std::size_t offset) {
  T value;
  std::memcpy(&value, bytes + offset, sizeof(T));
  return value;
}

std::string fixed_text(const char* bytes, std::size_t size) {
  std::string text(bytes, size);
  const std::size_t end = text.find('\0');
  if (end != std::string::npos) text.resize(end);
  return text;
}

[[noreturn]] void throw_laz(const std::string& path, const std::string& why) {
  throw file_error(path, "is LAZ (LASzip-compressed LAS: " + why +
                             "), which is not read; decompress it to .las first, e.g. `laszip -i in.laz -o out.las` "
                             "or `pdal translate in.laz out.las`");
}

/// Byte offset of the red, green, blue words in a record of `format`, or 0 when it has none.
std::size_t rgb_offset(int format) {
  switch (format) {
    case 2: return 20;
    case 3:
    case 5: return 28;
    case 7:
    case 8:
    case 10: return 30;
    default: return 0;
  }
}

/// Names of the fields a record of `format` holds, in record order (extra bytes as one entry).
std::vector<std::string> record_field_names(int format, std::size_t extra_bytes) {
  std::vector<std::string> names = {"x", "y", "z", "intensity", "return_number", "number_of_returns", "classification",
                                    "scan_angle", "user_data", "point_source_id"};
  if (format == 1 || format >= 3) names.push_back("gps_time");
  if (rgb_offset(format) != 0) names.insert(names.end(), {"red", "green", "blue"});
  if (format == 8 || format == 10) names.push_back("nir");
  if (format == 4 || format == 5 || format == 9 || format == 10) names.push_back("wave_packet");
  if (extra_bytes > 0) names.push_back("extra_bytes(" + std::to_string(extra_bytes) + ")");
  return names;
}

/// Metres per unit and name of an EPSG linear unit code (GeoTIFF keys 3076, 4099, 2052); {0, ""}
/// for a code not in this table (the units then stay undeclared).
std::pair<double, std::string> epsg_linear_unit(unsigned code) {
  switch (code) {
    case 9001: return {1.0, "metre"};
    case 9002: return {0.3048, "foot"};
    case 9003: return {1200.0 / 3937.0, "US survey foot"};
    case 9005: return {0.3047972654, "Clarke's foot"};
    case 9036: return {1000.0, "kilometre"};
    case 9094: return {0.3047997101815088, "Gold Coast foot"};
    case 9095: return {0.3048007491, "British foot (1936)"};
    default: return {0.0, ""};
  }
}

/// The units of a GeoKeyDirectory (`keys`, 16-bit words) with its double parameters (`doubles`).
void units_from_geo_keys(const std::vector<std::uint16_t>& keys, const std::vector<double>& doubles, LasUnits& units) {
  if (keys.size() < 4) return;
  const std::size_t count = std::min<std::size_t>(keys[3], (keys.size() - 4) / 4);
  double user_size = 0.0;
  unsigned linear = 0, vertical = 0, model = 0;
  for (std::size_t k = 0; k < count; ++k) {
    const std::uint16_t id = keys[4 + 4 * k], location = keys[5 + 4 * k], value = keys[7 + 4 * k];
    if (location == 0) {
      if (id == 1024) model = value;
      if (id == 3076) linear = value;
      if (id == 4099) vertical = value;
    } else if (location == 34736 && id == 3077 && value < doubles.size()) {
      user_size = doubles[value];
    }
  }
  if (model == 2) {
    units.geographic = true;
    units.horizontal_name = "degree";
  } else if (linear == 32767 && std::isfinite(user_size) && user_size > 0.0) {
    units.horizontal_metres = user_size;
    units.horizontal_name = "user-defined unit of " + std::to_string(user_size) + " m";
  } else if (const auto [metres, name] = epsg_linear_unit(linear); metres > 0.0) {
    units.horizontal_metres = metres;
    units.horizontal_name = name;
  }
  if (const auto [metres, name] = epsg_linear_unit(vertical); metres > 0.0) {
    units.vertical_metres = metres;
    units.vertical_name = name;
  }
  if (!units.horizontal_name.empty() || !units.vertical_name.empty()) units.source = "GeoTIFF keys";
}

/// The UNIT[name, metres] directly inside the WKT element that starts at `begin` ("PROJCS[" or
/// "VERT_CS["): the one at bracket depth 1, after the nested GEOGCS's own angular unit.
bool wkt_element_unit(const std::string& wkt, std::size_t begin, double& metres, std::string& name) {
  int depth = 0;
  for (std::size_t i = wkt.find('[', begin); i < wkt.size(); ++i) {
    const char c = wkt[i];
    if (c == '[') ++depth;
    else if (c == ']' && --depth == 0) return false;
    else if (depth == 1 && wkt.compare(i, 6, "UNIT[\"") == 0) {
      const std::size_t name_end = wkt.find('"', i + 6);
      if (name_end == std::string::npos) return false;
      name = wkt.substr(i + 6, name_end - i - 6);
      const std::size_t comma = wkt.find(',', name_end);
      if (comma == std::string::npos) return false;
      char* end = nullptr;
      const std::string tail = wkt.substr(comma + 1, 40);
      metres = std::strtod(tail.c_str(), &end);
      return end != tail.c_str() && std::isfinite(metres) && metres > 0.0;
    }
  }
  return false;
}

/// The units of an OGC WKT (version 1) coordinate system.
void units_from_wkt(const std::string& wkt, LasUnits& units) {
  LasUnits found;
  const std::size_t projected = wkt.find("PROJCS[");
  double metres = 0.0;
  std::string name;
  if (projected != std::string::npos) {
    if (wkt_element_unit(wkt, projected, metres, name)) {
      found.horizontal_metres = metres;
      found.horizontal_name = name;
    }
  } else if (wkt.find("GEOGCS[") != std::string::npos) {
    found.geographic = true;
    found.horizontal_name = "degree";
  }
  const std::size_t vertical = wkt.find("VERT_CS[");
  if (vertical != std::string::npos && wkt_element_unit(wkt, vertical, metres, name)) {
    found.vertical_metres = metres;
    found.vertical_name = name;
  }
  if (!found.horizontal_name.empty() || !found.vertical_name.empty()) {
    found.source = "WKT";
    units = found;
  }
}

/// Walks the variable-length records between the public header and the points: each must end
/// before the point data; a LASzip record marks a compressed file. Reads the CRS records' units
/// into header.units (the WKT when both are present: LAS 1.4 makes it the required form).
void check_variable_length_records(const std::string& path, const RandomAccessFile& file, LasHeader& header) {
  std::size_t position = header.header_size;
  char vlr[kVlrHeaderSize];
  std::vector<std::uint16_t> geo_keys;
  std::vector<double> geo_doubles;
  std::string wkt;
  for (std::size_t k = 0; k < header.vlr_count; ++k) {
    if (position > header.point_data_offset || header.point_data_offset - position < kVlrHeaderSize)
      throw file_error(path, "variable-length record " + std::to_string(k + 1) + " of " + std::to_string(header.vlr_count) +
                                 " (header field 'number of variable length records') does not fit before the "
                                 "'offset to point data' " + std::to_string(header.point_data_offset));
    file.read_at(position, kVlrHeaderSize, vlr);
    const std::string user = fixed_text(vlr + 2, 16);
    const std::uint16_t record_id = load<std::uint16_t>(vlr, 18);
    const std::size_t length = load<std::uint16_t>(vlr, 20);
    if (user == "laszip encoded" || record_id == 22204) throw_laz(path, "it has a LASzip variable-length record");
    const std::size_t body = position + kVlrHeaderSize;
    if (user == "LASF_Projection" && body <= header.point_data_offset && header.point_data_offset - body >= length) {
      std::string bytes(length, '\0');
      if (length > 0) file.read_at(body, length, bytes.data());
      if (record_id == 34735) {
        geo_keys.resize(length / 2);
        if (!geo_keys.empty()) std::memcpy(geo_keys.data(), bytes.data(), 2 * geo_keys.size());
      } else if (record_id == 34736) {
        geo_doubles.resize(length / 8);
        if (!geo_doubles.empty()) std::memcpy(geo_doubles.data(), bytes.data(), 8 * geo_doubles.size());
      } else if (record_id == 2112) {
        wkt = fixed_text(bytes.data(), bytes.size());
      }
    }
    position += kVlrHeaderSize + length;
    if (position > header.point_data_offset)
      throw file_error(path, "variable-length record " + std::to_string(k + 1) + " ('" + user + "', " +
                                 std::to_string(length) + " bytes) runs past the 'offset to point data' " +
                                 std::to_string(header.point_data_offset));
  }
  units_from_geo_keys(geo_keys, geo_doubles, header.units);
  if (!wkt.empty()) units_from_wkt(wkt, header.units);
}

/// True when the header's box is all zeros (written by tools that do not fill it): nothing to check against.
bool box_unset(const LasHeader& header) { return header.min.isZero(0.0) && header.max.isZero(0.0); }

}  // namespace

LasRecordReader::LasRecordReader(const std::string& path) : file_(path), header_(read_las_header(path)) {
  if (file_.size() != header_.file_size)
    throw file_error(path, "changed size while its header was read");
}

bool LasRecordReader::has_rgb() const { return rgb_offset(header_.point_format) != 0; }

bool LasRecordReader::read(std::size_t max_records, LasRecords& records) {
  const std::size_t remaining = static_cast<std::size_t>(header_.point_count) - next_record_;
  const std::size_t count = std::min(std::max<std::size_t>(max_records, 1), remaining);
  records.count = count;
  records.x.resize(count);
  records.y.resize(count);
  records.z.resize(count);
  records.intensity.resize(count);
  records.classification.resize(count);
  records.return_number.resize(count);
  records.number_of_returns.resize(count);
  records.rgb.resize(has_rgb() ? count : 0);
  if (count == 0) return false;
  const std::size_t length = header_.record_length;
  buffer_.resize(count * length);  // count * length <= the file's size: read_las_header checked the count
  file_.read_at(header_.point_data_offset + next_record_ * length, count * length, buffer_.data());
  const int format = header_.point_format;
  const std::size_t colour = rgb_offset(format);
  const bool check_box = !box_unset(header_);
  // A point may sit half a unit of the scale outside a box computed before quantisation, plus rounding.
  Eigen::Vector3d tolerance;
  for (int axis = 0; axis < 3; ++axis)
    tolerance[axis] = std::abs(header_.scale[axis]) +
                      1e-9 * std::max(std::abs(header_.min[axis]), std::abs(header_.max[axis]));
  static const char* const kMinNames[3] = {"min x", "min y", "min z"};
  static const char* const kMaxNames[3] = {"max x", "max y", "max z"};
  for (std::size_t i = 0; i < count; ++i) {
    const char* record = buffer_.data() + i * length;
    double* coordinates[3] = {&records.x[i], &records.y[i], &records.z[i]};
    for (int axis = 0; axis < 3; ++axis) {
      const double value = static_cast<double>(load<std::int32_t>(record, 4 * axis)) * header_.scale[axis] +
                           header_.offset[axis];
      *coordinates[axis] = value;
      if (check_box && std::isfinite(value)) {
        if (value < header_.min[axis] - tolerance[axis] || value > header_.max[axis] + tolerance[axis]) {
          const bool below = value < header_.min[axis] - tolerance[axis];
          throw file_error(file_.path(), "point " + std::to_string(next_record_ + i) + " has " +
                                             std::string("xyz").substr(axis, 1) + " = " + std::to_string(value) +
                                             ", outside the header's '" + (below ? kMinNames[axis] : kMaxNames[axis]) +
                                             "' " + std::to_string(below ? header_.min[axis] : header_.max[axis]) +
                                             " (the header's bounding box does not hold the points)");
        }
      }
    }
    records.intensity[i] = load<std::uint16_t>(record, 12);
    const std::uint8_t returns = static_cast<std::uint8_t>(record[14]);
    if (format < 6) {
      records.return_number[i] = returns & 0x07;
      records.number_of_returns[i] = (returns >> 3) & 0x07;
      records.classification[i] = static_cast<std::uint8_t>(record[15]) & 0x1F;
    } else {
      records.return_number[i] = returns & 0x0F;
      records.number_of_returns[i] = returns >> 4;
      records.classification[i] = static_cast<std::uint8_t>(record[16]);
    }
    if (colour != 0)
      for (int c = 0; c < 3; ++c) records.rgb[i][c] = load<std::uint16_t>(record, colour + 2 * c);
  }
  next_record_ += count;
  return true;
}

PointCloud read_las_cloud(const std::string& path, const CloudReadOptions& options, CloudReadReport& report) {
  LasRecordReader reader(path);
  const LasHeader& header = reader.header();
  const std::size_t total = static_cast<std::size_t>(header.point_count);
  PointCloud cloud;
  cloud.positions.resize(3, static_cast<Eigen::Index>(total));
  cloud.intensity.resize(total);
  cloud.labels.resize(total);
  std::vector<std::array<std::uint16_t, 3>> rgb;
  if (reader.has_rgb()) rgb.resize(total);
  std::vector<float> return_number, number_of_returns;
  if (options.keep_extra_fields) {
    return_number.resize(total);
    number_of_returns.resize(total);
  }
  bool origin_chosen = false;
  if (options.local_origin == LocalOrigin::Auto && !box_unset(header)) {
    cloud.local_origin = local_origin_near(0.5 * (header.min + header.max));
    origin_chosen = true;
  }
  // Blocks of 2^20 records keep the raw bytes a small fraction of the cloud.
  constexpr std::size_t kBlockRecords = std::size_t{1} << 20;
  LasRecords records;
  std::size_t kept = 0, index = 0;
  float* positions = cloud.positions.data();
  while (reader.read(kBlockRecords, records)) {
    for (std::size_t i = 0; i < records.count; ++i, ++index) {
      const Eigen::Vector3d p(records.x[i], records.y[i], records.z[i]);
      if (options.local_origin == LocalOrigin::Auto && !origin_chosen && p.allFinite()) {
        cloud.local_origin = local_origin_near(p);
        origin_chosen = true;
      }
      const Eigen::Vector3f relative = (p - cloud.local_origin).cast<float>();
      if (!relative.allFinite()) {
        if (options.reject_non_finite)
          throw_non_finite(path, index, !std::isfinite(relative.x()) ? "x" : !std::isfinite(relative.y()) ? "y" : "z");
        continue;
      }
      positions[3 * kept] = relative.x();
      positions[3 * kept + 1] = relative.y();
      positions[3 * kept + 2] = relative.z();
      cloud.intensity[kept] = records.intensity[i];
      cloud.labels[kept] = records.classification[i];
      if (!rgb.empty()) rgb[kept] = records.rgb[i];
      if (options.keep_extra_fields) {
        return_number[kept] = records.return_number[i];
        number_of_returns[kept] = records.number_of_returns[i];
      }
      ++kept;
    }
  }
  if (kept != total) {
    cloud.positions.conservativeResize(3, static_cast<Eigen::Index>(kept));
    cloud.intensity.resize(kept);
    cloud.labels.resize(kept);
    if (!rgb.empty()) rgb.resize(kept);
    if (options.keep_extra_fields) {
      return_number.resize(kept);
      number_of_returns.resize(kept);
    }
  }
  if (!rgb.empty()) {
    // The specification scales colours to 16 bits; many writers store 8-bit values unscaled.
    bool sixteen_bit = false;
    for (const auto& colour : rgb) sixteen_bit = sixteen_bit || colour[0] > 255 || colour[1] > 255 || colour[2] > 255;
    cloud.colors.resize(kept);
    for (std::size_t k = 0; k < kept; ++k)
      for (int c = 0; c < 3; ++c)
        cloud.colors[k][c] = static_cast<std::uint8_t>(sixteen_bit ? rgb[k][c] >> 8 : rgb[k][c]);
  }
  if (options.keep_extra_fields) {
    cloud.extra_fields["return_number"] = std::move(return_number);
    cloud.extra_fields["number_of_returns"] = std::move(number_of_returns);
  }
  report.encoding = "LAS " + std::to_string(header.version_major) + "." + std::to_string(header.version_minor) +
                    " point format " + std::to_string(header.point_format);
  report.points_in_file = total;
  report.non_finite_dropped = total - kept;
  report.fields = record_field_names(header.point_format, header.extra_bytes);
  return cloud;
}

}  // namespace io_internal

LasHeader read_las_header(const std::string& path) {
  const io_internal::RandomAccessFile file(path);
  LasHeader header;
  header.file_size = file.size();
  char bytes[375] = {};
  const std::size_t available = std::min<std::size_t>(file.size(), sizeof(bytes));
  file.read_at(0, available, bytes);
  if (available < 4 || std::memcmp(bytes, "LASF", 4) != 0)
    throw file_error(path, "bad magic: not a LAS file (expected the file signature 'LASF' at byte 0)");
  if (available < 227)
    throw file_error(path, "truncated: the LAS public header block needs 227 bytes, the file has " +
                               std::to_string(file.size()));
  using io_internal::load;
  header.version_major = static_cast<unsigned char>(bytes[24]);
  header.version_minor = static_cast<unsigned char>(bytes[25]);
  if (header.version_major != 1 || header.version_minor > 4)
    throw file_error(path, "header field 'version' is " + std::to_string(header.version_major) + "." +
                               std::to_string(header.version_minor) + " (expected LAS 1.0 to 1.4)");
  header.system_identifier = io_internal::fixed_text(bytes + 26, 32);
  header.generating_software = io_internal::fixed_text(bytes + 58, 32);
  header.header_size = load<std::uint16_t>(bytes, 94);
  header.point_data_offset = load<std::uint32_t>(bytes, 96);
  header.vlr_count = load<std::uint32_t>(bytes, 100);
  const unsigned format_byte = static_cast<unsigned char>(bytes[104]);
  header.record_length = load<std::uint16_t>(bytes, 105);
  const std::uint32_t legacy_count = load<std::uint32_t>(bytes, 107);
  for (int axis = 0; axis < 3; ++axis) {
    header.scale[axis] = load<double>(bytes, 131 + 8 * axis);
    header.offset[axis] = load<double>(bytes, 155 + 8 * axis);
    header.max[axis] = load<double>(bytes, 179 + 16 * axis);
    header.min[axis] = load<double>(bytes, 187 + 16 * axis);
  }
  const std::string version = std::to_string(header.version_major) + "." + std::to_string(header.version_minor);
  const std::size_t minimum = io_internal::minimum_header_size(header.version_minor);
  if (header.header_size < minimum)
    throw file_error(path, "header field 'header size' is " + std::to_string(header.header_size) + "; LAS " + version +
                               " needs at least " + std::to_string(minimum) + " bytes");
  if (header.header_size > file.size())
    throw file_error(path, "truncated: header field 'header size' is " + std::to_string(header.header_size) +
                               " bytes, the file has " + std::to_string(file.size()));
  if (format_byte & 0xC0u) io_internal::throw_laz(path, "point data format byte " + std::to_string(format_byte) +
                                                        " has the compression bits set");
  if (format_byte > 10)
    throw file_error(path, "header field 'point data format' is " + std::to_string(format_byte) +
                               " (expected 0 to 10)");
  header.point_format = static_cast<int>(format_byte);
  const std::size_t base = kLasBaseRecordSize[format_byte];
  if (header.record_length < base)
    throw file_error(path, "header field 'point data record length' is " + std::to_string(header.record_length) +
                               "; point format " + std::to_string(format_byte) + " needs at least " +
                               std::to_string(base) + " bytes");
  header.extra_bytes = header.record_length - base;
  if (header.point_data_offset < header.header_size)
    throw file_error(path, "header field 'offset to point data' is " + std::to_string(header.point_data_offset) +
                               ", inside the " + std::to_string(header.header_size) + "-byte header");
  if (header.point_data_offset > file.size())
    throw file_error(path, "truncated: header field 'offset to point data' is " +
                               std::to_string(header.point_data_offset) + ", the file has " +
                               std::to_string(file.size()) + " bytes");
  header.point_count = legacy_count;
  if (header.version_minor >= 4) {
    const std::uint64_t count64 = load<std::uint64_t>(bytes, 247);
    if (count64 != 0 && legacy_count != 0 && count64 != legacy_count)
      throw file_error(path, "header fields 'legacy number of point records' (" + std::to_string(legacy_count) +
                                 ") and 'number of point records' (" + std::to_string(count64) + ") disagree");
    if (count64 != 0) header.point_count = count64;
  }
  const std::size_t data_bytes = file.size() - header.point_data_offset;
  if (header.point_count > data_bytes / header.record_length)
    throw file_error(path, "header field 'number of point records' is " + std::to_string(header.point_count) +
                               " records of " + std::to_string(header.record_length) + " bytes, but only " +
                               std::to_string(data_bytes) + " bytes follow the 'offset to point data' " +
                               std::to_string(header.point_data_offset) + " (truncated, or the header lies)");
  static const char* const kAxis = "xyz";
  for (int axis = 0; axis < 3; ++axis) {
    const std::string a(1, kAxis[axis]);
    if (!std::isfinite(header.scale[axis]) || !(header.scale[axis] > 0.0))
      throw file_error(path, "header field '" + a + " scale factor' is " + std::to_string(header.scale[axis]) +
                                 " (expected a finite positive number)");
    if (!std::isfinite(header.offset[axis]))
      throw file_error(path, "header field '" + a + " offset' is not finite");
    if (!std::isfinite(header.min[axis]) || !std::isfinite(header.max[axis]))
      throw file_error(path, "header field 'min " + a + "' or 'max " + a + "' is not finite");
    if (header.point_count > 0 && header.min[axis] > header.max[axis])
      throw file_error(path, "header field 'min " + a + "' (" + std::to_string(header.min[axis]) +
                                 ") is larger than 'max " + a + "' (" + std::to_string(header.max[axis]) + ")");
  }
  io_internal::check_variable_length_records(path, file, header);
  return header;
}

CoordinateUnits coordinate_units(const std::string& path, CloudFormat format) {
  CoordinateUnits units;
  if (format == CloudFormat::Auto) {
    try {
      units.las = cloud_format_from_path(path) == CloudFormat::Las;
    } catch (const Error&) {
      return units;  // the read names the unknown extension
    }
  } else {
    units.las = format == CloudFormat::Las;
  }
  if (!units.las || !std::filesystem::is_regular_file(path)) return units;  // a missing file: the read names it
  const LasUnits declared = read_las_header(path).units;
  if (declared.geographic)
    throw file_error(path, "its coordinates are longitude and latitude in degrees (a geographic CRS); quadrix models "
                           "lengths: reproject it to a projected CRS first (e.g. pdal translate with filters.reprojection)");
  if (declared.horizontal_metres > 0.0) {
    units.metres_per_unit = declared.horizontal_metres;
    units.name = declared.horizontal_name;
    units.source = "LAS " + declared.source;
  }
  if (declared.vertical_metres > 0.0 && std::abs(declared.vertical_metres - units.metres_per_unit) > 1e-9 * units.metres_per_unit)
    throw file_error(path, "its CRS declares x and y in " + units.name + " but z in " + declared.vertical_name +
                           ": mixed units are not modelled (convert z to the x and y unit first)");
  return units;
}

void require_metres(const CoordinateUnits& units, const std::string& path, const std::string& what) {
  if (units.metres_per_unit == 1.0) return;
  char size[64];
  std::snprintf(size, sizeof size, "%.10g", units.metres_per_unit);
  throw file_error(path, "its coordinates are in " + units.name + " (" + size + " m, declared by its " + units.source + "); " + what +
                             " works in metres: scale the file to metres first (quadrix model converts it by itself)");
}

}  // namespace quadrix
