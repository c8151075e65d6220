#pragma once
// Out-of-core reconstruction of a cloud larger than memory (LVR2's chunked path, exact seams):
//
//   input --stream--> chunk files (one pass, nodes/chunk/chunk_store.h)
//         --> flow graph over chunks, K in flight: read -> ... -> extract, each chunk keeping
//             the cells it owns on the global grid (Frame::owned_cells)
//         --> stitch (seam vertices welded by their lattice edge) --> rim trim, optimize once
//
// Every chunk sees its points plus an overlap of a few voxels, so the normals, distances and
// rim trimming near its cells are those of the whole cloud; the grid is global, so the chunks'
// cells tile the single-process grid and their seam vertices coincide.

#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "graph/frame.h"
#include "nodes/chunk/chunk_store.h"
#include "nodes/chunk/mesh_stitch.h"

namespace meshflow {

struct ChunkingConfig {
  /// Chunk edge, metres (rounded to whole voxels); <= 0: chosen from `memory_budget` and the
  /// first points' spacing (auto_chunk_size).
  float chunk_size = 10.0f;
  /// Bytes the chunks in flight may take together (the automatic chunk size); 0 = 1 GiB.
  std::size_t memory_budget = 0;
  /// Points within this many voxels of a chunk go to it too: enough for the normals' and the
  /// distance's neighbours of its border corners (distance.max_distance_voxels + 2 suffices).
  int overlap_voxels = 5;
  std::string directory;                ///< parent of the chunk files; "" = the system's temp dir
  std::size_t in_flight = 2;            ///< chunks inside the flow graph at once (bounds memory)
  std::size_t batch_points = 1u << 20;  ///< points read from the input at a time
};

/// What a chunked reconstruction did.
struct ChunkedReport {
  float voxel_size = 0.0f;         ///< metres (given, or chosen from the first batch)
  int chunk_cells = 0;             ///< chunk edge in cells
  std::size_t chunks = 0;          ///< chunks meshed
  std::uint64_t points = 0;        ///< finite points read
  std::uint64_t dropped = 0;       ///< NaN / Inf points dropped
  std::uint64_t rows_written = 0;  ///< points spilled, overlap copies included
  std::uint64_t max_chunk_points = 0;
  std::size_t seam_vertices = 0;     ///< vertices welded across chunk seams
  std::size_t rim_trimmed = 0;       ///< triangles peeled off the rim (max_rim_voxels), stitched
  std::vector<std::string> failed;   ///< "chunk name: error" of chunks that failed (skipped)
  std::vector<StageRecord> timings;  ///< every stage record of every chunk
  double partition_s = 0.0, mesh_s = 0.0, stitch_s = 0.0, optimize_s = 0.0;
  OptimizeReport optimize;
};

struct ChunkedResult {
  TriangleMesh mesh;  ///< local coordinates of `origin`
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  ChunkedReport report;
};

/// The configuration each chunk runs with: `config` with the voxel fixed, no optimisation (it
/// runs once on the stitched mesh) and no compression.
ReconstructionConfig chunk_stage_config(const ReconstructionConfig& config, float voxel_size);

/// Bytes a chunk holds per point while in the graph (points, normals, kd-tree, grid, distances,
/// mesh; measured on the synthetic city at 3-6 points per voxel, with margin).
constexpr std::size_t kChunkBytesPerPoint = 1024;

/// A chunk edge (metres) for which `in_flight` chunks fit `memory_budget` bytes: a chunk of edge
/// c holds about 2 c^2 of surface (terrain and walls), sampled as densely as `sample` (a piece of
/// the input: its median nearest-neighbour spacing d gives about 4.5 d^2 of surface per point),
/// at kChunkBytesPerPoint. At least 4 voxels. `index` is over sample.positions. O(log n).
float auto_chunk_size(const PointCloud& sample, const SpatialIndex& index, float voxel_size,
                      std::size_t memory_budget, std::size_t in_flight);

/// The chunk grid for `voxel_size` and `chunking` (chunk edge rounded to whole cells, >= 1).
chunk::ChunkGrid make_chunk_grid(float voxel_size, const ChunkingConfig& chunking);

/// Streams `path` (columns as io::read_point_cloud) into chunk files. The voxel size is
/// config.voxelize.voxel_size, or when that is 0 chosen from the first batch of points (3x its
/// median spacing, as suggest_voxel_size); the chunk edge is chunking.chunk_size or, when that
/// is <= 0, auto_chunk_size() of the same batch (the store's grid() holds the one used).
/// Returns the store; `files` receives the chunks to mesh in Morton order. Throws meshflow::Error
/// for unreadable input or a cloud without finite points.
std::unique_ptr<chunk::ChunkStore> partition_input(
    const std::string& path, const std::string& columns, const ReconstructionConfig& config,
    const ChunkingConfig& chunking, std::vector<chunk::ChunkFile>& files, float& voxel_size);

/// Meshes `files` (chunk files of `grid` with rows `rows`) through one flow graph, `in_flight`
/// at a time; hands each finished chunk frame (failed ones with `error` set; the mesh in the
/// input's local frame, with Frame::beyond_data for the rim trim; Frame::source_index = its
/// position in `files`) to `sink` in the order of `files`, from one thread at a time. Each
/// chunk's file is deleted once read.
void mesh_chunk_files(const std::vector<chunk::ChunkFile>& files, const chunk::ChunkGrid& grid,
                      const chunk::ChunkRows& rows, const ReconstructionConfig& config,
                      std::size_t in_flight, const std::string& name,
                      const std::function<void(const FramePtr&)>& sink);

/// The same with the chunks taken as the graph asks for them: `next()` returns the position in
/// `files` of the next chunk to mesh, or a negative value when there is none left (a work
/// queue shared with other processes: MPI ranks). Called from graph threads, never
/// concurrently with itself; `sink` sees the chunks in the order `next` gave them.
void mesh_chunk_files(const std::vector<chunk::ChunkFile>& files,
                      const std::function<long long()>& next, const chunk::ChunkGrid& grid,
                      const chunk::ChunkRows& rows, const ReconstructionConfig& config,
                      std::size_t in_flight, const std::string& name,
                      const std::function<void(const FramePtr&)>& sink);

/// What a chunk's sink does: its stage records into `report`, its mesh (and rim verdicts) into
/// `stitcher`, or its error into report.failed; frees the frame's mesh.
void collect_chunk_frame(Frame& frame, chunk::MeshStitcher& stitcher, ChunkedReport& report);

/// Welds chunk meshes delivered in order (MeshStitcher), then trims the rim over the stitched
/// mesh (config.max_rim_voxels) and runs config's optimize steps once; fills the report's
/// seam, rim, stitch and optimize fields. `on_step` (optional) is told each optimize step.
TriangleMesh finish_chunked_mesh(chunk::MeshStitcher& stitcher, const ReconstructionConfig& config,
                                 float voxel_size, ChunkedReport& report,
                                 const std::function<void(const std::string&)>& on_step = {});

/// The whole path in one process: partition, mesh the chunks, stitch, optimise (config's
/// steps, on the stitched mesh). `on_stage` (optional) is told each phase ("partition",
/// "chunk i/n", "stitch", optimize steps) for progress lines. Memory: the chunks in flight
/// plus the stitched mesh; disk: about the input's points (with overlap copies) as chunk files.
ChunkedResult reconstruct_chunked(const std::string& path, const std::string& columns,
                                  const ReconstructionConfig& config,
                                  const ChunkingConfig& chunking,
                                  const std::function<void(const std::string&)>& on_stage = {});

}  // namespace meshflow
