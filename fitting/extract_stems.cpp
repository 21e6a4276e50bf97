// Stems inside a cluster (beyond the paper's geometry-only extraction): a trunk standing in a hedge,
// a pole beside a parked car. Horizontal slices of the cluster are split into blobs; a blob that is
// narrow and stands alone in its slice is a section of a stem, and sections above one another make
// the stem (slice-based stem detection, as in tree-stem mapping from laser scans).
#include "fitting/extraction.h"
#include "fitting/extraction_internal.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace quadrix {

namespace {

// One blob of a slice that could be a stem's section.
struct Section {
  long slice = 0;                        // slice number along the up axis
  Eigen::Vector2d centre;                // horizontal centre of its points
  std::vector<std::uint32_t> members;    // indices into the cluster
};

// Blobs of one slice: connected components of its points at `link` horizontally (a sweep along x).
std::vector<std::vector<std::uint32_t>> blobs_of_slice(const std::vector<Eigen::Vector2d>& horizontal,
                                                       std::vector<std::uint32_t> slice, double link) {
  std::sort(slice.begin(), slice.end(), [&](std::uint32_t a, std::uint32_t b) { return horizontal[a].x() < horizontal[b].x(); });
  detail::UnionFind sets(slice.size());
  for (std::uint32_t i = 0; i < slice.size(); ++i)
    for (std::uint32_t j = i + 1; j < slice.size() && horizontal[slice[j]].x() - horizontal[slice[i]].x() <= link; ++j)
      if ((horizontal[slice[j]] - horizontal[slice[i]]).squaredNorm() <= link * link) sets.unite(i, j);
  std::map<std::uint32_t, std::vector<std::uint32_t>> blobs;
  for (std::uint32_t i = 0; i < slice.size(); ++i) blobs[sets.find(i)].push_back(slice[i]);
  std::vector<std::vector<std::uint32_t>> result;
  for (auto& entry : blobs) result.push_back(std::move(entry.second));
  return result;
}

}  // namespace

std::vector<std::vector<std::uint32_t>> find_stems(const Eigen::Matrix3Xd& points, const std::vector<std::uint32_t>& cluster,
                                                   const StemOptions& options, const Eigen::Vector3d& up_axis) {
  std::vector<std::vector<std::uint32_t>> stems;
  if (!options.enabled || cluster.size() < static_cast<std::size_t>(std::max(options.minimum_points, 1)) ||
      !(options.slice_height > 0.0))
    return stems;
  const Eigen::Vector3d up = up_axis.normalized();
  const Eigen::Vector3d across = (std::abs(up.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY()).cross(up).normalized();
  const Eigen::Vector3d across_too = up.cross(across);
  std::vector<Eigen::Vector2d> horizontal(cluster.size());
  std::map<long, std::vector<std::uint32_t>> slices;
  double foot = 1e300;
  for (std::size_t i = 0; i < cluster.size(); ++i) foot = std::min(foot, points.col(cluster[i]).dot(up));
  for (std::size_t i = 0; i < cluster.size(); ++i) {
    const Eigen::Vector3d p = points.col(cluster[i]);
    horizontal[i] = Eigen::Vector2d(p.dot(across), p.dot(across_too));
    slices[static_cast<long>(std::floor((p.dot(up) - foot) / options.slice_height))].push_back(static_cast<std::uint32_t>(i));
  }
  // Sections: narrow blobs with at most one other point of the slice within isolation_radius of
  // their centre beyond the blob itself (a wall or a hedge around it has many).
  std::vector<Section> sections;
  for (const auto& [slice, members] : slices)
    for (std::vector<std::uint32_t>& blob : blobs_of_slice(horizontal, members, options.link_distance)) {
      Eigen::Vector2d centre = Eigen::Vector2d::Zero();
      for (const std::uint32_t i : blob) centre += horizontal[i];
      centre /= static_cast<double>(blob.size());
      double radius = 0.0;
      for (const std::uint32_t i : blob) radius = std::max(radius, (horizontal[i] - centre).norm());
      if (radius > options.maximum_radius) continue;
      std::size_t around = 0;
      for (const std::uint32_t i : members) {
        const double distance = (horizontal[i] - centre).norm();
        around += distance > radius + options.link_distance && distance <= options.isolation_radius ? 1 : 0;
      }
      // Only isolated sections make stems: one that touches a hedge or a car body would bring their
      // points with it; the stem is then the part that stands free.
      if (around > 1) continue;
      Section section;
      section.slice = slice;
      section.centre = centre;
      section.members = std::move(blob);
      sections.push_back(std::move(section));
    }
  // Stems: sections of slices up to two apart (one hidden by a branch or a gap between beams) whose
  // centres lie within link_offset of each other.
  detail::UnionFind chains(sections.size());
  for (std::uint32_t a = 0; a < sections.size(); ++a)
    for (std::uint32_t b = a + 1; b < sections.size(); ++b) {
      const long gap = std::abs(sections[b].slice - sections[a].slice);
      if (gap >= 1 && gap <= 2 && (sections[a].centre - sections[b].centre).norm() <= options.link_offset) chains.unite(a, b);
    }
  std::map<std::uint32_t, std::vector<std::size_t>> members_of_chain;
  for (std::uint32_t a = 0; a < sections.size(); ++a) members_of_chain[chains.find(a)].push_back(a);
  for (const auto& [root, chain] : members_of_chain) {
    long lowest = sections[chain.front()].slice, highest = lowest;
    std::vector<std::uint32_t> stem;
    for (const std::size_t a : chain) {
      lowest = std::min(lowest, sections[a].slice);
      highest = std::max(highest, sections[a].slice);
      for (const std::uint32_t i : sections[a].members) stem.push_back(cluster[i]);
    }
    const double span = static_cast<double>(highest - lowest + 1) * options.slice_height;
    const double top = static_cast<double>(highest + 1) * options.slice_height;
    if (span < options.minimum_span || top < options.minimum_top || static_cast<int>(chain.size()) < options.minimum_sections ||
        static_cast<int>(stem.size()) < options.minimum_points)
      continue;
    std::sort(stem.begin(), stem.end());
    stems.push_back(std::move(stem));
  }
  return stems;
}

}  // namespace quadrix
