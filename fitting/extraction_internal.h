// Helpers shared by the extraction translation units (not installed, not part of the API).
#pragma once

#include "fitting/extraction.h"

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <numeric>
#include <vector>

namespace quadrix::detail {

/// Disjoint sets over 0..size-1 with path halving; a set is named by its smallest member.
class UnionFind {
 public:
  /// Every element in a set of its own.
  explicit UnionFind(std::size_t size) : parent_(size) { std::iota(parent_.begin(), parent_.end(), 0u); }
  /// The smallest member of x's set.
  std::uint32_t find(std::uint32_t x) {
    while (parent_[x] != x) {
      parent_[x] = parent_[parent_[x]];
      x = parent_[x];
    }
    return x;
  }
  /// Joins the sets of a and b; false when they were one already.
  bool unite(std::uint32_t a, std::uint32_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return false;
    parent_[std::max(a, b)] = std::min(a, b);
    return true;
  }

 private:
  std::vector<std::uint32_t> parent_;
};

/// Milliseconds since `start`.
inline double elapsed_ms(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

/// Running first and second moments of a point set (for incremental PCA).
struct Moments {
  double count = 0.0;                                  ///< number of points
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();       ///< sum of x
  Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();     ///< sum of x x^T

  /// Adds one point.
  void add(const Eigen::Vector3d& x) {
    count += 1.0;
    sum += x;
    outer.noalias() += x * x.transpose();
  }
  /// Adds another moment set.
  void add(const Moments& other) {
    count += other.count;
    sum += other.sum;
    outer += other.outer;
  }
  /// Mean of the points.
  Eigen::Vector3d mean() const { return sum / count; }
  /// Covariance (population) of the points.
  Eigen::Matrix3d covariance() const {
    const Eigen::Vector3d m = mean();
    Eigen::Matrix3d c = outer / count - m * m.transpose();
    return 0.5 * (c + c.transpose());
  }
};

/// Eigen decomposition of a covariance, eigenvalues ascending (clamped at 0), eigenvectors as columns.
struct Principal {
  Eigen::Vector3d values = Eigen::Vector3d::Zero();       ///< ascending
  Eigen::Matrix3d vectors = Eigen::Matrix3d::Identity();  ///< column i belongs to values(i)
};

/// PCA of a covariance matrix.
inline Principal principal_axes(const Eigen::Matrix3d& covariance) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
  solver.computeDirect(covariance);
  Principal result;
  result.values = solver.eigenvalues().cwiseMax(0.0);
  result.vectors = solver.eigenvectors();
  return result;
}

/// Gathers the columns `indices` of `points`.
inline Eigen::Matrix3Xd gather_points(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& indices) {
  Eigen::Matrix3Xd out(3, static_cast<Eigen::Index>(indices.size()));
  for (std::size_t i = 0; i < indices.size(); ++i) out.col(static_cast<Eigen::Index>(i)) = points.col(indices[i]);
  return out;
}

/// Hash key of an integer voxel coordinate (21 bits per axis, offset so negatives work).
inline std::uint64_t voxel_key(std::int64_t x, std::int64_t y, std::int64_t z) {
  constexpr std::int64_t offset = 1 << 20;
  constexpr std::uint64_t mask = (1u << 21) - 1u;
  return ((static_cast<std::uint64_t>(x + offset) & mask) << 42) | ((static_cast<std::uint64_t>(y + offset) & mask) << 21) |
         (static_cast<std::uint64_t>(z + offset) & mask);
}

/// Whether a plane's points are big enough to be a plane element: at least minimum_plane_points
/// points over minimum_plane_voxels voxels, width s_s,2 >= minimum_plane_width and area proxy
/// s_s,1 s_s,2 >= minimum_plane_area (defined in extract_planes.cpp).
bool plane_is_large_enough(const Moments& moments, std::size_t voxels, const PlaneOptions& options);

/// The points of a cluster's dominant plane, or nothing: RANSAC + PCA refit with the plane merge
/// distance, kept when it holds at least `minimum_fraction` of the cluster, passes the voxel
/// eigenvalue-ratio test and plane_is_large_enough. Catches walls whose voxels all straddle an edge
/// (recesses, door jambs, facades with their side walls) and so never passed as planar voxels.
std::vector<std::uint32_t> dominant_cluster_plane(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& cluster,
                                                  const PlaneOptions& options, double minimum_fraction);

/// Parameters of the shape behind a static-scan element (DetectedShape's, in the cloud's frame).
struct ShapeParameters {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();   ///< plane normal, cylinder or cone axis (unit)
  Eigen::Vector3d point = Eigen::Vector3d::Zero();   ///< point on a plane, axis point, sphere centre, cone apex
  double size = 0.0;                                 ///< cylinder or sphere radius (m), cone half-angle (radians)
};

/// extract_elements on `points` = cloud.positions as doubles (the caller already holds them), so a
/// modelling run converts the cloud once. Static scans: `shape_parameters`, when given, gets the
/// parameters of each element's shape, in the order of the elements.
ExtractionResult extract_elements_of_points(const Eigen::Matrix3Xd& points, const PointCloud& cloud,
                                            const ExtractionOptions& options, const std::vector<std::uint32_t>& labels,
                                            std::vector<ShapeParameters>* shape_parameters = nullptr);

/// detect_shapes, also giving each element's shape parameters (when `parameters` is not null).
ExtractionResult detect_shapes_with_parameters(const Eigen::Matrix3Xd& points, const Eigen::Matrix3Xd& normals,
                                               const ExtractionOptions& options, std::vector<ShapeParameters>* parameters);

/// CGAL Shape_detection region growing of planes on `candidates` (k nearest neighbours, PCA
/// normals); defined in cgal_shape_detection.cpp. Returns the point-index sets of the regions.
std::vector<std::vector<std::uint32_t>> cgal_region_growing_planes(const Eigen::Matrix3Xd& points,
                                                                   const std::vector<std::uint32_t>& candidates,
                                                                   const PlaneOptions& options);

/// A piece of one detected shape (a tile's part of a primitive), for merge_shape_pieces.
struct ShapePiece {
  QuadricType type = QuadricType::Invalid;          ///< plane, circular cylinder, sphere or circular cone
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  ///< as ShapeParameters::axis
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  ///< as ShapeParameters::point
  double size = 0.0;                                ///< as ShapeParameters::size
  Eigen::Matrix3Xd points;                          ///< (an even sample of) its points
  double weight = 0.0;                              ///< its full point count: heavier pieces are merged into first
};

/// Joins pieces of one shape by the rules detect_shapes applies to the pieces Efficient RANSAC
/// returns (same type, close parameters, one shape refitted on both pieces' points explains them
/// all; then a shape the larger ones explain is dissolved; defined in cgal_shape_detection.cpp).
/// Returns, for each piece, the index of the piece it joined (itself when it stays), or -1 when its
/// shape was dissolved; kept pieces take the refitted parameters.
std::vector<int> merge_shape_pieces(std::vector<ShapePiece>& pieces, const ShapeDetectionOptions& options,
                                    const Eigen::Vector3d& up);

}  // namespace quadrix::detail
