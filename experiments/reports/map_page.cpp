// map.html of a map folder (see map_page.h).
#include "experiments/reports/map_page.h"

#include "experiments/reports/interactive_page.h"
#include "experiments/reports/interactive_page_script.h"
#include "geometry/error.h"
#include "geometry/io.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <deque>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

namespace quadrix {
namespace {

using nlohmann::json;

std::string html_text(const std::string& text) {
  std::string out;
  for (const char c : text) out += c == '<' ? std::string("&lt;") : c == '&' ? std::string("&amp;") : c == '>' ? std::string("&gt;") : std::string(1, c);
  return out;
}

std::vector<std::string> split_fields(const std::string& line, char separator) {
  std::vector<std::string> fields;
  std::string field;
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') { field += '"'; ++i; }
      else if (c == '"') quoted = false;
      else field += c;
    } else if (c == '"' && field.empty()) {
      quoted = true;
    } else if (c == separator) {
      fields.push_back(field);
      field.clear();
    } else if (c != '\r') {
      field += c;
    }
  }
  fields.push_back(field);
  return fields;
}

double number_field(const std::string& text, const std::string& path, std::size_t line, const std::string& column) {
  std::size_t used = 0;
  double value = 0.0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !std::isfinite(value))
    throw file_error(path, "line " + std::to_string(line) + ", column " + column + ": expected a number, got '" + text + "'");
  return value;
}

Eigen::Isometry3d pose_from_numbers(const std::vector<double>& n) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) pose.matrix()(r, c) = n[static_cast<std::size_t>(4 * r + c)];
  return pose;
}

std::string key_of(const std::string& session, const std::string& scan) { return session + '\n' + scan; }

json positions_of(const std::vector<MapPagePose>& poses, const std::vector<std::string>& sessions) {
  json lines = json::array();
  for (std::size_t s = 0; s < sessions.size(); ++s) {
    json values = json::array();
    for (const MapPagePose& pose : poses)
      if (pose.session == sessions[s])
        for (int k = 0; k < 3; ++k) values.push_back(std::round(pose.pose.translation()[k] * 1000.0) / 1000.0);
    lines.push_back({{"session", s}, {"xyz", values}});
  }
  return lines;
}

}  // namespace

// The page's script: panel and legend first (they work without WebGL), then the 3-D view.
extern const char* const kMapPageScript;

std::vector<MapPagePose> read_map_poses(const std::string& path) {
  std::istringstream in(read_page_file(path, "poses"));
  std::vector<MapPagePose> poses;
  std::string line;
  std::size_t number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> fields;
    if (line.find('\t') != std::string::npos) {
      fields = split_fields(line, '\t');
    } else {
      std::istringstream words(line);
      for (std::string word; words >> word;) fields.push_back(word);
    }
    if (number == 1 && !fields.empty() && fields[0] == "session") continue;  // header
    // A trailing column (quadrix map's `frame`) may follow the 12 numbers.
    if (fields.size() != 14 && fields.size() != 15)
      throw file_error(path, "line " + std::to_string(number) + ": expected session, scan and 12 numbers (14 fields, or 15 with a frame), got " +
                                 std::to_string(fields.size()));
    std::vector<double> values;
    for (std::size_t k = 2; k < 14; ++k) values.push_back(number_field(fields[k], path, number, std::to_string(k + 1)));
    poses.push_back({fields[0], fields[1], pose_from_numbers(values)});
  }
  return poses;
}

std::vector<MapPageEdge> read_map_edges(const std::string& path) {
  std::istringstream in(read_page_file(path, "edges"));
  std::string line;
  if (!std::getline(in, line)) throw file_error(path, "empty; expected a header naming from_session, from_scan, ...");
  const std::vector<std::string> header = split_fields(line, ',');
  std::map<std::string, std::size_t> column;
  for (std::size_t i = 0; i < header.size(); ++i) column[header[i]] = i;
  std::vector<std::string> required{"from_session", "from_scan", "to_session", "to_scan", "kind", "status", "used"};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) required.push_back("t" + std::to_string(r) + std::to_string(c));
  for (const std::string& name : required)
    if (!column.count(name)) throw file_error(path, "line 1: the header has no column " + name);
  std::vector<MapPageEdge> edges;
  std::size_t number = 1;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    const std::vector<std::string> fields = split_fields(line, ',');
    if (fields.size() < header.size())
      throw file_error(path, "line " + std::to_string(number) + ": expected " + std::to_string(header.size()) + " fields, got " +
                                 std::to_string(fields.size()));
    const auto field = [&](const std::string& name) { return fields[column.at(name)]; };
    MapPageEdge edge;
    edge.from_session = field("from_session");
    edge.from_scan = field("from_scan");
    edge.to_session = field("to_session");
    edge.to_scan = field("to_scan");
    edge.kind = field("kind");
    edge.status = field("status");
    const std::string used = field("used");
    if (used == "1" || used == "true" || used == "yes") edge.used = true;
    else if (used == "0" || used == "false" || used == "no") edge.used = false;
    else throw file_error(path, "line " + std::to_string(number) + ", column used: expected 1/0 or true/false, got '" + used + "'");
    std::vector<double> values;
    for (std::size_t k = 7; k < required.size(); ++k) values.push_back(number_field(field(required[k]), path, number, required[k]));
    edge.transform = pose_from_numbers(values);
    edges.push_back(edge);
  }
  return edges;
}

std::vector<MapPagePose> odometry_trajectory(const std::vector<MapPagePose>& poses, const std::vector<MapPageEdge>& edges) {
  // neighbours[scan] = (other scan, pose of other = pose of scan * relative)
  std::map<std::string, std::vector<std::pair<std::string, Eigen::Isometry3d>>> neighbours;
  for (const MapPageEdge& edge : edges) {
    if (edge.kind != "odometry" || edge.from_session != edge.to_session) continue;
    const std::string from = key_of(edge.from_session, edge.from_scan), to = key_of(edge.to_session, edge.to_scan);
    // p_to = T p_from: pose_to = pose_from * T^-1 and pose_from = pose_to * T.
    neighbours[from].emplace_back(to, edge.transform.inverse());
    neighbours[to].emplace_back(from, edge.transform);
  }
  std::map<std::string, Eigen::Isometry3d> reached;
  std::map<std::string, bool> session_started;
  for (const MapPagePose& pose : poses) {
    if (session_started[pose.session]) continue;
    session_started[pose.session] = true;
    const std::string start = key_of(pose.session, pose.scan);
    reached[start] = pose.pose;
    std::deque<std::string> queue{start};
    while (!queue.empty()) {
      const std::string current = queue.front();
      queue.pop_front();
      for (const auto& [next, relative] : neighbours[current]) {
        if (reached.count(next)) continue;
        reached[next] = reached[current] * relative;
        queue.push_back(next);
      }
    }
  }
  std::vector<MapPagePose> before;
  for (const MapPagePose& pose : poses) {
    const auto it = reached.find(key_of(pose.session, pose.scan));
    if (it != reached.end() && neighbours.count(it->first)) before.push_back({pose.session, pose.scan, it->second});
  }
  return before;
}

std::string map_page_html(const MapPageInput& input) {
  std::vector<std::string> sessions;
  for (const MapPagePose& pose : input.poses)
    if (std::find(sessions.begin(), sessions.end(), pose.session) == sessions.end()) sessions.push_back(pose.session);
  std::map<std::string, Eigen::Vector3d> position;
  for (const MapPagePose& pose : input.poses) position[key_of(pose.session, pose.scan)] = pose.pose.translation();

  json data;
  data["title"] = input.title;
  data["sessions"] = sessions;
  data["scans"] = input.poses.size();
  data["after"] = positions_of(input.poses, sessions);
  data["before"] = positions_of(odometry_trajectory(input.poses, input.edges), sessions);
  json loops = json::array();
  std::size_t odometry_edges = 0, unplaced = 0;
  for (const MapPageEdge& edge : input.edges) {
    if (edge.kind == "odometry") {
      ++odometry_edges;
      continue;
    }
    const auto a = position.find(key_of(edge.from_session, edge.from_scan));
    const auto b = position.find(key_of(edge.to_session, edge.to_scan));
    if (a == position.end() || b == position.end()) {
      ++unplaced;
      continue;
    }
    loops.push_back({{"kind", edge.kind}, {"status", edge.status}, {"used", edge.used},
                     {"from", edge.from_session + " " + edge.from_scan}, {"to", edge.to_session + " " + edge.to_scan},
                     {"a", {a->second.x(), a->second.y(), a->second.z()}}, {"b", {b->second.x(), b->second.y(), b->second.z()}}});
  }
  data["loops"] = loops;
  data["odometry_edges"] = odometry_edges;
  data["unplaced_edges"] = unplaced;
  data["report"] = nullptr;
  if (!input.report_json.empty()) {
    try {
      data["report"] = json::parse(input.report_json);
    } catch (const json::exception& error) {
      data["note"] = std::string("report.json is not valid JSON: ") + error.what();
    }
  }
  // Map points: centimetres from the box's low corner, colours when the file has them.
  const std::size_t stride = std::max<std::size_t>(1, (input.points.size() + input.point_budget - 1) / std::max<std::size_t>(1, input.point_budget));
  json xyz = json::array(), rgb = json::array();
  Eigen::Vector3f low = Eigen::Vector3f::Constant(0.0f);
  bool any = false;
  for (std::size_t i = 0; i < input.points.size(); i += stride)
    if (input.points.positions.col(static_cast<Eigen::Index>(i)).allFinite()) {
      low = any ? low.cwiseMin(input.points.positions.col(static_cast<Eigen::Index>(i))) : Eigen::Vector3f(input.points.positions.col(static_cast<Eigen::Index>(i)));
      any = true;
    }
  const bool coloured = input.points.colors.size() == input.points.size();
  for (std::size_t i = 0; i < input.points.size(); i += stride) {
    const Eigen::Vector3f p = input.points.positions.col(static_cast<Eigen::Index>(i));
    if (!p.allFinite()) continue;
    for (int k = 0; k < 3; ++k) xyz.push_back(std::lround((p[k] - low[k]) * 100.0f));
    if (coloured)
      for (int k = 0; k < 3; ++k) rgb.push_back(input.points.colors[i][static_cast<std::size_t>(k)]);
  }
  data["points"] = {{"origin", {low.x(), low.y(), low.z()}}, {"xyz", xyz}, {"rgb", rgb}, {"total", input.points.size()}};

  const std::string three = read_three_js_file("three.min.js");
  const std::string controls = read_three_js_file("examples/js/controls/OrbitControls.js");
  std::string html;
  html.reserve(three.size() + controls.size() + 8192);
  html += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>quadrix map: " + html_text(input.title) +
          "</title>\n<style>\n";
  html += kPageStyle;
  html += "#nowebgl { padding: 24px; font-size: 15px; color: #8a4b00; }\n.legend-line { display: inline-block; width: 18px; height: 3px; "
          "margin-right: 5px; vertical-align: 3px; }\n</style>\n</head>\n<body>\n<div id=\"view\"></div>\n<div id=\"panel\"></div>\n";
  html += "<script>\n" + escape_script_text(kPageErrorHook) + "\n</script>\n";
  html += "<script>/* three.js, " + std::string(kThreeJsDirectory) + "/three.min.js (libjs-three, MIT) */\n" + escape_script_text(three) +
          "\n</script>\n";
  html += "<script>/* " + std::string(kThreeJsDirectory) + "/examples/js/controls/OrbitControls.js (libjs-three, MIT) */\n" +
          escape_script_text(controls) + "\n</script>\n";
  html += "<script type=\"application/json\" id=\"quadrix-map-data\">" + json_for_script(data.dump(-1, ' ', false, json::error_handler_t::replace)) + "</script>\n";
  html += "<script>\n" + escape_script_text(kMapPageScript) + "\n</script>\n</body>\n</html>\n";
  return html;
}

bool is_map_folder(const std::string& folder) {
  const std::filesystem::path root(folder);
  return std::filesystem::is_directory(root) && std::filesystem::exists(root / "poses.tsv") && std::filesystem::exists(root / "edges.csv");
}

MapPageInput read_map_folder(const std::string& folder, std::size_t point_budget) {
  const std::filesystem::path root(folder);
  if (!is_map_folder(folder)) throw file_error(folder, "not a map folder: expected poses.tsv and edges.csv in it");
  MapPageInput input;
  input.title = root.filename().empty() ? root.parent_path().filename().string() : root.filename().string();
  input.poses = read_map_poses((root / "poses.tsv").string());
  input.edges = read_map_edges((root / "edges.csv").string());
  if (std::filesystem::exists(root / "report.json")) input.report_json = read_page_file((root / "report.json").string(), "report");
  if (std::filesystem::exists(root / "map.ply")) input.points = read_point_cloud((root / "map.ply").string());
  input.point_budget = point_budget;
  return input;
}

std::string write_map_page(const std::string& folder) {
  const std::string path = (std::filesystem::path(folder) / "map.html").string();
  write_page(path, map_page_html(read_map_folder(folder)));
  return path;
}

std::vector<std::string> map_folder_names() {
  return {"poses.tsv", "edges.csv", "report.json", "map.ply", "map_model.qsm", "models", "map.html"};
}

const char* const kMapPageScript = R"JS(
(function () {
  'use strict';
  var data = JSON.parse(document.getElementById('quadrix-map-data').textContent);
  var panel = document.getElementById('panel'), viewElement = document.getElementById('view');
  function element(tag, text, className) {
    var e = document.createElement(tag);
    if (text !== undefined && text !== null) e.textContent = String(text);
    if (className) e.className = className;
    return e;
  }
  function addRow(table, name, value) {
    var tr = element('tr');
    tr.appendChild(element('td', name));
    tr.appendChild(element('td', value, 'n'));
    table.appendChild(tr);
  }
  function formatted(value) {
    if (typeof value === 'number') return Number.isInteger(value) ? String(value) : value.toFixed(Math.abs(value) >= 100 ? 1 : 3);
    return String(value);
  }
  var palette = [[31, 119, 180], [214, 39, 40], [44, 160, 44], [148, 103, 189], [140, 86, 75], [227, 119, 194], [127, 127, 127], [23, 190, 207]];
  function sessionColour(s) { return palette[s % palette.length]; }
  function css(c) { return 'rgb(' + c[0] + ',' + c[1] + ',' + c[2] + ')'; }
  function lighter(c) { return [Math.round(c[0] * 0.45 + 140), Math.round(c[1] * 0.45 + 140), Math.round(c[2] * 0.45 + 140)]; }
  // Loop edges by status: ok green, ambiguous amber, anything else (rejected, failed, degenerate) red; used solid, unused faint.
  function statusGroup(status) { return status === 'ok' ? 'ok' : status === 'ambiguous' ? 'ambiguous' : 'rejected'; }
  var groupColour = {ok: [26, 150, 65], ambiguous: [230, 145, 0], rejected: [215, 25, 28]};

  // ---- panel: counts, report, legend ----
  panel.appendChild(element('h1', data.title));
  if (data.note) panel.appendChild(element('div', data.note, 'note'));
  panel.appendChild(element('h2', 'Counts'));
  var counts = element('table');
  addRow(counts, 'sessions', data.sessions.length);
  addRow(counts, 'scans', data.scans);
  addRow(counts, 'odometry edges', data.odometry_edges);
  addRow(counts, 'loop edges', data.loops.length);
  var byGroup = {};
  data.loops.forEach(function (edge) {
    var key = statusGroup(edge.status) + (edge.used ? ', used' : ', not used');
    byGroup[key] = (byGroup[key] || 0) + 1;
  });
  Object.keys(byGroup).sort().forEach(function (key) { addRow(counts, '  ' + key, byGroup[key]); });
  if (data.unplaced_edges) addRow(counts, 'edges without poses', data.unplaced_edges);
  addRow(counts, 'map points shown', data.points.xyz.length / 3 + ' of ' + data.points.total);
  panel.appendChild(counts);
  if (data.report && typeof data.report === 'object') {
    // Every number, text and flag of report.json, nested keys joined with dots; an ATE found first.
    var flat = [];
    (function walk(value, prefix, depth) {
      if (value !== null && typeof value === 'object' && !Array.isArray(value) && depth < 4) {
        Object.keys(value).forEach(function (key) { walk(value[key], prefix ? prefix + '.' + key : key, depth + 1); });
      } else if (value === null || typeof value !== 'object') {
        flat.push([prefix, value]);
      }
    })(data.report, '', 0);
    var ate = flat.filter(function (entry) { return /(^|[._])ate/i.test(entry[0]); });
    if (ate.length) {
      panel.appendChild(element('h2', 'Evaluation'));
      var evaluation = element('table');
      ate.forEach(function (entry) { addRow(evaluation, entry[0], formatted(entry[1])); });
      panel.appendChild(evaluation);
    }
    panel.appendChild(element('h2', 'Report'));
    var report = element('table');
    flat.slice(0, 200).forEach(function (entry) { addRow(report, entry[0], entry[1] === null ? '-' : formatted(entry[1])); });
    panel.appendChild(report);
  }
  panel.appendChild(element('h2', 'Legend'));
  var legend = element('div');
  panel.appendChild(legend);
  var toggles = [];  // {label, colour, dashed, objects: []}
  function legendEntry(text, colour, faint) {
    var entry = {objects: [], box: document.createElement('input')};
    var label = element('label', null, 'toggle');
    entry.box.type = 'checkbox';
    entry.box.checked = true;
    label.appendChild(entry.box);
    var swatch = element('span', null, 'legend-line');
    swatch.style.background = css(colour);
    if (faint) swatch.style.opacity = '0.35';
    label.appendChild(swatch);
    label.appendChild(document.createTextNode(text));
    legend.appendChild(label);
    toggles.push(entry);
    return entry;
  }
  var sessionEntries = data.sessions.map(function (name, s) {
    return {after: legendEntry('session ' + name + ': after (poses.tsv)', sessionColour(s)),
            before: legendEntry('session ' + name + ': before (odometry)', lighter(sessionColour(s)))};
  });
  var groupEntries = {};
  ['ok', 'ambiguous', 'rejected'].forEach(function (group) {
    [true, false].forEach(function (used) {
      var count = data.loops.filter(function (e) { return statusGroup(e.status) === group && e.used === used; }).length;
      if (count) groupEntries[group + used] = legendEntry('loop edges ' + group + (used ? ', used' : ', not used') + ' (' + count + ')', groupColour[group], !used);
    });
  });
  var pointsEntry = data.points.xyz.length ? legendEntry('map points', [120, 120, 120]) : null;

  function finish(webgl) {
    if (!webgl) document.body.setAttribute('data-webgl', 'missing');
    var ms = performance.now().toFixed(0);
    document.body.setAttribute('data-ready-ms', ms);
    document.title = 'quadrix map ready ' + ms + ' ms' + (webgl ? '' : ' (no WebGL)');
  }

  // ---- 3-D view, when the browser has WebGL ----
  var probe = document.createElement('canvas'), context = null;
  try { context = probe.getContext('webgl') || probe.getContext('experimental-webgl'); } catch (error) { context = null; }
  if (!context || typeof THREE === 'undefined' || typeof THREE.OrbitControls === 'undefined') {
    viewElement.appendChild(element('div', 'WebGL is not available in this browser, so the 3-D view of the trajectories, loop edges ' +
        'and map is off. The panel on the right still lists the counts and the report.', 'note'));
    viewElement.firstChild.id = 'nowebgl';
    finish(false);
    return;
  }
  var renderer = new THREE.WebGLRenderer({canvas: probe, context: context, preserveDrawingBuffer: true});
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setClearColor(0xffffff, 1);
  viewElement.appendChild(renderer.domElement);
  var scene = new THREE.Scene();
  var camera = new THREE.PerspectiveCamera(45, 1, 0.5, 50000);
  camera.up.set(0, 0, 1);
  var controls = new THREE.OrbitControls(camera, renderer.domElement);
  controls.screenSpacePanning = true;
  var frameRequested = false;
  function render() { frameRequested = false; renderer.render(scene, camera); }
  function requestRender() { if (!frameRequested) { frameRequested = true; requestAnimationFrame(render); } }
  controls.addEventListener('change', requestRender);
  function resize() {
    var width = Math.max(viewElement.clientWidth, 1), height = Math.max(viewElement.clientHeight, 1);
    renderer.setSize(width, height);
    camera.aspect = width / height;
    camera.updateProjectionMatrix();
    requestRender();
  }
  window.addEventListener('resize', resize);
  var box = new THREE.Box3();
  function colourOf(c) { return new THREE.Color(c[0] / 255, c[1] / 255, c[2] / 255); }
  function line(xyz, colour, segments, faint) {
    var geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(xyz), 3));
    geometry.computeBoundingBox();
    box.union(geometry.boundingBox);
    var material = new THREE.LineBasicMaterial({color: colourOf(colour), transparent: !!faint, opacity: faint ? 0.35 : 1.0});
    var object = segments ? new THREE.LineSegments(geometry, material) : new THREE.Line(geometry, material);
    scene.add(object);
    return object;
  }
  data.after.forEach(function (trajectory) {
    if (trajectory.xyz.length >= 6) sessionEntries[trajectory.session].after.objects.push(line(trajectory.xyz, sessionColour(trajectory.session), false, false));
  });
  data.before.forEach(function (trajectory) {
    if (trajectory.xyz.length >= 6) sessionEntries[trajectory.session].before.objects.push(line(trajectory.xyz, lighter(sessionColour(trajectory.session)), false, false));
  });
  Object.keys(groupEntries).forEach(function (key) {
    var xyz = [];
    data.loops.forEach(function (e) { if (statusGroup(e.status) + e.used === key) xyz.push(e.a[0], e.a[1], e.a[2], e.b[0], e.b[1], e.b[2]); });
    var group = key.replace(/(true|false)$/, '');
    groupEntries[key].objects.push(line(xyz, groupColour[group], true, /false$/.test(key)));
  });
  if (pointsEntry) {
    var p = data.points, count = p.xyz.length / 3, positions = new Float32Array(p.xyz.length);
    for (var i = 0; i < p.xyz.length; ++i) positions[i] = p.origin[i % 3] + p.xyz[i] / 100;
    var geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
    var material;
    if (p.rgb.length === p.xyz.length) {
      var colours = new Float32Array(p.rgb.length);
      for (var j = 0; j < p.rgb.length; ++j) colours[j] = p.rgb[j] / 255;
      geometry.setAttribute('color', new THREE.BufferAttribute(colours, 3));
      material = new THREE.PointsMaterial({size: 1.5, sizeAttenuation: false, vertexColors: THREE.VertexColors});
    } else {
      material = new THREE.PointsMaterial({size: 1.5, sizeAttenuation: false, color: 0x888888});
    }
    geometry.computeBoundingBox();
    box.union(geometry.boundingBox);
    var cloud = new THREE.Points(geometry, material);
    scene.add(cloud);
    pointsEntry.objects.push(cloud);
  }
  toggles.forEach(function (entry) {
    entry.box.addEventListener('change', function () {
      entry.objects.forEach(function (object) { object.visible = entry.box.checked; });
      requestRender();
    });
  });
  if (box.isEmpty()) box.set(new THREE.Vector3(-10, -10, -1), new THREE.Vector3(10, 10, 1));
  var centre = box.getCenter(new THREE.Vector3()), size = box.getSize(new THREE.Vector3());
  var extent = Math.max(size.x, size.y, size.z, 1);
  controls.target.copy(centre);
  camera.position.set(centre.x, centre.y - 0.6 * extent, centre.z + 1.1 * extent);
  camera.far = 20 * extent;
  resize();
  controls.update();
  requestAnimationFrame(function () { render(); finish(true); });
})();
)JS";

}  // namespace quadrix
