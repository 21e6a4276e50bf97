// The alternative occlusion model of the scanner simulator (CGAL's AABB tree on meshes instead of
// exact ray–quadric intersection within bounds, kept to measure which is faster): every
// bounded primitive meshed (mesh_surface) into one CGAL AABB tree of triangles, first hit per
// ray. The exact RayCaster stays the simulator's caster; this one exists to measure the choice
// (microbenchmark_simulator) and to cross-check hits (tests). CGAL stays in the .cpp.
#pragma once

#include "experiments/synthetic/scanner_simulator.h"
#include "experiments/synthetic/synthetic_scene.h"

#include <Eigen/Core>

#include <cstddef>
#include <memory>

namespace quadrix {

/// Nearest-hit ray casting against the triangle meshes of a scene's bounded primitives.
class MeshRayCaster {
 public:
  /// Meshes every primitive at `resolution` segments per parametric direction (mesh_surface),
  /// keeps the triangles whose centroid lies inside the primitive's bounds (extent and polygon),
  /// and builds the AABB tree. Throws quadrix::Error for resolution outside 3..4096 or a porous primitive.
  explicit MeshRayCaster(const Scene& scene, int resolution = 64);
  ~MeshRayCaster();
  MeshRayCaster(const MeshRayCaster&) = delete;
  MeshRayCaster& operator=(const MeshRayCaster&) = delete;

  /// Nearest hit with range in (min_range, max_range] along a unit direction (primitive -1: none).
  RayHit cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double min_range, double max_range) const;
  /// Triangles in the tree.
  std::size_t triangle_count() const;

 private:
  struct Tree;
  std::unique_ptr<Tree> tree_;
};

}  // namespace quadrix
