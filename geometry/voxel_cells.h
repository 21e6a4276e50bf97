// Integer cells of a voxel grid and the isolated-point rule built on them: a spurious return
// (rain, dust, a multipath echo, an injected outlier) stands alone, while a point of a scanned
// surface has its scan line's neighbours within a few decimetres. The extraction leaves isolated
// points out before modelling, and registration's checks before measuring any overlap.
#pragma once

#include "geometry/point_cloud.h"

#include <Eigen/Core>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace quadrix {

/// A 64-bit key of an integer cell (21 bits per axis, so cells of 0.3 m reach ±314 km): the voxel
/// hashes of the isolation rule, the overlap and the dense search's thinning share it.
std::uint64_t cell_key(const Eigen::Vector3i& cell);

/// A hash map from cell_key to `Value`: open addressing with linear probing in flat arrays that
/// double when half full. The voxel hashes of a scan (isolated points, thinning, coverage, planar
/// voxels) insert ~10^5 cells and look up millions; std::unordered_map allocates a node per cell.
/// With this map, leaving out a KITTI scan's isolated points takes 4.2 ms instead of 6.6, and 18
/// instead of 48 with 30% outliers (microbenchmark_dense_search; Debian 12's Boost 1.74 has no flat map). Keys are below 2^63 (cell_key, the extraction's voxel_key); cells are
/// never removed.
template <typename Value>
class CellMap {
 public:
  /// An empty map with room for `expected` cells before it first grows.
  explicit CellMap(std::size_t expected = 0) { reset(std::max<std::size_t>(16, 2 * expected)); }

  /// The value of `key`, default-constructed and inserted when absent.
  Value& operator[](std::uint64_t key) {
    std::size_t slot = slot_of(key);
    while (keys_[slot] != key) {
      if (keys_[slot] == kEmpty) {
        if (2 * (size_ + 1) > keys_.size()) {
          grow();
          return (*this)[key];
        }
        keys_[slot] = key;
        ++size_;
        return values_[slot];
      }
      slot = (slot + 1) & mask_;
    }
    return values_[slot];
  }

  /// Inserts `key` with `value` when absent: the value held and whether it was inserted.
  std::pair<Value&, bool> try_emplace(std::uint64_t key, const Value& value) {
    const std::size_t before = size_;
    Value& held = (*this)[key];
    const bool inserted = size_ > before;
    if (inserted) held = value;
    return {held, inserted};
  }

  /// Inserts `key` with a default value; whether it was absent.
  bool insert(std::uint64_t key) { return try_emplace(key, Value{}).second; }

  /// The value of `key`, or nullptr when absent.
  const Value* find(std::uint64_t key) const {
    for (std::size_t slot = slot_of(key);; slot = (slot + 1) & mask_) {
      if (keys_[slot] == key) return &values_[slot];
      if (keys_[slot] == kEmpty) return nullptr;
    }
  }

  /// Cells held.
  std::size_t size() const { return size_; }

  /// Calls `visit(key, value)` for every cell, in no particular order.
  template <typename Visit>
  void for_each(const Visit& visit) const {
    for (std::size_t slot = 0; slot < keys_.size(); ++slot)
      if (keys_[slot] != kEmpty) visit(keys_[slot], values_[slot]);
  }

  /// Calls `visit(key, value)` for every cell, in no particular order, with the value writable.
  template <typename Visit>
  void for_each(const Visit& visit) {
    for (std::size_t slot = 0; slot < keys_.size(); ++slot)
      if (keys_[slot] != kEmpty) visit(keys_[slot], values_[slot]);
  }

 private:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};  // no cell_key reaches 2^63

  // Fibonacci hashing: the high bits of key * 2^64/phi, which spreads neighbouring cells apart.
  std::size_t slot_of(std::uint64_t key) const { return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> shift_); }

  // Empties the map into the smallest power of two of at least `minimum_slots` slots (and 16).
  void reset(std::size_t minimum_slots) {
    std::size_t slots = 16;
    int bits = 4;
    while (slots < minimum_slots) {
      slots *= 2;
      ++bits;
    }
    keys_.assign(slots, kEmpty);
    values_.assign(slots, Value{});
    mask_ = slots - 1;
    shift_ = 64 - bits;
    size_ = 0;
  }

  // Doubles the slots and inserts every cell again.
  void grow() {
    std::vector<std::uint64_t> keys = std::move(keys_);
    std::vector<Value> values = std::move(values_);
    reset(2 * keys.size());
    for (std::size_t slot = 0; slot < keys.size(); ++slot)
      if (keys[slot] != kEmpty) (*this)[keys[slot]] = std::move(values[slot]);
  }

  std::vector<std::uint64_t> keys_;
  std::vector<Value> values_;
  std::size_t mask_ = 0;
  int shift_ = 64;
  std::size_t size_ = 0;
};

/// The isolated-point rule for a point of `cell` over any occupancy structure: whether its
/// `others_in_own_cell` plus the points of the 26 cells around (`points_in(key)` counting a cell
/// by cell_key) reach `neighbours`. Stops counting as soon as they do.
template <typename PointsIn>
bool has_enough_company(const Eigen::Vector3i& cell, std::uint32_t others_in_own_cell, std::uint32_t neighbours,
                        const PointsIn& points_in) {
  std::uint32_t others = others_in_own_cell;
  for (int dx = -1; dx <= 1; ++dx)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dz = -1; dz <= 1; ++dz) {
        if (others >= neighbours) return true;
        if (dx != 0 || dy != 0 || dz != 0) others += points_in(cell_key(cell + Eigen::Vector3i(dx, dy, dz)));
      }
  return others >= neighbours;
}

/// The `candidates` (columns of `points`) that other candidates keep company: at least
/// `neighbours` of them lie in the point's cube of edge `cell` or in the 26 around it. Order is
/// kept; non-finite points are left out. `cell` must be positive and `neighbours` at least 1 (else
/// quadrix::Error).
std::vector<std::uint32_t> accompanied_points(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& candidates,
                                              double cell, int neighbours = 1);

/// The finite points of `cloud` that at least `neighbours` other points keep company, by the rule
/// of accompanied_points. Only positions are kept. `cell` must be positive and `neighbours` at
/// least 1 (else quadrix::Error).
PointCloud without_isolated_points(const PointCloud& cloud, double cell, int neighbours = 1);

}  // namespace quadrix
