// Sampling and meshing of quadric surfaces in their canonical frame (paper Eq. (Q=PCP): world =
// P_q * canonical), clipped to a LocalExtent. Every surface type is a set of parametric patches.
#include "geometry/mesh.h"

#include "geometry/constants.h"
#include "geometry/error.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>

namespace quadrix {
namespace {


/// One parametric patch of a canonical surface: map(u, v) for u in [u0, u1], v in [v0, v1].
struct Patch {
  std::function<Eigen::Vector3d(double, double)> map;  ///< canonical coordinates of (u, v)
  double u0 = 0.0, u1 = 0.0, v0 = 0.0, v1 = 0.0;        ///< parameter ranges
  bool v_periodic = false;                              ///< v wraps around (v1 is v0)
};

bool inside(const LocalExtent& extent, const Eigen::Vector3d& y, double slack) {
  return (y.array() >= extent.minimum.array() - slack).all() && (y.array() <= extent.maximum.array() + slack).all();
}

double extent_size(const LocalExtent& extent) { return (extent.maximum - extent.minimum).cwiseAbs().maxCoeff(); }

void check_extent(const LocalExtent& extent, const char* where) {
  if (!extent.minimum.allFinite() || !extent.maximum.allFinite() ||
      !(extent.maximum.array() >= extent.minimum.array()).all())
    throw Error(std::string(where) + ": extent must be finite with maximum >= minimum on every axis");
}

Patch make_patch(std::function<Eigen::Vector3d(double, double)> map, double u0, double u1, double v0, double v1,
                 bool periodic) {
  Patch patch;
  patch.map = std::move(map);
  patch.u0 = u0;
  patch.u1 = u1;
  patch.v0 = v0;
  patch.v1 = v1;
  patch.v_periodic = periodic;
  return patch;
}

// Patches covering (at least) the part of the canonical surface inside the extent.
std::vector<Patch> surface_patches(const QuadricDecomposition& shape, const LocalExtent& extent) {
  const Eigen::Vector3d s = shape.scale;
  const Eigen::Vector3d& lo = extent.minimum;
  const Eigen::Vector3d& hi = extent.maximum;
  const double two_pi = 2.0 * kPi;
  std::vector<Patch> patches;
  switch (shape.type) {
    case QuadricType::Plane:  // y_a = 0: rectangle in b-c
      patches.push_back(make_patch([](double u, double v) { return Eigen::Vector3d(0.0, u, v); }, lo[1], hi[1], lo[2], hi[2], false));
      break;
    case QuadricType::ParallelPlanes:  // y_a = +/- s_a
      for (double side : {1.0, -1.0}) {
        const double offset = side * s[0];
        patches.push_back(make_patch([offset](double u, double v) { return Eigen::Vector3d(offset, u, v); }, lo[1], hi[1], lo[2], hi[2], false));
      }
      break;
    case QuadricType::IntersectingPlanes:  // y_a = +/- s_a y_b
      for (double side : {1.0, -1.0}) {
        const double slope = side * s[0];
        patches.push_back(make_patch([slope](double u, double v) { return Eigen::Vector3d(slope * u, u, v); }, lo[1], hi[1], lo[2], hi[2], false));
      }
      break;
    case QuadricType::Sphere:
    case QuadricType::Ellipsoid:
      patches.push_back(make_patch([s](double theta, double phi) {
        return Eigen::Vector3d(s[0] * std::sin(theta) * std::cos(phi), s[1] * std::sin(theta) * std::sin(phi), s[2] * std::cos(theta));
      }, 0.0, kPi, 0.0, two_pi, true));
      break;
    case QuadricType::CircularCylinder:
    case QuadricType::EllipticCylinder:
      patches.push_back(make_patch([s](double z, double phi) {
        return Eigen::Vector3d(s[0] * std::cos(phi), s[1] * std::sin(phi), z);
      }, lo[2], hi[2], 0.0, two_pi, true));
      break;
    case QuadricType::CircularCone:
    case QuadricType::EllipticCone: {
      auto cone = [s](double h, double phi) { return Eigen::Vector3d(h * s[0] * std::cos(phi), h * s[1] * std::sin(phi), h); };
      if (lo[2] < 0.0) patches.push_back(make_patch(cone, lo[2], std::min(hi[2], 0.0), 0.0, two_pi, true));
      if (hi[2] > 0.0) patches.push_back(make_patch(cone, std::max(lo[2], 0.0), hi[2], 0.0, two_pi, true));
      break;
    }
    case QuadricType::HyperboloidOneSheet:
      patches.push_back(make_patch([s](double u, double phi) {
        return Eigen::Vector3d(s[0] * std::cosh(u) * std::cos(phi), s[1] * std::cosh(u) * std::sin(phi), s[2] * std::sinh(u));
      }, std::asinh(lo[2] / s[2]), std::asinh(hi[2] / s[2]), 0.0, two_pi, true));
      break;
    case QuadricType::HyperboloidTwoSheets:
      for (double side : {1.0, -1.0}) {
        const double reach = side > 0.0 ? hi[2] : -lo[2];
        if (reach < s[2]) continue;
        patches.push_back(make_patch([s, side](double u, double phi) {
          return Eigen::Vector3d(s[0] * std::sinh(u) * std::cos(phi), s[1] * std::sinh(u) * std::sin(phi), side * s[2] * std::cosh(u));
        }, 0.0, std::acosh(reach / s[2]), 0.0, two_pi, true));
      }
      break;
    case QuadricType::HyperbolicCylinder:  // y_a^2/s_a^2 - y_b^2/s_b^2 = 1
      for (double side : {1.0, -1.0}) {
        patches.push_back(make_patch([s, side](double u, double z) {
          return Eigen::Vector3d(side * s[0] * std::cosh(u), s[1] * std::sinh(u), z);
        }, std::asinh(lo[1] / s[1]), std::asinh(hi[1] / s[1]), lo[2], hi[2], false));
      }
      break;
    case QuadricType::EllipticParaboloid:  // y_a^2/s_a^2 + y_b^2/s_b^2 = 2 y_c
      if (hi[2] > 0.0)
        patches.push_back(make_patch([s](double r, double phi) {
          return Eigen::Vector3d(s[0] * r * std::cos(phi), s[1] * r * std::sin(phi), 0.5 * r * r);
        }, 0.0, std::sqrt(2.0 * hi[2]), 0.0, two_pi, true));
      break;
    case QuadricType::HyperbolicParaboloid:  // y_a^2/s_a^2 - y_b^2/s_b^2 = 2 y_c
      patches.push_back(make_patch([s](double u, double v) {
        return Eigen::Vector3d(u, v, 0.5 * (u * u / (s[0] * s[0]) - v * v / (s[1] * s[1])));
      }, lo[0], hi[0], lo[1], hi[1], false));
      break;
    case QuadricType::ParabolicCylinder:  // y_a^2/s_a^2 = 2 y_b
      patches.push_back(make_patch([s](double u, double v) {
        return Eigen::Vector3d(u, 0.5 * u * u / (s[0] * s[0]), v);
      }, lo[0], hi[0], lo[2], hi[2], false));
      break;
    default:
      break;
  }
  return patches;
}

// Largest chord over `segments` equal parameter steps, times the number of segments: the length
// the curve would have if it moved everywhere at its largest speed.
template <typename Curve>
double speed_length(const Curve& curve, double t0, double t1, int segments) {
  double largest = 0.0;
  Eigen::Vector3d previous = curve(t0);
  for (int k = 1; k <= segments; ++k) {
    const Eigen::Vector3d current = curve(t0 + (t1 - t0) * k / segments);
    largest = std::max(largest, (current - previous).norm());
    previous = current;
  }
  return largest * segments;
}

// Outward direction of the canonical surface at y (for triangle orientation).
Eigen::Vector3d outward(const QuadricDecomposition& shape, const Quadric& canonical, const Eigen::Vector3d& y) {
  if (shape.type == QuadricType::Plane) return Eigen::Vector3d::UnitX();
  if (shape.type == QuadricType::Line) return Eigen::Vector3d(y[0], y[1], 0.0);
  if (shape.type == QuadricType::Point) return y;
  return canonical.gradient(y);
}

TriangleMesh grid_mesh(const Patch& patch, int resolution) {
  TriangleMesh mesh;
  const int rows = resolution + 1;
  const int columns = patch.v_periodic ? resolution : resolution + 1;
  mesh.vertices.resize(3, rows * columns);
  for (int i = 0; i < rows; ++i) {
    const double u = patch.u0 + (patch.u1 - patch.u0) * i / resolution;
    for (int j = 0; j < columns; ++j) {
      const double v = patch.v0 + (patch.v1 - patch.v0) * j / resolution;
      mesh.vertices.col(i * columns + j) = patch.map(u, v);
    }
  }
  for (int i = 0; i < resolution; ++i) {
    for (int j = 0; j < resolution; ++j) {
      const int j1 = patch.v_periodic ? (j + 1) % columns : j + 1;
      const int a = i * columns + j, b = i * columns + j1, c = (i + 1) * columns + j, d = (i + 1) * columns + j1;
      mesh.triangles.emplace_back(a, b, d);
      mesh.triangles.emplace_back(a, d, c);
    }
  }
  return mesh;
}

TriangleMesh octahedron(double radius) {
  TriangleMesh mesh;
  mesh.vertices.resize(3, 6);
  mesh.vertices << radius, -radius, 0, 0, 0, 0,
                   0, 0, radius, -radius, 0, 0,
                   0, 0, 0, 0, radius, -radius;
  const int faces[8][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  for (const auto& f : faces) mesh.triangles.emplace_back(f[0], f[1], f[2]);
  return mesh;
}

}  // namespace

Eigen::Matrix3Xd sample_surface(const QuadricDecomposition& shape, const LocalExtent& extent, double spacing) {
  check_extent(extent, "sample_surface");
  if (!(spacing > 0.0) || !std::isfinite(spacing)) {
    std::ostringstream message;
    message << "sample_surface: spacing must be a positive finite number of metres, got " << spacing;
    throw Error(message.str());
  }
  const double slack = 1e-9 * std::max(1.0, extent_size(extent));
  const Eigen::Isometry3d pose = shape.pose();
  std::vector<Eigen::Vector3d> points;
  constexpr std::size_t kMaximumPoints = 50000000;
  auto guard = [&](double expected) {
    if (expected > double(kMaximumPoints)) {
      std::ostringstream message;
      message << "sample_surface: spacing " << spacing << " m would produce about " << expected
              << " points (limit " << kMaximumPoints << "); use a larger spacing";
      throw Error(message.str());
    }
  };
  if (shape.type == QuadricType::Point) {
    if (inside(extent, Eigen::Vector3d::Zero(), slack)) points.push_back(pose * Eigen::Vector3d::Zero());
  } else if (shape.type == QuadricType::Line) {
    if (inside(extent, Eigen::Vector3d(0.0, 0.0, extent.minimum[2]), slack)) {
      const double length = extent.maximum[2] - extent.minimum[2];
      const double count = std::ceil(length / spacing) + 1.0;
      guard(count);
      const int n = int(count);
      for (int k = 0; k < n; ++k) {
        const double z = n == 1 ? extent.minimum[2] : extent.minimum[2] + length * k / (n - 1);
        points.push_back(pose * Eigen::Vector3d(0.0, 0.0, z));
      }
    }
  } else {
    constexpr int kSegments = 64;
    for (const Patch& patch : surface_patches(shape, extent)) {
      if (!(patch.u1 >= patch.u0) || !(patch.v1 >= patch.v0)) continue;
      double u_length = 0.0;
      for (int k = 0; k <= 8; ++k) {
        const double v = patch.v0 + (patch.v1 - patch.v0) * k / 8.0;
        u_length = std::max(u_length, speed_length([&](double u) { return patch.map(u, v); }, patch.u0, patch.u1, kSegments));
      }
      const double u_count = std::ceil(u_length / spacing) + 1.0;
      guard(u_count);
      const int rows = std::max(1, int(u_count));
      for (int i = 0; i < rows; ++i) {
        const double u = rows == 1 ? patch.u0 : patch.u0 + (patch.u1 - patch.u0) * i / (rows - 1);
        const double v_length = speed_length([&](double v) { return patch.map(u, v); }, patch.v0, patch.v1, kSegments);
        const double v_count = std::ceil(v_length / spacing) + (patch.v_periodic ? 0.0 : 1.0);
        guard(v_count * rows + double(points.size()));
        const int columns = std::max(1, int(v_count));
        for (int j = 0; j < columns; ++j) {
          double v;
          if (patch.v_periodic) v = patch.v0 + (patch.v1 - patch.v0) * j / columns;
          else v = columns == 1 ? patch.v0 : patch.v0 + (patch.v1 - patch.v0) * j / (columns - 1);
          const Eigen::Vector3d y = patch.map(u, v);
          if (inside(extent, y, slack)) points.push_back(pose * y);
        }
      }
    }
  }
  Eigen::Matrix3Xd result(3, Eigen::Index(points.size()));
  for (std::size_t k = 0; k < points.size(); ++k) result.col(Eigen::Index(k)) = points[k];
  return result;
}

TriangleMesh mesh_surface(const QuadricDecomposition& shape, const LocalExtent& extent, int resolution) {
  check_extent(extent, "mesh_surface");
  if (resolution < 3 || resolution > 4096)
    throw Error("mesh_surface: resolution must be between 3 and 4096 segments, got " + std::to_string(resolution));
  const double size = std::max(extent_size(extent), 1e-9);
  const double slack = 1e-9 * std::max(1.0, size);
  TriangleMesh canonical_mesh;
  std::vector<Patch> patches;
  if (shape.type == QuadricType::Point) {
    // A small octahedron (radius 1% of the extent's largest side) so the point can be seen.
    if (inside(extent, Eigen::Vector3d::Zero(), slack)) append_mesh(canonical_mesh, octahedron(0.01 * size), {0, 0, 0});
  } else if (shape.type == QuadricType::Line) {
    // A thin tube (radius 0.5% of the extent's largest side) along c, clipped to the extent along c.
    const double radius = 0.005 * size;
    if (inside(extent, Eigen::Vector3d(0.0, 0.0, extent.minimum[2]), slack))
      patches.push_back(make_patch([radius](double z, double phi) {
        return Eigen::Vector3d(radius * std::cos(phi), radius * std::sin(phi), z);
      }, extent.minimum[2], extent.maximum[2], 0.0, 2.0 * kPi, true));
  } else {
    patches = surface_patches(shape, extent);
  }
  for (const Patch& patch : patches) {
    if (!(patch.u1 >= patch.u0) || !(patch.v1 >= patch.v0)) continue;
    append_mesh(canonical_mesh, grid_mesh(patch, resolution), {0, 0, 0});
  }
  canonical_mesh.colors.clear();
  // Orient (counter-clockwise seen from outside), drop degenerate triangles and triangles leaving
  // the extent, then keep only used vertices and move them into the world (pose P_q).
  const bool has_canonical_form = shape.type != QuadricType::Point && shape.type != QuadricType::Line &&
                                  shape.type != QuadricType::Plane && shape.type != QuadricType::Invalid &&
                                  shape.type != QuadricType::Imaginary;
  const Quadric canonical =
      has_canonical_form ? Quadric::from_canonical(shape.type, shape.scale, Eigen::Isometry3d::Identity()) : Quadric();
  const bool line_tube = shape.type == QuadricType::Line;
  const double area_floor = 1e-14 * size * size;  // collapsed rows (poles, apex) give slivers below this
  std::vector<int> remap(std::size_t(canonical_mesh.vertices.cols()), -1);
  TriangleMesh mesh;
  std::vector<Eigen::Vector3d> kept;
  for (Eigen::Vector3i triangle : canonical_mesh.triangles) {
    const Eigen::Vector3d p0 = canonical_mesh.vertices.col(triangle[0]);
    const Eigen::Vector3d p1 = canonical_mesh.vertices.col(triangle[1]);
    const Eigen::Vector3d p2 = canonical_mesh.vertices.col(triangle[2]);
    const Eigen::Vector3d normal = (p1 - p0).cross(p2 - p0);
    // Collapsed rows (poles, apex) leave slivers and needles: zero area outright, or area tiny
    // against the longest edge, where the facet's orientation is rounding noise.
    const double longest_edge_squared =
        std::max({(p1 - p0).squaredNorm(), (p2 - p1).squaredNorm(), (p0 - p2).squaredNorm()});
    if (normal.norm() <= area_floor || normal.norm() <= 1e-9 * longest_edge_squared) continue;
    const bool all_inside = line_tube ? true : (inside(extent, p0, slack) && inside(extent, p1, slack) && inside(extent, p2, slack));
    if (!all_inside) continue;
    if (normal.dot(outward(shape, canonical, (p0 + p1 + p2) / 3.0)) < 0.0) std::swap(triangle[1], triangle[2]);
    for (int k = 0; k < 3; ++k) {
      int& index = remap[std::size_t(triangle[k])];
      if (index < 0) {
        index = int(kept.size());
        kept.push_back(canonical_mesh.vertices.col(triangle[k]));
      }
      triangle[k] = index;
    }
    mesh.triangles.push_back(triangle);
  }
  const Eigen::Isometry3d pose = shape.pose();
  mesh.vertices.resize(3, Eigen::Index(kept.size()));
  for (std::size_t k = 0; k < kept.size(); ++k) mesh.vertices.col(Eigen::Index(k)) = pose * kept[k];
  return mesh;
}

void append_mesh(TriangleMesh& mesh, const TriangleMesh& part, const std::array<std::uint8_t, 3>& color) {
  const Eigen::Index offset = mesh.vertices.cols();
  if (mesh.colors.size() != std::size_t(offset)) mesh.colors.resize(std::size_t(offset), {128, 128, 128});
  Eigen::Matrix3Xd vertices(3, offset + part.vertices.cols());
  vertices.leftCols(offset) = mesh.vertices;
  vertices.rightCols(part.vertices.cols()) = part.vertices;
  mesh.vertices = std::move(vertices);
  for (const Eigen::Vector3i& triangle : part.triangles)
    mesh.triangles.push_back(triangle + Eigen::Vector3i::Constant(int(offset)));
  mesh.colors.resize(std::size_t(mesh.vertices.cols()), color);
}

std::array<std::uint8_t, 3> quadric_type_color(QuadricType type) {
  switch (type) {
    case QuadricType::Point: return {240, 220, 40};
    case QuadricType::Line: return {220, 40, 220};
    case QuadricType::Plane: return {120, 140, 180};
    case QuadricType::Sphere: return {220, 40, 40};
    case QuadricType::Ellipsoid: return {235, 120, 120};
    case QuadricType::CircularCylinder: return {40, 170, 60};
    case QuadricType::EllipticCylinder: return {130, 205, 90};
    case QuadricType::CircularCone: return {255, 140, 0};
    case QuadricType::EllipticCone: return {250, 185, 80};
    case QuadricType::HyperboloidOneSheet: return {150, 80, 200};
    case QuadricType::HyperboloidTwoSheets: return {110, 60, 170};
    case QuadricType::EllipticParaboloid: return {0, 170, 200};
    case QuadricType::HyperbolicParaboloid: return {0, 125, 160};
    case QuadricType::ParabolicCylinder: return {70, 200, 200};
    case QuadricType::HyperbolicCylinder: return {170, 120, 60};
    case QuadricType::IntersectingPlanes: return {90, 110, 150};
    case QuadricType::ParallelPlanes: return {155, 175, 215};
    case QuadricType::Imaginary:
    case QuadricType::Invalid: return {128, 128, 128};
  }
  return {128, 128, 128};
}

}  // namespace quadrix
