// Element extraction (paper §"Quadric Extraction"): a point cloud is reduced to key elements —
// the ground E_g, planes E_p, lines E_l and object clusters E_o — each a subset of points with a
// semantic class. LiDAR scans use ground segmentation, voxel planes, clustering and RANSAC lines;
// static scans (monument and airborne presets) use CGAL Efficient RANSAC shape detection.
#pragma once

#include "fitting/scene_model.h"
#include "geometry/point_cloud.h"
#include "geometry/quadric.h"

#include <Eigen/Core>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace quadrix {

/// Where element classes come from (paper: semantic labels when reliable, else geometry).
enum class SemanticMode {
  Cluster,  ///< geometry only: ground, voxel planes, RANSAC lines, remaining clusters -> objects (default)
  Labels,   ///< per-point SemanticKITTI labels mapped by element_class_for_semantic_kitti_label
};

/// Plane extraction algorithm for non-ground points.
enum class PlaneMethod {
  VoxelRegionGrowing,  ///< the paper's: voxel eigenvalue-ratio test + region growing over planar voxels (default)
  CgalRegionGrowing,   ///< CGAL Shape_detection region growing on the point set (PCA normals, k neighbours)
};

/// Euclidean clustering backend (both give identical clusters: connected components at a radius).
enum class ClusterMethod {
  Grid,  ///< hash grid with cell = radius, union-find over neighbouring cells (default, faster)
  Pcl,   ///< pcl::EuclideanClusterExtraction with a k-d tree
};

/// Outcome of an extraction.
enum class ExtractionStatus {
  Ok,              ///< elements extracted
  EmptyCloud,      ///< no point inside the range limits
  NoGround,        ///< no ground found (other elements may still exist)
  NoElements,      ///< points present but no element passed the size tests
};

/// Lower-case name of a status ("ok", "empty_cloud", "no_ground", "no_elements").
std::string extraction_status_name(ExtractionStatus status);

/// Ground segmentation (replaces the paper's TRAVEL): a concentric-zone patch model like
/// Patchwork. The plane around the sensor is split into rings x sectors; in each patch a plane is
/// fitted by PCA to its lowest points and refined on its inliers; patches whose plane is upright,
/// flat and continuous (in height and slope) with a neighbour form regions, and the region holding the
/// most ground points is the ground. Handles slopes (each patch has its own plane) and kerbs (a kerb breaks
/// height continuity only by its own height, below `max_step_height`).
struct GroundOptions {
  std::vector<double> ring_edges = {0.0, 4.0, 8.0, 12.0, 16.0, 22.0, 30.0, 40.0, 55.0, 80.0, 200.0};  ///< ring radii around the sensor, m
  int sectors_near = 16;                  ///< sectors of the innermost ring (later rings get proportionally more, capped)
  int sectors_max = 64;                   ///< upper bound on sectors per ring
  int minimum_patch_points = 10;          ///< patches with fewer points are not fitted
  double seed_height = 0.4;               ///< seed points: within this height (m) above the mean of the lowest points
  int lowest_points = 20;                 ///< how many lowest points define the patch floor
  double inlier_distance = 0.15;          ///< point-to-patch-plane distance (m) for ground points
  int refinement_iterations = 3;          ///< PCA refits on inliers
  double max_slope_deg = 25.0;            ///< patch normal at most this far from the up axis, degrees
  double max_flatness = 0.01;             ///< smallest / sum of eigenvalues of an accepted patch (planarity)
  double max_step_height = 0.4;           ///< height jump (m) allowed between neighbouring patch planes at their shared border
  double max_neighbour_angle_deg = 15.0;  ///< angle allowed between neighbouring patch normals, degrees
};

/// Paper's plane extraction (G3Reg-style): voxelise P \ E_g, keep voxels whose eigenvalue ratio
/// lambda_2 / lambda_1 (second smallest / smallest) exceeds the threshold, merge neighbouring planar
/// voxels whose normals agree and whose centroids lie near the growing plane.
struct PlaneOptions {
  PlaneMethod method = PlaneMethod::VoxelRegionGrowing;  ///< which algorithm
  double voxel_size = 1.0;             ///< plane voxel edge, m (HDL-64E: 1.0)
  double merge_distance = 0.20;        ///< centroid-to-plane distance for merging voxels / CGAL region distance, m (HDL-64E: 0.20)
  double normal_cosine = 0.95;         ///< |cos| between normals to merge (HDL-64E: 0.95)
  double eigenvalue_ratio = 30.0;      ///< lambda_2 / lambda_1 above which a voxel is planar (HDL-64E: 30)
  int minimum_voxel_points = 8;        ///< voxels with fewer points are not tested
  int minimum_plane_points = 80;       ///< planes with fewer points are returned to clustering
  int minimum_plane_voxels = 2;        ///< planes spanning fewer voxels are returned to clustering
  double minimum_plane_width = 0.5;    ///< second-largest statistical scale s_s,2 of a plane at least this, m
  double minimum_plane_area = 2.0;     ///< product of the two largest statistical scales s_s,1 s_s,2 (the plane's V_a) at least this, m^2
  int cgal_neighbours = 12;            ///< CgalRegionGrowing: k nearest neighbours for normals and growing
  double cluster_plane_coverage = 0.65;  ///< a cluster without a pole whose RANSAC planes together hold at least this fraction of it is split into those planes (walls whose voxels all straddle an edge)
  double cluster_plane_share = 0.25;     ///< each of those planes holds at least this fraction of the cluster points no earlier plane took
  double cluster_plane_distance = 0.1;   ///< point-to-plane distance of those planes' points, m (tighter than merge_distance: points near an edge between two walls stay with the other wall)
  double cluster_plane_width = 0.3;      ///< minimum_plane_width for those planes, m (spinning heads; mid360/avia presets: the full 0.5)
  double cluster_plane_area = 0.3;       ///< minimum_plane_area for those planes, m^2 (spinning heads; mid360/avia presets: the full 2.0)
  double cluster_plane_tilt_deg = 20.0;  ///< the smaller size tests hold for planes whose normal is within this of horizontal (walls); others need the full ones, degrees
};

/// Euclidean clustering of the points left after ground and planes (paper: clusters of TRAVEL).
struct ClusterOptions {
  ClusterMethod method = ClusterMethod::Grid;  ///< backend
  double radius = 0.5;                 ///< points closer than this join one cluster, m
  int minimum_points = 20;             ///< smaller clusters are dropped (HDL-64E: 20)
  int maximum_points = 20000;          ///< larger clusters are dropped (merged clutter)
  double maximum_extent = 20.0;        ///< clusters with a larger bounding-box diagonal are dropped, m
  double minimum_height_above_ground = 0.2;  ///< cluster tops lower than this above the ground plane are dropped, m
};

/// RANSAC lines on clusters (paper: "RANSAC is applied to detect lines").
struct LineOptions {
  double inlier_distance = 0.12;       ///< point-to-line distance for RANSAC inliers, m
  double membership_distance = 0.25;   ///< points this close to an accepted (refined) line join it: the pole's thickness, m
  int iterations = 100;                ///< RANSAC hypotheses per line
  int minimum_points = 15;             ///< inliers a line needs
  double minimum_length = 1.2;         ///< extent of the inliers along the line, m
  double minimum_inlier_fraction = 0.6;  ///< inliers / cluster points: a line must dominate its cluster
  double max_tilt_deg = 30.0;          ///< line direction at most this far from the up axis (poles), degrees; 90 accepts any
  int maximum_lines_per_cluster = 2;   ///< lines taken from one cluster (pole + arm)
  std::uint64_t seed = 42;             ///< RANSAC random seed (deterministic)
};

/// Trunks under crowns (geometry-only mode; the paper's trunk and vegetation classes without
/// labels): a cluster whose foot is a narrow upright stem and whose top is a crown spreading in
/// both horizontal directions gives a Trunk element (the stem, fitted as an elliptic cylinder) and
/// a Vegetation element (the crown, an ellipsoid). Lamp posts (arm and lamp are thin) and sign
/// posts (the sign is flat) keep their line. A line whose stem is clearly thicker than a pole and is
/// cut by the top of the scanner's view is a Trunk element too: its crown is above the top beam.
/// `enabled` switches both rules. The 0.11 m radius separates the stems measured by
/// stem_radius_across_view (vlp64 preset): in KITTI 00 frames 0-5 and 4438 non-trunk stems reach
/// 0.081 m and trunks start at 0.114 m; on the synthetic street (seeds 1-10) lamp posts reach
/// 0.088 m and trunks start at 0.112 m. Stems farther than about 25 m are too sparse to measure.
struct TrunkOptions {
  bool enabled = true;                 ///< look for a trunk in every cluster before its lines (off in the mid360/avia presets)
  double slice_height = 0.25;          ///< the stem is grown upward from the cluster's foot in slices this tall, m
  double maximum_radius = 0.5;         ///< every stem point lies within this horizontal distance of the stem's centre line, m
  double minimum_height = 1.0;         ///< the stem is at least this tall, m
  int minimum_points = 15;             ///< points a stem needs
  int minimum_crown_points = 30;       ///< points the crown (everything above the stem) needs
  double minimum_crown_spread = 0.2;   ///< the crown's smaller horizontal standard deviation at least this, m (a crown is round, a sign or an arm is thin)
  double crownless_minimum_radius = 0.11;  ///< an upright line whose stem measures at least this radius across the line of sight (stem_radius_across_view) is a Trunk even without a crown; poles are thinner, m (0: off)
  int crownless_slice_points = 5;      ///< a slice of that stem is measured only when it holds at least this many points (sparse far stems are not measured and stay lines)
  double crownless_top_tolerance_deg = 0.5;  ///< ... and only when the stem reaches the top of the scanner's view (stem_reaches_top_of_view): its top lies within this elevation angle of the highest point seen in its azimuth span, degrees
};

/// Stems inside clusters (geometry-only mode, beyond the paper): a cluster that is neither a tree
/// with a bare foot (TrunkOptions) nor a pole (LineOptions) may still hold a trunk standing in a
/// hedge or a pole beside a car. The cluster is cut into horizontal slices; the points of a slice
/// are linked into blobs; a blob within `maximum_radius` of its centre whose slice has at most one
/// other point within `isolation_radius` is a section; sections above one another make a stem,
/// which becomes a Line element (a trunk's thickness, measured from two places, falls on both sides
/// of TrunkOptions::crownless_minimum_radius too often to split the class). Off by default: on the
/// synthetic validation set under random yaw it turned one answer into an `ok` and wrong half turn
/// (docs/modelling.md gives the measurements).
struct StemOptions {
  bool enabled = false;                ///< look for stems in clusters that gave no trunk and no line (never in the mid360/avia presets)
  double slice_height = 0.3;           ///< height of a slice along the up axis, m (about 5 HDL-64E beams on a stem 10 m away)
  double link_distance = 0.15;         ///< points of a slice closer than this horizontally are one blob, m
  double maximum_radius = 0.35;        ///< a section's points lie within this of its centre: a trunk's half-width, m
  double isolation_radius = 0.8;       ///< a section has at most one other point of its slice within this of its centre, m
  double link_offset = 0.3;            ///< sections of slices up to two apart join one stem when their centres are this close, m
  double minimum_span = 1.0;           ///< a stem spans at least this height, m
  double minimum_top = 2.0;            ///< and reaches at least this high above the cluster's lowest point (a pedestrian does not), m
  int minimum_sections = 3;            ///< and has at least this many sections
  int minimum_points = 8;              ///< and this many points
};

/// CGAL Efficient RANSAC for static scans (Schnabel et al. 2007). Every parameter is set
/// explicitly (CGAL 5.5 defaults disagree with its documentation).
struct ShapeDetectionOptions {
  double simplification_voxel = 0.05;  ///< grid simplification before normals, m (0: off)
  int normal_neighbours = 18;          ///< k of CGAL jet normal estimation
  double probability = 0.01;           ///< probability to miss the largest candidate shape
  int minimum_points = 200;            ///< min_points: smallest shape, points
  double epsilon = 0.03;               ///< max point-to-shape distance, m
  double cluster_epsilon = 0.15;       ///< max distance between connected points of a shape, m
  double normal_threshold = 0.9;       ///< min |cos| between point normal and shape normal
  bool detect_planes = true;           ///< look for planes
  bool detect_cylinders = true;        ///< look for cylinders
  bool detect_spheres = true;          ///< look for spheres
  bool detect_cones = true;            ///< look for cones
  bool detect_tori = false;            ///< look for tori (not quadrics: kept as Object elements, fitted as ellipsoids)
  bool mark_ground = true;             ///< the lowest large plane whose normal is within 10 deg of up becomes the Ground
  bool merge_equal_shapes = true;      ///< merge shapes of one type with the same parameters (RANSAC returns one connected piece per shape, so a surface cut by occlusion shadows comes back in pieces)
  double merge_angle_deg = 3.0;        ///< merging: normals / axes within this angle, degrees
  double merge_distance = 0.15;        ///< merging: plane offsets, axis lines, centres and apexes within this distance, m
  double merge_radius_fraction = 0.3;  ///< merging: radii within this fraction, axes and centres within merge_distance plus this fraction of the radius (cones: half-angles within merge_angle_deg); the refit then decides
  double explained_rms = 0.5;          ///< a (refitted or simpler) shape explains points when their RMS distance to it is at most this fraction of epsilon ...
  double explained_fraction = 0.9;     ///< ... and at least this fraction of them lie within epsilon
  double merge_plane_gap = 5.0;        ///< merging planes: only pieces whose points come within about this distance, m (coplanar faces apart stay apart; the ground and 0: any distance)
  double minimum_cone_angle_deg = 5.0; ///< cones narrower than this are cylinders: a cylinder becomes a cone (fitted from its normals, or a detected cone refined on both) only at this half-angle or more, degrees
  double absorb_fraction = 0.8;        ///< a shape whose points larger shapes explain (within epsilon) at this fraction is dissolved into them (> 1: off)
  std::uint32_t seed = 7;              ///< seed of CGAL's default random generator before detection (deterministic runs)
};

/// Everything extraction needs. Defaults are the HDL-64E values of the released configs.
struct ExtractionOptions {
  std::string preset = "vlp64";        ///< name of the preset these values came from (reported)
  SemanticMode semantic_mode = SemanticMode::Cluster;  ///< geometry-only or label-driven
  std::vector<ElementClass> label_classes;  ///< labels mode: the classes taken from the labels, among line, vehicle, trunk and vegetation (empty: every class); points of other classes go through the geometry-only pipeline as if unlabelled (a car detector's output, or measuring which classes matter)
  bool static_scan = false;            ///< true: CGAL Efficient RANSAC shapes instead of the LiDAR pipeline
  double minimum_range = 2.0;          ///< points nearer the sensor are dropped (ego vehicle), m
  double maximum_range = 80.0;         ///< points farther away are dropped, m (0: unlimited)
  int ground_class = -1;               ///< static scans: points whose label (a LAS file's ASPRS classification, PointCloud::labels) is this class are the Ground element, the shapes are detected among the others; without such points the ground is the lowest large horizontal plane (-1: always that; airborne preset: 2, ASPRS ground)
  double isolation_cell = 0.3;         ///< points in range with no other point in their cube of this edge or the 26 around are left out before modelling (spurious returns), m (0: every point kept)
  int isolation_neighbours = 1;        ///< ... or with fewer than this many other points there
  Eigen::Vector3d sensor_origin = Eigen::Vector3d::Zero();  ///< scanner position (ranges, patch centre, normal orientation)
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();            ///< up axis of the cloud (unit after normalisation)
  GroundOptions ground;                ///< ground segmentation
  PlaneOptions planes;                 ///< plane extraction
  ClusterOptions clusters;             ///< clustering
  LineOptions lines;                   ///< line RANSAC
  TrunkOptions trunks;                 ///< trunks separated from their crowns
  StemOptions stems;                   ///< trunks and poles standing inside clusters
  ShapeDetectionOptions shapes;        ///< static-scan shape detection
};

/// Parses a comma-separated list of class names for ExtractionOptions::label_classes
/// ("vehicle,trunk,line"); throws quadrix::Error naming a name that is not line, vehicle, trunk or vegetation.
std::vector<ElementClass> parse_label_classes(const std::string& names);

/// Presets from the released configs (REFERENCE.md "Extraction parameters per sensor"):
/// vlp64 (HDL-64E), vlp16, mid360, avia, monument (static TLS scan, CGAL shapes), airborne
/// (nadir airborne laser scan, 0.5-2 points/m^2: roofs and ground, CGAL planes). Throws
/// quadrix::Error naming the valid presets otherwise.
ExtractionOptions extraction_preset(const std::string& name);
/// Names accepted by extraction_preset, in listing order.
std::vector<std::string> extraction_preset_names();

/// One key element: points of the cloud with a semantic class.
struct Element {
  ElementClass element_class = ElementClass::Object;  ///< semantic class (decides the fitted type)
  std::vector<std::uint32_t> point_indices;           ///< indices into the input cloud
  QuadricType detected_type = QuadricType::Invalid;   ///< shape a detector found (CGAL shapes), Invalid otherwise
};

/// The ground plane and which points belong to it.
struct GroundSegmentation {
  std::vector<std::uint32_t> ground_indices;   ///< points on the ground
  std::vector<std::uint32_t> other_indices;    ///< the remaining candidate points
  std::vector<float> other_heights;            ///< height of each other_indices point above the ground (its patch plane, else the global plane), m
  bool found = false;                          ///< whether any ground patch was accepted
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< PCA normal of the ground points near the sensor, pointing up
  double offset = 0.0;                         ///< plane normal . x + offset = 0
  int patches_accepted = 0;                    ///< ground patches kept
  int patches_fitted = 0;                      ///< patches with enough points to test
};

/// The points an extraction worked on (those within the range limits that keep company by the
/// isolated-point rule) and the rule that chose them: the registration's checks reuse them when
/// they crop and leave out isolated points by the same rule.
struct MeasuredPoints {
  std::vector<std::uint32_t> indices;                   ///< indices into the cloud, ascending
  std::size_t cloud_size = 0;                           ///< points of the cloud they index
  Eigen::Vector3d sensor_origin = Eigen::Vector3d::Zero();  ///< ExtractionOptions::sensor_origin the range was measured from
  double minimum_range = 0.0;                           ///< ExtractionOptions::minimum_range used, m
  double maximum_range = 0.0;                           ///< ExtractionOptions::maximum_range used, m (0: none)
  double isolation_cell = 0.0;                          ///< ExtractionOptions::isolation_cell used, m (0: no point left out)
  int isolation_neighbours = 1;                         ///< ExtractionOptions::isolation_neighbours used
};

/// Everything an extraction returns.
struct ExtractionResult {
  ExtractionStatus status = ExtractionStatus::Ok;  ///< outcome
  std::string message;                             ///< why, for non-ok statuses
  std::vector<Element> elements;                   ///< the key elements (ground first when found)
  bool has_ground = false;                         ///< whether a ground was found
  Eigen::Vector3d ground_normal = Eigen::Vector3d::UnitZ();  ///< unit normal of the ground, pointing up
  double ground_offset = 0.0;                      ///< ground plane normal . x + offset = 0
  std::string ground_source;                       ///< static scans: "classification" (ExtractionOptions::ground_class), "geometry" (lowest large horizontal plane) or "" (no ground)
  std::size_t points_in_range = 0;                 ///< points kept by the range limits
  std::size_t isolated_points = 0;                 ///< of those, points left out as isolated (ExtractionOptions::isolation_cell)
  MeasuredPoints measured;                         ///< the points in range that keep company, which the extraction worked on
  std::map<std::string, double> timings_ms;        ///< per-stage wall times
};

/// Ground segmentation of the points `candidates` (indices into `points`), paper step 1(a).
GroundSegmentation segment_ground(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& candidates,
                                  const GroundOptions& options, const Eigen::Vector3d& sensor_origin,
                                  const Eigen::Vector3d& up);

/// Plane extraction on `candidates`, paper step 1(b). Returns Plane elements; `remaining` gets the
/// candidates not in any plane.
std::vector<Element> extract_planes(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& candidates,
                                    const PlaneOptions& options, std::vector<std::uint32_t>& remaining);

/// Euclidean clusters of `candidates` (connected components at options.radius), sizes within
/// [minimum_points, maximum_points], largest first. Extent and ground-height filters are not applied here.
std::vector<std::vector<std::uint32_t>> euclidean_clusters(const Eigen::Matrix3Xd& points,
                                                           const std::vector<std::uint32_t>& candidates,
                                                           const ClusterOptions& options);

/// RANSAC lines in one cluster, paper step 1(c). Returns Line elements; `remaining` gets the cluster
/// points not on a line.
std::vector<Element> extract_lines(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& cluster,
                                   const LineOptions& options, const Eigen::Vector3d& up,
                                   std::vector<std::uint32_t>& remaining);

/// A trunk under a crown in one cluster (TrunkOptions): on success `trunk` gets the stem points,
/// `crown` the rest, and the result is true; otherwise both are empty and the result is false.
bool separate_trunk(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& cluster,
                    const TrunkOptions& options, const Eigen::Vector3d& up, std::vector<std::uint32_t>& trunk,
                    std::vector<std::uint32_t>& crown);

/// Stems of one cluster (StemOptions): the point-index sets of every stem found, each sorted; the
/// cluster's other points are not returned.
std::vector<std::vector<std::uint32_t>> find_stems(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& cluster,
                                                   const StemOptions& options, const Eigen::Vector3d& up);

/// Radius of an upright stem (a line element) across the line of sight from `sensor_origin`, for
/// telling trunks from poles without a crown: the stem is cut along its PCA axis into
/// `options.slice_height` slices; each slice holding at least `options.crownless_slice_points`
/// points gives half its extent across the view direction (the visible half of a cylinder spans its
/// full diameter), and the result is the lower quartile of those half-widths (a bush or a sign at
/// part of the height does not widen it). Returns -1 when fewer slices than cover
/// `options.minimum_height` were measured (too sparse to tell).
double stem_radius_across_view(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& stem,
                               const TrunkOptions& options, const Eigen::Vector3d& sensor_origin);

/// True when an upright stem is cut by the top of a spinning scanner's view (so a crown above it
/// may be out of sight): among the `cloud` points whose azimuth about `up` (seen from
/// `sensor_origin`) lies within the stem's azimuth span, none is higher in elevation than the
/// stem's top by more than `options.crownless_top_tolerance_deg`. A pole or a pillar whose top the
/// scanner saw has beams passing over it that hit what stands behind.
bool stem_reaches_top_of_view(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& stem,
                              const std::vector<std::uint32_t>& cloud, const TrunkOptions& options,
                              const Eigen::Vector3d& up, const Eigen::Vector3d& sensor_origin);

/// Planes of one cluster (paper step 1(b) for walls the voxels missed): RANSAC planes taken one
/// after the other from the points no earlier plane holds, each holding at least
/// options.cluster_plane_share of them and passing the eigenvalue-ratio and size tests. Returned
/// (largest first) when together they hold at least options.cluster_plane_coverage of the
/// cluster; otherwise empty. Planes that enclose a convex solid (every plane with the cluster on
/// one side, one of them a roof facing `up`: a car, a box) are one object: then only a plane
/// holding cluster_plane_coverage of it with the full size tests is returned, if any.
std::vector<std::vector<std::uint32_t>> cluster_planes(const Eigen::Matrix3Xd& points,
                                                       const std::vector<std::uint32_t>& cluster,
                                                       const PlaneOptions& options, const Eigen::Vector3d& up);

/// CGAL Efficient RANSAC shapes (static scans). `normals` may be empty: they are then estimated
/// with CGAL jet fitting and oriented toward options.sensor_origin.
ExtractionResult detect_shapes(const Eigen::Matrix3Xd& points, const Eigen::Matrix3Xd& normals,
                               const ExtractionOptions& options);

/// Element class of a SemanticKITTI label id (lower 16 bits): car 10, bicycle 11, motorcycle 15,
/// truck 18, other-vehicle 20 (and moving 252-259) -> Vehicle; road 40, parking 44, sidewalk 48,
/// other-ground 49, terrain 72 -> Ground; building 50, fence 51, other-structure 52 -> Plane;
/// vegetation 70 -> Vegetation; trunk 71 -> Trunk; pole 80, traffic-sign 81 -> Line.
/// Returns false for the rest (unlabelled, outlier, person, bicyclist, other-object ...), which are ignored.
bool element_class_for_semantic_kitti_label(std::uint32_t label, ElementClass& element_class);

/// Whether `point` lies within the range limits around the sensor (minimum_range, maximum_range
/// from sensor_origin; maximum 0 is unlimited): the crop extraction starts with, and the one
/// registration's verification applies to the clouds it measures.
bool within_range(const Eigen::Vector3d& point, const ExtractionOptions& options);

/// Whole extraction of a cloud (paper §"Quadric Extraction"). In Labels mode `labels` holds one
/// SemanticKITTI label per point (else Error naming the counts); in Cluster mode it is ignored.
/// Degenerate input gives a status, never an exception.
ExtractionResult extract_elements(const PointCloud& cloud, const ExtractionOptions& options,
                                  const std::vector<std::uint32_t>& labels = {});

}  // namespace quadrix
