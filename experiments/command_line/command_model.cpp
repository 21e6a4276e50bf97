// `quadrix model INPUT... [--poses P,...] --out model.json [--binary model.qsm] [--mesh model.ply]
// [--elements elements.ply] [--picture model.png] [--preset P] [--sensor-origin X,Y,Z] [--labels FILE]
// [--score-labels FILE] [--fitter NAME] [--no-page]`:
// the paper's quadric-based scene representation of one cloud (or of TLS stations merged by pose)
// (§"Quadric Extraction", §"Quadric Fitting", §"Quadric Modeling"). Beside model.json it writes the
// interactive page model.html (quadrix view) unless --no-page.
#include "experiments/command_line/command_registry.h"
#include "experiments/command_line/terminal_text.h"
#include "experiments/reports/interactive_page.h"
#include "experiments/reports/model_picture.h"
#include "experiments/studies/modelling_evaluation.h"
#include "estimation/registration.h"
#include "estimation/registration_config.h"
#include "fitting/scene_modelling.h"
#include "geometry/error.h"
#include "geometry/io.h"
#include "geometry/mesh.h"

#include <nlohmann/json.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <optional>

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
    const Eigen::Isometry3f pose = read_pose_matrix(options.poses[i]).cast<float>();
    for (Eigen::Index column = 0; column < clouds.back().positions.cols(); ++column)
      clouds.back().positions.col(column) = pose * Eigen::Vector3f(clouds.back().positions.col(column));
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

// The interactive page beside the JSON (model.json -> model.html), with the same extents as --mesh.
// Returns its path, or "" when skipped or not buildable (libjs-three missing: a warning only, since
// the model is written).
std::string write_model_page(const ModelCommandOptions& options, const PresetChoice& preset, const ModellingOptions& modelling,
                             const ModellingResult& result, const PointCloud& cloud, const Eigen::Matrix3Xd& points) {
  if (options.no_page) return "";
  const SceneModel& model = result.model;
  const std::filesystem::path json_path(options.out);
  const std::string page_path = json_path.extension() == ".json"
                                    ? std::filesystem::path(json_path).replace_extension(".html").string()
                                    : options.out + ".html";  // never the JSON's own path
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
                         const std::string& page_path) {
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
    std::printf(", normal (%.4f, %.4f, %.4f), offset %.3f m", model.ground_normal.x(), model.ground_normal.y(),
                model.ground_normal.z(), model.ground_offset);
  std::printf("\nwrote %s", options.out.c_str());
  const std::initializer_list<const std::string*> written = {&options.binary, &options.mesh, &options.elements, &options.picture,
                                                             &page_path};
  for (const std::string* path : written)
    if (!path->empty()) std::printf(", %s", path->c_str());
  std::printf("\n");
}

void run(const ModelCommandOptions& options) {
  if (options.plane_method != "voxel" && options.plane_method != "cgal")
    throw Error("--plane-method: expected voxel or cgal, got '" + options.plane_method + "'");
  if (!options.config.empty() && !std::filesystem::exists(options.config))
    throw file_error(options.config, "configuration file does not exist");
  if (!options.fitter.empty()) make_quadric_fitter(options.fitter);  // fail early with the list of fitters
  CloudReadOptions read_options;
  read_options.format = cloud_format_from_name(options.format);
  const Eigen::Vector3d sensor_origin(options.sensor_origin.data());
  if (!sensor_origin.allFinite()) throw Error("--sensor-origin: expected three finite numbers X,Y,Z in metres");
  const bool centred = !sensor_origin.isZero(0.0);
  if (centred && (options.inputs.size() != 1 || !options.poses.empty()))
    throw Error("--sensor-origin: takes one input without --poses (stations merged by pose are modelled in the world frame)");
  const PointCloud cloud = read_merged_clouds(options, read_options);
  // A cloud in a map's frame is modelled centred on its sensor (the extraction measures ranges and
  // heights from the origin), and the model is moved back: every output is in the file's frame.
  const PointCloud centred_cloud = centred ? centred_on_sensor(cloud, sensor_origin) : PointCloud();
  const PointCloud& modelled = centred ? centred_cloud : cloud;
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
  const PresetChoice preset{options.preset, extraction.preset, notes};
  std::vector<std::uint32_t> labels;
  if (!options.labels.empty()) {
    labels = read_semantic_kitti_labels(options.labels, cloud.size());
    extraction.semantic_mode = SemanticMode::Labels;
  }
  // Read before modelling, so a bad file fails at once.
  std::vector<std::uint32_t> score_labels;
  if (!options.score_labels.empty()) score_labels = read_semantic_kitti_labels(options.score_labels, cloud.size());
  ModellingResult result = model_scene(modelled, extraction, modelling, labels);
  if (centred) result.model = translated(std::move(result.model), sensor_origin);
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

  write_scene_model_json(options.out, model, model_json_extra(options, preset, modelling, result, raw_bytes, element_counts, scores));
  if (!options.binary.empty()) write_scene_model_binary(options.binary, model);
  const Eigen::Matrix3Xd points = cloud.positions.cast<double>();
  write_mesh_outputs(options, result, points);
  if (!options.elements.empty()) write_point_cloud(options.elements, element_cloud(result, cloud));
  const std::string page_path = write_model_page(options, preset, modelling, result, cloud, points);
  print_model_summary(options, preset, modelling, result, cloud, quadric_counts, element_counts, binary_bytes.size(), raw_bytes,
                      page_path);
  if (scores) print_class_scores(*scores);
}

const CommandRegistration registration(50, [](CLI::App& app) {
  auto options = std::make_shared<ModelCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "model", "Model a point cloud with quadrics (paper's scene representation) and write JSON/binary/mesh");
  command->add_option("input", options->inputs, "Point cloud (any supported format); several with --poses are merged")
      ->required();
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
  command->add_option("--out", options->out, "Model JSON (quadrics array + stats)")->required();
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
  command->callback([options] { run(*options); });
});

}  // namespace
}  // namespace quadrix::cli
