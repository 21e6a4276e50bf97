// Maps from many scans (paper §"Real-World Applications": QuadricsReg as the loop-closure module of
// a LiDAR SLAM system and for multi-session mapping). One verb per stage:
//   read      a scan list (SCANS.tsv or the KITTI odometry layout),
//   model     every scan once (model_scene), keeping only its SceneModel,
//   odometry  given, or registered scan to scan when a session has none (ICP from the previous
//             motion verified by the registration's checks, else global registration),
//   candidates within a session by radius search around the odometry position (LIO-SAM), the radius
//             growing with the distance travelled since the last accepted loop; across sessions by
//             a bird's-eye place descriptor of each scan matched under every heading (Scan Context on
//             the height band every sensor sees: place_descriptor), then, once sessions are
//             placed in the map frame, by radius search there (rounds, each followed by a solve),
//   register  candidate pairs from their cached models (register_models), verified on the clouds
//             loaded on demand (verify_registration),
//   optimise  the pose graph (optimise_pose_graph; loop edges that are ok or vouched for by a map
//             under Huber, other ambiguous ones under DCS),
//   write     poses.tsv, edges.csv, report.json, map.ply and the merged quadric model.
#pragma once

#include "estimation/pose_graph.h"
#include "estimation/registration.h"
#include "fitting/scene_model.h"
#include "geometry/scan_list.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstddef>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

namespace quadrix {

/// MapOptions::information_rounds above this is refused: each round is a full graph solve, and on the
/// tuning drives the factors settled within a few rounds.
constexpr std::size_t kMaximumInformationRounds = 20;

/// Options of the whole mapping run.
struct MapOptions {
  std::string preset = "auto";                 ///< registration preset of every scan (registration_preset name, or auto per scan)
  double maximum_median_range = 1000.0;        ///< a scan whose median point lies farther from its sensor is in another unit (millimetres), m: Error
  // Loop candidates within a session (LIO-SAM's radius search).
  double loop_radius = 30.0;                   ///< search radius around the odometry position right after a loop, m (LIO-SAM's is 15; the registration solves pairs 20-30 m apart, and on the tuning town drive 30 m closed every return within 30 m and the candidates just behind on the same street measured the odometry's scale error: docs/mapping.md)
  double loop_radius_growth = 0.05;            ///< the radius grows by this many metres per metre travelled since the last accepted loop (odometry drift)
  double maximum_loop_radius = 45.0;           ///< the radius never exceeds this, m
  double minimum_loop_travel = 15.0;           ///< a candidate lies at least this far back along the path, m (LIO-SAM: 30 s)
  std::size_t candidates_per_scan = 2;         ///< the nearest this many candidates of each scan are registered
  double minimum_candidate_spacing = 30.0;     ///< candidates of one scan lie at least this far apart along the path, m: one a pass, so that a return competes with the scans just behind on the same street rather than with their neighbours
  // Across sessions.
  std::size_t place_candidates_per_scan = 3;   ///< the best-ranked this many scans of other sessions are registered with each scan
  std::size_t place_query_stride = 1;          ///< query every this many scans of a session across sessions
  std::size_t joint_rounds = 3;                ///< rounds of loop candidates across sessions by radius search in the joint map frame once sessions are placed, each followed by a graph solve (0: none; stops early when a round adds no used edge)
  double joint_radius = 30.0;                  ///< radius of that search around each scan's current map position, m (covers the placement's error: sessions placed by a few edges lie a few metres off)
  double joint_gate_translation = 10.0;        ///< a joint-frame edge stays out of the graph when its translation departs from the relative pose of the current map poses by more than this, m
  double joint_gate_rotation_degrees = 15.0;   ///< or its rotation by more than this, degrees
  double place_consensus_rotation_degrees = 30.0;  ///< a used edge between two sessions (place descriptor) stays in only when the relative pose of the sessions' odometry frames most such edges agree on predicts it within this rotation, degrees (three-sensor town drives: right edges predict each other within 6 deg, the odometry's drift between them; a wrong `ok` one departed by 173-180 deg)
  double place_consensus_translation = 50.0;   ///< and within this translation, m (right ones within 22 m, the wrong one by 154-462 m)
  std::size_t place_vote_minimum = 10;         ///< ambiguous place edges between two sessions enter the graph (under Huber, as `ok` ones) when at least this many place edges (ok or ambiguous) agree on the relative pose of the two sessions' odometry frames within place_vote_rotation_degrees and place_vote_translation, and place_vote_ratio times as many as agree on any pose beyond the place consensus gate (0: never). Cross-sensor pairs of one place are right but rarely `ok` (overlap below the floor); on the three-sensor tuning drive the right ones formed votes of 27 (HDL-64E / VLP-16) and 33 (HDL-64E / Livox), wrong ones at most 6 (docs/mapping.md)
  double place_vote_rotation_degrees = 3.0;    ///< the vote's agreement in rotation, degrees (right edges of one pair of sessions differ by the two odometries' drift between their places)
  double place_vote_translation = 10.0;        ///< and in translation, m
  double place_vote_ratio = 2.0;               ///< the winning vote must be this many times any contradicting one
  bool use_ambiguous_joint_edges = true;       ///< ambiguous edges of the joint-frame rounds that pass the ambiguous gate (ambiguous_gate_*) enter the graph, under Huber as `ok` ones (cross-sensor pairs of one place are right but rarely `ok`: docs/mapping.md)
  double ambiguous_gate_translation = 4.0;     ///< an ambiguous loop edge within a session or of the joint-frame rounds enters the graph only when its translation departs from the relative pose of the map solved without ambiguous edges by at most this, m (three-sensor tuning drive: right ones depart by at most 3.8 m, wrong ones by 4.1 m and by 20-80 m; docs/mapping.md)
  double ambiguous_gate_rotation_degrees = 4.0;///< and its rotation by at most this, degrees (tuning drive: 4 m / 4 deg kept 229 right edges and no wrong one, 5 m / 5 deg 230 and 1; within sessions right ones depart by at most 2.2 deg)
  // Odometry when none is given.
  bool register_consecutive = true;            ///< sessions without odometry are registered scan to scan
  // Loop edges into the graph.
  bool use_ambiguous_edges = true;             ///< ambiguous loop edges within a session enter the graph when they pass the odometry gate and arbitrate_ambiguous_edges, under Huber as `ok` ones (else only `ok` ones): on the BALM walk's validation seeds the RPE fell from 0.67 to 0.57 % and 0.52 to 0.47 % (docs/mapping.md)
  bool use_ambiguous_edges_across_sessions = false;  ///< ambiguous loop edges between sessions enter the graph too (off: nothing arbitrates them, no odometry joins two sessions, and on the three-sensor town drive 884 of 903 were wrong and placed the sessions 197 m off, docs/mapping.md)
  double odometry_gate_sigmas = 5.0;           ///< a loop edge within a session stays out of the graph when its rotation or translation departs from the odometry's relative pose by more than this many of the odometry drift's standard deviations over the path between the two scans (consistent_with_odometry; 0: no gate)
  double loop_translation_sigma = 0.1;         ///< standard deviation of a loop edge's translation, m (fixed information: loop_information_from_registration off, or an answer without inliers)
  double loop_rotation_sigma_degrees = 0.5;    ///< standard deviation of its rotation, degrees
  bool loop_information_from_registration = false;  ///< a loop edge's information is the registration's H (moved to the graph's error) divided by its inlier count and scaled by loop_information_scale, instead of the fixed sigmas (off: it lowered the tuning drive's ATE from 0.124 to 0.108 m but raised the validation drive's from 0.056 to 0.060 m, docs/mapping.md)
  double loop_information_scale = 1.7e5;       ///< that scale, 1/m²: the mean χ² of right loop edges against the truth is 6 (their degrees of freedom) on the tuning town drive (docs/mapping.md)
  // Odometry drift (the information of odometry edges).
  double odometry_translation_drift = 0.05;    ///< odometry's translation error per metre travelled (5%)
  double odometry_rotation_drift_degrees = 1.0;///< odometry's rotation error per metre travelled, degrees
  double odometry_translation_floor = 0.05;    ///< a step's translation sigma is at least this, m (scans standing still)
  double odometry_rotation_floor_degrees = 0.5;///< a step's rotation sigma is at least this, degrees
  std::size_t information_rounds = 10;         ///< at most this many rounds of variance component estimation after the last solve: each group of used edges (odometry per session, loop edges per pair of sessions) has its information scaled by what its residuals measured (estimate_variance_factors), then the graph is solved again (0: the information as given). Three-sensor tuning drive: ATE 0.261 -> 0.151 / 0.140 / 0.136 m after 1 / 2 / 3 rounds (offline re-solve of its edges; docs/mapping.md)
  double outlier_threshold = 100.0;            ///< after the information calibration, used loop edges leave the graph one at a time while the largest Baarda statistic (a block's χ² over its redundancy, snoop_pose_graph) exceeds this, and the calibration runs again (0: no test; needs information_rounds > 0). Tuning drives: right edges within 0.3 m and 1 deg of the truth reach 73 (1,062 edges), 12 of 21 right ones 0.3-2 m off exceed it and leaving them out moved the ATE by 1 mm (docs/mapping.md)
  std::size_t maximum_outlier_removals = 50;   ///< at most this many edges leave by that test in one run (each costs a graph solve and its covariance); more is reported as a warning
  double information_tolerance = 1.5;          ///< the rounds stop once every group's factors lie within 1/this .. this (tuning drive: within 1.5 after 5 rounds, the ATE changing by under 1 cm a round from the third)
  std::size_t information_minimum_edges = 5;   ///< a group with fewer used edges takes the factors of all odometry or all loop edges (a median of a few χ² is noise; pooling larger groups gave a session with exact odometry the weight of one drifting 0.7 deg/m: 0.157 m ATE where 7-edge groups of their own gave 0.049 m, two interleaved sessions of the BALM walk, docs/mapping.md)
  PoseGraphOptions graph;                      ///< DCS Φ and the solver
  double map_voxel = 0.2;                      ///< map.ply keeps one point per cube of this edge, m
  std::size_t cloud_cache = 6;                 ///< clouds kept in memory for verification at once
  std::optional<RegistrationOptions> registration_options;  ///< fixed options (both extractions included) for every scan and pair instead of resolving `preset` per scan
};

/// Whether a loop edge between two scans of one session agrees with their odometry: `measured` and
/// `predicted` (the odometry's relative pose) map the same scan into the same frame, `path` metres of
/// the odometry lie between the scans. With the drift's standard deviations σ_r = max(floor, rotation
/// drift · path) and σ_t = max(floor, translation drift · path) (MapOptions::odometry_*), the edge
/// agrees when its rotation departs by at most k σ_r and its translation by at most k σ_t + path ·
/// sin(min(θ + k floor_r, 90°)), θ its rotation's departure (the lever arm: a heading error θ moves a
/// point L metres along the path by at most L sin θ), k = options.odometry_gate_sigmas. Over a long path
/// the rotation's limit opens (k σ_r ≥ 180°): a loop after a long drive is the registration's to judge,
/// but its translation must still fit the rotation it departs by. `why` (when given) receives the
/// departure and the limits when the edge does not agree.
bool consistent_with_odometry(const Eigen::Isometry3d& measured, const Eigen::Isometry3d& predicted, double path,
                              const MapOptions& options, std::string* why = nullptr);

/// The place descriptor of a scan (Scan Context, Kim and Kim 2018, on what every sensor sees): the
/// points around the `up` axis binned into 60 sectors and 18 rings of 2 m from 4 to 40 m; a cell is
/// occupied when a point lies 0.5-2.5 m above the ground (the 5th percentile of the heights 3-20 m
/// out), the band between a car's sill and its roof that an HDL-64E (2 deg up), a VLP-16 and a Livox
/// all see, where the highest point of a cell or a ring's share of cells depends on the sensor's
/// field of view and density. A sector is seen when any point falls in it (a Livox sees 12 of 60).
/// 120 values: each sector's ring occupancy as a bit mask, then each sector's seen flag.
Eigen::VectorXd place_descriptor(const PointCloud& cloud, const Eigen::Vector3d& up);

/// Distance of two place descriptors under the best heading: over the 60 sector shifts, 1 - the mean
/// cosine similarity of the sectors' ring occupancies over the sectors both scans see (a sector
/// without an occupied cell in either is dissimilar); the smallest over the shifts with at least 6
/// such sectors, +infinity when none has. 0 for a scan and itself turned by a multiple of 6 deg.
/// Throws quadrix::Error for descriptors not of place_descriptor's size.
double place_distance(const Eigen::VectorXd& first, const Eigen::VectorXd& second);

/// Kind of an edge.
enum class MapEdgeKind { Odometry, Loop };

struct MapEdge;

/// The second-stage gate of ambiguous loop edges within a session: the pose graph of the used
/// edges but those (odometry, `ok` loop edges, and whatever else is used) is solved from `initial`,
/// and each used `ambiguous` loop edge within a session stays used only when its rotation and
/// translation depart from that map's relative pose by at most options.ambiguous_gate_rotation_degrees
/// and ambiguous_gate_translation; the others are marked unused with the departure in their note.
/// Unlike consistent_with_odometry, whose allowance grows with the path, this allowance is fixed: an
/// ambiguous edge has only the map of the sure edges to vouch for it. Returns the edges refused.
std::size_t arbitrate_ambiguous_edges(std::vector<MapEdge>& edges, const std::vector<Eigen::Isometry3d>& initial,
                                      const MapOptions& options);

/// One edge of the map: a relative pose between two scans.
struct MapEdge {
  std::size_t from = 0;                        ///< scan index (into ScanList::scans), source
  std::size_t to = 0;                          ///< scan index, target
  MapEdgeKind kind = MapEdgeKind::Odometry;    ///< odometry (consecutive scans) or loop
  std::string status = "ok";                   ///< "given" (odometry from the list), or the registration status
  bool used = false;                           ///< entered the pose graph
  bool across_sessions = false;                ///< joins two sessions
  bool voted = false;                          ///< an ambiguous place edge let into the graph by the place vote (MapOptions::place_vote_minimum)
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();  ///< maps `from` points into the `to` frame
  Information6d information = Information6d::Identity();       ///< rotation then translation
  double overlap = 0.0;                        ///< dense overlap of the registration (0 for given odometry)
  std::size_t inliers = 0;                     ///< the registration's inlier correspondences (RegistrationResult::correspondences)
  double inlier_rmse = 0.0;                    ///< their RMS point distance, m
  Information6d registration_information = Information6d::Zero();  ///< the registration's point-to-plane H = JᵀJ (RegistrationResult::information: left perturbation in the `to` frame)
  double registration_ms = 0.0;                ///< time of the registration
  double chi2_before = 0.0;                    ///< χ² at the odometry poses (used edges)
  double chi2_after = 0.0;                     ///< χ² at the optimised poses (used edges)
  double dcs_scale = 1.0;                      ///< DCS scale after optimisation (used loop edges)
  std::string note;                            ///< why not used, or the registration's message
};

/// One round of loop candidates across sessions by radius search in the joint map frame.
struct JointRound {
  std::size_t candidates = 0;                  ///< pairs proposed (already registered ones included)
  std::size_t registered = 0;                  ///< pairs registered in this round (not registered before)
  std::size_t ok = 0;                          ///< of those, `ok`
  std::size_t ambiguous = 0;                   ///< of those, `ambiguous`
  std::size_t gated = 0;                       ///< `ok` or `ambiguous` ones the joint-frame gate kept out
  std::size_t used = 0;                        ///< edges of this round that entered the graph (readmitted ones included)
  std::size_t readmitted = 0;                  ///< of those, edges of earlier rounds beyond the gate then that agree with this round's map
  std::size_t sessions_in_map_frame = 0;       ///< sessions joined to the first after this round's solve
};

/// The information calibration of one group of edges (MapOptions::information_rounds).
struct InformationGroup {
  std::string name;                            ///< "odometry <session>" or "loop <session>-<session>"
  std::size_t edges = 0;                       ///< used edges of the group
  double rotation_factor = 1.0;                ///< product over the rounds of the rotation variance factors (the variances the group was given were this many times too large, < 1, or too small, > 1)
  double translation_factor = 1.0;             ///< the same for the translation
  bool pooled = false;                         ///< in the last round the group had too few edges and took its kind's pooled factors
  bool measured = true;                        ///< false when nothing in the graph contradicted the group in rotation or translation (that factor left at 1)
};

/// Everything map_scans returns.
struct MapResult {
  ScanList list;                               ///< the input
  std::vector<Eigen::Isometry3d> odometry;     ///< each scan's pose in its session's odometry frame (given or registered)
  std::vector<Eigen::Isometry3d> initial;      ///< each scan's pose before optimisation (odometry; later sessions placed by their first used edge)
  std::vector<Eigen::Isometry3d> poses;        ///< each scan's optimised pose: map frame, or its session's own frame when not joined
  std::vector<bool> in_map_frame;              ///< the scan's session is joined to the first session
  std::vector<MapEdge> edges;                  ///< odometry edges, then loop edges
  std::vector<SceneModel> models;              ///< each scan's model (sensor frame)
  std::vector<std::string> presets;            ///< the preset each scan was modelled with
  PoseGraphSummary graph;                      ///< the optimisation
  std::map<std::string, double> timings_ms;    ///< "modelling", "odometry", "candidates", "registration", "loops", "graph", "joint_rounds" (with several sessions), "total"
  std::size_t candidates_within = 0;           ///< candidate pairs within sessions
  std::size_t candidates_across = 0;           ///< candidate pairs across sessions
  std::vector<std::vector<std::size_t>> place_ranking;  ///< per scan, the scans of other sessions ranked by descriptor (best first, top place_candidates_per_scan)
  std::vector<std::vector<std::size_t>> joint_candidates;  ///< per scan, the scans of earlier sessions the joint-frame radius search proposed (every round)
  std::vector<JointRound> joint_rounds;        ///< what each round of the joint-frame search found
  std::vector<InformationGroup> information_groups;  ///< the information calibration per group of used edges (empty with information_rounds 0)
  std::vector<double> calibration_costs;       ///< the graph's final cost after each calibration round
  bool calibration_converged = false;          ///< the last round's factors all lay within information_tolerance
  std::string calibration_note;                ///< why the calibration stopped early (a singular graph), else empty
  std::size_t outlier_edges = 0;               ///< used loop edges the outlier test (MapOptions::outlier_threshold) took out of the graph
  bool outlier_test_exhausted = false;         ///< it stopped at maximum_outlier_removals with an edge still above the threshold
};

/// Progress callback: stage name, done, total.
using MapProgress = std::function<void(const std::string& stage, std::size_t done, std::size_t total)>;

/// What modelling keeps of one scan: what a worker returns for it (mapped_scan_to_bytes). The
/// registration options of the scan are not part of it: they are a function of the cloud and the
/// MapOptions (the preset, `auto` measured on the cloud), so whoever registers a pair resolves them
/// again from the clouds it reads for verification.
struct MappedScan {
  SceneModel model;                      ///< as model_scene built it (sensor frame)
  std::optional<SceneModel> augmented;   ///< the same with augmented points, when model_scene gave none and the preset matches them
  Eigen::VectorXd descriptor;            ///< the scan's place_descriptor (place recognition)
  std::string preset;                    ///< preset name, or the auto choice's reasons
  double modelling_ms = 0.0;             ///< model_scene time
};

/// One registration a map run asks for: `from` registered onto `to` (indices into ScanList::scans).
struct MapPairRequest {
  std::size_t from = 0;                           ///< source scan
  std::size_t to = 0;                             ///< target scan
  MapEdgeKind kind = MapEdgeKind::Loop;           ///< what the edge becomes
  std::optional<Eigen::Isometry3d> local_guess;   ///< consecutive scans without odometry: point-to-plane ICP from this motion first, global registration when that is not ok
};

/// Who does the heavy work of map_scans. Both calls come from the thread that called map_scans, in
/// batches whose results do not depend on each other (every scan at once; each scan's loop
/// candidates within its session; every pair across sessions at once; one pair at a time along a
/// chain of consecutive scans without odometry), so any executor that runs model_map_scan and
/// register_map_pair (on any machine reading the same files) gives the same map. An empty member
/// runs that part in this process (TBB), with the models kept in memory; `model` without
/// `register_pairs` is an Error (a model made elsewhere comes without the registration options its
/// pairs need).
struct MapExecutor {
  /// Models the scans of these indices (model_map_scan each); returns their models in the same order.
  std::function<std::vector<MappedScan>(const std::vector<std::size_t>& scans)> model;
  /// Registers these pairs (register_map_pair each, from the models the `model` call returned);
  /// returns their edges in the same order.
  std::function<std::vector<MapEdge>(const std::vector<MapPairRequest>& pairs)> register_pairs;
};

/// Models scan `index` of `list` (reads its cloud; what a worker does per scan). Throws
/// quadrix::Error naming the row for an unreadable scan, one of fewer than 100 points, or one whose
/// median point lies farther than options.maximum_median_range (another unit).
MappedScan model_map_scan(const ScanList& list, std::size_t index, const MapOptions& options);

/// Registers `pair` from the two scans' models (`from`, `to`: what model_map_scan returned for them),
/// verified on their clouds read from the list's paths (what a worker does per pair).
MapEdge register_map_pair(const ScanList& list, const MapPairRequest& pair, const MappedScan& from, const MappedScan& to,
                          const MapOptions& options);

/// A MappedScan as bytes (the binary scene-model format for the models, little-endian numbers).
std::string mapped_scan_to_bytes(const MappedScan& scan);
/// Parses mapped_scan_to_bytes; throws quadrix::Error naming `source_name` when the bytes are not one.
MappedScan mapped_scan_from_bytes(const std::string& bytes, const std::string& source_name = "<memory>");
/// A MapEdge as bytes (every member, little-endian numbers).
std::string map_edge_to_bytes(const MapEdge& edge);
/// Parses map_edge_to_bytes; throws quadrix::Error naming `source_name` when the bytes are not one.
MapEdge map_edge_from_bytes(const std::string& bytes, const std::string& source_name = "<memory>");

/// Builds the map of `list` (every stage of the file comment), the scans modelled and the pairs
/// registered by `executor` (default: in this process). Throws quadrix::Error naming the row for an
/// unreadable scan, an empty one or one in another unit.
MapResult map_scans(const ScanList& list, const MapOptions& options = {}, const MapProgress& progress = {},
                    const MapExecutor& executor = {});

/// Writes the outputs of `result` into `folder` atomically: they are written into a fresh sibling
/// folder which then replaces `folder` (an existing `folder` is replaced only once everything is
/// written). `evaluation_json`, when not empty, is stored as the "evaluation" member of report.json.
void write_map(const std::string& folder, const MapResult& result, const MapOptions& options,
               const std::string& evaluation_json = "");

/// Metrics of a map against true poses.
struct MapEvaluation {
  double ate = 0.0;                    ///< RMSE of positions after one SE(3) Umeyama alignment (no scale), m
  double ate_odometry = 0.0;           ///< the same for the initial poses (odometry only)
  double rpe_translation_percent = 0.0;///< KITTI metric: mean translational error over 100..800 m sub-sequences, %
  double rpe_rotation_deg_per_100m = 0.0; ///< mean rotational error, deg/100 m
  double rpe_odometry_translation_percent = 0.0;  ///< the same for the odometry
  double rpe_odometry_rotation_deg_per_100m = 0.0;///< the same for the odometry
  std::size_t rpe_segments = 0;        ///< sub-sequences the RPE averaged
  std::string rpe_lengths = "100..800 m";  ///< the sub-sequence lengths: KITTI's, or 10..80 m when the path is shorter than 100 m
  std::size_t used_loop_edges = 0;     ///< loop edges in the graph
  std::size_t wrong_used_loop_edges = 0;  ///< of those, more than 2 m or 5 deg from the truth
  std::size_t ok_loop_edges = 0;       ///< loop edges registered ok
  std::size_t wrong_ok_loop_edges = 0; ///< of those, wrong
  double precision = 1.0;              ///< 1 - wrong/used (1 with no used edge)
  std::size_t true_revisits = 0;       ///< scans with a true revisit: an earlier scan within 30 m and at least minimum_loop_travel back (or in another session)
  std::size_t closed_revisits = 0;     ///< of those, joined to some earlier scan by an ok loop edge
  std::size_t returns = 0;             ///< scans that came back: an earlier scan within the radius although the true path left that radius in between (or in another session)
  std::size_t closed_returns = 0;      ///< of those, joined by an ok loop edge to such an earlier scan
  double recall = 0.0;                 ///< closed / true revisits
  std::size_t place_queries = 0;       ///< scans with a true revisit in another session within 10 m
  std::size_t place_hits = 0;          ///< of those, with such a scan among their ranked candidates
  std::size_t joint_place_queries = 0; ///< scans with a true revisit in another session within 10 m searched by the descriptor or in the joint frame
  std::size_t joint_place_hits = 0;    ///< of those, with such a scan among their ranked or joint-frame candidates
  std::vector<std::size_t> wrong_edges;///< indices into MapResult::edges of wrong used loop edges
  std::string scope;                   ///< "map" (every scan joined) or which sessions were compared
};

/// Evaluates `result` against `truth` (matched by session and scan; every scan must have a truth
/// row, else Error naming it). ATE and RPE are computed over the scans in the map frame.
MapEvaluation evaluate_map(const MapResult& result, const std::vector<PoseRow>& truth, double revisit_radius = 30.0,
                           double minimum_loop_travel = 15.0);

/// The evaluation as a JSON object.
std::string map_evaluation_json(const MapEvaluation& evaluation);

/// The rigid transform (no scale) that best maps `from` onto `to` in least squares (Umeyama 1991).
Eigen::Isometry3d umeyama_alignment(const Eigen::Matrix3Xd& from, const Eigen::Matrix3Xd& to);

/// KITTI's relative error (Geiger et al. 2012): mean over sub-sequences starting at every pose, of
/// the `lengths` along the true path (KITTI: 100, 200, ..., 800 m), of translation error / length
/// (%) and rotation error / length (deg/100 m). Returns {percent, deg per 100 m, segments}.
std::tuple<double, double, std::size_t> kitti_relative_error(const std::vector<Eigen::Isometry3d>& estimate,
                                                             const std::vector<Eigen::Isometry3d>& truth,
                                                             const std::vector<double>& lengths = {100, 200, 300, 400, 500, 600, 700, 800});

}  // namespace quadrix
