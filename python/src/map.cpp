// quadrix.map: one map from many scans (estimation/mapping.h), in this process (TBB) or with the
// per-scan modelling and the per-pair registrations as tasks on a Dask distributed cluster
// (`client=`); the pose graph is solved where the call was made. Workers read the clouds from the
// paths of the scan list (a filesystem every worker shares) and return models and edges as bytes.
#include "bindings.h"

#include "estimation/mapping.h"
#include "estimation/registration_config.h"
#include "experiments/reports/map_page.h"
#include "geometry/error.h"
#include "geometry/output_paths.h"

#include <pybind11/eval.h>
#include <pybind11/stl.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <cctype>
#include <sstream>
#include <stdlib.h>
#include <unistd.h>

namespace quadrix::python {

namespace {

/// A map run as Python sees it: the result, the evaluation when truth was given, the folder written.
struct MapRun {
  MapResult result;
  std::optional<MapEvaluation> evaluation;
  std::string evaluation_json;
  std::string out;
};

/// MapOptions from quadrix.map's keyword arguments (the names of MapOptions' members, plus `config`:
/// a dict in the YAML schema or a YAML file path applied to the named preset for every scan and pair).
/// TypeError for an unknown keyword, ValueError for a bad value.
MapOptions map_options_from(const py::dict& keywords) {
  MapOptions options;
  py::object config = py::none();
  for (const auto& item : keywords) {
    const std::string key = item.first.cast<std::string>();
    const py::handle value = item.second;
    try {
      if (key == "preset") options.preset = value.cast<std::string>();
      else if (key == "maximum_median_range") options.maximum_median_range = value.cast<double>();
      else if (key == "loop_radius") options.loop_radius = value.cast<double>();
      else if (key == "loop_radius_growth") options.loop_radius_growth = value.cast<double>();
      else if (key == "maximum_loop_radius") options.maximum_loop_radius = value.cast<double>();
      else if (key == "minimum_loop_travel") options.minimum_loop_travel = value.cast<double>();
      else if (key == "candidates_per_scan") options.candidates_per_scan = value.cast<std::size_t>();
      else if (key == "minimum_candidate_spacing") options.minimum_candidate_spacing = value.cast<double>();
      else if (key == "place_candidates_per_scan") options.place_candidates_per_scan = value.cast<std::size_t>();
      else if (key == "place_query_stride") options.place_query_stride = value.cast<std::size_t>();
      else if (key == "joint_rounds") options.joint_rounds = value.cast<std::size_t>();
      else if (key == "joint_radius") options.joint_radius = value.cast<double>();
      else if (key == "joint_gate_translation") options.joint_gate_translation = value.cast<double>();
      else if (key == "joint_gate_rotation_degrees") options.joint_gate_rotation_degrees = value.cast<double>();
      else if (key == "place_consensus_rotation_degrees") options.place_consensus_rotation_degrees = value.cast<double>();
      else if (key == "place_consensus_translation") options.place_consensus_translation = value.cast<double>();
      else if (key == "place_vote_minimum") options.place_vote_minimum = value.cast<std::size_t>();
      else if (key == "place_vote_rotation_degrees") options.place_vote_rotation_degrees = value.cast<double>();
      else if (key == "place_vote_translation") options.place_vote_translation = value.cast<double>();
      else if (key == "place_vote_ratio") options.place_vote_ratio = value.cast<double>();
      else if (key == "use_ambiguous_joint_edges") options.use_ambiguous_joint_edges = value.cast<bool>();
      else if (key == "ambiguous_gate_translation") options.ambiguous_gate_translation = value.cast<double>();
      else if (key == "ambiguous_gate_rotation_degrees") options.ambiguous_gate_rotation_degrees = value.cast<double>();
      else if (key == "register_consecutive") options.register_consecutive = value.cast<bool>();
      else if (key == "use_ambiguous_edges") options.use_ambiguous_edges = value.cast<bool>();
      else if (key == "use_ambiguous_edges_across_sessions") options.use_ambiguous_edges_across_sessions = value.cast<bool>();
      else if (key == "odometry_gate_sigmas") options.odometry_gate_sigmas = value.cast<double>();
      else if (key == "loop_information_from_registration") options.loop_information_from_registration = value.cast<bool>();
      else if (key == "loop_information_scale") options.loop_information_scale = value.cast<double>();
      else if (key == "loop_translation_sigma") options.loop_translation_sigma = value.cast<double>();
      else if (key == "loop_rotation_sigma_degrees") options.loop_rotation_sigma_degrees = value.cast<double>();
      else if (key == "odometry_translation_drift") options.odometry_translation_drift = value.cast<double>();
      else if (key == "odometry_rotation_drift_degrees") options.odometry_rotation_drift_degrees = value.cast<double>();
      else if (key == "odometry_translation_floor") options.odometry_translation_floor = value.cast<double>();
      else if (key == "odometry_rotation_floor_degrees") options.odometry_rotation_floor_degrees = value.cast<double>();
      else if (key == "information_rounds") options.information_rounds = value.cast<std::size_t>();
      else if (key == "information_minimum_edges") options.information_minimum_edges = value.cast<std::size_t>();
      else if (key == "information_tolerance") options.information_tolerance = value.cast<double>();
      else if (key == "outlier_threshold") options.outlier_threshold = value.cast<double>();
      else if (key == "maximum_outlier_removals") options.maximum_outlier_removals = value.cast<std::size_t>();
      else if (key == "map_voxel") options.map_voxel = value.cast<double>();
      else if (key == "cloud_cache") options.cloud_cache = value.cast<std::size_t>();
      else if (key == "config") config = py::reinterpret_borrow<py::object>(value);
      else throw py::type_error("map() got an unexpected keyword argument '" + key + "'");
    } catch (const py::cast_error&) {
      throw Error("map: option " + key + "=" + py::repr(value).cast<std::string>() +
                  ": expected a number (a non-negative integer for counts, a string for preset, a bool for switches)");
    }
  }
  if (!config.is_none()) {
    if (options.preset == "auto") throw Error("map: config= applies to a named preset (preset='vlp64', ...), not auto");
    RegistrationOptions registration = registration_preset(options.preset);
    apply_config_object(config, registration);
    options.registration_options = registration;
  }
  if (options.loop_radius < 0 || options.maximum_loop_radius < 0 || options.minimum_loop_travel < 0 || options.map_voxel <= 0)
    throw Error("map: loop_radius, maximum_loop_radius and minimum_loop_travel must be >= 0 and map_voxel > 0");
  return options;
}

/// The 12 numbers of a pose given as a 4x4 or 3x4 array-like, or 12 numbers.
std::string pose_text(const py::handle& value, std::size_t entry) {
  const py::array_t<double, py::array::c_style | py::array::forcecast> array = py::array_t<double>::ensure(value);
  if (!array || !(array.size() == 12 || array.size() == 16))
    throw Error("scans[" + std::to_string(entry) + "]: odometry must be a 4x4 or 3x4 pose or 12 numbers, or None");
  std::ostringstream text;
  text.precision(17);
  for (py::ssize_t k = 0; k < 12; ++k) text << (k ? " " : "") << array.data()[k];
  return text.str();
}

/// A scan list from a SCANS.tsv path, or from a Python list of (session, scan, odometry) tuples or
/// {"session", "scan", "odometry"} dicts (odometry: a 4x4/3x4 pose, 12 numbers, or None; scan paths
/// relative to the working folder). A list is checked by the same reader as a file (written to a
/// temporary TSV); its errors name the entry as scans[i].
ScanList scan_list_from(const py::handle& scans) {
  if (py::isinstance<py::str>(scans) || py::hasattr(scans, "__fspath__")) {
    const std::string path = path_from_object(scans);
    require_existing_file(path);
    return read_scan_list(path);
  }
  std::ostringstream text;
  text << "session\tscan\todometry\n";
  std::size_t entry = 0;
  for (const py::handle item : scans) {
    py::object session, scan, odometry = py::none();
    if (py::isinstance<py::dict>(item)) {
      const py::dict row = py::reinterpret_borrow<py::dict>(item);
      if (!row.contains("session") || !row.contains("scan"))
        throw Error("scans[" + std::to_string(entry) + "]: a dict needs the keys 'session' and 'scan'");
      session = row["session"];
      scan = row["scan"];
      if (row.contains("odometry")) odometry = row["odometry"];
    } else {
      const py::sequence row = py::reinterpret_borrow<py::sequence>(item);
      if (py::len(row) < 2 || py::len(row) > 3)
        throw Error("scans[" + std::to_string(entry) + "]: expected (session, scan, odometry) or (session, scan)");
      session = row[0];
      scan = row[1];
      if (py::len(row) == 3) odometry = row[2];
    }
    const std::string session_name = py::str(session).cast<std::string>();
    const std::string path = std::filesystem::absolute(path_from_object(scan)).string();
    if (session_name.find_first_of("\t\n") != std::string::npos || path.find_first_of("\t\n") != std::string::npos)
      throw Error("scans[" + std::to_string(entry) + "]: a session name or path holds a tab or a line break");
    text << session_name << '\t' << path << '\t' << (odometry.is_none() ? std::string("-") : pose_text(odometry, entry)) << '\n';
    ++entry;
  }
  if (entry == 0) throw Error("map: the scan list is empty");
  std::string pattern = (std::filesystem::temp_directory_path() / "quadrix_map_list_XXXXXX").string();
  if (::mkdtemp(pattern.data()) == nullptr) throw Error("map: cannot create a temporary folder for the scan list in " + pattern);
  const std::filesystem::path folder = pattern;
  const std::string file = (folder / "scans.tsv").string();
  { std::ofstream(file) << text.str(); }
  try {
    ScanList list = read_scan_list(file);
    std::filesystem::remove_all(folder);
    list.source = "scans";
    return list;
  } catch (const Error& error) {
    std::filesystem::remove_all(folder);
    // "FILE: row N (...)" -> "scans[N-2] (...)": the header is row 1.
    std::string message = error.what();
    const std::string prefix = file + ": row ";
    if (message.rfind(prefix, 0) == 0) {
      const std::string rest = message.substr(prefix.size());
      std::size_t digits = 0;
      while (digits < rest.size() && std::isdigit(static_cast<unsigned char>(rest[digits]))) ++digits;
      if (digits > 0 && std::stoul(rest.substr(0, digits)) >= 2)
        message = "scans[" + std::to_string(std::stoul(rest.substr(0, digits)) - 2) + "]" + rest.substr(digits);
    }
    std::size_t at;
    while ((at = message.find(file)) != std::string::npos) message.replace(at, file.size(), "scans");
    throw Error(message);
  }
}

/// What a worker needs of a scan: (source, session, scan, path, row).
py::tuple entry_tuple(const ScanList& list, std::size_t index) {
  const ScanEntry& entry = list.scans[index];
  return py::make_tuple(list.source, entry.session, entry.scan, entry.path, entry.row);
}

ScanList list_of_entries(const std::vector<py::tuple>& entries) {
  ScanList list;
  for (const py::tuple& entry : entries) {
    list.source = entry[0].cast<std::string>();
    ScanEntry scan;
    scan.session = entry[1].cast<std::string>();
    scan.scan = entry[2].cast<std::string>();
    scan.path = entry[3].cast<std::string>();
    scan.row = entry[4].cast<std::size_t>();
    list.scans.push_back(scan);
  }
  return list;
}

py::array_t<double> pose_stack(const std::vector<Eigen::Isometry3d>& poses) {
  py::array_t<double> array({static_cast<py::ssize_t>(poses.size()), py::ssize_t{4}, py::ssize_t{4}});
  auto view = array.mutable_unchecked<3>();
  for (std::size_t k = 0; k < poses.size(); ++k)
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) view(static_cast<py::ssize_t>(k), r, c) = poses[k].matrix()(r, c);
  return array;
}

py::dict edge_dict(const MapResult& result, const MapEdge& edge) {
  py::dict row;
  row["from"] = edge.from;
  row["to"] = edge.to;
  row["from_session"] = result.list.scans[edge.from].session;
  row["from_scan"] = result.list.scans[edge.from].scan;
  row["to_session"] = result.list.scans[edge.to].session;
  row["to_scan"] = result.list.scans[edge.to].scan;
  row["kind"] = edge.kind == MapEdgeKind::Loop ? "loop" : "odometry";
  row["status"] = edge.status;
  row["used"] = edge.used;
  row["across_sessions"] = edge.across_sessions;
  row["transform"] = matrix_array(edge.transform);
  py::array_t<double> information({py::ssize_t{6}, py::ssize_t{6}});
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) information.mutable_at(r, c) = edge.information(r, c);
  row["information"] = information;
  row["overlap"] = edge.overlap;
  row["chi2_before"] = edge.chi2_before;
  row["chi2_after"] = edge.chi2_after;
  row["dcs_scale"] = edge.dcs_scale;
  row["registration_ms"] = edge.registration_ms;
  row["note"] = edge.note;
  return row;
}

}  // namespace

void bind_map(py::module_& module) {
  py::class_<MapRun, std::shared_ptr<MapRun>>(module, "MapResult", R"doc(
The result of quadrix.map: each scan's pose in the map frame, the edges of the pose graph, the
graph's summary, the timings and, when truth was given, the evaluation.
)doc")
      .def_property_readonly("sessions", [](const MapRun& run) {
        std::vector<std::string> names;
        for (const ScanEntry& entry : run.result.list.scans) names.push_back(entry.session);
        return names;
      }, "Session of each scan (list order).")
      .def_property_readonly("scans", [](const MapRun& run) {
        std::vector<std::string> names;
        for (const ScanEntry& entry : run.result.list.scans) names.push_back(entry.scan);
        return names;
      }, "Each scan's cloud file as listed.")
      .def_property_readonly("poses", [](const MapRun& run) { return pose_stack(run.result.poses); },
                             "(N, 4, 4) optimised sensor poses: map frame, or the session's own frame when not joined.")
      .def_property_readonly("initial", [](const MapRun& run) { return pose_stack(run.result.initial); },
                             "(N, 4, 4) poses before optimisation (odometry; later sessions placed by their edges).")
      .def_property_readonly("odometry", [](const MapRun& run) { return pose_stack(run.result.odometry); },
                             "(N, 4, 4) poses in each session's odometry frame (given or registered scan to scan).")
      .def_property_readonly("in_map_frame", [](const MapRun& run) { return run.result.in_map_frame; },
                             "Whether each scan's session joined the first one.")
      .def_property_readonly("edges", [](const MapRun& run) {
        py::list edges;
        for (const MapEdge& edge : run.result.edges) edges.append(edge_dict(run.result, edge));
        return edges;
      }, "One dict per edge: from, to (scan indices), sessions and scans, kind, status, used, transform (4x4: from points into the to frame), information (6x6), overlap, chi2_before, chi2_after, dcs_scale, registration_ms, note.")
      .def_property_readonly("graph", [](const MapRun& run) {
        py::dict graph;
        graph["initial_cost"] = run.result.graph.initial_cost;
        graph["final_cost"] = run.result.graph.final_cost;
        graph["iterations"] = run.result.graph.iterations;
        graph["converged"] = run.result.graph.converged;
        return graph;
      }, "The pose graph's cost before and after, iterations, convergence.")
      .def_property_readonly("information_groups", [](const MapRun& run) {
        py::list groups;
        for (const InformationGroup& group : run.result.information_groups) {
          py::dict entry;
          entry["name"] = group.name;
          entry["edges"] = group.edges;
          entry["rotation_factor"] = group.rotation_factor;
          entry["translation_factor"] = group.translation_factor;
          entry["pooled"] = group.pooled;
          entry["measured"] = group.measured;
          groups.append(entry);
        }
        return groups;
      }, "The information calibration per group of used edges (name, edges, rotation_factor, translation_factor, pooled, measured), as report.json's information_groups.")
      .def_property_readonly("outlier_edges", [](const MapRun& run) { return run.result.outlier_edges; },
                             "Used loop edges the outlier test took out of the graph (their notes in edges say why).")
      .def_property_readonly("timings_ms", [](const MapRun& run) { return run.result.timings_ms; }, "Time of each stage, ms.")
      .def_property_readonly("presets", [](const MapRun& run) { return run.result.presets; }, "The preset each scan was modelled with.")
      .def_property_readonly("candidates_within", [](const MapRun& run) { return run.result.candidates_within; },
                             "Loop candidate pairs within sessions.")
      .def_property_readonly("candidates_across", [](const MapRun& run) { return run.result.candidates_across; },
                             "Candidate pairs across sessions.")
      .def_property_readonly("evaluation", [](const MapRun& run) -> py::object {
        if (!run.evaluation) return py::none();
        return json_loads(run.evaluation_json);
      }, "With gt=: ATE, RPE, loop-edge precision and recall (as report.json's evaluation), else None.")
      .def_property_readonly("out", [](const MapRun& run) -> py::object {
        if (run.out.empty()) return py::none();
        return py::str(run.out);
      }, "The folder written, or None.")
      .def("__repr__", [](const MapRun& run) {
        std::size_t loops = 0, used = 0;
        for (const MapEdge& edge : run.result.edges)
          if (edge.kind == MapEdgeKind::Loop) loops += 1, used += edge.used;
        return "<quadrix.MapResult " + std::to_string(run.result.list.scans.size()) + " scans, " + std::to_string(loops) +
               " loop edges (" + std::to_string(used) + " used)>";
      });

  // A worker's part, one scan or one pair, as bytes (what the tasks below run).
  module.def(
      "_map_model_scan",
      [](const py::tuple& entry, const py::dict& keywords) {
        const MapOptions options = map_options_from(keywords);
        const ScanList list = list_of_entries({entry});
        std::string bytes;
        {
          py::gil_scoped_release release;
          bytes = mapped_scan_to_bytes(model_map_scan(list, 0, options));
        }
        return py::bytes(bytes);
      },
      py::arg("entry"), py::arg("options"));
  module.def(
      "_map_register_pair",
      [](const py::tuple& from_entry, const py::tuple& to_entry, int kind, const py::object& guess, const py::bytes& from_model,
         const py::bytes& to_model, const py::dict& keywords) {
        const MapOptions options = map_options_from(keywords);
        const ScanList list = list_of_entries({from_entry, to_entry});
        MapPairRequest pair;
        pair.from = 0;
        pair.to = 1;
        pair.kind = kind == 1 ? MapEdgeKind::Loop : MapEdgeKind::Odometry;
        if (!guess.is_none()) {
          const std::vector<double> numbers = guess.cast<std::vector<double>>();
          if (numbers.size() != 16) throw Error("map: a local guess is 16 numbers");
          Eigen::Matrix4d matrix;
          for (int k = 0; k < 16; ++k) matrix(k / 4, k % 4) = numbers[static_cast<std::size_t>(k)];
          pair.local_guess = Eigen::Isometry3d(matrix);
        }
        const std::string from_bytes = from_model, to_bytes = to_model;
        std::string bytes;
        {
          py::gil_scoped_release release;
          bytes = map_edge_to_bytes(register_map_pair(list, pair, mapped_scan_from_bytes(from_bytes, "model of " + list.scans[0].scan),
                                                      mapped_scan_from_bytes(to_bytes, "model of " + list.scans[1].scan), options));
        }
        return py::bytes(bytes);
      },
      py::arg("from_entry"), py::arg("to_entry"), py::arg("kind"), py::arg("guess"), py::arg("from_model"), py::arg("to_model"),
      py::arg("options"));

  // Dask pickles a task's function; a pybind11 function is not picklable, a Python function of this
  // module is (by reference: workers import quadrix and look it up).
  py::exec(R"(
def _map_model_task(entry, options):
    return _map_model_scan(entry, options)

def _map_register_task(from_entry, to_entry, kind, guess, from_model, to_model, options):
    return _map_register_pair(from_entry, to_entry, kind, guess, from_model, to_model, options)
)", module.attr("__dict__"));

  module.def(
      "map",
      [module](const py::object& scans, const py::object& out, const py::object& client, const py::object& gt,
               const py::object& progress, const py::kwargs& keywords) {
        const py::dict options_dict = keywords;
        const MapOptions options = map_options_from(options_dict);
        const ScanList list = scan_list_from(scans);
        const std::string truth_path = gt.is_none() ? std::string() : path_from_object(gt);
        std::vector<PoseRow> truth;
        if (!truth_path.empty()) {
          require_existing_file(truth_path);
          truth = read_pose_table(truth_path);
        }
        // The folder is checked before the work and replaced whole at the end, as `quadrix map --out`
        // does: a failure midway leaves the earlier folder as it was.
        std::optional<FolderReplacement> out_folder;
        const std::string out_path = out.is_none() ? std::string() : path_from_object(out);
        if (!out_path.empty()) {
          std::vector<std::string> inputs = {truth_path};
          for (const ScanEntry& scan : list.scans) inputs.push_back(scan.path);
          out_folder.emplace("out", out_path, map_folder_names(), inputs);
        }
        auto run = std::make_shared<MapRun>();
        // With a client: the executor's futures (one model per scan) live here, released with the GIL held.
        std::vector<py::object> model_futures(list.scans.size());
        const py::object model_task = module.attr("_map_model_task");
        const py::object register_task = module.attr("_map_register_task");
        MapExecutor executor;
        if (!client.is_none()) {
          executor.model = [&](const std::vector<std::size_t>& indices) {
            py::gil_scoped_acquire acquire;
            py::list futures;
            for (std::size_t index : indices) {
              model_futures[index] = client.attr("submit")(model_task, entry_tuple(list, index), options_dict, py::arg("pure") = false);
              futures.append(model_futures[index]);
            }
            const py::list parts = client.attr("gather")(futures);
            std::vector<MappedScan> models;
            // Each model's bytes are let go once parsed, so the driver does not hold every model twice.
            for (std::size_t k = 0; k < indices.size(); ++k) {
              models.push_back(mapped_scan_from_bytes(parts[k].cast<std::string>(), "model of " + list.scans[indices[k]].scan));
              parts[k] = py::none();
            }
            return models;
          };
          executor.register_pairs = [&](const std::vector<MapPairRequest>& pairs) {
            py::gil_scoped_acquire acquire;
            py::list futures;
            for (const MapPairRequest& pair : pairs) {
              py::object guess = py::none();
              if (pair.local_guess) {
                py::list numbers;
                for (int k = 0; k < 16; ++k) numbers.append(pair.local_guess->matrix()(k / 4, k % 4));
                guess = numbers;
              }
              futures.append(client.attr("submit")(register_task, entry_tuple(list, pair.from), entry_tuple(list, pair.to),
                                                   pair.kind == MapEdgeKind::Loop ? 1 : 0, guess, model_futures[pair.from],
                                                   model_futures[pair.to], options_dict, py::arg("pure") = false));
            }
            const py::list parts = client.attr("gather")(futures);
            std::vector<MapEdge> edges;
            for (std::size_t k = 0; k < pairs.size(); ++k) {
              MapEdge edge = map_edge_from_bytes(parts[k].cast<std::string>(), "edge " + list.scans[pairs[k].from].scan);
              edge.from = pairs[k].from;
              edge.to = pairs[k].to;
              edges.push_back(std::move(edge));
            }
            return edges;
          };
        }
        // Progress from whichever thread reports it (TBB's in this process), with the GIL taken for the call.
        MapProgress report;
        if (!progress.is_none())
          report = [&progress](const std::string& stage, std::size_t done, std::size_t total) {
            py::gil_scoped_acquire acquire;
            progress(stage, done, total);
          };
        {
          py::gil_scoped_release release;
          run->result = map_scans(list, options, report, executor);
          if (!truth.empty()) {
            run->evaluation = evaluate_map(run->result, truth, 30.0, options.minimum_loop_travel);
            run->evaluation_json = map_evaluation_json(*run->evaluation);
          }
          if (out_folder) {
            write_map(out_folder->staging_folder(), run->result, options, run->evaluation_json);
            write_map_page(out_folder->staging_folder());
            out_folder->commit();
            run->out = out_path;
          }
        }
        return run;
      },
      py::arg("scans"), py::arg("out") = py::none(), py::kw_only(), py::arg("client") = py::none(), py::arg("gt") = py::none(),
      py::arg("progress") = py::none(),
      R"doc(
One map from many scans (quadrix map): every scan modelled once, odometry given or registered scan
to scan, loop candidates by radius search within sessions and by a place descriptor across them,
loop edges from the registration, a pose graph. Returns a quadrix.MapResult.

scans: a SCANS.tsv path (header; session, scan, odometry columns), or a list of (session, scan,
odometry) tuples or dicts with those keys (odometry: a 4x4 or 3x4 pose, 12 numbers, or None).
out: a folder to write as the command line does (poses.tsv, edges.csv, report.json, map.ply,
map_model.qsm, models/, map.html), replaced only once everything is written.
client: a dask.distributed Client: each scan's modelling and each pair's registration run as tasks
on its workers, which read the clouds from the list's paths (a filesystem they all share); models
travel between tasks as bytes; the pose graph is solved here. The same map as without a client.
gt: true poses (poses.tsv format): the evaluation (ATE, RPE, loop-edge precision and recall).
progress: called as progress(stage, done, total) as scans are modelled and pairs registered
(total 0 when not known ahead), from the thread that reports it.
Keyword options: the members of MapOptions (preset, loop_radius, loop_radius_growth,
maximum_loop_radius, minimum_loop_travel, candidates_per_scan, minimum_candidate_spacing,
place_candidates_per_scan, place_query_stride, joint_rounds, joint_radius, joint_gate_translation,
joint_gate_rotation_degrees, place_consensus_rotation_degrees, place_consensus_translation, use_ambiguous_joint_edges, ambiguous_gate_translation,
ambiguous_gate_rotation_degrees, register_consecutive, use_ambiguous_edges,
use_ambiguous_edges_across_sessions, odometry_gate_sigmas, loop_information_from_registration,
loop_information_scale,
loop_translation_sigma, loop_rotation_sigma_degrees, odometry_translation_drift,
odometry_rotation_drift_degrees, odometry_translation_floor, odometry_rotation_floor_degrees,
place_vote_minimum, place_vote_rotation_degrees, place_vote_translation, place_vote_ratio, information_rounds, information_minimum_edges, information_tolerance, outlier_threshold, maximum_outlier_removals, map_voxel, cloud_cache) and config (a dict or YAML file of registration options for a named preset).
)doc");
}

}  // namespace quadrix::python
