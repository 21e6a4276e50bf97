// quadrix.config, quadrix.config_schema, quadrix.config_keys, quadrix.presets, and the conversion of
// a configuration dict (the YAML schema of registration_config_keys) to RegistrationOptions.
// A dict goes through the very reader of YAML files (apply_registration_config), so a dict and a
// file with the same content set the same options and are checked the same way.
#include "bindings.h"

#include "estimation/refiner.h"
#include "estimation/registration_config.h"
#include "geometry/error.h"

#include <pybind11/stl.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <type_traits>
#include <unistd.h>

namespace quadrix::python {

namespace {

// Name a dict is reported under in errors of the shared YAML reader.
constexpr const char* kDictName = "<config dict>";


// KeyError for the first key of `section` that is neither a key of the table nor a section of some.
void check_keys(const py::dict& section, const std::string& prefix) {
  for (const auto& [name_object, value] : section) {
    const std::string name = py::str(name_object).cast<std::string>();
    const std::string path = prefix.empty() ? name : prefix + "." + name;
    if (find_registration_config_key(path) != nullptr) continue;
    std::string known;
    for (const std::string& each : registration_config_names_below(prefix)) known += (known.empty() ? "" : ", ") + each;
    if (registration_config_names_below(path).empty())
      throw py::key_error("unknown configuration key '" + path + "' (known here: " + known + ")");
    if (!py::isinstance<py::dict>(value))
      throw py::value_error("configuration key '" + path + "' is a section: expected a dict");
    check_keys(py::reinterpret_borrow<py::dict>(value), path);
  }
}

// A YAML node of a Python value (None, bool, int, float, str, list/tuple/array, dict).
YAML::Node yaml_node(const py::handle& value, const std::string& path) {
  if (value.is_none()) return YAML::Node(YAML::NodeType::Null);
  if (py::isinstance<py::bool_>(value) || py::isinstance(value, py::module_::import("numpy").attr("bool_")))
    return YAML::Node(value.cast<bool>() ? "true" : "false");
  if (py::isinstance<py::str>(value)) return YAML::Node(value.cast<std::string>());
  if (py::isinstance<py::dict>(value)) {
    YAML::Node node(YAML::NodeType::Map);
    for (const auto& [name, item] : py::reinterpret_borrow<py::dict>(value)) {
      const std::string key = py::str(name).cast<std::string>();
      node[key] = yaml_node(item, path.empty() ? key : path + "." + key);
    }
    return node;
  }
  if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value) || py::isinstance<py::array>(value)) {
    YAML::Node node(YAML::NodeType::Sequence);
    const py::object items = py::isinstance<py::array>(value) ? value.attr("tolist")() : py::reinterpret_borrow<py::object>(value);
    for (const py::handle item : items) node.push_back(yaml_node(item, path));
    return node;
  }
  if (py::hasattr(value, "__index__")) return YAML::Node(py::str(value.attr("__index__")()).cast<std::string>());
  if (py::hasattr(value, "__float__")) {
    const double number = value.cast<double>();
    if (std::isnan(number)) return YAML::Node(".nan");
    if (std::isinf(number)) return YAML::Node(number > 0 ? ".inf" : "-.inf");
    return YAML::Node(py::repr(py::float_(number)).cast<std::string>());  // shortest text that reads back exactly
  }
  throw py::type_error("configuration key '" + path + "': cannot use a value of type " +
                       py::str(py::type::of(value).attr("__name__")).cast<std::string>());
}

// Replaces every occurrence of `from` in `text` by `to`.
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  for (std::size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size()))
    text.replace(at, from.size(), to);
  return text;
}

// Applies a dict through a temporary YAML file read by apply_registration_config.
void apply_config_dict(const py::dict& config, RegistrationOptions& options) {
  check_keys(config, "");
  YAML::Emitter emitter;
  emitter << yaml_node(config, "");
  static std::atomic<unsigned> counter{0};
  const std::filesystem::path file = std::filesystem::temp_directory_path() /
                                     ("quadrix-config-" + std::to_string(::getpid()) + "-" +
                                      std::to_string(counter++) + ".yaml");
  struct Remove {
    std::filesystem::path path;
    ~Remove() {
      std::error_code ignored;
      std::filesystem::remove(path, ignored);
    }
  } remove{file};
  {
    std::ofstream out(file);
    out << emitter.c_str() << "\n";
    if (!out) throw Error(file.string() + ": cannot write the temporary configuration file");
  }
  try {
    apply_registration_config(file.string(), options);
  } catch (const Error& error) {
    throw Error(replaced(error.what(), file.string(), kDictName));
  }
}

// The Python value of one configuration member.
py::object member_value(const RegistrationConfigMember& member) {
  return std::visit(
      [](auto* value) -> py::object {
        using T = std::remove_pointer_t<decltype(value)>;
        if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
          return py::cast(std::vector<double>{(*value)(0), (*value)(1), (*value)(2)});
        } else {
          return py::cast(*value);
        }
      },
      member);
}

}  // namespace

void apply_config_object(const py::handle& config, RegistrationOptions& options) {
  if (config.is_none()) return;
  if (py::isinstance<py::dict>(config)) {
    apply_config_dict(py::reinterpret_borrow<py::dict>(config), options);
    return;
  }
  if (py::isinstance<py::str>(config) || py::hasattr(config, "__fspath__")) {
    const std::string path = path_from_object(config);
    require_existing_file(path);
    apply_registration_config(path, options);
    return;
  }
  throw py::type_error("config: expected None, a dict in the YAML schema or the path of a YAML file");
}

RegistrationOptions registration_options_from(const std::string& source_preset, const PointCloud& source,
                                              const std::string& target_preset, const PointCloud& target,
                                              const py::handle& config, const py::handle& refiner,
                                              std::string* notes) {
  RegistrationOptions options;
  {
    py::gil_scoped_release release;  // auto measures both clouds
    options = resolve_registration_options(source_preset, source, target_preset, target, notes);
  }
  apply_config_object(config, options);
  if (!refiner.is_none()) {
    const std::string name = refiner.cast<std::string>();
    make_refiner(name);  // an Error listing the refiners for an unknown name
    options.estimation.refiner = name;
  }
  return options;
}

py::dict config_dict(const RegistrationOptions& options, const std::string& side) {
  if (side != "source" && side != "target")
    throw py::value_error("side: expected 'source' or 'target', got '" + side + "'");
  RegistrationOptions values = options;  // the table reaches members through non-const options
  const ConfigSide which = side == "source" ? ConfigSide::Source : ConfigSide::Target;
  py::dict root;
  for (const RegistrationConfigKey& key : registration_config_keys()) {
    py::dict section = root;
    std::size_t begin = 0;
    for (std::size_t dot = key.path.find('.'); dot != std::string::npos; dot = key.path.find('.', begin)) {
      const py::str name(key.path.substr(begin, dot - begin));
      if (!section.contains(name)) section[name] = py::dict();
      section = section[name].cast<py::dict>();
      begin = dot + 1;
    }
    section[py::str(key.path.substr(begin))] = member_value(key.member(values, key.per_side ? which : ConfigSide::Source));
  }
  return root;
}

void bind_config(py::module_& module) {
  module.def(
      "config",
      [](const std::string& preset, const py::object& cloud, const py::object& config, const std::string& side) {
        std::shared_ptr<Cloud> holder;
        const PointCloud empty;
        const PointCloud& measured = cloud.is_none() ? empty : cloud_from_object(cloud, "cloud", holder);
        // auto without a cloud (as bare `quadrix config`): the defaults auto starts from.
        const std::string resolved = preset == "auto" && cloud.is_none() ? guess_sensor_preset(empty).preset : preset;
        const RegistrationOptions options =
            registration_options_from(resolved, measured, resolved, measured, config, py::none(), nullptr);
        return config_dict(options, side);
      },
      py::arg("preset") = "auto", py::arg("cloud") = py::none(), py::arg("config") = py::none(),
      py::arg("side") = "source", R"doc(
The effective registration options as a plain dict in the YAML schema (what ``quadrix config``
prints): nested dicts of every key of ``config_keys()``, e.g.
``config("vlp16")["extraction"]["planes"]["voxel_size"]``.

preset: vlp64, vlp16, mid360, avia, monument, or auto (the default of ``register`` and ``model``):
measured on ``cloud`` (a Cloud, an (N, 3) array or a path) as ``quadrix config CLOUD`` does; without
a cloud, the defaults auto starts from (as bare ``quadrix config``).
config: overrides applied after the preset: a dict in the same schema or a YAML file path.
side: "source" or "target", which side's per-side keys (sensor, extraction.*) to report.

The dict can be edited and passed back as ``config=`` to ``register``, ``model`` or ``config``.
Raises KeyError naming an unknown key of a config dict, ValueError for an unknown preset or a bad
value (naming the key and the file), FileNotFoundError for a missing file.
)doc");

  module.def("config_schema", &registration_config_schema, R"doc(
The configuration schema as text, as ``quadrix config --schema`` prints it: one line per key with
its type (and valid names) and description.
)doc");

  module.def(
      "config_keys",
      [] {
        py::dict keys;
        for (const RegistrationConfigKey& key : registration_config_keys()) keys[py::str(key.path)] = key.description;
        return keys;
      },
      R"doc(Every configuration key as {dotted path: description}, in the order ``config`` lists them.)doc");

  module.def(
      "presets",
      [] {
        std::vector<std::string> names = registration_preset_names();
        names.push_back("auto");
        return names;
      },
      R"doc(The preset names ``register``, ``model`` and ``config`` accept (the sensor presets, then "auto").)doc");
}

}  // namespace quadrix::python
