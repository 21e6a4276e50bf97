// The Python module `quadrix` (pybind11): NumPy in, NumPy out (DESIGN.md §2, python/).
// quadrix::Error (bad input, API misuse; its message names the file, line or key) becomes ValueError;
// missing files are FileNotFoundError and unknown keys of a config dict KeyError (raised by the bindings).
#include "bindings.h"

#include "geometry/error.h"

// Built as quadrix._quadrix; the package quadrix (package/__init__.py.in) checks the interpreter, then re-exports it.
PYBIND11_MODULE(_quadrix, module) {
  namespace py = pybind11;
  module.doc() = R"doc(
Quadrix: quadric primitives for point-cloud modelling and global registration (QuadricsReg).

Clouds are (N, 3) NumPy arrays, quadrix.Cloud objects or file paths.

  read_cloud, write_cloud        point-cloud files <-> quadrix.Cloud / arrays
  register                       global registration of two clouds (quadrix register)
  model, load_model, Model       the quadric scene model of a cloud (quadrix model)
  fit                            one quadric fitted to a segment (quadrix fit)
  synth, scenes, sensors         simulated scans of built-in scenes with ground truth (quadrix synth)
  map, MapResult                 one map from many scans, in-process or on a Dask cluster (quadrix map)
  config, config_keys, config_schema, presets   the registration options (quadrix config)

Errors: FileNotFoundError for missing files, KeyError for unknown config keys, ValueError for bad
input (the message names the file, line or key). Heavy calls release the GIL.
)doc";
  py::register_exception_translator([](std::exception_ptr error) {
    try {
      if (error) std::rethrow_exception(error);
    } catch (const quadrix::Error& quadrix_error) {
      PyErr_SetString(PyExc_ValueError, quadrix_error.what());
    }
  });
  quadrix::python::bind_clouds(module);
  quadrix::python::bind_config(module);
  quadrix::python::bind_models(module);
  quadrix::python::bind_tiles(module);
  quadrix::python::bind_map(module);
  quadrix::python::bind_register(module);
  quadrix::python::bind_synth(module);
  module.attr("__version__") = QUADRIX_VERSION;
}
