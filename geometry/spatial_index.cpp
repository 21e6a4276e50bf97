// PointIndex: nanoflann's k-d tree (DESIGN.md: nanoflann only inside geometry's spatial search).
#include "geometry/spatial_index.h"

#include "geometry/error.h"

#include <nanoflann.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

namespace quadrix {

namespace {

// nanoflann's dataset adaptor over the columns of a 3×N matrix.
struct ColumnCloud {
  Eigen::Matrix3Xd points;
  std::size_t kdtree_get_point_count() const { return static_cast<std::size_t>(points.cols()); }
  double kdtree_get_pt(std::size_t index, std::size_t dimension) const {
    return points(static_cast<Eigen::Index>(dimension), static_cast<Eigen::Index>(index));
  }
  template <class BoundingBox>
  bool kdtree_get_bbox(BoundingBox&) const { return false; }
};

using KdTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, ColumnCloud>, ColumnCloud, 3,
                                                   std::size_t>;

// nanoflann result set keeping the nearest point not excluded, ties by the lowest index. Its
// worst distance sits one ulp above the best so points at exactly the best distance are still
// offered (nanoflann only offers points strictly nearer than the worst distance).
class NearestNotExcluded {
 public:
  explicit NearestNotExcluded(const std::vector<bool>& excluded) : excluded_(excluded) {}
  bool full() const { return found_; }
  double worstDist() const { return found_ ? std::nextafter(best_squared_, std::numeric_limits<double>::infinity()) : std::numeric_limits<double>::infinity(); }
  bool addPoint(double squared, std::size_t index) {
    if (excluded_[index]) return true;
    if (!found_ || squared < best_squared_ || (squared == best_squared_ && index < best_index_)) {
      found_ = true;
      best_squared_ = squared;
      best_index_ = index;
    }
    return true;
  }
  std::optional<Neighbor> result() const {
    if (!found_) return std::nullopt;
    return Neighbor{best_index_, std::sqrt(best_squared_)};
  }

 private:
  const std::vector<bool>& excluded_;
  bool found_ = false;
  double best_squared_ = 0.0;
  std::size_t best_index_ = 0;
};

}  // namespace

struct PointIndex::Tree {
  ColumnCloud cloud;
  KdTree tree;
  explicit Tree(Eigen::Matrix3Xd points)
      : cloud{std::move(points)}, tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10)) {
    if (cloud.points.cols() > 0) tree.buildIndex();
  }
};

PointIndex::PointIndex(Eigen::Matrix3Xd points) {
  for (Eigen::Index i = 0; i < points.cols(); ++i)
    if (!points.col(i).allFinite())
      throw Error("PointIndex: point " + std::to_string(i) + " is not finite (expected finite coordinates)");
  tree_ = std::make_unique<Tree>(std::move(points));
}

PointIndex::~PointIndex() = default;
PointIndex::PointIndex(PointIndex&&) noexcept = default;
PointIndex& PointIndex::operator=(PointIndex&&) noexcept = default;

std::size_t PointIndex::size() const { return tree_ ? tree_->cloud.kdtree_get_point_count() : 0; }

const Eigen::Matrix3Xd& PointIndex::points() const { return tree_->cloud.points; }

std::optional<Neighbor> PointIndex::nearest_not_excluded(const Eigen::Vector3d& query, const std::vector<bool>& excluded) const {
  if (excluded.size() != size())
    throw Error("PointIndex::nearest_not_excluded: " + std::to_string(excluded.size()) + " exclusion flags for " +
                std::to_string(size()) + " points (expected one per point)");
  if (size() == 0) return std::nullopt;
  NearestNotExcluded result(excluded);
  tree_->tree.findNeighbors(result, query.data(), nanoflann::SearchParams());
  return result.result();
}

std::optional<Neighbor> PointIndex::nearest(const Eigen::Vector3d& query) const {
  if (size() == 0) return std::nullopt;
  std::size_t index = 0;
  double squared = 0.0;
  nanoflann::KNNResultSet<double, std::size_t> result(1);
  result.init(&index, &squared);
  tree_->tree.findNeighbors(result, query.data(), nanoflann::SearchParams());
  return Neighbor{index, std::sqrt(squared)};
}

std::optional<Neighbor> PointIndex::nearest_within(const Eigen::Vector3d& query, double maximum_distance) const {
  if (size() == 0 || !(maximum_distance >= 0.0)) return std::nullopt;
  std::size_t index = 0;
  double squared = 0.0;
  nanoflann::KNNResultSet<double, std::size_t> result(1);
  result.init(&index, &squared);
  // The result set's worst distance bounds the search: leaves and branches beyond it are skipped,
  // and only a point strictly nearer is taken. The bound is a hair above maximum_distance squared
  // (the square of a distance need not round to its squared distance); the nearest point found
  // is then held to maximum_distance itself, as `nearest(query)` followed by a comparison would be.
  squared = maximum_distance * maximum_distance * (1.0 + 1e-12) + std::numeric_limits<double>::min();
  tree_->tree.findNeighbors(result, query.data(), nanoflann::SearchParams());
  if (result.size() == 0) return std::nullopt;
  const double distance = std::sqrt(squared);
  if (distance > maximum_distance) return std::nullopt;
  return Neighbor{index, distance};
}

std::vector<Neighbor> PointIndex::nearest(const Eigen::Vector3d& query, std::size_t count) const {
  count = std::min(count, size());
  std::vector<Neighbor> found;
  if (count == 0) return found;
  std::vector<std::size_t> indices(count);
  std::vector<double> squared(count);
  count = tree_->tree.knnSearch(query.data(), count, indices.data(), squared.data());
  found.reserve(count);
  for (std::size_t i = 0; i < count; ++i) found.push_back(Neighbor{indices[i], std::sqrt(squared[i])});
  return found;
}

}  // namespace quadrix
