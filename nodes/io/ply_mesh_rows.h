#pragma once
// The bytes of a PLY mesh file as write_ply() lays them out: the header and the binary rows,
// shared by write_ply() and PlyMeshFile (a mesh written part by part at known offsets).

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "nodes/io/mesh_writers.h"
#include "runtime/triangle_mesh.h"

namespace meshflow::io {

/// Which vertex properties a PLY mesh file has, in write_ply()'s order.
struct PlyMeshLayout {
  bool world = false;       ///< x y z as doubles (a non-zero origin added), else floats
  bool normals = false;     ///< float nx ny nz
  bool colors = false;      ///< uchar red green blue
  std::size_t scalars = 0;  ///< float properties after them (VertexScalar)
  /// Bytes of one binary vertex row. O(1).
  std::size_t vertex_bytes() const {
    return (world ? 24 : 12) + (normals ? 12 : 0) + (colors ? 3 : 0) + 4 * scalars;
  }
  /// Bytes of one binary face row: uchar 3, uint a b c.
  static constexpr std::size_t kFaceBytes = 13;
  /// Bytes from a row's start to its normal. O(1).
  std::size_t normal_offset() const { return world ? 24 : 12; }
};

/// The layout write_ply() gives `mesh` with `origin` and `scalars` (normals and colours when
/// every vertex has them). O(1).
PlyMeshLayout ply_mesh_layout(const TriangleMesh& mesh, const Eigen::Vector3d& origin,
                              std::size_t scalars = 0);

/// The header write_ply() writes ("ply" to "end_header\n") for `vertices` and `triangles` rows
/// of `layout` (`scalars` naming its scalar properties). O(scalars).
std::string ply_mesh_header(PlyEncoding encoding, const PlyMeshLayout& layout,
                            std::uint64_t vertices, std::uint64_t triangles,
                            const std::vector<VertexScalar>& scalars = {});

/// Writes vertex `i` of `mesh` as a binary row of `layout` at `at` (layout.vertex_bytes() bytes:
/// position plus `origin` in doubles when layout.world, normal, colour, `scalars`' values) and
/// returns the byte after it. O(1).
char* put_ply_vertex(char* at, const TriangleMesh& mesh, std::size_t i,
                     const Eigen::Vector3d& origin, const PlyMeshLayout& layout,
                     const std::vector<VertexScalar>& scalars = {});

/// Writes `t` as a binary face row (kFaceBytes) at `at`; returns the byte after it. O(1).
char* put_ply_face(char* at, const Triangle& t);

/// Copies v's bytes (native order: little-endian on the supported platforms) to `at` and
/// returns the byte after them; the caller sized the buffer. O(sizeof(T)).
template <typename T>
char* put_bytes(char* at, const T& v) {
  std::memcpy(at, &v, sizeof(T));
  return at + sizeof(T);
}

}  // namespace meshflow::io
