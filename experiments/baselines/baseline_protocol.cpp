// JSON form of the baselines' options and results (baseline_protocol.h): what `quadrix bench` sends
// to quadrix-baselines and reads back.
#include "experiments/baselines/baseline_protocol.h"

#include "geometry/error.h"

#include <nlohmann/json.hpp>

#include <utility>
#include <variant>

namespace quadrix {
namespace {

using Json = nlohmann::json;
using OptionMember = std::variant<double BaselineOptions::*, int BaselineOptions::*, bool BaselineOptions::*,
                                  unsigned BaselineOptions::*>;

// Every field of BaselineOptions by its member name: one table for writing and reading.
const std::vector<std::pair<const char*, OptionMember>>& option_fields() {
  static const std::vector<std::pair<const char*, OptionMember>> fields = {
      {"voxel_size", &BaselineOptions::voxel_size},
      {"normal_radius", &BaselineOptions::normal_radius},
      {"normal_max_neighbours", &BaselineOptions::normal_max_neighbours},
      {"feature_radius", &BaselineOptions::feature_radius},
      {"feature_max_neighbours", &BaselineOptions::feature_max_neighbours},
      {"max_correspondence_distance", &BaselineOptions::max_correspondence_distance},
      {"mutual_filter", &BaselineOptions::mutual_filter},
      {"edge_length_similarity", &BaselineOptions::edge_length_similarity},
      {"ransac_iterations", &BaselineOptions::ransac_iterations},
      {"ransac_confidence", &BaselineOptions::ransac_confidence},
      {"fgr_iterations", &BaselineOptions::fgr_iterations},
      {"fgr_tuple_scale", &BaselineOptions::fgr_tuple_scale},
      {"fgr_maximum_tuple_count", &BaselineOptions::fgr_maximum_tuple_count},
      {"prerejective_iterations", &BaselineOptions::prerejective_iterations},
      {"prerejective_samples", &BaselineOptions::prerejective_samples},
      {"prerejective_feature_neighbours", &BaselineOptions::prerejective_feature_neighbours},
      {"prerejective_inlier_fraction", &BaselineOptions::prerejective_inlier_fraction},
      {"threads", &BaselineOptions::threads},
      {"seed", &BaselineOptions::seed},
  };
  return fields;
}

Json parse(const std::string& text, const char* what) {
  try {
    Json parsed = Json::parse(text);
    if (!parsed.is_object()) throw Error(std::string(what) + ": expected a JSON object");
    return parsed;
  } catch (const Json::exception& error) {
    throw Error(std::string(what) + ": not valid JSON (" + error.what() + ")");
  }
}

// The value of `key` in `object` as T; Error naming the key when it is missing or of another type.
template <typename T>
T field(const Json& object, const std::string& key, const char* what) {
  const auto found = object.find(key);
  if (found == object.end()) throw Error(std::string(what) + ": missing field '" + key + "'");
  try {
    return found->get<T>();
  } catch (const Json::exception&) {
    throw Error(std::string(what) + ": field '" + key + "' has the wrong type (" + found->dump() + ")");
  }
}

}  // namespace

std::vector<std::string> baseline_method_names() { return {"open3d-ransac", "open3d-fgr", "pcl-prerejective"}; }

std::string baseline_options_to_json(const BaselineOptions& options) {
  Json object = Json::object();
  for (const auto& [name, member] : option_fields())
    std::visit([&, key = name](auto pointer) { object[key] = options.*pointer; }, member);
  return object.dump();
}

BaselineOptions baseline_options_from_json(const std::string& text) {
  const char* what = "baseline options";
  const Json object = parse(text, what);
  BaselineOptions options;
  for (const auto& [key, value] : object.items()) {
    bool known = false;
    for (const auto& [name, member] : option_fields()) {
      if (key != name) continue;
      known = true;
      std::visit(
          [&, field_name = key](auto pointer) {
            using Value = std::decay_t<decltype(options.*pointer)>;
            options.*pointer = field<Value>(object, field_name, what);
          },
          member);
    }
    if (!known) throw Error(std::string(what) + ": unknown field '" + key + "'");
  }
  return options;
}

std::string baseline_result_to_json(const BaselineResult& result) {
  Json object = Json::object();
  std::vector<double> transform;
  for (int row = 0; row < 4; ++row)
    for (int column = 0; column < 4; ++column) transform.push_back(result.transform.matrix()(row, column));
  object["transform"] = transform;
  object["solved"] = result.solved;
  object["message"] = result.message;
  object["timings_ms"] = result.timings_ms;
  object["cpu_ms"] = result.cpu_ms;
  object["counts"] = result.counts;
  return object.dump();
}

BaselineResult baseline_result_from_json(const std::string& text) {
  const char* what = "baseline result";
  const Json object = parse(text, what);
  BaselineResult result;
  const auto transform = field<std::vector<double>>(object, "transform", what);
  if (transform.size() != 16) throw Error(std::string(what) + ": field 'transform' must hold 16 numbers");
  for (int row = 0; row < 4; ++row)
    for (int column = 0; column < 4; ++column) result.transform.matrix()(row, column) = transform[row * 4 + column];
  result.solved = field<bool>(object, "solved", what);
  result.message = field<std::string>(object, "message", what);
  result.timings_ms = field<std::map<std::string, double>>(object, "timings_ms", what);
  result.cpu_ms = field<double>(object, "cpu_ms", what);
  result.counts = field<std::map<std::string, double>>(object, "counts", what);
  return result;
}

}  // namespace quadrix
