// Benchmark pairs: pairs.tsv, the paper's loop-closure and odometry rules, published lists (see bench_pairs.h).
#include "experiments/benchmark/bench_pairs.h"

#include "geometry/error.h"
#include "geometry/io.h"
#include "geometry/text_fields.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <sstream>

namespace quadrix {
namespace {

namespace fs = std::filesystem;

std::string frame_name(int frame) {
  char name[16];
  std::snprintf(name, sizeof(name), "%06d", frame);
  return name;
}

std::string number_text(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

// Uniform spatial sampling: group by the grid cell of `positions[k]`, visit cells round-robin,
// take members in seeded random order, until `limit` are taken. Returns the kept indices, sorted.
std::vector<std::size_t> sample_spatially(const std::vector<Eigen::Vector3d>& positions, std::size_t limit, double cell,
                                          std::uint64_t seed) {
  std::vector<std::size_t> kept;
  if (positions.size() <= limit) {
    for (std::size_t k = 0; k < positions.size(); ++k) kept.push_back(k);
    return kept;
  }
  if (!(cell > 0.0)) throw Error("spatial sampling: the cell size must be positive, got " + number_text(cell));
  std::map<std::array<long long, 3>, std::vector<std::size_t>> cells;
  for (std::size_t k = 0; k < positions.size(); ++k) {
    const std::array<long long, 3> key{static_cast<long long>(std::floor(positions[k].x() / cell)),
                                       static_cast<long long>(std::floor(positions[k].y() / cell)),
                                       static_cast<long long>(std::floor(positions[k].z() / cell))};
    cells[key].push_back(k);
  }
  std::mt19937_64 random(seed);
  std::vector<std::vector<std::size_t>> members;
  for (auto& entry : cells) {
    std::shuffle(entry.second.begin(), entry.second.end(), random);
    members.push_back(std::move(entry.second));
  }
  for (std::size_t round = 0; kept.size() < limit; ++round)
    for (const std::vector<std::size_t>& cell_members : members) {
      if (kept.size() == limit) break;
      if (round < cell_members.size()) kept.push_back(cell_members[round]);
    }
  std::sort(kept.begin(), kept.end());
  return kept;
}

BenchPair make_kitti_pair(const KittiSequence& sequence, std::size_t a, std::size_t b, const std::string& mode,
                          const std::string& kind, const std::string& difficulty) {
  const int i = sequence.frames[a];
  const int j = sequence.frames[b];
  const Eigen::Isometry3d& pose_i = sequence.lidar_poses[static_cast<std::size_t>(i)];
  const Eigen::Isometry3d& pose_j = sequence.lidar_poses[static_cast<std::size_t>(j)];
  BenchPair pair;
  pair.id = "kitti" + sequence.name + "_" + mode + "_" + std::to_string(i) + "_" + std::to_string(j);
  if (!sequence.cloud_paths.empty()) {
    pair.source = sequence.cloud_paths[a];
    pair.target = sequence.cloud_paths[b];
  }
  pair.ground_truth = pose_j.inverse() * pose_i;  // T_j_from_i = L(j)^-1 L(i)
  pair.ground_truth_quality = "exact";
  pair.sensor = "HDL-64E";
  pair.kind = kind;
  pair.difficulty = difficulty;
  pair.distance = (pose_i.translation() - pose_j.translation()).norm();
  return pair;
}

}  // namespace

std::vector<BenchPair> read_pairs_tsv(const std::string& path) {
  std::ifstream file(path);
  if (!file) throw file_error(path, "cannot open the pairs file");
  const fs::path folder = fs::path(path).parent_path();
  const auto resolve = [&](const std::string& relative) {
    const fs::path p(relative);
    return (p.is_absolute() ? p : folder / p).lexically_normal().string();
  };
  std::string line;
  std::size_t line_number = 0;
  std::map<std::string, std::size_t> columns;
  std::vector<BenchPair> pairs;
  std::set<std::string> ids;
  while (std::getline(file, line)) {
    ++line_number;
    const std::string where = path + ":" + std::to_string(line_number);
    if (trimmed(line).empty() || trimmed(line)[0] == '#') continue;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::vector<std::string> fields = split_fields(line, '\t');
    if (columns.empty()) {
      for (std::size_t c = 0; c < fields.size(); ++c) columns[trimmed(fields[c])] = c;
      for (const char* required : {"id", "source", "target", "gt"})
        if (!columns.count(required))
          throw Error(where + ": header lacks the column '" + required +
                      "' (expected tab-separated: id source target gt [gt_quality sensor kind t_m rot_deg])");
      continue;
    }
    if (fields.size() != columns.size())
      throw Error(where + ": " + std::to_string(fields.size()) + " tab-separated fields, expected " +
                  std::to_string(columns.size()) + " (as many as the header)");
    const auto field = [&](const char* name) -> std::string {
      const auto found = columns.find(name);
      return found == columns.end() ? std::string() : trimmed(fields[found->second]);
    };
    BenchPair pair;
    pair.id = field("id");
    if (pair.id.empty()) throw Error(where + ": empty id");
    if (!ids.insert(pair.id).second) throw Error(where + ": duplicate id '" + pair.id + "'");
    if (field("source").empty() || field("target").empty()) throw Error(where + ": empty source or target path");
    pair.source = resolve(field("source"));
    pair.target = resolve(field("target"));
    const std::string quality = field("gt_quality");
    pair.ground_truth_quality = quality.empty() ? "exact" : quality;
    const std::string gt = field("gt");
    if (gt.empty() || gt == "-" || pair.ground_truth_quality == "none") {
      pair.ground_truth_quality = "none";
    } else {
      try {
        pair.ground_truth = read_pose_matrix(resolve(gt));
      } catch (const Error& error) {
        throw Error(where + ": ground truth of '" + pair.id + "': " + error.what());
      }
    }
    pair.sensor = field("sensor");
    pair.kind = field("kind");
    pair.difficulty = pair.kind.empty() ? "all" : pair.kind;
    const std::string distance = field("t_m");
    if (!distance.empty() && distance != "-") {
      try {
        std::size_t used = 0;
        pair.distance = std::stod(distance, &used);
        if (used != distance.size()) throw std::invalid_argument(distance);
      } catch (const std::exception&) {
        throw Error(where + ": t_m '" + distance + "' is not a number (or '-')");
      }
    }
    const auto label_file = [&](const char* name) {
      const std::string value = field(name);
      return value.empty() || value == "-" ? std::string() : resolve(value);
    };
    pair.source_labels = label_file("source_labels");
    pair.target_labels = label_file("target_labels");
    pairs.push_back(std::move(pair));
  }
  if (columns.empty()) throw file_error(path, "empty pairs file (expected a header line)");
  return pairs;
}

std::string kitti_frame_path(const std::string& root, const std::string& sequence, int frame) {
  const fs::path folder = fs::path(root) / "sequences" / sequence / "velodyne";
  const fs::path bin = folder / (frame_name(frame) + ".bin");
  if (fs::exists(bin)) return bin.string();
  if (!fs::is_directory(folder)) return "";
  std::vector<std::string> candidates;
  for (const auto& entry : fs::directory_iterator(folder))
    if (entry.path().stem() == frame_name(frame)) candidates.push_back(entry.path().string());
  std::sort(candidates.begin(), candidates.end());
  for (const std::string& candidate : candidates) {
    try {
      cloud_format_from_path(candidate);
      return candidate;
    } catch (const Error&) {
    }
  }
  return "";
}

KittiSequence kitti_sequence_from_poses(const std::string& name, const std::vector<Eigen::Isometry3d>& lidar_poses) {
  KittiSequence sequence;
  sequence.name = name;
  sequence.lidar_poses = lidar_poses;
  for (std::size_t i = 0; i < lidar_poses.size(); ++i) sequence.frames.push_back(static_cast<int>(i));
  return sequence;
}

KittiSequence load_kitti_sequence(const std::string& root, const std::string& sequence_name,
                                  const std::string& calibration_path) {
  const fs::path base(root);
  const fs::path sequence_folder = base / "sequences" / sequence_name;
  const fs::path velodyne = sequence_folder / "velodyne";
  if (!fs::is_directory(velodyne)) throw file_error(velodyne.string(), "no such folder (expected ROOT/sequences/SS/velodyne)");
  fs::path poses_path = base / "poses" / (sequence_name + ".txt");
  if (!fs::exists(poses_path)) poses_path = sequence_folder / "poses.txt";
  if (!fs::exists(poses_path))
    throw file_error((base / "poses" / (sequence_name + ".txt")).string(),
                     "no pose file (expected ROOT/poses/SS.txt or ROOT/sequences/SS/poses.txt)");
  int sequence_number = 0;
  try {
    sequence_number = std::stoi(sequence_name);
  } catch (const std::exception&) {
    throw Error("KITTI sequence '" + sequence_name + "': expected a number such as 00");
  }
  const fs::path calibration = calibration_path.empty() ? sequence_folder / "calib.txt" : fs::path(calibration_path);
  if (!fs::exists(calibration)) throw file_error(calibration.string(), "no calibration file (give --calib FILE)");
  const Eigen::Isometry3d velodyne_to_camera = read_kitti_calibration(calibration.string(), sequence_number);
  std::vector<Eigen::Isometry3d> lidar_poses;
  for (const Eigen::Isometry3d& camera_pose : read_kitti_poses(poses_path.string()))
    lidar_poses.push_back(camera_pose * velodyne_to_camera);  // LiDAR pose of frame i = P(i) Tr

  KittiSequence sequence;
  sequence.name = sequence_name;
  sequence.lidar_poses = std::move(lidar_poses);
  std::set<int> frames;
  for (const auto& entry : fs::directory_iterator(velodyne)) {
    const std::string stem = entry.path().stem().string();
    if (stem.size() != 6 || !std::all_of(stem.begin(), stem.end(), [](char c) { return c >= '0' && c <= '9'; })) continue;
    frames.insert(std::stoi(stem));
  }
  for (const int frame : frames) {
    if (static_cast<std::size_t>(frame) >= sequence.lidar_poses.size())
      throw file_error(poses_path.string(), "has " + std::to_string(sequence.lidar_poses.size()) + " poses but frame " +
                                                frame_name(frame) + " exists in " + velodyne.string());
    const std::string cloud = kitti_frame_path(root, sequence_name, frame);
    if (cloud.empty()) continue;
    sequence.frames.push_back(frame);
    sequence.cloud_paths.push_back(cloud);
  }
  return sequence;
}

std::string DistanceBin::name() const { return number_text(minimum) + "-" + number_text(maximum); }

std::vector<DistanceBin> parse_distance_bins(const std::string& text) {
  std::vector<DistanceBin> bins;
  for (const std::string& entry : split_fields(text, ',')) {
    const std::string item = trimmed(entry);
    const auto dash = item.find('-', 1);
    DistanceBin bin;
    try {
      if (dash == std::string::npos) throw std::invalid_argument(item);
      std::size_t used_min = 0;
      std::size_t used_max = 0;
      const std::string low = item.substr(0, dash);
      const std::string high = item.substr(dash + 1);
      bin.minimum = std::stod(low, &used_min);
      bin.maximum = std::stod(high, &used_max);
      if (used_min != low.size() || used_max != high.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw Error("--bins entry '" + item + "': expected MIN-MAX in metres, e.g. 0-10");
    }
    if (!(bin.minimum >= 0.0 && bin.maximum > bin.minimum))
      throw Error("--bins entry '" + item + "': expected 0 <= MIN < MAX");
    bins.push_back(bin);
  }
  if (bins.empty()) throw Error("--bins: no bin given (expected e.g. 0-10,10-20,20-30)");
  return bins;
}

std::vector<double> parse_odometry_distances(const std::string& text) {
  std::vector<double> distances;
  const auto parse = [&](const std::string& item) {
    try {
      std::size_t used = 0;
      const double value = std::stod(item, &used);
      if (used != item.size() || !(value > 0.0)) throw std::invalid_argument(item);
      return value;
    } catch (const std::exception&) {
      throw Error("--distance entry '" + item + "': expected a positive distance in metres, a list 1,5,10 or a range 1..10");
    }
  };
  for (const std::string& entry : split_fields(text, ',')) {
    const std::string item = trimmed(entry);
    const auto dots = item.find("..");
    if (dots == std::string::npos) {
      distances.push_back(parse(item));
      continue;
    }
    const double first = parse(item.substr(0, dots));
    const double last = parse(item.substr(dots + 2));
    if (last < first) throw Error("--distance range '" + item + "': the end is below the start");
    for (double d = first; d <= last + 1e-9; d += 1.0) distances.push_back(d);
  }
  if (distances.empty()) throw Error("--distance: no distance given (expected e.g. 1..10)");
  return distances;
}

std::vector<BenchPair> generate_loop_closure_pairs(const KittiSequence& sequence, const std::vector<DistanceBin>& bins,
                                                   const LoopClosureOptions& options) {
  std::vector<BenchPair> pairs;
  const std::size_t n = sequence.frames.size();
  for (const DistanceBin& bin : bins) {
    std::vector<std::pair<std::size_t, std::size_t>> members;
    std::vector<Eigen::Vector3d> positions;
    for (std::size_t a = 0; a < n; ++a) {
      const Eigen::Vector3d t_i = sequence.lidar_poses[static_cast<std::size_t>(sequence.frames[a])].translation();
      for (std::size_t b = a + 1; b < n; ++b) {
        if (sequence.frames[b] - sequence.frames[a] < options.minimum_frame_gap) continue;  // |i - j| >= t_lc
        const double distance = (t_i - sequence.lidar_poses[static_cast<std::size_t>(sequence.frames[b])].translation()).norm();
        if (distance < bin.minimum || distance > bin.maximum) continue;  // d^min_lc <= ||t_i - t_j|| <= d^max_lc
        members.emplace_back(a, b);
        positions.push_back(t_i);
      }
    }
    for (const std::size_t k : sample_spatially(positions, options.pairs_per_bin, options.sampling_cell, options.seed))
      pairs.push_back(make_kitti_pair(sequence, members[k].first, members[k].second, "lc", "loop_closure", bin.name()));
  }
  return pairs;
}

std::vector<BenchPair> generate_odometry_pairs(const KittiSequence& sequence, const std::vector<double>& distances,
                                               const OdometryOptions& options) {
  std::vector<BenchPair> pairs;
  const std::size_t n = sequence.frames.size();
  for (const double d_odo : distances) {
    std::vector<std::pair<std::size_t, std::size_t>> members;
    std::vector<Eigen::Vector3d> positions;
    for (std::size_t a = 0; a + 1 < n; ++a) {
      const Eigen::Vector3d t_i = sequence.lidar_poses[static_cast<std::size_t>(sequence.frames[a])].translation();
      std::size_t best = n;
      double best_gap = 0.0;
      for (std::size_t b = a + 1; b < n; ++b) {  // j = argmin_k | ||t_i - t_k|| - d_odo |
        const double gap =
            std::abs((t_i - sequence.lidar_poses[static_cast<std::size_t>(sequence.frames[b])].translation()).norm() - d_odo);
        if (best == n || gap < best_gap) {
          best = b;
          best_gap = gap;
        }
      }
      if (best == n || best_gap > options.tolerance) continue;
      members.emplace_back(a, best);
      positions.push_back(t_i);
    }
    const std::string name = number_text(d_odo) + " m";
    const std::string mode = "odo" + number_text(d_odo);
    for (const std::size_t k : sample_spatially(positions, options.pairs_per_distance, options.sampling_cell, options.seed))
      pairs.push_back(make_kitti_pair(sequence, members[k].first, members[k].second, mode, "odometry", name));
  }
  return pairs;
}

std::vector<ListedPair> read_pair_list(const std::string& path) {
  std::ifstream file(path);
  if (!file) throw file_error(path, "cannot open the pair list");
  std::vector<ListedPair> pairs;
  std::string line;
  std::size_t line_number = 0;
  bool header_seen = false;
  while (std::getline(file, line)) {
    ++line_number;
    const std::string where = path + ":" + std::to_string(line_number);
    std::istringstream stream(line);
    std::vector<std::string> tokens;
    for (std::string token; stream >> token;) tokens.push_back(token);
    if (tokens.empty()) continue;
    if (!header_seen && tokens[0] == "seq") {
      header_seen = true;
      continue;
    }
    if (tokens.size() != 20)
      throw Error(where + ": " + std::to_string(tokens.size()) + " columns, expected 20 (seq i seq_db j mot1..mot16)");
    ListedPair pair;
    int* indices[4] = {&pair.sequence, &pair.frame, &pair.database_sequence, &pair.database_frame};
    for (int c = 0; c < 4; ++c) {
      const std::string& token = tokens[static_cast<std::size_t>(c)];
      if (token.empty() || !std::all_of(token.begin(), token.end(), [](char ch) { return ch >= '0' && ch <= '9'; }))
        throw Error(where + ": column " + std::to_string(c + 1) + " '" + token + "' is not a non-negative integer index");
      *indices[c] = std::stoi(token);
    }
    Eigen::Matrix4d matrix;
    for (int k = 0; k < 16; ++k) {
      const std::string& token = tokens[static_cast<std::size_t>(4 + k)];
      try {
        std::size_t used = 0;
        matrix(k / 4, k % 4) = std::stod(token, &used);
        if (used != token.size()) throw std::invalid_argument(token);
      } catch (const std::exception&) {
        throw Error(where + ": mot" + std::to_string(k + 1) + " '" + token + "' is not a number");
      }
    }
    const Eigen::Matrix3d rotation = matrix.topLeftCorner<3, 3>();
    if ((rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > kPoseOrthonormalityTolerance ||
        rotation.determinant() < 0.0)
      throw Error(where + ": mot1..mot16 do not hold a rotation (R^T R != I within " +
                  number_text(kPoseOrthonormalityTolerance) + " or det < 0)");
    pair.transform.linear() = rotation;
    pair.transform.translation() = matrix.topRightCorner<3, 1>();
    pairs.push_back(pair);
  }
  if (!header_seen && pairs.empty()) throw file_error(path, "empty pair list");
  return pairs;
}

std::vector<BenchPair> listed_pairs_to_bench(const std::vector<ListedPair>& listed, const std::string& list_path,
                                             const std::string& root) {
  std::string difficulty = fs::path(list_path).stem().string();  // test_0_10 -> 0-10
  if (difficulty.rfind("test_", 0) == 0) {
    difficulty = difficulty.substr(5);
    std::replace(difficulty.begin(), difficulty.end(), '_', '-');
  }
  std::vector<BenchPair> pairs;
  std::set<std::string> ids;
  for (const ListedPair& entry : listed) {
    char sequence[8];
    char database_sequence[8];
    std::snprintf(sequence, sizeof(sequence), "%02d", entry.sequence);
    std::snprintf(database_sequence, sizeof(database_sequence), "%02d", entry.database_sequence);
    BenchPair pair;
    pair.id = "list" + std::string(sequence) + "_" + difficulty + "_" + std::to_string(entry.frame) + "_" +
              (entry.database_sequence == entry.sequence ? "" : std::string(database_sequence) + ":") +
              std::to_string(entry.database_frame);
    if (!ids.insert(pair.id).second)
      throw file_error(list_path, "lists the pair " + pair.id + " twice (each pair may appear once)");
    if (!root.empty()) {
      pair.source = kitti_frame_path(root, sequence, entry.frame);
      pair.target = kitti_frame_path(root, database_sequence, entry.database_frame);
      if (pair.source.empty())
        throw file_error(list_path, "frame " + frame_name(entry.frame) + " of sequence " + sequence + " has no cloud under " +
                                        (fs::path(root) / "sequences" / sequence / "velodyne").string());
      if (pair.target.empty())
        throw file_error(list_path, "frame " + frame_name(entry.database_frame) + " of sequence " + database_sequence +
                                        " has no cloud under " + (fs::path(root) / "sequences" / database_sequence / "velodyne").string());
    }
    pair.ground_truth = entry.transform;
    pair.ground_truth_quality = "exact";
    pair.kind = "loop_closure";
    pair.difficulty = difficulty;
    pair.distance = entry.transform.translation().norm();
    pairs.push_back(std::move(pair));
  }
  return pairs;
}

}  // namespace quadrix
