// A synthetic loop-closure benchmark in the paper's distance bins: street layouts driven twice, the
// second pass in the opposite direction (or, for forward-looking sensors, the same one) with other
// parked cars and pedestrians, and pairs between
// the passes binned by the distance between the scans (paper §"Loop closure", KITTI bins 0-10,
// 10-20, 20-30 m). `quadrix bench --pairs DIR/pairs.tsv` runs it; its summary reports success per bin.
#pragma once

#include "experiments/synthetic/scanner_simulator.h"
#include "experiments/synthetic/synthetic_scene.h"

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace quadrix {

/// Options of write_loop_closure_set.
struct LoopClosureSetOptions {
  std::uint64_t first_seed = 1;     ///< street layouts first_seed, first_seed + 1, ... (make_street_scene seeds)
  int streets = 6;                  ///< how many street layouts
  SensorModel sensor = sensor_preset("hdl64");  ///< the sensor of every scan (its name goes to pairs.tsv), or of the first pass's (the targets') when source_sensor is set
  std::optional<SensorModel> source_sensor;     ///< the second pass's sensor (the sources'), for a cross-sensor set; pairs.tsv then names "source->target"
  double scan_spacing = 3.0;        ///< metres between consecutive scans of a pass
  int pairs_per_bin = 20;           ///< pairs drawn per street and bin (fewer when a bin has fewer)
  std::vector<std::pair<double, double>> bins{{0.0, 10.0}, {10.0, 20.0}, {20.0, 30.0}};  ///< [min, max) distance bins, m
  StreetOptions street;             ///< options of every street layout (solid or porous foliage)
  bool same_direction = false;      ///< the second pass drives the first one's way (make_street_pass pass 3): a forward-looking sensor shares no view with a pass the other way
};

/// One pair of the set, as written to pairs.tsv.
struct LoopClosureSetPair {
  std::string id;          ///< street<seed>_p2_<source scan>_to_p1_<target scan>
  std::string source;      ///< cloud of the second pass, relative to the set's folder
  std::string target;      ///< cloud of the first pass, relative to the set's folder
  std::string truth;       ///< file of the transform mapping source points into the target frame
  std::string bin;         ///< distance bin name, e.g. "20-30"
  double distance = 0.0;   ///< distance between the two sensors, m
  double rotation = 0.0;   ///< rotation between the two scans, degrees
};

/// Simulates both passes of every street and writes DIR/street_<seed>/pass_<k>/scan_NNN.ply (labelled
/// clouds in the sensor frame), the ground-truth transforms of the drawn pairs, and DIR/pairs.tsv in
/// the shared data folder's format with the bin as each pair's kind. Deterministic for given options.
/// Throws quadrix::Error on bad options (no streets, an empty or negative bin, pairs_per_bin < 1).
std::vector<LoopClosureSetPair> write_loop_closure_set(const std::string& directory, const LoopClosureSetOptions& options);

}  // namespace quadrix
