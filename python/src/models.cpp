// quadrix.Model, quadrix.model, quadrix.load_model and quadrix.fit: the scene representation of one
// cloud (paper §"Quadric Modeling", Struct. 1) and one quadric fitted to a segment (`quadrix fit`).
#include "bindings.h"
#include "experiments/reports/fit_report.h"

#include "estimation/registration.h"
#include "estimation/registration_config.h"
#include "fitting/quadric_fitter.h"
#include "fitting/scene_modelling.h"
#include "fitting/shape_parameters.h"
#include "geometry/error.h"
#include "geometry/quadric.h"

#include <pybind11/stl.h>

#include <cmath>
#include <fstream>
#include <limits>

namespace quadrix::python {

namespace {

// An (M, columns) float64 array filled row by row by `fill(row, out_row_pointer)`.
template <typename Fill>
py::array_t<double> record_rows(const SceneModel& model, std::size_t begin, std::size_t end, int columns, Fill fill) {
  py::array_t<double> array({static_cast<py::ssize_t>(end - begin), static_cast<py::ssize_t>(columns)});
  auto out = array.mutable_unchecked<2>();
  for (std::size_t i = begin; i < end; ++i) fill(model.records[i], &out(static_cast<py::ssize_t>(i - begin), 0));
  return array;
}


// The dict `quadrix fit` prints as JSON: the same fit_report_json, parsed.
py::object fit_dict(const QuadricFit& fit, const std::string& fitter_name, std::size_t point_count,
                    const Eigen::Matrix3Xd& points) {
  return json_loads(fit_report_json(fit, fitter_name, point_count, -1, points));
}

}  // namespace

std::string derived_status(const SceneModel& model) {
  return modelling_status_name(model.augmented_begin > 0 ? ModellingStatus::Ok : ModellingStatus::Empty);
}

void bind_models(py::module_& module) {
  py::class_<Model, std::shared_ptr<Model>>(module, "Model", R"doc(
A scene model (paper Struct. 1): M records, the first ``quadric_count`` fitted quadrics of the
scene's elements, the rest augmented points (type "point"). Per-record arrays have M rows.
Returned by ``model`` and ``load_model``; ``RegistrationResult.source_model`` / ``.target_model``.
)doc")
      .def_property_readonly("records", [](const Model& m) {
            return record_rows(m.model, 0, m.model.size(), 21, [](const QuadricRecord& r, double* out) {
              const auto values = r.to_array();
              std::copy(values.begin(), values.end(), out);
            });
          }, "(M, 21) float64: the records in Struct. 1 order [label, q(10), scale(3), quaternion w x y z(4), center(3)].")
      .def_property_readonly("labels", [](const Model& m) {
            py::array_t<std::uint32_t> labels(static_cast<py::ssize_t>(m.model.size()));
            for (std::size_t i = 0; i < m.model.size(); ++i) labels.mutable_at(i) = m.model.records[i].label;
            return labels;
          }, "(M,) uint32 semantic label of each record (an element class value).")
      .def_property_readonly("classes", [](const Model& m) {
            std::vector<std::string> names;
            for (const QuadricRecord& record : m.model.records)
              names.push_back(element_class_name(element_class_from_label(record.label)));
            return names;
          }, "Element class name of each record: ground, plane, line, object, vehicle, trunk, vegetation, cylinder, sphere, cone.")
      .def_property_readonly("types", [](const Model& m) {
            std::vector<std::string> names;
            for (const QuadricType type : m.model.types) names.push_back(quadric_type_name(type));
            return names;
          }, "Fitted quadric type name of each record (plane, line, ellipsoid, ..., point for augmented points).")
      .def_property_readonly("q", [](const Model& m) {
            return record_rows(m.model, 0, m.model.size(), 10, [](const QuadricRecord& r, double* out) {
              for (int i = 0; i < 10; ++i) out[i] = r.q(i);
            });
          }, "(M, 10) float64: the quadric parameters A..J (paper Eq. 2).")
      .def_property_readonly("scale", [](const Model& m) {
            return record_rows(m.model, 0, m.model.size(), 3, [](const QuadricRecord& r, double* out) {
              for (int i = 0; i < 3; ++i) out[i] = r.full_scale(i);
            });
          }, "(M, 3) float64: full scale s_f, metres.")
      .def_property_readonly("rotation", [](const Model& m) {
            return record_rows(m.model, 0, m.model.size(), 4, [](const QuadricRecord& r, double* out) {
              out[0] = r.full_rotation.w(); out[1] = r.full_rotation.x(); out[2] = r.full_rotation.y(); out[3] = r.full_rotation.z();
            });
          }, "(M, 4) float64: full rotation eta_f as a unit quaternion (w, x, y, z).")
      .def_property_readonly("rotation_matrix", [](const Model& m) {
            py::array_t<double> array({static_cast<py::ssize_t>(m.model.size()), py::ssize_t{3}, py::ssize_t{3}});
            auto out = array.mutable_unchecked<3>();
            for (std::size_t i = 0; i < m.model.size(); ++i) {
              const Eigen::Matrix3d rotation = m.model.records[i].full_rotation.normalized().toRotationMatrix();
              for (int row = 0; row < 3; ++row)
                for (int column = 0; column < 3; ++column) out(static_cast<py::ssize_t>(i), row, column) = rotation(row, column);
            }
            return array;
          }, "(M, 3, 3) float64: the full rotation R_f as matrices (columns: the record's axes), as model.json's rotation_matrix.")
      .def_property_readonly("center", [](const Model& m) {
            return record_rows(m.model, 0, m.model.size(), 3, [](const QuadricRecord& r, double* out) {
              for (int i = 0; i < 3; ++i) out[i] = r.full_center(i);
            });
          }, "(M, 3) float64: full center t_f, metres (model.json's center).")
      .def_property_readonly("centre", [](const Model& m) {
            return record_rows(m.model, 0, m.model.size(), 3, [](const QuadricRecord& r, double* out) {
              for (int i = 0; i < 3; ++i) out[i] = r.full_center(i);
            });
          }, "Deprecated alias of ``center`` (the spelling of every other name and key), kept for existing code.")
      .def_property_readonly("shapes", [](const Model& m) {
            return json_loads(scene_model_shapes_json(m.model));
          }, "List of M dicts: the plain shape parameters of each record, as model.json's \"shape\" (plane normal, "
             "offset; cylinder point, axis, radius; cone apex, axis, half_angle_deg; sphere center, radius; ...).")
      .def_property_readonly("point_counts", [](const Model& m) {
            return py::array_t<std::uint32_t>(static_cast<py::ssize_t>(m.model.element_point_counts.size()),
                                              m.model.element_point_counts.data());
          }, "(M,) uint32: points of the element behind each record.")
      .def_property_readonly("quadric_count", [](const Model& m) { return m.model.augmented_begin; },
                             "Number of fitted quadrics (records before the augmented points).")
      .def_property_readonly("augmented_points", [](const Model& m) {
            return record_rows(m.model, m.model.augmented_begin, m.model.size(), 3, [](const QuadricRecord& r, double* out) {
              for (int i = 0; i < 3; ++i) out[i] = r.full_center(i);
            });
          }, "(A, 3) float64: positions of the augmented points (records from quadric_count on).")
      .def_property_readonly("augmented_descriptors", [](const Model& m) {
            py::array_t<float> array({static_cast<py::ssize_t>(m.model.augmented_descriptors.size()),
                                      static_cast<py::ssize_t>(kFpfhSize)});
            auto out = array.mutable_unchecked<2>();
            for (std::size_t i = 0; i < m.model.augmented_descriptors.size(); ++i)
              for (int k = 0; k < kFpfhSize; ++k) out(static_cast<py::ssize_t>(i), k) = m.model.augmented_descriptors[i][k];
            return array;
          }, "(A, 33) float32: FPFH descriptor of each augmented point ((0, 33) when the model has none).")
      .def_property_readonly("ground", [](const Model& m) {
            py::dict ground;
            ground["found"] = m.model.has_ground;
            ground["normal"] = std::vector<double>{m.model.ground_normal(0), m.model.ground_normal(1), m.model.ground_normal(2)};
            ground["offset"] = m.model.ground_offset;
            return ground;
          }, "The ground plane {found, normal (up), offset}: normal . x + offset = 0.")
      .def_property_readonly("source_points", [](const Model& m) { return m.model.source_point_count; },
                             "Points of the cloud that was modelled.")
      .def_property_readonly("timings_ms", [](const Model& m) { return m.model.timings_ms; },
                             "Wall time of each modelling stage, ms.")
      .def_readonly("status", &Model::status,
                    "ok (at least one quadric) or empty. A loaded model gets it from its records.")
      .def_readonly("message", &Model::message, "Why, when the status is not ok ('' for a loaded model).")
      .def("to_json", [](const Model& m) { return scene_model_to_json(m.model); },
           "The model as JSON text (the format of ``quadrix model --out``; ``load_model`` reads it back exactly).")
      .def(
          "save",
          [](const Model& m, const py::object& path) {
            const std::string file = path_from_object(path);
            require_writable_location(file);
            py::gil_scoped_release release;
            if (file.size() >= 5 && file.compare(file.size() - 5, 5, ".json") == 0)
              write_scene_model_json(file, m.model);
            else
              write_scene_model_binary(file, m.model);
          },
          py::arg("path"), R"doc(
Writes the model atomically: JSON when ``path`` ends in .json (as ``quadrix model --out``), else the
checksummed binary format (as ``quadrix model --binary``, e.g. model.qsm). ``load_model`` reads both.
)doc")
      .def("__len__", [](const Model& m) { return m.model.size(); }, "Number of records.")
      .def("__repr__", [](const Model& m) {
        return "<quadrix.Model " + m.status + ": " + std::to_string(m.model.augmented_begin) + " quadrics, " +
               std::to_string(m.model.augmented_count()) + " augmented points from " +
               std::to_string(m.model.source_point_count) + " points>";
      });

  module.def(
      "load_model",
      [](const py::object& path) {
        const std::string file = path_from_object(path);
        require_existing_file(file);
        auto result = std::make_shared<Model>();
        {
          py::gil_scoped_release release;
          std::ifstream in(file, std::ios::binary);
          char magic[8] = {};
          in.read(magic, sizeof magic);
          const bool binary = in.gcount() == 8 && std::string(magic, 8) == "QDXSCENE";
          in.close();
          result->model = binary ? read_scene_model_binary(file) : read_scene_model_json(file);
        }
        result->status = derived_status(result->model);
        return result;
      },
      py::arg("path"), R"doc(
Reads a model written by ``Model.save`` or ``quadrix model`` (JSON or binary, recognised by content).

Raises FileNotFoundError when the file does not exist and ValueError naming the file and the field
when it is not a valid model (bad magic, truncation, checksum mismatch, invalid record).
)doc");

  module.def(
      "model",
      [](const py::object& cloud, const std::string& preset, const py::object& config, const py::object& labels,
         const py::object& fitter, const py::object& sensor_origin) {
        std::shared_ptr<Cloud> holder;
        // A file is read relative to a local origin (georeferenced coordinates stay exact in float32).
        const PointCloud& given = cloud_from_object(cloud, "cloud", holder, nullptr, LocalOrigin::Auto);
        // As `quadrix model --sensor-origin`: modelled centred on the sensor, the model moved back.
        // As `quadrix model`: coordinates in another unit (a LAS file in feet) are modelled in metres,
        // the presets' unit, and the model is returned in the cloud's frame and unit. One copy at most.
        const ModellingFrame frame{point_from_object(sensor_origin, "sensor_origin"), holder->units.metres_per_unit};
        const PointCloud moved = frame.moves() ? in_modelling_frame(given, frame, "sensor_origin moved the cloud") : PointCloud();
        const PointCloud& points = frame.moves() ? moved : given;
        RegistrationOptions options = registration_options_from(preset, points, preset, points, config, py::none(), nullptr);
        ExtractionOptions extraction = options.source_extraction;
        if (!holder->units.las) extraction.ground_class = -1;  // only a LAS file's labels are ASPRS classes
        const std::vector<std::uint32_t> point_labels = labels_from_object(labels, points.size(), "labels");
        if (!point_labels.empty()) extraction.semantic_mode = SemanticMode::Labels;
        if (!fitter.is_none()) options.modelling.fitter = fitter.cast<std::string>();
        make_quadric_fitter(options.modelling.fitter);  // an Error listing the fitters for an unknown name
        // K_e bounds registration's cost; a static scan modelled for itself keeps every primitive it finds.
        if (extraction.static_scan) options.modelling.quadrics_per_class = std::numeric_limits<int>::max();
        auto result = std::make_shared<Model>();
        {
          py::gil_scoped_release release;
          ModellingResult modelling = model_scene(points, extraction, options.modelling, point_labels);
          result->model = in_file_frame(std::move(modelling.model), frame, given.local_origin);
          result->status = modelling_status_name(modelling.status);
          result->message = std::move(modelling.message);
        }
        return result;
      },
      py::arg("cloud"), py::arg("preset") = "auto", py::arg("config") = py::none(), py::arg("labels") = py::none(),
      py::arg("fitter") = py::none(), py::arg("sensor_origin") = py::none(), R"doc(
Models a cloud with quadrics (paper §"Quadric-based Scene Representation"): extraction of ground,
walls, poles and objects, one quadric per element, augmented points in sparse scenes. Returns a
quadrix.Model.

cloud: a Cloud, an (N, 3) array or a file path.
preset: vlp64, vlp16, mid360, avia, monument, or auto (measured on the cloud, as ``register`` does
for each side, so this is the model ``register`` builds for that cloud before augmenting the other side).
config: a dict in the YAML schema (see ``config``) or a YAML file path, applied after the preset.
labels: optional N SemanticKITTI labels (switches the extraction to the labels semantic mode, as
``quadrix model --labels``). fitter: a fitter name overriding the preset's (statistical, taubin,
constrained, cgal, learned, auto). sensor_origin: where the sensor stood in the cloud's frame, (x, y,
z) in metres, for a cloud in a map's frame: it is modelled centred on the sensor (``auto`` measures
it there) and the model is returned in the cloud's frame, as ``quadrix model --sensor-origin``.

A LAS file whose CRS declares another length unit (feet in most US state-plane surveys; a path, or a
Cloud from ``read_cloud``) is modelled in metres and the model returned in the file's unit and
coordinates, as ``quadrix model`` does; a LAS file's classification is its ground (``airborne``).

Releases the GIL while modelling. Raises ValueError for an unknown preset or fitter, KeyError for an
unknown config key.
)doc");

  module.def(
      "fit",
      [](const py::object& points, const std::string& type, const std::string& fitter_name, const std::string& residuals) {
        std::shared_ptr<Cloud> holder;
        const PointCloud& cloud = cloud_from_object(points, "points", holder);
        const FitTypeHint hint = fit_type_hint_from_name(type);
        FitEvaluationOptions evaluation;
        evaluation.residuals = residual_evaluation_from_name(residuals, "residuals");
        const auto fitter = make_quadric_fitter(fitter_name, evaluation);
        QuadricFit fit;
        const Eigen::Matrix3Xd positions = cloud.positions.cast<double>();
        {
          py::gil_scoped_release release;
          fit = fitter->fit(positions, Eigen::Matrix3Xd(), hint);
        }
        return fit_dict(fit, fitter->name(), cloud.size(), positions);
      },
      py::arg("points"), py::arg("type") = "auto", py::arg("fitter") = "statistical", py::arg("residuals") = "exact",
      R"doc(
Fits one quadric to all points (one element) and returns what ``quadrix fit`` prints, as a dict with
the same keys: fitter, status, message (only when not ok), type, points, shape (the plain parameters:
plane normal, offset; sphere center, radius; cylinder point, axis, radius, extent, height; cone
apex, axis, half_angle_deg, extent, height; line point, direction; ellipsoid center, radii, axes),
q (10, normalised), scale, rotation (unit quaternion w, x, y, z, as ``Model.rotation``),
rotation_matrix (9, row-major), center, degeneracy {scale, rotation, translation}, statistical_scale,
statistical_center, residual_rms, residual_max, f_p2s, time_ms, residual_evaluation,
residual_points, evaluation_ms. Numbers the CLI prints as null (NaN, e.g. with residuals="skip") are None.

points: a Cloud, an (N, 3) array or a file path.
type: auto, point, line, plane, sphere, ellipsoid, cylinder, elliptic_cylinder, cone, elliptic_cone.
fitter: statistical, taubin, constrained, cgal, learned or auto.
residuals: exact (every point), subsample (at most 2000 evenly strided points) or skip.

Degenerate input is a status, not an exception; unknown names raise ValueError listing the valid ones.
)doc");
}

}  // namespace quadrix::python
