// map.html: the self-contained 3-D page of a map folder (`quadrix map --out DIR`, or a baseline's
// folder): each session's trajectory before (odometry, chained from the odometry edges) and after
// (poses.tsv), the loop edges between the poses after, coloured by status and drawn solid when the
// graph used them, the merged map's points (map.ply, subsampled), a legend with toggles and a panel
// with the report's counts and the evaluation (ATE) when report.json has them. Like the view page
// (interactive_page.h) it inlines three.js from Debian's libjs-three and opens from disk. Every
// string from the data reaches the page as text (textContent), never as HTML, and the embedded
// JSON has '<', '>' and '&' escaped so it cannot close its script element. Without WebGL the page
// says so in visible text and still shows the panel. Once drawn it sets data-ready-ms on <body>
// and the title "quadrix map ready <ms> ms" (data-webgl="missing" without WebGL); a JavaScript
// error sets data-error.
#pragma once

#include "geometry/point_cloud.h"

#include <Eigen/Geometry>

#include <cstddef>
#include <string>
#include <vector>

namespace quadrix {

/// One row of poses.tsv: a scan's sensor pose in the map frame.
struct MapPagePose {
  std::string session;                                    ///< session name as written
  std::string scan;                                       ///< scan path as written
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  ///< sensor -> map
};

/// One row of edges.csv (the columns the page uses).
struct MapPageEdge {
  std::string from_session, from_scan, to_session, to_scan;  ///< the two scans
  std::string kind;                                           ///< "odometry" or "loop"
  std::string status;                                         ///< registration status ("ok", "ambiguous", ...)
  bool used = false;                                          ///< the pose graph used the edge
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();  ///< maps `from` points into the `to` frame
};

/// Everything the map page shows.
struct MapPageInput {
  std::string title;                     ///< heading (the folder)
  std::vector<MapPagePose> poses;        ///< poses after (poses.tsv)
  std::vector<MapPageEdge> edges;        ///< odometry and loop edges (edges.csv)
  std::string report_json;               ///< report.json text, or empty
  PointCloud points;                     ///< map points (map.ply), may be empty
  std::size_t point_budget = 300000;     ///< most map points written into the page
};

/// Reads poses.tsv (header, then session, scan and 12 numbers, tab- or space-separated). Throws
/// quadrix::Error naming the file and line of a malformed row.
std::vector<MapPagePose> read_map_poses(const std::string& path);
/// Reads edges.csv (header naming at least from_session, from_scan, to_session, to_scan, kind,
/// status, used, t00..t23). Throws quadrix::Error naming the file, line and column when malformed.
std::vector<MapPageEdge> read_map_edges(const std::string& path);

/// The trajectory before the graph: for each session, its first pose after, then the odometry
/// edges chained (one pose per scan reached; a scan no odometry edge reaches keeps no pose).
std::vector<MapPagePose> odometry_trajectory(const std::vector<MapPagePose>& poses, const std::vector<MapPageEdge>& edges);

/// The page as HTML text. Throws quadrix::Error naming the file and package when three.js is missing.
std::string map_page_html(const MapPageInput& input);

/// True when `folder` holds a map: poses.tsv and edges.csv.
bool is_map_folder(const std::string& folder);

/// Reads the map folder (poses.tsv, edges.csv; report.json and map.ply when present) into a page input.
MapPageInput read_map_folder(const std::string& folder, std::size_t point_budget = 300000);

/// Writes FOLDER/map.html (atomically) for a map folder; returns its path.
std::string write_map_page(const std::string& folder);

/// Every entry a map folder holds (write_map's files and models, and the page): what a folder
/// replaced by a new map run may hold (FolderReplacement's own names).
std::vector<std::string> map_folder_names();

}  // namespace quadrix
