// Shared pieces of the io_*.cpp readers and writers (not a public header: only io_*.cpp include it).
#pragma once

#include "geometry/error.h"
#include "geometry/io.h"
#include "geometry/las.h"

#include <array>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace quadrix::io_internal {

/// A whole file read with one bulk read.
struct FileBytes {
  std::unique_ptr<char[]> data;  ///< the bytes (not zero-terminated)
  std::size_t size = 0;          ///< number of bytes
  /// The bytes as a string view.
  std::string_view view() const { return {data.get(), size}; }
};

/// Reads `path` completely; Error naming the file when it cannot be opened or read, or is not a
/// regular file (a FIFO or a device would block or never end).
FileBytes read_file_bytes(const std::string& path);

/// The size of the regular file `path` in bytes, before any of it is read; Error naming the file
/// when it does not exist or is not a regular file.
std::size_t regular_file_size(const std::string& path);
/// A regular file open for positioned reads (the streaming readers): its size known up front, every
/// read checked. FIFOs and devices are refused, so nothing blocks or reads without bound.
class RandomAccessFile {
 public:
  /// Opens `path`; Error naming it when it cannot be opened or is not a regular file.
  explicit RandomAccessFile(const std::string& path);
  ~RandomAccessFile();
  RandomAccessFile(const RandomAccessFile&) = delete;
  RandomAccessFile& operator=(const RandomAccessFile&) = delete;
  /// Bytes in the file when it was opened.
  std::size_t size() const { return size_; }
  /// Reads exactly `count` bytes at `offset` into `destination`; Error naming the file when they are not there.
  void read_at(std::size_t offset, std::size_t count, char* destination) const;
  /// The file's path.
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  int descriptor_ = -1;
  std::size_t size_ = 0;
};

/// Scalar storage types of binary formats.
enum class ScalarType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Int64, UInt64, Float32, Float64 };

/// Bytes of one value of `type`.
std::size_t scalar_size(ScalarType type);
/// True for Float32/Float64.
bool scalar_is_floating(ScalarType type);

/// Decodes `count` values of `type` found at `source + i * stride` into `destination[i]`;
/// `swap_bytes` for data whose byte order differs from the machine's (little endian).
void decode_strided(const char* source, std::size_t stride, std::size_t count, ScalarType type, bool swap_bytes,
                    double* destination);

/// The role a field plays by its (case-insensitive) name, as read_point_cloud documents.
enum class FieldRole { X, Y, Z, Intensity, Label, Red, Green, Blue, Extra };
/// Role of the field called `name`.
FieldRole field_role(const std::string& name);

/// Most values a point a cloud reader accepts (the sum of a PCD header's COUNTs, the columns of a
/// .npy array): each becomes a column, and a file of zero points has no data to bound their number.
inline constexpr std::size_t kMaxValuesPerPoint = 65536;

/// One per-point field as read from a file, before its role (position, intensity, ...) is assigned.
struct FieldColumn {
  std::string name;             ///< field name as in the file (or from headerless_column_names)
  bool floating_point = true;   ///< stored as a floating-point type in the file
  std::vector<double> values;   ///< one value per record
};

/// Turns columns into a PointCloud (roles by name, see read_point_cloud), dropping points with a
/// non-finite coordinate; sets report.points_in_file and report.non_finite_dropped.
PointCloud assemble_cloud(const std::string& path, std::vector<FieldColumn>& columns, std::size_t rows,
                          const CloudReadOptions& options, CloudReadReport& report);

/// Error for a non-finite coordinate under reject_non_finite: names the file, the point and the field.
[[noreturn]] void throw_non_finite(const std::string& path, std::size_t point_index, const char* field);

/// Column names of files without a header: x y z | x y z intensity | x y z red green blue | x y z column_4...
std::vector<std::string> headerless_column_names(std::size_t column_count);

/// Parses a whole token as a double (leading '+' allowed, "nan"/"inf" accepted); false if not a number.
bool parse_double(std::string_view token, double& value);
/// Parses a whole token as a non-negative integer; false otherwise.
bool parse_size(std::string_view token, std::size_t& value);

/// Splits `line` at spaces/tabs (and at `extra_separator` when not 0) into tokens, reusing `tokens`.
void split_tokens(std::string_view line, std::vector<std::string_view>& tokens, char extra_separator = 0);

/// Walks a text buffer line by line, counting lines from 1 and stripping a trailing '\r'.
class LineReader {
 public:
  /// Reads `text` starting at byte `offset`, whose first line is numbered `first_line_number`.
  LineReader(std::string_view text, std::size_t offset = 0, std::size_t first_line_number = 1)
      : text_(text), position_(offset), next_line_number_(first_line_number) {}
  /// Fetches the next line into `line`; false at the end of the text.
  bool next(std::string_view& line);
  /// Number of the line last returned by next().
  std::size_t line_number() const { return next_line_number_ - 1; }
  /// Byte offset just after the line last returned by next().
  std::size_t position() const { return position_; }

 private:
  std::string_view text_;
  std::size_t position_;
  std::size_t next_line_number_;
};

/// Formats a float with the shortest text that reads back to the same float.
void append_number(std::string& out, float value);
/// Formats a double with the shortest text that reads back to the same double.
void append_number(std::string& out, double value);
/// Formats an unsigned integer.
void append_number(std::string& out, std::uint64_t value);

/// Checks every optional field of `cloud` has one entry a point; Error naming `path` and the field otherwise.
void check_cloud_consistent(const std::string& path, const PointCloud& cloud);
/// Checks an extra-field name can be written in a text header (non-empty, no whitespace, not a reserved name).
void check_extra_field_name(const std::string& path, const std::string& name);

// Per-format readers and writers (defined in io_binary.cpp, io_ply.cpp, io_pcd.cpp, io_text.cpp).
PointCloud read_kitti_bin(const std::string& path, const CloudReadOptions& options, CloudReadReport& report);
PointCloud read_nuscenes_bin(const std::string& path, const CloudReadOptions& options, CloudReadReport& report);
PointCloud read_npy_cloud(const std::string& path, const CloudReadOptions& options, CloudReadReport& report);
PointCloud read_ply_cloud(const std::string& path, const CloudReadOptions& options, CloudReadReport& report);
PointCloud read_pcd_cloud(const std::string& path, const CloudReadOptions& options, CloudReadReport& report);
PointCloud read_xyz_cloud(const std::string& path, const CloudReadOptions& options, CloudReadReport& report);
PointCloud read_csv_cloud(const std::string& path, const CloudReadOptions& options, CloudReadReport& report);
PointCloud read_las_cloud(const std::string& path, const CloudReadOptions& options, CloudReadReport& report);
void write_ply_cloud(const std::string& path, const PointCloud& cloud, bool binary);
void write_pcd_cloud(const std::string& path, const PointCloud& cloud, bool binary);

/// One scalar field of a fixed-size binary record.
struct RecordField {
  std::string name;                           ///< as in the header
  ScalarType type = ScalarType::Float32;      ///< storage type
  std::size_t offset = 0;                     ///< byte offset inside the record
};

/// Where the fixed-size point records of a binary file are and what they hold (streaming readers).
struct BinaryRecordLayout {
  std::string encoding;                       ///< e.g. "binary_little_endian"
  std::size_t body_offset = 0;                ///< byte of the first record
  std::size_t record_size = 0;                ///< bytes a record
  std::size_t records = 0;                    ///< records declared
  bool swap_bytes = false;                    ///< big-endian data
  std::vector<RecordField> fields;            ///< scalar fields
};

/// The vertex records of a binary PLY whose header is in `text` (the start of the file). Error for
/// ascii, a vertex element with list properties, or an earlier element with lists (records of
/// variable size cannot be skipped without reading them).
BinaryRecordLayout ply_record_layout(const std::string& path, std::string_view text);
/// The point records of a DATA binary PCD whose header is in `text`. Error for ascii and binary_compressed.
BinaryRecordLayout pcd_record_layout(const std::string& path, std::string_view text);

/// LAS point records decoded into columns (file coordinates in double).
struct LasRecords {
  std::size_t count = 0;                                  ///< records decoded
  std::vector<double> x, y, z;                            ///< X * scale + offset
  std::vector<std::uint16_t> intensity;                   ///< as stored
  std::vector<std::uint8_t> classification;               ///< class (formats 0-5: low 5 bits)
  std::vector<std::uint8_t> return_number;                ///< 1-based return of the pulse
  std::vector<std::uint8_t> number_of_returns;            ///< returns of the pulse
  std::vector<std::array<std::uint16_t, 3>> rgb;          ///< formats 2, 3, 5, 7, 8, 10 only
};

/// Reads the point records of a LAS file in order, block by block, with the header checked first.
/// Every decoded point is checked against the header's bounding box (Error naming the field).
class LasRecordReader {
 public:
  /// Opens `path` and reads its header (read_las_header).
  explicit LasRecordReader(const std::string& path);
  /// The checked header.
  const LasHeader& header() const { return header_; }
  /// True when the format carries RGB.
  bool has_rgb() const;
  /// Decodes the next at most `max_records` records into `records`; false when none remain.
  bool read(std::size_t max_records, LasRecords& records);
  /// Records decoded so far.
  std::size_t records_read() const { return next_record_; }

 private:
  RandomAccessFile file_;
  LasHeader header_;
  std::size_t next_record_ = 0;
  std::vector<char> buffer_;
};

/// A NumPy array of floating-point numbers, rows x columns, converted to double (row-major).
struct NumpyMatrix {
  std::size_t rows = 0;          ///< first dimension
  std::size_t columns = 0;       ///< second dimension (1 for a 1-D array)
  std::string dtype;             ///< descr as in the header, e.g. "<f8"
  std::vector<double> values;    ///< row-major values
};
/// Reads a 1-D or 2-D float32/float64 .npy file (v1/v2/v3, either byte order, C or Fortran order).
NumpyMatrix read_npy_matrix(const std::string& path);

}  // namespace quadrix::io_internal
