// The interactive page of `quadrix view` (DESIGN.md §7): one self-contained HTML file that opens
// from disk without a network. It inlines three.js and its OrbitControls from Debian's libjs-three
// (read at run time from /usr/share/javascript/three, never vendored), the data (points subsampled
// to a budget, quadric meshes built here with geometry/mesh.h, all as base64 little-endian arrays)
// and the page's own script. Two kinds of page:
//   registration: target grey, source as scanned or moved by the answer / any candidate, the
//                 clique's correspondences as lines between matched quadric centres, a side panel
//                 with status, message, timings, counts and the candidates (click one to apply it);
//   model:        every quadric as a mesh coloured by type, toggles per type and per class, a click
//                 on a quadric shows its 21-number record and point count; optional points.
// Once the first frame is drawn the page sets document.title to "quadrix view ready <ms> ms" and
// the attribute data-ready-ms on <body>; a JavaScript error sets data-error and a title starting
// with "quadrix view error" (what the headless-Chromium test reads).
#pragma once

#include "fitting/scene_model.h"
#include "geometry/mesh.h"
#include "geometry/point_cloud.h"
#include "geometry/quadric_record.h"

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace quadrix {

/// Where the page looks for libjs-three's files (three.min.js, examples/js/controls/OrbitControls.js).
inline constexpr const char* kThreeJsDirectory = "/usr/share/javascript/three";

/// The whole text of `path` (a page's input: a report, a model, a pose table); Error naming the file and `what`.
std::string read_page_file(const std::string& path, const std::string& what);

/// A libjs-three file under kThreeJsDirectory; Error naming it and the package when it is missing.
std::string read_three_js_file(const std::string& relative);

/// Script text with every "</" written "<\/", so it cannot close the <script> element it is inlined in.
std::string escape_script_text(const std::string& text);

/// JSON text for a <script> element: <, >, & and U+2028/U+2029 as \u escapes (no string can close the element).
std::string json_for_script(const std::string& text);

/// One quadric shown on a model page.
struct PageQuadric {
  QuadricRecord record;                ///< paper Struct. 1 (shown on click, meshed from q)
  QuadricType type = QuadricType::Invalid;  ///< fitted type (mesh colour, type toggle)
  std::string class_name;              ///< semantic class shown and toggled ("plane", "cylinder", "column", ...)
  std::size_t point_count = 0;         ///< points of the element behind the quadric
  std::optional<LocalExtent> extent;   ///< surface bounds in the canonical frame; absent: the box of s_f, R_f, t_f
};

/// Everything a model page shows.
struct ModelPageInput {
  std::string title;                   ///< heading of the side panel (e.g. the input file)
  std::string status;                  ///< modelling status shown in the panel ("ok", ...)
  std::string message;                 ///< free text under the status (may be empty)
  std::vector<std::pair<std::string, std::string>> facts;  ///< extra lines of the panel: name, value
  std::vector<PageQuadric> quadrics;   ///< the meshed quadrics
  PointCloud points;                   ///< the modelled points (may be empty), subsampled to point_budget
  std::size_t points_total = 0;        ///< points of the modelled cloud when `points` is already a subsample (0: points.size())
  std::size_t point_budget = 400000;   ///< most points written into the page
  int mesh_resolution = 24;            ///< segments per parametric direction of each quadric mesh (3..256)
};

/// Everything a registration page shows.
struct RegistrationPageInput {
  std::string report_json;             ///< report.json text (registration_report_json): status, timings, counts, candidates with cliques
  std::optional<SceneModel> source_model;  ///< R_x, for the centres of matched quadrics (absent: no correspondence lines)
  std::optional<SceneModel> target_model;  ///< R_y
  PointCloud source;                   ///< source points in the source frame (as scanned)
  PointCloud target;                   ///< target points
  std::size_t point_budget = 400000;   ///< most points written into the page (both clouds together)
  std::string note;                    ///< shown in the panel when something is missing (e.g. old folder without models)
};

/// Quadrics of the fitted records [0, augmented_begin) of a model, class names from the labels
/// (ElementClass), extents from the record's full attributes.
std::vector<PageQuadric> page_quadrics(const SceneModel& model);

/// Bounds of `points` (columns `indices` of a 3xN matrix, world frame) in the canonical frame of
/// `shape`, widened by `margin` metres on every side: the extent `quadrix model --mesh` uses.
LocalExtent local_extent_of_points(const QuadricDecomposition& shape, const Eigen::Matrix3Xd& points,
                                   const std::vector<std::uint32_t>& indices, double margin = 0.05);

/// The mesh a page draws for a quadric: mesh_surface inside its extent, or without one inside the
/// box centred at t_f with half sides 1.1 s_f (at least 5 cm) along the columns of R_f. Empty for
/// invalid and imaginary quadrics.
TriangleMesh page_quadric_mesh(const PageQuadric& quadric, int resolution = 24);

/// Every `stride`-th point so that at most `budget` remain (all when the cloud is small enough).
PointCloud subsample_points(const PointCloud& cloud, std::size_t budget);

/// The model page as HTML text. Throws quadrix::Error naming the file and the package (libjs-three)
/// when a three.js file is missing, or the option out of range.
std::string model_page_html(const ModelPageInput& input);

/// The registration page as HTML text. Throws quadrix::Error when report_json is not a report
/// (names the missing key) or a three.js file is missing.
std::string registration_page_html(const RegistrationPageInput& input);

/// Writes `html` atomically to `path`.
void write_page(const std::string& path, const std::string& html);

/// Reads what `quadrix register --out DIR` wrote back into a page input: report.json, merged.ply
/// (split by its side labels; the source moved back by the inverse of the reported transform) and,
/// when present, source_model.json / target_model.json. Throws quadrix::Error naming the file missing.
RegistrationPageInput read_registration_folder(const std::string& directory);

/// A model page input from a `quadrix model` JSON file (quadrics only: the file has no points).
ModelPageInput read_model_json_page(const std::string& path);

/// A model page input from a `quadrix synth` folder: its scans merged in the world frame by their
/// poses and the ground-truth primitives' records (scene.json, primitives.json).
ModelPageInput read_synthetic_folder_page(const std::string& directory);

}  // namespace quadrix
