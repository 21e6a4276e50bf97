// Streaming readers: fixed-size binary records (binary PLY, binary PCD, KITTI and nuScenes .bin),
// LAS (through LasRecordReader) and XYZ text read block by block.
#include "geometry/point_stream.h"

#include "geometry/io_internal.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace quadrix {

Eigen::Matrix3Xf PointChunk::relative_to(const Eigen::Vector3d& origin) const {
  return (positions.colwise() - origin).cast<float>();
}

namespace {

using io_internal::FieldRole;

/// Header bytes a PLY or PCD header may take: enough for any header a writer produces, and a bound
/// on what is read before the header has been checked.
constexpr std::size_t kMaxHeaderBytes = std::size_t{4} << 20;

/// Appends points to a chunk, dropping non-finite ones as read_point_cloud does.
class ChunkFiller {
 public:
  ChunkFiller(PointChunk& chunk, std::size_t capacity, bool intensity, bool labels) : chunk_(chunk) {
    chunk.positions.resize(3, static_cast<Eigen::Index>(capacity));
    chunk.intensity.resize(intensity ? capacity : 0);
    chunk.labels.resize(labels ? capacity : 0);
  }
  /// Adds one point when x, y, z are finite; returns false (the point dropped) otherwise.
  bool add(double x, double y, double z, float intensity, std::uint32_t label) {
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) return false;
    chunk_.positions.col(static_cast<Eigen::Index>(count_)) = Eigen::Vector3d(x, y, z);
    if (!chunk_.intensity.empty()) chunk_.intensity[count_] = intensity;
    if (!chunk_.labels.empty()) chunk_.labels[count_] = label;
    ++count_;
    return true;
  }
  /// Shrinks the chunk to the points added.
  void finish() {
    chunk_.positions.conservativeResize(3, static_cast<Eigen::Index>(count_));
    if (!chunk_.intensity.empty()) chunk_.intensity.resize(count_);
    if (!chunk_.labels.empty()) chunk_.labels.resize(count_);
  }

 private:
  PointChunk& chunk_;
  std::size_t count_ = 0;
};

/// A label value read as a double, which must be an integer that fits 32 bits (as read_point_cloud requires).
std::uint32_t checked_label(const std::string& path, const std::string& field, std::size_t record, double value) {
  if (!(value >= 0.0 && value <= 4294967295.0 && value == std::floor(value)))
    throw file_error(path, "field '" + field + "' of point " + std::to_string(record) + " is " + std::to_string(value) +
                               "; labels must be integers in 0..4294967295");
  return static_cast<std::uint32_t>(value);
}

/// Fixed-size records: x, y, z, and the first intensity and label fields by name.
class RecordStream final : public PointStream {
 public:
  RecordStream(const std::string& path, CloudFormat format, io_internal::BinaryRecordLayout layout)
      : file_(path), layout_(std::move(layout)) {
    path_ = path;
    format_ = format;
    int slot[5] = {-1, -1, -1, -1, -1};  // x, y, z, intensity, label: first field of each role
    for (std::size_t f = 0; f < layout_.fields.size(); ++f) {
      const FieldRole role = io_internal::field_role(layout_.fields[f].name);
      const int index = role == FieldRole::X ? 0 : role == FieldRole::Y ? 1 : role == FieldRole::Z ? 2
                        : role == FieldRole::Intensity ? 3 : role == FieldRole::Label ? 4 : -1;
      if (index >= 0 && slot[index] < 0) slot[index] = static_cast<int>(f);
    }
    const char* axis_names[3] = {"x", "y", "z"};
    for (int axis = 0; axis < 3; ++axis)
      if (slot[axis] < 0) throw file_error(path, std::string("no '") + axis_names[axis] + "' field; x, y and z are required");
    for (int k = 0; k < 5; ++k) slots_[k] = slot[k];
    if (layout_.record_size == 0 && layout_.records > 0)
      throw file_error(path, "point records have no bytes");
    const std::size_t available = file_.size() >= layout_.body_offset ? file_.size() - layout_.body_offset : 0;
    if (file_.size() < layout_.body_offset ||
        (layout_.record_size != 0 && layout_.records > available / layout_.record_size))
      throw file_error(path, "truncated: the header declares " + std::to_string(layout_.records) + " points of " +
                                 std::to_string(layout_.record_size) + " bytes, but " + std::to_string(available) +
                                 " bytes follow the header");
    point_count_ = layout_.records;
    if (layout_.records > 0) {
      std::vector<double> first(3);
      std::vector<char> record(layout_.record_size);
      file_.read_at(layout_.body_offset, layout_.record_size, record.data());
      for (int axis = 0; axis < 3; ++axis) {
        const io_internal::RecordField& field = layout_.fields[static_cast<std::size_t>(slots_[axis])];
        io_internal::decode_strided(record.data() + field.offset, 0, 1, field.type, layout_.swap_bytes, &first[axis]);
      }
      origin_ = local_origin_near(Eigen::Vector3d(first[0], first[1], first[2]));
    }
  }

  bool read(std::size_t max_points, PointChunk& chunk) override {
    const std::size_t count = std::min(std::max<std::size_t>(max_points, 1), layout_.records - records_read_);
    ChunkFiller filler(chunk, count, slots_[3] >= 0, slots_[4] >= 0);
    if (count == 0) {
      filler.finish();
      return false;
    }
    buffer_.resize(count * layout_.record_size);
    file_.read_at(layout_.body_offset + records_read_ * layout_.record_size, buffer_.size(), buffer_.data());
    for (int k = 0; k < 5; ++k) {
      columns_[k].resize(count);
      if (slots_[k] < 0) continue;
      const io_internal::RecordField& field = layout_.fields[static_cast<std::size_t>(slots_[k])];
      io_internal::decode_strided(buffer_.data() + field.offset, layout_.record_size, count, field.type,
                                  layout_.swap_bytes, columns_[k].data());
    }
    for (std::size_t i = 0; i < count; ++i) {
      const std::uint32_t label =
          slots_[4] >= 0 && std::isfinite(columns_[0][i]) && std::isfinite(columns_[1][i]) && std::isfinite(columns_[2][i])
              ? checked_label(path_, layout_.fields[static_cast<std::size_t>(slots_[4])].name, records_read_ + i, columns_[4][i])
              : 0;
      if (!filler.add(columns_[0][i], columns_[1][i], columns_[2][i], static_cast<float>(columns_[3][i]), label))
        ++non_finite_dropped_;
    }
    filler.finish();
    records_read_ += count;
    return true;
  }

 private:
  io_internal::RandomAccessFile file_;
  io_internal::BinaryRecordLayout layout_;
  int slots_[5] = {-1, -1, -1, -1, -1};
  std::vector<double> columns_[5];
  std::vector<char> buffer_;
};

/// LAS records: positions scaled in double, intensity, classification as labels.
class LasStream final : public PointStream {
 public:
  explicit LasStream(const std::string& path) : reader_(path) {
    path_ = path;
    format_ = CloudFormat::Las;
    const LasHeader& header = reader_.header();
    point_count_ = static_cast<std::size_t>(header.point_count);
    const bool box_set = !(header.min.isZero(0.0) && header.max.isZero(0.0));
    if (box_set) {
      bounds_ = PointBounds{header.min, header.max};
      origin_ = local_origin_near(0.5 * (header.min + header.max));
    } else if (header.point_count > 0) {
      io_internal::LasRecordReader first(path);
      io_internal::LasRecords record;
      first.read(1, record);
      origin_ = local_origin_near(Eigen::Vector3d(record.x[0], record.y[0], record.z[0]));
    }
  }

  bool read(std::size_t max_points, PointChunk& chunk) override {
    const bool more = reader_.read(max_points, records_);
    ChunkFiller filler(chunk, records_.count, true, true);
    for (std::size_t i = 0; i < records_.count; ++i)
      if (!filler.add(records_.x[i], records_.y[i], records_.z[i], records_.intensity[i], records_.classification[i]))
        ++non_finite_dropped_;
    filler.finish();
    records_read_ += records_.count;
    return more;
  }

 private:
  io_internal::LasRecordReader reader_;
  io_internal::LasRecords records_;
};

/// XYZ text read in blocks of bytes; lines split across blocks are carried over. The same rules as
/// read_point_cloud: '#' comments, blank lines skipped, the first data line fixes the column count
/// (4 columns: x y z intensity).
class XyzStream final : public PointStream {
 public:
  explicit XyzStream(const std::string& path) : file_(path) {
    path_ = path;
    format_ = CloudFormat::Xyz;
    // The origin from the first data line (its errors come from read()).
    std::vector<char> head(std::min<std::size_t>(file_.size(), kBlockBytes));
    file_.read_at(0, head.size(), head.data());
    io_internal::LineReader lines(std::string_view(head.data(), head.size()));
    std::string_view line;
    std::vector<std::string_view> cells;
    while (lines.next(line)) {
      io_internal::split_tokens(strip_comment(line), cells);
      if (cells.empty()) continue;
      double p[3];
      if (cells.size() >= 3 && io_internal::parse_double(cells[0], p[0]) && io_internal::parse_double(cells[1], p[1]) &&
          io_internal::parse_double(cells[2], p[2]))
        origin_ = local_origin_near(Eigen::Vector3d(p[0], p[1], p[2]));
      break;
    }
  }

  bool read(std::size_t max_points, PointChunk& chunk) override {
    max_points = std::max<std::size_t>(max_points, 1);
    // Grown as lines arrive: a text line holds a point in as few as 6 bytes, so nothing is sized ahead.
    chunk.positions.resize(3, 0);
    chunk.intensity.clear();
    chunk.labels.clear();
    std::vector<double> xs, ys, zs;
    std::vector<float> intensity;
    std::size_t records = 0;
    std::string_view line;
    while (records < max_points && next_line(line)) {
      io_internal::split_tokens(strip_comment(line), cells_);
      if (cells_.empty()) continue;
      const std::string where = "line " + std::to_string(line_number_) + ": ";
      if (columns_ == 0) {
        if (cells_.size() < 3)
          throw file_error(path_, where + "has " + std::to_string(cells_.size()) + " column(s); expected at least x, y, z");
        columns_ = cells_.size();
        names_ = io_internal::headerless_column_names(columns_);
      }
      if (cells_.size() != columns_)
        throw file_error(path_, where + "has " + std::to_string(cells_.size()) + " values, expected " +
                                    std::to_string(columns_) + " like the first data line");
      double values[4] = {0, 0, 0, 0};
      for (std::size_t c = 0; c < cells_.size(); ++c) {
        double value = 0;
        if (!io_internal::parse_double(cells_[c], value))
          throw file_error(path_, where + "'" + std::string(cells_[c]) + "' is not a number (column " +
                                      std::to_string(c + 1) + ", '" + names_[c] + "')");
        if (c < 4) values[c] = value;
      }
      ++records;
      ++records_read_;
      if (!(std::isfinite(values[0]) && std::isfinite(values[1]) && std::isfinite(values[2]))) {
        ++non_finite_dropped_;
        continue;
      }
      xs.push_back(values[0]);
      ys.push_back(values[1]);
      zs.push_back(values[2]);
      if (columns_ == 4) intensity.push_back(static_cast<float>(values[3]));
    }
    chunk.positions.resize(3, static_cast<Eigen::Index>(xs.size()));
    for (std::size_t i = 0; i < xs.size(); ++i)
      chunk.positions.col(static_cast<Eigen::Index>(i)) = Eigen::Vector3d(xs[i], ys[i], zs[i]);
    chunk.intensity = std::move(intensity);
    return records > 0;
  }

 private:
  static constexpr std::size_t kBlockBytes = std::size_t{1} << 20;
  /// Longest line accepted: far beyond kMaxValuesPerPoint numbers of 24 characters, and a bound on memory.
  static constexpr std::size_t kMaxLineBytes = std::size_t{64} << 20;

  static std::string_view strip_comment(std::string_view line) {
    const std::size_t hash = line.find('#');
    return hash == std::string_view::npos ? line : line.substr(0, hash);
  }

  /// The next line (without '\n' and a trailing '\r'); false at the end of the file.
  bool next_line(std::string_view& line) {
    while (true) {
      const std::size_t end = pending_.find('\n', start_);
      if (end != std::string::npos) {
        line = std::string_view(pending_).substr(start_, end - start_);
        start_ = end + 1;
        break;
      }
      if (offset_ >= file_.size()) {
        if (start_ >= pending_.size()) return false;
        line = std::string_view(pending_).substr(start_);
        start_ = pending_.size();
        break;
      }
      pending_.erase(0, start_);
      start_ = 0;
      if (pending_.size() > kMaxLineBytes)
        throw file_error(path_, "line " + std::to_string(line_number_ + 1) + " is longer than " +
                                    std::to_string(kMaxLineBytes >> 20) + " MB (not a text point cloud?)");
      const std::size_t count = std::min(kBlockBytes, file_.size() - offset_);
      const std::size_t old = pending_.size();
      pending_.resize(old + count);
      file_.read_at(offset_, count, pending_.data() + old);
      offset_ += count;
    }
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    ++line_number_;
    return true;
  }

  io_internal::RandomAccessFile file_;
  std::string pending_;           // bytes read but not yet consumed, from start_
  std::size_t start_ = 0;
  std::size_t offset_ = 0;        // next file byte to read
  std::size_t line_number_ = 0;
  std::size_t columns_ = 0;
  std::vector<std::string> names_;
  std::vector<std::string_view> cells_;
};

/// The start of the file, enough to hold a PLY or PCD header.
std::string read_head(const std::string& path) {
  const io_internal::RandomAccessFile file(path);
  std::string head(std::min(file.size(), kMaxHeaderBytes), '\0');
  file.read_at(0, head.size(), head.data());
  return head;
}

/// Layout of a raw float32 file of `floats` values a point (x, y, z, intensity[, ring]).
io_internal::BinaryRecordLayout float_records(const std::string& path, std::size_t floats, const char* layout_text) {
  const io_internal::RandomAccessFile file(path);
  const std::size_t record = floats * sizeof(float);
  if (file.size() % record != 0)
    throw file_error(path, "size " + std::to_string(file.size()) + " bytes is not a multiple of " +
                               std::to_string(record) + " (" + layout_text + "); truncated or not this format");
  io_internal::BinaryRecordLayout layout;
  layout.encoding = "binary float32";
  layout.record_size = record;
  layout.records = file.size() / record;
  const char* names[5] = {"x", "y", "z", "intensity", "ring"};
  for (std::size_t f = 0; f < floats; ++f) layout.fields.push_back({names[f], io_internal::ScalarType::Float32, 4 * f});
  return layout;
}

}  // namespace

std::unique_ptr<PointStream> open_point_stream(const std::string& path, const PointStreamOptions& options) {
  const CloudFormat format = options.format == CloudFormat::Auto ? cloud_format_from_path(path) : options.format;
  switch (format) {
    case CloudFormat::KittiBin:
      return std::make_unique<RecordStream>(
          path, format, float_records(path, 4, "KITTI .bin stores float32 x, y, z, intensity: 16 bytes a point"));
    case CloudFormat::NuScenesBin:
      return std::make_unique<RecordStream>(
          path, format,
          float_records(path, 5, "nuScenes .pcd.bin stores float32 x, y, z, intensity, ring: 20 bytes a point"));
    case CloudFormat::Ply: return std::make_unique<RecordStream>(path, format, io_internal::ply_record_layout(path, read_head(path)));
    case CloudFormat::Pcd: return std::make_unique<RecordStream>(path, format, io_internal::pcd_record_layout(path, read_head(path)));
    case CloudFormat::Las: return std::make_unique<LasStream>(path);
    case CloudFormat::Xyz: return std::make_unique<XyzStream>(path);
    case CloudFormat::Csv:
    case CloudFormat::Npy:
    case CloudFormat::Auto: break;
  }
  throw file_error(path, "format '" + cloud_format_name(format) +
                             "' is not streamed (binary PLY, LAS, KITTI/nuScenes .bin, binary PCD and XYZ are); "
                             "read it whole with read_point_cloud");
}

}  // namespace quadrix
