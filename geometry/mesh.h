// Surface sampling and triangle meshes of quadrics inside bounded extents, for pictures
// (CloudCompare/MeshLab), simulation and augmentation.
#pragma once

#include "geometry/quadric.h"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace quadrix {

/// Bounds of a quadric's surface in its canonical frame (the frame of decompose().pose()):
/// the part of the surface with local coordinates inside [minimum, maximum] is kept.
struct LocalExtent {
  Eigen::Vector3d minimum = Eigen::Vector3d::Constant(-1.0);  ///< lower corner, metres, canonical frame
  Eigen::Vector3d maximum = Eigen::Vector3d::Constant(1.0);   ///< upper corner, metres, canonical frame
};

/// An indexed triangle mesh with optional per-vertex colours.
struct TriangleMesh {
  Eigen::Matrix3Xd vertices;                      ///< one column a vertex, metres
  std::vector<Eigen::Vector3i> triangles;         ///< vertex indices, counter-clockwise seen from outside
  std::vector<std::array<std::uint8_t, 3>> colors;  ///< RGB per vertex, empty when uncoloured
};

/// Points spread over the surface inside the extent with at most about `spacing` metres between
/// neighbours (point/line types: the point, or samples along the line). Deterministic for equal
/// inputs; throws quadrix::Error for a non-positive spacing or more than 5e7 points.
Eigen::Matrix3Xd sample_surface(const QuadricDecomposition& shape, const LocalExtent& extent, double spacing);

/// A triangle mesh of the surface inside the extent, `resolution` (3..4096) segments per parametric
/// direction; triangles leaving the extent are dropped (lines become thin tubes of radius 0.5% and
/// points octahedra of radius 1% of the extent's largest side, so they can be seen). Uncoloured.
TriangleMesh mesh_surface(const QuadricDecomposition& shape, const LocalExtent& extent, int resolution = 32);

/// Appends `part` to `mesh` (vertex indices shifted), giving every new vertex `color`; vertices of
/// `mesh` that had no colour yet become grey (128, 128, 128) so the colours stay one per vertex.
void append_mesh(TriangleMesh& mesh, const TriangleMesh& part, const std::array<std::uint8_t, 3>& color);

/// Display colour of a type (planes grey-blue, cylinders green, spheres red, cones orange, ...).
std::array<std::uint8_t, 3> quadric_type_color(QuadricType type);

}  // namespace quadrix
