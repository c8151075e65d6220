#pragma once
// meshflow-mpi's tiles (--tiles DIR): once rank 0 has finished the seams of the streamed
// output, every rank reads the finished rows of the chunks it welded back from the output's
// temporary file and writes their tiles with their coarser levels; not streamed, rank 0 cuts
// the finished mesh into tiles and sends each rank those of its chunks. Rank 0 joins the ranks'
// small per-tile records into the index. The files are those one process writes.

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "nodes/chunk/chunk_grid.h"
#include "nodes/chunk/chunk_store.h"
#include "nodes/chunk/mesh_tiles.h"
#include "nodes/chunk/phase_times.h"
#include "nodes/io/ply_mesh_file.h"
#include "runtime/triangle_mesh.h"

namespace meshflow::cli {

/// Where the tiles come from and go.
struct TileJob {
  std::string output;           ///< the streamed output (its temporary file holds the rows)
  io::PlyMeshLayout layout;     ///< the output's layout (chunk::streamed_layout())
  std::uint64_t vertices = 0;   ///< the output's vertex rows
  std::uint64_t triangles = 0;  ///< the output's face rows
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< the output's origin
  std::string dir;                                   ///< --tiles DIR
  chunk::ChunkGrid grid;
  const std::vector<chunk::ChunkFile>* files = nullptr;  ///< the chunks by position
  /// This rank's parts: position, first face row, faces.
  std::vector<std::array<std::uint64_t, 3>> rows;
  std::size_t chunks = 0;     ///< chunks this rank meshed (its timing's)
  std::size_t in_flight = 2;  ///< tiles written at once (chunk::write_tiles_in_flight())
};

/// What rank 0 learns.
struct TilesWritten {
  std::size_t tiles = 0;                 ///< tiles in the index
  std::string error;                     ///< "": every tile and the index written
  std::vector<chunk::RankTimes> others;  ///< ranks 1.. with their tile phases (rank 0: all)
};

/// Collective, after rank 0 finished the seams and synced the output's rows: rank 0's `verdict`
/// ("" to go on, else why not) goes to every rank (a rank that hears an error writes nothing).
/// Each rank (phase "tiles", parallel) opens the temporary file (kJoin), reads each of its parts'
/// finished rows as its chunk's tile (chunk::read_tile()) and writes it with its progressive
/// levels (chunk::write_tiles_in_flight(), graph/tile_levels.h); ranks other than 0 send rank 0
/// their records, error and timing. Rank 0 (phase "index", serial) writes DIR/tiles.json from every
/// rank's records in chunk position order, as one process orders them. Returns rank 0's view;
/// other ranks: their own error. Memory: `in_flight` tiles per rank; rank 0 every record.
TilesWritten write_tiles_on_ranks(const TileJob& job, const std::string& verdict,
                                  chunk::PhaseClock& clock, int rank, int ranks);

/// The not-streamed path's tiles: where they go and what the ranks' timings say.
struct ScatterJob {
  std::string dir;  ///< --tiles DIR
  chunk::ChunkGrid grid;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< the output's origin
  std::size_t chunks = 0;                            ///< chunks this rank meshed (its timing's)
  std::size_t in_flight = 2;  ///< tiles written at once (chunk::write_tiles_in_flight())
};

/// Collective, not streamed (rank 0 gathered the welded parts and finished the whole mesh):
/// rank 0's `verdict` ("" to go on, else why not) goes to every rank (a rank that hears an error
/// writes nothing). Rank 0 (phase "scatter", serial) cuts `mesh` (rank 0's: the finished mesh;
/// other ranks pass an empty one) into tiles (chunk::split_into_tiles()) and sends each rank the
/// tiles whose chunk `owner` (rank 0's: the rank that meshed a chunk; another number: rank 0)
/// gives it; every rank (phase "tiles", parallel) writes its tiles with their progressive levels;
/// ranks other than 0 send rank 0 their records, error and timing, and rank 0 (phase "index",
/// serial) writes DIR/tiles.json in tile order: the files chunk::write_tiles() writes in one
/// process. Returns rank 0's view; other ranks: their own error. Memory: rank 0 a copy of the
/// mesh as tiles until each is sent; each rank its tiles and `in_flight` of their levels.
TilesWritten scatter_tiles_to_ranks(const ScatterJob& job, const TriangleMesh& mesh,
                                    const std::function<int(const Eigen::Vector3i&)>& owner,
                                    const std::string& verdict, chunk::PhaseClock& clock, int rank,
                                    int ranks);

}  // namespace meshflow::cli
