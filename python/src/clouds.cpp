// quadrix.Cloud, quadrix.read_cloud, quadrix.write_cloud and the NumPy conversions every binding uses.
#include "bindings.h"

#include "geometry/error.h"
#include "geometry/io.h"

#include <pybind11/stl.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <sstream>

namespace quadrix::python {

static_assert(sizeof(std::array<std::uint8_t, 3>) == 3, "colors are viewed as an (N, 3) uint8 array");

namespace {

// A read-only NumPy view of `count` x `columns` values at `data`, kept alive by `owner`.
template <typename T>
py::array_t<T> view(const py::object& owner, const T* data, std::size_t count, std::size_t columns) {
  std::vector<py::ssize_t> shape{static_cast<py::ssize_t>(count)};
  std::vector<py::ssize_t> strides{static_cast<py::ssize_t>(sizeof(T) * columns)};
  if (columns > 1) {
    shape.push_back(static_cast<py::ssize_t>(columns));
    strides.push_back(static_cast<py::ssize_t>(sizeof(T)));
  }
  py::array_t<T> array(shape, strides, data, owner);
  array.attr("setflags")(py::arg("write") = false);
  return array;
}

// One per-point float field from an optional array (None -> empty); ValueError for another length.
std::vector<float> floats_from_object(const py::handle& value, std::size_t expected, const char* what) {
  if (value.is_none()) return {};
  const auto array = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(value);
  if (!array || array.ndim() != 1 || static_cast<std::size_t>(array.shape(0)) != expected) {
    throw py::value_error(std::string(what) + ": expected a 1-D array of " + std::to_string(expected) +
                          " values (one per point)");
  }
  return std::vector<float>(array.data(), array.data() + array.shape(0));
}

// The shape of an array as "(a, b, ...)".
std::string shape_text(const py::array& array) {
  std::ostringstream text;
  text << "(";
  for (py::ssize_t axis = 0; axis < array.ndim(); ++axis) text << (axis ? ", " : "") << array.shape(axis);
  text << (array.ndim() == 1 ? ",)" : ")");
  return text.str();
}

// Copies an (N, 3) array of T with any strides into the columns of `positions`.
template <typename T>
void copy_rows(const py::array& array, Eigen::Matrix3Xf& positions) {
  const auto rows = array.unchecked<T, 2>();
  for (py::ssize_t i = 0; i < rows.shape(0); ++i)
    for (py::ssize_t k = 0; k < 3; ++k) positions(k, i) = static_cast<float>(rows(i, k));
}

// A Cloud from arrays (the Python constructor and write_cloud).
std::shared_ptr<Cloud> cloud_from_arrays(const py::handle& points, const py::handle& intensity,
                                         const py::handle& labels) {
  auto cloud = std::make_shared<Cloud>();
  cloud->cloud.positions = positions_from_array(points, "points");
  cloud->cloud.intensity = floats_from_object(intensity, cloud->cloud.size(), "intensity");
  cloud->cloud.labels = labels_from_object(labels, cloud->cloud.size(), "labels");
  return cloud;
}

}  // namespace

Eigen::Matrix3Xf positions_from_array(const py::handle& points, const char* what) {
  const py::array array = py::module_::import("numpy").attr("asarray")(points);
  const char kind = array.dtype().kind();
  if (array.ndim() != 2 || array.shape(1) != 3 || (kind != 'f' && kind != 'i' && kind != 'u')) {
    throw py::value_error(std::string(what) + ": expected an (N, 3) array of real numbers, got shape " +
                          shape_text(array) + " of dtype " + py::str(array.dtype()).cast<std::string>());
  }
  Eigen::Matrix3Xf positions(3, array.shape(0));
  const bool float32 = array.dtype().is(py::dtype::of<float>());
  if (float32 && (array.flags() & py::array::c_style)) {
    // Row i of a C-contiguous (N, 3) float32 array is column i of the column-major 3 x N matrix.
    if (array.shape(0) > 0) std::memcpy(positions.data(), array.data(), sizeof(float) * 3 * array.shape(0));
  } else if (float32) {
    copy_rows<float>(array, positions);
  } else if (array.dtype().is(py::dtype::of<double>())) {
    copy_rows<double>(array, positions);
  } else {
    copy_rows<double>(py::array_t<double, py::array::forcecast>::ensure(array), positions);
  }
  if (!positions.allFinite()) {
    for (Eigen::Index i = 0; i < positions.cols(); ++i) {
      if (!positions.col(i).allFinite()) {
        std::ostringstream message;
        message << what << "[" << i << "] = (" << positions(0, i) << ", " << positions(1, i) << ", " << positions(2, i)
                << ") is not finite";
        throw py::value_error(message.str());
      }
    }
  }
  return positions;
}

std::string path_from_object(const py::handle& value) {
  return py::module_::import("os").attr("fsdecode")(value).cast<std::string>();
}

void require_existing_file(const std::string& path) {
  if (!std::filesystem::exists(path)) {
    PyErr_SetObject(PyExc_FileNotFoundError,
                    py::make_tuple(ENOENT, path + ": no such file", path).ptr());
    throw py::error_already_set();
  }
}

void require_writable_location(const std::string& path) {
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  if (!parent.empty() && !std::filesystem::is_directory(parent)) {
    PyErr_SetObject(PyExc_FileNotFoundError,
                    py::make_tuple(ENOENT, path + ": folder " + parent.string() + " does not exist", path).ptr());
    throw py::error_already_set();
  }
}

const PointCloud& cloud_from_object(const py::handle& value, const char* what, std::shared_ptr<Cloud>& holder,
                                    std::string* path, LocalOrigin local_origin) {
  if (py::isinstance<Cloud>(value)) {
    holder = value.cast<std::shared_ptr<Cloud>>();
    if (path) *path = holder->source;
    return holder->cloud;
  }
  holder = std::make_shared<Cloud>();
  if (py::isinstance<py::str>(value) || py::hasattr(value, "__fspath__")) {
    holder->source = path_from_object(value);
    require_existing_file(holder->source);
    if (path) *path = holder->source;
    py::gil_scoped_release release;
    holder->units = coordinate_units(holder->source);
    CloudReadOptions options;
    options.local_origin = local_origin;
    holder->cloud = read_point_cloud(holder->source, options);
    return holder->cloud;
  }
  holder->cloud.positions = positions_from_array(value, what);
  return holder->cloud;
}

std::vector<std::uint32_t> labels_from_object(const py::handle& value, std::size_t expected, const char* what) {
  if (value.is_none()) return {};
  const py::array array = py::module_::import("numpy").attr("asarray")(value);
  if (array.ndim() != 1 || static_cast<std::size_t>(array.shape(0)) != expected ||
      (array.dtype().kind() != 'i' && array.dtype().kind() != 'u')) {
    throw py::value_error(std::string(what) + ": expected a 1-D integer array of " + std::to_string(expected) +
                          " labels (one per point), got shape " + shape_text(array) + " of dtype " +
                          py::str(array.dtype()).cast<std::string>());
  }
  const auto labels = py::array_t<std::uint32_t, py::array::c_style | py::array::forcecast>::ensure(array);
  return std::vector<std::uint32_t>(labels.data(), labels.data() + labels.shape(0));
}

py::array_t<double> matrix_array(const Eigen::Isometry3d& pose) {
  py::array_t<double> array({4, 4});
  auto out = array.mutable_unchecked<2>();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) out(r, c) = pose.matrix()(r, c);
  return array;
}

Eigen::Isometry3d pose_from_object(const py::handle& value, const char* what) {
  const auto array = py::array_t<double, py::array::forcecast>::ensure(value);
  if (!array || array.ndim() != 2 || array.shape(0) != 4 || array.shape(1) != 4)
    throw py::value_error(std::string(what) + ": expected a 4x4 matrix");
  const auto in = array.unchecked<2>();
  Eigen::Isometry3d pose;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) pose.matrix()(r, c) = in(r, c);
  if (std::abs(in(3, 0)) + std::abs(in(3, 1)) + std::abs(in(3, 2)) + std::abs(in(3, 3) - 1.0) > 1e-9)
    throw py::value_error(std::string(what) + ": the last row of a rigid transform must be 0 0 0 1");
  return pose;
}

Eigen::Vector3d point_from_object(const py::handle& value, const char* what) {
  if (value.is_none()) return Eigen::Vector3d::Zero();
  const auto array = py::array_t<double, py::array::forcecast>::ensure(value);
  if (!array || array.ndim() != 1 || array.shape(0) != 3)
    throw py::value_error(std::string(what) + ": expected three numbers (x, y, z in metres)");
  const auto in = array.unchecked<1>();
  const Eigen::Vector3d point(in(0), in(1), in(2));
  if (!point.allFinite()) throw py::value_error(std::string(what) + ": the coordinates must be finite");
  return point;
}

py::object json_loads(const std::string& text) { return py::module_::import("json").attr("loads")(text); }

void bind_clouds(py::module_& module) {
  py::class_<Cloud, std::shared_ptr<Cloud>>(module, "Cloud", R"doc(
A point cloud: positions plus the optional per-point fields a file carried.

``Cloud(points, intensity=None, labels=None)`` builds one from arrays: ``points`` is any (N, 3)
real array (float32 C-contiguous is copied once with memcpy, other layouts converted in one pass),
``intensity`` N floats, ``labels`` N non-negative integers. ``read_cloud`` returns one; every
function taking a cloud accepts a Cloud (used in place, no copy), an (N, 3) array or a file path.
The array properties are read-only views of the cloud's memory (copy them to modify).
)doc")
      .def(py::init(&cloud_from_arrays), py::arg("points"), py::arg("intensity") = py::none(),
           py::arg("labels") = py::none(), "Builds a cloud from an (N, 3) array and optional per-point fields.")
      .def_property_readonly(
          "points",
          [](py::object self) {
            const Cloud& cloud = self.cast<const Cloud&>();
            return view<float>(self, cloud.cloud.positions.data(), cloud.cloud.size(), 3);
          },
          "(N, 3) float32 positions in the file's unit (``units``: metres unless a LAS file declares another), relative to ``local_origin`` (read-only view).")
      .def_property_readonly(
          "intensity",
          [](py::object self) -> py::object {
            const Cloud& cloud = self.cast<const Cloud&>();
            if (cloud.cloud.intensity.empty()) return py::none();
            return view<float>(self, cloud.cloud.intensity.data(), cloud.cloud.size(), 1);
          },
          "(N,) float32 intensity / reflectance, or None when the cloud has none.")
      .def_property_readonly(
          "labels",
          [](py::object self) -> py::object {
            const Cloud& cloud = self.cast<const Cloud&>();
            if (cloud.cloud.labels.empty()) return py::none();
            return view<std::uint32_t>(self, cloud.cloud.labels.data(), cloud.cloud.size(), 1);
          },
          "(N,) uint32 semantic labels, or None when the cloud has none.")
      .def_property_readonly(
          "colors",
          [](py::object self) -> py::object {
            const Cloud& cloud = self.cast<const Cloud&>();
            if (cloud.cloud.colors.empty()) return py::none();
            return view<std::uint8_t>(self, cloud.cloud.colors.front().data(), cloud.cloud.size(), 3);
          },
          "(N, 3) uint8 RGB colours, or None when the cloud has none.")
      .def_property_readonly(
          "fields",
          [](py::object self) {
            const Cloud& cloud = self.cast<const Cloud&>();
            py::dict fields;
            for (const auto& [name, values] : cloud.cloud.extra_fields)
              fields[py::str(name)] = view<float>(self, values.data(), values.size(), 1);
            return fields;
          },
          "Other scalar per-point fields the file carried, name -> (N,) float32 array.")
      .def_readonly("source", &Cloud::source, "The file the cloud was read from ('' when built from arrays).")
      .def_property_readonly(
          "local_origin",
          [](const Cloud& cloud) {
            return std::vector<double>{cloud.cloud.local_origin.x(), cloud.cloud.local_origin.y(), cloud.cloud.local_origin.z()};
          },
          "[x, y, z] in the file's coordinates that ``points`` are relative to (0 0 0 unless read with local_origin='auto').")
      .def_property_readonly(
          "units",
          [](const Cloud& cloud) {
            py::dict units;
            units["name"] = cloud.units.name;
            units["metres_per_unit"] = cloud.units.metres_per_unit;
            units["declared_by"] = cloud.units.source.empty() ? "nothing (metres assumed)" : cloud.units.source;
            return units;
          },
          "The length unit of the coordinates {name, metres_per_unit, declared_by}: what a LAS file's CRS declares, else metres.")
      .def("__len__", [](const Cloud& cloud) { return cloud.cloud.size(); }, "Number of points.")
      .def("__repr__", [](const Cloud& cloud) {
        std::string fields;
        if (!cloud.cloud.intensity.empty()) fields += ", intensity";
        if (!cloud.cloud.labels.empty()) fields += ", labels";
        if (!cloud.cloud.colors.empty()) fields += ", colors";
        for (const auto& entry : cloud.cloud.extra_fields) fields += ", " + entry.first;
        return "<quadrix.Cloud " + std::to_string(cloud.cloud.size()) + " points" + fields +
               (cloud.source.empty() ? "" : " from " + cloud.source) + ">";
      });

  module.def(
      "read_cloud",
      [](const py::object& path, const std::string& format, const std::string& local_origin) {
        auto cloud = std::make_shared<Cloud>();
        cloud->source = path_from_object(path);
        require_existing_file(cloud->source);
        CloudReadOptions options;
        options.format = cloud_format_from_name(format);
        if (local_origin == "auto")
          options.local_origin = LocalOrigin::Auto;
        else if (local_origin != "zero")
          throw Error("read_cloud: local_origin must be 'zero' or 'auto', got '" + local_origin + "'");
        py::gil_scoped_release release;
        cloud->units = coordinate_units(cloud->source, options.format);
        cloud->cloud = read_point_cloud(cloud->source, options);
        return cloud;
      },
      py::arg("path"), py::arg("format") = "auto", py::arg("local_origin") = "zero", R"doc(
Reads a point cloud file into a quadrix.Cloud (``.points`` is an (N, 3) float32 array;
``.intensity``, ``.labels``, ``.colors`` and ``.fields`` when the file has them).

path: str or os.PathLike. The format follows the extension (.bin KITTI, .pcd.bin nuScenes, .ply,
.pcd, .xyz/.txt, .csv, .npy) unless ``format`` names one (auto, bin, kitti-bin, nuscenes-bin, ply,
pcd, xyz, csv, npy, las). Points with a NaN/inf coordinate are dropped, as in ``quadrix info``.
local_origin: ``zero`` (positions as in the file; float32 rounds georeferenced coordinates to
decimetres) or ``auto`` (a round point near the file's centre is subtracted in double first and kept
as ``Cloud.local_origin``; ``model`` writes its model back in the file's coordinates). The file's
length unit (a LAS file may declare feet) is kept as ``Cloud.units``.

Raises FileNotFoundError when the file does not exist and ValueError naming the file (and line or
field) when it cannot be parsed.
)doc");

  module.def(
      "write_cloud",
      [](const py::object& path, const py::object& points, const py::object& intensity, const py::object& labels,
         bool binary) {
        const std::string file = path_from_object(path);
        require_writable_location(file);
        std::shared_ptr<Cloud> cloud;
        if (py::isinstance<Cloud>(points)) {
          cloud = points.cast<std::shared_ptr<Cloud>>();
          if (!intensity.is_none() || !labels.is_none()) {
            auto copy = std::make_shared<Cloud>(*cloud);
            if (!intensity.is_none()) copy->cloud.intensity = floats_from_object(intensity, copy->cloud.size(), "intensity");
            if (!labels.is_none()) copy->cloud.labels = labels_from_object(labels, copy->cloud.size(), "labels");
            cloud = copy;
          }
        } else {
          cloud = cloud_from_arrays(points, intensity, labels);
        }
        CloudWriteOptions options;
        options.binary = binary;
        py::gil_scoped_release release;
        write_point_cloud(file, cloud->cloud, options);
      },
      py::arg("path"), py::arg("points"), py::arg("intensity") = py::none(), py::arg("labels") = py::none(),
      py::arg("binary") = true, R"doc(
Writes a point cloud atomically as PLY or PCD (by the extension of ``path``).

points: an (N, 3) array or a quadrix.Cloud (then every field it carries is written).
intensity: optional N floats; labels: optional N non-negative integers (override a Cloud's).
binary: binary_little_endian PLY / binary PCD (default), else ASCII.

Raises FileNotFoundError when the folder of ``path`` does not exist, ValueError for another
extension or arrays of the wrong shape.
)doc");
}

}  // namespace quadrix::python
