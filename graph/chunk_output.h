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

#include "nodes/chunk/mesh_tiles.h"
#include "nodes/chunk/seam_weld.h"
#include "nodes/io/ply_mesh_file.h"
#include "runtime/triangle_mesh.h"

namespace meshflow::chunk {

/// The part of a streamed output that finish_seam_rows() revisits: the vertices and triangles
/// near the chunk seams, with their output rows. Parts' neighbourhoods are independent of each
/// other (given their first rows) and join by append() in output order.
struct SeamNeighbourhood {
  bool any_feature = false;  ///< some vertex of some part is a feature vertex
  // Vertices (ascending output row) and what finish_seams() needs of them:
  std::vector<std::uint64_t> vertex_index;
  std::vector<Eigen::Vector3f> positions, normals;  ///< normals: empty without
  std::vector<std::uint8_t> features, seam, near;
  // Triangles (ascending output row), in output vertex indices:
  std::vector<std::uint64_t> triangle_index;
  std::vector<Triangle> triangles;

  /// Appends `later` (the neighbourhood of parts after this one's). O(later).
  void append(const SeamNeighbourhood& later);
};

/// Adds to `into` the neighbourhood of one welded part (weld_chunk()'s, its triangles in output
/// indices) written at vertex row `first_vertex` and face row `first_triangle`: the triangles
/// touching a vertex next to a seam and their vertices. `flags`: the part's kept vertices'
/// bytes (`feature_bit` marks feature vertices); with fewer than one per vertex nothing is
/// added. `normals`: keep the vertices' normals. `voxel_size`, `chunk_cells`: the grid the
/// chunks were extracted on. Thread-safe on distinct `into`. O(part).
void add_seam_neighbourhood(const TriangleMesh& part, const std::vector<std::uint8_t>& flags,
                            std::uint64_t first_vertex, std::uint64_t first_triangle,
                            float voxel_size, int chunk_cells, std::uint8_t feature_bit,
                            bool normals, SeamNeighbourhood& into);

/// Finishes the seams of every part's `neighbourhood` joined in output order (when some vertex
/// is a feature vertex: finish_seam_neighbourhood()) and rewrites in `file` the triangles and
/// normals that changed; `rewritten` (optional) receives the rows rewritten. Returns the flips
/// made. Consumes the neighbourhood's positions. Throws meshflow::Error for a triangle whose
/// vertex was not kept, or a failed write. O(S log S) for S triangles near the seams.
std::size_t finish_seam_rows(SeamNeighbourhood& neighbourhood, io::PlyMeshFile& file,
                             std::size_t* rewritten = nullptr);

/// The PLY layout of the output `plan` describes (normals and colours when every chunk has
/// them; world coordinates when `origin` is non-zero). O(1).
io::PlyMeshLayout streamed_layout(const WeldPlan& plan, const Eigen::Vector3d& origin);

class StreamedChunkOutput {
 public:
  /// Opens `path` (its temporary file: io::PlyMeshFile) for the parts of `plan` (its counts,
  /// normals, colours and flags: without flags the seams are left as they are, as
  /// finish_joined_mesh() leaves them without flags); `origin` non-zero: world coordinates.
  /// `voxel_size`, `chunk_cells`: the grid the chunks were extracted on; `feature_bit`: the bit
  /// of the flag bytes marking extended marching cubes' feature vertices. Throws
  /// meshflow::Error naming `path`.
  StreamedChunkOutput(const std::string& path, const WeldPlan& plan, const Eigen::Vector3d& origin,
                      float voxel_size, int chunk_cells, std::uint8_t feature_bit);

  /// Writes the next chunk's welded part (weld_chunk() of the chunks in plan order, failed
  /// chunks left out; `flags` its kept vertices' bytes, or empty when plan.flags is false; `chunk`
  /// its chunk index, for its tile) and keeps the triangles that touch a vertex next to a seam.
  /// Not thread-safe. O(part).
  void add(const TriangleMesh& part, const std::vector<std::uint8_t>& flags,
           const Eigen::Vector3i& chunk = Eigen::Vector3i::Zero());

  /// Finishes the seams (finish_seam_rows() of the kept neighbourhood) once every part was
  /// added. Returns the flips made. Throws meshflow::Error when a write failed. O(S log S) for
  /// S triangles near the seams, plus their rewrites.
  std::size_t finish_seams();

  /// After finish_seams(): each part's finished rows read back as its chunk's tile
  /// (chunk::read_tile()) and written to `dir` with the coarser levels `levels` makes, then
  /// the index (chunk::write_tiles_in_flight(): `in_flight` tiles in memory at a time, in
  /// parallel; chunk::write_tile_index()). Returns the tiles written. Throws meshflow::Error
  /// naming a file that cannot be written. O(output) plus the levels' cost.
  std::size_t write_tiles(const std::string& dir, const CoarserLevels& levels = {},
                          std::size_t in_flight = 2);

  /// Renames the file into place. Throws meshflow::Error when the parts did not fill the plan
  /// or the close or rename failed (no file left under the path).
  void commit() { file_.commit(); }

  /// Rows rewritten by finish_seams() (triangles flipped, normals changed).
  std::size_t rewritten() const { return rewritten_; }

 private:
  io::PlyMeshFile file_;
  Eigen::Vector3d origin_;
  bool normals_, flags_;
  float voxel_size_;
  int chunk_cells_;
  std::uint8_t feature_bit_;
  std::uint64_t vertices_ = 0, triangles_ = 0;  // rows written so far
  std::size_t rewritten_ = 0;
  SeamNeighbourhood near_;
  struct PartRows {
    Eigen::Vector3i chunk;
    std::uint64_t first_triangle, triangles;
  };
  std::vector<PartRows> parts_;
};

}  // namespace meshflow::chunk
