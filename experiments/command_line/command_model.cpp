// `quadrix model INPUT... [--poses P,...] --out model.json [--binary model.qsm] [--mesh model.ply]
// [--elements elements.ply] [--picture model.png] [--preset P] [--sensor-origin X,Y,Z] [--labels FILE]
// [--score-labels FILE] [--fitter NAME] [--no-page] [--tile-size M] [--memory-budget B] [--tile i/n]`
// and `quadrix model merge PARTS... --out model.json`:
// the paper's quadric-based scene representation of one cloud (or of TLS stations merged by pose)
// (§"Quadric Extraction", §"Quadric Fitting", §"Quadric Modeling"). Beside model.json it writes the
// interactive page model.html (quadrix view) unless --no-page. A static scan above the memory budget
// (or with --tile-size) is modelled tile by tile (fitting/tiled_modelling.h); --tile i/n writes the
// partial model of one group of tiles, which `model merge` joins.
#include "geometry/output_paths.h"
#include "experiments/command_line/command_registry.h"
#include "experiments/command_line/terminal_text.h"
#include "experiments/reports/interactive_page.h"
#include "experiments/reports/model_picture.h"
#include "experiments/studies/modelling_evaluation.h"
#include "estimation/registration.h"
#include "estimation/registration_config.h"
#include "fitting/scene_modelling.h"
#include "fitting/tiled_modelling.h"
#include "geometry/error.h"
#include "geometry/io.h"
#include "geometry/las.h"
#include "geometry/mesh.h"

#include <nlohmann/json.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <chrono>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <unistd.h>

namespace quadrix::cli {
namespace {

struct ModelCommandOptions {
  std::vector<std::string> inputs;    ///< point-cloud files (several: stations of one static scan, merged with `poses`)
  std::vector<std::string> poses;     ///< sensor -> world pose file of each input (4x4 row-major), for merging
  std::string format = "auto";        ///< input format override
  std::string preset = "auto";        ///< sensor preset, or auto (measured on the cloud, as `register` and Python's model() do)
  std::string config;                 ///< YAML overrides applied after the preset (keys: quadrix config --schema)
  bool verbose = false;               ///< print the auto preset's measurements and the per-stage timings
  std::string labels;                 ///< SemanticKITTI .label file (switches to the labels semantic mode)
  std::string score_labels;           ///< SemanticKITTI .label file the element classes are scored against (the mode is unchanged)
  std::string fitter;                 ///< QuadricFitter registry name (empty: the preset's)
  std::string plane_method = "voxel"; ///< voxel (paper) or cgal (CGAL region growing)
  std::string out;                    ///< model JSON
  std::string binary;                 ///< model binary (.qsm)
  std::string mesh;                   ///< PLY mesh of the fitted quadrics
  std::string elements;               ///< PLY of the element points coloured per element
  std::string picture;                ///< PNG picture of the mesh
  double view_azimuth_deg = -60.0;    ///< picture camera azimuth, degrees
  double view_elevation_deg = 30.0;   ///< picture camera elevation, degrees
  double view_zoom = 1.0;             ///< picture zoom (> 1: closer)
  bool no_page = false;               ///< skip the interactive page beside --out
  std::vector<double> sensor_origin{0.0, 0.0, 0.0};  ///< where the sensor stood in the file's frame (one input, no --poses)
  double tile_size = 0.0;             ///< static scans: tile edge, m (0: tiles only above the memory budget, sized from it)
  std::string memory_budget = "2G";   ///< static scans: memory the modelling may hold (bytes, or with K, M, G)
  std::string tile;                   ///< static scans: "i/n" models the i-th of n tile groups into a partial model (--out)
};

// Options of `quadrix model merge`.
struct ModelMergeOptions {
  std::vector<std::string> parts;     ///< partial models of `quadrix model --tile i/n`
  std::string preset = "monument";    ///< preset the parts were modelled with (merge rules, fitter)
  std::string fitter;                 ///< QuadricFitter registry name (empty: the preset's)
  std::string out;                    ///< model JSON
  std::string binary;                 ///< model binary (.qsm)
};

// The preset a run used: as asked, as resolved (auto names the preset it chose) and, for auto,
// the measurements behind the choice.
struct PresetChoice {
  std::string requested;  ///< --preset as given (a name or auto)
  std::string used;       ///< the preset whose options ran
  std::string notes;      ///< auto's measurements and rule ("" for a named preset)
};

// A distinct colour per element (golden-ratio hue walk, full saturation).
std::array<std::uint8_t, 3> element_color(std::size_t index) {
  const double hue = std::fmod(0.13 + 0.618033988749895 * static_cast<double>(index), 1.0) * 6.0;
  const double x = 1.0 - std::abs(std::fmod(hue, 2.0) - 1.0);
  double r = 0, g = 0, b = 0;
  switch (static_cast<int>(hue)) {
    case 0: r = 1; g = x; break;
    case 1: r = x; g = 1; break;
    case 2: g = 1; b = x; break;
    case 3: g = x; b = 1; break;
    case 4: r = x; b = 1; break;
    default: r = 1; b = x; break;
  }
  const auto byte = [](double v) { return static_cast<std::uint8_t>(std::lround(40.0 + 215.0 * v)); };
  return {byte(r), byte(g), byte(b)};
}

// The ground's colour in --mesh and --picture: pale, so that it frames the structures without hiding them.
constexpr std::array<std::uint8_t, 3> kGroundMeshColor{226, 220, 205};

// The mesh of every fitted quadric, with what its picture needs: the box of the structures' vertices
// (2nd..98th percentile per axis, ground left out, so the picture frames the scene's content rather
// than a ground plane reaching to the crop radius) and a legend of the types drawn.
struct ModelMesh {
  TriangleMesh mesh;                                                     ///< every quadric inside its extent
  Eigen::AlignedBox3d content;                                           ///< where the structures are (empty: ground only)
  std::vector<std::pair<std::array<std::uint8_t, 3>, std::string>> legend;  ///< colour and type name, ground last
};

ModelMesh model_mesh(const ModellingResult& result, const Eigen::Matrix3Xd& points) {
  ModelMesh out;
  std::map<std::string, std::array<std::uint8_t, 3>> types_drawn;
  bool ground_drawn = false;
  std::vector<double> coordinates[3];
  for (std::size_t record_index = 0; record_index < result.model.augmented_begin; ++record_index) {
    const QuadricDecomposition shape = result.model.records[record_index].quadric().decompose();
    if (shape.type == QuadricType::Invalid || shape.type == QuadricType::Imaginary) continue;
    const Element& element = result.extraction.elements[static_cast<std::size_t>(result.record_elements[record_index])];
    // The extent: the element's points in the quadric's canonical frame, with a small margin.
    const Eigen::Isometry3d to_local = shape.pose().inverse();
    LocalExtent extent;
    extent.minimum = Eigen::Vector3d::Constant(1e300);
    extent.maximum = Eigen::Vector3d::Constant(-1e300);
    for (const std::uint32_t index : element.point_indices) {
      const Eigen::Vector3d local = to_local * Eigen::Vector3d(points.col(index));
      extent.minimum = extent.minimum.cwiseMin(local);
      extent.maximum = extent.maximum.cwiseMax(local);
    }
    extent.minimum.array() -= 0.05;
    extent.maximum.array() += 0.05;
    const bool ground = element.element_class == ElementClass::Ground;
    const QuadricType type = result.model.types[record_index];
    const TriangleMesh surface = mesh_surface(shape, extent, 24);
    append_mesh(out.mesh, surface, ground ? kGroundMeshColor : quadric_type_color(type));
    if (surface.triangles.empty()) continue;
    if (ground) {
      ground_drawn = true;
      continue;
    }
    types_drawn[quadric_type_name(type)] = quadric_type_color(type);
    for (Eigen::Index v = 0; v < surface.vertices.cols(); ++v)
      for (int axis = 0; axis < 3; ++axis) coordinates[axis].push_back(surface.vertices(axis, v));
  }
  if (!coordinates[0].empty()) {
    Eigen::Vector3d low, high;
    for (int axis = 0; axis < 3; ++axis) {
      std::vector<double>& values = coordinates[axis];
      std::sort(values.begin(), values.end());
      low[axis] = values[static_cast<std::size_t>(0.02 * static_cast<double>(values.size() - 1))];
      high[axis] = values[static_cast<std::size_t>(std::ceil(0.98 * static_cast<double>(values.size() - 1)))];
    }
    out.content = Eigen::AlignedBox3d(low, high);
  }
  for (const auto& [name, color] : types_drawn) out.legend.push_back({color, name});
  if (ground_drawn) out.legend.push_back({kGroundMeshColor, "ground"});
  return out;
}

PointCloud element_cloud(const ModellingResult& result, const PointCloud& cloud) {
  std::size_t total = 0;
  for (const Element& element : result.extraction.elements) total += element.point_indices.size();
  PointCloud out;
  out.positions.resize(3, static_cast<Eigen::Index>(total));
  std::vector<float> element_ids;
  element_ids.reserve(total);
  Eigen::Index column = 0;
  for (std::size_t e = 0; e < result.extraction.elements.size(); ++e) {
    const Element& element = result.extraction.elements[e];
    const auto color = element.element_class == ElementClass::Ground ? std::array<std::uint8_t, 3>{150, 120, 90}
                                                                      : element_color(e);
    for (const std::uint32_t index : element.point_indices) {
      out.positions.col(column++) = cloud.positions.col(index);
      out.colors.push_back(color);
      out.labels.push_back(static_cast<std::uint32_t>(element.element_class));
      element_ids.push_back(static_cast<float>(e));
    }
  }
  out.extra_fields["element"] = std::move(element_ids);
  return out;
}

std::string human_bytes(double bytes) {
  char buffer[32];
  if (bytes >= 1024.0 * 1024.0)
    std::snprintf(buffer, sizeof buffer, "%.2f MiB", bytes / (1024.0 * 1024.0));
  else if (bytes >= 1024.0)
    std::snprintf(buffer, sizeof buffer, "%.1f KiB", bytes / 1024.0);
  else
    std::snprintf(buffer, sizeof buffer, "%.0f B", bytes);
  return buffer;
}

// The length unit of the inputs' coordinates (coordinate_units: a LAS file may declare feet; every
// other file is in metres, the unit every preset's lengths are in), one for all inputs.
struct InputUnits : CoordinateUnits {
  bool all_las = false;  // every input is LAS, so its labels are ASPRS classes
};

InputUnits input_units(const ModelCommandOptions& options, CloudFormat format) {
  InputUnits units;
  units.all_las = true;
  for (std::size_t i = 0; i < options.inputs.size(); ++i) {
    const std::string& path = options.inputs[i];
    const CoordinateUnits found = coordinate_units(path, format);
    if (i > 0 && std::abs(found.metres_per_unit - units.metres_per_unit) > 1e-9 * units.metres_per_unit)
      throw file_error(path, "its coordinates are in " + found.name + ", those of " + options.inputs.front() + " in " +
                             units.name + ": inputs merged into one cloud need one unit");
    if (i == 0) static_cast<CoordinateUnits&>(units) = found;
    units.all_las = units.all_las && found.las;
  }
  return units;
}

// The "units" member of the model JSON: what the file declared and that the model is written in it.
std::string units_json(const InputUnits& units) {
  return "\"units\": " + nlohmann::json{{"name", units.name},
                                       {"metres_per_unit", units.metres_per_unit},
                                       {"declared_by", units.source.empty() ? "nothing (metres assumed)" : units.source},
                                       {"modelled_in", "metre"},
                                       {"written_in", units.name}}
                              .dump();
}

// One input as read, or several moved into the world frame by their poses and concatenated
// (labels and extra fields are kept only when every input has them).
PointCloud read_merged_clouds(const ModelCommandOptions& options, const CloudReadOptions& read_options) {
  if (options.inputs.size() == 1 && options.poses.empty()) return read_point_cloud(options.inputs.front(), read_options);
  if (options.poses.size() != options.inputs.size())
    throw Error("--poses: " + std::to_string(options.poses.size()) + " pose files for " +
                std::to_string(options.inputs.size()) + " inputs (expected one per input)");
  std::vector<PointCloud> clouds;
  std::size_t total = 0;
  for (std::size_t i = 0; i < options.inputs.size(); ++i) {
    clouds.push_back(read_point_cloud(options.inputs[i], read_options));
    const Eigen::Isometry3d pose = read_pose_matrix(options.poses[i]);
    for (Eigen::Index column = 0; column < clouds.back().positions.cols(); ++column)
      clouds.back().positions.col(column) = (pose * clouds.back().positions.col(column).cast<double>()).cast<float>();
    require_finite_points(clouds.back(), "--poses " + options.poses[i] + " moved " + options.inputs[i]);
    total += clouds.back().size();
  }
  PointCloud merged;
  merged.positions.resize(3, static_cast<Eigen::Index>(total));
  Eigen::Index column = 0;
  for (const PointCloud& cloud : clouds) {
    merged.positions.middleCols(column, cloud.positions.cols()) = cloud.positions;
    column += cloud.positions.cols();
  }
  const bool all_labelled = std::all_of(clouds.begin(), clouds.end(), [](const PointCloud& c) { return !c.labels.empty(); });
  for (const PointCloud& cloud : clouds) {
    if (all_labelled) merged.labels.insert(merged.labels.end(), cloud.labels.begin(), cloud.labels.end());
    for (const auto& [name, values] : clouds.front().extra_fields) {
      const auto field = cloud.extra_fields.find(name);
      if (field == cloud.extra_fields.end()) continue;
      std::vector<float>& values_out = merged.extra_fields[name];
      values_out.insert(values_out.end(), field->second.begin(), field->second.end());
    }
  }
  for (auto it = merged.extra_fields.begin(); it != merged.extra_fields.end();)
    it = it->second.size() == total ? std::next(it) : merged.extra_fields.erase(it);
  return merged;
}

// The "class_scores" member of the model JSON: per class the counts, recall and precision, and
// where each labelled class's points went.
std::string class_scores_json(const ClassScores& scores) {
  nlohmann::json classes = nlohmann::json::object(), confusion = nlohmann::json::object();
  for (const ClassScore& score : scores.classes)
    classes[element_class_name(score.element_class)] = {{"labelled", score.labelled}, {"predicted", score.predicted},
                                                        {"agreeing", score.agreeing}, {"recall", score.recall},
                                                        {"precision", score.precision}};
  for (const auto& [truth, row] : scores.confusion) confusion[element_class_name(truth)] = row;
  return "\"class_scores\": " + nlohmann::json{{"scored", scores.scored}, {"classes", classes}, {"confusion", confusion}}.dump();
}

// The per-class table of --score-labels: recall and precision, then where each class's points went.
void print_class_scores(const ClassScores& scores) {
  std::printf("\nclasses against %zu labelled points in range (per point; a point in no element or in an object cluster is missed):\n",
              scores.scored);
  std::printf("%-12s %9s %9s %9s %7s %9s   labelled points went to\n", "class", "labelled", "modelled", "agreeing", "recall",
              "precision");
  for (const ClassScore& score : scores.classes) {
    std::printf("%-12s %9zu %9zu %9zu %6.1f%% %8.1f%%  ", element_class_name(score.element_class).c_str(), score.labelled,
                score.predicted, score.agreeing, 100.0 * score.recall, 100.0 * score.precision);
    const auto row = scores.confusion.find(score.element_class);
    if (row != scores.confusion.end())
      for (const auto& [modelled, count] : row->second)
        std::printf(" %s %.0f%%", modelled.c_str(), 100.0 * static_cast<double>(count) / static_cast<double>(score.labelled));
    std::printf("\n");
  }
}

// The model's header fields beside its records in model.json: inputs, preset, fitter, statuses,
// raw size, the points in range and how many were isolated, the extracted elements per class and,
// with --score-labels, the class scores.
std::string model_json_extra(const ModelCommandOptions& options, const PresetChoice& preset, const ModellingOptions& modelling,
                             const ModellingResult& result, double raw_bytes,
                             const std::map<std::string, int>& element_counts, const std::optional<ClassScores>& scores) {
  std::string extra = "\"input\": " + nlohmann::json(std::filesystem::path(options.inputs.front()).filename().string()).dump() + ", \"inputs\": " +
                      std::to_string(options.inputs.size()) + ", \"preset\": \"" + preset.used +
                      "\", \"preset_requested\": \"" + preset.requested + "\", \"preset_notes\": " +
                      nlohmann::json(preset.notes).dump() + ", \"fitter\": \"" + modelling.fitter + "\", \"status\": \"" +
                      modelling_status_name(result.status) + "\", \"extraction_status\": \"" +
                      extraction_status_name(result.extraction.status) + "\", \"raw_cloud_bytes\": " +
                      std::to_string(static_cast<long long>(raw_bytes)) + ", \"points_in_range\": " +
                      std::to_string(result.extraction.points_in_range) + ", \"isolated_points\": " +
                      std::to_string(result.extraction.isolated_points) + ", \"elements_by_class\": {";
  bool first = true;
  for (const auto& [name, count] : element_counts) {
    extra += std::string(first ? "" : ", ") + "\"" + name + "\": " + std::to_string(count);
    first = false;
  }
  extra += "}";
  if (scores) extra += ", " + class_scores_json(*scores);
  return extra;
}

// The mesh of every quadric (--mesh) and its picture (--picture), when asked for.
void write_mesh_outputs(const ModelCommandOptions& options, const ModellingResult& result, const Eigen::Matrix3Xd& points) {
  if (options.mesh.empty() && options.picture.empty()) return;
  const ModelMesh drawn = model_mesh(result, points);
  if (!options.mesh.empty()) write_mesh_ply(options.mesh, drawn.mesh);
  if (options.picture.empty()) return;
  if (drawn.mesh.triangles.empty()) throw Error("--picture " + options.picture + ": the model has no quadric to draw");
  MeshPictureOptions view;
  view.azimuth_deg = options.view_azimuth_deg;
  view.elevation_deg = options.view_elevation_deg;
  view.zoom = options.view_zoom;
  view.frame_box = drawn.content;
  view.legend = drawn.legend;
  view.title = std::filesystem::path(options.inputs.front()).filename().string();
  write_mesh_picture(options.picture, drawn.mesh, view);
}

// Where the interactive page goes: beside the JSON (model.json -> model.html), never the JSON's own
// path; "" with --no-page.
std::string model_page_path(const ModelCommandOptions& options) {
  if (options.no_page) return "";
  const std::filesystem::path json_path(options.out);
  return json_path.extension() == ".json" ? std::filesystem::path(json_path).replace_extension(".html").string()
                                          : options.out + ".html";
}

// The interactive page beside the JSON (model.json -> model.html), with the same extents as --mesh.
// Returns its path, or "" when skipped or not buildable (libjs-three missing: a warning only, since
// the model is written).
std::string write_model_page(const ModelCommandOptions& options, const PresetChoice& preset, const ModellingOptions& modelling,
                             const ModellingResult& result, const PointCloud& cloud, const Eigen::Matrix3Xd& points) {
  if (options.no_page) return "";
  const SceneModel& model = result.model;
  const std::string page_path = model_page_path(options);
  ModelPageInput page;
  page.title = std::filesystem::path(options.inputs.front()).filename().string() +
               (options.inputs.size() > 1 ? " + " + std::to_string(options.inputs.size() - 1) + " more" : "");
  page.status = modelling_status_name(result.status);
  page.message = result.message;
  page.facts = {{"preset", preset.used}, {"fitter", modelling.fitter}, {"points", std::to_string(cloud.size())},
                {"elements", std::to_string(result.extraction.elements.size())},
                {"records", std::to_string(model.size()) + " (" + std::to_string(model.augmented_count()) + " augmented points)"}};
  page.quadrics = page_quadrics(model);
  for (std::size_t i = 0; i < page.quadrics.size(); ++i) {
    const Element& element = result.extraction.elements[static_cast<std::size_t>(result.record_elements[i])];
    page.quadrics[i].extent = local_extent_of_points(model.records[i].quadric().decompose(), points, element.point_indices);
  }
  page.points = subsample_points(cloud, page.point_budget);
  page.points_total = cloud.size();
  try {
    write_page(page_path, model_page_html(page));
  } catch (const Error& error) {
    std::fprintf(stderr, "quadrix: warning: %s not written: %s (--no-page skips it)\n", page_path.c_str(), error.what());
    return "";
  }
  return page_path;
}

// The terminal summary: counts per class and type, timings, the model's size against the raw
// cloud's, the ground, and every file written.
void print_model_summary(const ModelCommandOptions& options, const PresetChoice& preset, const ModellingOptions& modelling, const ModellingResult& result,
                         const PointCloud& cloud, const std::map<std::pair<std::string, std::string>, int>& quadric_counts,
                         std::map<std::string, int> element_counts, std::size_t binary_size, double raw_bytes,
                         const std::string& page_path, const std::string& length_unit) {
  const SceneModel& model = result.model;
  std::printf("quadrix model %s%s  (%zu points, %zu in range, %zu of them isolated and left out, fitter %s)\n",
              options.inputs.front().c_str(),
              options.inputs.size() > 1 ? (" + " + std::to_string(options.inputs.size() - 1) + " more").c_str() : "", cloud.size(),
              result.extraction.points_in_range, result.extraction.isolated_points, modelling.fitter.c_str());
  std::printf("%s\n", preset_summary_line(preset.requested, preset.used, preset.notes, options.verbose).c_str());
  // A model that is not ok says in full why and what to give (e.g. --sensor-origin): the terminal is where that is read.
  const bool whole_message = options.verbose || result.status != ModellingStatus::Ok;
  std::printf("status: %s\n\n", status_summary_line(modelling_status_name(result.status), result.message, whole_message).c_str());
  std::printf("%-12s %-20s %9s %9s\n", "class", "type", "elements", "quadrics");
  for (const auto& [key, count] : quadric_counts)
    std::printf("%-12s %-20s %9d %9d\n", key.first.c_str(), key.second.c_str(), element_counts[key.first], count);
  for (const auto& [name, count] : element_counts) {
    bool listed = false;
    for (const auto& [key, unused] : quadric_counts) listed = listed || key.first == name;
    if (!listed) std::printf("%-12s %-20s %9d %9d\n", name.c_str(), "(not fitted)", count, 0);
  }
  std::printf("%-12s %-20s %9s %9zu\n", "augmented", "point", "", model.augmented_count());
  std::printf("%-12s %-20s %9zu %9zu\n\n", "total", "", result.extraction.elements.size(), model.size());
  if (options.verbose) std::printf("timings (ms, 2 shared cores):");
  for (const char* stage : {"crop", "isolated_points", "ground", "planes", "clusters", "lines", "simplification", "normals", "shape_detection",
                            "fitting", "selection", "augmentation", "total"}) {
    const auto it = model.timings_ms.find(stage);
    if (options.verbose && it != model.timings_ms.end()) std::printf("  %s %.1f", stage, it->second);
  }
  if (options.verbose) std::printf("\n");
  std::printf("model: %s binary (%zu records x 21 numbers)", human_bytes(static_cast<double>(binary_size)).c_str(),
              model.size());
  if (raw_bytes > 0.0)
    std::printf(" vs raw cloud %s (%.0fx smaller)", human_bytes(raw_bytes).c_str(), raw_bytes / static_cast<double>(binary_size));
  std::printf("\nground: %s", model.has_ground ? "found" : "not found");
  if (model.has_ground)
    std::printf(", normal (%.4f, %.4f, %.4f), offset %.3f %s", model.ground_normal.x(), model.ground_normal.y(),
                model.ground_normal.z(), model.ground_offset, length_unit.c_str());
  std::printf("\nwrote %s", options.out.c_str());
  const std::initializer_list<const std::string*> written = {&options.binary, &options.mesh, &options.elements, &options.picture,
                                                             &page_path};
  for (const std::string* path : written)
    if (!path->empty()) std::printf(", %s", path->c_str());
  std::printf("\n");
}

// Bytes of "2G", "1500M", "512K" or a plain number of bytes.
std::size_t parse_bytes(const std::string& text, const std::string& option) {
  std::size_t used = 0;
  double value = 0.0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  double unit = 1.0;
  const std::string suffix = text.substr(std::min(used, text.size()));
  if (suffix == "K" || suffix == "k") unit = 1024.0;
  else if (suffix == "M" || suffix == "m") unit = 1024.0 * 1024.0;
  else if (suffix == "G" || suffix == "g") unit = 1024.0 * 1024.0 * 1024.0;
  else if (!suffix.empty()) used = 0;
  if (used == 0 || !(value > 0.0) || !std::isfinite(value * unit))
    throw Error(option + ": expected a positive size in bytes, optionally with K, M or G (2G), got '" + text + "'");
  return static_cast<std::size_t>(value * unit);
}

// Tiled modelling's progress on a terminal (stderr): pass, tiles done, points per second, time
// left; nothing when stderr is not a terminal (logs).
std::function<void(const TilingProgress&)> terminal_progress() {
  if (isatty(STDERR_FILENO) == 0) return {};
  struct State {
    int pass = 0;
    std::chrono::steady_clock::time_point shown;
  };
  auto state = std::make_shared<State>();
  return [state](const TilingProgress& progress) {
    const auto now = std::chrono::steady_clock::now();
    const bool last = progress.pass == 2 && progress.tiles_done == progress.tiles_total;
    if (progress.pass == state->pass && !last && now - state->shown < std::chrono::milliseconds(250)) return;
    if (progress.pass != state->pass && state->pass != 0) std::fprintf(stderr, "\n");
    state->pass = progress.pass;
    state->shown = now;
    const double rate = progress.seconds > 0.0 ? static_cast<double>(progress.points_done) / progress.seconds / 1e6 : 0.0;
    if (progress.pass == 1) {
      std::fprintf(stderr, "\rpass 1/3 binning: %.1f M points, %.2f M points/s   ", static_cast<double>(progress.points_done) / 1e6, rate);
    } else if (progress.pass == 2) {
      const double left = progress.points_done > 0 && progress.points_total > progress.points_done
                              ? progress.seconds * static_cast<double>(progress.points_total - progress.points_done) /
                                    static_cast<double>(progress.points_done)
                              : 0.0;
      std::fprintf(stderr, "\rpass 2/3 modelling tiles: %zu/%zu, %.2f M points/s, %.0f s left   ", progress.tiles_done,
                   progress.tiles_total, rate, left);
    } else {
      std::fprintf(stderr, "\rpass 3/3 merging the pieces of %zu tiles\n", progress.tiles_total);
      state->pass = 0;
    }
    std::fflush(stderr);
  };
}

// Quadrics of a model per class and type.
std::map<std::pair<std::string, std::string>, int> quadric_counts_of(const SceneModel& model) {
  std::map<std::pair<std::string, std::string>, int> counts;
  for (std::size_t i = 0; i < model.augmented_begin; ++i)
    ++counts[{element_class_name(element_class_from_label(model.records[i].label)), quadric_type_name(model.types[i])}];
  return counts;
}

// The inputs as named in messages: the first file, and how many more.
std::string input_name(const ModelCommandOptions& options) {
  return std::filesystem::path(options.inputs.front()).filename().string() +
         (options.inputs.size() > 1 ? " + " + std::to_string(options.inputs.size() - 1) + " more" : "");
}

// Writes a merged tiled model (--out JSON, --binary) and prints its summary.
void write_tiled_model(const std::string& out, const std::string& binary, const std::string& source, std::size_t inputs,
                       const std::string& preset, const std::string& fitter, const ModellingResult& result,
                       const std::string& tiling_json, const std::string& more_members = "") {
  const SceneModel& model = result.model;
  const auto counts = quadric_counts_of(model);
  std::string extra = "\"input\": " + nlohmann::json(source).dump() + ", \"inputs\": " + std::to_string(inputs) +
                      ", \"preset\": \"" + preset + "\", \"fitter\": \"" + fitter + "\", \"status\": \"" +
                      modelling_status_name(result.status) + "\", \"tiling\": " + tiling_json +
                      (more_members.empty() ? "" : ", " + more_members);
  write_scene_model_json(out, model, extra);
  if (!binary.empty()) write_scene_model_binary(binary, model);
  std::printf("quadrix model %s  (%zu points, tile by tile, preset %s, fitter %s)\n", source.c_str(), model.source_point_count,
              preset.c_str(), fitter.c_str());
  std::printf("status: %s%s%s\n\n", modelling_status_name(result.status).c_str(), result.message.empty() ? "" : " - ",
              result.message.c_str());
  std::printf("%-12s %-20s %9s\n", "class", "type", "quadrics");
  for (const auto& [key, count] : counts) std::printf("%-12s %-20s %9d\n", key.first.c_str(), key.second.c_str(), count);
  std::printf("%-12s %-20s %9zu\n\ntimings (ms, 2 shared cores):", "total", "", model.size());
  for (const char* stage : {"counting", "binning", "modelling", "tiles", "merge", "fitting", "total"}) {
    const auto it = model.timings_ms.find(stage);
    if (it != model.timings_ms.end()) std::printf("  %s %.1f", stage, it->second);
  }
  std::printf("\nwrote %s%s%s\n", out.c_str(), binary.empty() ? "" : ", ", binary.c_str());
}

// A static scan tile by tile: the whole model, or with --tile i/n the partial model of one group.
// Coordinates in another unit than metres (`units`) are tiled and modelled scaled to metres, and
// the model is written back in the file's unit.
void run_tiled(const ModelCommandOptions& options, ExtractionOptions extraction, const ModellingOptions& modelling,
               PointChunkSource& file_points, const Eigen::Vector3d& sensor_origin, TilingOptions tiling,
               const InputUnits& units) {
  for (const auto& [flag, value] : std::initializer_list<std::pair<const char*, const std::string*>>{
           {"--labels", &options.labels}, {"--score-labels", &options.score_labels}, {"--mesh", &options.mesh},
           {"--elements", &options.elements}, {"--picture", &options.picture}})
    if (!value->empty())
      throw Error(std::string(flag) + ": not available tile by tile (it needs every element's points in memory); "
                  "model whole with a larger --memory-budget");
  const bool rescaled = units.metres_per_unit != 1.0;
  if (rescaled && tiling.groups > 1)
    throw Error(options.inputs.front() + ": coordinates in " + units.name + " are modelled in metres; --tile i/n parts " +
                "of a survey in another unit are not joined: model it in one process (tiles in parallel on this machine's cores)");
  ScaledChunkSource metric_points(file_points, units.metres_per_unit);
  PointChunkSource& points = rescaled ? static_cast<PointChunkSource&>(metric_points) : file_points;
  // Tiles are modelled relative to their corners, in the file's frame (scaled to metres).
  extraction.sensor_origin = sensor_origin * units.metres_per_unit;
  tiling.progress = terminal_progress();
  const std::string source = points.name();
  if (tiling.groups > 1) {
    const PartialModel part = model_tile_group(points, extraction, tiling);
    write_partial_model(options.out, part);
    std::printf("quadrix model %s: tile group %d/%d, %llu tiles %s %.1f m, %llu of %llu points, %zu shape pieces; wrote %s "
                "(join the parts with `quadrix model merge`)\n",
                source.c_str(), part.group + 1, part.groups, static_cast<unsigned long long>(part.tiles),
                part.tile_points > 0 ? "split by point count on a grid of" : "of", part.tile_size,
                static_cast<unsigned long long>(part.group_points), static_cast<unsigned long long>(part.survey_points),
                part.pieces.size(), options.out.c_str());
    return;
  }
  // model_tiled's passes, so the tile edge chosen from the budget is reported.
  const auto start = std::chrono::steady_clock::now();
  const PartialModel part = model_tile_group(points, extraction, tiling);
  const double tiles_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  if (tiling.progress) tiling.progress({3, 0, 0, part.tiles, part.tiles, 0.0});
  ModellingResult result = merge_partial_models({part}, extraction, modelling, tiling);
  if (rescaled) result.model = scaled(std::move(result.model), 1.0 / units.metres_per_unit);
  result.model.timings_ms["tiles"] = tiles_ms;
  result.model.timings_ms.insert(part.timings_ms.begin(), part.timings_ms.end());
  result.model.timings_ms["total"] = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  const nlohmann::json tiling_json = {{"tile_size", part.tile_size}, {"tile_size_requested", tiling.tile_size},
                                      {"tile_points", part.tile_points}, {"largest_tile", part.largest_tile},
                                      {"tiles", part.tiles}, {"margin", tiling.margin}, {"memory_budget", tiling.memory_budget}};
  write_tiled_model(options.out, options.binary, source, options.inputs.size(), extraction.preset, modelling.fitter, result,
                    tiling_json.dump(), units_json(units));
  if (part.tile_points > 0)
    std::printf("tiles: %llu split by point count (at most %llu points, largest %llu) on a %.1f m grid, margin %.1f m\n",
                static_cast<unsigned long long>(part.tiles), static_cast<unsigned long long>(part.tile_points),
                static_cast<unsigned long long>(part.largest_tile), part.tile_size, tiling.margin);
  else
    std::printf("tiles: %llu of %.1f m, margin %.1f m\n", static_cast<unsigned long long>(part.tiles), part.tile_size, tiling.margin);
  if (rescaled)
    std::printf("units: the file is in %s (%.10g m, declared by its %s): modelled in metres (as are the tile sizes above), written in %s\n",
                units.name.c_str(), units.metres_per_unit, units.source.c_str(), units.name.c_str());
}

// The files of a static scan streamed from disk when it is modelled tile by tile, so the scan is
// never held whole: the preset is named, or auto on files whose headers declare more points than
// the memory budget holds (auto's rule for more than 1.5 M points is the static scan, monument),
// and the files can be read in chunks. Empty otherwise: the scan is read whole and the usual path
// decides.
std::unique_ptr<FileChunkSource> streamed_static_scan(const ModelCommandOptions& options, const TilingOptions& tiling,
                                                      RegistrationOptions& registration, std::string& notes) {
  if (!options.labels.empty() || !options.score_labels.empty()) return nullptr;  // need the cloud (refused tiled)
  const bool forced = options.tile_size > 0.0 || !options.tile.empty();
  if (options.preset != "auto") {
    registration = resolve_registration_side(options.preset, PointCloud(), "source");
    if (!options.config.empty()) apply_registration_config(options.config, registration, "source");
    if (!registration.source_extraction.static_scan) return nullptr;
  }
  std::vector<Eigen::Isometry3d> poses;
  if (!options.poses.empty()) {
    if (options.poses.size() != options.inputs.size()) return nullptr;  // the whole read names the mismatch
    for (const std::string& pose : options.poses) poses.push_back(read_pose_matrix(pose));
  }
  PointStreamOptions stream_options;
  stream_options.format = cloud_format_from_name(options.format);
  std::unique_ptr<FileChunkSource> source;
  try {
    source = std::make_unique<FileChunkSource>(options.inputs, poses, stream_options);
  } catch (const Error&) {
    return nullptr;  // not streamable (ascii PLY, CSV, ...) or bad: the whole read reads it or names the problem
  }
  const bool large = source->declared_points() && tiling_needed(*source->declared_points(), tiling);
  if (options.preset == "auto") {
    if (!large) return nullptr;  // auto measures the cloud
    registration = registration_preset("monument");
    if (!options.config.empty()) apply_registration_config(options.config, registration, "source");
    notes = "source auto: " + std::to_string(*source->declared_points()) +
            " points declared, above the memory budget: static scan, monument, tile by tile";
    return source;
  }
  return forced || large ? std::move(source) : nullptr;
}

void run_merge(const ModelMergeOptions& options) {
  const ExtractionOptions extraction = extraction_preset(options.preset);
  if (!extraction.static_scan) throw Error("model merge --preset: tiles are a static scan's (monument), got '" + options.preset + "'");
  ModellingOptions modelling = registration_preset(options.preset).modelling;
  if (!options.fitter.empty()) modelling.fitter = options.fitter;
  make_quadric_fitter(modelling.fitter);
  std::vector<PartialModel> parts;
  for (const std::string& path : options.parts) parts.push_back(read_partial_model(path));
  const auto start = std::chrono::steady_clock::now();
  ModellingResult result = merge_partial_models(parts, extraction, modelling);
  result.model.timings_ms["total"] = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  const nlohmann::json tiling_json = {{"tile_size", parts.front().tile_size}, {"margin", parts.front().margin},
                                      {"groups", parts.front().groups}};
  write_tiled_model(options.out, options.binary, std::filesystem::path(options.parts.front()).filename().string(),
                    options.parts.size(), options.preset, modelling.fitter, result, tiling_json.dump());
}

void run(const ModelCommandOptions& options) {
  if (options.inputs.empty()) throw Error("model: INPUT is required (or `quadrix model merge PARTS... --out M`)");
  if (options.out.empty()) throw Error("model: --out is required");
  if (options.plane_method != "voxel" && options.plane_method != "cgal")
    throw Error("--plane-method: expected voxel or cgal, got '" + options.plane_method + "'");
  if (!options.config.empty() && !std::filesystem::exists(options.config))
    throw file_error(options.config, "configuration file does not exist");
  if (!options.fitter.empty()) make_quadric_fitter(options.fitter);  // fail early with the list of fitters
  // A picture's camera needs numbers: inf would draw nothing.
  if (!std::isfinite(options.view_azimuth_deg)) throw Error("--view-azimuth: expected a finite angle in degrees");
  if (!(options.view_elevation_deg >= -89.0 && options.view_elevation_deg <= 89.0))
    throw Error("--view-elevation: expected an angle in [-89, 89] degrees");
  if (!(options.view_zoom > 0.0 && options.view_zoom <= 1e3)) throw Error("--view-zoom: expected a zoom in (0, 1000]");
  // Every output is checked before the work: none replaces an input, another output or anything
  // but a regular file, and each can be written.
  std::vector<std::string> inputs = options.inputs;
  inputs.insert(inputs.end(), options.poses.begin(), options.poses.end());
  inputs.push_back(options.labels);
  inputs.push_back(options.score_labels);
  inputs.push_back(options.config);
  check_outputs({{"--out", options.out},
                 {"--binary", options.binary},
                 {"--mesh", options.mesh},
                 {"--elements", options.elements},
                 {"--picture", options.picture},
                 {"the page beside --out (--no-page skips it)", model_page_path(options)}},
                inputs);
  TilingOptions tiling;
  if (!(options.tile_size >= 0.0) || !std::isfinite(options.tile_size))
    throw Error("--tile-size: expected a tile edge > 0 m (0: tiles only above --memory-budget)");
  tiling.tile_size = options.tile_size;
  tiling.memory_budget = parse_bytes(options.memory_budget, "--memory-budget");
  if (!options.tile.empty()) parse_tile_group(options.tile, tiling.group, tiling.groups);
  CloudReadOptions read_options;
  read_options.format = cloud_format_from_name(options.format);
  const Eigen::Vector3d sensor_origin(options.sensor_origin.data());
  if (!sensor_origin.allFinite()) throw Error("--sensor-origin: expected three finite numbers X,Y,Z in metres");
  const bool centred = !sensor_origin.isZero(0.0);
  // One scan is read relative to a local origin when its coordinates are large (a survey's or a map's
  // frame), so float32 storage keeps them exact; every output is written back in the file's frame.
  if (options.inputs.size() == 1 && options.poses.empty()) read_options.local_origin = LocalOrigin::Auto;
  if (centred && (options.inputs.size() != 1 || !options.poses.empty()))
    throw Error("--sensor-origin: takes one input without --poses (stations merged by pose are modelled in the world frame)");
  // Coordinates in another unit (a LAS file in feet) are modelled in metres, the presets' unit, and
  // the model is written back in the file's unit.
  const InputUnits units = input_units(options, read_options.format);
  const bool rescaled = units.metres_per_unit != 1.0;
  {
    // A static scan tiled from its files: never read whole.
    RegistrationOptions registration;
    std::string notes;
    if (const std::unique_ptr<FileChunkSource> files = streamed_static_scan(options, tiling, registration, notes)) {
      ExtractionOptions extraction = registration.source_extraction;
      if (options.plane_method == "cgal") extraction.planes.method = PlaneMethod::CgalRegionGrowing;
      ModellingOptions modelling = registration.modelling;
      if (!options.fitter.empty()) modelling.fitter = options.fitter;
      make_quadric_fitter(modelling.fitter);
      // K_e bounds registration's cost; a static scan modelled for itself keeps every primitive it finds.
      modelling.quadrics_per_class = std::numeric_limits<int>::max();
      if (options.verbose && !notes.empty()) std::printf("%s\n", notes.c_str());
      run_tiled(options, extraction, modelling, *files, sensor_origin, tiling, units);
      return;
    }
  }
  const PointCloud cloud = read_merged_clouds(options, read_options);
  // A cloud in a map's frame is modelled centred on its sensor (the extraction measures ranges and
  // heights from the origin), and the model is moved back: every output is in the file's frame.
  // One copy at most, centred and/or in metres; `cloud` stays in the file's frame and unit.
  const ModellingFrame frame{sensor_origin, units.metres_per_unit};
  const PointCloud moved = frame.moves() ? in_modelling_frame(cloud, frame, "--sensor-origin moved " + options.inputs.front())
                                         : PointCloud();
  const PointCloud& modelled = frame.moves() ? moved : cloud;
  // The library's preset resolution (as `register` and Python's model() do it): a named preset, or
  // auto measured on the cloud (its up axis and platform crop set on the extraction), then --config.
  std::string notes;
  RegistrationOptions registration = resolve_registration_side(options.preset, modelled, "source", &notes);
  if (!options.config.empty()) apply_registration_config(options.config, registration, "source");
  ExtractionOptions extraction = registration.source_extraction;
  if (options.plane_method == "cgal") extraction.planes.method = PlaneMethod::CgalRegionGrowing;
  ModellingOptions modelling = registration.modelling;
  if (!options.fitter.empty()) modelling.fitter = options.fitter;
  make_quadric_fitter(modelling.fitter);
  if (!units.all_las) extraction.ground_class = -1;  // only a LAS file's labels are ASPRS classes
  const PresetChoice preset{options.preset, extraction.preset, notes};
  if (!extraction.static_scan && (options.tile_size > 0.0 || !options.tile.empty()))
    throw Error("--tile-size, --tile: tile-by-tile modelling is for static scans (--preset monument), not preset '" +
                extraction.preset + "'");
  if (extraction.static_scan) {
    // K_e bounds registration's cost; a static scan modelled for itself keeps every primitive it finds.
    modelling.quadrics_per_class = std::numeric_limits<int>::max();
    if (options.tile_size > 0.0 || !options.tile.empty() || tiling_needed(cloud.size(), tiling)) {
      // Served in the file's frame (the cloud was read relative to its local origin).
      MatrixChunkSource points(cloud.positions, input_name(options), cloud.local_origin);
      run_tiled(options, extraction, modelling, points, sensor_origin, tiling, units);
      return;
    }
  }
  std::vector<std::uint32_t> labels;
  if (!options.labels.empty()) {
    labels = read_semantic_kitti_labels(options.labels, cloud.size());
    extraction.semantic_mode = SemanticMode::Labels;
  }
  // Read before modelling, so a bad file fails at once.
  std::vector<std::uint32_t> score_labels;
  if (!options.score_labels.empty()) score_labels = read_semantic_kitti_labels(options.score_labels, cloud.size());
  ModellingResult result = model_scene(modelled, extraction, modelling, labels);
  result.model = in_file_frame(std::move(result.model), frame, cloud.local_origin);
  const SceneModel& model = result.model;
  std::optional<ClassScores> scores;
  if (!options.score_labels.empty()) scores = score_element_classes(modelled, result.extraction, score_labels, extraction);

  // Counts per class and type (quadrics kept in the model; elements extracted).
  std::map<std::pair<std::string, std::string>, int> quadric_counts;
  std::map<std::string, int> element_counts;
  for (std::size_t i = 0; i < model.augmented_begin; ++i)
    ++quadric_counts[{element_class_name(element_class_from_label(model.records[i].label)), quadric_type_name(model.types[i])}];
  for (const Element& element : result.extraction.elements) ++element_counts[element_class_name(element.element_class)];
  const std::string binary_bytes = scene_model_to_binary(model);
  double raw_bytes = 0.0;
  for (const std::string& input : options.inputs)
    if (std::filesystem::exists(input)) raw_bytes += static_cast<double>(std::filesystem::file_size(input));

  write_scene_model_json(options.out, model,
                         model_json_extra(options, preset, modelling, result, raw_bytes, element_counts, scores) + ", " +
                             units_json(units) + ", \"ground_source\": " + nlohmann::json(result.extraction.ground_source).dump());
  if (!options.binary.empty()) write_scene_model_binary(options.binary, model);
  const Eigen::Matrix3Xd points = cloud.positions.cast<double>().colwise() + cloud.local_origin;  // the file's frame
  write_mesh_outputs(options, result, points);
  if (!options.elements.empty()) {
    PointCloud elements = element_cloud(result, cloud);
    elements.local_origin = cloud.local_origin;  // written in the file's frame
    write_point_cloud(options.elements, elements);
  }
  const PointCloud page_cloud = cloud.local_origin.isZero(0.0) ? PointCloud() : centred_on_sensor(cloud, Eigen::Vector3d::Zero());
  const std::string page_path =
      write_model_page(options, preset, modelling, result, cloud.local_origin.isZero(0.0) ? cloud : page_cloud, points);
  print_model_summary(options, preset, modelling, result, cloud, quadric_counts, element_counts, binary_bytes.size(), raw_bytes,
                      page_path, rescaled ? units.name : "m");
  if (rescaled)
    std::printf("units: the file is in %s (%.10g m, declared by its %s): modelled in metres, written in %s\n", units.name.c_str(),
                units.metres_per_unit, units.source.c_str(), units.name.c_str());
  if (!result.extraction.ground_source.empty())
    std::printf("ground from: %s\n", (result.extraction.ground_source == "classification"
                                          ? "the file's classification (class " + std::to_string(extraction.ground_class) + ")"
                                          : std::string("the lowest large horizontal plane"))
                                             .c_str());
  if (scores) print_class_scores(*scores);
}

const CommandRegistration registration(50, [](CLI::App& app) {
  auto options = std::make_shared<ModelCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "model", "Model a point cloud with quadrics (paper's scene representation) and write JSON/binary/mesh");
  command->add_option("input", options->inputs, "Point cloud (any supported format); several with --poses are merged");
  command->add_option("--poses", options->poses,
                      "Sensor-to-world pose file (4x4) per input, comma-separated: the inputs are merged in the world "
                      "frame (TLS stations)")
      ->delimiter(',');
  std::string presets;
  for (const auto& name : registration_preset_names()) presets += name + "|";
  command->add_option("--preset", options->preset,
                      "Sensor preset: " + presets + "auto (chosen from the cloud: field of view, rings, size; as `register`)")
      ->capture_default_str();
  command->add_option("--config", options->config,
                      "YAML overrides applied after the preset (keys: quadrix config --schema; the source side's)");
  command->add_option("--sensor-origin", options->sensor_origin,
                      "Where the sensor stood in the file's frame, X,Y,Z in metres (default: the origin). For a cloud in "
                      "a map's frame: it is modelled centred on its sensor, and every output is in the file's frame")
      ->expected(3)
      ->delimiter(',');
  command->add_option("--labels", options->labels,
                      "SemanticKITTI .label file: use the labels semantic mode instead of geometry-only clusters");
  command->add_option("--score-labels", options->score_labels,
                      "SemanticKITTI .label file: score the element classes against it per point (recall, precision, "
                      "where each class went); printed and written to the model JSON as class_scores");
  std::string fitters;
  for (const auto& name : quadric_fitter_names()) fitters += (fitters.empty() ? "" : ", ") + name;
  command->add_option("--fitter", options->fitter,
                      "Quadric fitter: " + fitters + " (default: the preset's; statistical, constrained for monument)");
  command->add_option("--plane-method", options->plane_method,
                      "voxel (paper: voxel eigenvalue ratio + region growing) or cgal (CGAL region growing)")
      ->capture_default_str();
  command->add_option("--format", options->format, "Input format override (see `quadrix info --help`)")
      ->capture_default_str();
  command->add_option("--out", options->out, "Model JSON (quadrics array + stats); with --tile, the partial model");
  command->add_option("--binary", options->binary, "Compact binary model (.qsm)");
  command->add_option("--mesh", options->mesh, "PLY mesh of every fitted quadric inside its extent, coloured by type");
  command->add_option("--elements", options->elements, "PLY of the element points, coloured per element");
  command->add_option("--picture", options->picture, "PNG picture of the mesh (z-buffer rendering, colours by type)");
  command->add_option("--view-azimuth", options->view_azimuth_deg, "Picture camera azimuth around the up axis, degrees")
      ->capture_default_str();
  command->add_option("--view-elevation", options->view_elevation_deg, "Picture camera elevation, degrees (-89..89)")
      ->capture_default_str();
  command->add_option("--view-zoom", options->view_zoom, "Picture zoom (> 1 moves the camera closer)")->capture_default_str();
  command->add_flag("-v,--verbose", options->verbose, "Also print auto's measurements, the whole status message and the stage timings");
  command->add_flag("--no-page", options->no_page, "Do not write the interactive page (--out with .html) beside the JSON");
  command->add_option("--tile-size", options->tile_size,
                      "Static scans: model tile by tile with square tiles of this edge in x-y, m (default: tiles only "
                      "when the whole cloud would exceed --memory-budget, split by point count to fit it)");
  command->add_option("--memory-budget", options->memory_budget,
                      "Static scans: memory the modelling may hold, bytes or with K, M, G; above it the scan is modelled "
                      "tile by tile")
      ->capture_default_str();
  command->add_option("--tile", options->tile,
                      "Static scans: model only the i-th of n tile groups (i/n) and write its partial model to --out; "
                      "join the n parts with `quadrix model merge`");
  auto merge = std::make_shared<ModelMergeOptions>();
  CLI::App* merge_command = command->add_subcommand(
      "merge", "Join the partial models of `quadrix model --tile i/n` (every i once) into one model");
  merge_command->add_option("parts", merge->parts, "Partial models, one per tile group")->required();
  merge_command->add_option("--preset", merge->preset, "Preset the parts were modelled with")->capture_default_str();
  merge_command->add_option("--fitter", merge->fitter, "Quadric fitter (default: the preset's)");
  merge_command->add_option("--out", merge->out, "Model JSON")->required();
  merge_command->add_option("--binary", merge->binary, "Compact binary model (.qsm)");
  merge_command->callback([merge] { run_merge(*merge); });
  command->callback([options, merge_command] {
    if (!merge_command->parsed()) run(*options);
  });
});

}  // namespace
}  // namespace quadrix::cli
