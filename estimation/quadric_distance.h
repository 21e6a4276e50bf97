// The degeneracy-aware quadric distance between two corresponding quadrics and its analytic
// Jacobian (paper §"Quadric-based 6-DoF Transformation Estimation", Eq. (quadrics distance) and
// Eq. (Jacobian of quadrics distance)), the factors built from record correspondences (with the
// f_pp Manhattan filter, correspondence augmentation for non-central quadrics and the optional
// ground constraint), and the robust kernels shared by the refiners and candidate selection.
//
// Pose parametrisation (used by every refiner): T = (R, t) maps source coordinates into the target
// frame, x_y = R x_x + t. Increments delta = [phi; rho] in R^6 act on the right:
//     T [+] delta = (R Exp(phi), t + R rho),
// which equals T * Exp_SE(3)(delta) to first order (the SE(3) right perturbation); all Jacobians
// below are d e(T [+] delta) / d delta at delta = 0.
#pragma once

#include "geometry/quadric.h"
#include "geometry/quadric_record.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace quadrix {

/// e = [e_R (9); e_t (3)] of Eq. (quadrics distance).
using Vector12d = Eigen::Matrix<double, 12, 1>;
/// A 6-vector increment [phi; rho] (rotation first, then body-frame translation).
using Vector6d = Eigen::Matrix<double, 6, 1>;
/// d e / d delta: 12 residual rows, 6 increment columns [phi | rho].
using Matrix12x6d = Eigen::Matrix<double, 12, 6>;

/// One correspondence between a source record and a target record, by index.
struct RecordCorrespondence {
  std::size_t source_index = 0;  ///< index into the source records R_x
  std::size_t target_index = 0;  ///< index into the target records R_y
};

/// Where a factor comes from.
enum class FactorKind : std::uint8_t {
  Correspondence,  ///< a record pair (r_x, r_y) of the candidate set
  Augmented,       ///< a sample on the source's centre line/plane associated with the target quadric
  Ground,          ///< the ground-plane constraint (normal and offset alignment)
};

/// The per-correspondence data of the quadric distance, built once (Algorithm 1, AddFactor).
/// Principal axes enter only through cross products, which vanish for parallel AND antiparallel
/// axes, so the +/- sign ambiguity of eigenvectors (paper: r_q = +/- R_q[:, i]) does not matter.
struct QuadricFactor {
  Eigen::Matrix3d source_axes = Eigen::Matrix3d::Identity();  ///< R̂_q,x: decomposed principal axes of the source (columns)
  Eigen::Vector3d source_center = Eigen::Vector3d::Zero();    ///< t_f,x: full centre of the source (or an augmented sample), metres
  Eigen::Matrix3d target_axes = Eigen::Matrix3d::Identity();  ///< R̂_q,y: decomposed principal axes of the target (columns)
  Eigen::Vector3d target_center = Eigen::Vector3d::Zero();    ///< t_f,y: full centre of the target, metres
  Eigen::Vector3d rotation_mask = Eigen::Vector3d::Zero();    ///< I_R,y (times I_R,x, see make_quadric_factor): axes whose alignment counts
  Eigen::Vector3d translation_mask = Eigen::Vector3d::Zero(); ///< I_t,y: target axes along which the centre offset counts
  double weight = 1.0;                                        ///< w: the squared residual is multiplied by w (>= 0)
  FactorKind kind = FactorKind::Correspondence;               ///< origin of the factor
  std::size_t source_index = 0;                               ///< source record index (ground factor: 0)
  std::size_t target_index = 0;                               ///< target record index (ground factor: 0)
};

/// Builds the factor of one record pair from the decompositions of their quadrics. The rotation
/// mask is I_R,y ⊙ I_R,x: identical to the paper's I_R,y whenever both quadrics have the same type,
/// and it refuses to align a target axis with a source axis that is itself undefined (e.g. a
/// spheroid matched to a slightly elliptic target). The translation mask is I_t,y.
QuadricFactor make_quadric_factor(const QuadricRecord& source, const QuadricDecomposition& source_shape,
                                  const QuadricRecord& target, const QuadricDecomposition& target_shape,
                                  std::size_t source_index = 0, std::size_t target_index = 0);

/// Same, decomposing both records' quadrics with default tolerances.
QuadricFactor make_quadric_factor(const QuadricRecord& source, const QuadricRecord& target);

/// e = [e_R; e_t] of Eq. (quadrics distance) at pose T, unweighted:
/// e_R[3i..3i+2] = I'_R[i] (R R̂_x[:,i]) x R̂_y[:,i],  e_t = diag(I_t) R̂_y^T (R t_f,x + t - t_f,y).
Vector12d quadric_distance(const QuadricFactor& factor, const Eigen::Isometry3d& transform);

/// e and its analytic Jacobian d e(T [+] delta)/d delta at delta = 0 (Eq. (Jacobian of quadrics
/// distance), re-derived for the right perturbation above):
///   d e_R,i / d phi = I_R[i] [R̂_y[:,i]]x R [R̂_x[:,i]]x,   d e_R / d rho = 0,
///   d e_t / d phi  = -diag(I_t) R̂_y^T R [t_f,x]x,          d e_t / d rho = diag(I_t) R̂_y^T R.
/// (The paper's d e_t/d t = diag(I_t) R̂_y^T is the derivative w.r.t. a world-frame translation;
/// with the body-frame increment rho it gains the factor R.) Both outputs are unweighted.
void quadric_distance_with_jacobian(const QuadricFactor& factor, const Eigen::Isometry3d& transform,
                                    Vector12d* residual, Matrix12x6d* jacobian);

/// The ground plane of one cloud: points x with normal . x + offset = 0 (normal need not be unit).
struct GroundPlane {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< v̂_g, upward normal of the ground
  double offset = 0.0;                                ///< d in n . x + d = 0 (the pair (n, d) is normalised by norm(n))
};

/// The ground constraint: a plane-to-plane factor aligning R n_x with n_y (rotation about the
/// normal is free) and putting the source ground point -d_x n_x on the target ground plane
/// (normal offset only). It is the quadric factor of two planes (I_R = I_t = [1,0,0]), except that
/// the rotation residual is multiplied by `tilt_lever_arm` (metres): with L > 1 a tilt θ costs what
/// lifting a ground point L metres out by L sin θ would, comparable with the centres' metres.
/// Throws quadrix::Error if a normal is zero or not finite, the weight is negative, or the lever
/// arm is not finite and positive.
QuadricFactor make_ground_factor(const GroundPlane& source_ground, const GroundPlane& target_ground,
                                 double weight = 1.0, double tilt_lever_arm = 1.0);

/// True when a structure's defined principal axes (I_R[i] = 1, axes of `shape.rotation`) are each
/// within `tolerance_degrees` of parallel, antiparallel or perpendicular to `ground_normal`
/// (the negation of the paper's f_pp: f_pp(r) = !is_manhattan_aligned). Axes with I_R = 0 are
/// ignored; a shape without defined axes (point, sphere) is aligned.
bool is_manhattan_aligned(const QuadricDecomposition& shape, const Eigen::Vector3d& ground_normal,
                          double tolerance_degrees);

/// How factors are built from a set of record correspondences (Algorithm 1, inner loop).
struct FactorBuildOptions {
  bool augment_non_central = true;  ///< Augment(): 2 samples on linear centres, 4 on planar centres
  double augmented_weight = 1.0;    ///< w of each augmented factor
  std::optional<Eigen::Vector3d> source_ground_normal;  ///< v̂_g of the source cloud; unset: no f_pp filter
  std::optional<Eigen::Vector3d> target_ground_normal;  ///< v̂_g of the target cloud; unset: no f_pp filter
  double manhattan_tolerance_degrees = 10.0;            ///< δ_g of f_pp, degrees (10 refinement, 5 selection)
  std::vector<std::uint32_t> structure_labels;          ///< labels f_pp applies to; empty: every non-central quadric
  std::optional<GroundPlane> source_ground;  ///< with target_ground: adds the ground constraint factor
  std::optional<GroundPlane> target_ground;  ///< with source_ground: adds the ground constraint factor
  double ground_weight = 1.0;                ///< w of the ground constraint factor
  double ground_tilt_lever_arm = 1.0;        ///< multiplies the ground factor's rotation residual, metres (make_ground_factor)
  bool use_rotation_error = true;            ///< keep e_R of Eq. (quadrics distance); false zeroes every factor's I_R (ablation "W/O e_R")
  bool use_translation_error = true;         ///< keep e_t of Eq. (quadrics distance); false zeroes every factor's I_t (ablation "W/O e_t")
};

/// The factors of one candidate set with counts of what happened to its correspondences.
struct FactorSet {
  std::vector<QuadricFactor> factors;     ///< correspondence, augmented and ground factors
  std::size_t correspondence_count = 0;   ///< correspondences given
  std::size_t filtered_count = 0;         ///< correspondences removed by f_pp
  std::size_t augmented_count = 0;        ///< augmented factors added
};

/// Decomposes every record's quadric once (reuse the result across candidates).
std::vector<QuadricDecomposition> decompose_records(const std::vector<QuadricRecord>& records,
                                                    const DecompositionTolerances& tolerances = {});

/// Builds the factors of Algorithm 1 for one candidate set: skip pairs whose source or target
/// structure fails f_pp, add the pair's factor, and Augment() non-central sources: 2 samples
/// t_f,x +/- r d (linear centre, d = the centre line direction) or 4 samples t_f,x +/- r d_1,
/// +/- r d_2 (planar centre), r = mean(s_f,x), directions = the columns of the full rotation R_f,x
/// along which I_t,x = 0; each sample is a point associated with the target quadric (rotation mask
/// 0, translation mask I_t,y). Throws quadrix::Error for an index out of range or decomposition
/// lists whose sizes differ from the record lists.
FactorSet build_quadric_factors(const std::vector<QuadricRecord>& source, const std::vector<QuadricDecomposition>& source_shapes,
                                const std::vector<QuadricRecord>& target, const std::vector<QuadricDecomposition>& target_shapes,
                                const std::vector<RecordCorrespondence>& correspondences,
                                const FactorBuildOptions& options = {});

/// Robust kernels rho(s) applied to a factor's weighted squared norm s = w ||e||^2.
enum class RobustLoss : std::uint8_t {
  None,    ///< rho(s) = s
  Huber,   ///< rho(s) = s if s <= a^2, else 2 a sqrt(s) - a^2  (a = scale)
  Cauchy,  ///< rho(s) = a^2 log(1 + s / a^2)
  Dcs,     ///< dynamic covariance scaling (Agarwal et al. 2013), Phi = scale:
           ///< rho(s) = s if s <= Phi, else Phi (3 s - Phi) / (Phi + s); its weight rho'(s) =
           ///< min(1, 2 Phi / (Phi + s))^2 is the square of the DCS scaling factor.
};

/// rho, rho' and rho'' of a kernel at s (s >= 0).
struct LossValue {
  double rho = 0.0;         ///< rho(s)
  double derivative = 1.0;  ///< rho'(s)
  double second = 0.0;      ///< rho''(s)
};

/// Evaluates a robust kernel; throws quadrix::Error if scale <= 0 for a kernel that uses it.
LossValue evaluate_robust_loss(RobustLoss loss, double scale, double squared_norm);

/// Lower-case kernel name ("none", "huber", "cauchy", "dcs").
const char* robust_loss_name(RobustLoss loss);
/// Parses a kernel name; throws quadrix::Error naming the text otherwise.
RobustLoss robust_loss_from_name(const std::string& name);

/// Cross-product (skew-symmetric) matrix [v]_x, so that [v]_x w = v x w.
inline Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

/// The pose update T [+] delta = (R Exp(phi), t + R rho) used by every refiner.
Eigen::Isometry3d apply_increment(const Eigen::Isometry3d& transform, const Vector6d& increment);

/// Rank analysis of H = sum_k w_k J_k^T J_k at `pose` (robust kernels not applied).
struct ConstraintAnalysis {
  int rank = 0;                          ///< eigenvalues of H above threshold * largest
  Vector6d eigenvalues = Vector6d::Zero();///< ascending eigenvalues of H
  std::vector<Vector6d> weak_directions; ///< eigenvectors of the eigenvalues below the threshold
};

/// Checks whether the factors constrain all 6 DoF at `pose` (used by every backend before it runs).
ConstraintAnalysis analyse_constraints(const std::vector<QuadricFactor>& factors, const Eigen::Isometry3d& pose,
                                       double relative_threshold = 1e-6);

/// F(T) = 1/2 sum_k rho(w_k ||e_k(T)||^2): the objective every backend minimises.
double refinement_cost(const std::vector<QuadricFactor>& factors, const Eigen::Isometry3d& pose,
                       RobustLoss loss = RobustLoss::None, double loss_scale = 1.0);

}  // namespace quadrix
