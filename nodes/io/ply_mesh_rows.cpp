#include "nodes/io/ply_mesh_rows.h"

#include <cstring>
#include <sstream>

namespace meshflow::io {

PlyMeshLayout ply_mesh_layout(const TriangleMesh& mesh, const Eigen::Vector3d& origin,
                              std::size_t scalars) {
  PlyMeshLayout layout;
  layout.world = !origin.isZero();
  layout.normals = mesh.normals.size() == mesh.vertices.size() && !mesh.normals.empty();
  layout.colors = mesh.colors.size() == mesh.vertices.size() && !mesh.colors.empty();
  layout.scalars = scalars;
  return layout;
}

std::string ply_mesh_header(PlyEncoding encoding, const PlyMeshLayout& layout,
                            std::uint64_t vertices, std::uint64_t triangles,
                            const std::vector<VertexScalar>& scalars) {
  std::ostringstream out;
  out << "ply\nformat " << (encoding == PlyEncoding::kBinary ? "binary_little_endian" : "ascii")
      << " 1.0\ncomment written by meshflow\nelement vertex " << vertices << '\n';
  // Georeferenced meshes: world coordinates, in doubles (floats hold millions of metres only to
  // decimetres).
  out << (layout.world ? "property double x\nproperty double y\nproperty double z\n"
                       : "property float x\nproperty float y\nproperty float z\n");
  if (layout.normals) out << "property float nx\nproperty float ny\nproperty float nz\n";
  if (layout.colors) out << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  for (const VertexScalar& scalar : scalars) out << "property float " << scalar.name << '\n';
  out << "element face " << triangles << "\nproperty list uchar uint vertex_indices\nend_header\n";
  return out.str();
}

char* put_ply_vertex(char* at, const TriangleMesh& mesh, std::size_t i,
                     const Eigen::Vector3d& origin, const PlyMeshLayout& layout,
                     const std::vector<VertexScalar>& scalars) {
  for (int k = 0; k < 3; ++k)
    at = layout.world ? put_bytes(at, static_cast<double>(mesh.vertices[i][k]) + origin[k])
                      : put_bytes(at, mesh.vertices[i][k]);
  if (layout.normals)
    for (int k = 0; k < 3; ++k) at = put_bytes(at, mesh.normals[i][k]);
  if (layout.colors) {
    const Rgb8& c = mesh.colors[i];
    for (std::uint8_t channel : {c.r, c.g, c.b}) at = put_bytes(at, channel);
  }
  for (const VertexScalar& scalar : scalars) at = put_bytes(at, scalar.values[i]);
  return at;
}

char* put_ply_face(char* at, const Triangle& t) {
  at = put_bytes(at, std::uint8_t{3});
  for (std::uint32_t v : t) at = put_bytes(at, v);
  return at;
}

}  // namespace meshflow::io
