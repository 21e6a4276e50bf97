// The mapping pipeline (mapping.h): model every scan once, odometry, loop candidates, loop edges from
// the registration pipeline, the pose graph.
#include "estimation/mapping.h"

#include "estimation/registration_config.h"
#include "fitting/scene_modelling.h"
#include "geometry/constants.h"
#include "geometry/error.h"
#include "geometry/io.h"
#include "geometry/las.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <cmath>
#include <cstdio>
#include <list>
#include <limits>
#include <mutex>
#include <numeric>
#include <set>

namespace quadrix {
namespace {

using Clock = std::chrono::steady_clock;

double elapsed_ms(Clock::time_point start) { return std::chrono::duration<double, std::milli>(Clock::now() - start).count(); }

constexpr double kDegrees = kPi / 180.0;  // radians in a degree

/// Rings and sectors of the bird's-eye place descriptor.
constexpr int kDescriptorRings = 20;
constexpr int kDescriptorSectors = 60;
constexpr double kDescriptorRingWidth = 2.0;  // m: 20 rings reach 40 m
constexpr int kDescriptorFirstRing = 2;       // rings within 4 m hold the platform and the points every sensor misses under it
/// The height band above the ground every sensor sees at every range of the grid: HDL-64E looks
/// 2 deg up, VLP-16 15 deg down, so the band between a car's sill and roof is in all their views.
constexpr double kBandLow = 0.5, kBandHigh = 2.5;  // m above the ground
/// Fewer sectors seen by both scans than this: no comparison (a Livox's 70 deg field of view is 12).
constexpr int kMinimumCommonSectors = 6;

}  // namespace

Eigen::VectorXd place_descriptor(const PointCloud& cloud, const Eigen::Vector3d& up) {
  const Eigen::Vector3d axis = up.normalized();
  const Eigen::Vector3d east = (std::abs(axis.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY()).cross(axis).normalized();
  const Eigen::Vector3d north = axis.cross(east);
  // The ground's height: the 5th percentile of the heights 3-20 m around the sensor.
  std::vector<double> heights;
  for (std::size_t index = 0; index < cloud.size(); ++index) {
    const Eigen::Vector3d point = cloud.point(index);
    const double range = std::hypot(point.dot(east), point.dot(north));
    if (range > 3.0 && range < 20.0) heights.push_back(point.dot(axis));
  }
  double ground = 0.0;
  if (!heights.empty()) {
    const auto fifth = heights.begin() + static_cast<std::ptrdiff_t>(heights.size() / 20);
    std::nth_element(heights.begin(), fifth, heights.end());
    ground = *fifth;
  }
  Eigen::VectorXd descriptor = Eigen::VectorXd::Zero(2 * kDescriptorSectors);
  std::vector<std::uint32_t> occupied(kDescriptorSectors, 0);
  for (std::size_t index = 0; index < cloud.size(); ++index) {
    const Eigen::Vector3d point = cloud.point(index);
    const double x = point.dot(east), y = point.dot(north);
    const double range = std::hypot(x, y);
    const int ring = static_cast<int>(range / kDescriptorRingWidth);
    if (ring < kDescriptorFirstRing || ring >= kDescriptorRings) continue;
    const int sector = std::min(kDescriptorSectors - 1, static_cast<int>((std::atan2(y, x) + kPi) / (2.0 * kPi) * kDescriptorSectors));
    descriptor(kDescriptorSectors + sector) = 1.0;  // seen
    const double height = point.dot(axis) - ground;
    if (height >= kBandLow && height <= kBandHigh) occupied[static_cast<std::size_t>(sector)] |= 1u << (ring - kDescriptorFirstRing);
  }
  for (int sector = 0; sector < kDescriptorSectors; ++sector) descriptor(sector) = static_cast<double>(occupied[static_cast<std::size_t>(sector)]);
  return descriptor;
}

double place_distance(const Eigen::VectorXd& first, const Eigen::VectorXd& second) {
  if (first.size() != 2 * kDescriptorSectors || second.size() != 2 * kDescriptorSectors)
    throw Error("place_distance: descriptors of " + std::to_string(2 * kDescriptorSectors) + " values expected, got " +
                std::to_string(first.size()) + " and " + std::to_string(second.size()));
  std::array<std::uint32_t, kDescriptorSectors> a{}, b{};
  std::array<bool, kDescriptorSectors> a_seen{}, b_seen{};
  for (int sector = 0; sector < kDescriptorSectors; ++sector) {
    a[sector] = static_cast<std::uint32_t>(first(sector));
    b[sector] = static_cast<std::uint32_t>(second(sector));
    a_seen[sector] = first(kDescriptorSectors + sector) > 0.5;
    b_seen[sector] = second(kDescriptorSectors + sector) > 0.5;
  }
  double best = std::numeric_limits<double>::infinity();
  for (int shift = 0; shift < kDescriptorSectors; ++shift) {
    double similarity = 0.0;
    int common = 0;
    for (int sector = 0; sector < kDescriptorSectors; ++sector) {
      const int other = (sector + shift) % kDescriptorSectors;
      if (!a_seen[sector] || !b_seen[other]) continue;
      ++common;
      const int a_count = __builtin_popcount(a[sector]), b_count = __builtin_popcount(b[other]);
      if (a_count > 0 && b_count > 0) similarity += __builtin_popcount(a[sector] & b[other]) / std::sqrt(static_cast<double>(a_count) * b_count);
    }
    if (common >= kMinimumCommonSectors) best = std::min(best, 1.0 - similarity / common);
  }
  return best;
}

namespace {

/// A few clouds kept in memory for verification, least recently used dropped first.
class CloudCache {
 public:
  CloudCache(const ScanList& list, std::size_t capacity) : list_(list), capacity_(std::max<std::size_t>(2, capacity)) {}

  std::shared_ptr<const PointCloud> get(std::size_t scan) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      for (auto it = entries_.begin(); it != entries_.end(); ++it)
        if (it->first == scan) {
          entries_.splice(entries_.begin(), entries_, it);
          return it->second;
        }
    }
    auto cloud = std::make_shared<const PointCloud>(read_point_cloud(list_.scans[scan].path));
    std::lock_guard<std::mutex> lock(mutex_);
    entries_.emplace_front(scan, cloud);
    while (entries_.size() > capacity_) entries_.pop_back();
    return cloud;
  }

 private:
  const ScanList& list_;
  std::size_t capacity_;
  std::mutex mutex_;
  std::list<std::pair<std::size_t, std::shared_ptr<const PointCloud>>> entries_;
};

/// What modelling keeps of one scan.
struct ScanModel {
  SceneModel model;                 ///< as model_scene built it
  std::optional<SceneModel> augmented;  ///< the same with augmented points, when model_scene gave none (augment_other_side's copy, made once)
  RegistrationOptions options;      ///< its preset's options (auto: resolved on this scan); source_extraction is what it was modelled with
  Eigen::VectorXd descriptor;       ///< place_descriptor
  std::string preset;               ///< preset name or the auto choice's reasons
  double modelling_ms = 0.0;        ///< model_scene time
};

Information6d diagonal_information(double rotation_sigma, double translation_sigma) {
  Information6d information = Information6d::Zero();
  information.diagonal().head<3>().setConstant(1.0 / (rotation_sigma * rotation_sigma));
  information.diagonal().tail<3>().setConstant(1.0 / (translation_sigma * translation_sigma));
  return information;
}

/// The information of an odometry step of length `distance`: sigmas grow with the distance travelled.
Information6d odometry_information(double distance, const MapOptions& options) {
  const double translation = std::max(options.odometry_translation_floor, options.odometry_translation_drift * distance);
  const double rotation =
      std::max(options.odometry_rotation_floor_degrees, options.odometry_rotation_drift_degrees * distance) * kDegrees;
  return diagonal_information(rotation, translation);
}

double median_range(const PointCloud& cloud) {
  std::vector<float> ranges(cloud.size());
  for (std::size_t index = 0; index < cloud.size(); ++index) ranges[index] = cloud.positions.col(static_cast<Eigen::Index>(index)).norm();
  const auto middle = ranges.begin() + static_cast<std::ptrdiff_t>(ranges.size() / 2);
  std::nth_element(ranges.begin(), middle, ranges.end());
  return *middle;
}

/// The registration options of one scan: the fixed ones, or its preset (`auto` measured on the
/// cloud); `preset` receives the name or auto's reasons.
RegistrationOptions scan_registration_options(const PointCloud& cloud, const MapOptions& options, std::string& preset) {
  if (options.registration_options) {
    preset = "fixed options";
    return *options.registration_options;
  }
  std::string notes;
  RegistrationOptions resolved = resolve_registration_side(options.preset, cloud, "scan", &notes);
  preset = notes.empty() ? options.preset : notes;
  return resolved;
}

/// Models scan `index` of `list`; errors name the row.
ScanModel model_one_scan(const ScanList& list, std::size_t index, const MapOptions& options) {
  const ScanEntry& entry = list.scans[index];
  const std::string where = list.source + ": row " + std::to_string(entry.row) + " (" + entry.scan + "): ";
  PointCloud cloud;
  try {
    require_metres(coordinate_units(entry.path), entry.path, "a map");
    cloud = read_point_cloud(entry.path);
  } catch (const Error& error) {
    throw Error(where + error.what());
  }
  if (cloud.size() < 100) throw Error(where + "the scan holds " + std::to_string(cloud.size()) + " points; at least 100 are needed");
  const double range = median_range(cloud);
  if (range > options.maximum_median_range)
    throw Error(where + "the median point lies " + std::to_string(static_cast<long long>(range)) +
                " m from the sensor (more than " + std::to_string(static_cast<long long>(options.maximum_median_range)) +
                " m): expected metres; is the scan in millimetres?");
  ScanModel scan;
  const RegistrationOptions resolved = scan_registration_options(cloud, options, scan.preset);
  scan.options = resolved;
  const Clock::time_point start = Clock::now();
  ModellingResult modelling = model_scene(cloud, resolved.source_extraction, resolved.modelling);
  if (modelling.model.augmented_count() == 0 && resolved.correspondences.match_augmented_points) {
    ModellingResult augmented = modelling;
    augment_scene_model(cloud.positions.cast<double>(), augmented, resolved.modelling);
    if (augmented.model.augmented_count() > 0) scan.augmented = std::move(augmented.model);
  }
  scan.modelling_ms = elapsed_ms(start);
  scan.model = std::move(modelling.model);
  scan.descriptor = place_descriptor(cloud, resolved.source_extraction.up);
  return scan;
}

/// Models every scan once, in parallel; errors name the row (the first failing one).
std::vector<ScanModel> model_scans(const ScanList& list, const MapOptions& options, const MapProgress& progress) {
  std::vector<ScanModel> models(list.scans.size());
  std::mutex mutex;
  std::size_t done = 0;
  std::string first_error;
  std::size_t first_error_scan = list.scans.size();
  tbb::parallel_for(std::size_t{0}, list.scans.size(), [&](std::size_t index) {
    try {
      models[index] = model_one_scan(list, index, options);
    } catch (const Error& error) {
      std::lock_guard<std::mutex> lock(mutex);
      if (index < first_error_scan) {
        first_error_scan = index;
        first_error = error.what();
      }
      return;
    }
    std::lock_guard<std::mutex> lock(mutex);
    ++done;
    if (progress) progress("scans modelled", done, list.scans.size());
  });
  if (first_error_scan < list.scans.size()) throw Error(first_error);
  return models;
}

/// What a worker returns of a scan model (everything but the options, which follow from the cloud).
MappedScan mapped_of(const ScanModel& scan) {
  MappedScan mapped;
  mapped.model = scan.model;
  mapped.augmented = scan.augmented;
  mapped.descriptor = scan.descriptor;
  mapped.preset = scan.preset;
  mapped.modelling_ms = scan.modelling_ms;
  return mapped;
}

/// The cached model of a scan from what a worker returned (`options`: its registration options when known).
ScanModel scan_model_of(MappedScan mapped, const RegistrationOptions& options = {}) {
  ScanModel scan;
  scan.model = std::move(mapped.model);
  scan.augmented = std::move(mapped.augmented);
  scan.options = options;
  scan.descriptor = std::move(mapped.descriptor);
  scan.preset = std::move(mapped.preset);
  scan.modelling_ms = mapped.modelling_ms;
  return scan;
}

/// Registration of one pair from the cached models, verified on the clouds.
MapEdge register_pair(std::size_t from, std::size_t to, MapEdgeKind kind, const std::vector<ScanModel>& models,
                      CloudCache& clouds, const MapOptions& options) {
  const Clock::time_point start = Clock::now();
  // The source's options with the target's extraction, as `quadrix register` resolves a pair.
  RegistrationOptions registration = models[from].options;
  registration.target_extraction = models[to].options.source_extraction;
  const SceneModel* source = &models[from].model;
  const SceneModel* target = &models[to].model;
  if (registration.correspondences.match_augmented_points) {
    if (lacks_augmentation_of(*source, *target) && models[from].augmented) source = &*models[from].augmented;
    else if (lacks_augmentation_of(*target, *source) && models[to].augmented) target = &*models[to].augmented;
  }
  RegistrationResult result = register_models(*source, *target, registration);
  {
    const std::shared_ptr<const PointCloud> source_cloud = clouds.get(from);
    const std::shared_ptr<const PointCloud> target_cloud = clouds.get(to);
    verify_registration(result, *source_cloud, *target_cloud, registration);
  }
  MapEdge edge;
  edge.from = from;
  edge.to = to;
  edge.kind = kind;
  edge.status = registration_status_name(result.status);
  edge.transform = result.transform;
  edge.overlap = result.overlap ? result.overlap->transformed : 0.0;
  edge.inliers = result.correspondences.size();
  edge.inlier_rmse = result.inlier_rmse;
  edge.registration_information = result.information;
  edge.information = diagonal_information(options.loop_rotation_sigma_degrees * kDegrees, options.loop_translation_sigma);
  if (options.loop_information_from_registration && edge.inliers > 0) {
    // H perturbs the answer on the left about the target's origin; the graph's error turns about the
    // source's position p, e = A δ with A = [[I, 0], [-[p]x, I]]: Ω = A^-T H A^-1.
    const Information6d moved = information_about_shifted_origin(result.information, -result.transform.translation());
    edge.information = options.loop_information_scale / static_cast<double>(edge.inliers) * 0.5 * (moved + moved.transpose());
  }
  edge.note = result.status == RegistrationStatus::Ok ? "" : result.message;
  edge.registration_ms = elapsed_ms(start);
  return edge;
}

/// Odometry of scan `from` onto the previous scan `to`: point-to-plane ICP from `guess` (the previous
/// motion) verified by the registration's checks (RegistrationOptions::local_only); when that is not
/// `ok`, global registration from the models (register_pair).
MapEdge register_consecutive(std::size_t from, std::size_t to, const Eigen::Isometry3d& guess, const std::vector<ScanModel>& models,
                             CloudCache& clouds, const MapOptions& options) {
  const Clock::time_point start = Clock::now();
  RegistrationOptions registration = models[from].options;
  registration.target_extraction = models[to].options.source_extraction;
  registration.initial_guess = guess;
  registration.local_only = true;
  ModellingResult source_modelling, target_modelling;  // the cached models; the checks crop the clouds themselves
  source_modelling.model = models[from].model;
  target_modelling.model = models[to].model;
  RegistrationResult result;
  {
    const std::shared_ptr<const PointCloud> source_cloud = clouds.get(from);
    const std::shared_ptr<const PointCloud> target_cloud = clouds.get(to);
    result = register_modelled_clouds({source_cloud.get(), &source_modelling, 0.0, false},
                                      {target_cloud.get(), &target_modelling, 0.0, false}, registration);
  }
  if (result.status != RegistrationStatus::Ok) {
    MapEdge edge = register_pair(from, to, MapEdgeKind::Odometry, models, clouds, options);
    edge.note = "local alignment " + std::string(registration_status_name(result.status)) + ", global registration used" +
                (edge.note.empty() ? "" : "; " + edge.note);
    edge.registration_ms = elapsed_ms(start);
    return edge;
  }
  MapEdge edge;
  edge.from = from;
  edge.to = to;
  edge.kind = MapEdgeKind::Odometry;
  edge.status = registration_status_name(result.status);
  edge.transform = result.transform;
  edge.overlap = result.overlap ? result.overlap->transformed : 0.0;
  edge.note = "local alignment from the previous motion";
  edge.registration_ms = elapsed_ms(start);
  return edge;
}

/// One requested registration from the cached models: consecutive scans from their local guess,
/// anything else globally.
MapEdge register_request(const MapPairRequest& pair, const std::vector<ScanModel>& models, CloudCache& clouds,
                         const MapOptions& options) {
  if (pair.local_guess) return register_consecutive(pair.from, pair.to, *pair.local_guess, models, clouds, options);
  return register_pair(pair.from, pair.to, pair.kind, models, clouds, options);
}

/// Distance travelled along a session's odometry from scan `first` to scan `last` (indices into poses).
std::vector<double> path_lengths(const std::vector<Eigen::Isometry3d>& poses, std::size_t begin, std::size_t end) {
  std::vector<double> length(end - begin, 0.0);
  for (std::size_t index = begin + 1; index < end; ++index)
    length[index - begin] = length[index - begin - 1] + (poses[index].translation() - poses[index - 1].translation()).norm();
  return length;
}

/// Of the scans `near` (distance, scan), the nearest at most `count`, any two at least `spacing`
/// apart along their path (`travelled(scan)`): in effect the nearest scan of each earlier pass.
template <typename Travelled>
std::vector<std::size_t> nearest_spaced(std::vector<std::pair<double, std::size_t>> near, std::size_t count, double spacing,
                                        const Travelled& travelled) {
  std::sort(near.begin(), near.end());
  std::vector<std::size_t> chosen;
  for (const auto& [distance, other] : near) {
    if (chosen.size() >= count) break;
    bool spaced = true;
    for (std::size_t kept : chosen)
      if (std::abs(travelled(kept) - travelled(other)) < spacing) spaced = false;
    if (spaced) chosen.push_back(other);
  }
  return chosen;
}

/// How far a measured relative pose departs from a predicted one: the angle of the rotation between
/// them, degrees, and the distance between their translations, m.
struct PoseDeparture {
  double degrees = 0.0;
  double metres = 0.0;
};

PoseDeparture departure_between(const Eigen::Isometry3d& measured, const Eigen::Isometry3d& predicted) {
  return {Eigen::AngleAxisd(predicted.linear().transpose() * measured.linear()).angle() / kDegrees,
          (measured.translation() - predicted.translation()).norm()};
}

/// How many sessions (index ranges) have their first scan in the map frame.
std::size_t joined_sessions(const std::vector<bool>& in_map_frame, const std::vector<std::pair<std::size_t, std::size_t>>& sessions) {
  std::size_t joined = 0;
  for (const auto& session : sessions) joined += in_map_frame[session.first];
  return joined;
}

/// One round of loop candidates across sessions in the joint map frame (LIO-SAM's radius search,
/// as within a session): for each scan of a placed session and each earlier placed session it has
/// no used edge to yet, the nearest scans of that session within MapOptions::joint_radius of its
/// current map position, one a pass (nearest_spaced). Records them in result.joint_candidates and
/// `summary.candidates`; returns the pairs not registered before, added to `registered` (smaller,
/// larger scan index).
std::vector<MapPairRequest> joint_frame_requests(MapResult& result, const std::vector<std::pair<std::size_t, std::size_t>>& sessions,
                                                 const std::vector<std::size_t>& session_of, const std::vector<double>& travelled_at,
                                                 const MapOptions& options, std::set<std::pair<std::size_t, std::size_t>>& registered,
                                                 JointRound& summary) {
  std::set<std::pair<std::size_t, std::size_t>> linked;  // (scan, session) with a used edge between them
  for (const MapEdge& edge : result.edges)
    if (edge.used && edge.across_sessions) linked.emplace(edge.from, session_of[edge.to]), linked.emplace(edge.to, session_of[edge.from]);
  std::vector<MapPairRequest> requests;
  for (std::size_t session = 1; session < sessions.size(); ++session) {
    if (!result.in_map_frame[sessions[session].first]) continue;
    for (std::size_t index = sessions[session].first; index < sessions[session].second; ++index)
      for (std::size_t earlier = 0; earlier < session; ++earlier) {
        const auto [begin, end] = sessions[earlier];
        if (!result.in_map_frame[begin] || linked.count({index, earlier})) continue;
        std::vector<std::pair<double, std::size_t>> near;
        for (std::size_t other = begin; other < end; ++other) {
          const double distance = (result.poses[other].translation() - result.poses[index].translation()).norm();
          if (distance <= options.joint_radius) near.emplace_back(distance, other);
        }
        for (std::size_t other : nearest_spaced(std::move(near), options.candidates_per_scan, options.minimum_candidate_spacing,
                                                [&travelled_at](std::size_t scan) { return travelled_at[scan]; })) {
          ++summary.candidates;
          result.joint_candidates[index].push_back(other);
          if (!registered.emplace(std::min(index, other), std::max(index, other)).second) continue;
          MapPairRequest request;
          request.from = index;
          request.to = other;
          requests.push_back(request);
        }
      }
  }
  return requests;
}

}  // namespace

bool consistent_with_odometry(const Eigen::Isometry3d& measured, const Eigen::Isometry3d& predicted, double path,
                              const MapOptions& options, std::string* why) {
  const double k = options.odometry_gate_sigmas;
  if (!(k > 0.0)) return true;
  const double rotation_sigma = std::max(options.odometry_rotation_floor_degrees, options.odometry_rotation_drift_degrees * path);
  const double rotation_limit = k * rotation_sigma;
  const auto [rotation, translation] = departure_between(measured, predicted);
  // The heading error that moved the far scan is the rotation the edge departs by (if it is right),
  // give or take k rotation floors: its lever arm over the path bounds the translation's departure.
  const double lever_degrees = std::min(rotation + k * options.odometry_rotation_floor_degrees, 90.0);
  const double translation_limit = k * std::max(options.odometry_translation_floor, options.odometry_translation_drift * path) +
                                   path * std::sin(lever_degrees * kDegrees);
  if ((rotation_limit >= 180.0 || rotation <= rotation_limit) && translation <= translation_limit) return true;
  if (why != nullptr) {
    char text[256];
    std::snprintf(text, sizeof(text),
                  "departs from the odometry by %.1f deg and %.2f m over %.1f m of path (limits %.1f deg, %.2f m)", rotation,
                  translation, path, rotation_limit, translation_limit);
    *why = text;
  }
  return false;
}

std::size_t arbitrate_ambiguous_edges(std::vector<MapEdge>& edges, const std::vector<Eigen::Isometry3d>& initial, const MapOptions& options) {
  std::vector<PoseGraphEdge> sure;
  std::vector<std::size_t> arbitrated;
  for (std::size_t index = 0; index < edges.size(); ++index) {
    const MapEdge& edge = edges[index];
    if (!edge.used) continue;
    const bool loop = edge.kind == MapEdgeKind::Loop;
    if (loop && !edge.across_sessions && edge.status == "ambiguous") arbitrated.push_back(index);
    else sure.push_back({edge.from, edge.to, edge.transform, edge.information, loop && edge.status == "ok", loop && edge.status != "ok"});
  }
  if (arbitrated.empty()) return 0;
  std::vector<Eigen::Isometry3d> poses = initial;
  optimise_pose_graph(poses, sure, options.graph);
  std::size_t refused = 0;
  for (std::size_t index : arbitrated) {
    MapEdge& edge = edges[index];
    const auto [rotation, translation] = departure_between(edge.transform, poses[edge.to].inverse() * poses[edge.from]);
    if (rotation <= options.ambiguous_gate_rotation_degrees && translation <= options.ambiguous_gate_translation) continue;
    edge.used = false;
    ++refused;
    char text[200];
    std::snprintf(text, sizeof text, "not in the graph: departs from the map of the sure edges by %.1f deg and %.2f m (limits %.1f deg, %.2f m)",
                  rotation, translation, options.ambiguous_gate_rotation_degrees, options.ambiguous_gate_translation);
    edge.note = text + (edge.note.empty() ? std::string() : "; " + edge.note);
  }
  return refused;
}

MappedScan model_map_scan(const ScanList& list, std::size_t index, const MapOptions& options) {
  if (index >= list.scans.size()) throw Error(list.source + ": no scan " + std::to_string(index) + " in the list");
  return mapped_of(model_one_scan(list, index, options));
}

MapEdge register_map_pair(const ScanList& list, const MapPairRequest& pair, const MappedScan& from, const MappedScan& to,
                          const MapOptions& options) {
  if (pair.from >= list.scans.size() || pair.to >= list.scans.size() || pair.from == pair.to)
    throw Error(list.source + ": no pair " + std::to_string(pair.from) + " -> " + std::to_string(pair.to) + " in the list");
  // The two scans as a list of their own, so the pair's clouds are read once into a cache of two;
  // each side's options resolved from its cloud as modelling resolved them.
  ScanList two;
  two.source = list.source;
  two.scans = {list.scans[pair.from], list.scans[pair.to]};
  CloudCache clouds(two, 2);
  std::vector<ScanModel> models;
  std::string preset;
  models.push_back(scan_model_of(from, scan_registration_options(*clouds.get(0), options, preset)));
  models.push_back(scan_model_of(to, scan_registration_options(*clouds.get(1), options, preset)));
  MapPairRequest local = pair;
  local.from = 0;
  local.to = 1;
  MapEdge edge = register_request(local, models, clouds, options);
  edge.from = pair.from;
  edge.to = pair.to;
  return edge;
}

MapResult map_scans(const ScanList& input, const MapOptions& options, const MapProgress& progress, const MapExecutor& executor) {
  const Clock::time_point run_start = Clock::now();
  MapResult result;
  result.list = input;
  const ScanList& list = result.list;
  const std::size_t count = list.scans.size();
  if (count == 0) throw Error(list.source + ": no scans listed");
  if (!(options.information_tolerance > 1.0 && options.information_tolerance < 1e3))
    throw Error("option 'information_tolerance' must be above 1 and below 1000, got " + std::to_string(options.information_tolerance));
  if (!(options.outlier_threshold >= 0.0 && std::isfinite(options.outlier_threshold)))
    throw Error("option 'outlier_threshold' must be a finite number of at least 0, got " + std::to_string(options.outlier_threshold));
  if (!(options.place_vote_rotation_degrees > 0.0 && options.place_vote_translation > 0.0 && options.place_vote_ratio >= 1.0 &&
        std::isfinite(options.place_vote_rotation_degrees) && std::isfinite(options.place_vote_translation) &&
        std::isfinite(options.place_vote_ratio)))
    throw Error("options 'place_vote_rotation_degrees' and 'place_vote_translation' must be positive and 'place_vote_ratio' at least 1, got " +
                std::to_string(options.place_vote_rotation_degrees) + ", " + std::to_string(options.place_vote_translation) + ", " +
                std::to_string(options.place_vote_ratio));
  if (options.information_rounds > kMaximumInformationRounds)
    throw Error("option 'information_rounds' must be at most " + std::to_string(kMaximumInformationRounds) + ", got " +
                std::to_string(options.information_rounds));

  // Model every scan once (paper §"Quadric-based Scene Representation"); only the models stay in memory.
  Clock::time_point stage = Clock::now();
  std::vector<ScanModel> models;
  // A model made elsewhere comes without its registration options (they follow from the cloud the
  // worker read), so pairs of such models are registered by the executor too.
  if (executor.model && !executor.register_pairs)
    throw Error(list.source + ": a map executor that models the scans must also register the pairs");
  if (executor.model) {
    std::vector<std::size_t> every(count);
    std::iota(every.begin(), every.end(), std::size_t{0});
    std::vector<MappedScan> mapped = executor.model(every);
    if (mapped.size() != count)
      throw Error(list.source + ": the map executor returned " + std::to_string(mapped.size()) + " models for " +
                  std::to_string(count) + " scans");
    models.reserve(count);
    for (MappedScan& scan : mapped) models.push_back(scan_model_of(std::move(scan)));
    if (progress) progress("scans modelled", count, count);
  } else {
    models = model_scans(list, options, progress);
  }
  result.timings_ms["modelling"] = elapsed_ms(stage);
  for (const ScanModel& model : models) result.presets.push_back(model.preset);
  CloudCache clouds(list, options.cloud_cache);
  // Registers a batch of independent pairs: by the executor, or here in parallel from the cached
  // models; `each_done` after every pair (in this process) or after the batch (executor).
  const auto register_batch = [&](const std::vector<MapPairRequest>& pairs, const std::function<void()>& each_done) {
    std::vector<MapEdge> found;
    if (executor.register_pairs) {
      found = executor.register_pairs(pairs);
      if (found.size() != pairs.size())
        throw Error(list.source + ": the map executor returned " + std::to_string(found.size()) + " edges for " +
                    std::to_string(pairs.size()) + " pairs");
      for (std::size_t k = 0; k < pairs.size(); ++k) {
        if (found[k].from != pairs[k].from || found[k].to != pairs[k].to)
          throw Error(list.source + ": the map executor answered pair " + std::to_string(k) + " with another pair's edge");
        if (each_done) each_done();
      }
      return found;
    }
    found.resize(pairs.size());
    std::mutex mutex;
    tbb::parallel_for(std::size_t{0}, pairs.size(), [&](std::size_t k) {
      found[k] = register_request(pairs[k], models, clouds, options);
      std::lock_guard<std::mutex> lock(mutex);
      if (each_done) each_done();
    });
    return found;
  };

  // Sessions as index ranges.
  std::vector<std::pair<std::size_t, std::size_t>> sessions;
  for (std::size_t index = 0; index < count; ++index)
    if (index == 0 || list.scans[index].session != list.scans[index - 1].session) sessions.emplace_back(index, index + 1);
    else sessions.back().second = index + 1;
  std::vector<std::size_t> session_of(count);
  for (std::size_t session = 0; session < sessions.size(); ++session)
    for (std::size_t index = sessions[session].first; index < sessions[session].second; ++index) session_of[index] = session;

  // Odometry: given, or each scan registered onto the previous one.
  stage = Clock::now();
  result.odometry.assign(count, Eigen::Isometry3d::Identity());
  std::vector<MapEdge> odometry_edges;
  std::vector<std::pair<std::size_t, std::size_t>> consecutive;
  for (const auto& [begin, end] : sessions)
    for (std::size_t index = begin + 1; index < end; ++index) {
      if (list.scans[index].odometry) continue;
      consecutive.emplace_back(index, index - 1);
    }
  if (!consecutive.empty() && !options.register_consecutive)
    throw Error(list.source + ": session '" + list.scans[consecutive.front().first].session +
                "' has no odometry and registering consecutive scans is off");
  // In time order: each step starts from the previous one's motion (identity for the first).
  std::vector<MapEdge> registered(consecutive.size());
  for (std::size_t pair = 0; pair < consecutive.size(); ++pair) {
    const bool continues = pair > 0 && consecutive[pair - 1].first + 1 == consecutive[pair].first &&
                           session_of[consecutive[pair - 1].first] == session_of[consecutive[pair].first];
    const bool answered = continues && (registered[pair - 1].status == "ok" || registered[pair - 1].status == "ambiguous");
    MapPairRequest request;
    request.from = consecutive[pair].first;
    request.to = consecutive[pair].second;
    request.kind = MapEdgeKind::Odometry;
    request.local_guess = answered ? registered[pair - 1].transform : Eigen::Isometry3d::Identity();
    registered[pair] = std::move(register_batch({request}, {}).front());
    if (progress) progress("consecutive scans registered", pair + 1, consecutive.size());
  }
  std::size_t next_registered = 0;
  for (const auto& [begin, end] : sessions) {
    for (std::size_t index = begin; index < end; ++index) {
      if (list.scans[index].odometry) {
        result.odometry[index] = *list.scans[index].odometry;
        if (index == begin) continue;
        MapEdge edge;
        edge.from = index;
        edge.to = index - 1;
        edge.kind = MapEdgeKind::Odometry;
        edge.status = "given";
        edge.transform = result.odometry[index - 1].inverse() * result.odometry[index];
        odometry_edges.push_back(edge);
        continue;
      }
      if (index == begin) continue;  // the first scan of a session without odometry defines its frame
      MapEdge edge = registered[next_registered++];
      if (edge.status != "ok" && edge.status != "ambiguous") {
        // No answer: keep the previous motion (constant velocity), and say so.
        const Eigen::Isometry3d previous =
            index >= begin + 2 ? result.odometry[index - 2].inverse() * result.odometry[index - 1] : Eigen::Isometry3d::Identity();
        edge.transform = previous;
        edge.note = "registration " + edge.status + ": previous motion kept; " + edge.note;
      }
      result.odometry[index] = result.odometry[index - 1] * edge.transform;  // the edge maps this scan into the previous one's frame
      odometry_edges.push_back(edge);
    }
  }
  for (MapEdge& edge : odometry_edges) {
    const double distance = edge.transform.translation().norm();
    edge.information = odometry_information(distance, options);
    if (edge.status != "ok" && edge.status != "given") edge.information *= 0.01;  // a guessed or unsure step is 10x less certain
    edge.used = true;
  }
  result.timings_ms["odometry"] = elapsed_ms(stage);

  // Loop candidates within each session: LIO-SAM's radius search around the odometry position, the
  // radius growing with the distance travelled since the last accepted loop; positions re-anchored
  // at each accepted loop (the loop's pose of the current scan replaces the drifted one).
  std::vector<MapEdge> loop_edges;
  double candidates_ms = 0.0, registration_ms = 0.0;
  std::size_t registered_count = 0;
  const Clock::time_point loops_start = Clock::now();
  for (const auto& [begin, end] : sessions) {
    const std::vector<double> travelled = path_lengths(result.odometry, begin, end);
    Eigen::Isometry3d correction = Eigen::Isometry3d::Identity();
    std::vector<Eigen::Isometry3d> anchored(end - begin);
    double last_loop_at = 0.0;
    for (std::size_t index = begin; index < end; ++index) {
      const Clock::time_point candidates_start = Clock::now();
      anchored[index - begin] = correction * result.odometry[index];
      const double radius = std::min(options.maximum_loop_radius,
                                     options.loop_radius + options.loop_radius_growth * (travelled[index - begin] - last_loop_at));
      std::vector<std::pair<double, std::size_t>> near;
      for (std::size_t other = begin; other < index; ++other) {
        if (travelled[index - begin] - travelled[other - begin] < options.minimum_loop_travel) continue;
        const double distance = (anchored[other - begin].translation() - anchored[index - begin].translation()).norm();
        if (distance <= radius) near.emplace_back(distance, other);
      }
      const std::vector<std::size_t> chosen =
          nearest_spaced(std::move(near), options.candidates_per_scan, options.minimum_candidate_spacing,
                         [&travelled, first = begin](std::size_t scan) { return travelled[scan - first]; });
      candidates_ms += elapsed_ms(candidates_start);
      if (chosen.empty()) continue;
      result.candidates_within += chosen.size();
      const Clock::time_point registration_start = Clock::now();
      std::vector<MapPairRequest> requests(chosen.size());
      for (std::size_t k = 0; k < chosen.size(); ++k) requests[k].from = index, requests[k].to = chosen[k];
      std::vector<MapEdge> found = register_batch(requests, {});
      registration_ms += elapsed_ms(registration_start);
      registered_count += found.size();
      if (progress) progress("loop candidates registered", registered_count, 0);
      const MapEdge* best = nullptr;
      for (const MapEdge& edge : found)
        if (edge.status == "ok" && (best == nullptr || edge.overlap > best->overlap)) best = &edge;
      if (best != nullptr) {
        // The scan's pose as the loop says: T_index = T_other * Z^-1 ... Z maps index into other's frame.
        const Eigen::Isometry3d closed = anchored[best->to - begin] * best->transform;
        correction = closed * result.odometry[index].inverse();
        anchored[index - begin] = closed;
        last_loop_at = travelled[index - begin];
      }
      for (MapEdge& edge : found) loop_edges.push_back(std::move(edge));
    }
  }

  // Across sessions: rank the scans of earlier sessions by descriptor distance, register the best few.
  if (sessions.size() > 1) {
    const Clock::time_point candidates_start = Clock::now();
    std::vector<std::pair<std::size_t, std::size_t>> pairs;
    result.place_ranking.assign(count, {});
    std::vector<std::size_t> queries;
    for (std::size_t session = 1; session < sessions.size(); ++session)
      for (std::size_t index = sessions[session].first; index < sessions[session].second; index += std::max<std::size_t>(1, options.place_query_stride))
        queries.push_back(index);
    // Each query against every scan of the earlier sessions (a rotation search per pair): in parallel.
    tbb::parallel_for(std::size_t{0}, queries.size(), [&](std::size_t query) {
      const std::size_t index = queries[query];
      std::vector<std::pair<double, std::size_t>> ranked;
      for (std::size_t other = 0; other < sessions[session_of[index]].first; ++other)
        ranked.emplace_back(place_distance(models[index].descriptor, models[other].descriptor), other);
      const std::size_t keep = std::min(options.place_candidates_per_scan, ranked.size());
      std::partial_sort(ranked.begin(), ranked.begin() + static_cast<std::ptrdiff_t>(keep), ranked.end());
      for (std::size_t k = 0; k < keep; ++k)
        if (std::isfinite(ranked[k].first)) result.place_ranking[index].push_back(ranked[k].second);
    });
    for (const std::size_t index : queries)
      for (const std::size_t other : result.place_ranking[index]) pairs.emplace_back(index, other);
    result.candidates_across = pairs.size();
    candidates_ms += elapsed_ms(candidates_start);
    const Clock::time_point registration_start = Clock::now();
    std::vector<MapPairRequest> requests(pairs.size());
    for (std::size_t pair = 0; pair < pairs.size(); ++pair) requests[pair].from = pairs[pair].first, requests[pair].to = pairs[pair].second;
    std::size_t done = 0;
    std::vector<MapEdge> found = register_batch(requests, [&] {
      if (progress) progress("place candidates registered", ++done, pairs.size());
    });
    for (MapEdge& edge : found) edge.across_sessions = true;
    registration_ms += elapsed_ms(registration_start);
    for (MapEdge& edge : found) loop_edges.push_back(std::move(edge));
  }
  result.timings_ms["candidates"] = candidates_ms;
  result.timings_ms["registration"] = registration_ms;
  result.timings_ms["loops"] = elapsed_ms(loops_start);

  // The pose graph.
  stage = Clock::now();
  // Odometry travelled along each session, for the gate of loop edges within a session.
  std::vector<double> travelled_at(count, 0.0);
  for (const auto& [begin, end] : sessions) {
    const std::vector<double> travelled = path_lengths(result.odometry, begin, end);
    for (std::size_t index = begin; index < end; ++index) travelled_at[index] = travelled[index - begin];
  }
  for (MapEdge& edge : loop_edges) {
    const bool ambiguous_allowed =
        edge.across_sessions ? options.use_ambiguous_edges_across_sessions : options.use_ambiguous_edges;
    edge.used = edge.status == "ok" || (ambiguous_allowed && edge.status == "ambiguous");
    std::string why;
    if (edge.used && !edge.across_sessions &&
        !consistent_with_odometry(edge.transform, result.odometry[edge.to].inverse() * result.odometry[edge.from],
                                  std::abs(travelled_at[edge.from] - travelled_at[edge.to]), options, &why)) {
      edge.used = false;
      edge.note = "not in the graph: " + why;
    }
  }
  // The later session's odometry frame in the earlier one's, as a loop edge between two sessions measures it.
  const auto later_session_frame = [&](const MapEdge& edge) {
    const Eigen::Isometry3d frame = result.odometry[edge.to] * edge.transform * result.odometry[edge.from].inverse();
    return session_of[edge.from] > session_of[edge.to] ? frame : frame.inverse();
  };
  // Ambiguous place edges between two sessions enter by a clear vote: each place edge (ok or
  // ambiguous) measures the later session's odometry frame in the earlier one's; the pose most
  // edges agree on (within place_vote_*) wins when enough agree and no pose beyond the consensus
  // gate comes close. A pair of scans of one place by two different sensors is mostly answered
  // right but `ambiguous` (too little of the sparser cloud lands on the denser one to confirm it),
  // and a wrong answer agrees with few others; many right ones agree on one pose.
  if (options.place_vote_minimum > 0) {
    std::map<std::pair<std::size_t, std::size_t>, std::vector<std::size_t>> place_edges;  // (earlier, later) session -> edges
    for (std::size_t index = 0; index < loop_edges.size(); ++index) {
      const MapEdge& edge = loop_edges[index];
      if (edge.across_sessions && (edge.status == "ok" || edge.status == "ambiguous"))
        place_edges[std::minmax(session_of[edge.from], session_of[edge.to])].push_back(index);
    }
    for (const auto& [session_pair, members] : place_edges) {
      std::vector<Eigen::Isometry3d> frames;
      for (const std::size_t index : members) frames.push_back(later_session_frame(loop_edges[index]));
      const auto within = [](const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double degrees, double metres) {
        const PoseDeparture departure = departure_between(a, b);
        return departure.degrees <= degrees && departure.metres <= metres;
      };
      std::vector<std::size_t> support(members.size(), 0);
      for (std::size_t a = 0; a < members.size(); ++a)
        for (std::size_t b = 0; b < members.size(); ++b)
          support[a] += within(frames[a], frames[b], options.place_vote_rotation_degrees, options.place_vote_translation);
      const std::size_t best = static_cast<std::size_t>(std::max_element(support.begin(), support.end()) - support.begin());
      std::size_t rival = 0;
      for (std::size_t other = 0; other < members.size(); ++other)
        if (!within(frames[best], frames[other], options.place_consensus_rotation_degrees, options.place_consensus_translation))
          rival = std::max(rival, support[other]);
      if (support[best] < options.place_vote_minimum || static_cast<double>(support[best]) < options.place_vote_ratio * static_cast<double>(rival))
        continue;
      for (std::size_t other = 0; other < members.size(); ++other) {
        MapEdge& edge = loop_edges[members[other]];
        if (edge.status != "ambiguous" || edge.used ||
            !within(frames[best], frames[other], options.place_vote_rotation_degrees, options.place_vote_translation))
          continue;
        edge.used = edge.voted = true;
        char why[160];
        std::snprintf(why, sizeof why, "in the graph by the place vote: %zu of the %zu place edges between these sessions agree (the largest contradicting vote %zu)",
                      support[best], members.size(), rival);
        edge.note = why + (edge.note.empty() ? std::string() : "; " + edge.note);
      }
    }
  }
  // Edges between two sessions must agree with each other: each one's relative pose of the two
  // sessions' odometry frames predicts the others (drift between them allowed by the consensus gate);
  // the edges the best-supported one predicts stay, the others leave the graph. When two or more
  // edges join a pair of sessions and none predicts another, none stays: contradicting edges do not
  // glue sessions (a single edge cannot be checked and stays).
  std::map<std::pair<std::size_t, std::size_t>, std::vector<std::size_t>> across_pairs;  // (smaller, larger) session -> edges
  for (std::size_t index = 0; index < loop_edges.size(); ++index) {
    const MapEdge& edge = loop_edges[index];
    if (edge.used && edge.across_sessions) across_pairs[std::minmax(session_of[edge.from], session_of[edge.to])].push_back(index);
  }
  for (const auto& [session_pair, members] : across_pairs) {
    if (members.size() < 2) continue;
    const auto predicts = [&](const MapEdge& by, const MapEdge& other, PoseDeparture& departure) {
      // `by`'s frame of `other`'s from-session in its to-session.
      Eigen::Isometry3d frame = later_session_frame(by);
      if (session_of[other.from] < session_of[other.to]) frame = frame.inverse();
      departure = departure_between(other.transform, result.odometry[other.to].inverse() * frame * result.odometry[other.from]);
      return departure.degrees <= options.place_consensus_rotation_degrees && departure.metres <= options.place_consensus_translation;
    };
    std::size_t best = members.front(), best_support = 0;
    for (const std::size_t candidate : members) {
      std::size_t support = 0;
      PoseDeparture departure;
      for (const std::size_t other : members) support += other != candidate && predicts(loop_edges[candidate], loop_edges[other], departure);
      if (support > best_support) best = candidate, best_support = support;
    }
    for (const std::size_t other : members) {
      PoseDeparture departure;
      if (other == best && best_support > 0) continue;
      if (best_support > 0 && predicts(loop_edges[best], loop_edges[other], departure)) continue;
      MapEdge& edge = loop_edges[other];
      edge.used = false;
      char why[200];
      if (best_support > 0)
        std::snprintf(why, sizeof why, "not in the graph: departs by %.1f deg and %.1f m from what %zu of the %zu edges between these sessions agree on",
                      departure.degrees, departure.metres, best_support + 1, members.size());
      else
        std::snprintf(why, sizeof why, "not in the graph: none of the %zu edges between these sessions agrees with another", members.size());
      edge.note = why + (edge.note.empty() ? std::string() : "; " + edge.note);
    }
  }
  for (MapEdge& edge : loop_edges)
    if (!edge.used && edge.note.empty()) edge.note = "not in the graph (" + edge.status + ")";
  result.edges = odometry_edges;
  result.edges.insert(result.edges.end(), loop_edges.begin(), loop_edges.end());

  // Initial poses: the first session's odometry; each later session placed through the used edge to
  // an already placed session that most other such edges agree with (2 m / 5 deg), else left in its frame.
  result.initial = result.odometry;
  std::vector<bool> placed(sessions.size(), false);
  placed[0] = true;
  for (bool changed = true; changed;) {
    changed = false;
    for (std::size_t session = 1; session < sessions.size(); ++session) {
      if (placed[session]) continue;
      std::vector<Eigen::Isometry3d> proposals;  // the session's frame in the map, one per edge
      for (const MapEdge& edge : result.edges) {
        if (!edge.used || edge.kind != MapEdgeKind::Loop) continue;
        std::size_t mine = edge.from, theirs = edge.to;
        Eigen::Isometry3d mine_in_theirs = edge.transform;
        if (session_of[mine] != session) {
          std::swap(mine, theirs);
          mine_in_theirs = mine_in_theirs.inverse();
        }
        if (session_of[mine] != session || !placed[session_of[theirs]]) continue;
        proposals.push_back(result.initial[theirs] * mine_in_theirs * result.odometry[mine].inverse());
      }
      if (proposals.empty()) continue;
      std::size_t best = 0, best_support = 0;
      for (std::size_t a = 0; a < proposals.size(); ++a) {
        std::size_t support = 0;
        for (const Eigen::Isometry3d& other : proposals)
          if (registration_succeeded(proposals[a], other)) ++support;
        if (support > best_support) best = a, best_support = support;
      }
      for (std::size_t index = sessions[session].first; index < sessions[session].second; ++index)
        result.initial[index] = proposals[best] * result.odometry[index];
      placed[session] = changed = true;
    }
  }

  // Solves the graph of the used edges from the current poses: Huber on `ok` loop edges and on the
  // ambiguous ones a map has vouched for (within a session after arbitrate_ambiguous_edges, and
  // those of the joint-frame rounds, from joint_edges_begin on, which pass the ambiguous gate); DCS
  // on the others (ambiguous edges between sessions by the place descriptor, when let in). A vouched
  // edge under DCS as well would be judged twice: on the tuning three-sensor drive DCS scaled the
  // right cross-sensor edges down to 0.1-0.3 and left 0.48 m of ATE where Huber gave 0.29 m.
  std::size_t joint_edges_begin = std::numeric_limits<std::size_t>::max();
  const auto vouched = [&](std::size_t index) {
    const MapEdge& edge = result.edges[index];
    return edge.status == "ok" || (edge.status == "ambiguous" && (!edge.across_sessions || edge.voted || index >= joint_edges_begin));
  };
  // The graph of the used edges, and the index into result.edges of each of its edges.
  const auto used_graph = [&](std::vector<PoseGraphEdge>& graph_edges, std::vector<std::size_t>& graph_edge_of) {
    for (std::size_t index = 0; index < result.edges.size(); ++index) {
      const MapEdge& edge = result.edges[index];
      if (!edge.used) continue;
      const bool loop = edge.kind == MapEdgeKind::Loop;
      graph_edges.push_back({edge.from, edge.to, edge.transform, edge.information, loop && vouched(index), loop && !vouched(index)});
      graph_edge_of.push_back(index);
    }
  };
  const auto solve_graph = [&] {
    std::vector<PoseGraphEdge> graph_edges;
    std::vector<std::size_t> graph_edge_of;
    used_graph(graph_edges, graph_edge_of);
    result.graph = optimise_pose_graph(result.poses, graph_edges, options.graph);
    for (std::size_t k = 0; k < graph_edges.size(); ++k) {
      MapEdge& edge = result.edges[graph_edge_of[k]];
      edge.chi2_before = result.graph.initial_chi2[k];
      edge.chi2_after = result.graph.final_chi2[k];
      edge.dcs_scale = result.graph.final_scale[k];
    }
    result.in_map_frame.assign(count, false);
    for (std::size_t index = 0; index < count; ++index) result.in_map_frame[index] = result.graph.component[index] == result.graph.component[0];
  };
  result.poses = result.initial;
  // Ambiguous edges within a session: the map of the sure edges arbitrates them.
  arbitrate_ambiguous_edges(result.edges, result.initial, options);
  solve_graph();
  result.timings_ms["graph"] = elapsed_ms(stage);

  // Across sessions again, now in the joint map frame (LIO-SAM's radius search, as within a session):
  // around each placed scan's map position, the nearest scans of each earlier placed session, one a
  // pass; registered globally from the models (no guess), kept when the answer agrees with the
  // relative pose of the current map poses within the gate (the placement's error), then solved
  // again. Rounds repeat while they add used edges; a scan that already has a used edge to a
  // session is not searched again against it.
  if (sessions.size() > 1 && options.joint_rounds > 0) {
    const Clock::time_point joint_start = Clock::now();
    double joint_graph_ms = 0.0;
    result.joint_candidates.assign(count, {});
    std::set<std::pair<std::size_t, std::size_t>> registered_pairs;  // (smaller, larger) scan index
    for (const MapEdge& edge : result.edges)
      if (edge.kind == MapEdgeKind::Loop) registered_pairs.emplace(std::min(edge.from, edge.to), std::max(edge.from, edge.to));
    const std::size_t first_joint_edge = result.edges.size();
    joint_edges_begin = first_joint_edge;
    // Whether a joint-frame edge agrees with the current map: `ok` ones within joint_gate_* (the
    // placement's error), ambiguous ones within the tighter ambiguous_gate_* (they have only the map
    // to vouch for them). Sets `used`; returns the departure (for the note) and whether the gate
    // kept out an `ok` or ambiguous answer.
    const auto judge = [&](MapEdge& edge, std::size_t round) {
      const auto [rotation, translation] =
          departure_between(edge.transform, result.poses[edge.to].inverse() * result.poses[edge.from]);
      char departure[160];
      std::snprintf(departure, sizeof departure, "joint-frame round %zu: departs from the map poses by %.2f deg and %.2f m", round,
                    rotation, translation);
      const bool ok = edge.status == "ok", ambiguous = edge.status == "ambiguous";
      const bool agrees = ok ? rotation <= options.joint_gate_rotation_degrees && translation <= options.joint_gate_translation
                             : rotation <= options.ambiguous_gate_rotation_degrees && translation <= options.ambiguous_gate_translation;
      edge.used = agrees && (ok || (ambiguous && options.use_ambiguous_joint_edges));
      return std::make_pair(std::string(departure), (ok || ambiguous) && !agrees);
    };
    for (std::size_t round = 1; round <= options.joint_rounds; ++round) {
      JointRound summary;
      // Edges of earlier rounds that were beyond the gate are judged again against the map the
      // last solve made (no new registration): a session placed better now may agree with them.
      if (round > 1)
        for (std::size_t index = first_joint_edge; index < result.edges.size(); ++index) {
          MapEdge& edge = result.edges[index];
          if (edge.used || (edge.status != "ok" && edge.status != "ambiguous")) continue;
          const auto [departure, gated] = judge(edge, round);
          if (!edge.used) continue;
          ++summary.used;
          ++summary.readmitted;
          edge.note = departure + " (judged again: in the graph); " + edge.note;
        }
      const std::vector<MapPairRequest> requests =
          joint_frame_requests(result, sessions, session_of, travelled_at, options, registered_pairs, summary);
      summary.registered = requests.size();
      result.candidates_across += requests.size();
      if (requests.empty() && summary.used == 0) {
        summary.sessions_in_map_frame = joined_sessions(result.in_map_frame, sessions);
        result.joint_rounds.push_back(summary);
        break;
      }
      const Clock::time_point registration_start = Clock::now();
      std::size_t done = 0;
      std::vector<MapEdge> found = register_batch(requests, [&] {
        if (progress) progress("joint-frame candidates registered (round " + std::to_string(round) + ")", ++done, requests.size());
      });
      registration_ms += elapsed_ms(registration_start);
      for (MapEdge& edge : found) {
        edge.across_sessions = true;
        summary.ok += edge.status == "ok";
        summary.ambiguous += edge.status == "ambiguous";
        const auto [departure, gated] = judge(edge, round);
        summary.gated += gated;
        summary.used += edge.used;
        const std::string verdict = edge.used ? "" : gated ? " (beyond the gate: not in the graph)" : " (not in the graph: " + edge.status + ")";
        edge.note = departure + verdict + (edge.note.empty() ? "" : "; " + edge.note);
        result.edges.push_back(std::move(edge));
      }
      if (summary.used > 0) {
        const Clock::time_point graph_start = Clock::now();
        solve_graph();
        joint_graph_ms += elapsed_ms(graph_start);
      }
      summary.sessions_in_map_frame = joined_sessions(result.in_map_frame, sessions);
      result.joint_rounds.push_back(summary);
      if (summary.used == 0) break;
    }
    result.timings_ms["registration"] = registration_ms;
    result.timings_ms["graph"] += joint_graph_ms;
    result.timings_ms["joint_rounds"] = elapsed_ms(joint_start);
  }
  // Each group of used edges is weighted by what its residuals measured (robust variance component
  // estimation, estimate_variance_factors): the odometry's drift and each sensor pair's loop-edge
  // accuracy are rarely what the options assume (the three-sensor town drive's odometry turned out
  // a hundred times better in rotation than 1 deg/m, and VLP-16 edges ten times worse than HDL-64E
  // ones), and a graph weighted wrongly bends the map towards its worst edges.
  if (options.information_rounds > 0) {
    const Clock::time_point calibration_start = Clock::now();
    std::map<std::pair<std::size_t, std::size_t>, std::size_t> loop_group;  // (smaller, larger) session -> group
    std::vector<std::size_t> group_of_edge(result.edges.size(), 0);
    std::vector<std::size_t> pool;  // 0 odometry, 1 loop
    for (std::size_t session = 0; session < sessions.size(); ++session) {
      result.information_groups.push_back({"odometry " + list.sessions[session]});
      pool.push_back(0);
    }
    for (std::size_t index = 0; index < result.edges.size(); ++index) {
      const MapEdge& edge = result.edges[index];
      if (edge.kind == MapEdgeKind::Odometry) {
        group_of_edge[index] = session_of[edge.from];
        continue;
      }
      const std::pair<std::size_t, std::size_t> key = std::minmax(session_of[edge.from], session_of[edge.to]);
      const auto [found, added] = loop_group.emplace(key, result.information_groups.size());
      if (added) {
        result.information_groups.push_back({"loop " + list.sessions[key.first] + "-" + list.sessions[key.second]});
        pool.push_back(1);
      }
      group_of_edge[index] = found->second;
    }
    // Rounds of estimate_variance_factors, each followed by a solve, until the factors settle.
    const auto calibrate = [&] {
      for (std::size_t round = 0; round < options.information_rounds; ++round) {
        std::vector<PoseGraphEdge> graph_edges;
        std::vector<std::size_t> graph_edge_of, graph_groups;
        used_graph(graph_edges, graph_edge_of);
        for (const std::size_t index : graph_edge_of) graph_groups.push_back(group_of_edge[index]);
        std::vector<VarianceFactors> factors;
        try {
          factors = estimate_variance_factors(result.poses, graph_edges, graph_groups, result.information_groups.size(), pool,
                                              options.information_minimum_edges, options.graph);
        } catch (const Error& error) {
          // A graph whose covariance cannot be formed (a pose only edges without information reach)
          // keeps the weights of the last round: the map stands, only uncalibrated.
          result.calibration_note = std::string("calibration stopped: ") + error.what();
          return false;
        }
        for (std::size_t g = 0; g < factors.size(); ++g) {
          InformationGroup& group = result.information_groups[g];
          group.edges = factors[g].edges;
          group.rotation_factor *= factors[g].rotation;
          group.translation_factor *= factors[g].translation;
          group.pooled = factors[g].pooled;
          group.measured = factors[g].measured;
        }
        result.calibration_converged = std::all_of(factors.begin(), factors.end(), [&](const VarianceFactors& factor) {
          const auto within = [&](double value) {
            return value <= options.information_tolerance && value >= 1.0 / options.information_tolerance;
          };
          return within(factor.rotation) && within(factor.translation);
        });
        for (std::size_t k = 0; k < graph_edge_of.size(); ++k) {
          const VarianceFactors& factor = factors[graph_groups[k]];
          MapEdge& edge = result.edges[graph_edge_of[k]];
          edge.information = scaled_information(edge.information, factor.rotation, factor.translation);
        }
        solve_graph();
        result.calibration_costs.push_back(result.graph.final_cost);
        if (progress) progress("information calibration rounds", round + 1, options.information_rounds);
        if (result.calibration_converged) break;
      }
      return true;
    };
    // Baarda's data snooping on the calibrated graph (snoop_pose_graph): a loop edge whose residual
    // is far beyond what the rest of the graph leaves it, in the units its own group's accuracy
    // sets, leaves the graph. The odometry gate cannot see a wrong edge that slid a few metres along a
    // street close to its scans' path (its allowance grows with the path); the rest of a calibrated
    // graph holds such a pair to centimetres. Odometry edges are not tested: they hold the sessions
    // together.
    if (calibrate() && options.outlier_threshold > 0.0) {
      std::vector<PoseGraphEdge> graph_edges;
      std::vector<std::size_t> graph_edge_of;
      used_graph(graph_edges, graph_edge_of);
      std::vector<bool> testable(graph_edges.size(), false);
      for (std::size_t k = 0; k < graph_edges.size(); ++k) testable[k] = result.edges[graph_edge_of[k]].kind == MapEdgeKind::Loop;
      std::vector<Eigen::Isometry3d> snooped_poses = result.poses;
      try {
        const DataSnooping snooping = snoop_pose_graph(snooped_poses, graph_edges, testable, options.outlier_threshold,
                                                       options.maximum_outlier_removals, options.graph);
        for (std::size_t removal = 0; removal < snooping.removed.size(); ++removal) {
          MapEdge& edge = result.edges[graph_edge_of[snooping.removed[removal]]];
          edge.used = false;
          char text[200];
          std::snprintf(text, sizeof text,
                        "not in the graph: outlier test (its residual's chi-square over its redundancy is %.3g, limit %.3g)",
                        snooping.statistic[removal], options.outlier_threshold);
          edge.note = text + (edge.note.empty() ? std::string() : "; " + edge.note);
        }
        result.outlier_edges = snooping.removed.size();
        result.outlier_test_exhausted = snooping.exhausted;
        if (!snooping.removed.empty()) {
          result.poses = std::move(snooped_poses);  // solved without the removed edges already
          solve_graph();
          calibrate();
        }
      } catch (const Error& error) {
        result.calibration_note = std::string("outlier test stopped: ") + error.what();
      }
    }
    result.timings_ms["graph"] += elapsed_ms(calibration_start);
  }
  // The models move into the result once no pair needs them: a copy made when modelling ended
  // would hold every model twice through the registrations.
  result.models.reserve(models.size());
  for (ScanModel& model : models) result.models.push_back(std::move(model.model));
  result.timings_ms["total"] = elapsed_ms(run_start);
  return result;
}

}  // namespace quadrix
