// The self-contained HTML page of `quadrix view` (see interactive_page.h).
#include "experiments/reports/interactive_page.h"

#include "experiments/reports/interactive_page_script.h"

#include "geometry/error.h"
#include "geometry/io.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <functional>
#include <fstream>
#include <map>
#include <ostream>
#include <sstream>

namespace quadrix {

std::string read_page_file(const std::string& path, const std::string& what) {
  // A FIFO or a device would block or never end: only regular files are read.
  std::error_code code;
  if (std::filesystem::exists(path, code) && !std::filesystem::is_regular_file(path, code))
    throw file_error(path, "cannot read " + what + ": not a regular file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw file_error(path, "cannot open " + what);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// The libjs-three files, read at run time: the page must not depend on a copy in the repository.
std::string read_three_js_file(const std::string& relative) {
  const std::string path = std::string(kThreeJsDirectory) + "/" + relative;
  if (!std::filesystem::exists(path))
    throw file_error(path, "not found; the 3-D pages inline three.js from Debian's libjs-three "
                           "(apt-get install libjs-three)");
  return read_page_file(path, "three.js file of libjs-three");
}

// Text inlined into a <script> element must not close it early.
std::string escape_script_text(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '<' && i + 1 < text.size() && text[i + 1] == '/') {
      out += "<\\/";
      ++i;
    } else {
      out += text[i];
    }
  }
  return out;
}

// JSON text embedded in a <script> element: `<`, `>` and `&` (which JSON only holds inside strings)
// and U+2028/U+2029 written as \u escapes, so no string from data (a file named "<!--<script>.bin",
// a crafted report) can close the element or change how the HTML parser reads it. JSON.parse reads
// the same values back.
std::string json_for_script(const std::string& text) {
  std::string out;
  out.reserve(text.size() + 64);
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '<') {
      out += "\\u003c";
    } else if (c == '>') {
      out += "\\u003e";
    } else if (c == '&') {
      out += "\\u0026";
    } else if (c == '\xE2' && i + 2 < text.size() && text[i + 1] == '\x80' && (text[i + 2] == '\xA8' || text[i + 2] == '\xA9')) {
      out += text[i + 2] == '\xA8' ? "\\u2028" : "\\u2029";
      i += 2;
    } else {
      out += c;
    }
  }
  return out;
}

namespace {

using nlohmann::json;


// A file named by a folder's own description (scene.json's scans[].cloud): relative, and inside
// the folder once links are resolved. `quadrix view DIR` reads nothing outside DIR.
std::filesystem::path file_inside_folder(const std::filesystem::path& folder, const std::string& name, const std::string& where) {
  const std::filesystem::path relative(name);
  const std::filesystem::path normal = relative.lexically_normal();
  if (name.empty() || relative.is_absolute() || relative.has_root_name() || (!normal.empty() && *normal.begin() == ".."))
    throw file_error(where, "\"" + name + "\" is not a file inside the folder (expected a path relative to it)");
  const std::filesystem::path base = std::filesystem::weakly_canonical(folder);
  const std::filesystem::path resolved = std::filesystem::weakly_canonical(folder / relative);
  const auto mismatch = std::mismatch(base.begin(), base.end(), resolved.begin(), resolved.end());
  if (mismatch.first != base.end())
    throw file_error(where, "\"" + name + "\" leads outside the folder (a link to " + resolved.string() + ")");
  return resolved;
}

std::string base64(const void* data, std::size_t bytes) {
  static const char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto* in = static_cast<const unsigned char*>(data);
  std::string out;
  out.reserve((bytes + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < bytes; i += 3) {
    const unsigned v = (in[i] << 16) | (in[i + 1] << 8) | in[i + 2];
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += kAlphabet[(v >> 6) & 63];
    out += kAlphabet[v & 63];
  }
  if (i < bytes) {
    const unsigned v = (in[i] << 16) | (i + 1 < bytes ? in[i + 1] << 8 : 0);
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += i + 1 < bytes ? kAlphabet[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

// Float32 little-endian (every supported target is little-endian, as the binary model format).
std::string base64_floats(const std::vector<float>& values) { return base64(values.data(), values.size() * sizeof(float)); }
std::string base64_indices(const std::vector<std::uint32_t>& values) {
  return base64(values.data(), values.size() * sizeof(std::uint32_t));
}

// Points as 16-bit integers on a grid spanning their box ({"origin", "step", "count", "data"}):
// half the bytes of float32, at a step of box/65535 (1.5 mm on a 100 m scene), so big clouds open fast.
json quantized_points(const PointCloud& cloud) {
  std::vector<Eigen::Vector3f> finite;
  finite.reserve(cloud.size());
  for (Eigen::Index i = 0; i < cloud.positions.cols(); ++i)
    if (cloud.positions.col(i).allFinite()) finite.push_back(cloud.positions.col(i));
  Eigen::Vector3f low = Eigen::Vector3f::Zero(), high = Eigen::Vector3f::Zero();
  if (!finite.empty()) {
    low = high = finite.front();
    for (const Eigen::Vector3f& p : finite) {
      low = low.cwiseMin(p);
      high = high.cwiseMax(p);
    }
  }
  const Eigen::Vector3f step = ((high - low) / 65535.0f).cwiseMax(1e-6f);
  std::vector<std::uint16_t> values;
  values.reserve(3 * finite.size());
  for (const Eigen::Vector3f& p : finite)
    for (int k = 0; k < 3; ++k)
      values.push_back(static_cast<std::uint16_t>(std::clamp(std::lround((p[k] - low[k]) / step[k]), 0L, 65535L)));
  return {{"origin", {low.x(), low.y(), low.z()}},
          {"step", {step.x(), step.y(), step.z()}},
          {"count", finite.size()},
          {"data", base64(values.data(), values.size() * sizeof(std::uint16_t))}};
}

Eigen::Isometry3d matrix_from_rows(const json& rows, const std::string& where) {
  if (!rows.is_array() || rows.size() != 4) throw Error(where + ": expected a 4x4 matrix (4 rows of 4 numbers)");
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r) {
    if (!rows[r].is_array() || rows[r].size() != 4) throw Error(where + ": row " + std::to_string(r) + " is not 4 numbers");
    for (int c = 0; c < 4; ++c) m(r, c) = rows[r][c].get<double>();
  }
  Eigen::Isometry3d pose;
  pose.matrix() = m;
  return pose;
}

// Name of a record label: its ElementClass, or "label N" for labels of other schemes (synthetic scenes).
std::string label_name(std::uint32_t label) {
  return label >= 1 && label <= 10 ? element_class_name(static_cast<ElementClass>(label)) : "label " + std::to_string(label);
}

// The centre a correspondence line ends at: t_f of the record (paper Struct. 1).
json centres_of(const SceneModel& model) {
  std::vector<float> values;
  for (const QuadricRecord& record : model.records)
    values.insert(values.end(), {static_cast<float>(record.full_center.x()), static_cast<float>(record.full_center.y()),
                                 static_cast<float>(record.full_center.z())});
  json classes = json::array();
  json types = json::array();
  for (std::size_t i = 0; i < model.records.size(); ++i) {
    classes.push_back(label_name(model.records[i].label));
    types.push_back(quadric_type_name(model.types[i]));
  }
  return {{"centres", base64_floats(values)}, {"classes", classes}, {"types", types}, {"augmented_begin", model.augmented_begin}};
}

std::string page_html(const std::string& title, const json& data) {
  const std::string three = read_three_js_file("three.min.js");
  const std::string controls = read_three_js_file("examples/js/controls/OrbitControls.js");
  std::string html;
  html.reserve(three.size() + controls.size() + 4096);
  html += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>quadrix view: ";
  for (const char c : title) html += c == '<' ? std::string("&lt;") : c == '&' ? std::string("&amp;") : std::string(1, c);
  html += "</title>\n<style>\n";
  html += kPageStyle;
  html += "</style>\n</head>\n<body>\n<div id=\"view\"></div>\n<div id=\"panel\"></div>\n<div id=\"pick\"></div>\n";
  html += "<script>\n" + escape_script_text(kPageErrorHook) + "\n</script>\n";
  html += "<script>/* three.js, " + std::string(kThreeJsDirectory) + "/three.min.js (libjs-three, MIT) */\n" +
          escape_script_text(three) + "\n</script>\n";
  html += "<script>/* " + std::string(kThreeJsDirectory) + "/examples/js/controls/OrbitControls.js (libjs-three, MIT) */\n" +
          escape_script_text(controls) + "\n</script>\n";
  html += "<script type=\"application/json\" id=\"quadrix-data\">" + json_for_script(data.dump(-1, ' ', false, json::error_handler_t::replace)) + "</script>\n";
  html += "<script>\n" + escape_script_text(kPageScript) + "\n</script>\n</body>\n</html>\n";
  return html;
}

const json& require(const json& object, const char* key, const std::string& where) {
  const auto it = object.find(key);
  if (it == object.end()) throw Error(where + ": missing key \"" + key + "\"");
  return *it;
}

}  // namespace

std::vector<PageQuadric> page_quadrics(const SceneModel& model) {
  std::vector<PageQuadric> quadrics;
  for (std::size_t i = 0; i < model.augmented_begin && i < model.records.size(); ++i) {
    PageQuadric quadric;
    quadric.record = model.records[i];
    quadric.type = model.types[i];
    quadric.class_name = label_name(quadric.record.label);
    quadric.point_count = i < model.element_point_counts.size() ? model.element_point_counts[i] : 0;
    quadrics.push_back(quadric);
  }
  return quadrics;
}

LocalExtent local_extent_of_points(const QuadricDecomposition& shape, const Eigen::Matrix3Xd& points,
                                   const std::vector<std::uint32_t>& indices, double margin) {
  const Eigen::Isometry3d to_local = shape.pose().inverse();
  LocalExtent extent;
  extent.minimum = Eigen::Vector3d::Constant(1e300);
  extent.maximum = Eigen::Vector3d::Constant(-1e300);
  for (const std::uint32_t index : indices) {
    if (index >= static_cast<std::uint32_t>(points.cols()))
      throw Error("local_extent_of_points: point index " + std::to_string(index) + " beyond the " +
                  std::to_string(points.cols()) + " points");
    const Eigen::Vector3d local = to_local * Eigen::Vector3d(points.col(index));
    extent.minimum = extent.minimum.cwiseMin(local);
    extent.maximum = extent.maximum.cwiseMax(local);
  }
  if (indices.empty()) return LocalExtent{};
  extent.minimum.array() -= margin;
  extent.maximum.array() += margin;
  return extent;
}

TriangleMesh page_quadric_mesh(const PageQuadric& quadric, int resolution) {
  const QuadricDecomposition shape = quadric.record.quadric().decompose();
  if (shape.type == QuadricType::Invalid || shape.type == QuadricType::Imaginary) return {};
  if (quadric.extent) return mesh_surface(shape, *quadric.extent, resolution);
  // Without an extent: a box around t_f along the columns of R_f. A record does not keep the
  // element's full spread (s_f takes the statistical scale s_s index by index, while R_f's free
  // columns are filled from R_s in descending-variance order, so a plane's normal gets the largest
  // spread and a cylinder's axis the smallest), so the half sides come per type: planes span the two
  // largest of s_f in their plane, lines the largest along their axis, cylinders and cones at least
  // three radii along theirs, closed surfaces 1.2 s_f.
  Eigen::Isometry3d box = Eigen::Isometry3d::Identity();
  box.linear() = quadric.record.full_rotation.normalized().toRotationMatrix();
  box.translation() = quadric.record.full_center;
  const Eigen::Vector3d s = quadric.record.full_scale.cwiseAbs();
  Eigen::Vector3d sorted = s;
  std::sort(sorted.data(), sorted.data() + 3, std::greater<double>());
  Eigen::Vector3d half;
  switch (shape.type) {
    case QuadricType::Plane:
    case QuadricType::ParallelPlanes: half = Eigen::Vector3d(0.05, 1.1 * sorted[0], 1.1 * sorted[1]); break;  // normal = column a
    case QuadricType::Line: half = Eigen::Vector3d(0.05, 0.05, 1.1 * sorted[0]).cwiseMax(0.02 * sorted[0]); break;  // axis = column c
    case QuadricType::CircularCylinder:
    case QuadricType::EllipticCylinder:
    case QuadricType::CircularCone:
    case QuadricType::EllipticCone: {
      const double radius = std::max(shape.type == QuadricType::CircularCone || shape.type == QuadricType::EllipticCone ? 0.5 : s.head<2>().maxCoeff(), 0.05);
      half = Eigen::Vector3d(1.2 * radius, 1.2 * radius, std::max(3.0 * radius, 1.1 * s[2]));
      if (shape.type == QuadricType::CircularCone || shape.type == QuadricType::EllipticCone)
        half.head<2>() = Eigen::Vector3d::Constant(half[2] * std::max(shape.scale[0], shape.scale[1]) * 1.2).head<2>();
      break;
    }
    default: half = 1.2 * s; break;
  }
  half = half.cwiseMax(0.05);
  const Eigen::Isometry3d box_to_local = shape.pose().inverse() * box;
  LocalExtent extent;
  extent.minimum = Eigen::Vector3d::Constant(1e300);
  extent.maximum = Eigen::Vector3d::Constant(-1e300);
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d local =
        box_to_local * Eigen::Vector3d((corner & 1 ? 1 : -1) * half.x(), (corner & 2 ? 1 : -1) * half.y(), (corner & 4 ? 1 : -1) * half.z());
    extent.minimum = extent.minimum.cwiseMin(local);
    extent.maximum = extent.maximum.cwiseMax(local);
  }
  const TriangleMesh surface = mesh_surface(shape, extent, resolution);
  // The axis-aligned extent of a turned box is larger than the box: keep triangles whose centroid
  // lies inside the box itself, then drop the vertices no triangle uses.
  const Eigen::Isometry3d world_to_box = box.inverse();
  std::vector<int> new_index(static_cast<std::size_t>(surface.vertices.cols()), -1);
  TriangleMesh mesh;
  std::vector<Eigen::Vector3d> kept;
  for (const Eigen::Vector3i& triangle : surface.triangles) {
    const Eigen::Vector3d centroid =
        (surface.vertices.col(triangle[0]) + surface.vertices.col(triangle[1]) + surface.vertices.col(triangle[2])) / 3.0;
    if (((world_to_box * centroid).cwiseAbs() - half).maxCoeff() > 1e-9) continue;
    Eigen::Vector3i mapped;
    for (int k = 0; k < 3; ++k) {
      int& slot = new_index[static_cast<std::size_t>(triangle[k])];
      if (slot < 0) {
        slot = static_cast<int>(kept.size());
        kept.push_back(surface.vertices.col(triangle[k]));
      }
      mapped[k] = slot;
    }
    mesh.triangles.push_back(mapped);
  }
  mesh.vertices.resize(3, static_cast<Eigen::Index>(kept.size()));
  for (std::size_t i = 0; i < kept.size(); ++i) mesh.vertices.col(static_cast<Eigen::Index>(i)) = kept[i];
  return mesh;
}

PointCloud subsample_points(const PointCloud& cloud, std::size_t budget) {
  if (budget == 0 || cloud.size() <= budget) return cloud;
  const std::size_t stride = (cloud.size() + budget - 1) / budget;
  PointCloud out;
  out.positions.resize(3, static_cast<Eigen::Index>((cloud.size() + stride - 1) / stride));
  Eigen::Index column = 0;
  for (std::size_t i = 0; i < cloud.size(); i += stride) out.positions.col(column++) = cloud.positions.col(static_cast<Eigen::Index>(i));
  return out;
}

std::string model_page_html(const ModelPageInput& input) {
  if (input.mesh_resolution < 3 || input.mesh_resolution > 256)
    throw Error("model page: mesh_resolution must be within 3..256, got " + std::to_string(input.mesh_resolution));
  json data;
  data["kind"] = "model";
  data["title"] = input.title;
  data["status"] = input.status;
  data["message"] = input.message;
  json facts = json::array();
  for (const auto& [name, value] : input.facts) facts.push_back({name, value});
  data["facts"] = facts;
  const PointCloud points = subsample_points(input.points, input.point_budget);
  data["points"] = quantized_points(points);
  data["points_total"] = input.points_total > 0 ? input.points_total : input.points.size();
  json quadrics = json::array();
  for (std::size_t i = 0; i < input.quadrics.size(); ++i) {
    const PageQuadric& quadric = input.quadrics[i];
    // A bounded plane is flat: a few segments draw it exactly (the box-clipped one needs the finer grid).
    const bool flat = quadric.extent && (quadric.type == QuadricType::Plane || quadric.type == QuadricType::ParallelPlanes);
    const TriangleMesh mesh = page_quadric_mesh(quadric, flat ? 4 : input.mesh_resolution);
    std::vector<float> vertices;
    vertices.reserve(3 * static_cast<std::size_t>(mesh.vertices.cols()));
    for (Eigen::Index v = 0; v < mesh.vertices.cols(); ++v)
      for (int k = 0; k < 3; ++k) vertices.push_back(static_cast<float>(mesh.vertices(k, v)));
    std::vector<std::uint32_t> indices;
    indices.reserve(3 * mesh.triangles.size());
    for (const Eigen::Vector3i& t : mesh.triangles)
      for (int k = 0; k < 3; ++k) indices.push_back(static_cast<std::uint32_t>(t[k]));
    const auto colour = quadric_type_color(quadric.type);
    const std::array<double, 21> record = quadric.record.to_array();
    quadrics.push_back({{"index", i},
                        {"type", quadric_type_name(quadric.type)},
                        {"class", quadric.class_name},
                        {"points", quadric.point_count},
                        {"colour", {colour[0], colour[1], colour[2]}},
                        {"record", record},
                        {"vertices", base64_floats(vertices)},
                        {"triangles", base64_indices(indices)}});
  }
  data["quadrics"] = quadrics;
  return page_html(input.title, data);
}

std::string registration_page_html(const RegistrationPageInput& input) {
  json report;
  try {
    report = json::parse(input.report_json);
  } catch (const json::parse_error& error) {
    throw Error("registration page: the report is not JSON (" + std::string(error.what()) + ")");
  }
  for (const char* key : {"transform", "status", "message", "timings_ms", "counts", "candidates"}) require(report, key, "registration page: report");
  json data;
  data["kind"] = "registration";
  const json& input_paths = report.contains("input") ? report["input"] : json::object();
  const std::string source_name = input_paths.value("source", std::string("source"));
  const std::string target_name = input_paths.value("target", std::string("target"));
  data["title"] = std::filesystem::path(source_name).filename().string() + " -> " + std::filesystem::path(target_name).filename().string();
  data["report"] = report;
  data["note"] = input.note;
  // The budget is shared in proportion to the clouds' sizes.
  const std::size_t total = input.source.size() + input.target.size();
  const auto share = [&](std::size_t size) {
    return total <= input.point_budget ? size : std::max<std::size_t>(1, input.point_budget * size / std::max<std::size_t>(total, 1));
  };
  data["source"] = quantized_points(subsample_points(input.source, share(input.source.size())));
  data["target"] = quantized_points(subsample_points(input.target, share(input.target.size())));
  data["source_total"] = input.source.size();
  data["target_total"] = input.target.size();
  if (input.source_model && input.target_model) {
    data["source_model"] = centres_of(*input.source_model);
    data["target_model"] = centres_of(*input.target_model);
  }
  return page_html(data["title"].get<std::string>(), data);
}

void write_page(const std::string& path, const std::string& html) {
  write_file_atomically(path, [&html](std::ostream& out) { out << html; });
}

RegistrationPageInput read_registration_folder(const std::string& directory) {
  const std::filesystem::path folder(directory);
  const std::string report_path = (folder / "report.json").string();
  const std::string merged_path = (folder / "merged.ply").string();
  if (!std::filesystem::exists(report_path))
    throw file_error(report_path, "not found; expected the folder `quadrix register --out DIR` writes (report.json, merged.ply)");
  if (!std::filesystem::exists(merged_path))
    throw file_error(merged_path, "not found; expected the merged cloud `quadrix register --out DIR` writes beside report.json");
  RegistrationPageInput input;
  input.report_json = read_page_file(report_path, "registration report");
  json report;
  try {
    report = json::parse(input.report_json);
  } catch (const json::parse_error& error) {
    throw file_error(report_path, std::string("not valid JSON: ") + error.what());
  }
  const Eigen::Isometry3d transform = matrix_from_rows(require(report, "transform", report_path), report_path + ": \"transform\"");
  // merged.ply: target points (label 0) as they are, source points (label 1) moved by the answer.
  const PointCloud merged = read_point_cloud(merged_path);
  if (merged.labels.size() != merged.size())
    throw file_error(merged_path, "expected a per-point label field (0 target, 1 source), as merge_aligned_clouds writes");
  std::size_t source_count = 0;
  for (const std::uint32_t label : merged.labels) source_count += label == 1 ? 1 : 0;
  input.source.positions.resize(3, static_cast<Eigen::Index>(source_count));
  input.target.positions.resize(3, static_cast<Eigen::Index>(merged.size() - source_count));
  const Eigen::Isometry3d back = transform.inverse();
  // With sensor origins, merged.ply is in the target file's frame and everything else of the folder
  // between the sensor-centred clouds: the merged points are moved there.
  Eigen::Vector3f target_origin = Eigen::Vector3f::Zero();
  if (report.contains("sensor_origins")) {
    const json& origin = require(require(report, "sensor_origins", report_path), "target", report_path);
    if (!origin.is_array() || origin.size() != 3 || !origin[0].is_number() || !origin[1].is_number() || !origin[2].is_number())
      throw file_error(report_path, "\"sensor_origins\".\"target\": expected three numbers");
    target_origin = Eigen::Vector3f(origin[0].get<float>(), origin[1].get<float>(), origin[2].get<float>());
  }
  Eigen::Index s = 0, t = 0;
  for (std::size_t i = 0; i < merged.size(); ++i) {
    const Eigen::Vector3f p = merged.positions.col(static_cast<Eigen::Index>(i)) - target_origin;
    if (merged.labels[i] == 1)
      input.source.positions.col(s++) = (back * p.cast<double>()).cast<float>();
    else
      input.target.positions.col(t++) = p;
  }
  const std::string source_model = (folder / "source_model.json").string();
  const std::string target_model = (folder / "target_model.json").string();
  if (std::filesystem::exists(source_model) && std::filesystem::exists(target_model)) {
    input.source_model = read_scene_model_json(source_model);
    input.target_model = read_scene_model_json(target_model);
  } else {
    input.note = "no source_model.json / target_model.json in " + directory +
                 " (written by quadrix register --out since the viewer exists): correspondence lines are not shown";
  }
  return input;
}

ModelPageInput read_model_json_page(const std::string& path) {
  const std::string text = read_page_file(path, "scene model JSON");
  const SceneModel model = scene_model_from_json(text, path);
  ModelPageInput input;
  input.title = std::filesystem::path(path).filename().string();
  input.quadrics = page_quadrics(model);
  const json document = json::parse(text);
  const json stats = document.value("stats", json::object());
  input.status = stats.value("status", std::string("model"));
  if (stats.contains("input")) input.facts.push_back({"input", stats["input"].get<std::string>()});
  if (stats.contains("preset")) input.facts.push_back({"preset", stats["preset"].get<std::string>()});
  if (stats.contains("fitter")) input.facts.push_back({"fitter", stats["fitter"].get<std::string>()});
  input.facts.push_back({"source points", std::to_string(model.source_point_count)});
  input.facts.push_back({"records", std::to_string(model.size()) + " (" + std::to_string(model.augmented_count()) + " augmented points)"});
  input.message = "quadrics only: a model JSON holds no points (quadrix model writes a page with them)";
  return input;
}

ModelPageInput read_synthetic_folder_page(const std::string& directory) {
  const std::filesystem::path folder(directory);
  const std::string scene_path = (folder / "scene.json").string();
  const std::string primitives_path = (folder / "primitives.json").string();
  for (const std::string& path : {scene_path, primitives_path})
    if (!std::filesystem::exists(path)) throw file_error(path, "not found; expected a `quadrix synth` folder");
  json scene, primitives;
  try {
    scene = json::parse(read_page_file(scene_path, "synthetic scene description"));
    primitives = json::parse(read_page_file(primitives_path, "ground-truth primitives"));
  } catch (const json::parse_error& error) {
    throw Error(directory + ": scene.json or primitives.json is not valid JSON: " + error.what());
  }
  ModelPageInput input;
  input.title = scene.value("scene", std::string("synthetic scene")) + " (" + folder.filename().string() + ")";
  input.status = "ground truth";
  input.message = "the true primitives of the synthetic scene and its scans in the world frame";
  // The scans in the world frame; points per primitive from their primitive_id field.
  std::vector<PointCloud> clouds;
  std::size_t total = 0;
  std::map<long long, std::vector<std::uint32_t>> primitive_points;  // indices into the merged cloud
  for (const json& scan : require(scene, "scans", scene_path)) {
    const json& name = require(scan, "cloud", scene_path);
    if (!name.is_string()) throw file_error(scene_path, "scans[].cloud: expected a file name (a string)");
    const PointCloud cloud = read_point_cloud(file_inside_folder(folder, name.get<std::string>(), scene_path + ": scans[].cloud").string());
    const Eigen::Isometry3f pose = matrix_from_rows(require(scan, "sensor_to_world", scene_path), scene_path + ": sensor_to_world").cast<float>();
    PointCloud world;
    world.positions = pose * cloud.positions;
    const auto ids = cloud.extra_fields.find("primitive_id");
    if (ids != cloud.extra_fields.end())
      for (std::size_t i = 0; i < ids->second.size(); ++i)
        primitive_points[std::lround(ids->second[i])].push_back(static_cast<std::uint32_t>(total + i));
    total += world.size();
    clouds.push_back(std::move(world));
  }
  input.points.positions.resize(3, static_cast<Eigen::Index>(total));
  Eigen::Index column = 0;
  for (const PointCloud& cloud : clouds) {
    input.points.positions.middleCols(column, cloud.positions.cols()) = cloud.positions;
    column += cloud.positions.cols();
  }
  const Eigen::Matrix3Xd world_points = input.points.positions.cast<double>();
  for (const json& primitive : require(primitives, "primitives", primitives_path)) {
    PageQuadric quadric;
    const json& values = require(primitive, "record", primitives_path);
    if (!values.is_array() || values.size() != 21) throw file_error(primitives_path, "\"record\" of a primitive is not 21 numbers");
    std::array<double, 21> record{};
    for (std::size_t k = 0; k < 21; ++k) record[k] = values[k].get<double>();
    quadric.record = QuadricRecord::from_array(record);
    quadric.type = quadric_type_from_name(require(primitive, "model_type", primitives_path).get<std::string>());
    quadric.class_name = primitive.value("label_name", std::string("primitive"));
    const long long id = primitive.value("id", -1LL);
    // The surface where the scans hit the primitive (as `quadrix model` bounds its quadrics).
    const auto hits = primitive_points.find(id);
    quadric.point_count = hits == primitive_points.end() ? 0 : hits->second.size();
    if (quadric.point_count >= 3)
      quadric.extent = local_extent_of_points(quadric.record.quadric().decompose(), world_points, hits->second);
    input.quadrics.push_back(quadric);
  }
  input.facts.push_back({"sensor", scene.contains("sensor") ? scene["sensor"].value("name", std::string("?")) : std::string("?")});
  input.facts.push_back({"scans", std::to_string(clouds.size())});
  input.facts.push_back({"points", std::to_string(total)});
  input.facts.push_back({"primitives", std::to_string(input.quadrics.size())});
  return input;
}

}  // namespace quadrix
