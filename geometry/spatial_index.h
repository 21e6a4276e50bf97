// Exact nearest-neighbour search over a fixed set of 3-D points (a k-d tree; nanoflann stays in
// the .cpp). Used wherever a stage needs the nearest of many points: SNN in candidate selection,
// point-to-plane alignment and normals in the dense search.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <memory>
#include <optional>
#include <vector>

namespace quadrix {

/// One neighbour found by a PointIndex query.
struct Neighbor {
  std::size_t index = 0;  ///< column of the indexed point
  double distance = 0.0;  ///< Euclidean distance to the query, metres
};

/// A k-d tree over the columns of a 3×N matrix; the points are copied, so the source may go away.
class PointIndex {
 public:
  /// Builds the tree over `points` (any N, including 0; non-finite points are rejected by Error).
  explicit PointIndex(Eigen::Matrix3Xd points);
  ~PointIndex();
  PointIndex(PointIndex&&) noexcept;             ///< movable
  PointIndex& operator=(PointIndex&&) noexcept;  ///< movable
  PointIndex(const PointIndex&) = delete;
  PointIndex& operator=(const PointIndex&) = delete;

  /// Number of indexed points.
  std::size_t size() const;
  /// The indexed points, one column each.
  const Eigen::Matrix3Xd& points() const;
  /// The nearest point whose `excluded[index]` is false, ties by the lowest index; nullopt when
  /// every point is excluded. `excluded` has size() entries (else quadrix::Error). Used for greedy
  /// one-to-one assignment: excluded points cost one flag test when the search reaches them.
  std::optional<Neighbor> nearest_not_excluded(const Eigen::Vector3d& query, const std::vector<bool>& excluded) const;
  /// The `count` nearest points to `query`, nearest first (fewer when the index holds fewer).
  std::vector<Neighbor> nearest(const Eigen::Vector3d& query, std::size_t count) const;
  /// The nearest point to `query` (nullopt for an empty index); allocates nothing, for inner loops such as ICP.
  std::optional<Neighbor> nearest(const Eigen::Vector3d& query) const;
  /// The nearest point to `query` within `maximum_distance` (nullopt when none is): the tree skips
  /// every branch beyond it, so a query far from all points (ICP from a wrong start) costs little.
  std::optional<Neighbor> nearest_within(const Eigen::Vector3d& query, double maximum_distance) const;

 private:
  struct Tree;
  std::unique_ptr<Tree> tree_;
};

}  // namespace quadrix
