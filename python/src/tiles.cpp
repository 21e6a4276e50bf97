// quadrix.model_tiles, quadrix.merge_tiles and quadrix.model_tiled: tile-by-tile modelling of large
// static scans (fitting/tiled_modelling.h), in one process or as tasks on a Dask distributed
// cluster (`client=`), the merge where the call was made.
#include "bindings.h"

#include "estimation/registration_config.h"
#include "fitting/extraction.h"
#include "fitting/tiled_modelling.h"
#include "geometry/error.h"

#include <pybind11/eval.h>
#include <pybind11/stl.h>

#include <filesystem>
#include <memory>

namespace quadrix::python {

namespace {

// The static-scan extraction of `preset`; ValueError for a LiDAR preset.
ExtractionOptions static_extraction(const std::string& preset) {
  ExtractionOptions extraction = extraction_preset(preset);
  if (!extraction.static_scan) throw Error("tiles: preset '" + preset + "' is not a static scan's (use monument)");
  return extraction;
}

TilingOptions tiling_of(int tile, int tiles, double tile_size, double margin) {
  TilingOptions tiling;
  tiling.group = tile;
  tiling.groups = tiles;
  tiling.tile_size = tile_size;
  tiling.margin = margin;
  return tiling;
}

std::shared_ptr<Model> model_of(ModellingResult&& result) {
  auto model = std::make_shared<Model>();
  model->model = std::move(result.model);
  model->status = modelling_status_name(result.status);
  model->message = std::move(result.message);
  return model;
}

ModellingOptions static_modelling(const std::string& preset, const py::object& fitter) {
  ModellingOptions modelling = registration_preset(preset).modelling;
  if (!fitter.is_none()) modelling.fitter = fitter.cast<std::string>();
  make_quadric_fitter(modelling.fitter);  // an Error listing the fitters for an unknown name
  return modelling;
}

// The points of `cloud` as a chunk source: a file path is streamed from disk chunk by chunk (never
// held whole; formats that cannot be streamed are read whole), a Cloud or an array is served from
// memory in its file's frame. `holder` and `points` keep what the source refers to alive; `units`
// is the coordinates' length unit (coordinate_units: a LAS file may declare feet).
std::unique_ptr<PointChunkSource> chunk_source(const py::object& cloud, std::shared_ptr<Cloud>& holder, const PointCloud*& points,
                                               CoordinateUnits& units) {
  if (py::isinstance<py::str>(cloud) || py::hasattr(cloud, "__fspath__")) {
    const std::string path = path_from_object(cloud);
    try {
      auto source = std::make_unique<FileChunkSource>(std::vector<std::string>{path});
      units = coordinate_units(path);
      return source;
    } catch (const Error&) {
      // not streamable (ascii PLY, CSV, NPY) or bad: the whole read reads it or names the problem
    }
  }
  points = &cloud_from_object(cloud, "cloud", holder, nullptr, LocalOrigin::Auto);
  units = holder->units;
  return std::make_unique<MatrixChunkSource>(points->positions, "cloud", points->local_origin);
}

// Parts are joined in metres, whatever files they came from: tile groups of a survey in another
// unit are refused with the reason (model_tiled without a client models it in one process).
void require_metres_for_parts(const CoordinateUnits& units, const std::string& name) {
  if (units.metres_per_unit != 1.0)
    throw Error(name + ": coordinates in " + units.name + " are modelled in metres; tile groups (model_tiles, model_tiled " +
                "with client=) of a survey in another unit are not joined: use model_tiled without client=");
}

}  // namespace

void bind_tiles(py::module_& module) {
  module.def(
      "model_tiles",
      [](const py::object& cloud, int tile, int tiles, const std::string& preset, double tile_size, double margin) {
        std::shared_ptr<Cloud> holder;
        const PointCloud* points = nullptr;
        CoordinateUnits units;
        const std::unique_ptr<PointChunkSource> source = chunk_source(cloud, holder, points, units);
        require_metres_for_parts(units, source->name());
        const ExtractionOptions extraction = static_extraction(preset);
        std::string bytes;
        {
          py::gil_scoped_release release;
          bytes = partial_model_to_bytes(model_tile_group(*source, extraction, tiling_of(tile, tiles, tile_size, margin)));
        }
        return py::bytes(bytes);
      },
      py::arg("cloud"), py::arg("tile") = 0, py::arg("tiles") = 1, py::arg("preset") = "monument", py::arg("tile_size") = 0.0,
      py::arg("margin") = 2.0, R"doc(
Passes 1 and 2 of tile-by-tile modelling for tile group ``tile`` (0-based) of ``tiles``: the shape
pieces of those tiles as bytes (the partial model ``quadrix model --tile i/n`` writes), for ``merge_tiles``.

cloud: a Cloud, an (N, 3) array or a file path (a path is what Dask workers are given; it is read
chunk by chunk, never whole, when its format can be streamed).
preset: a static-scan preset (monument). tile_size: tile edge in metres (0: tiles split by point count to fit a 2 GiB
memory budget). margin: overlap modelled around each tile, metres.
)doc");

  module.def(
      "merge_tiles",
      [](const std::vector<py::bytes>& parts, const std::string& preset, const py::object& fitter) {
        const ExtractionOptions extraction = static_extraction(preset);
        const ModellingOptions modelling = static_modelling(preset, fitter);
        std::vector<std::string> raw;
        for (const py::bytes& part : parts) raw.push_back(std::string(part));
        py::gil_scoped_release release;
        std::vector<PartialModel> models;
        for (std::size_t i = 0; i < raw.size(); ++i) models.push_back(partial_model_from_bytes(raw[i], "part " + std::to_string(i)));
        return model_of(merge_partial_models(models, extraction, modelling));
      },
      py::arg("parts"), py::arg("preset") = "monument", py::arg("fitter") = py::none(), R"doc(
Pass 3 of tile-by-tile modelling: joins the parts of ``model_tiles`` (every group once), merges the
primitives cut by tile borders and fits one quadric each. Returns a quadrix.Model with every
primitive found (no per-class cap, no augmented points). ValueError for a missing or repeated part.
)doc");

  // Dask pickles a task's function; a pybind11 function is not picklable, a Python function of
  // this module is (by reference: workers import quadrix and look it up).
  py::exec(R"(
def _model_tiles_task(*arguments):
    import quadrix
    return quadrix.model_tiles(*arguments)
)", module.attr("__dict__"));

  module.def(
      "model_tiled",
      [module](const py::object& cloud, const std::string& preset, double tile_size, double margin, const py::object& client,
               const py::object& tiles, const py::object& fitter) {
        if (client.is_none()) {
          std::shared_ptr<Cloud> holder;
          const PointCloud* points = nullptr;
          CoordinateUnits units;
          const std::unique_ptr<PointChunkSource> source = chunk_source(cloud, holder, points, units);
          const ExtractionOptions extraction = static_extraction(preset);
          const ModellingOptions modelling = static_modelling(preset, fitter);
          py::gil_scoped_release release;
          // Another unit (a LAS file in feet): tiled and modelled in metres, returned in the file's unit.
          ScaledChunkSource metric(*source, units.metres_per_unit);
          const bool rescaled = units.metres_per_unit != 1.0;
          ModellingResult result = model_tiled(rescaled ? static_cast<PointChunkSource&>(metric) : *source, extraction, modelling,
                                               tiling_of(0, 1, tile_size, margin));
          if (rescaled) result.model = scaled(std::move(result.model), 1.0 / units.metres_per_unit);
          return model_of(std::move(result));
        }
        if (!py::isinstance<py::str>(cloud) && !py::hasattr(cloud, "__fspath__"))
          throw Error("model_tiled: with client=, cloud must be a file path the workers can read");
        const std::string path = std::filesystem::absolute(path_from_object(cloud)).string();
        require_metres_for_parts(coordinate_units(path), path);
        int groups = 0;
        if (tiles.is_none()) {
          const py::dict workers = client.attr("scheduler_info")()["workers"];
          groups = std::max<int>(1, static_cast<int>(2 * py::len(workers)));
        } else {
          groups = tiles.cast<int>();
        }
        if (groups < 1) throw Error("model_tiled: tiles must be at least 1");
        py::list futures;
        for (int group = 0; group < groups; ++group)
          futures.append(client.attr("submit")(module.attr("_model_tiles_task"), path, group, groups, preset, tile_size, margin,
                                               py::arg("pure") = false));
        const py::list parts = client.attr("gather")(futures);
        return module.attr("merge_tiles")(parts, preset, fitter).cast<std::shared_ptr<Model>>();
      },
      py::arg("cloud"), py::arg("preset") = "monument", py::arg("tile_size") = 0.0, py::arg("margin") = 2.0,
      py::arg("client") = py::none(), py::arg("tiles") = py::none(), py::arg("fitter") = py::none(), R"doc(
Models a large static scan tile by tile (``quadrix model --tile-size``): bins the points into tiles,
models each tile with a margin of overlap, merges the primitives cut by tile borders. Returns a
quadrix.Model.

client: a dask.distributed Client: the survey is split into ``tiles`` groups of tiles (default two
per worker), each modelled by ``model_tiles`` as one task on the cluster (``cloud`` must then be a
file path every worker can read), and merged here. Same model whatever the split.
A LAS file in another length unit (feet) is tiled and modelled in metres and returned in its unit,
in one process: with ``client=`` (and in ``model_tiles``) it is refused with the reason.
)doc");
}

}  // namespace quadrix::python
