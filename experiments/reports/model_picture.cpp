// Z-buffer rasteriser for model pictures (see model_picture.h).
#include "experiments/reports/model_picture.h"
#include "experiments/reports/picture_text.h"

#include "geometry/constants.h"
#include "geometry/error.h"
#include "geometry/io.h"

// The one translation unit holding stb's PNG writer (bev.png and model pictures both use write_rgb_png).
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace quadrix {

namespace {

void check_range(const char* name, double value, double minimum, double maximum) {
  if (!(value >= minimum && value <= maximum))
    throw Error(std::string("mesh picture option ") + name + " must be within " + std::to_string(minimum) + ".." +
                std::to_string(maximum) + ", got " + std::to_string(value));
}

/// Refuses an empty mesh and picture options out of range, naming the option.
void check_picture_inputs(const TriangleMesh& mesh, const MeshPictureOptions& options) {
  if (mesh.vertices.cols() == 0 || mesh.triangles.empty()) throw Error("render_mesh: the mesh has no triangles");
  check_range("width", options.width, 64, 8192);
  check_range("height", options.height, 64, 8192);
  check_range("supersampling", options.supersampling, 1, 4);
  check_range("field_of_view_deg", options.field_of_view_deg, 0.0, 120.0);
  check_range("zoom", options.zoom, 0.05, 100.0);
  check_range("elevation_deg", options.elevation_deg, -89.0, 89.0);
  if (!(options.up.norm() > 0.0)) throw Error("mesh picture option up must be a non-zero vector");
}

/// The camera's frame and its projection onto the supersampled image.
struct MeshCamera {
  Eigen::Vector3d eye, forward, right, up, towards_camera;
  bool perspective = true;
  double focal = 0.0, cx = 0.0, cy = 0.0;  // pixels per unit of the image plane, image centre
  int width = 0, height = 0;               // supersampled image size
};

/// Aims at the frame box's (or the vertices' bounding box's) centre from azimuth/elevation so the bounding sphere spans the shorter side.
MeshCamera frame_mesh(const TriangleMesh& mesh, const MeshPictureOptions& options) {
  MeshCamera camera;
  const bool boxed = !options.frame_box.isEmpty();
  const Eigen::Vector3d lower = boxed ? options.frame_box.min() : Eigen::Vector3d(mesh.vertices.rowwise().minCoeff());
  const Eigen::Vector3d upper = boxed ? options.frame_box.max() : Eigen::Vector3d(mesh.vertices.rowwise().maxCoeff());
  const Eigen::Vector3d centre = 0.5 * (lower + upper);
  const double radius = std::max(1e-6, 0.5 * (upper - lower).norm()) / options.zoom;
  const Eigen::Vector3d up = options.up.normalized();
  const Eigen::Vector3d helper = std::abs(up.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d east = (helper - helper.dot(up) * up).normalized(), north = up.cross(east);
  const double azimuth = options.azimuth_deg * kPi / 180.0, elevation = options.elevation_deg * kPi / 180.0;
  camera.towards_camera =
      (std::cos(elevation) * (std::cos(azimuth) * east + std::sin(azimuth) * north) + std::sin(elevation) * up).normalized();
  camera.forward = -camera.towards_camera;
  camera.right = camera.forward.cross(up).normalized();
  camera.up = camera.right.cross(camera.forward);
  camera.perspective = options.field_of_view_deg > 0.0;
  const double half_angle = 0.5 * options.field_of_view_deg * kPi / 180.0;
  const double distance = camera.perspective ? radius / std::sin(half_angle) : 2.0 * radius;
  camera.eye = centre + distance * camera.towards_camera;

  camera.width = options.width * options.supersampling;
  camera.height = options.height * options.supersampling;
  // Pixels per unit of the image plane: the bounding sphere spans the shorter side.
  camera.focal = 0.5 * std::min(camera.width, camera.height) / (camera.perspective ? std::tan(half_angle) : radius);
  camera.cx = 0.5 * camera.width;
  camera.cy = 0.5 * camera.height;
  return camera;
}

/// Every vertex as x, y pixels of the supersampled image and depth along the view direction.
std::vector<Eigen::Vector3d> project_vertices(const TriangleMesh& mesh, const MeshCamera& camera) {
  std::vector<Eigen::Vector3d> screen(static_cast<std::size_t>(mesh.vertices.cols()));
  for (Eigen::Index v = 0; v < mesh.vertices.cols(); ++v) {
    const Eigen::Vector3d relative = mesh.vertices.col(v) - camera.eye;
    const double depth = relative.dot(camera.forward);
    const double divisor = camera.perspective ? std::max(depth, 1e-6) : 1.0;
    screen[static_cast<std::size_t>(v)] = Eigen::Vector3d(camera.cx + camera.focal * relative.dot(camera.right) / divisor,
                                                          camera.cy - camera.focal * relative.dot(camera.up) / divisor, depth);
  }
  return screen;
}

/// Colour and depth of every pixel of the supersampled image.
struct Framebuffer {
  int width = 0, height = 0;
  std::vector<double> depth;
  std::vector<std::array<double, 3>> colour;
};

/// An image of the background colour with every depth at infinity.
Framebuffer empty_framebuffer(const MeshCamera& camera, const MeshPictureOptions& options) {
  Framebuffer frame;
  frame.width = camera.width;
  frame.height = camera.height;
  frame.depth.assign(static_cast<std::size_t>(camera.width) * camera.height, std::numeric_limits<double>::infinity());
  frame.colour.assign(static_cast<std::size_t>(camera.width) * camera.height,
                      {static_cast<double>(options.background[0]), static_cast<double>(options.background[1]),
                       static_cast<double>(options.background[2])});
  return frame;
}

/// Paints `base` x `shade` on the pixels inside screen triangle abc (signed `area`) where it is the nearest surface.
void fill_triangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, double area,
                   const std::array<double, 3>& base, double shade, Framebuffer& frame) {
  const int x0 = std::max(0, static_cast<int>(std::floor(std::min({a.x(), b.x(), c.x()}))));
  const int x1 = std::min(frame.width - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), c.x()}))));
  const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), c.y()}))));
  const int y1 = std::min(frame.height - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), c.y()}))));
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      const double px = x + 0.5, py = y + 0.5;
      const double wa = ((b.x() - px) * (c.y() - py) - (b.y() - py) * (c.x() - px)) / area;
      const double wb = ((c.x() - px) * (a.y() - py) - (c.y() - py) * (a.x() - px)) / area;
      const double wc = 1.0 - wa - wb;
      if (wa < 0.0 || wb < 0.0 || wc < 0.0) continue;
      const double depth = wa * a.z() + wb * b.z() + wc * c.z();
      const std::size_t pixel = static_cast<std::size_t>(y) * frame.width + x;
      if (depth >= frame.depth[pixel]) continue;
      frame.depth[pixel] = depth;
      for (int k = 0; k < 3; ++k) frame.colour[pixel][k] = base[k] * shade;
    }
}

/// Draws every triangle flat-shaded, two-sided (open surfaces), by a key light over the left shoulder plus ambient.
void draw_triangles(const TriangleMesh& mesh, const MeshCamera& camera, const std::vector<Eigen::Vector3d>& screen,
                    Framebuffer& frame) {
  const Eigen::Vector3d light = (camera.towards_camera + 0.6 * camera.up - 0.4 * camera.right).normalized();
  const bool coloured = mesh.colors.size() == static_cast<std::size_t>(mesh.vertices.cols());
  for (const Eigen::Vector3i& triangle : mesh.triangles) {
    if ((triangle.array() < 0).any() || (triangle.array() >= mesh.vertices.cols()).any())
      throw Error("render_mesh: a triangle names a vertex beyond the " + std::to_string(mesh.vertices.cols()) + " vertices");
    const Eigen::Vector3d& a = screen[static_cast<std::size_t>(triangle[0])];
    const Eigen::Vector3d& b = screen[static_cast<std::size_t>(triangle[1])];
    const Eigen::Vector3d& c = screen[static_cast<std::size_t>(triangle[2])];
    if (camera.perspective && (a.z() <= 1e-3 || b.z() <= 1e-3 || c.z() <= 1e-3)) continue;  // behind the camera
    const double area = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
    if (std::abs(area) < 1e-12) continue;
    const Eigen::Vector3d normal = (mesh.vertices.col(triangle[1]) - mesh.vertices.col(triangle[0]))
                                       .cross(mesh.vertices.col(triangle[2]) - mesh.vertices.col(triangle[0]));
    if (!(normal.norm() > 0.0)) continue;
    const double shade = 0.35 + 0.65 * std::abs(normal.normalized().dot(light));
    std::array<double, 3> base = {170.0, 170.0, 170.0};
    if (coloured)
      for (int k = 0; k < 3; ++k)
        base[k] = (mesh.colors[static_cast<std::size_t>(triangle[0])][k] + mesh.colors[static_cast<std::size_t>(triangle[1])][k] +
                   mesh.colors[static_cast<std::size_t>(triangle[2])][k]) / 3.0;
    fill_triangle(a, b, c, area, base, shade, frame);
  }
}

/// Box-filters the supersampled image down to the picture's size (smooth edges).
RgbImage downsample(const Framebuffer& frame, const MeshPictureOptions& options) {
  RgbImage image;
  image.width = options.width;
  image.height = options.height;
  image.pixels.resize(static_cast<std::size_t>(image.width) * image.height * 3);
  const int factor = options.supersampling;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      for (int k = 0; k < 3; ++k) {
        double sum = 0.0;
        for (int dy = 0; dy < factor; ++dy)
          for (int dx = 0; dx < factor; ++dx)
            sum += frame.colour[static_cast<std::size_t>(y * factor + dy) * frame.width + (x * factor + dx)][k];
        image.pixels[(static_cast<std::size_t>(y) * image.width + x) * 3 + k] =
            static_cast<std::uint8_t>(std::clamp(std::lround(sum / (factor * factor)), 0L, 255L));
      }
  return image;
}

}  // namespace

RgbImage render_mesh(const TriangleMesh& mesh, const MeshPictureOptions& options) {
  check_picture_inputs(mesh, options);
  const MeshCamera camera = frame_mesh(mesh, options);
  const std::vector<Eigen::Vector3d> screen = project_vertices(mesh, camera);
  Framebuffer frame = empty_framebuffer(camera, options);
  draw_triangles(mesh, camera, screen, frame);
  return downsample(frame, options);
}

void write_rgb_png(const std::string& path, const RgbImage& image) {
  if (image.width <= 0 || image.height <= 0 ||
      image.pixels.size() != static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height) * 3)
    throw file_error(path, "image of " + std::to_string(image.width) + " x " + std::to_string(image.height) + " pixels has " +
                               std::to_string(image.pixels.size()) + " bytes (expected width x height x 3)");
  std::vector<std::uint8_t> png;
  const auto append = [](void* context, void* data, int size) {
    auto* bytes = static_cast<std::vector<std::uint8_t>*>(context);
    bytes->insert(bytes->end(), static_cast<std::uint8_t*>(data), static_cast<std::uint8_t*>(data) + size);
  };
  if (stbi_write_png_to_func(append, &png, image.width, image.height, 3, image.pixels.data(), image.width * 3) == 0)
    throw file_error(path, "PNG encoding failed");
  write_file_atomically(path, [&png](std::ostream& out) {
    out.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  });
}

void write_mesh_picture(const std::string& path, const TriangleMesh& mesh, const MeshPictureOptions& options) {
  RgbImage image = render_mesh(mesh, options);
  if (!options.legend.empty()) {
    std::vector<LegendEntry> entries;
    for (const auto& [color, label] : options.legend) entries.push_back({color, label});
    const double text_height = std::max(11.0, std::min(image.width, image.height) / 55.0);
    const int margin = std::min(image.width, image.height) / 40;
    draw_picture_legend(image, margin, margin, options.title, entries, text_height);
  }
  write_rgb_png(path, image);
}

}  // namespace quadrix
