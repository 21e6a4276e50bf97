// Format selection, the shared column -> PointCloud assembly, atomic writing and text helpers.
#include "geometry/io.h"
#include "geometry/io_internal.h"
#include "geometry/removed_on_signal.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

namespace quadrix {
namespace io_internal {

namespace {

std::string lowercase(std::string_view text) {
  std::string result(text);
  for (char& c : result) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return result;
}

bool ends_with(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() && text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

template <typename T>
T load_value(const char* source, bool swap_bytes) {
  T value;
  if (!swap_bytes) {
    std::memcpy(&value, source, sizeof(T));
  } else {
    char reversed[sizeof(T)];
    for (std::size_t i = 0; i < sizeof(T); ++i) reversed[i] = source[sizeof(T) - 1 - i];
    std::memcpy(&value, reversed, sizeof(T));
  }
  return value;
}

template <typename T>
void decode_typed(const char* source, std::size_t stride, std::size_t count, bool swap_bytes, double* destination) {
  if (swap_bytes) {
    for (std::size_t i = 0; i < count; ++i) destination[i] = static_cast<double>(load_value<T>(source + i * stride, true));
  } else {
    for (std::size_t i = 0; i < count; ++i) {
      T value;
      std::memcpy(&value, source + i * stride, sizeof(T));
      destination[i] = static_cast<double>(value);
    }
  }
}

using Role = FieldRole;

Role role_of(const std::string& name) {
  const std::string lower = lowercase(name);
  if (lower == "x") return Role::X;
  if (lower == "y") return Role::Y;
  if (lower == "z") return Role::Z;
  if (lower == "intensity" || lower == "scalar_intensity" || lower == "reflectance" ||
      lower == "scalar_reflectance" || lower == "remission" || lower == "scalar_remission")
    return Role::Intensity;
  if (lower == "label" || lower == "scalar_label" || lower == "semantic_label") return Role::Label;
  if (lower == "red" || lower == "r" || lower == "diffuse_red") return Role::Red;
  if (lower == "green" || lower == "g" || lower == "diffuse_green") return Role::Green;
  if (lower == "blue" || lower == "b" || lower == "diffuse_blue") return Role::Blue;
  return Role::Extra;
}

std::uint8_t to_color_channel(double value, bool scale_unit_range) {
  if (!std::isfinite(value)) return 0;
  const double scaled = scale_unit_range ? value * 255.0 : value;
  return static_cast<std::uint8_t>(std::lround(std::clamp(scaled, 0.0, 255.0)));
}

}  // namespace

FieldRole field_role(const std::string& name) { return role_of(name); }

RandomAccessFile::RandomAccessFile(const std::string& path) : path_(path) {
  descriptor_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (descriptor_ < 0) throw file_error(path, std::string("cannot open: ") + std::strerror(errno));
  struct stat status {};
  if (::fstat(descriptor_, &status) != 0 || !S_ISREG(status.st_mode)) {
    ::close(descriptor_);
    throw file_error(path, S_ISDIR(status.st_mode) ? "is a directory, expected a file"
                                                    : "is not a regular file (a FIFO, device or socket cannot be streamed)");
  }
  size_ = static_cast<std::size_t>(status.st_size);
}

RandomAccessFile::~RandomAccessFile() {
  if (descriptor_ >= 0) ::close(descriptor_);
}

void RandomAccessFile::read_at(std::size_t offset, std::size_t count, char* destination) const {
  if (offset > size_ || count > size_ - offset)
    throw file_error(path_, "truncated: needs bytes " + std::to_string(offset) + ".." + std::to_string(offset + count) +
                                " but the file has " + std::to_string(size_));
  std::size_t done = 0;
  while (done < count) {
    const ssize_t got = ::pread(descriptor_, destination + done, count - done, static_cast<off_t>(offset + done));
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0)
      throw file_error(path_, "read failed at byte " + std::to_string(offset + done) + ": " +
                                  (got < 0 ? std::strerror(errno) : "file shrank while reading"));
    done += static_cast<std::size_t>(got);
  }
}

FileBytes read_file_bytes(const std::string& path) {
  std::error_code code;
  if (std::filesystem::is_directory(path, code)) throw file_error(path, "is a directory, expected a file");
  // Opened without blocking: opening a FIFO that has no writer would wait forever.
  const int descriptor = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (descriptor < 0) throw file_error(path, std::string("cannot open: ") + std::strerror(errno));
  struct stat status {};
  if (::fstat(descriptor, &status) != 0 || !S_ISREG(status.st_mode)) {
    ::close(descriptor);
    throw file_error(path, "is not a regular file (a FIFO, device or socket): refused");
  }
  const off_t end = ::lseek(descriptor, 0, SEEK_END);
  if (end < 0 || ::lseek(descriptor, 0, SEEK_SET) < 0) {
    ::close(descriptor);
    throw file_error(path, "cannot determine the file size (not a regular file?)");
  }
  FileBytes bytes;
  bytes.size = static_cast<std::size_t>(end);
  bytes.data.reset(new char[bytes.size > 0 ? bytes.size : 1]);
  std::size_t done = 0;
  while (done < bytes.size) {
    const ssize_t got = ::read(descriptor, bytes.data.get() + done, bytes.size - done);
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) {
      const std::string reason = got < 0 ? std::strerror(errno) : "file shrank while reading";
      ::close(descriptor);
      throw file_error(path, "read failed after " + std::to_string(done) + " bytes: " + reason);
    }
    done += static_cast<std::size_t>(got);
  }
  ::close(descriptor);
  return bytes;
}

std::size_t regular_file_size(const std::string& path) {
  struct stat status {};
  if (::stat(path.c_str(), &status) != 0) throw file_error(path, std::string("cannot open: ") + std::strerror(errno));
  if (S_ISDIR(status.st_mode)) throw file_error(path, "is a directory, expected a file");
  if (!S_ISREG(status.st_mode)) throw file_error(path, "is not a regular file (a FIFO, device or socket): refused");
  return static_cast<std::size_t>(status.st_size);
}

std::size_t scalar_size(ScalarType type) {
  switch (type) {
    case ScalarType::Int8:
    case ScalarType::UInt8: return 1;
    case ScalarType::Int16:
    case ScalarType::UInt16: return 2;
    case ScalarType::Int32:
    case ScalarType::UInt32:
    case ScalarType::Float32: return 4;
    case ScalarType::Int64:
    case ScalarType::UInt64:
    case ScalarType::Float64: return 8;
  }
  return 0;
}

bool scalar_is_floating(ScalarType type) { return type == ScalarType::Float32 || type == ScalarType::Float64; }

void decode_strided(const char* source, std::size_t stride, std::size_t count, ScalarType type, bool swap_bytes,
                    double* destination) {
  switch (type) {
    case ScalarType::Int8: return decode_typed<std::int8_t>(source, stride, count, false, destination);
    case ScalarType::UInt8: return decode_typed<std::uint8_t>(source, stride, count, false, destination);
    case ScalarType::Int16: return decode_typed<std::int16_t>(source, stride, count, swap_bytes, destination);
    case ScalarType::UInt16: return decode_typed<std::uint16_t>(source, stride, count, swap_bytes, destination);
    case ScalarType::Int32: return decode_typed<std::int32_t>(source, stride, count, swap_bytes, destination);
    case ScalarType::UInt32: return decode_typed<std::uint32_t>(source, stride, count, swap_bytes, destination);
    case ScalarType::Int64: return decode_typed<std::int64_t>(source, stride, count, swap_bytes, destination);
    case ScalarType::UInt64: return decode_typed<std::uint64_t>(source, stride, count, swap_bytes, destination);
    case ScalarType::Float32: return decode_typed<float>(source, stride, count, swap_bytes, destination);
    case ScalarType::Float64: return decode_typed<double>(source, stride, count, swap_bytes, destination);
  }
}

void throw_non_finite(const std::string& path, std::size_t point_index, const char* field) {
  throw file_error(path, "point " + std::to_string(point_index) + " has a non-finite " + field +
                             " coordinate (NaN or inf) and reject_non_finite is set");
}

namespace {

/// The columns that fill the cloud's named fields, indexed by Role, and the rest as extra fields.
struct ColumnRoles {
  const FieldColumn* by_role[8] = {};
  std::vector<const FieldColumn*> extras;
  bool has_colors = false;
};

/// Gives each column its role by name (first of a role wins); colours only when red, green and blue all exist.
ColumnRoles assign_column_roles(const std::string& path, const std::vector<FieldColumn>& columns, std::size_t rows) {
  ColumnRoles roles;
  for (const FieldColumn& column : columns) {
    if (column.values.size() != rows)
      throw Error("internal: column '" + column.name + "' of " + path + " has " + std::to_string(column.values.size()) +
                  " values for " + std::to_string(rows) + " records");
    const Role role = role_of(column.name);
    const int slot = static_cast<int>(role);
    if (role != Role::Extra && roles.by_role[slot] == nullptr) {
      roles.by_role[slot] = &column;
    } else {
      roles.extras.push_back(&column);
    }
  }
  roles.has_colors = roles.by_role[static_cast<int>(Role::Red)] && roles.by_role[static_cast<int>(Role::Green)] &&
                     roles.by_role[static_cast<int>(Role::Blue)];
  if (!roles.has_colors) {
    for (Role role : {Role::Red, Role::Green, Role::Blue}) {
      if (roles.by_role[static_cast<int>(role)]) roles.extras.push_back(roles.by_role[static_cast<int>(role)]);
      roles.by_role[static_cast<int>(role)] = nullptr;
    }
  }
  return roles;
}

/// Refuses a file without x, y or z, listing the fields it does have.
void require_xyz_columns(const std::string& path, const std::vector<FieldColumn>& columns, const ColumnRoles& roles) {
  const char* axis_names[3] = {"x", "y", "z"};
  for (int axis = 0; axis < 3; ++axis) {
    if (roles.by_role[axis] == nullptr) {
      std::string present;
      for (const FieldColumn& column : columns) present += (present.empty() ? "" : " ") + column.name;
      throw file_error(path, std::string("no '") + axis_names[axis] + "' field (fields: " +
                                 (present.empty() ? "none" : present) + "); x, y and z are required");
    }
  }
}

/// local_origin_near the centre of the finite points' box (zero when there are none).
Eigen::Vector3d auto_local_origin(const double* x, const double* y, const double* z, std::size_t rows) {
  Eigen::Vector3d low = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), high = -low;
  for (std::size_t i = 0; i < rows; ++i) {
    const Eigen::Vector3d p(x[i], y[i], z[i]);
    if (!p.allFinite()) continue;
    low = low.cwiseMin(p);
    high = high.cwiseMax(p);
  }
  if (!(low.array() <= high.array()).all()) return Eigen::Vector3d::Zero();
  return local_origin_near(0.5 * (low + high));
}

/// Copies the finite positions relative to the local origin the options ask for (or throws under
/// reject_non_finite); returns the rows kept, which other fields follow.
std::vector<std::size_t> copy_finite_positions(const std::string& path, const ColumnRoles& roles, std::size_t rows,
                                               const CloudReadOptions& options, PointCloud& cloud) {
  const double* x = roles.by_role[0]->values.data();
  const double* y = roles.by_role[1]->values.data();
  const double* z = roles.by_role[2]->values.data();
  if (options.local_origin == LocalOrigin::Auto) cloud.local_origin = auto_local_origin(x, y, z, rows);
  const Eigen::Vector3d origin = cloud.local_origin;
  std::vector<std::size_t> kept;
  kept.reserve(rows);
  cloud.positions.resize(3, static_cast<Eigen::Index>(rows));
  float* out = cloud.positions.data();
  std::size_t count = 0;
  for (std::size_t i = 0; i < rows; ++i) {
    const float px = static_cast<float>(x[i] - origin.x()), py = static_cast<float>(y[i] - origin.y()),
                pz = static_cast<float>(z[i] - origin.z());
    if (std::isfinite(px) && std::isfinite(py) && std::isfinite(pz)) {
      out[3 * count] = px;
      out[3 * count + 1] = py;
      out[3 * count + 2] = pz;
      ++count;
      kept.push_back(i);
    } else if (options.reject_non_finite) {
      throw_non_finite(path, i, !std::isfinite(px) ? "x" : !std::isfinite(py) ? "y" : "z");
    }
  }
  if (count != rows) cloud.positions.conservativeResize(3, static_cast<Eigen::Index>(count));
  return kept;
}

/// Copies the kept rows' labels, which must be integers that fit 32 bits.
void copy_labels(const std::string& path, const FieldColumn& column, const std::vector<std::size_t>& kept,
                 PointCloud& cloud) {
  cloud.labels.resize(kept.size());
  for (std::size_t k = 0; k < kept.size(); ++k) {
    const double value = column.values[kept[k]];
    if (!(value >= 0.0 && value <= 4294967295.0 && value == std::floor(value)))
      throw file_error(path, "field '" + column.name + "' of point " + std::to_string(kept[k]) + " is " +
                                 std::to_string(value) + "; labels must be integers in 0..4294967295");
    cloud.labels[k] = static_cast<std::uint32_t>(value);
  }
}

/// Copies the kept rows' colours; floating-point channels that all stay within 0..1 are scaled to 0..255.
void copy_colors(const ColumnRoles& roles, const std::vector<std::size_t>& kept, PointCloud& cloud) {
  const std::size_t count = kept.size();
  const FieldColumn* channels[3] = {roles.by_role[static_cast<int>(Role::Red)], roles.by_role[static_cast<int>(Role::Green)],
                                    roles.by_role[static_cast<int>(Role::Blue)]};
  bool scale[3];
  for (int c = 0; c < 3; ++c) {
    scale[c] = false;
    if (channels[c]->floating_point) {
      scale[c] = true;
      for (std::size_t k = 0; k < count && scale[c]; ++k)
        if (channels[c]->values[kept[k]] > 1.0) scale[c] = false;
    }
  }
  const bool scale_all = scale[0] && scale[1] && scale[2];
  cloud.colors.resize(count);
  for (std::size_t k = 0; k < count; ++k)
    for (int c = 0; c < 3; ++c) cloud.colors[k][c] = to_color_channel(channels[c]->values[kept[k]], scale_all);
}

/// The kept rows of one column as floats (intensity and extra fields).
std::vector<float> kept_values(const FieldColumn& column, const std::vector<std::size_t>& kept) {
  std::vector<float> values(kept.size());
  for (std::size_t k = 0; k < kept.size(); ++k) values[k] = static_cast<float>(column.values[kept[k]]);
  return values;
}

}  // namespace

PointCloud assemble_cloud(const std::string& path, std::vector<FieldColumn>& columns, std::size_t rows,
                          const CloudReadOptions& options, CloudReadReport& report) {
  const ColumnRoles roles = assign_column_roles(path, columns, rows);
  require_xyz_columns(path, columns, roles);
  PointCloud cloud;
  const std::vector<std::size_t> kept = copy_finite_positions(path, roles, rows, options, cloud);
  report.points_in_file = rows;
  report.non_finite_dropped = rows - kept.size();
  if (const FieldColumn* column = roles.by_role[static_cast<int>(Role::Intensity)]) cloud.intensity = kept_values(*column, kept);
  if (const FieldColumn* column = roles.by_role[static_cast<int>(Role::Label)]) copy_labels(path, *column, kept, cloud);
  if (roles.has_colors) copy_colors(roles, kept, cloud);
  if (options.keep_extra_fields)
    for (const FieldColumn* column : roles.extras) cloud.extra_fields[column->name] = kept_values(*column, kept);
  return cloud;
}

std::vector<std::string> headerless_column_names(std::size_t column_count) {
  std::vector<std::string> names = {"x", "y", "z"};
  if (column_count == 4) {
    names.push_back("intensity");
  } else if (column_count == 6) {
    names.insert(names.end(), {"red", "green", "blue"});
  } else {
    for (std::size_t c = 4; c <= column_count; ++c) names.push_back("column_" + std::to_string(c));
  }
  names.resize(column_count);
  return names;
}

bool parse_double(std::string_view token, double& value) {
  if (token.empty()) return false;
  const char* begin = token.data();
  const char* end = begin + token.size();
  if (*begin == '+') ++begin;
  if (begin == end) return false;
  const auto result = std::from_chars(begin, end, value);
  if (result.ptr != end) return false;
  if (result.ec == std::errc::result_out_of_range) {
    // Overflow is inf (dropped later as non-finite); underflow is a tiny number, i.e. zero or subnormal.
    value = std::strtod(std::string(begin, end).c_str(), nullptr);
    return true;
  }
  return result.ec == std::errc();
}

bool parse_size(std::string_view token, std::size_t& value) {
  if (token.empty()) return false;
  const auto result = std::from_chars(token.data(), token.data() + token.size(), value);
  return result.ec == std::errc() && result.ptr == token.data() + token.size();
}

void split_tokens(std::string_view line, std::vector<std::string_view>& tokens, char extra_separator) {
  tokens.clear();
  std::size_t i = 0;
  const std::size_t n = line.size();
  auto is_separator = [extra_separator](char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f' || (extra_separator != 0 && c == extra_separator);
  };
  while (i < n) {
    while (i < n && is_separator(line[i])) ++i;
    if (i >= n) break;
    const std::size_t start = i;
    while (i < n && !is_separator(line[i])) ++i;
    tokens.push_back(line.substr(start, i - start));
  }
}

bool LineReader::next(std::string_view& line) {
  if (position_ >= text_.size()) return false;
  const std::size_t end = text_.find('\n', position_);
  const std::size_t stop = end == std::string_view::npos ? text_.size() : end;
  line = text_.substr(position_, stop - position_);
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  position_ = end == std::string_view::npos ? text_.size() : end + 1;
  ++next_line_number_;
  return true;
}

void append_number(std::string& out, float value) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  out.append(buffer, result.ptr);
}

void append_number(std::string& out, double value) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  out.append(buffer, result.ptr);
}

void append_number(std::string& out, std::uint64_t value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  out.append(buffer, result.ptr);
}

void check_cloud_consistent(const std::string& path, const PointCloud& cloud) {
  const std::size_t n = cloud.size();
  auto check = [&](const std::string& field, std::size_t size) {
    if (size != 0 && size != n)
      throw file_error(path, "cannot write: cloud field '" + field + "' has " + std::to_string(size) +
                                 " values for " + std::to_string(n) + " points");
  };
  check("intensity", cloud.intensity.size());
  check("labels", cloud.labels.size());
  check("colors", cloud.colors.size());
  for (const auto& [name, values] : cloud.extra_fields) {
    check(name, values.size());
    check_extra_field_name(path, name);
  }
}

void check_extra_field_name(const std::string& path, const std::string& name) {
  if (name.empty()) throw file_error(path, "cannot write: an extra field has an empty name");
  for (char c : name)
    if (std::isspace(static_cast<unsigned char>(c)) || !std::isprint(static_cast<unsigned char>(c)))
      throw file_error(path, "cannot write: extra field name '" + name + "' contains whitespace or control characters");
  if (role_of(name) != Role::Extra || lowercase(name) == "rgb" || lowercase(name) == "rgba")
    throw file_error(path, "cannot write: extra field name '" + name +
                               "' would be read back as x/y/z/intensity/label/colour; rename it");
}

}  // namespace io_internal

Eigen::Vector3d local_origin_near(const Eigen::Vector3d& reference) {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  for (int axis = 0; axis < 3; ++axis)
    if (std::isfinite(reference[axis]) && std::abs(reference[axis]) > kLocalOriginThreshold)
      origin[axis] = std::round(reference[axis]);
  return origin;
}

std::string cloud_format_name(CloudFormat format) {
  switch (format) {
    case CloudFormat::Auto: return "auto";
    case CloudFormat::KittiBin: return "kitti-bin";
    case CloudFormat::NuScenesBin: return "nuscenes-bin";
    case CloudFormat::Ply: return "ply";
    case CloudFormat::Pcd: return "pcd";
    case CloudFormat::Xyz: return "xyz";
    case CloudFormat::Csv: return "csv";
    case CloudFormat::Npy: return "npy";
    case CloudFormat::Las: return "las";
  }
  return "unknown";
}

CloudFormat cloud_format_from_name(const std::string& name) {
  const std::string lower = io_internal::lowercase(name);
  if (lower == "auto") return CloudFormat::Auto;
  if (lower == "bin" || lower == "kitti-bin" || lower == "kitti") return CloudFormat::KittiBin;
  if (lower == "nuscenes-bin" || lower == "nuscenes" || lower == "pcd.bin") return CloudFormat::NuScenesBin;
  if (lower == "ply") return CloudFormat::Ply;
  if (lower == "pcd") return CloudFormat::Pcd;
  if (lower == "xyz" || lower == "txt") return CloudFormat::Xyz;
  if (lower == "csv") return CloudFormat::Csv;
  if (lower == "npy") return CloudFormat::Npy;
  if (lower == "las") return CloudFormat::Las;
  throw Error("unknown point-cloud format '" + name +
              "' (expected one of: auto, bin, kitti-bin, nuscenes-bin, ply, pcd, xyz, txt, csv, npy, las)");
}

CloudFormat cloud_format_from_path(const std::string& path) {
  const std::string lower = io_internal::lowercase(std::filesystem::path(path).filename().string());
  using io_internal::ends_with;
  if (ends_with(lower, ".pcd.bin")) return CloudFormat::NuScenesBin;
  if (ends_with(lower, ".bin")) return CloudFormat::KittiBin;
  if (ends_with(lower, ".ply")) return CloudFormat::Ply;
  if (ends_with(lower, ".pcd")) return CloudFormat::Pcd;
  if (ends_with(lower, ".xyz") || ends_with(lower, ".txt")) return CloudFormat::Xyz;
  if (ends_with(lower, ".csv")) return CloudFormat::Csv;
  if (ends_with(lower, ".npy")) return CloudFormat::Npy;
  if (ends_with(lower, ".las")) return CloudFormat::Las;
  if (ends_with(lower, ".laz"))
    throw file_error(path, "LAZ (LASzip-compressed LAS) is not read; decompress it to .las first, e.g. "
                           "`laszip -i in.laz -o out.las` or `pdal translate in.laz out.las`");
  throw file_error(path,
                   "unknown point-cloud extension (expected .bin, .pcd.bin, .ply, .pcd, .xyz, .txt, .csv, .npy or "
                   ".las; or choose the format explicitly, e.g. --format ply)");
}

PointCloud read_point_cloud(const std::string& path, const CloudReadOptions& options, CloudReadReport* report) {
  CloudReadReport local;
  CloudReadReport& out = report ? *report : local;
  out = CloudReadReport{};
  const CloudFormat format = options.format == CloudFormat::Auto ? cloud_format_from_path(path) : options.format;
  out.format = format;
  switch (format) {
    case CloudFormat::KittiBin: return io_internal::read_kitti_bin(path, options, out);
    case CloudFormat::NuScenesBin: return io_internal::read_nuscenes_bin(path, options, out);
    case CloudFormat::Ply: return io_internal::read_ply_cloud(path, options, out);
    case CloudFormat::Pcd: return io_internal::read_pcd_cloud(path, options, out);
    case CloudFormat::Xyz: return io_internal::read_xyz_cloud(path, options, out);
    case CloudFormat::Csv: return io_internal::read_csv_cloud(path, options, out);
    case CloudFormat::Npy: return io_internal::read_npy_cloud(path, options, out);
    case CloudFormat::Las: return io_internal::read_las_cloud(path, options, out);
    case CloudFormat::Auto: break;
  }
  throw file_error(path, "no reader for the requested format");
}

void write_point_cloud(const std::string& path, const PointCloud& cloud, const CloudWriteOptions& options) {
  const CloudFormat format = options.format == CloudFormat::Auto ? cloud_format_from_path(path) : options.format;
  io_internal::check_cloud_consistent(path, cloud);
  if (format == CloudFormat::Ply) return io_internal::write_ply_cloud(path, cloud, options.binary);
  if (format == CloudFormat::Pcd) return io_internal::write_pcd_cloud(path, cloud, options.binary);
  throw file_error(path, "writing format '" + cloud_format_name(format) + "' is not supported; write .ply or .pcd");
}

namespace {

// Paths removed when a handled signal ends the process: fixed storage, so the handler reads them
// without allocating. A slot is free (0), being filled (1) or live (2).
constexpr int kRemovalSlots = 256;
constexpr std::size_t kRemovalPathBytes = 4096;
char removal_paths[kRemovalSlots][kRemovalPathBytes];
std::atomic<int> removal_state[kRemovalSlots];
std::atomic<long> removal_order[kRemovalSlots];
std::atomic<long> removal_counter{0};

// Removes the folder open as `folder` (a descriptor) and everything below it, down to 16 levels,
// with only async-signal-safe calls (getdents64, unlinkat, openat), for the handler below: a staging
// folder a writer filled with files and folders of its own.
void remove_folder_contents(int folder, int depth) {
  alignas(8) char buffer[2048];
  for (;;) {
    const long bytes = ::syscall(SYS_getdents64, folder, buffer, sizeof buffer);
    if (bytes <= 0) return;
    bool removed_any = false;
    for (long offset = 0; offset < bytes;) {
      struct Entry {
        std::uint64_t inode;
        std::int64_t next;
        unsigned short length;
        unsigned char type;
        char name[1];
      };
      const Entry* entry = reinterpret_cast<const Entry*>(buffer + offset);
      offset += entry->length;
      const char* name = entry->name;
      if (name[0] == '.' && (name[1] == '\0' || (name[1] == '.' && name[2] == '\0'))) continue;
      if (::unlinkat(folder, name, 0) == 0) {
        removed_any = true;
        continue;
      }
      if (depth >= 16) continue;
      const int inner = ::openat(folder, name, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
      if (inner < 0) continue;
      remove_folder_contents(inner, depth + 1);
      ::close(inner);
      removed_any = ::unlinkat(folder, name, AT_REMOVEDIR) == 0 || removed_any;
    }
    if (!removed_any) return;  // what is left cannot be removed: stop rather than loop
    ::lseek(folder, 0, SEEK_SET);
  }
}

// Removes every live path, newest first (files before the folder holding them; a folder with
// everything in it), with only async-signal-safe calls, then ends the process by the same signal
// with its default action.
extern "C" void remove_tracked_paths_and_exit(int signal_number) {
  bool removed[kRemovalSlots] = {};
  for (int round = 0; round < kRemovalSlots; ++round) {
    int newest = -1;
    long newest_order = -1;
    for (int slot = 0; slot < kRemovalSlots; ++slot)
      if (!removed[slot] && removal_state[slot].load() == 2 && removal_order[slot].load() > newest_order) {
        newest = slot;
        newest_order = removal_order[slot].load();
      }
    if (newest < 0) break;
    removed[newest] = true;
    if (::unlink(removal_paths[newest]) != 0 && ::rmdir(removal_paths[newest]) != 0) {
      const int folder = ::open(removal_paths[newest], O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
      if (folder >= 0) {
        remove_folder_contents(folder, 0);
        ::close(folder);
        ::rmdir(removal_paths[newest]);
      }
    }
  }
  ::signal(signal_number, SIG_DFL);
  ::raise(signal_number);
}

// The path a write to `path` replaces: `path` itself, or the regular file a symlink leads to.
// Error for anything but a regular file or nothing.
std::filesystem::path replaced_path(const std::string& path) {
  const std::filesystem::path target(path);
  std::error_code code;
  const std::filesystem::file_status link = std::filesystem::symlink_status(target, code);
  if (code || !std::filesystem::exists(link)) return target;
  if (std::filesystem::is_symlink(link)) {
    const std::filesystem::file_status pointed = std::filesystem::status(target, code);
    if (code || !std::filesystem::is_regular_file(pointed))
      throw file_error(path, "cannot write: it is a symlink to something other than a regular file");
    return std::filesystem::canonical(target);
  }
  if (std::filesystem::is_directory(link)) throw file_error(path, "cannot write: it is a directory");
  if (!std::filesystem::is_regular_file(link))
    throw file_error(path, "cannot write: it is not a regular file (a device, FIFO or socket); refused");
  return target;
}

}  // namespace

RemovedOnSignal::RemovedOnSignal(const std::string& path) {
  if (path.empty() || path.size() >= kRemovalPathBytes) return;
  for (int slot = 0; slot < kRemovalSlots; ++slot) {
    int expected = 0;
    if (!removal_state[slot].compare_exchange_strong(expected, 1)) continue;
    std::memcpy(removal_paths[slot], path.c_str(), path.size() + 1);
    removal_order[slot].store(removal_counter.fetch_add(1) + 1);
    removal_state[slot].store(2);
    slot_ = slot;
    return;
  }
}

RemovedOnSignal::~RemovedOnSignal() {
  if (slot_ >= 0) removal_state[slot_].store(0);
}

void remove_on_signals() {
  struct sigaction action {};
  action.sa_handler = remove_tracked_paths_and_exit;
  sigemptyset(&action.sa_mask);
  for (const int signal_number : {SIGINT, SIGTERM, SIGHUP}) ::sigaction(signal_number, &action, nullptr);
}

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  static std::atomic<unsigned> counter{0};
  const std::filesystem::path target = replaced_path(path);
  const std::filesystem::path directory = target.has_parent_path() ? target.parent_path() : std::filesystem::path(".");
  std::error_code code;
  if (!std::filesystem::is_directory(directory, code))
    throw file_error(path, "cannot write: directory '" + directory.string() + "' does not exist");
  const std::string temporary = (directory / ("." + target.filename().string() + ".tmp-" + std::to_string(::getpid()) +
                                              "-" + std::to_string(counter.fetch_add(1))))
                                    .string();
  const RemovedOnSignal removed_if_interrupted(temporary);
  try {
    {
      std::ofstream stream(temporary, std::ios::binary | std::ios::trunc);
      if (!stream) throw file_error(path, "cannot create temporary file '" + temporary + "': " + std::strerror(errno));
      write(stream);
      stream.flush();
      if (!stream) throw file_error(path, "writing failed (disk full or I/O error)");
      stream.close();
      if (stream.fail()) throw file_error(path, "closing the temporary file failed");
    }
    const int descriptor = ::open(temporary.c_str(), O_RDONLY | O_CLOEXEC);
    if (descriptor >= 0) {
      const int synced = ::fsync(descriptor);
      ::close(descriptor);
      if (synced != 0) throw file_error(path, std::string("fsync failed: ") + std::strerror(errno));
    }
    replaced_path(path);  // still a regular file or nothing (a FIFO made meanwhile is not replaced)
    if (std::rename(temporary.c_str(), target.c_str()) != 0)
      throw file_error(path, std::string("cannot rename the temporary file over the target: ") + std::strerror(errno));
  } catch (...) {
    std::remove(temporary.c_str());
    throw;
  }
}

}  // namespace quadrix
