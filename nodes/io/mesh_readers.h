#pragma once
// Mesh readers for the formats other tools write: Wavefront OBJ, OFF and STL (binary and
// ASCII), and read_mesh(), which picks the reader (PLY included) by extension.

#include <string>

#include "runtime/triangle_mesh.h"

namespace meshflow::io {

/// Wavefront OBJ: `v x y z [r g b]` (colours 0..1 or 0..255), `vn`, `f` with `i`, `i/t`,
/// `i//n` or `i/t/n` corners (1-based or negative, relative), polygons fanned into triangles;
/// `vt`, groups, materials and other statements are ignored. Normals are kept when every
/// face corner names the normal of the same index as its vertex (the layout meshflow and most
/// exporters of per-vertex normals write), colours when every vertex has one. Throws
/// meshflow::Error naming the file and line for a malformed number, an index out of range or
/// a face with fewer than 3 corners. O(file size).
TriangleMesh read_obj_mesh(const std::string& path);

/// OFF (and COFF / NOFF / CNOFF): counts line, vertices (with normals and colours where the
/// header keyword says so), faces `n i0 ... in-1 [colour]`, `#` comments. Counts the file
/// cannot hold (more vertices or faces than it has bytes for) are errors before any
/// allocation. Throws meshflow::Error naming the file and line. O(file size).
TriangleMesh read_off_mesh(const std::string& path);

/// STL, binary (80-byte header, uint32 count, 50 bytes per triangle; the file size must match)
/// or ASCII (`solid ... facet normal ... outer loop vertex x y z ... endloop endfacet`).
/// Corners at bit-identical positions become one vertex (STL stores triangles apart), in order
/// of first appearance, so the result is deterministic. Throws meshflow::Error naming the file
/// and triangle or line. O(T) expected (hash of positions).
TriangleMesh read_stl_mesh(const std::string& path);

/// The mesh in `path` by its extension: .ply (read_ply_mesh), .obj, .off, .stl, .glb
/// (read_glb_mesh). Throws
/// meshflow::Error for another extension, naming the formats it reads.
TriangleMesh read_mesh(const std::string& path);

/// Whether read_mesh() knows the extension of `path`.
bool is_mesh_file(const std::string& path);

}  // namespace meshflow::io
