// Mapping baselines with Open3D 0.16 (see map_baselines.h): odometry alone, LIO-SAM-like ICP loop
// closure with radius search, and Open3D's multiway registration (pose graph + line process).
#include "experiments/baselines/map_baselines.h"

#include "geometry/error.h"
#include "geometry/io.h"
#include "geometry/scan_list.h"

#include <open3d/geometry/KDTreeSearchParam.h>
#include <open3d/geometry/PointCloud.h>
#include <open3d/pipelines/registration/GlobalOptimization.h>
#include <open3d/pipelines/registration/GlobalOptimizationConvergenceCriteria.h>
#include <open3d/pipelines/registration/GlobalOptimizationMethod.h>
#include <open3d/pipelines/registration/PoseGraph.h>
#include <open3d/pipelines/registration/Registration.h>
#include <open3d/pipelines/registration/TransformationEstimation.h>
#include <open3d/utility/Logging.h>

#include <omp.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <set>
#include <sstream>

namespace quadrix {
namespace {

namespace o3d_geometry = open3d::geometry;
namespace o3d_registration = open3d::pipelines::registration;

constexpr double kPi = 3.14159265358979323846;

std::string pose_text(const Eigen::Isometry3d& pose, char separator) {
  std::string text;
  char buffer[32];
  for (int k = 0; k < 12; ++k) {
    std::snprintf(buffer, sizeof(buffer), "%.10g", pose.matrix()(k / 4, k % 4));
    if (k) text += separator;
    text += buffer;
  }
  return text;
}

double angle_degrees(const Eigen::Matrix3d& rotation) {
  return std::acos(std::clamp((rotation.trace() - 1.0) / 2.0, -1.0, 1.0)) * 180.0 / kPi;
}

double aligned_rmse(const std::vector<Eigen::Vector3d>& estimate, const std::vector<Eigen::Vector3d>& truth) {
  Eigen::Matrix3Xd from(3, estimate.size()), to(3, truth.size());
  for (std::size_t i = 0; i < estimate.size(); ++i) {
    from.col(static_cast<Eigen::Index>(i)) = estimate[i];
    to.col(static_cast<Eigen::Index>(i)) = truth[i];
  }
  const Eigen::Matrix4d alignment = Eigen::umeyama(from, to, false);  // evo_ape --align: SE(3), no scale
  const Eigen::Matrix3Xd moved = (alignment.topLeftCorner<3, 3>() * from).colwise() + alignment.topRightCorner<3, 1>();
  return std::sqrt((moved - to).colwise().squaredNorm().mean());
}

// One edge as written to edges.csv.
struct Edge {
  std::size_t from = 0, to = 0;      // rows of the scan list
  std::string kind, status;          // odometry / loop; ok / rejected
  bool used = false;
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();  // p_to = T p_from
  double fitness = -1.0, rmse = -1.0;  // ICP's, -1 for given odometry
};

// A session's scans (rows of the list, in order) and their down-sampled clouds with normals.
struct Session {
  std::string name;
  std::vector<std::size_t> rows;
};

std::shared_ptr<o3d_geometry::PointCloud> prepared_cloud(const std::string& path, const MapBaselineOptions& options) {
  const PointCloud cloud = read_point_cloud(path);
  o3d_geometry::PointCloud converted;
  converted.points_.reserve(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) converted.points_.push_back(cloud.point(i));
  auto down = converted.VoxelDownSample(options.voxel_size);
  down->EstimateNormals(o3d_geometry::KDTreeSearchParamHybrid(2.0 * options.voxel_size + 0.5, 30), true);
  return down;
}

}  // namespace

std::vector<std::string> map_baseline_methods() { return {"odometry", "icp-loops", "multiway"}; }

MapBaselineSummary run_map_baseline(const std::string& method, const std::string& scan_list, const std::string& out,
                                    const std::string& truth_path, const MapBaselineOptions& options) {
  const std::vector<std::string> methods = map_baseline_methods();
  if (std::find(methods.begin(), methods.end(), method) == methods.end())
    throw Error("unknown mapping baseline '" + method + "' (expected odometry, icp-loops or multiway)");
  const auto start = std::chrono::steady_clock::now();
  open3d::utility::SetVerbosityLevel(open3d::utility::VerbosityLevel::Error);
  omp_set_num_threads(options.threads);
  const ScanList list = read_scan_list(scan_list);
  const std::vector<ScanEntry>& rows = list.scans;
  std::vector<Session> sessions;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (!rows[i].odometry)
      throw Error(scan_list + ": session " + rows[i].session + " has no odometry ('-'); the mapping baselines start from it");
    auto it = std::find_if(sessions.begin(), sessions.end(), [&](const Session& s) { return s.name == rows[i].session; });
    if (it == sessions.end()) {
      sessions.push_back({rows[i].session, {}});
      it = sessions.end() - 1;
    }
    it->rows.push_back(i);
  }
  MapBaselineSummary summary;
  summary.method = method;
  summary.scans = static_cast<int>(rows.size());
  std::vector<Eigen::Isometry3d> poses(rows.size());
  std::vector<Edge> edges;
  std::vector<std::shared_ptr<o3d_geometry::PointCloud>> clouds(rows.size());
  const auto cloud = [&](std::size_t row) {
    if (!clouds[row]) clouds[row] = prepared_cloud(rows[row].path, options);
    return clouds[row];
  };
  const auto icp = [&](std::size_t from, std::size_t to, const Eigen::Isometry3d& initial) {
    return o3d_registration::RegistrationICP(*cloud(from), *cloud(to), options.icp_distance, initial.matrix(),
                                             o3d_registration::TransformationEstimationPointToPlane(),
                                             o3d_registration::ICPConvergenceCriteria(1e-6, 1e-6, options.icp_iterations));
  };

  for (const Session& session : sessions) {
    const std::size_t first_edge = edges.size();
    // Odometry edges: the given odometry, for every method, so that the methods differ only in their loop edges.
    std::vector<Eigen::Isometry3d> initial(session.rows.size());
    initial[0] = *rows[session.rows[0]].odometry;
    for (std::size_t k = 0; k + 1 < session.rows.size(); ++k) {
      const std::size_t a = session.rows[k], b = session.rows[k + 1];
      Edge edge{a, b, "odometry", "ok", true, rows[b].odometry->inverse() * *rows[a].odometry};
      initial[k + 1] = initial[k] * edge.transform.inverse();
      edges.push_back(edge);
    }
    // Loop candidates by radius search around the odometry positions, among scans older than min_age.
    if (method != "odometry") {
      for (std::size_t k = 0; k < session.rows.size(); ++k) {
        std::vector<std::pair<double, std::size_t>> near;
        for (std::size_t j = 0; j + static_cast<std::size_t>(options.min_age) < k; ++j) {
          const double distance = (initial[k].translation() - initial[j].translation()).norm();
          if (distance <= options.radius) near.emplace_back(distance, j);
        }
        if (near.empty()) continue;
        std::sort(near.begin(), near.end());
        if (method == "icp-loops") near.resize(1);  // LIO-SAM: the closest older key frame
        for (const auto& [distance, j] : near) {
          const std::size_t from = session.rows[k], to = session.rows[j];
          const auto result = icp(from, to, initial[j].inverse() * initial[k]);
          Edge edge{from, to, "loop", "rejected", false, Eigen::Isometry3d(result.transformation_)};
          edge.fitness = result.fitness_;
          edge.rmse = result.inlier_rmse_;
          if (result.correspondence_set_.size() < 3) {
            edge.status = "failed";  // no overlap within icp_distance of the odometry's guess: nothing to add
          } else if (method == "icp-loops") {
            const bool pass = result.fitness_ >= options.min_fitness && result.inlier_rmse_ <= options.max_rmse;
            edge.status = pass ? "ok" : "rejected";
            edge.used = pass;
          } else {
            edge.status = "candidate";  // the line process decides
          }
          ++summary.loop_candidates;
          edges.push_back(edge);
        }
      }
    }
    // The session's pose graph: node k = sensor k -> session frame (node 0 fixed), Open3D's convention.
    std::vector<Eigen::Isometry3d> optimised = initial;
    bool has_loop = false;
    const auto enters_graph = [&](const Edge& edge) {
      return edge.kind == "odometry" || edge.used || (method == "multiway" && edge.status == "candidate");
    };
    for (std::size_t e = first_edge; e < edges.size(); ++e) has_loop = has_loop || (edges[e].kind == "loop" && enters_graph(edges[e]));
    if (has_loop) {
      std::map<std::size_t, int> node_of;
      o3d_registration::PoseGraph graph;
      for (std::size_t k = 0; k < session.rows.size(); ++k) {
        node_of[session.rows[k]] = static_cast<int>(k);
        graph.nodes_.emplace_back(initial[k].matrix());
      }
      std::vector<std::size_t> graph_edges;  // edges[] index of each graph edge
      for (std::size_t e = first_edge; e < edges.size(); ++e) {
        const Edge& edge = edges[e];
        if (!enters_graph(edge)) continue;
        const Eigen::Matrix6d information = o3d_registration::GetInformationMatrixFromPointClouds(
            *cloud(edge.from), *cloud(edge.to), options.icp_distance, edge.transform.matrix());
        graph.edges_.emplace_back(node_of[edge.from], node_of[edge.to], edge.transform.matrix(), information,
                                  /*uncertain=*/edge.kind == "loop" && method == "multiway", 1.0);
        graph_edges.push_back(e);
      }
      o3d_registration::GlobalOptimization(
          graph, o3d_registration::GlobalOptimizationLevenbergMarquardt(), o3d_registration::GlobalOptimizationConvergenceCriteria(),
          o3d_registration::GlobalOptimizationOption(options.icp_distance, options.edge_prune_threshold, 1.0, 0));
      for (std::size_t k = 0; k < session.rows.size(); ++k) optimised[k].matrix() = graph.nodes_[k].pose_;
      if (method == "multiway") {
        // Open3D removes the uncertain edges whose line-process weight fell below the threshold.
        std::set<std::pair<int, int>> kept;
        for (const auto& edge : graph.edges_)
          if (edge.uncertain_ && edge.confidence_ >= options.edge_prune_threshold) kept.insert({edge.source_node_id_, edge.target_node_id_});
        for (std::size_t e = first_edge; e < edges.size(); ++e)
          if (edges[e].kind == "loop" && edges[e].status == "candidate") {
            edges[e].used = kept.count({node_of[edges[e].from], node_of[edges[e].to]}) > 0;
            edges[e].status = edges[e].used ? "ok" : "rejected";
          }
      }
    }
    for (std::size_t k = 0; k < session.rows.size(); ++k) poses[session.rows[k]] = optimised[k];
  }
  for (const Edge& edge : edges) summary.loop_edges_used += edge.kind == "loop" && edge.used;
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // Evaluation against the truth: ATE per session (each aligned alone) and of session 1 (the map frame),
  // and the used loop edges more than 2 m or 5 degrees from the true relative pose.
  if (!truth_path.empty()) {
    std::map<std::pair<std::string, std::string>, Eigen::Isometry3d> truth;
    for (const PoseRow& row : read_pose_table(truth_path)) truth[{row.session, row.scan}] = row.pose;
    const auto truth_of = [&](std::size_t row) {
      const auto it = truth.find({rows[row].session, rows[row].scan});
      if (it == truth.end()) throw Error(truth_path + ": no pose for session " + rows[row].session + ", scan " + rows[row].scan);
      return it->second;
    };
    for (const Session& session : sessions) {
      std::vector<Eigen::Vector3d> estimate, reference;
      for (const std::size_t row : session.rows) {
        estimate.push_back(poses[row].translation());
        reference.push_back(truth_of(row).translation());
      }
      if (estimate.size() >= 3) summary.ate["session " + session.name] = aligned_rmse(estimate, reference);
    }
    if (summary.ate.count("session " + sessions.front().name)) summary.ate["map"] = summary.ate["session " + sessions.front().name];
    summary.wrong_used_edges = 0;
    for (const Edge& edge : edges) {
      if (edge.kind != "loop" || !edge.used) continue;
      const Eigen::Isometry3d expected = truth_of(edge.to).inverse() * truth_of(edge.from);
      const Eigen::Isometry3d error = expected.inverse() * edge.transform;
      summary.wrong_used_edges += error.translation().norm() > 2.0 || angle_degrees(error.linear()) > 5.0;
    }
  }

  std::filesystem::create_directories(out);
  write_file_atomically((std::filesystem::path(out) / "poses.tsv").string(), [&](std::ostream& file) {
    file << "session\tscan";
    for (int k = 0; k < 12; ++k) file << "\tt" << k / 4 << k % 4;
    file << '\n';
    for (std::size_t i = 0; i < rows.size(); ++i) file << rows[i].session << '\t' << rows[i].scan << '\t' << pose_text(poses[i], '\t') << '\n';
  });
  write_file_atomically((std::filesystem::path(out) / "edges.csv").string(), [&](std::ostream& file) {
    file << "from_session,from_scan,to_session,to_scan,kind,status,used";
    for (int k = 0; k < 12; ++k) file << ",t" << k / 4 << k % 4;
    file << ",icp_fitness,icp_rmse\n";
    for (const Edge& edge : edges)
      file << rows[edge.from].session << ',' << rows[edge.from].scan << ',' << rows[edge.to].session << ',' << rows[edge.to].scan << ','
           << edge.kind << ',' << edge.status << ',' << (edge.used ? 1 : 0) << ',' << pose_text(edge.transform, ',') << ','
           << edge.fitness << ',' << edge.rmse << '\n';
  });
  write_file_atomically((std::filesystem::path(out) / "report.json").string(), [&](std::ostream& file) {
    file << "{\n  \"method\": \"" << method << "\",\n  \"scans\": " << summary.scans << ",\n  \"sessions\": " << sessions.size()
         << ",\n  \"sessions_not_joined\": [";
    for (std::size_t s = 1; s < sessions.size(); ++s) file << (s > 1 ? ", " : "") << '"' << sessions[s].name << '"';
    file << "],\n  \"loop_candidates\": " << summary.loop_candidates << ",\n  \"loop_edges_used\": " << summary.loop_edges_used
         << ",\n  \"seconds\": " << summary.seconds << ",\n  \"options\": {\"radius_m\": " << options.radius
         << ", \"min_age_scans\": " << options.min_age << ", \"voxel_m\": " << options.voxel_size << ", \"icp_distance_m\": "
         << options.icp_distance << ", \"min_fitness\": " << options.min_fitness << ", \"max_rmse_m\": " << options.max_rmse << "}";
    if (!summary.ate.empty()) {
      file << ",\n  \"evaluation\": {\"wrong_used_loop_edges\": " << summary.wrong_used_edges;
      for (const auto& [name, value] : summary.ate) file << ", \"ate_m " << name << "\": " << value;
      file << "}";
    }
    file << "\n}\n";
  });
  return summary;
}

}  // namespace quadrix
