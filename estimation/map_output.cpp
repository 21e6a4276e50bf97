// The map's files (write_map) and its evaluation against true poses (evaluate_map: ATE after one
// Umeyama alignment, KITTI's relative error, loop-edge precision and recall).
#include "estimation/mapping.h"

#include "geometry/error.h"
#include "geometry/io.h"
#include "geometry/voxel_cells.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <map>
#include <set>
#include <sstream>
#include <unistd.h>

namespace quadrix {
namespace {

constexpr double kDegrees = 3.14159265358979323846 / 180.0;

std::string pose_numbers(const Eigen::Isometry3d& pose, char separator) {
  std::ostringstream text;
  text << std::setprecision(10);
  for (int row = 0; row < 3; ++row)
    for (int column = 0; column < 4; ++column) {
      if (row + column > 0) text << separator;
      text << pose.matrix()(row, column);
    }
  return text.str();
}

std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) {
    if (c == '"') quoted += '"';
    quoted += c == '\n' ? ' ' : c;
  }
  return quoted + "\"";
}

std::string json_string(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') out += '\\', out += c;
    else if (c == '\n') out += "\\n";
    else if (static_cast<unsigned char>(c) < 0x20) out += ' ';
    else out += c;
  }
  return out + "\"";
}

std::string json_number(double value) {
  if (!std::isfinite(value)) return "null";
  std::ostringstream text;
  text << std::setprecision(10) << value;
  return text.str();
}

/// A record moved rigidly by `motion` (points p' = motion p): the quadric, the full rotation and centre.
QuadricRecord moved(QuadricRecord record, const Eigen::Isometry3d& motion) {
  record.q = record.quadric().transformed(motion).normalized().parameters();
  record.full_rotation = Eigen::Quaterniond(motion.rotation() * record.full_rotation.normalized().toRotationMatrix());
  record.full_center = motion * record.full_center;
  return record;
}

/// The fitted quadrics of every scan in the map frame (augmented points left out), one model.
SceneModel merged_model(const MapResult& result) {
  SceneModel merged;
  bool ground_set = false;
  for (std::size_t scan = 0; scan < result.models.size(); ++scan) {
    if (!result.in_map_frame[scan]) continue;
    const SceneModel& model = result.models[scan];
    for (std::size_t record = 0; record < model.augmented_begin; ++record) {
      merged.records.push_back(moved(model.records[record], result.poses[scan]));
      merged.types.push_back(model.types[record]);
      merged.element_point_counts.push_back(model.element_point_counts[record]);
    }
    merged.source_point_count += model.source_point_count;
    if (!ground_set && model.has_ground) {
      merged.has_ground = true;
      merged.ground_normal = result.poses[scan].rotation() * model.ground_normal;
      merged.ground_offset = model.ground_offset - merged.ground_normal.dot(result.poses[scan].translation());
      ground_set = true;
    }
  }
  merged.augmented_begin = merged.records.size();
  return merged;
}

/// The clouds in the map frame, one point per `voxel` cube, coloured by session.
PointCloud merged_cloud(const MapResult& result, double voxel) {
  static const std::array<std::array<std::uint8_t, 3>, 8> palette = {{{230, 25, 75}, {60, 180, 75}, {0, 130, 200}, {245, 130, 48},
                                                                       {145, 30, 180}, {70, 240, 240}, {240, 50, 230}, {128, 128, 0}}};
  std::map<std::string, std::size_t> session_number;
  for (const std::string& session : result.list.sessions) session_number.emplace(session, session_number.size());
  CellMap<std::uint32_t> taken;
  std::vector<Eigen::Vector3f> points;
  std::vector<std::array<std::uint8_t, 3>> colors;
  for (std::size_t scan = 0; scan < result.list.scans.size(); ++scan) {
    if (!result.in_map_frame[scan]) continue;
    const PointCloud cloud = read_point_cloud(result.list.scans[scan].path);
    const Eigen::Isometry3f pose = result.poses[scan].cast<float>();
    const auto& color = palette[session_number[result.list.scans[scan].session] % palette.size()];
    for (std::size_t index = 0; index < cloud.size(); ++index) {
      const Eigen::Vector3f point = pose * Eigen::Vector3f(cloud.positions.col(static_cast<Eigen::Index>(index)));
      const Eigen::Vector3i cell = (point.cast<double>() / voxel).array().floor().cast<int>();
      if (!taken.try_emplace(cell_key(cell), 1).second) continue;
      points.push_back(point);
      colors.push_back(color);
    }
  }
  PointCloud cloud;
  cloud.positions.resize(3, static_cast<Eigen::Index>(points.size()));
  for (std::size_t index = 0; index < points.size(); ++index) cloud.positions.col(static_cast<Eigen::Index>(index)) = points[index];
  cloud.colors = std::move(colors);
  return cloud;
}

void write_text(const std::filesystem::path& path, const std::string& text) {
  write_file_atomically(path.string(), [&](std::ostream& stream) { stream << text; });
}

std::string report_json(const MapResult& result, const MapOptions& options, const std::string& evaluation_json) {
  std::map<std::string, std::size_t> counts;
  for (const MapEdge& edge : result.edges) {
    const std::string kind = edge.kind == MapEdgeKind::Odometry ? "odometry" : (edge.across_sessions ? "loop_across" : "loop_within");
    ++counts[kind + "_" + edge.status];
    if (edge.used) ++counts[kind + "_used"];
  }
  std::set<std::string> joined, alone;
  for (std::size_t scan = 0; scan < result.list.scans.size(); ++scan)
    (result.in_map_frame[scan] ? joined : alone).insert(result.list.scans[scan].session);
  std::ostringstream json;
  json << "{\n  \"format\": \"quadrix-map-report\",\n  \"version\": 1,\n";
  json << "  \"scans\": " << result.list.scans.size() << ",\n  \"sessions\": " << result.list.sessions.size() << ",\n";
  json << "  \"sessions_in_map_frame\": [";
  bool first = true;
  for (const std::string& session : result.list.sessions)
    if (joined.count(session)) json << (first ? "" : ", ") << json_string(session), first = false;
  json << "],\n  \"sessions_in_own_frame\": [";
  first = true;
  for (const std::string& session : result.list.sessions)
    if (!joined.count(session)) json << (first ? "" : ", ") << json_string(session), first = false;
  json << "],\n  \"candidates_within_sessions\": " << result.candidates_within
       << ",\n  \"candidates_across_sessions\": " << result.candidates_across << ",\n  \"joint_rounds\": [";
  for (std::size_t round = 0; round < result.joint_rounds.size(); ++round) {
    const JointRound& joint = result.joint_rounds[round];
    json << (round == 0 ? "" : ", ") << "{\"candidates\": " << joint.candidates << ", \"registered\": " << joint.registered
         << ", \"ok\": " << joint.ok << ", \"ambiguous\": " << joint.ambiguous << ", \"gated\": " << joint.gated << ", \"readmitted\": " << joint.readmitted
         << ", \"used\": " << joint.used << ", \"sessions_in_map_frame\": " << joint.sessions_in_map_frame << "}";
  }
  json << "],\n  \"information_groups\": [";
  for (std::size_t g = 0; g < result.information_groups.size(); ++g) {
    const InformationGroup& group = result.information_groups[g];
    json << (g == 0 ? "" : ", ") << "{\"name\": " << json_string(group.name) << ", \"edges\": " << group.edges
         << ", \"rotation_factor\": " << json_number(group.rotation_factor)
         << ", \"translation_factor\": " << json_number(group.translation_factor)
         << ", \"pooled\": " << (group.pooled ? "true" : "false") << ", \"measured\": " << (group.measured ? "true" : "false") << "}";
  }
  json << "],\n  \"calibration_costs\": [";
  for (std::size_t round = 0; round < result.calibration_costs.size(); ++round)
    json << (round == 0 ? "" : ", ") << json_number(result.calibration_costs[round]);
  json << "],\n  \"calibration_converged\": " << (result.calibration_converged ? "true" : "false")
       << ",\n  \"calibration_note\": " << json_string(result.calibration_note)
       << ",\n  \"outlier_edges\": " << result.outlier_edges
       << ",\n  \"outlier_test_exhausted\": " << (result.outlier_test_exhausted ? "true" : "false");
  json << ",\n  \"edges\": {";
  first = true;
  for (const auto& [name, value] : counts) json << (first ? "" : ", ") << json_string(name) << ": " << value, first = false;
  json << "},\n  \"graph\": {\"initial_cost\": " << json_number(result.graph.initial_cost)
       << ", \"final_cost\": " << json_number(result.graph.final_cost) << ", \"iterations\": " << result.graph.iterations
       << ", \"converged\": " << (result.graph.converged ? "true" : "false") << ", \"components\": " << result.graph.gauges.size()
       << ", \"ceres\": " << json_string(result.graph.report) << "},\n  \"timings_ms\": {";
  first = true;
  for (const auto& [name, value] : result.timings_ms) json << (first ? "" : ", ") << json_string(name) << ": " << json_number(value), first = false;
  json << "},\n  \"ms_per_scan\": " << json_number(result.timings_ms.count("total") ? result.timings_ms.at("total") / result.list.scans.size() : 0.0);
  json << ",\n  \"options\": {\"preset\": " << json_string(options.preset) << ", \"loop_radius\": " << json_number(options.loop_radius)
       << ", \"loop_radius_growth\": " << json_number(options.loop_radius_growth)
       << ", \"maximum_loop_radius\": " << json_number(options.maximum_loop_radius)
       << ", \"minimum_loop_travel\": " << json_number(options.minimum_loop_travel)
       << ", \"candidates_per_scan\": " << options.candidates_per_scan
       << ", \"minimum_candidate_spacing\": " << json_number(options.minimum_candidate_spacing)
       << ", \"loop_information\": " << (options.loop_information_from_registration ? "\"registration\"" : "\"fixed\"")
       << ", \"loop_information_scale\": " << json_number(options.loop_information_scale)
       << ", \"place_candidates_per_scan\": " << options.place_candidates_per_scan
       << ", \"use_ambiguous_edges\": " << (options.use_ambiguous_edges ? "true" : "false")
       << ", \"use_ambiguous_edges_across_sessions\": " << (options.use_ambiguous_edges_across_sessions ? "true" : "false")
       << ", \"odometry_gate_sigmas\": " << json_number(options.odometry_gate_sigmas)
       << ", \"joint_rounds\": " << options.joint_rounds << ", \"joint_radius\": " << json_number(options.joint_radius)
       << ", \"joint_gate_translation\": " << json_number(options.joint_gate_translation)
       << ", \"joint_gate_rotation_degrees\": " << json_number(options.joint_gate_rotation_degrees)
       << ", \"place_consensus_rotation_degrees\": " << json_number(options.place_consensus_rotation_degrees)
       << ", \"place_consensus_translation\": " << json_number(options.place_consensus_translation)
       << ", \"place_vote_minimum\": " << options.place_vote_minimum
       << ", \"place_vote_rotation_degrees\": " << json_number(options.place_vote_rotation_degrees)
       << ", \"place_vote_translation\": " << json_number(options.place_vote_translation)
       << ", \"place_vote_ratio\": " << json_number(options.place_vote_ratio)
       << ", \"outlier_threshold\": " << json_number(options.outlier_threshold)
       << ", \"use_ambiguous_joint_edges\": " << (options.use_ambiguous_joint_edges ? "true" : "false")
       << ", \"ambiguous_gate_translation\": " << json_number(options.ambiguous_gate_translation)
       << ", \"ambiguous_gate_rotation_degrees\": " << json_number(options.ambiguous_gate_rotation_degrees)
       << ", \"information_rounds\": " << options.information_rounds
       << ", \"information_minimum_edges\": " << options.information_minimum_edges
       << ", \"information_tolerance\": " << json_number(options.information_tolerance)
       << ", \"dcs_phi\": " << json_number(options.graph.dcs_phi) << "}";
  if (!evaluation_json.empty()) json << ",\n  \"evaluation\": " << evaluation_json;
  json << "\n}\n";
  return json.str();
}

}  // namespace

void write_map(const std::string& folder, const MapResult& result, const MapOptions& options, const std::string& evaluation_json) {
  namespace fs = std::filesystem;
  const fs::path target = fs::absolute(fs::path(folder)).lexically_normal();
  const fs::path parent = target.parent_path();
  std::error_code code;
  if (!fs::is_directory(parent, code)) throw file_error(folder, "cannot write: folder '" + parent.string() + "' does not exist");
  if (fs::exists(target, code) && !fs::is_directory(target, code)) throw file_error(folder, "exists and is not a folder");
  const std::string suffix = std::to_string(::getpid());
  const fs::path temporary = parent / ("." + target.filename().string() + ".tmp-" + suffix);
  fs::remove_all(temporary, code);
  fs::create_directory(temporary);
  try {
    const ScanList& list = result.list;
    std::ostringstream poses;
    // session, scan, the 12 numbers t00..t23 each in its own column (the format of truth tables), and
    // the frame the pose is in ("map", or "own" for a session that joined nothing).
    poses << "session\tscan";
    for (int row = 0; row < 3; ++row)
      for (int column = 0; column < 4; ++column) poses << "\tt" << row << column;
    poses << "\tframe\n";
    for (std::size_t scan = 0; scan < list.scans.size(); ++scan)
      poses << list.scans[scan].session << '\t' << list.scans[scan].scan << '\t' << pose_numbers(result.poses[scan], '\t') << '\t'
            << (result.in_map_frame[scan] ? "map" : "own") << '\n';
    write_text(temporary / "poses.tsv", poses.str());

    std::ostringstream edges;
    edges << "from_session,from_scan,to_session,to_scan,kind,status,used";
    for (int row = 0; row < 3; ++row)
      for (int column = 0; column < 4; ++column) edges << ",t" << row << column;
    edges << ",across_sessions,overlap,chi2_before,chi2_after,dcs_scale,registration_ms,inliers,inlier_rmse,registration_information,note\n";
    for (const MapEdge& edge : result.edges) {
      edges << csv_field(list.scans[edge.from].session) << ',' << csv_field(list.scans[edge.from].scan) << ','
            << csv_field(list.scans[edge.to].session) << ',' << csv_field(list.scans[edge.to].scan) << ','
            << (edge.kind == MapEdgeKind::Odometry ? "odometry" : "loop") << ',' << edge.status << ',' << (edge.used ? 1 : 0) << ','
            << pose_numbers(edge.transform, ',') << ',' << (edge.across_sessions ? 1 : 0) << ',' << json_number(edge.overlap) << ','
            << json_number(edge.chi2_before) << ',' << json_number(edge.chi2_after) << ',' << json_number(edge.dcs_scale) << ','
            << json_number(edge.registration_ms) << ',' << edge.inliers << ',' << json_number(edge.inlier_rmse) << ',';
      // The registration's H: its 21 upper-triangular numbers row by row, space-separated.
      for (int row = 0; row < 6; ++row)
        for (int column = row; column < 6; ++column)
          edges << (row + column > 0 ? " " : "") << json_number(edge.registration_information(row, column));
      edges << ',' << csv_field(edge.note) << '\n';
    }
    write_text(temporary / "edges.csv", edges.str());
    write_text(temporary / "report.json", report_json(result, options, evaluation_json));
    write_point_cloud((temporary / "map.ply").string(), merged_cloud(result, options.map_voxel));
    write_scene_model_binary((temporary / "map_model.qsm").string(), merged_model(result));
    fs::create_directory(temporary / "models");
    for (std::size_t scan = 0; scan < list.scans.size(); ++scan) {
      std::ostringstream name;
      name << std::setw(5) << std::setfill('0') << scan << ".qsm";
      write_scene_model_binary((temporary / "models" / name.str()).string(), result.models[scan]);
    }
    const fs::path previous = parent / ("." + target.filename().string() + ".old-" + suffix);
    const bool existed = fs::exists(target);
    if (existed) fs::rename(target, previous);
    fs::rename(temporary, target);
    if (existed) fs::remove_all(previous, code);
  } catch (...) {
    fs::remove_all(temporary, code);
    throw;
  }
}

Eigen::Isometry3d umeyama_alignment(const Eigen::Matrix3Xd& from, const Eigen::Matrix3Xd& to) {
  if (from.cols() != to.cols() || from.cols() < 3) throw Error("umeyama_alignment: needs two sets of at least 3 matching points");
  Eigen::Isometry3d alignment = Eigen::Isometry3d::Identity();
  alignment.matrix() = Eigen::umeyama(from, to, false);
  return alignment;
}

std::tuple<double, double, std::size_t> kitti_relative_error(const std::vector<Eigen::Isometry3d>& estimate,
                                                             const std::vector<Eigen::Isometry3d>& truth,
                                                             const std::vector<double>& lengths) {
  if (estimate.size() != truth.size()) throw Error("kitti_relative_error: estimate and truth differ in length");
  std::vector<double> distance(truth.size(), 0.0);
  for (std::size_t index = 1; index < truth.size(); ++index)
    distance[index] = distance[index - 1] + (truth[index].translation() - truth[index - 1].translation()).norm();
  double translation = 0.0, rotation = 0.0;
  std::size_t segments = 0;
  for (std::size_t first = 0; first < truth.size(); ++first)
    for (double length : lengths) {
      std::size_t last = first;
      while (last < truth.size() && distance[last] - distance[first] < length) ++last;
      if (last >= truth.size()) continue;
      const Eigen::Isometry3d true_motion = truth[first].inverse() * truth[last];
      const Eigen::Isometry3d estimated_motion = estimate[first].inverse() * estimate[last];
      const Eigen::Isometry3d error = true_motion.inverse() * estimated_motion;
      translation += error.translation().norm() / length;
      rotation += Eigen::AngleAxisd(error.rotation()).angle() / kDegrees / length;
      ++segments;
    }
  if (segments == 0) return {0.0, 0.0, 0};
  return {100.0 * translation / segments, 100.0 * rotation / segments, segments};
}

MapEvaluation evaluate_map(const MapResult& result, const std::vector<PoseRow>& truth_rows, double revisit_radius,
                           double minimum_loop_travel) {
  const ScanList& list = result.list;
  const std::size_t count = list.scans.size();
  std::map<std::pair<std::string, std::string>, Eigen::Isometry3d> by_name;
  for (const PoseRow& row : truth_rows) {
    by_name[{row.session, row.scan}] = row.pose;
    by_name.emplace(std::make_pair(row.session, std::filesystem::path(row.scan).filename().string()), row.pose);
  }
  std::vector<Eigen::Isometry3d> truth(count);
  for (std::size_t scan = 0; scan < count; ++scan) {
    auto it = by_name.find({list.scans[scan].session, list.scans[scan].scan});
    if (it == by_name.end()) it = by_name.find({list.scans[scan].session, std::filesystem::path(list.scans[scan].scan).filename().string()});
    if (it == by_name.end())
      throw Error("ground truth: no pose for session '" + list.scans[scan].session + "', scan '" + list.scans[scan].scan + "'");
    truth[scan] = it->second;
  }
  MapEvaluation evaluation;
  std::vector<std::size_t> in_map;
  for (std::size_t scan = 0; scan < count; ++scan)
    if (result.in_map_frame[scan]) in_map.push_back(scan);
  evaluation.scope = in_map.size() == count ? "every scan" : std::to_string(in_map.size()) + " of " + std::to_string(count) + " scans (those joined to the first session)";

  const auto ate = [&](const std::vector<Eigen::Isometry3d>& poses, const std::vector<std::size_t>& scans) {
    Eigen::Matrix3Xd estimated(3, static_cast<Eigen::Index>(scans.size())), true_positions(3, static_cast<Eigen::Index>(scans.size()));
    for (std::size_t k = 0; k < scans.size(); ++k) {
      estimated.col(static_cast<Eigen::Index>(k)) = poses[scans[k]].translation();
      true_positions.col(static_cast<Eigen::Index>(k)) = truth[scans[k]].translation();
    }
    const Eigen::Isometry3d alignment = umeyama_alignment(estimated, true_positions);
    double sum = 0.0;
    for (std::size_t k = 0; k < scans.size(); ++k)
      sum += (alignment * estimated.col(static_cast<Eigen::Index>(k)) - true_positions.col(static_cast<Eigen::Index>(k))).squaredNorm();
    return std::pair<double, double>{sum, static_cast<double>(scans.size())};
  };
  if (in_map.size() >= 3) {
    const auto [sum, n] = ate(result.poses, in_map);
    evaluation.ate = std::sqrt(sum / n);
  }
  // Odometry alone joins no sessions: each session is aligned on its own, the squared errors pooled.
  {
    double sum = 0.0, n = 0.0;
    for (std::size_t begin = 0; begin < count;) {
      std::size_t end = begin;
      std::vector<std::size_t> session;
      while (end < count && list.scans[end].session == list.scans[begin].session) session.push_back(end++);
      if (session.size() >= 3) {
        const auto [s, m] = ate(result.odometry, session);
        sum += s, n += m;
      }
      begin = end;
    }
    evaluation.ate_odometry = n > 0 ? std::sqrt(sum / n) : 0.0;
  }
  // Relative error along the first session.
  {
    std::vector<Eigen::Isometry3d> estimated, odometry, true_poses;
    for (std::size_t scan = 0; scan < count && list.scans[scan].session == list.scans[0].session; ++scan) {
      estimated.push_back(result.poses[scan]);
      odometry.push_back(result.odometry[scan]);
      true_poses.push_back(truth[scan]);
    }
    std::vector<double> lengths = {100, 200, 300, 400, 500, 600, 700, 800};
    auto [percent, degrees, segments] = kitti_relative_error(estimated, true_poses, lengths);
    if (segments == 0) {
      lengths = {10, 20, 30, 40, 50, 60, 70, 80};
      evaluation.rpe_lengths = "10..80 m (the path is shorter than 100 m)";
      std::tie(percent, degrees, segments) = kitti_relative_error(estimated, true_poses, lengths);
    }
    evaluation.rpe_translation_percent = percent;
    evaluation.rpe_rotation_deg_per_100m = degrees;
    evaluation.rpe_segments = segments;
    const auto [odometry_percent, odometry_degrees, odometry_segments] = kitti_relative_error(odometry, true_poses, lengths);
    evaluation.rpe_odometry_translation_percent = odometry_percent;
    evaluation.rpe_odometry_rotation_deg_per_100m = odometry_degrees;
  }
  // Loop edges against the truth: wrong beyond 2 m or 5 deg (the paper's success rule).
  std::vector<bool> closed(count, false);
  std::vector<std::pair<std::size_t, std::size_t>> ok_loops;  // (earlier scan, later scan) of each ok loop edge
  for (std::size_t index = 0; index < result.edges.size(); ++index) {
    const MapEdge& edge = result.edges[index];
    if (edge.kind != MapEdgeKind::Loop) continue;
    const Eigen::Isometry3d true_transform = truth[edge.to].inverse() * truth[edge.from];
    const bool right = registration_succeeded(edge.transform, true_transform);
    if (edge.status == "ok") {
      ++evaluation.ok_loop_edges;
      if (!right) ++evaluation.wrong_ok_loop_edges;
      closed[edge.from] = true;
      if (right) ok_loops.emplace_back(edge.to, edge.from);
    }
    if (edge.used) {
      ++evaluation.used_loop_edges;
      if (!right) {
        ++evaluation.wrong_used_loop_edges;
        evaluation.wrong_edges.push_back(index);
      }
    }
  }
  evaluation.precision =
      evaluation.used_loop_edges == 0 ? 1.0 : 1.0 - static_cast<double>(evaluation.wrong_used_loop_edges) / evaluation.used_loop_edges;
  // True revisits: an earlier scan within the radius, far enough back along the true path (same
  // session) or of an earlier session.
  std::vector<double> travelled(count, 0.0);
  for (std::size_t scan = 1; scan < count; ++scan)
    if (list.scans[scan].session == list.scans[scan - 1].session)
      travelled[scan] = travelled[scan - 1] + (truth[scan].translation() - truth[scan - 1].translation()).norm();
  for (std::size_t scan = 0; scan < count; ++scan) {
    bool revisit = false, place_revisit = false, place_hit = false;
    for (std::size_t other = 0; other < scan; ++other) {
      const double distance = (truth[scan].translation() - truth[other].translation()).norm();
      const bool same_session = list.scans[other].session == list.scans[scan].session;
      if (distance <= revisit_radius && (!same_session || travelled[scan] - travelled[other] >= minimum_loop_travel)) revisit = true;
      if (!same_session && distance <= 10.0) place_revisit = true;
    }
    if (revisit) {
      ++evaluation.true_revisits;
      if (closed[scan]) ++evaluation.closed_revisits;
    }
    // Returns: an earlier scan within the radius although the path left the radius in between (a
    // scan a few metres back on the same street is no return), or any within it in another session.
    std::vector<bool> returns_to(scan, false);
    bool returned = false, left = false;
    for (std::size_t other = scan; other-- > 0;) {
      const double distance = (truth[scan].translation() - truth[other].translation()).norm();
      if (list.scans[other].session != list.scans[scan].session) {
        returns_to[other] = distance <= revisit_radius;
      } else if (distance > revisit_radius) {
        left = true;
      } else {
        returns_to[other] = left;
      }
      returned = returned || returns_to[other];
    }
    if (returned) {
      ++evaluation.returns;
      for (const auto& [to, from] : ok_loops)
        if (from == scan && returns_to[to]) {
          ++evaluation.closed_returns;
          break;
        }
    }
    const bool ranked = scan < result.place_ranking.size() && !result.place_ranking[scan].empty();
    const bool searched = scan < result.joint_candidates.size() && !result.joint_candidates[scan].empty();
    if (place_revisit && ranked) {
      ++evaluation.place_queries;
      for (std::size_t other : result.place_ranking[scan])
        if ((truth[scan].translation() - truth[other].translation()).norm() <= 10.0) place_hit = true;
      if (place_hit) ++evaluation.place_hits;
    }
    if (place_revisit && (ranked || searched)) {
      ++evaluation.joint_place_queries;
      if (searched)
        for (std::size_t other : result.joint_candidates[scan])
          if ((truth[scan].translation() - truth[other].translation()).norm() <= 10.0) place_hit = true;
      if (place_hit) ++evaluation.joint_place_hits;
    }
  }
  evaluation.recall = evaluation.true_revisits == 0 ? 0.0 : static_cast<double>(evaluation.closed_revisits) / evaluation.true_revisits;
  return evaluation;
}

std::string map_evaluation_json(const MapEvaluation& evaluation) {
  std::ostringstream json;
  json << "{\"scope\": " << json_string(evaluation.scope) << ", \"ate_m\": " << json_number(evaluation.ate)
       << ", \"ate_odometry_m\": " << json_number(evaluation.ate_odometry)
       << ", \"rpe_translation_percent\": " << json_number(evaluation.rpe_translation_percent)
       << ", \"rpe_rotation_deg_per_100m\": " << json_number(evaluation.rpe_rotation_deg_per_100m)
       << ", \"rpe_odometry_translation_percent\": " << json_number(evaluation.rpe_odometry_translation_percent)
       << ", \"rpe_odometry_rotation_deg_per_100m\": " << json_number(evaluation.rpe_odometry_rotation_deg_per_100m)
       << ", \"rpe_segments\": " << evaluation.rpe_segments << ", \"rpe_lengths\": " << json_string(evaluation.rpe_lengths)
       << ", \"used_loop_edges\": " << evaluation.used_loop_edges << ", \"wrong_used_loop_edges\": " << evaluation.wrong_used_loop_edges
       << ", \"ok_loop_edges\": " << evaluation.ok_loop_edges << ", \"wrong_ok_loop_edges\": " << evaluation.wrong_ok_loop_edges
       << ", \"precision\": " << json_number(evaluation.precision) << ", \"true_revisits\": " << evaluation.true_revisits
       << ", \"closed_revisits\": " << evaluation.closed_revisits << ", \"recall\": " << json_number(evaluation.recall)
       << ", \"returns\": " << evaluation.returns << ", \"closed_returns\": " << evaluation.closed_returns
       << ", \"place_queries\": " << evaluation.place_queries << ", \"place_hits\": " << evaluation.place_hits
       << ", \"joint_place_queries\": " << evaluation.joint_place_queries << ", \"joint_place_hits\": " << evaluation.joint_place_hits << "}";
  return json.str();
}

}  // namespace quadrix
