// quadrix.synth, quadrix.scenes, quadrix.sensors: `quadrix synth` as a function, for notebooks and
// tests that need clouds with exact ground truth.
#include "bindings.h"

#include "experiments/synthetic/synthetic_output.h"
#include "geometry/error.h"
#include "geometry/output_paths.h"

#include <pybind11/stl.h>

#include <optional>

namespace quadrix::python {

void bind_synth(py::module_& module) {
  module.def(
      "synth",
      [](const std::string& scene_name, std::uint64_t seed, const std::string& sensor_name, const py::object& poses,
         std::optional<double> noise, std::optional<double> dropout, bool primitives, const py::object& out,
         const std::string& format, bool binary, const std::string& foliage) {
        SensorModel sensor = sensor_preset(sensor_name);
        if (noise) {
          if (!(*noise >= 0.0)) throw py::value_error("noise: expected a range noise sigma >= 0 in metres");
          sensor.range_noise_sigma = *noise;
        }
        if (dropout) {
          if (!(*dropout >= 0.0 && *dropout < 1.0)) throw py::value_error("dropout: expected a probability in [0, 1)");
          sensor.dropout_probability = *dropout;
        }
        SyntheticOutputOptions output;
        if (format == "ply") {
          output.cloud_format = CloudFormat::Ply;
        } else if (format == "pcd") {
          output.cloud_format = CloudFormat::Pcd;
        } else {
          throw py::value_error("format: expected ply or pcd, got '" + format + "'");
        }
        output.binary = binary;
        std::vector<Eigen::Isometry3d> sensor_poses;
        std::optional<std::string> pose_spec;
        if (py::isinstance<py::str>(poses) || py::hasattr(poses, "__fspath__")) {
          pose_spec = path_from_object(poses);
        } else if (!poses.is_none()) {
          for (const py::handle pose : poses) sensor_poses.push_back(pose_from_object(pose, "poses[i]"));
        }
        // The folder is checked before the work and replaced whole once every file is written, as
        // `quadrix synth --out` does: an error or a full disk midway leaves the earlier folder as it was.
        std::optional<FolderReplacement> folder;
        if (!out.is_none())
          folder.emplace("out", path_from_object(out), synthetic_folder_names(),
                         std::vector<std::string>{pose_spec.value_or(std::string())});

        SyntheticRun run;
        std::vector<std::string> files;
        std::string primitives_text;
        {
          py::gil_scoped_release release;
          StreetOptions street;
          street.foliage = foliage_from_name(foliage, "foliage");
          const Scene scene = make_scene(scene_name, seed, street);
          if (pose_spec) sensor_poses = parse_pose_spec(*pose_spec);
          if (sensor_poses.empty() && !pose_spec) sensor_poses = default_sensor_poses(scene, sensor);
          run = run_synthetic(scene, sensor, sensor_poses, seed);
          if (folder) {
            files = write_synthetic_folder(folder->staging_folder(), run, output);
            folder->commit();
          }
          if (primitives) primitives_text = primitives_json(run.scene, output.record_samples);
        }

        py::dict result;
        result["scene"] = run.scene.name;
        result["sensor"] = run.sensor.name;
        result["seed"] = seed;
        py::list clouds, pose_list, pairs;
        for (SimulatedScan& scan : run.scans) {
          auto cloud = std::make_shared<Cloud>();
          cloud->cloud = std::move(scan.cloud);
          clouds.append(py::cast(cloud));
          pose_list.append(matrix_array(scan.sensor_pose));
        }
        // Every pair target < source, in the order of the folder's pairs.tsv (write_synthetic_folder).
        for (std::size_t target = 0; target < run.scans.size(); ++target) {
          for (std::size_t source = target + 1; source < run.scans.size(); ++source) {
            py::dict pair;
            pair["source"] = source;
            pair["target"] = target;
            pair["transform"] = matrix_array(relative_transform(run.scans[target].sensor_pose, run.scans[source].sensor_pose));
            pairs.append(pair);
          }
        }
        result["clouds"] = clouds;
        result["poses"] = pose_list;
        result["pairs"] = pairs;
        result["primitives"] = primitives ? json_loads(primitives_text) : py::object(py::none());
        result["files"] = files;
        return result;
      },
      py::arg("scene") = "street", py::arg("seed") = 1, py::arg("sensor") = "hdl64", py::arg("poses") = py::none(),
      py::arg("noise") = py::none(), py::arg("dropout") = py::none(), py::arg("primitives") = true,
      py::arg("out") = py::none(), py::arg("format") = "ply", py::arg("binary") = true, py::arg("foliage") = "solid",
      R"doc(
Simulates scans of a built-in scene with exact ground truth, as ``quadrix synth`` does (same seed,
same clouds). Returns a dict:

  scene, sensor, seed    what was simulated
  clouds                 one quadrix.Cloud per sensor pose, in the sensor frame; labels = semantic
                         label, fields["primitive_id"] = the primitive each point hit
  poses                  sensor -> world 4x4 of each scan
  pairs                  [{source, target, transform}] for every target < source: transform maps
                         points of clouds[source] into the frame of clouds[target] (ground truth
                         for ``register(clouds[source], clouds[target])``)
  primitives             the ground-truth primitives (primitives.json), or None with primitives=False
  files                  the files written under ``out`` (empty without it)

scene: street, corridor or monument (``scenes()``). sensor: hdl64, vlp16, livox or tls (``sensors()``).
seed: layout and noise seed. poses: None (the scene's default LiDAR pair, or its six TLS stations
for tls), a POSE_SPEC string "x,y,z,yaw_deg[,pitch_deg[,roll_deg]];..." or pose file, or a list of
4x4 sensor -> world matrices. noise: range noise sigma override, m. dropout: return-loss
probability override. out: also write the ``quadrix synth --out`` folder there (format ply|pcd,
binary or ASCII). foliage (street only): "solid" crowns, or "porous" crowns and hedges that rays
enter (``quadrix synth --foliage``).

Example::

    data = quadrix.synth("street", seed=3, sensor="hdl64")
    pair = data["pairs"][0]
    result = quadrix.register(data["clouds"][pair["source"]], data["clouds"][pair["target"]])
)doc");

  module.def(
      "scenes",
      [] {
        py::dict scenes;
        for (const std::string& name : scene_names()) scenes[py::str(name)] = scene_description(name);
        return scenes;
      },
      R"doc(The built-in scenes of ``synth`` as {name: description}.)doc");

  module.def(
      "sensors",
      [] {
        py::dict sensors;
        for (const std::string& name : sensor_names()) sensors[py::str(name)] = sensor_preset(name).description;
        return sensors;
      },
      R"doc(The simulated sensors of ``synth`` as {name: description}.)doc");
}

}  // namespace quadrix::python
