// Shared pieces of the pybind11 module `quadrix` (python/src/*.cpp): the Python Cloud type, the
// conversions between NumPy / Python objects and Quadrix's types, and the error mapping.
// Python sees NumPy arrays and plain dicts; Quadrix's own types stay on the C++ side.
#pragma once

#include "estimation/registration.h"
#include "fitting/scene_model.h"
#include "geometry/io.h"
#include "geometry/las.h"
#include "geometry/point_cloud.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <Eigen/Geometry>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace quadrix::python {

namespace py = pybind11;

/// A point cloud owned by Python (`quadrix.Cloud`): positions and the optional per-point fields.
/// Shared so that arrays handed out as views keep it alive.
struct Cloud {
  PointCloud cloud;        ///< the cloud as Quadrix reads and registers it
  std::string source;      ///< file it was read from ("" when built from arrays)
  CoordinateUnits units;   ///< the file's length unit (a LAS file may declare feet); metres for arrays
};

/// A scene model owned by Python (`quadrix.Model`).
struct Model {
  SceneModel model;     ///< the records, augmented points and statistics
  std::string status;   ///< modelling_status_name of the run, or derived from the records when loaded
  std::string message;  ///< why, when not ok (empty for a loaded model)
};

/// The status of a model without a modelling run (read from a file, or a registration's side): ok
/// with at least one quadric, else empty.
std::string derived_status(const SceneModel& model);

/// The (N, 3) float32 positions of `cloud` from `points`: any (N, 3) real array; float32 C-contiguous
/// input is copied once with memcpy (each row is one column of the column-major Matrix3Xf), any
/// other dtype or layout is converted in one pass. Throws ValueError for another shape or a
/// non-finite coordinate (naming the row).
Eigen::Matrix3Xf positions_from_array(const py::handle& points, const char* what);

/// The cloud behind `value`: a quadrix.Cloud (used in place, no copy), a path (str or os.PathLike,
/// read with read_point_cloud; FileNotFoundError when it does not exist), or an (N, 3) array.
/// `holder` keeps a cloud built here alive while the returned reference is used (and holds the
/// cloud's units). A path is read with `local_origin` (Auto keeps georeferenced coordinates exact).
const PointCloud& cloud_from_object(const py::handle& value, const char* what, std::shared_ptr<Cloud>& holder,
                                    std::string* path = nullptr, LocalOrigin local_origin = LocalOrigin::Zero);

/// Optional per-point uint32 labels (None -> empty); ValueError when the length is not `expected`.
std::vector<std::uint32_t> labels_from_object(const py::handle& value, std::size_t expected, const char* what);

/// The path of a str or os.PathLike as UTF-8.
std::string path_from_object(const py::handle& value);

/// FileNotFoundError naming `path` unless it exists.
void require_existing_file(const std::string& path);

/// FileNotFoundError naming `path` unless its parent folder exists (writers create the file only).
void require_writable_location(const std::string& path);

/// A 4x4 float64 array of a pose.
py::array_t<double> matrix_array(const Eigen::Isometry3d& pose);

/// A pose from a 4x4 array-like (ValueError for another shape or a last row other than 0 0 0 1).
Eigen::Isometry3d pose_from_object(const py::handle& value, const char* what);

/// A point from None (the origin) or three finite numbers; ValueError naming `what` otherwise.
Eigen::Vector3d point_from_object(const py::handle& value, const char* what);

/// Python objects of the JSON text `text` (json.loads).
py::object json_loads(const std::string& text);

/// Registration options for a pair as `quadrix register` builds them: each side's preset (a name or
/// "auto", measured on that cloud), then `config` (None, a dict in the YAML schema, or a YAML file
/// path), then the refiner override. `notes` receives auto's reasons.
RegistrationOptions registration_options_from(const std::string& source_preset, const PointCloud& source,
                                              const std::string& target_preset, const PointCloud& target,
                                              const py::handle& config, const py::handle& refiner,
                                              std::string* notes);

/// Applies `config` (None, a dict in the YAML schema, or a YAML file path) to `options`. A dict's
/// unknown keys raise KeyError naming the dotted key; its values are checked by the same reader as
/// files (ValueError naming the key). A file that does not exist raises FileNotFoundError.
void apply_config_object(const py::handle& config, RegistrationOptions& options);

/// Every key of registration_config_keys with its value in `options` (per-side keys from `side`),
/// as nested dicts in the YAML schema (the content of `quadrix config`).
py::dict config_dict(const RegistrationOptions& options, const std::string& side);

void bind_clouds(py::module_& module);    ///< Cloud, read_cloud, write_cloud
void bind_config(py::module_& module);    ///< config, config_schema, config_keys, presets
void bind_models(py::module_& module);    ///< Model, model, load_model, fit
void bind_register(py::module_& module);  ///< RegistrationResult, register
void bind_synth(py::module_& module);     ///< synth, scenes, sensors
void bind_tiles(py::module_& module);     ///< model_tiles, merge_tiles, model_tiled
void bind_map(py::module_& module);       ///< MapResult, map

}  // namespace quadrix::python
