// quadrix.register and quadrix.RegistrationResult: `quadrix register` as a function. The result's
// content is report.json's: it is built by the same registration_report_json (quadrix_reports), so
// Python and the command line cannot drift apart.
#include "bindings.h"

#include "estimation/registration_config.h"
#include "experiments/reports/registration_report.h"
#include "geometry/error.h"
#include "geometry/io.h"

#include <pybind11/stl.h>

#include <chrono>

namespace quadrix::python {

namespace {

/// What quadrix.register returns.
struct Registration {
  RegistrationResult result;  ///< register_clouds' result (between the sensor-centred clouds)
  Eigen::Vector3d source_origin = Eigen::Vector3d::Zero();  ///< where the source's sensor stood in the source's frame
  Eigen::Vector3d target_origin = Eigen::Vector3d::Zero();  ///< where the target's sensor stood in the target's frame
  std::string json;           ///< registration_report_json: report.json's text
  py::object report;          ///< json.loads(json)
};

// report[key], or None when the report has no such key.
py::object report_entry(const Registration& registration, const char* key) {
  return registration.report.attr("get")(key);
}

// A Python model of one side of the result.
std::shared_ptr<Model> side_model(const SceneModel& scene) {
  auto model = std::make_shared<Model>();
  model->model = scene;
  model->status = derived_status(scene);
  return model;
}

}  // namespace

void bind_register(py::module_& module) {
  py::class_<Registration, std::shared_ptr<Registration>>(module, "RegistrationResult", R"doc(
The outcome of ``register``: the content of ``quadrix register --out``'s report.json (the same
function builds both), plus the two scene models.

``transform`` maps source points into the target frame: ``p_target = T[:3, :3] @ p + T[:3, 3]``.
``status`` is ok, ambiguous, degenerate or failed (see the README's table); only use the transform
as an answer when it is ok.
)doc")
      .def_property_readonly(
          "transform",
          [](const Registration& r) {
            return matrix_array(between_cloud_frames(r.result.transform, r.source_origin, r.target_origin));
          },
          "4x4 float64: T* mapping source points into the target frame, the frames the clouds were given in "
          "(identity unless ok/ambiguous).")
      .def_property_readonly("status", [](const Registration& r) { return registration_status_name(r.result.status); },
                             "ok, ambiguous, degenerate or failed.")
      .def_property_readonly("ok", [](const Registration& r) { return r.result.status == RegistrationStatus::Ok; },
                             "True when the status is ok.")
      .def_property_readonly("message", [](const Registration& r) { return r.result.message; },
                             "Why, for any status but ok; a short summary otherwise.")
      .def_property_readonly("timings_ms", [](const Registration& r) { return report_entry(r, "timings_ms"); },
                             "report.json's timings_ms: total, load, every stage, and registration (register_clouds' own total), ms.")
      .def_property_readonly("counts", [](const Registration& r) { return report_entry(r, "counts"); },
                             "report.json's counts: points, elements, quadrics, augmented points, correspondences, clique sizes.")
      .def_property_readonly("candidates", [](const Registration& r) { return report_entry(r, "candidates"); },
                             "report.json's candidates: one dict per clique level (clique size, refinement, score, transform, selected...).")
      .def_property_readonly("overlap", [](const Registration& r) { return report_entry(r, "overlap"); },
                             "report.json's overlap {distance_m, transformed, identity, sampled_points}.")
      .def_property_readonly("dense_search", [](const Registration& r) { return report_entry(r, "dense_search"); },
                             "report.json's dense_search, or None when the dense search did not run.")
      .def_property_readonly("ground_correlation", [](const Registration& r) { return report_entry(r, "ground_correlation"); },
                             "report.json's ground_correlation (poses with share, yaw_deg, transform, best first), or None when it did not run.")
      .def_property_readonly("half_turn", [](const Registration& r) { return report_entry(r, "half_turn"); },
                             "report.json's half_turn, or None when the half-turn check did not run.")
      .def_property_readonly("free_space", [](const Registration& r) { return report_entry(r, "free_space"); },
                             "report.json's free_space, or None when the free-space check did not run.")
      .def_property_readonly("ground_truth", [](const Registration& r) { return report_entry(r, "ground_truth"); },
                             "report.json's ground_truth {transform, rte_m, rre_deg, success} when ground_truth= was given, else None.")
      .def_property_readonly("best_candidate", [](const Registration& r) { return r.result.best_candidate; },
                             "Index of the chosen candidate in ``candidates`` (len(candidates) when the answer came from the initial guess).")
      .def_property_readonly("fitness", [](const Registration& r) { return r.result.fitness; },
                             "Share of the source points (within range, isolated points left out) with a target point within "
                             "0.3 m (config quality.correspondence_distance) after ``transform``, as Open3D's fitness; 0 unless ok/ambiguous.")
      .def_property_readonly("inlier_rmse", [](const Registration& r) { return r.result.inlier_rmse; },
                             "Root mean square of those inliers' point-to-point distances, m (Open3D's inlier_rmse).")
      .def_property_readonly(
          "correspondences",
          [](const Registration& r) {
            py::array_t<std::int64_t> pairs(std::vector<py::ssize_t>{static_cast<py::ssize_t>(r.result.correspondences.size()), 2});
            auto view = pairs.mutable_unchecked<2>();
            for (std::size_t k = 0; k < r.result.correspondences.size(); ++k) {
              view(static_cast<py::ssize_t>(k), 0) = static_cast<std::int64_t>(r.result.correspondences[k].first);
              view(static_cast<py::ssize_t>(k), 1) = static_cast<std::int64_t>(r.result.correspondences[k].second);
            }
            return pairs;
          },
          "(N, 2) int64: the inliers as (source index, target index), rows of the clouds given, each source point once.")
      .def_property_readonly(
          "information",
          [](const Registration& r) {
            // About the target frame given (its origin), as ``transform`` is between the frames given.
            const Eigen::Matrix<double, 6, 6> information =
                information_about_shifted_origin(r.result.information, r.target_origin);
            py::array_t<double> matrix(std::vector<py::ssize_t>{6, 6});
            auto view = matrix.mutable_unchecked<2>();
            for (int i = 0; i < 6; ++i)
              for (int j = 0; j < 6; ++j) view(i, j) = information(i, j);
            return matrix;
          },
          "(6, 6) float64: H = J^T J of the point-to-plane cost over ``correspondences`` at ``transform``, as "
          "small_gicp returns H: order rotation then translation, perturbation on the left in the TARGET frame "
          "(T = Exp(delta) @ transform, rotation about the target frame's origin). A pose graph's edge information.")
      .def_property_readonly("from_initial_guess", [](const Registration& r) { return r.result.from_initial_guess; },
                             "True when the answer is ICP from ``initial_guess`` (always with local_only=True).")
      .def_readonly("report", &Registration::report, "The whole report.json content as a dict.")
      .def_property_readonly("source_model", [](const Registration& r) { return side_model(r.result.source_model); },
                             "The source's quadrix.Model (R_x) as registered.")
      .def_property_readonly("target_model", [](const Registration& r) { return side_model(r.result.target_model); },
                             "The target's quadrix.Model (R_y) as registered.")
      .def("to_json", [](const Registration& r) { return r.json; }, "report.json's text (pretty-printed JSON).")
      .def(
          "save",
          [](const Registration& r, const py::object& path) {
            const std::string file = path_from_object(path);
            require_writable_location(file);
            write_file_atomically(file, [&](std::ostream& out) { out << r.json; });
          },
          py::arg("path"), "Writes report.json's text to ``path`` atomically (what ``quadrix register --out`` writes).")
      .def("__repr__", [](const Registration& r) {
        return std::string("<quadrix.RegistrationResult ") + registration_status_name(r.result.status) + ": " +
               r.result.message + ">";
      });

  module.def(
      "register",
      [](const py::object& source_object, const py::object& target_object, const std::string& preset,
         const py::object& config, const py::object& refiner, const py::object& source_preset,
         const py::object& target_preset, const py::object& source_labels, const py::object& target_labels,
         const py::object& ground_truth, const py::object& source_origin, const py::object& target_origin,
         const py::object& initial_guess, bool local_only) {
        using Clock = std::chrono::steady_clock;
        auto registration = std::make_shared<Registration>();
        registration->source_origin = point_from_object(source_origin, "source_origin");
        registration->target_origin = point_from_object(target_origin, "target_origin");
        // As `quadrix register --source-origin`: clouds in a map's frame are registered centred on
        // their sensors; the ground truth is compared between the sensors' frames.
        const bool centred = !registration->source_origin.isZero(0.0) || !registration->target_origin.isZero(0.0);
        std::optional<Eigen::Isometry3d> truth;
        if (!ground_truth.is_none())
          truth = between_sensor_frames(pose_from_object(ground_truth, "ground_truth"), registration->source_origin,
                                        registration->target_origin);
        std::optional<Eigen::Isometry3d> guess;
        if (!initial_guess.is_none())
          guess = between_sensor_frames(pose_from_object(initial_guess, "initial_guess"), registration->source_origin,
                                        registration->target_origin);
        if (local_only && !guess) throw Error("local_only=True needs initial_guess (a 4x4 pose to start from)");
        const Clock::time_point start = Clock::now();
        std::shared_ptr<Cloud> source_holder, target_holder;
        RegistrationReportContext context;
        const PointCloud& source_given = cloud_from_object(source_object, "source", source_holder, &context.source_path);
        const PointCloud& target_given = cloud_from_object(target_object, "target", target_holder, &context.target_path);
        require_metres(source_holder->units, context.source_path.empty() ? "source" : context.source_path, "registration");
        require_metres(target_holder->units, context.target_path.empty() ? "target" : context.target_path, "registration");
        // A cloud given as a quadrix.Cloud is used in place: it is copied only to be moved.
        PointCloud source_centred, target_centred;
        if (centred) {
          source_centred = centred_on_sensor(source_given, registration->source_origin);
          target_centred = centred_on_sensor(target_given, registration->target_origin);
        }
        const PointCloud& source = centred ? source_centred : source_given;
        const PointCloud& target = centred ? target_centred : target_given;
        const std::vector<std::uint32_t> source_point_labels = labels_from_object(source_labels, source.size(), "source_labels");
        const std::vector<std::uint32_t> target_point_labels = labels_from_object(target_labels, target.size(), "target_labels");
        context.load_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();

        std::string notes;
        RegistrationOptions options = registration_options_from(
            source_preset.is_none() ? preset : source_preset.cast<std::string>(), source,
            target_preset.is_none() ? preset : target_preset.cast<std::string>(), target, config, refiner, &notes);
        options.initial_guess = guess;
        options.local_only = local_only;
        {
          py::gil_scoped_release release;
          registration->result = register_clouds(source, target, options, source_point_labels, target_point_labels);
          context.total_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
          context.source_preset = options.source_extraction.preset;
          context.target_preset = options.target_extraction.preset;
          context.preset_notes = notes;
          context.ground_truth = truth;
          context.overlap = registration->result.overlap;
          context.source_sensor_origin = registration->source_origin;
          context.target_sensor_origin = registration->target_origin;
          registration->json = registration_report_json(registration->result, context);
        }
        registration->report = json_loads(registration->json);
        return registration;
      },
      py::arg("source"), py::arg("target"), py::arg("preset") = "auto", py::arg("config") = py::none(),
      py::arg("refiner") = py::none(), py::kw_only(), py::arg("source_preset") = py::none(),
      py::arg("target_preset") = py::none(), py::arg("source_labels") = py::none(),
      py::arg("target_labels") = py::none(), py::arg("ground_truth") = py::none(), py::arg("source_origin") = py::none(),
      py::arg("target_origin") = py::none(), py::arg("initial_guess") = py::none(), py::arg("local_only") = false, R"doc(
Registers ``source`` onto ``target`` globally with quadrics, as ``quadrix register`` does, and returns
a quadrix.RegistrationResult (transform, status, message, timings_ms, counts, candidates, overlap:
report.json's content; and fitness, inlier_rmse, correspondences, information for a back end).

source, target: each a quadrix.Cloud, an (N, 3) array (any real dtype; float32 C-contiguous is
    copied once with memcpy) or a file path (str / os.PathLike, any format read_cloud reads).
preset: vlp64, vlp16, mid360, avia, monument or auto (default: chosen per cloud from its field of
    view, rings and size, as ``quadrix register --preset auto``; see ``presets()``).
config: overrides applied after the presets: a dict in the YAML schema (``config()`` returns one,
    ``config_keys()`` lists the keys) or the path of a YAML file (as ``--config``).
refiner: "ceres" or "nlopt" (as ``--refiner``); None keeps the preset's (ceres).
source_preset, target_preset: per-side presets for cross-sensor pairs (keyword-only).
source_labels, target_labels: optional SemanticKITTI labels, one per point (as ``--labels-source``).
ground_truth: optional 4x4 T_gt mapping source into target; the report then has ground_truth
    {rte_m, rre_deg, success} by the paper's rule (2 m, 5 deg), as ``--gt``.
source_origin, target_origin: where each side's sensor stood in its cloud's frame, (x, y, z) in
    metres (as ``--source-origin``; keyword-only); None: the origin. For clouds in a map's frame: they
    are registered centred on their sensors, ``transform`` is between the frames given, and the
    report's other transforms and the models are between the sensor-centred clouds.
initial_guess: optional 4x4 pose mapping source into target (odometry, a previous answer; keyword-only),
    in the frames given. Point-to-plane ICP from it is verified beside the global answer and the
    better verified one wins (``ok`` over ``ambiguous``, then, for answers that disagree, the larger
    overlap; the global answer when they agree; two ``ok`` answers that disagree leave the winner
    ``ambiguous``).
local_only: with ``initial_guess``: skip the global quadric matching; the answer is ICP from the
    guess, and the same checks decide ok or ambiguous (keyword-only).

The GIL is released while the pipeline runs, so threads can register pairs concurrently.
Raises FileNotFoundError for a missing file, ValueError naming the file for an unreadable one or a
bad config value, KeyError naming an unknown key of a config dict.

Example::

    source, target = quadrix.read_cloud("000000.bin"), quadrix.read_cloud("004438.ply")
    result = quadrix.register(source, target)
    if result.ok:
        aligned = source.points @ result.transform[:3, :3].T + result.transform[:3, 3]
)doc");
}

}  // namespace quadrix::python
