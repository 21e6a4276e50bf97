// A pose graph over SE(3) (paper §"Real-World Applications": the registration becomes a pose-graph
// constraint and the graph is optimised): one pose per scan, relative-pose edges with a 6x6
// information matrix, one fixed gauge pose per connected component. Solved with Ceres
// (Levenberg-Marquardt, quaternion manifold) in up to two stages. First, odometry edges plain and
// loop edges under the convex Huber kernel, which pulls a drifted trajectory onto its loops however
// far it drifted. Then, when there are switchable edges (unsure loops), from there with those under
// dynamic covariance scaling (DCS, Agarwal et al. 2013, the kernel of the paper's selection step),
// which scales down an edge that disagrees with the corrected graph. DCS from drifted odometry
// would scale every loop edge down (χ² is thousands there); on sure loop edges it also scales right
// ones down once calibrated residuals reach a few units of χ², which cost accuracy on the BALM walk
// (docs/mapping.md), so sure loop edges stay under Huber throughout.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstddef>
#include <string>
#include <vector>

namespace quadrix {

/// 6x6 information matrix of a relative pose, rotation (rad) then translation (m).
using Information6d = Eigen::Matrix<double, 6, 6>;

/// One relative-pose constraint: `measurement` maps the points of pose `from` into the frame of pose
/// `to` (T_to^-1 T_from), the convention of RegistrationResult::transform (source = from, target = to).
struct PoseGraphEdge {
  std::size_t from = 0;                                          ///< index of the source pose
  std::size_t to = 0;                                            ///< index of the target pose
  Eigen::Isometry3d measurement = Eigen::Isometry3d::Identity(); ///< T_to^-1 T_from as measured
  Information6d information = Information6d::Identity();        ///< inverse covariance of the error, rotation then translation, `to` frame
  bool robust = false;                                           ///< a sure loop edge: under Huber (else plain least squares)
  bool switchable = false;                                       ///< an unsure loop edge: left out of the first stage, under DCS in the second
};

/// Options of optimise_pose_graph.
struct PoseGraphOptions {
  double dcs_phi = 0.5;             ///< Φ of DCS: a robust edge with squared error χ² is scaled by s = min(1, 2Φ/(Φ+χ²)) (paper's selection kernel, Φ = 0.5)
  double huber_threshold = 2.0;     ///< the Huber kernel on robust edges is quadratic up to χ² = this², linear in the error beyond
  int maximum_iterations = 100;     ///< Levenberg-Marquardt iterations
  double function_tolerance = 1e-10;///< relative cost change at which Ceres stops
};

/// What optimise_pose_graph did.
struct PoseGraphSummary {
  double initial_cost = 0.0;            ///< the first stage's cost 1/2 Σ ρ(χ²) (Huber on robust edges) at the initial poses
  double final_cost = 0.0;              ///< the same cost at the optimised poses
  std::vector<double> initial_chi2;     ///< χ² of each edge (in edge order) before optimisation
  std::vector<double> final_chi2;       ///< χ² of each edge after optimisation
  std::vector<double> final_scale;      ///< DCS scale s of each switchable edge after (1 for the others)
  std::vector<std::size_t> component;   ///< connected component of each pose (0 = the one holding pose 0)
  std::vector<std::size_t> gauges;      ///< the pose held fixed in each component
  int iterations = 0;                   ///< Ceres iterations
  bool converged = false;               ///< Ceres reported convergence
  std::string report;                   ///< Ceres' brief report
};

/// The pose-graph error of one edge at poses T_from, T_to: e = [2 vec(q(Ê Z^-1)); p(Ê) - p(Z)] with
/// Ê = T_to^-1 T_from and Z the measurement (rotation then translation, in the `to` frame).
Eigen::Matrix<double, 6, 1> pose_graph_error(const Eigen::Isometry3d& from_pose, const Eigen::Isometry3d& to_pose,
                                             const Eigen::Isometry3d& measurement);

/// The DCS scale s = min(1, 2Φ/(Φ+χ²)) of an edge with squared error χ².
double dcs_scale(double chi2, double phi);

/// Connected components of `pose_count` poses joined by `edges`: component of each pose, numbered in
/// order of their smallest pose.
std::vector<std::size_t> pose_graph_components(std::size_t pose_count, const std::vector<PoseGraphEdge>& edges);

/// Optimises `poses` (sensor -> map) in place: minimise 1/2 Σ ρ_e(e_eᵀ Ω_e e_e) over every pose but the
/// first of each connected component, which stays where it is (the gauge), with ρ the identity for
/// plain edges, Huber for robust ones and DCS for switchable ones (second stage; file comment).
/// Costs and χ² are reported at the start and at the end. Throws quadrix::Error for an edge naming a pose
/// that does not exist or an information matrix that is not symmetric positive semi-definite.
PoseGraphSummary optimise_pose_graph(std::vector<Eigen::Isometry3d>& poses, const std::vector<PoseGraphEdge>& edges,
                                     const PoseGraphOptions& options = {});

/// What one group of edges was found to deserve by estimate_variance_factors: the factors by which
/// its rotation and translation variances are to be multiplied (> 1: they were given too small, the
/// edges are worse than stated; < 1: too large).
struct VarianceFactors {
  std::size_t edges = 0;     ///< edges of the group that took part (switchable ones do not)
  double rotation = 1.0;     ///< median of the group's rotation χ² over their redundancy, over the median of χ²(3)
  double translation = 1.0;  ///< the same for the translation block
  bool pooled = false;       ///< the group had fewer than the minimum edges and took its kind's pooled factors
  bool measured = true;      ///< false when a block had no edge the rest of the graph checks (e.g. the odometry of a session joined to nothing): that block's factor left at 1
};

/// Redundancy of one edge's rotation and translation blocks (each out of 3): the share of the block's
/// degrees of freedom the rest of the graph checks. 0: the edge alone fixes it (its residual is zero
/// whatever its error); 3: the rest of the graph fixes it (its residual is its whole error).
struct EdgeRedundancy {
  double rotation = 3.0;     ///< r = 3 - tr(W_rot (J C Jᵀ)_rot)
  double translation = 3.0;  ///< the same for the translation block
};

/// Each edge's redundancy at `poses` (a solved graph): r_b = 3 - tr(W_b (J C Jᵀ)_b) for the rotation
/// and translation blocks b (Förstner 1979), with W = ρ'(χ²) Ω the edge's information weighted by its
/// kernel (Huber for robust edges, DCS for switchable ones, options' thresholds), J the Jacobian of its
/// error over both poses' tangent steps, and C the poses' covariance, the inverse of the graph's
/// normal matrix Σ Jᵀ W J with the first pose of each connected component fixed (the gauge).
/// Throws quadrix::Error for an edge naming no pose, or a singular normal matrix (a pose no edge's
/// information reaches).
std::vector<EdgeRedundancy> edge_redundancies(const std::vector<Eigen::Isometry3d>& poses, const std::vector<PoseGraphEdge>& edges,
                                              const PoseGraphOptions& options = {});

/// Robust variance component estimation (Förstner 1979, with medians instead of sums so that a few
/// wrong edges under Huber do not set a group's scale): at `poses` (a solved graph), each group g of
/// edges gets σ²_g,rot = median_{e ∈ g}(3 χ²_e,rot / r_e,rot) / median(χ²(3)), χ²_e,rot = e_rotᵀ Ω_rot e_rot
/// with Ω_rot the diagonal 3x3 block of the edge's information and r_e,rot its redundancy
/// (edge_redundancies: E[χ²] = σ² r, so a group the graph trusts most, whose residuals are smallest,
/// is not taken for the most accurate); likewise for the translation block. Blocks with a redundancy
/// under 0.05 take no part (their own measurement fixes them). `group[k]` is edge k's group (<
/// group_count); `pool[g]` names the pool a group falls back to when it has fewer than
/// `minimum_edges` edges (e.g. all odometry or all loop edges: the pooled factors are the medians over
/// the pool's edges). Switchable edges take no part. A block with nothing to measure keeps its
/// factor at 1. Throws quadrix::Error when `group` and `edges` differ in size or a group or pool
/// index is out of range.
std::vector<VarianceFactors> estimate_variance_factors(const std::vector<Eigen::Isometry3d>& poses,
                                                       const std::vector<PoseGraphEdge>& edges,
                                                       const std::vector<std::size_t>& group, std::size_t group_count,
                                                       const std::vector<std::size_t>& pool, std::size_t minimum_edges,
                                                       const PoseGraphOptions& options = {});

/// Baarda's outlier statistic of one edge's rotation and translation blocks: χ²_b / r_b, the block's
/// χ² = e_bᵀ Ω_b e_b over its redundancy (edge_redundancies). For a single observation it is Baarda's
/// squared w-statistic (the residual over its own standard deviation); a right edge under a calibrated
/// information has expectation 1, a wrong one grows with the square of its error. 0 for a block under
/// 0.05 redundancy: the edge alone fixes it, nothing in the graph can test it.
struct EdgeOutlierStatistic {
  double rotation = 0.0;     ///< χ²_rot / r_rot
  double translation = 0.0;  ///< χ²_trans / r_trans
  /// The larger of the two.
  double largest() const { return rotation > translation ? rotation : translation; }
};

/// Each edge's EdgeOutlierStatistic at `poses` (a solved graph). Throws as edge_redundancies does.
std::vector<EdgeOutlierStatistic> edge_outlier_statistics(const std::vector<Eigen::Isometry3d>& poses,
                                                          const std::vector<PoseGraphEdge>& edges,
                                                          const PoseGraphOptions& options = {});

/// What snoop_pose_graph removed.
struct DataSnooping {
  std::vector<std::size_t> removed;  ///< indices into the edges given, in the order they left
  std::vector<double> statistic;     ///< each removed edge's EdgeOutlierStatistic::largest() when it left
  bool exhausted = false;            ///< stopped at maximum_removals with an edge still above the threshold
};

/// Baarda's iterative data snooping (Baarda 1968; one edge at a time, since a wrong edge pulls its
/// neighbours' residuals up with it): solve the graph of `edges` but those removed from `poses`, find the
/// edge with `testable` set whose EdgeOutlierStatistic::largest() is the largest, and remove it while
/// that exceeds `threshold`; at most `maximum_removals` edges. The informations must be calibrated
/// (estimate_variance_factors) for the threshold to mean anything. `poses` ends solved without the
/// removed edges. An edge that alone joins two parts of the graph is never removed (its redundancy is 0).
/// Throws quadrix::Error when `testable` and `edges` differ in size, or as edge_redundancies does.
DataSnooping snoop_pose_graph(std::vector<Eigen::Isometry3d>& poses, const std::vector<PoseGraphEdge>& edges,
                              const std::vector<bool>& testable, double threshold, std::size_t maximum_removals,
                              const PoseGraphOptions& options = {});

/// Scales an information matrix Ω into S Ω S with S = diag(1/√rotation_factor I₃, 1/√translation_factor
/// I₃): the rotation block's variances grow by rotation_factor, the translation block's by
/// translation_factor, and the matrix stays symmetric positive semi-definite (cross terms scaled by both).
Information6d scaled_information(const Information6d& information, double rotation_factor, double translation_factor);

}  // namespace quadrix
