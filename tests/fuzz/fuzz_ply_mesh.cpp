// Fuzz target: read_mesh_ply (vertices, optional colours, 'face' lists fanned into triangles).
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace quadrix;
  static const fuzz::InputFile file("ply_mesh", ".ply");
  const std::string& path = file.write(data, size);
  TriangleMesh mesh;
  try {
    mesh = read_mesh_ply(path);
  } catch (const Error& error) {
    fuzz::require_names(error, path);
    return 0;
  }
  const Eigen::Index vertices = mesh.vertices.cols();
  fuzz::require(mesh.vertices.rows() == 3);
  fuzz::require(mesh.vertices.allFinite());
  fuzz::require(mesh.colors.empty() || mesh.colors.size() == static_cast<std::size_t>(vertices));
  for (const Eigen::Vector3i& triangle : mesh.triangles)
    for (int corner = 0; corner < 3; ++corner) fuzz::require(triangle[corner] >= 0 && triangle[corner] < vertices);
  return 0;
}
