// A picture of a quadric model: the triangle mesh `quadrix model --mesh` writes, rasterised with a
// z-buffer and flat Lambert shading from a chosen viewpoint, saved as PNG (stb). Enough to see
// what a model looks like without a 3-D viewer.
#pragma once

#include "geometry/mesh.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace quadrix {

/// Camera and image of a mesh picture.
struct MeshPictureOptions {
  int width = 1600;                  ///< image width, pixels (64..8192)
  int height = 1000;                 ///< image height, pixels (64..8192)
  double azimuth_deg = -60.0;        ///< direction the camera sits in, around the up axis from +x, degrees
  double elevation_deg = 30.0;       ///< camera height above the horizon as seen from the mesh centre, degrees
  double field_of_view_deg = 35.0;   ///< vertical field of view of the perspective camera, degrees (0: orthographic)
  double zoom = 1.0;                 ///< > 1 moves the camera closer (the mesh's bounding sphere fills 1/zoom of the view)
  int supersampling = 2;             ///< rendered at this factor and box-filtered down (1..4), for smooth edges
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();  ///< up axis of the mesh
  std::array<std::uint8_t, 3> background = {255, 255, 255};  ///< colour where no triangle is drawn
  Eigen::AlignedBox3d frame_box;     ///< the box the camera frames (empty: every vertex), e.g. the structures without the ground
  std::vector<std::pair<std::array<std::uint8_t, 3>, std::string>> legend;  ///< colour and label per row, drawn top left by write_mesh_picture (empty: none)
  std::string title;                 ///< first line of the legend box (e.g. the input file)
};

/// An RGB image, row-major from the top-left, 3 bytes a pixel.
struct RgbImage {
  int width = 0;                     ///< pixels
  int height = 0;                    ///< pixels
  std::vector<std::uint8_t> pixels;  ///< width * height * 3 bytes
};

/// Rasterises `mesh` (per-vertex colours, grey when absent) as seen from the options' camera, which
/// frames the bounding sphere of options.frame_box (of the vertices when it is empty). Throws quadrix::Error for an empty mesh or options
/// out of range (naming the option).
RgbImage render_mesh(const TriangleMesh& mesh, const MeshPictureOptions& options = {});

/// Writes an RGB image as PNG (stb) atomically (temporary file, then rename); throws quadrix::Error
/// naming the path when the image is inconsistent or encoding fails. Any PNG writer can share it.
void write_rgb_png(const std::string& path, const RgbImage& image);

/// render_mesh, the legend of options.legend (with options.title) in the top-left corner, then write_rgb_png.
void write_mesh_picture(const std::string& path, const TriangleMesh& mesh, const MeshPictureOptions& options = {});

}  // namespace quadrix
