#pragma once
// A binary PLY mesh file written part by part at known offsets: for a mesh too large to hold,
// whose vertex and triangle counts are known before its parts (the out-of-core path's welded
// chunks). The bytes are write_ply()'s for the same mesh.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "nodes/io/ply_mesh_rows.h"
#include "runtime/triangle_mesh.h"

namespace meshflow::io {

/// Writes "PATH.tmp" (the header at once, rows where told) and renames it to PATH on commit();
/// destroyed without commit() it removes the temporary file (AtomicOutputFile's contract).
/// Rows may be written in any order and rewritten (a vertex's normal, a triangle: patches after
/// the parts). Other processes may write rows into the same temporary file at once (kJoin:
/// meshflow-mpi's ranks, each its own rows). Not thread-safe. Memory: one block of 4 MiB while
/// a part is written.
class PlyMeshFile {
 public:
  /// kCreate: this object creates the temporary file and commits it. kJoin: it opens the
  /// temporary file another PlyMeshFile (same path, layout, counts, origin) created, only to
  /// write rows: close() ends it, and it neither renames nor removes the file.
  enum class Role { kCreate, kJoin };

  /// Creates `path`.tmp with write_ply()'s binary header for `vertices` and `triangles` rows of
  /// `layout` (no scalars), or with kJoin opens it; `origin` is added to positions when
  /// layout.world. Throws meshflow::Error naming `path` and the system's reason.
  PlyMeshFile(std::string path, const PlyMeshLayout& layout, std::uint64_t vertices,
              std::uint64_t triangles, const Eigen::Vector3d& origin, Role role = Role::kCreate);
  ~PlyMeshFile();
  PlyMeshFile(const PlyMeshFile&) = delete;
  PlyMeshFile& operator=(const PlyMeshFile&) = delete;

  /// Writes `part`'s vertices (with normals, colours as the layout has them) as rows `first`,
  /// `first` + 1, ... Throws meshflow::Error past the declared count or on a failed write.
  /// O(part).
  void write_vertices(std::uint64_t first, const TriangleMesh& part);
  /// Writes `triangles` as face rows `first`, `first` + 1, ... (as write_vertices()).
  void write_triangles(std::uint64_t first, const std::vector<Triangle>& triangles);
  /// Rewrites the normal of vertex row `vertex` (the layout has normals). O(1), one write.
  void write_normal(std::uint64_t vertex, const Eigen::Vector3f& normal);
  /// Rewrites face row `index`. O(1), one write.
  void write_triangle(std::uint64_t index, const Triangle& triangle);

  /// Reads face rows [first, first + count) back (as written so far). Throws meshflow::Error
  /// past the declared rows or on a short read. O(count).
  std::vector<Triangle> read_triangles(std::uint64_t first, std::uint64_t count) const;
  /// Reads vertex rows `rows` (ascending) back as a mesh of their own: positions in the local
  /// frame (`origin` subtracted when layout.world: the floats written, when the sum was exact),
  /// normals and colours as the layout has them. Throws as read_triangles(). O(rows), one read
  /// per run of consecutive rows.
  TriangleMesh read_vertices(const std::vector<std::uint64_t>& rows) const;

  /// Counts `vertices` and `triangles` rows written by joined writers (kJoin) toward commit()'s
  /// check. O(1).
  void add_rows_written_elsewhere(std::uint64_t vertices, std::uint64_t triangles);

  /// Flushes the rows written so far to the file system (fsync), so that processes opening the
  /// temporary file afterwards (kJoin: meshflow-mpi's ranks, also on a network file system)
  /// read them. Throws meshflow::Error when it fails. O(rows not yet flushed).
  void sync();

  /// Closes the file and renames it to its path. Throws meshflow::Error (the temporary file
  /// removed) when fewer rows than declared were written or the close or rename failed; with
  /// kJoin throws (use close()).
  void commit();

  /// kJoin: closes the file, its rows written. Throws meshflow::Error when the close failed, or
  /// for kCreate (use commit()).
  void close();

  /// Vertex rows written by this object so far (plus add_rows_written_elsewhere()'s). O(1).
  std::uint64_t vertex_rows_written() const { return vertex_rows_written_; }
  /// Face rows written by this object so far (plus add_rows_written_elsewhere()'s). O(1).
  std::uint64_t face_rows_written() const { return face_rows_written_; }

 private:
  void write_at(std::uint64_t offset, const char* bytes, std::size_t count);
  void read_at(std::uint64_t offset, char* bytes, std::size_t count) const;

  std::string path_, temp_path_;
  PlyMeshLayout layout_;
  std::uint64_t vertices_, triangles_;
  Eigen::Vector3d origin_;
  std::uint64_t header_bytes_ = 0;
  std::uint64_t vertex_rows_written_ = 0, face_rows_written_ = 0;
  int fd_ = -1;
  Role role_;
  bool committed_ = false;
};

}  // namespace meshflow::io
