#pragma once
// PLY point reader: ascii, binary_little_endian and binary_big_endian.

#include <cstdint>
#include <functional>
#include <string>

#include "runtime/point_cloud.h"
#include "runtime/triangle_mesh.h"

namespace meshflow::io {

/// Reads the `vertex` element of a PLY file into a PointCloud (metres as stored; map coordinates,
/// more than 1e4 m out, relative to a local origin with +z up: PointCloud::origin, z_up).
/// Recognised properties: x y z (required); nx ny nz (or normal_x..); red green blue
/// (or r g b / diffuse_*; 8-bit, 16-bit or float 0..1); intensity (or scalar_intensity,
/// reflectance). Every other property and element, list properties included, is skipped.
/// Throws meshflow::Error naming the file and the header line, element row or field on
/// malformed, truncated or inconsistent input (including data past the declared counts).
/// Streams the file: memory is the size of the output plus a fixed buffer. O(file size).
PointCloud read_ply(const std::string& path);

/// read_ply() in pieces: hands the vertices to `sink` in file order, `batch` (>= 1) at a time
/// (the last piece smaller), so a file larger than memory can be streamed. The cloud passed to
/// `sink` is reused after it returns. Throws as read_ply() does, possibly after some batches.
void read_ply_batches(const std::string& path, std::size_t batch,
                      const std::function<void(const PointCloud&)>& sink);

/// How the vertex rows of a PLY file can be read by byte range (read_ply_vertex_range).
struct PlyVertexRows {
  std::uint64_t count = 0;  ///< vertices the header declares
  /// Binary, and the vertex rows and every row before them of fixed size (no list
  /// properties), so row i starts at a byte computed from the header. ASCII rows have no
  /// fixed size: row i's place is known only by reading every line before it.
  bool by_byte_range = false;
  std::string why_not;  ///< when !by_byte_range: the reason, for messages
};

/// The vertex rows' layout from the header. Throws as read_ply() does on a bad header.
/// O(header).
PlyVertexRows ply_vertex_rows(const std::string& path);

/// Vertices [first, first + count) of a PLY whose rows can be read by byte range, handed to
/// `sink` `batch` (>= 1) at a time, in file order and in the local frame of the file's first
/// vertex (the one read_ply() gives every point), so ranges read apart (threads, MPI ranks)
/// together give read_ply()'s points. Reads the header, the first row and the range only.
/// Throws meshflow::Error when the file is not splittable (ply_vertex_rows().why_not), the
/// range lies past the declared count, or the file ends early. Thread-safe (own stream).
void read_ply_vertex_range(const std::string& path, std::uint64_t first, std::uint64_t count,
                           std::size_t batch, const std::function<void(const PointCloud&)>& sink);

/// Reads a PLY mesh: the vertex element as in read_ply (positions, normals, colours; in world
/// coordinates, refused beyond +-1e6 m as floats hold them no better: a TriangleMesh has no
/// local origin) and the
/// `face` element's `vertex_indices` lists (polygons are fan-triangulated). Throws
/// A file without a `face` element gives a mesh without triangles (a point set). Throws
/// meshflow::Error naming the file and face row for an index out of range or a face with fewer
/// than 3 vertices, and on everything read_ply rejects. O(file size).
TriangleMesh read_ply_mesh(const std::string& path);

/// Whether the PLY file's header declares a `face` element with at least one face (a mesh, not
/// a point set). Reads the header only. Throws meshflow::Error as read_ply() does on a
/// malformed header.
bool ply_has_faces(const std::string& path);

}  // namespace meshflow::io
