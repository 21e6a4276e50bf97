// Quadric surfaces (paper §"Quadrics"): the 10 parameters, the 4x4 form, normalisation,
// decomposition Q = P^-T C P^-1 into type, scale, rotation, centre and degeneracy indicators,
// rigid transforms, distances, and construction from (type, scales, pose).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <string>

namespace quadrix {

/// The 10 quadric parameters q = [A, B, C, D, E, F, G, H, I, J] of paper Eq. (quadrics equation).
using Vector10d = Eigen::Matrix<double, 10, 1>;

/// Named quadric types: every type of the paper's Table "Characteristics of typical quadrics"
/// (point, line, plane, sphere, cylinder, cone; ellipsoid/elliptic variants split out), and the
/// other real types among the 17 classical quadrics. Canonical axis convention (the table's):
/// plane normal = axis a; line, cylinder and cone axis = axis c; paraboloid axis = axis c.
enum class QuadricType : std::uint8_t {
  Point,                  ///< imaginary cone diag(la, lb, lc, 0): one real point
  Line,                   ///< imaginary plane pair diag(la, lb, 0, 0): one real line along c
  Plane,                  ///< coincident planes diag(la, 0, 0, 0): normal along a
  Sphere,                 ///< diag(l, l, l, -1)
  Ellipsoid,              ///< diag(la, lb, lc, -1), not all equal
  CircularCylinder,       ///< diag(l, l, 0, -1), axis c
  EllipticCylinder,       ///< diag(la, lb, 0, -1), la != lb, axis c
  CircularCone,           ///< diag(l, l, -lc, 0), apex at the centre, axis c
  EllipticCone,           ///< diag(la, lb, -lc, 0), la != lb
  HyperboloidOneSheet,    ///< diag(+, +, -, -1)
  HyperboloidTwoSheets,   ///< diag(+, +, -, +1) after normalisation: two sheets along c
  EllipticParaboloid,     ///< x^2/a^2 + y^2/b^2 - 2z = 0 (opens towards +c)
  HyperbolicParaboloid,   ///< x^2/a^2 - y^2/b^2 - 2z = 0
  ParabolicCylinder,      ///< x^2/a^2 - 2y = 0 (opens towards +b, ruled along c)
  HyperbolicCylinder,     ///< diag(+, -, 0, -1)
  IntersectingPlanes,     ///< diag(+, -, 0, 0)
  ParallelPlanes,         ///< diag(+, 0, 0, -1)
  Imaginary,              ///< no real point (imaginary ellipsoid, cylinder or parallel planes)
  Invalid,                ///< quadratic part zero or parameters not finite
};

/// Lower-case name of a type ("point", "circular_cylinder", ...), stable for files and JSON.
std::string quadric_type_name(QuadricType type);
/// Parses a name produced by quadric_type_name (also accepts "cylinder" and "cone" for the circular
/// variants); throws quadrix::Error naming the text otherwise.
QuadricType quadric_type_from_name(const std::string& name);

/// How the centre equation Q33 t + l = 0 (paper Eq. (solve t)) is solved.
enum class CenterKind : std::uint8_t {
  Central,       ///< rank 3: unique centre (point, sphere, ellipsoid, cone, hyperboloids)
  LinearCenter,  ///< rank 2, consistent: a line of centres (line, cylinders)
  PlanarCenter,  ///< rank 1, consistent: a plane of centres (plane, parallel planes)
  NoCenter,      ///< inconsistent system (paraboloids, parabolic cylinder)
};

/// Degeneracy indicators of paper Table "Characteristics of typical quadrics": 1 = attribute defined
/// along that axis, 0 = degenerate. Stored as 0/1 doubles so diag(I) is `mask.asDiagonal()`.
struct DegeneracyIndicators {
  Eigen::Vector3d scale = Eigen::Vector3d::Zero();        ///< I_s
  Eigen::Vector3d rotation = Eigen::Vector3d::Zero();     ///< I_R
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();  ///< I_t
};

/// The indicators of a type as the paper's table gives them (ellipsoid, elliptic cylinder and
/// elliptic cone: every distinct axis defined; spheroid symmetry is resolved by decompose()).
DegeneracyIndicators degeneracy_indicators(QuadricType type);

/// Tolerances of the decomposition. Eigenvalue tests are relative to the largest |eigenvalue| of
/// Q33; the centre and constant tests are relative to the magnitudes whose cancellation produces
/// them, so every decision is invariant to the scale of Q and to the units of length.
struct DecompositionTolerances {
  double zero_eigenvalue = 1e-9;   ///< |l| below this * max|l| counts as zero (rank decisions)
  double equal_eigenvalues = 1e-6; ///< |la - lb| below this * max|l| counts as equal (symmetry)
  double consistency = 1e-9;       ///< null-space part of l below this * max(|l|, sqrt(max|l_i| |k|)): consistent
  double zero_constant = 1e-9;     ///< |c44| below this * max(|k|, |l . t|) counts as zero (rank of Q)
};

/// Geometric attributes read from Q (paper Eq. (geometry analysis) and Eq. (Q=PCP)).
struct QuadricDecomposition {
  QuadricType type = QuadricType::Invalid;            ///< classified type
  CenterKind center_kind = CenterKind::NoCenter;      ///< solution space of Q33 t + l = 0
  Eigen::Vector3d scale = Eigen::Vector3d::Zero();    ///< s_q = diag(I_s) sqrt(|1/l|); cones: tan of half-angles
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  ///< R_q: columns a, b, c ordered and sign-normalised, det +1
  Eigen::Vector3d center = Eigen::Vector3d::Zero();   ///< t_q (minimum-norm solution for non-central types)
  Eigen::Vector3d eigenvalues = Eigen::Vector3d::Zero();  ///< l_a, l_b, l_c of the normalised Q33 in axis order
  double constant = 0.0;                              ///< c44 of the canonical form after normalisation
  DegeneracyIndicators indicators;                    ///< I_s, I_R, I_t of this quadric (symmetry-aware)
  int rank_q33 = 0;                                   ///< numerical rank of Q33
  int rank_q = 0;                                     ///< numerical rank of Q

  /// The pose P_q = [R_q t_q; 0 1] that maps canonical coordinates into the world.
  Eigen::Isometry3d pose() const;
};

/// A quadric surface x^T Q x = 0 with Q symmetric 4x4 (paper Eq. (Q and normal)).
class Quadric {
 public:
  /// The zero quadric (type Invalid).
  Quadric() = default;
  /// From a 4x4 matrix; only its symmetric part is kept.
  explicit Quadric(const Eigen::Matrix4d& matrix);
  /// From q = [A..J] of paper Eq. (quadrics equation).
  static Quadric from_parameters(const Vector10d& parameters);
  /// Q = P^-T C P^-1 with C = diag(I_C[0]/s_a^2, I_C[1]/s_b^2, I_C[2]/s_c^2, I_C[3]) (paper Eq. (Q=PCP)
  /// and the statistical fitter's C_e = S^-T I_C S^-1). Point, line and plane: the scales weight Q
  /// but do not change the surface; a non-positive one there is replaced by 1 (so the zero scales
  /// decompose() reports for them round-trip). Cones: C = diag(1/s_a^2, 1/s_b^2, -1, 0) with s_a, s_b
  /// the tangents of the half-angles (s_c unused); intersecting planes: diag(1/s_a^2, -1, 0, 0).
  /// Paraboloids use their canonical equations (see QuadricType). Throws quadrix::Error for Invalid
  /// and Imaginary, non-finite input, or a non-positive scale on an axis the surface depends on.
  static Quadric from_canonical(QuadricType type, const Eigen::Vector3d& scale, const Eigen::Isometry3d& pose);

  /// The symmetric 4x4 matrix Q.
  const Eigen::Matrix4d& matrix() const { return matrix_; }
  /// q = [A, B, C, D, E, F, G, H, I, J].
  Vector10d parameters() const;
  /// f_q(x) = x^T Q x (paper Eq. (quadrics equation)).
  double evaluate(const Eigen::Vector3d& x) const;
  /// grad f_q(x) = (grad Q) x (paper Eq. (Q and normal)): the unnormalised surface normal.
  Eigen::Vector3d gradient(const Eigen::Vector3d& x) const;
  /// First-order (Sampson/Taubin) distance |f| / ||grad f||; 0 where both vanish.
  double sampson_distance(const Eigen::Vector3d& x) const;
  /// Paper's normalisation: Q * |prod l(Q33) / prod l(Q)| when c44 != 0, Q / ||Q|| otherwise,
  /// with the overall sign chosen so that most eigenvalues of Q33 are positive (c44 < 0 on ties).
  Quadric normalized(const DecompositionTolerances& tolerances = {}) const;
  /// The same surface after moving it by T: Q' = T^-T Q T^-1.
  Quadric transformed(const Eigen::Isometry3d& transform) const;
  /// Type, scale, rotation, centre and indicators (paper §"Quadric Geometry Analysis").
  QuadricDecomposition decompose(const DecompositionTolerances& tolerances = {}) const;

 private:
  Eigen::Matrix4d matrix_ = Eigen::Matrix4d::Zero();
};

/// The quadric a decomposition describes: from_canonical(type, scale, pose()) (zero for Invalid and
/// Imaginary types, whose matrix cannot be rebuilt from their attributes).
Quadric quadric_from_decomposition(const QuadricDecomposition& shape);

/// True Euclidean distance from x to the surface described by a decomposition, for point, line,
/// plane, sphere, ellipsoid, circular/elliptic cylinder and circular/elliptic cone; for the other
/// types it returns the first-order (Sampson) distance of the quadric rebuilt from `shape`;
/// Imaginary and Invalid shapes have no real point: +infinity.
double orthogonal_distance(const QuadricDecomposition& shape, const Eigen::Vector3d& x);

/// The closest point of the surface to x, for the same types as orthogonal_distance; other real
/// types: the first-order foot point x - f grad f / |grad f|^2; Imaginary and Invalid: x.
Eigen::Vector3d closest_surface_point(const QuadricDecomposition& shape, const Eigen::Vector3d& x);

}  // namespace quadrix
