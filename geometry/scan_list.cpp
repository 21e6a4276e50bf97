// Scan lists (SCANS.tsv, the KITTI odometry layout) and pose tables (poses.tsv): parsing and the
// checks that name the row of bad input.
#include "geometry/scan_list.h"

#include "geometry/error.h"
#include "geometry/io.h"
#include "geometry/text_fields.h"

#include <Eigen/SVD>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace quadrix {
namespace {

std::vector<std::string> whitespace_tokens(const std::string& text) {
  std::vector<std::string> tokens;
  std::istringstream stream(text);
  std::string token;
  while (stream >> token) tokens.push_back(token);
  return tokens;
}

bool parse_number(const std::string& token, double& value) {
  errno = 0;
  char* end = nullptr;
  value = std::strtod(token.c_str(), &end);
  return end != token.c_str() && *end == '\0' && errno != ERANGE && std::isfinite(value);
}

/// A rigid pose from 12 row-major numbers; the rotation is projected onto SO(3) once it is
/// orthonormal within kPoseOrthonormalityTolerance (text poses carry 6 digits).
Eigen::Isometry3d pose_from_tokens(const std::vector<std::string>& tokens, const std::string& where) {
  if (tokens.size() != 12)
    throw Error(where + "expected 12 numbers (row-major 3x4 pose) or '-', found " + std::to_string(tokens.size()) + " fields");
  Eigen::Matrix<double, 3, 4> matrix;
  for (int index = 0; index < 12; ++index) {
    double value = 0.0;
    if (!parse_number(tokens[static_cast<std::size_t>(index)], value))
      throw Error(where + "pose number " + std::to_string(index + 1) + " '" + tokens[static_cast<std::size_t>(index)] +
                  "' is not a finite number");
    matrix(index / 4, index % 4) = value;
  }
  const Eigen::Matrix3d rotation = matrix.leftCols<3>();
  const double deviation = (rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (deviation > kPoseOrthonormalityTolerance || rotation.determinant() < 0.0)
    throw Error(where + "the pose's 3x3 part is not a rotation (max |R^T R - I| = " + std::to_string(deviation) +
                ", det " + std::to_string(rotation.determinant()) + ")");
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(rotation, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = svd.matrixU() * svd.matrixV().transpose();
  pose.translation() = matrix.col(3);
  return pose;
}

/// Checks that sessions are contiguous, hold at least two scans, and list no scan twice.
void check_sessions(ScanList& list) {
  std::set<std::string> closed;
  std::set<std::pair<std::string, std::string>> seen;
  std::map<std::string, std::size_t> counts;
  std::map<std::string, std::size_t> first_row;
  std::map<std::string, bool> has_odometry;
  std::string current;
  for (const ScanEntry& entry : list.scans) {
    const std::string where = list.source + ": row " + std::to_string(entry.row) + ": ";
    if (entry.session != current) {
      if (closed.count(entry.session))
        throw Error(where + "session '" + entry.session + "' continues after another session began (scans of a session must be adjacent rows, in time order)");
      if (!current.empty()) closed.insert(current);
      current = entry.session;
      list.sessions.push_back(entry.session);
      first_row[entry.session] = entry.row;
      has_odometry[entry.session] = entry.odometry.has_value();
    }
    if (!seen.insert({entry.session, entry.path}).second)
      throw Error(where + "scan '" + entry.scan + "' of session '" + entry.session + "' is listed twice");
    if (has_odometry[entry.session] != entry.odometry.has_value())
      throw Error(where + "session '" + entry.session + "' gives odometry on some rows and '-' on others (row " +
                  std::to_string(first_row[entry.session]) + "): give it on every row or on none");
    ++counts[entry.session];
  }
  if (list.scans.empty()) throw Error(list.source + ": no scans listed");
  for (const auto& [session, count] : counts)
    if (count < 2)
      throw Error(list.source + ": row " + std::to_string(first_row[session]) + ": session '" + session +
                  "' has one scan; a session needs at least two (a single scan has no trajectory)");
}

}  // namespace

ScanList read_scan_list(const std::string& path) {
  std::ifstream stream(path);
  if (!stream) throw file_error(path, "cannot open the scan list");
  ScanList list;
  list.source = path;
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  std::string line;
  std::size_t row = 0;
  int session_column = -1, scan_column = -1, odometry_column = -1;
  std::size_t header_fields = 0;
  while (std::getline(stream, line)) {
    ++row;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (trimmed(line).empty() || trimmed(line).front() == '#') continue;
    std::vector<std::string> fields = split_fields(line, '\t');
    if (session_column < 0) {
      for (std::size_t index = 0; index < fields.size(); ++index) {
        const std::string name = trimmed(fields[index]);
        if (name == "session") session_column = static_cast<int>(index);
        if (name == "scan") scan_column = static_cast<int>(index);
        if (name == "odometry") odometry_column = static_cast<int>(index);
      }
      if (session_column < 0 || scan_column < 0 || odometry_column < 0)
        throw file_error(path, "row " + std::to_string(row) +
                                   ": expected a header of tab-separated columns session, scan and odometry");
      header_fields = fields.size();
      continue;
    }
    const std::string where = path + ": row " + std::to_string(row) + ": ";
    const std::size_t needed = static_cast<std::size_t>(std::max({session_column, scan_column, odometry_column})) + 1;
    if (fields.size() < needed)
      throw Error(where + "expected " + std::to_string(header_fields) + " tab-separated fields, found " + std::to_string(fields.size()));
    ScanEntry entry;
    entry.row = row;
    entry.session = trimmed(fields[static_cast<std::size_t>(session_column)]);
    entry.scan = trimmed(fields[static_cast<std::size_t>(scan_column)]);
    if (entry.session.empty()) throw Error(where + "empty session");
    if (entry.scan.empty()) throw Error(where + "empty scan");
    const std::filesystem::path scan_path(entry.scan);
    entry.path = (scan_path.is_absolute() ? scan_path : folder / scan_path).lexically_normal().string();
    if (!std::filesystem::is_regular_file(entry.path))
      throw Error(where + "scan file '" + entry.path + "' does not exist");
    const std::string odometry = trimmed(fields[static_cast<std::size_t>(odometry_column)]);
    if (odometry != "-") entry.odometry = pose_from_tokens(whitespace_tokens(odometry), where + "odometry: ");
    list.scans.push_back(std::move(entry));
  }
  if (session_column < 0) throw file_error(path, "empty scan list (expected a header: session, scan, odometry)");
  check_sessions(list);
  return list;
}

ScanList read_kitti_scan_list(const std::string& velodyne_folder, const std::string& poses, const std::string& calibration,
                              const std::string& session) {
  if (!std::filesystem::is_directory(velodyne_folder)) throw file_error(velodyne_folder, "not a folder of KITTI .bin scans");
  std::vector<std::string> files;
  for (const auto& item : std::filesystem::directory_iterator(velodyne_folder))
    if (item.is_regular_file() && item.path().extension() == ".bin") files.push_back(item.path().string());
  std::sort(files.begin(), files.end());
  ScanList list;
  list.source = velodyne_folder;
  std::vector<Eigen::Isometry3d> camera_poses;
  if (!poses.empty()) camera_poses = read_kitti_poses(poses);
  Eigen::Isometry3d lidar_to_camera = Eigen::Isometry3d::Identity();
  if (!calibration.empty()) lidar_to_camera = read_kitti_calibration(calibration);
  for (const std::string& file : files) {
    ScanEntry entry;
    entry.session = session;
    entry.scan = std::filesystem::path(file).filename().string();
    entry.path = file;
    const std::string stem = std::filesystem::path(file).stem().string();
    char* end = nullptr;
    const unsigned long frame = std::strtoul(stem.c_str(), &end, 10);
    if (end == stem.c_str() || *end != '\0') throw file_error(file, "KITTI scans are named by their frame number (000000.bin)");
    entry.row = frame;
    if (!poses.empty()) {
      if (frame >= camera_poses.size())
        throw file_error(poses, "has " + std::to_string(camera_poses.size()) + " poses, but frame " + std::to_string(frame) + " is listed");
      entry.odometry = lidar_to_camera.inverse() * camera_poses[frame] * lidar_to_camera;
    }
    list.scans.push_back(std::move(entry));
  }
  check_sessions(list);
  return list;
}

std::vector<PoseRow> read_pose_table(const std::string& path) {
  std::ifstream stream(path);
  if (!stream) throw file_error(path, "cannot open the pose table");
  std::vector<PoseRow> rows;
  std::string line;
  std::size_t row = 0;
  bool header = false;
  int frame_column = -1;
  while (std::getline(stream, line)) {
    ++row;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (trimmed(line).empty() || trimmed(line).front() == '#') continue;
    const std::vector<std::string> fields = split_fields(line, '\t');
    if (!header) {
      if (fields.size() < 3 || trimmed(fields[0]) != "session" || trimmed(fields[1]) != "scan")
        throw file_error(path, "row " + std::to_string(row) + ": expected a header beginning with the tab-separated columns session, scan");
      for (std::size_t index = 2; index < fields.size(); ++index)
        if (trimmed(fields[index]) == "frame") frame_column = static_cast<int>(index);
      header = true;
      continue;
    }
    const std::string where = path + ": row " + std::to_string(row) + ": ";
    if (fields.size() < 3) throw Error(where + "expected session, scan and the 12 numbers of a pose");
    PoseRow pose;
    pose.session = trimmed(fields[0]);
    pose.scan = trimmed(fields[1]);
    std::vector<std::string> tokens;
    for (std::size_t index = 2; index < fields.size() && tokens.size() < 12; ++index) {
      if (static_cast<int>(index) == frame_column) continue;
      for (const std::string& token : whitespace_tokens(fields[index])) tokens.push_back(token);
    }
    pose.pose = pose_from_tokens(tokens, where);
    if (frame_column >= 0 && static_cast<std::size_t>(frame_column) < fields.size()) pose.frame = trimmed(fields[static_cast<std::size_t>(frame_column)]);
    rows.push_back(std::move(pose));
  }
  if (!header) throw file_error(path, "empty pose table (expected a header: session, scan, pose)");
  return rows;
}

}  // namespace quadrix
