#pragma once
// Mesh writers: PLY (binary little-endian or ascii), Wavefront OBJ, binary STL, OFF; glTF 2.0
// binary (.glb) is in nodes/io/glb_writer.h. write_mesh() picks one by extension.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "runtime/triangle_mesh.h"

namespace meshflow::io {

enum class PlyEncoding { kBinary, kAscii };

// Every writer takes the mesh's `origin` (Frame::origin, PointCloud::origin: non-zero for
// georeferenced inputs), the world position of the frame its vertices are in. PLY, OBJ and OFF
// then write world coordinates in double precision; STL and glTF, whose vertices are float32,
// keep the local coordinates and record the origin (the STL header's text, the glTF node's
// translation, which viewers apply).

/// A per-vertex float property of a PLY file, such as `quality` (the distance to the data in
/// metres, nearest_point_distances()) or `observations` (how many measurements support the
/// vertex): scalar fields in CloudCompare and MeshLab.
struct VertexScalar {
  std::string name;           ///< PLY property name (letters, digits, '_')
  std::vector<float> values;  ///< one per vertex
};

/// Writes vertices (float x y z; double with a non-zero origin), normals (nx ny nz) and colours
/// (uchar red green blue) when present, then each of `scalars` as a float property in order,
/// and faces (uchar count, uint vertex_indices). Atomic: the file appears complete or not at
/// all. Throws meshflow::Error on I/O failure, or a scalar with another number of values than
/// vertices or a name that is not a PLY word. O(V + T).
void write_ply(const std::string& path, const TriangleMesh& mesh,
               PlyEncoding encoding = PlyEncoding::kBinary,
               const Eigen::Vector3d& origin = Eigen::Vector3d::Zero(),
               const std::vector<VertexScalar>& scalars = {});

/// Writes v / vn / f lines (1-based indices, "f a//a b//b c//c" when normals exist); colours as
/// the common extension "v x y z r g b" (0..1). Atomic.
void write_obj(const std::string& path, const TriangleMesh& mesh,
               const Eigen::Vector3d& origin = Eigen::Vector3d::Zero());

/// Binary STL: an 80-byte header, the triangle count, per triangle its unit face normal and
/// three corners (float32, little-endian). STL has no shared vertices, normals or colours: the
/// readers of other tools weld corners again. Atomic. O(T).
void write_stl(const std::string& path, const TriangleMesh& mesh,
               const Eigen::Vector3d& origin = Eigen::Vector3d::Zero());

/// ASCII OFF ("OFF", or "COFF" with r g b a integer colours per vertex), faces "3 a b c". Atomic.
/// O(V + T).
void write_off(const std::string& path, const TriangleMesh& mesh,
               const Eigen::Vector3d& origin = Eigen::Vector3d::Zero());

/// Chooses the writer by extension: .ply (binary), .obj, .stl, .off, .glb. Throws
/// meshflow::Error naming the formats otherwise.
void write_mesh(const std::string& path, const TriangleMesh& mesh,
                const Eigen::Vector3d& origin = Eigen::Vector3d::Zero());

/// Throws meshflow::Error unless write_mesh() knows the extension of `path` and the file can
/// be created (check_output_writable(): not a directory, a writable directory; checked before a
/// long reconstruction, so a typo or a read-only directory does not cost it).
void check_mesh_output_format(const std::string& path);

}  // namespace meshflow::io
