// MeshRayCaster: CGAL 5.5 AABB_tree over the triangles of every meshed primitive.
#include "experiments/synthetic/mesh_ray_caster.h"

#include "geometry/error.h"
#include "geometry/mesh.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <cmath>
#include <optional>
#include <string>
#include <vector>

namespace quadrix {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Ray = Kernel::Ray_3;
using TriangleIterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, TriangleIterator>;
using TriangleTree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

Point to_point(const Eigen::Vector3d& p) { return Point(p.x(), p.y(), p.z()); }

}  // namespace

struct MeshRayCaster::Tree {
  std::vector<Triangle> triangles;
  std::vector<std::int32_t> primitive_of_triangle;  // scene primitive id of each triangle
  std::optional<TriangleTree> tree;
};

MeshRayCaster::MeshRayCaster(const Scene& scene, int resolution) : tree_(std::make_unique<Tree>()) {
  if (resolution < 3 || resolution > 4096)
    throw Error("MeshRayCaster: resolution must be 3..4096, got " + std::to_string(resolution));
  for (const ScenePrimitive& primitive : scene.primitives) {
    if (primitive.mean_free_path > 0.0)
      throw Error("MeshRayCaster: primitive '" + primitive.name + "' is a porous volume, which a mesh cannot stand for");
    const QuadricDecomposition shape = primitive_shape(primitive);
    const TriangleMesh mesh = mesh_surface(shape, primitive.extent, resolution);
    const Eigen::Isometry3d world_to_local = primitive.pose.inverse();
    for (const Eigen::Vector3i& triangle : mesh.triangles) {
      const Eigen::Vector3d a = mesh.vertices.col(triangle[0]), b = mesh.vertices.col(triangle[1]),
                            c = mesh.vertices.col(triangle[2]);
      // Polygon-bounded planes (pediments, recesses): keep the triangles inside the bounds.
      if (!inside_primitive_bounds(primitive, world_to_local * ((a + b + c) / 3.0), 1e-9)) continue;
      tree_->triangles.emplace_back(to_point(a), to_point(b), to_point(c));
      tree_->primitive_of_triangle.push_back(static_cast<std::int32_t>(primitive.id));
    }
  }
  tree_->tree.emplace(tree_->triangles.cbegin(), tree_->triangles.cend());
}

MeshRayCaster::~MeshRayCaster() = default;

std::size_t MeshRayCaster::triangle_count() const { return tree_->triangles.size(); }

RayHit MeshRayCaster::cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double min_range,
                           double max_range) const {
  RayHit hit;
  if (tree_->triangles.empty()) return hit;
  // Start the ray at min_range so hits nearer than it are skipped like in RayCaster::cast.
  const Eigen::Vector3d start = origin + min_range * direction;
  const Ray ray(to_point(start), to_point(start + direction));
  const auto intersection = tree_->tree->first_intersection(ray);
  if (!intersection) return hit;
  const Point* point = boost::get<Point>(&intersection->first);
  if (point == nullptr) return hit;  // a segment: the ray runs inside a triangle's plane (grazing), no return
  const double range = min_range + std::sqrt(CGAL::squared_distance(*point, ray.source()));
  if (!(range > min_range) || range > max_range) return hit;
  hit.range = range;
  hit.primitive = tree_->primitive_of_triangle[static_cast<std::size_t>(intersection->second - tree_->triangles.cbegin())];
  return hit;
}

}  // namespace quadrix
