// Poses: 4x4 (or 3x4) row-major text matrices, .npy matrices, KITTI pose lines and KITTI calibration.
#include "geometry/io.h"
#include "geometry/io_internal.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <ostream>

namespace quadrix {

namespace {

using io_internal::LineReader;

// Builds a pose from 12 row-major numbers (top 3 rows) and checks the rotation; `where` prefixes errors.
Eigen::Isometry3d pose_from_numbers(const std::string& path, const std::string& where, const double* numbers) {
  Eigen::Matrix4d matrix = Eigen::Matrix4d::Identity();
  for (int row = 0; row < 3; ++row)
    for (int column = 0; column < 4; ++column) matrix(row, column) = numbers[4 * row + column];
  if (!matrix.allFinite()) throw file_error(path, where + "the matrix has a non-finite entry (NaN/inf)");
  const Eigen::Matrix3d rotation = matrix.topLeftCorner<3, 3>();
  const double deviation = (rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (deviation > kPoseOrthonormalityTolerance)
    throw file_error(path, where + "the rotation part is not orthonormal (max |R^T R - I| = " + std::to_string(deviation) +
                               " > tolerance " + std::to_string(kPoseOrthonormalityTolerance) + ")");
  if (rotation.determinant() < 0)
    throw file_error(path, where + "the rotation part is a reflection (determinant " +
                               std::to_string(rotation.determinant()) + " < 0)");
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.matrix() = matrix;
  return pose;
}

void check_bottom_row(const std::string& path, const std::string& where, const double* bottom) {
  const double expected[4] = {0, 0, 0, 1};
  for (int k = 0; k < 4; ++k)
    if (!(std::abs(bottom[k] - expected[k]) <= 1e-9))
      throw file_error(path, where + "the bottom row is not 0 0 0 1 (found " + std::to_string(bottom[0]) + " " +
                                 std::to_string(bottom[1]) + " " + std::to_string(bottom[2]) + " " +
                                 std::to_string(bottom[3]) + ")");
}

// Parses every number of a line into `numbers`; Error naming the line on a non-numeric token.
void parse_numbers(const std::string& path, std::size_t line_number, const std::vector<std::string_view>& tokens,
                   std::size_t first, std::vector<double>& numbers) {
  for (std::size_t k = first; k < tokens.size(); ++k) {
    double value = 0;
    if (!io_internal::parse_double(tokens[k], value))
      throw file_error(path, "line " + std::to_string(line_number) + ": '" + std::string(tokens[k].substr(0, 40)) +
                                 (tokens[k].size() > 40 ? "...'" : "'") + " is not a number");
    numbers.push_back(value);
  }
}

bool has_npy_extension(const std::string& path) {
  std::string extension = std::filesystem::path(path).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return extension == ".npy";
}

}  // namespace

Eigen::Isometry3d read_pose_matrix(const std::string& path) {
  if (has_npy_extension(path)) {
    const io_internal::NumpyMatrix matrix = io_internal::read_npy_matrix(path);
    const std::size_t count = matrix.rows * matrix.columns;
    if (matrix.columns != 4 || (matrix.rows != 4 && matrix.rows != 3))
      throw file_error(path, ".npy pose must be a 4x4 or 3x4 array, found " + std::to_string(matrix.rows) + "x" +
                                 std::to_string(matrix.columns));
    if (count == 16) check_bottom_row(path, "", matrix.values.data() + 12);
    return pose_from_numbers(path, "", matrix.values.data());
  }
  const io_internal::FileBytes bytes = io_internal::read_file_bytes(path);
  LineReader lines(bytes.view());
  std::string_view line;
  std::vector<std::string_view> tokens;
  std::vector<double> numbers;
  std::size_t last_line = 0;
  while (lines.next(line)) {
    const std::size_t hash = line.find('#');
    if (hash != std::string_view::npos) line = line.substr(0, hash);
    io_internal::split_tokens(line, tokens, ',');
    if (tokens.empty()) continue;
    if (numbers.size() + tokens.size() > 16)
      throw file_error(path, "line " + std::to_string(lines.line_number()) +
                                 ": more than 16 numbers (expected a 4x4 or 3x4 row-major matrix)");
    const std::size_t first_of_line = numbers.size();
    parse_numbers(path, lines.line_number(), tokens, 0, numbers);
    for (std::size_t k = first_of_line; k < numbers.size(); ++k)
      if (!std::isfinite(numbers[k]))
        throw file_error(path, "line " + std::to_string(lines.line_number()) + ": the matrix has a non-finite entry (NaN/inf)");
    last_line = lines.line_number();
  }
  if (numbers.size() != 16 && numbers.size() != 12)
    throw file_error(path, "expected a 4x4 (16 numbers) or 3x4 (12 numbers) row-major matrix, found " +
                               std::to_string(numbers.size()) + " numbers");
  const std::string where = "line " + std::to_string(last_line) + ": ";
  if (numbers.size() == 16) check_bottom_row(path, where, numbers.data() + 12);
  return pose_from_numbers(path, where, numbers.data());
}

void write_pose_matrix(const std::string& path, const Eigen::Isometry3d& pose) {
  const Eigen::Matrix4d matrix = pose.matrix();
  if (!matrix.allFinite()) throw file_error(path, "cannot write pose: it has a non-finite entry");
  std::string text;
  for (int row = 0; row < 4; ++row) {
    for (int column = 0; column < 4; ++column) {
      if (column) text += ' ';
      io_internal::append_number(text, matrix(row, column));
    }
    text += '\n';
  }
  write_file_atomically(path, [&](std::ostream& stream) { stream << text; });
}

std::vector<Eigen::Isometry3d> read_kitti_poses(const std::string& path) {
  const io_internal::FileBytes bytes = io_internal::read_file_bytes(path);
  LineReader lines(bytes.view());
  std::string_view line;
  std::vector<std::string_view> tokens;
  std::vector<double> numbers;
  std::vector<Eigen::Isometry3d> poses;
  while (lines.next(line)) {
    io_internal::split_tokens(line, tokens);
    if (tokens.empty() || tokens[0].front() == '#') continue;
    const std::string where = "line " + std::to_string(lines.line_number()) + ": ";
    if (tokens.size() != 12)
      throw file_error(path, where + "expected 12 numbers (row-major 3x4 pose), found " + std::to_string(tokens.size()));
    numbers.clear();
    parse_numbers(path, lines.line_number(), tokens, 0, numbers);
    poses.push_back(pose_from_numbers(path, where, numbers.data()));
  }
  return poses;
}

namespace {

// Finds the Tr line; `sequence` < 0 accepts only "Tr:"/"Tr_velo_to_cam:", else also "seqA-B"/"seqA" lines.
Eigen::Isometry3d read_calibration(const std::string& path, int sequence) {
  const io_internal::FileBytes bytes = io_internal::read_file_bytes(path);
  LineReader lines(bytes.view());
  std::string_view line;
  std::vector<std::string_view> tokens;
  std::vector<double> numbers;
  std::vector<std::string> sequence_keys;
  while (lines.next(line)) {
    io_internal::split_tokens(line, tokens);
    if (tokens.empty() || tokens[0].front() == '#') continue;
    std::string key(tokens[0]);
    const std::string where = "line " + std::to_string(lines.line_number()) + ": ";
    bool match = key == "Tr:" || key == "Tr_velo_to_cam:";
    if (!match && key.rfind("seq", 0) == 0) {
      sequence_keys.push_back(key);
      std::string range = key.substr(3);
      if (!range.empty() && range.back() == ':') range.pop_back();
      const std::size_t dash = range.find('-');
      std::size_t first = 0, last = 0;
      const bool valid = dash == std::string::npos
                             ? io_internal::parse_size(range, first)
                             : io_internal::parse_size(std::string_view(range).substr(0, dash), first) &&
                                   io_internal::parse_size(std::string_view(range).substr(dash + 1), last);
      if (!valid) throw file_error(path, where + "'" + key + "' is not a sequence key like seq03 or seq04-12");
      if (dash == std::string::npos) last = first;
      match = sequence >= 0 && static_cast<std::size_t>(sequence) >= first && static_cast<std::size_t>(sequence) <= last;
    }
    if (!match) continue;
    if (tokens.size() != 13)
      throw file_error(path, where + "'" + key + "' must be followed by 12 numbers (row-major 3x4), found " +
                                 std::to_string(tokens.size() - 1));
    numbers.clear();
    parse_numbers(path, lines.line_number(), tokens, 1, numbers);
    return pose_from_numbers(path, where, numbers.data());
  }
  if (sequence < 0 && !sequence_keys.empty())
    throw file_error(path, "has no 'Tr:' line but per-sequence lines (" + sequence_keys.front() +
                               ", ...); pass the sequence number to read_kitti_calibration");
  if (sequence >= 0)
    throw file_error(path, "has no 'Tr:' line and no 'seq' line covering sequence " + std::to_string(sequence));
  throw file_error(path, "has no 'Tr:' or 'Tr_velo_to_cam:' line (not a KITTI calibration file?)");
}

}  // namespace

Eigen::Isometry3d read_kitti_calibration(const std::string& path) { return read_calibration(path, -1); }

Eigen::Isometry3d read_kitti_calibration(const std::string& path, int sequence) {
  if (sequence < 0) throw file_error(path, "sequence number " + std::to_string(sequence) + " is negative");
  return read_calibration(path, sequence);
}

}  // namespace quadrix
