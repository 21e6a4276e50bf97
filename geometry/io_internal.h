// Shared pieces of the io_*.cpp readers and writers (not a public header: only io_*.cpp include it).
#pragma once

#include "geometry/error.h"
#include "geometry/io.h"

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
void write_ply_cloud(const std::string& path, const PointCloud& cloud, bool binary);
void write_pcd_cloud(const std::string& path, const PointCloud& cloud, bool binary);

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
