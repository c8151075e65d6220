#pragma once
// The out-of-core path's output streamed: the welded parts of chunks finished in place
// (seam_weld.h's weld_chunk(), in chunk order) go straight into a binary PLY at the rows the
// weld's plan gives them, while the triangles around the seams are kept aside; once every part
// is written, the seams are finished on those alone (finish_seams()'s flips and normals) and
// the rows they change are rewritten. The file is byte for byte write_ply() of
// finish_joined_mesh()'s mesh; memory holds one part and the seams' neighbourhood, never the
// output.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "nodes/chunk/seam_weld.h"
#include "nodes/io/ply_mesh_file.h"
#include "runtime/triangle_mesh.h"

namespace meshflow::chunk {

class StreamedChunkOutput {
 public:
  /// Opens `path` (its temporary file: io::PlyMeshFile) for `vertices` and `triangles` rows,
  /// with normals and colours when `layout` says so (layout.world: `origin` non-zero, world
  /// coordinates); `flags`: every part comes with its vertices' flag bytes (else the seams are
  /// left as they are, as finish_joined_mesh() leaves them without flags). `voxel_size`,
  /// `chunk_cells`: the grid the chunks were extracted on; `feature_bit`: the bit of the flag
  /// bytes marking extended marching cubes' feature vertices. Throws meshflow::Error naming
  /// `path`.
  StreamedChunkOutput(const std::string& path, std::uint64_t vertices, std::uint64_t triangles,
                      const io::PlyMeshLayout& layout, bool flags, const Eigen::Vector3d& origin,
                      float voxel_size, int chunk_cells, std::uint8_t feature_bit);

  /// The same for the parts of `plan` (its counts, normals, colours and flags). Throws as above.
  StreamedChunkOutput(const std::string& path, const WeldPlan& plan, const Eigen::Vector3d& origin,
                      float voxel_size, int chunk_cells, std::uint8_t feature_bit);

  /// Writes the next chunk's welded part (weld_chunk() of the chunks in plan order, failed
  /// chunks left out; `flags` its kept vertices' bytes, or empty when plan.flags is false) and
  /// keeps the triangles that touch a vertex next to a seam. Not thread-safe. O(part).
  void add(const TriangleMesh& part, const std::vector<std::uint8_t>& flags);

  /// Finishes the seams (when some vertex is a feature vertex: finish_seams() on the kept
  /// triangles), rewrites the triangles and normals that changed and commits the file.
  /// Returns the flips made. Throws meshflow::Error when the parts did not fill the plan or a
  /// write failed. O(S log S) for S triangles near the seams, plus their rewrites.
  std::size_t finish();

  /// Rows rewritten by finish() (triangles flipped, normals changed).
  std::size_t rewritten() const { return rewritten_; }

 private:
  io::PlyMeshFile file_;
  bool normals_, flags_;
  float voxel_size_;
  int chunk_cells_;
  std::uint8_t feature_bit_;
  std::uint64_t vertices_ = 0, triangles_ = 0;  // rows written so far
  bool any_feature_ = false;
  std::size_t rewritten_ = 0;
  // The seams' neighbourhood: vertices (ascending output index) and triangles (ascending).
  std::vector<std::uint64_t> vertex_index_;
  std::vector<Eigen::Vector3f> positions_, vertex_normals_;
  std::vector<std::uint8_t> features_, seam_, near_;
  std::vector<std::uint64_t> triangle_index_;
  std::vector<Triangle> triangles_near_;  // output vertex indices
};

}  // namespace meshflow::chunk
